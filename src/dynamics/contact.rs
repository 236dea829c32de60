//! Stages 5 and 6: the narrow phase over the persistent contacts, and the contact cache
//! (manifolds reused while a pair barely moves, points matched by feature id, warm-start
//! impulses carried over, begin/end, sensor and hit events).
//!
//! # Contacts
//!
//! A contact exists for every pair of bodies whose broad-phase boxes (`Body::fat`)
//! overlap and that may collide (`broad_phase::may_collide`): the broad phase inserts
//! new pairs with [`insert_pairs`], and [`update_contacts`] removes a contact once the
//! boxes separate. A contact holds a manifold of 0 to 4 points; one with no point is a
//! pair that is near but apart. `contacts` stays sorted by `(a, b)`, so every decision
//! is made in key order, and nothing is ever swapped or copied wholesale: new pairs are
//! merged in place from the back, and removal compacts in place.
//!
//! | pair this step | result |
//! | --- | --- |
//! | a body is gone, or the boxes no longer overlap | contact removed (end event if it touched) |
//! | neither body awake (or one asleep, the other static) | kept unchanged: the warm start survives sleep |
//! | otherwise | manifold reused or rebuilt, impulses carried over |
//!
//! # Manifold reuse
//!
//! The narrow phase keeps points up to `margin = speculative_margin + dt · w` apart,
//! with `w = |v_b − v_a| + |ω_a| ρ_a + |ω_b| ρ_b` the fastest the two surfaces can close
//! (ρ how far a shape's core reaches from its centre of mass: a ball's turn closes
//! nothing), so a pair that closes fast gets its speculative point
//! a step early and the solver stops it at the surface: speculative continuous
//! collision (Catto, GDC 2013). It is part of continuous collision: when no dynamic body
//! of the pair has `ccd` on, `w` is 0 and fast bodies may tunnel. A full narrow phase stores the relative pose `b_in_a` it ran at and the
//! margin it used, `margin + slack`, with the pair's slack
//! ([`crate::config::reuse_slack`]: one slop, six for a pair with a convex hull, whose
//! manifold costs about ten times more to build, four for a box on a mesh triangle, whose
//! group of parts is rebuilt whole; none for two spheres, "Sphere pairs" below). While the relative pose has moved by
//! `drift = |Δt| + 2 sin(θ/2) R_b ≤ slack` (θ the angle of the relative turn; no
//! point of B moved more than that in A's frame) and `margin + drift ≤ built margin`,
//! the manifold is reused:
//! its points are the same two surface points fixed in the two bodies, so their
//! separation along the normal (fixed in A's frame) is recomputed exactly from the
//! current poses, `s = (p_b − p_a) · n` (with the rotation matrices the bodies keep:
//! `(R_bᵀ n)·l_b − n_A·l_a + n·(t_b − t_a)`), and no point of the shapes can have come
//! closer than the margin without being there before. Resting stacks rebuild almost
//! never (rapier's contact recycling works the same way).
//!
//! A convex pair first tries a looser bound that needs no relative pose: B's origin
//! moved in A's frame by `|Δ(R_aᵀ (t_b − t_a))|`, and the relative turn is at most the
//! two bodies' own turns, whose chords `2 sin(θ/2)` are at most `2 |q − q_built|`, so
//! `drift ≤ |Δ(R_aᵀ (t_b − t_a))| + 2 (|Δq_a| + |Δq_b|) R_b`. A resting pair passes it
//! for a matrix product, three square roots and no quaternion product; a pair it refuses
//! takes the exact test above (a pair turning together, whose relative pose stays put).
//!
//! ## Lever arms kept from the build
//!
//! A build also stores both bodies' world rotations (`built_rot_a`, `built_rot_b`), and
//! while the manifold is reused the solver's rows keep the lever arms they had then (a
//! sphere pair, measured afresh every step and never reused, takes its arms as the
//! bodies turn now):
//! each anchor taken about its body's centre of mass and turned by the stored rotation,
//! not by the current one (`contact_solver`, "Lever arms"). The separations still
//! follow the bodies' motion exactly. Turning the arms with a leaning body lets the
//! large, warm-started normal impulses of a loaded interface tip it further, step
//! after step: a tower of 22 unit boxes (45 Hz contacts) leaned over and fell within
//! 20 s with turning arms, while with kept arms a tower of 40 stands with its top
//! within 3 cm (`tests/stability.rs`; rapier3d keeps its recycled contacts' world lever
//! arms for the same reason). A reuse therefore also needs each body to have turned,
//! since the build, by at most `θ` with `2 sin(θ/2) R ≤ slack`, `R` its bounding radius
//! plus its centre of mass's distance from its origin: no kept arm is more than the
//! slack away from the body's own (a pair that turns together, such as a box riding a
//! tilting platform, is rebuilt as it turns).
//!
//! # Empty pairs
//!
//! Most pairs the broad phase keeps do not touch: their enlarged boxes overlap, their
//! shapes stay farther apart than the margin (in the `boxes` scene, two pairs in three).
//! At the start of the narrow phase every body forms a box around its shape at its pose
//! (`Body::bounds`: exact for spheres, capsules, cuboids and triangles, the bounding
//! sphere's box for the rest). A pair of two bodies (not a mesh or compound part) that
//! has no point and whose boxes lie more than `margin + slack` apart along an axis
//! keeps no point: what a build with that margin would find, and what a reuse of its
//! empty manifold would give. It then keeps no manifold to reuse (its next test is this
//! one again, or a build). The test costs two box comparisons where the reuse test costs
//! a relative pose and a drift bound. A pair that has points keeps the reuse test: its
//! points (speculative ones a step early, their impulses and friction state) stay while
//! the manifold is valid, as before (dropping them when the boxes part changed how
//! `jolt_pyramid` settles: its top box slid 437 mm instead of 15 mm).
//!
//! # Parts beyond reach
//!
//! A triangle part whose box meets the other body's enlarged box is often still far from
//! the body itself (a neighbouring cell of a terrain it only overhangs): its build finds
//! the ball about B's origin beyond reach ([`mid_phase::beyond_reach`]) and keeps no
//! point. The build leaves the gap it proved (`Contact::apart_gap`, with B's origin at
//! `built_pose`). When the group is rebuilt later and B's origin has moved by `Δ`, the
//! ball is still more than `gap − Δ` from the triangle; while that bound, less a guard
//! for rounding, exceeds the build's margin, a build would find the part beyond reach
//! again, and the rebuild writes that empty result without forming the triangle, keeping
//! the smaller bound for the new place (`mesh_pile`: about three in four reach tests
//! skipped, 2.3 % of the step's instructions). Only ever a shortcut to the same bits, so
//! derived state: not in snapshots or checksums; a restored world, which starts without
//! it, builds those parts instead and goes on identically.
//!
//! # Sphere pairs
//!
//! Two whole spheres are measured afresh every step and never reused: their closed form
//! (`d = c_b − c_a`, normal `d/|d|`, separation `|d| − r_a − r_b`, one point) costs less
//! than the reuse test's relative pose and drift bound, and is exact where a reuse
//! measures the old surface points. Their boxes are exact, so boxes apart by more than
//! the margin mean no point. The point is the one [`crate::collide::contact`] gives with
//! the step's margin, to the bit; its impulse is carried over as a build's is.
//!
//! # Warm start
//!
//! A rebuilt manifold's points are matched to the old ones by feature-id key first
//! (Catto, Box2D `b2UpdateContact`); a point whose id matches nothing takes the nearest
//! unmatched old point whose anchors both moved less than `2 · slop` in their body frames.
//! A matched point inherits the accumulated normal impulse. The friction patch's
//! impulse (projected onto the new tangent plane), twist impulse and sticking flag stay
//! with the contact while it has points, and reset when its manifold empties. A reused
//! manifold keeps its points, impulses and flags as they are.
//!
//! # Touching and events
//!
//! A contact is *touching* when some point has `separation <= slop`: penetrating points,
//! points resting at the slop, and points within one slop of the surface (so a resting
//! contact whose gap jitters by rounding does not flicker). Points further out are
//! speculative: the solver uses them, events ignore them.
//!
//! Events, in key order: `ContactBegin` / `SensorEnter` when a contact starts touching,
//! `ContactEnd` / `SensorLeave` when a touching contact stops touching or is removed.
//! Then, again in key order, one `Hit` per non-sensor contact whose manifold appears
//! (no point last step) or that starts touching, when its fastest point closes faster
//! than `hit_event_speed`: the closing speed `(v_a(p) − v_b(p))·n` at the midpoint `p`
//! of the two anchors, with the velocities before the solve. Counting speculative
//! manifolds matters: the solver stops a body at a speculative point before it touches,
//! so by the time it touches its closing speed is gone.
//!
//! # Capacity
//!
//! New pairs that do not fit in `contacts` are dropped, the last in key order first, and
//! counted in `StepReport::dropped_contacts`; their bodies are flagged `moved` so the
//! broad phase offers the pairs again next step.

use heapless::Vec as HVec;

use crate::collide::{contact_cached_unchecked, sphere_pair, Manifold, ManifoldPoint, PairCache};
use crate::config::{reuse_slack, WorldConfig};
use crate::dynamics::body::{Body, BodyKind, Material};
use crate::dynamics::broad_phase::may_collide;
use crate::dynamics::events::{push_event, Event, StepReport};
use crate::dynamics::mid_phase;
use crate::dynamics::pool::Pool;
use crate::math::{scalar, Iso, Quat, Vec3};
use crate::shape::{Shape, Sphere};

/// One persistent contact point with its accumulated impulses.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ContactPoint {
    /// `ContactId::key()` of the features that produced it.
    pub id: u64,
    /// Anchor on A in A's body frame (m).
    pub local_a: Vec3,
    /// Anchor on B in B's body frame (m).
    pub local_b: Vec3,
    /// Separation along the normal at the narrow phase (m), negative when penetrating.
    pub separation: f32,
    /// Accumulated normal impulse of one sub-step (N·s), ≥ 0.
    pub normal_impulse: f32,
    /// Normal closing speed before the solve (m/s; positive when approaching), at the
    /// midpoint of the two anchors, for hit events: formed when the points are built, and
    /// on a reuse only when the contact may be due a hit (`reuse`).
    pub approach_speed: f32,
}

/// A persistent contact between two bodies (slots `a < b`).
///
/// `repr(C)`, fields in the order the passes over every contact read them: the pair,
/// the point count and the flags first (the solver's plan and the sleep pass read
/// only these: one cache line of a contact for three contacts in four, whose first 24
/// bytes do not straddle a line); then what the solver's prepare and
/// store read (the normal, the material, the patch impulses, the reuse margin with the
/// reach test's memory beside it, the points, the bodies' rotations at the build, which
/// a sphere pair's prepare does not read); last what only the narrow phase reads (the
/// normal in A's frame, the pose the manifold was built at). Rust's own layout had put
/// the pair at byte 192 and the point count and flags at 306 of 312 bytes: two or three
/// cache lines for every contact visited.
///
/// The point slots past `len` hold whatever an earlier contact left there
/// ([`Contact::copy_from`]) and nothing reads them: `==` compares them too, and
/// [`Contact::same_as`] does not.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[repr(C)]
pub(crate) struct Contact {
    /// Slot of body A (the lower slot).
    pub a: u32,
    /// Slot of body B.
    pub b: u32,
    /// Which parts of the pair (`mid_phase`): 0 for a pair of convex shapes (the only
    /// contact of the pair); for a pair with a mesh or compound, the part pair's key
    /// `1 + part_a · parts_b + part_b`, or [`RECORD`] for the pair's record, which holds
    /// no points and follows the pair's part contacts.
    pub sub: u32,
    /// Points in use (0 while the shapes are apart).
    pub len: u8,
    /// One of the bodies is a sensor: detect, never push.
    pub sensor: bool,
    /// Touching this step (some point with `separation <= slop`): drives begin/end events.
    pub touching: bool,
    /// True while the patch sticks (static friction).
    pub sticking: bool,
    /// Scratch of one update: a hit event is due (see the module docs).
    pub hit_due: bool,
    /// Scratch of the mid phase's update of the part contacts (`mid_phase::update_parts`):
    /// how many new part contacts come just before this one, or a mark that it goes; on
    /// a record, in its two-pass form, how many part contacts it adds. 0 between steps.
    pub new_parts: u8,
    /// The separating axis test's memory of this pair: only ever a shortcut to the same
    /// answer, so it is derived state (not in snapshots or checksums; fresh after restore).
    pub sat_cache: PairCache,
    /// Unit normal from A to B (world), as of this step.
    pub normal: Vec3,
    /// Combined material.
    pub material: Material,
    /// Accumulated friction impulse of the patch, one sub-step (N·s, world vector in the
    /// tangent plane).
    pub friction_impulse: Vec3,
    /// Accumulated twist impulse about the normal, one sub-step (N·m·s).
    pub twist_impulse: f32,
    /// Margin (m) the manifold was last built with; negative: never built, build now, and
    /// for a sphere pair, never reused (its points are formed afresh every step, and the
    /// solver takes their arms as the bodies turn now, not `built_rot_*`).
    pub built_margin: f32,
    /// The reach test's memory of this part contact: a lower bound (m) of the distance
    /// between its triangle and the ball about B's origin (radius B's bounding radius)
    /// with B where `built_pose` puts it; 0: none. Derived state like `sat_cache` (module
    /// docs, "Parts beyond reach").
    pub apart_gap: f32,
    /// The points.
    pub points: [ContactPoint; 4],
    /// A's world rotation when the manifold was last built: while it is reused, the
    /// solver turns A's lever arms back to it (module docs, "Lever arms kept from the
    /// build").
    pub built_rot_a: Quat,
    /// B's world rotation when the manifold was last built (see `built_rot_a`).
    pub built_rot_b: Quat,
    /// The normal in A's body frame: it turns with A while the manifold is reused.
    pub normal_local: Vec3,
    /// B's pose in A's frame when the manifold was last built.
    pub built_pose: Iso,
}

impl Contact {
    /// The pair's key: `(a, b)` packed (the same for every contact of the pair).
    #[inline]
    pub fn key(&self) -> u64 {
        pair_key((self.a, self.b))
    }

    /// Sort key: the pair's key, then the part key `sub`.
    #[inline]
    pub fn full_key(&self) -> (u64, u32) {
        (self.key(), self.sub)
    }

    /// True for the record of a pair with a mesh or compound (no points of its own).
    #[inline]
    pub fn is_record(&self) -> bool {
        self.sub == RECORD
    }

    /// True for a contact between one part pair of a mesh or compound pair.
    #[inline]
    pub fn is_part(&self) -> bool {
        self.sub != 0 && self.sub != RECORD
    }

    /// A contact for a new pair: no points, never built.
    pub fn new_pair(a: u32, b: u32, material: Material, sensor: bool) -> Contact {
        Contact {
            a,
            b,
            material,
            sensor,
            built_margin: -1.0,
            ..Contact::default()
        }
    }

    /// `src` copied into `self` with only its first `len` points: the point slots past
    /// them keep what they held. Nothing reads a slot past `len` (snapshots write `len`
    /// points and restore zeros past them, the checksum hashes `len` points), so the
    /// contact means what a whole copy would. For the moves within the contact buffer
    /// (compaction, merge, the mid phase's relocation): a pair without points copies
    /// 152 of its 344 bytes, one with a point 200, and none calls `memcpy`.
    #[inline(always)]
    pub fn copy_from(&mut self, src: &Contact) {
        // Every field named: a new field fails to compile here until it is copied.
        let Contact {
            a,
            b,
            sub,
            len,
            sensor,
            touching,
            sticking,
            hit_due,
            new_parts,
            sat_cache,
            normal,
            material,
            friction_impulse,
            twist_impulse,
            built_margin,
            apart_gap,
            points,
            built_rot_a,
            built_rot_b,
            normal_local,
            built_pose,
        } = src;
        self.a = *a;
        self.b = *b;
        self.sub = *sub;
        self.len = *len;
        self.sensor = *sensor;
        self.touching = *touching;
        self.sticking = *sticking;
        self.hit_due = *hit_due;
        self.new_parts = *new_parts;
        self.sat_cache = *sat_cache;
        self.normal = *normal;
        self.material = *material;
        self.friction_impulse = *friction_impulse;
        self.twist_impulse = *twist_impulse;
        self.built_margin = *built_margin;
        self.apart_gap = *apart_gap;
        for (dst, p) in self.points.iter_mut().zip(points).take(usize::from(*len)) {
            *dst = *p;
        }
        self.built_rot_a = *built_rot_a;
        self.built_rot_b = *built_rot_b;
        self.normal_local = *normal_local;
        self.built_pose = *built_pose;
    }

    /// True when the two contacts are equal in every field and every point in use (the
    /// slots past `len` are not compared). For the tests: the engine never compares
    /// contacts.
    #[cfg(test)]
    pub fn same_as(&self, o: &Contact) -> bool {
        let (mut a, mut b) = (*self, *o);
        for c in [&mut a, &mut b] {
            let len = usize::from(c.len);
            for p in c.points.iter_mut().skip(len) {
                *p = ContactPoint::default();
            }
        }
        a == b
    }

    /// The points in use.
    #[inline]
    pub fn points(&self) -> &[ContactPoint] {
        self.points.get(..usize::from(self.len)).unwrap_or(&[])
    }
}

/// [`Contact::sub`] of a pair's record.
pub(crate) const RECORD: u32 = u32::MAX;

/// The contact key of a pair, as [`Contact::key`].
#[inline]
pub(crate) fn pair_key((a, b): (u32, u32)) -> u64 {
    ((a as u64) << 32) | b as u64
}

/// True when `contacts` (sorted by key) holds the pair.
pub(crate) fn contains_pair(contacts: &[Contact], pair: (u32, u32)) -> bool {
    let key = pair_key(pair);
    contacts.binary_search_by(|c| c.key().cmp(&key)).is_ok()
}

/// Runs of at most this many contacts are scanned, longer ones bisected ([`PairIndex`]).
const SCAN_MAX: usize = 16;

/// Lookups of pairs in `contacts` (sorted by key), for a search that makes many: indexed
/// by body A, the contacts whose lower slot is `s` are `contacts[starts[s]..starts[s +
/// 1]]`, so a lookup scans (or, past [`SCAN_MAX`], bisects) the contacts of one body
/// instead of bisecting them all. Building the index reads every contact's `a` once,
/// which pays when there are many lookups; without it ([`PairIndex::new`] with `build` false) a lookup is the
/// binary search of [`contains_pair`]. Either way the answers are the same.
pub(crate) struct PairIndex<'c, const N: usize> {
    contacts: &'c [Contact],
    /// Per slot, the position of its first contact as body A, or of the first contact
    /// after where it would be; unused when not built.
    starts: [u32; N],
    built: bool,
}

impl<'c, const N: usize> PairIndex<'c, N> {
    /// Lookups in `contacts` (sorted by key, slots below `N`), indexed if `build`.
    pub fn new(contacts: &'c [Contact], build: bool) -> Self {
        let mut starts = [0u32; N];
        if build {
            let mut at = 0usize;
            for (slot, start) in starts.iter_mut().enumerate() {
                // `at` only grows: at most `contacts.len()` rounds over all slots.
                while contacts.get(at).is_some_and(|c| (c.a as usize) < slot) {
                    at += 1;
                }
                *start = at as u32;
            }
        }
        PairIndex {
            contacts,
            starts,
            built: build,
        }
    }

    /// True when the contacts hold the pair `(a, b)`, `a < b`.
    pub fn contains(&self, (a, b): (u32, u32)) -> bool {
        if !self.built {
            return contains_pair(self.contacts, (a, b));
        }
        let start = self.starts.get(a as usize).copied().unwrap_or(0) as usize;
        let end = self
            .starts
            .get(a as usize + 1)
            .map_or(self.contacts.len(), |&e| e as usize);
        let run = self.contacts.get(start..end).unwrap_or(&[]);
        if run.len() <= SCAN_MAX {
            return run.iter().any(|c| c.a == a && c.b == b);
        }
        // The run is sorted by `b` (the contacts by key), and a body with parts (a height
        // field under a pile) has thousands in its run: bisect it.
        let at = run.partition_point(|c| c.b < b);
        run.get(at).is_some_and(|c| c.a == a && c.b == b)
    }
}

/// Merge `pairs` (sorted by key, distinct, none already in `contacts`) into `contacts`
/// as new contacts with no points and their bodies' materials combined by `cfg`'s rules,
/// keeping the order. Pairs beyond the capacity are dropped from the end (the highest
/// keys), counted in `report.dropped_contacts`, and their bodies flagged `moved` so the
/// broad phase offers them again.
pub(crate) fn insert_pairs<const N: usize, const C: usize>(
    contacts: &mut HVec<Contact, C>,
    pairs: &[(u32, u32)],
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    report: &mut StepReport,
) {
    let room = C - contacts.len();
    let (kept, dropped) = pairs.split_at(pairs.len().min(room));
    for &(a, b) in dropped {
        for s in [a, b] {
            if let Some(body) = bodies.at_mut(s as usize) {
                body.moved = true;
            }
        }
    }
    report.dropped_contacts = report
        .dropped_contacts
        .saturating_add(dropped.len().min(u32::MAX as usize) as u32);
    if kept.is_empty() {
        return;
    }
    // Grow by `kept.len()` placeholders, then merge from the back: the largest of the two
    // tails goes to the last free position. Each position is written once.
    let old_len = contacts.len();
    for _ in 0..kept.len() {
        // Cannot fail: `kept.len() <= room`.
        let _ = contacts.push(Contact::default());
    }
    let slots = contacts.as_mut_slice();
    let mut old_at = old_len; // one past the next old contact to place
    let mut new_at = kept.len(); // one past the next new pair to place
    for write in (0..slots.len()).rev() {
        let pair = if new_at > 0 {
            kept.get(new_at - 1)
        } else {
            None
        };
        let old_key = if old_at > 0 {
            slots.get(old_at - 1).map(Contact::key)
        } else {
            None
        };
        let take_new = match (pair, old_key) {
            (Some(p), Some(k)) => pair_key(*p) > k,
            (Some(_), None) => true,
            (None, _) => false,
        };
        if take_new {
            new_at -= 1;
            let Some(&(a, b)) = pair else { break };
            if let Some(dst) = slots.get_mut(write) {
                *dst = new_contact(a, b, bodies, cfg);
            }
        } else {
            old_at -= 1;
            // Slot to slot: `old_at < write` while new pairs remain (every slot above
            // `write` is placed, and there are `new_at > 0` of them still to come).
            let Some((low, high)) = slots.split_at_mut_checked(write) else {
                break;
            };
            let (Some(src), Some(dst)) = (low.get(old_at), high.first_mut()) else {
                break;
            };
            dst.copy_from(src);
        }
        if new_at == 0 {
            // The old contacts below `write` are already in place.
            break;
        }
    }
}

/// A new, empty contact for the pair `a < b`, with their material combined by the
/// world's rules.
fn new_contact<const N: usize>(
    a: u32,
    b: u32,
    bodies: &Pool<Body<'_>, N>,
    cfg: &WorldConfig,
) -> Contact {
    match (bodies.at(a as usize), bodies.at(b as usize)) {
        (Some(x), Some(y)) => {
            let mut c = Contact::new_pair(
                a,
                b,
                cfg.combine_materials(&x.material, &y.material),
                x.sensor || y.sensor,
            );
            if !(x.shape.is_convex() && y.shape.is_convex()) {
                c.sub = RECORD;
            }
            c
        }
        _ => Contact::new_pair(a, b, Material::DEFAULT, false),
    }
}

/// Stages 5 and 6 over every contact, in key order (see the module docs for every rule):
/// remove contacts whose boxes separated, reuse or rebuild the manifolds of pairs with an
/// awake body, keep sleeping ones, carry impulses over; then begin/end/sensor events and
/// hit events. `report.pairs` counts the pairs the narrow phase examined,
/// `report.contacts` and `report.points` the manifolds and points that result.
pub(crate) fn update_contacts<const N: usize, const C: usize, const E: usize>(
    contacts: &mut HVec<Contact, C>,
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    events: &mut HVec<Event, E>,
    report: &mut StepReport,
) {
    // The broad phase formed the bounds of the bodies it moves (`update_fat_boxes`).
    // Every body's spin reach, for the pairs' closing bounds (`closing_bound`).
    for (_, body) in bodies.iter_mut() {
        if body.kind == BodyKind::Static || !body.awake {
            body.refresh_bounds();
        }
        body.refresh_spin_reach();
    }
    let bodies = &*bodies;
    let mut write = 0usize;
    let len = contacts.len();
    let mut tested = 0u32;
    let (mut group_key, mut group_start) = (u64::MAX, 0usize);
    // Whether the current pair's part contacts stay: the same for each (`part_kept`).
    let mut parts_kept: Option<bool> = None;
    let slots = contacts.as_mut_slice();
    for read in 0..len {
        // Compact in place: the contact moves down to `write` (at most one copy).
        if read != write {
            // The slot at `read` is not read again: a copy, not a swap, slot to slot
            // (`write < read`, so the two are in different halves of the split).
            if let Some((low, high)) = slots.split_at_mut_checked(read) {
                if let (Some(dst), Some(src)) = (low.get_mut(write), high.first()) {
                    dst.copy_from(src);
                }
            }
        }
        let Some(key) = slots.get(write).map(Contact::key) else {
            break;
        };
        if key != group_key {
            // The first contact of a pair: a mesh or compound pair's group starts here.
            group_key = key;
            group_start = write;
            parts_kept = None;
        }
        let Some((parts, rest)) = slots.split_at_mut_checked(write) else {
            break;
        };
        let Some(c) = rest.first_mut() else {
            break;
        };
        let was_touching = c.touching;
        let kept = if c.is_record() {
            // Its part contacts came just before it: their narrow phase runs here, as a
            // group; the record touches when one of them does.
            let group = parts.get_mut(group_start..).unwrap_or(&mut []);
            update_record(c, group, bodies, cfg, &mut tested)
        } else if c.is_part() {
            c.hit_due = false;
            *parts_kept.get_or_insert_with(|| part_kept(c, bodies))
        } else {
            update_one(c, bodies, cfg, &mut tested)
        };
        if !c.is_part() {
            // A part contact's events are its pair's, raised by the record.
            touch_events(was_touching, c, kept, bodies, events, report);
        }
        if kept {
            write += 1;
        }
    }
    contacts.truncate(write);
    hit_events(contacts, bodies, cfg, events, report);
    report.pairs = tested;
    // No sum wraps: at most four points per contact, and no buffer holds 2³⁰ contacts
    // (344 bytes each).
    let (mut touching, mut points) = (0u32, 0u32);
    for c in contacts.iter() {
        touching = touching.wrapping_add(u32::from(c.len > 0));
        points = points.wrapping_add(u32::from(c.len));
    }
    report.contacts = touching;
    report.points = points;
}

/// A part contact stays while its pair does (its narrow phase runs with its record's):
/// while both bodies exist and their enlarged boxes overlap, the same for every part
/// contact of the pair.
fn part_kept<const N: usize>(c: &Contact, bodies: &Pool<Body<'_>, N>) -> bool {
    match (bodies.at(c.a as usize), bodies.at(c.b as usize)) {
        (Some(a), Some(b)) => a.fat.overlaps(&b.fat),
        _ => false,
    }
}

/// A pair record's update, with its part contacts `group` (just before it): false when
/// the pair ends (a body gone, the boxes apart). While a body is awake, the group's
/// manifolds are reused together or rebuilt together; a rebuild merges each patch of
/// parts into one contact (`mid_phase::merge_patches`) and carries the impulses of the
/// whole group over. The record touches when one of its parts does.
fn update_record<const N: usize>(
    c: &mut Contact,
    group: &mut [Contact],
    bodies: &Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    tested: &mut u32,
) -> bool {
    c.hit_due = false;
    c.len = 0;
    let (Some(a), Some(b)) = (bodies.at(c.a as usize), bodies.at(c.b as usize)) else {
        return false;
    };
    if !a.fat.overlaps(&b.fat) {
        return false;
    }
    if may_collide(a, b) {
        update_group(group, a, b, cfg, tested, c.touching);
    }
    c.touching = group.iter().any(|p| p.touching);
    true
}

/// Most old points and patches a group carries over a rebuild (the rest start cold).
const GROUP_CARRY: usize = 16;

/// The narrow phase of one pair's part contacts (see [`update_record`]).
fn update_group(
    group: &mut [Contact],
    a: &Body<'_>,
    b: &Body<'_>,
    cfg: &WorldConfig,
    tested: &mut u32,
    was_touching: bool,
) {
    // The pair's sweep reach is the same for every part: taken once.
    let reach = pair_reach(a, b, cfg);
    let frame = TriangleFrame::of(a, b, cfg.speculative_margin + reach);
    let reusable = match &frame {
        Some(frame) => {
            let mut memo = GroupMemo::default();
            group.iter().all(|c| frame.reusable(c, a, b, &mut memo))
        }
        None => group.iter().all(|c| {
            plan(c, a, b, cfg, reach, None)
                .is_some_and(|p| p.reusable(c, p.shape_b.bounding_radius(), a, b))
        }),
    };
    if reusable {
        for c in group.iter_mut() {
            reuse(c, a, b, cfg);
        }
        // A group that starts touching on a reuse is due its hit, as a rebuilt one is:
        // the closing speeds of its points, which only then are read.
        if group.iter().any(|c| c.touching) && !was_touching {
            for c in group.iter_mut().filter(|c| c.len > 0 && !c.sensor) {
                set_approach_speeds(c, a, b);
                c.hit_due = true;
            }
        }
        return;
    }
    // The group's points and friction patches before the rebuild.
    let mut old: HVec<ContactPoint, GROUP_CARRY> = HVec::new();
    let mut patches: HVec<(Vec3, Vec3, f32, bool), GROUP_CARRY> = HVec::new();
    for c in group.iter().filter(|c| c.len > 0) {
        for p in c.points() {
            let _ = old.push(*p);
        }
        let _ = patches.push((c.normal, c.friction_impulse, c.twist_impulse, c.sticking));
    }
    // A triangle group's parts share B's pose in the part's frame: taken once.
    let shared = frame.as_ref().map(|f| &f.b_in_a);
    for c in group.iter_mut() {
        *tested = tested.saturating_add(1);
        if let Some((frame, gap)) = frame.as_ref().and_then(|f| Some((f, f.still_apart(c)?))) {
            // What `build` writes for a part beyond reach, without forming the triangle.
            c.len = 0;
            c.touching = false;
            c.built_pose = frame.b_in_a;
            c.built_margin = frame.margin + frame.slack;
            c.apart_gap = gap;
            continue;
        }
        match plan(c, a, b, cfg, reach, shared) {
            Some(p) => {
                build(c, &p, a, b, cfg);
            }
            None => {
                c.len = 0;
                c.touching = false;
            }
        }
    }
    mid_phase::merge_patches(group, cfg.slop);
    let touching = group.iter().any(|c| c.touching);
    for c in group.iter_mut() {
        c.friction_impulse = Vec3::ZERO;
        c.twist_impulse = 0.0;
        c.sticking = false;
        if c.len == 0 {
            continue;
        }
        warm_start(c, &old, cfg.slop);
        // The friction patch of the old patch that faced the same way, if any.
        let n = c.normal;
        if let Some(&(_, f, t, s)) = patches
            .iter()
            .find(|p| p.0.dot(n) >= mid_phase::PATCH_NORMAL_COS)
        {
            c.friction_impulse = f;
            c.twist_impulse = t;
            c.sticking = s;
        }
        keep_patch_in_plane(c);
        c.hit_due = !c.sensor && (old.is_empty() || (touching && !was_touching));
    }
}

/// One contact's update, in place: false when it ends.
fn update_one<const N: usize>(
    c: &mut Contact,
    bodies: &Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    tested: &mut u32,
) -> bool {
    c.hit_due = false;
    let (Some(body_a), Some(body_b)) = (bodies.at(c.a as usize), bodies.at(c.b as usize)) else {
        return false;
    };
    if !body_a.fat.overlaps(&body_b.fat) {
        return false;
    }
    if !may_collide(body_a, body_b) {
        // Two sleepers, or a sleeper on a static body: nothing moved, keep it.
        return true;
    }
    *tested = tested.saturating_add(1);
    let (had_points, was_touching) = (c.len > 0, c.touching);
    narrow_phase(c, body_a, body_b, cfg);
    c.hit_due = !c.sensor && c.len > 0 && (!had_points || (c.touching && !was_touching));
    true
}

/// The fastest the surfaces of `a` and `b` can close (m/s): `|v_b − v_a| + |ω_a| ρ_a +
/// |ω_b| ρ_b`, with `ρ` how far a body's core reaches from its centre of mass
/// (`Body::turn_reach`). Turning about the centre of mass moves no surface point faster
/// than `|ω| ρ`: a ball turning about its centre closes on nothing. Each body's `|ω| ρ`
/// is its `Body::spin_reach`, formed once per step for every body at the start of the
/// narrow phase.
#[inline]
fn closing_bound(a: &Body<'_>, b: &Body<'_>) -> f32 {
    (b.linear_velocity - a.linear_velocity).length() + a.spin_reach + b.spin_reach
}

/// Stage 5 for one pair, in place: reuse the manifold when the pair barely moved, else
/// build a new one and carry the impulses over (module docs).
fn narrow_phase(c: &mut Contact, body_a: &Body<'_>, body_b: &Body<'_>, cfg: &WorldConfig) {
    let reach = pair_reach(body_a, body_b, cfg);
    if let (Shape::Sphere(a), Shape::Sphere(b)) = (&body_a.shape, &body_b.shape) {
        // Their reuse slack is 0: the step's margin, no more.
        let margin = cfg.speculative_margin + reach;
        spheres(c, (a, b), body_a, body_b, cfg, margin);
        return;
    }
    if c.len == 0
        && !c.is_part()
        && apart(
            body_a,
            body_b,
            cfg.speculative_margin + reach + reuse_slack(&body_a.shape, &body_b.shape),
        )
    {
        // No point, as a build or a reuse would give, for the price of a box test.
        c.touching = false;
        c.built_margin = -1.0;
        keep_patch_in_plane(c);
        return;
    }
    // A convex pair that barely moved: the reuse test from the bodies' own poses, before
    // any relative pose is formed (module docs, "Manifold reuse").
    if !c.is_part() && convex_reusable(c, body_a, body_b, cfg.speculative_margin + reach) {
        reuse(c, body_a, body_b, cfg);
        return;
    }
    let Some(plan) = plan(c, body_a, body_b, cfg, reach, None) else {
        c.len = 0;
        c.touching = false;
        return;
    };
    // B's radius: the body's kept one for a convex pair (the same bits as its shape's).
    let radius_b = match plan.parts {
        None => body_b.bounding_radius,
        Some(_) => plan.shape_b.bounding_radius(),
    };
    if plan.reusable(c, radius_b, body_a, body_b) {
        reuse(c, body_a, body_b, cfg);
    } else {
        let old_points = c.points;
        let old = old_points.get(..usize::from(c.len)).unwrap_or(&[]);
        if build(c, &plan, body_a, body_b, cfg) {
            warm_start(c, old, cfg.slop);
        }
        keep_patch_in_plane(c);
    }
}

/// What the narrow phase of one contact works on: the two convex shapes that meet (the
/// bodies', or one part of each for a part contact) at their world poses, and the margin
/// this step needs.
struct Plan<'a> {
    shape_a: Shape<'a>,
    pose_a: Iso,
    shape_b: Shape<'a>,
    pose_b: Iso,
    /// The parts' poses in their bodies' frames, for a part contact.
    parts: Option<mid_phase::PartPair<'a>>,
    margin: f32,
    /// B's (part's) pose in A's (part's) frame now.
    b_in_a: Iso,
}

/// How far (m) the surfaces of `body_a` and `body_b` can close within the step when
/// either is swept by continuous collision (the manifold's margin grows by it); else 0.
fn pair_reach(body_a: &Body<'_>, body_b: &Body<'_>, cfg: &WorldConfig) -> f32 {
    let swept = |b: &Body<'_>| b.ccd && b.kind == crate::BodyKind::Dynamic;
    if swept(body_a) || swept(body_b) {
        cfg.dt * closing_bound(body_a, body_b)
    } else {
        0.0
    }
}

/// The plan of contact `c`'s narrow phase, its margin grown by the pair's `reach`
/// ([`pair_reach`]); `None` for a part key that names no part. `b_in_a`: B's pose in A's
/// frame when the caller has it (a triangle group's, [`TriangleFrame`]), else formed here.
#[inline(always)]
fn plan<'a>(
    c: &Contact,
    body_a: &Body<'a>,
    body_b: &Body<'a>,
    cfg: &WorldConfig,
    reach: f32,
    b_in_a: Option<&Iso>,
) -> Option<Plan<'a>> {
    let parts = if c.is_part() {
        Some(mid_phase::part_pair(&body_a.shape, &body_b.shape, c.sub)?)
    } else {
        None
    };
    let (shape_a, pose_a, shape_b, pose_b) = match &parts {
        Some(p) => (
            p.a,
            placed(body_a.pose(), p.pose_a.as_ref()),
            p.b,
            placed(body_b.pose(), p.pose_b.as_ref()),
        ),
        None => (body_a.shape, *body_a.pose(), body_b.shape, *body_b.pose()),
    };
    Some(Plan {
        shape_a,
        pose_a,
        shape_b,
        pose_b,
        parts,
        margin: cfg.speculative_margin + reach,
        b_in_a: b_in_a.copied().unwrap_or_else(|| pose_a.inv_mul(&pose_b)),
    })
}

impl Plan<'_> {
    /// True when the manifold `c` holds may be reused (module docs, "Manifold reuse");
    /// `radius_b` is `shape_b`'s bounding radius (m), `body_a` and `body_b` the pair's
    /// bodies.
    fn reusable(&self, c: &Contact, radius_b: f32, body_a: &Body<'_>, body_b: &Body<'_>) -> bool {
        let slack = reuse_slack(&self.shape_a, &self.shape_b);
        // A part contact's second bound: A's radius (a mesh triangle's is about the
        // mesh's origin, far away).
        let radius_a = || self.parts.is_some().then(|| self.shape_a.bounding_radius());
        let drift = relative_drift(&c.built_pose, &self.b_in_a, radius_b);
        reuse_fits(c, &self.b_in_a, self.margin, slack, drift, radius_a)
            && arms_kept(c, body_a, body_b, slack)
    }
}

/// The reuse bounds of contact `c`'s manifold (module docs, "Manifold reuse"), with B's
/// pose in A's frame now `b_in_a`, this step's `margin`, the pair's `slack` and B's
/// drift since the build, `drift` ([`relative_drift`] from `c.built_pose` with B's
/// radius): B's points moved at most `slack` in A's frame, and `margin` plus that drift
/// is within the margin the manifold was built with. A change in the distance of two
/// points is bounded by either one's move relative to the other body, so when B's drift
/// does not fit, A's points in B's frame may: `radius_a` gives A's radius for that second
/// bound (formed only then; `None`: no second bound, a pair of two bodies).
#[inline(always)]
fn reuse_fits(
    c: &Contact,
    b_in_a: &Iso,
    margin: f32,
    slack: f32,
    drift: f32,
    radius_a: impl FnOnce() -> Option<f32>,
) -> bool {
    if c.built_margin < 0.0 {
        return false;
    }
    let fits = |drift: f32| drift <= slack && margin + drift <= c.built_margin;
    if fits(drift) {
        return true;
    }
    let Some(radius_a) = radius_a() else {
        return false;
    };
    let a_drift = relative_drift(&c.built_pose.inverse(), &b_in_a.inverse(), radius_a);
    fits(scalar::min(drift, a_drift))
}

/// The reuse test of a group whose A is a mesh or height field and whose B is convex,
/// without forming its triangles. Each of its part pairs is a triangle of A (in A's
/// frame) and B itself, so B's pose in the part's frame is the bodies' relative pose,
/// the same for every part, and the slack and B's radius are the same too: taken once
/// for the group. A part's own triangle is formed only when B's drift does not fit and
/// the triangle's radius is needed ([`Plan::reusable`]'s second bound). The answer is
/// [`Plan::reusable`]'s, bit for bit, for every contact of the group.
struct TriangleFrame {
    /// Triangles of A: part key `1 + t` names triangle `t` (B has one part).
    triangles: u32,
    /// B's pose in A's frame now.
    b_in_a: Iso,
    /// This step's margin (m).
    margin: f32,
    /// The reuse slack of a triangle against B (m).
    slack: f32,
    /// B's bounding radius (m).
    radius_b: f32,
}

impl TriangleFrame {
    /// The frame of a pair whose A is a mesh or height field and whose B is convex, with
    /// this step's `margin`; `None` for any other pair.
    fn of(a: &Body<'_>, b: &Body<'_>, margin: f32) -> Option<TriangleFrame> {
        let triangles = match a.shape {
            Shape::Mesh(m) => m.triangle_count(),
            Shape::HeightField(f) => f.triangle_count(),
            _ => return None,
        };
        if !b.shape.is_convex() {
            return None;
        }
        // Any triangle: the slack depends on the kinds of the shapes only.
        let triangle = Shape::Triangle(crate::shape::Triangle {
            vertices: [Vec3::ZERO; 3],
        });
        Some(TriangleFrame {
            triangles,
            b_in_a: a.pose().inv_mul(b.pose()),
            margin,
            slack: reuse_slack(&triangle, &b.shape),
            radius_b: b.shape.bounding_radius(),
        })
    }

    /// The gap bound of part contact `c` now, when its memory (`Contact::apart_gap`, with
    /// B's origin then at `built_pose`) still proves the part beyond reach, so that a
    /// build would find it beyond reach ([`mid_phase::beyond_reach`]) and keep no point.
    /// With `g` the gap then, `r` B's radius, `Δ` how far B's origin moved since and `s`
    /// the size of the coordinates, the bound is `(g − Δ + r)(1 − 10⁻⁴) − r − 10⁻⁴ s`:
    /// the distance from B's origin to the triangle was at least `g + r` and shrank by
    /// at most `Δ`; the guard, ten times the reach test's own, covers the rounding of `Δ`
    /// and of the distance a build would compute, so its test would pass whenever the
    /// bound exceeds the build's margin. `None` when it does not (or there is no memory).
    fn still_apart(&self, c: &Contact) -> Option<f32> {
        const GUARD: f32 = 1.0e-4;
        if c.apart_gap <= 0.0 {
            return None;
        }
        let (now, then) = (self.b_in_a.position, c.built_pose.position);
        let moved = (now - then).length();
        let size = 1.0 + now.abs().max_elem() + then.abs().max_elem() + self.radius_b;
        let r = self.radius_b;
        let gap = (c.apart_gap - moved + r) * (1.0 - GUARD) - r - GUARD * size;
        (gap > self.margin + self.slack).then_some(gap)
    }

    /// [`Plan::reusable`] of part contact `c` of bodies `a` and `b`, false where [`plan`]
    /// finds no part pair (a key past A's triangles).
    fn reusable(&self, c: &Contact, a: &Body<'_>, b: &Body<'_>, memo: &mut GroupMemo) -> bool {
        if c.sub == RECORD || c.sub.checked_sub(1).is_none_or(|t| t >= self.triangles) {
            return false;
        }
        let radius_a =
            || mid_phase::part_pair(&a.shape, &b.shape, c.sub).map(|p| p.a.bounding_radius());
        let pose = pose_bits(&c.built_pose);
        let drift = match memo.drift {
            Some((key, drift)) if key == pose => drift,
            _ => {
                let drift = relative_drift(&c.built_pose, &self.b_in_a, self.radius_b);
                memo.drift = Some((pose, drift));
                drift
            }
        };
        if !reuse_fits(c, &self.b_in_a, self.margin, self.slack, drift, radius_a) {
            return false;
        }
        // An empty manifold keeps no arms (`arms_kept`).
        if c.len == 0 {
            return true;
        }
        let (qa, qb) = (c.built_rot_a, c.built_rot_b);
        let rotations = [qa.x, qa.y, qa.z, qa.w, qb.x, qb.y, qb.z, qb.w].map(f32::to_bits);
        match memo.arms {
            Some((key, kept)) if key == rotations => kept,
            _ => {
                let kept = arms_kept(c, a, b, self.slack);
                memo.arms = Some((rotations, kept));
                kept
            }
        }
    }
}

/// What [`TriangleFrame::reusable`] last computed in one scan of a group: the parts a
/// group rebuilt together share their built pose and rotations, and the same inputs give
/// the same bits, so each is formed once per distinct value. Keys are the inputs' bits
/// (`==` on the floats would take `-0` for `0`).
#[derive(Default)]
struct GroupMemo {
    /// A built pose's bits ([`pose_bits`]) and B's drift since it.
    drift: Option<([u32; 7], f32)>,
    /// The bits of A's and B's built rotations, and whether the lever arms kept.
    arms: Option<([u32; 8], bool)>,
}

/// A pose's bits: its position, then its rotation.
fn pose_bits(p: &Iso) -> [u32; 7] {
    let (t, q) = (p.position, p.rotation);
    [t.x, t.y, t.z, q.x, q.y, q.z, q.w].map(f32::to_bits)
}

/// True when the boxes of `a` and `b` ([`Body::bounds`]) are more than `margin` apart
/// along an axis: the shapes are too, and a build with that margin finds no point
/// (module docs, "Empty pairs").
#[inline]
fn apart(a: &Body<'_>, b: &Body<'_>, margin: f32) -> bool {
    !a.bounds.expanded(margin).overlaps(&b.bounds)
}

/// Build `c`'s manifold afresh (no impulses carried over): false when it has no points.
fn build(
    c: &mut Contact,
    plan: &Plan<'_>,
    body_a: &Body<'_>,
    body_b: &Body<'_>,
    cfg: &WorldConfig,
) -> bool {
    let built_margin = plan.margin + reuse_slack(&plan.shape_a, &plan.shape_b);
    let (a, pose_a, b, pose_b) = (&plan.shape_a, &plan.pose_a, &plan.shape_b, &plan.pose_b);
    let kept_gap = if plan.parts.is_some() {
        mid_phase::beyond_reach(a, pose_a, b, pose_b, built_margin)
    } else {
        None
    };
    c.apart_gap = kept_gap.unwrap_or(0.0);
    let mut manifold = if kept_gap.is_some() {
        None
    } else {
        contact_cached_unchecked(a, pose_a, b, pose_b, built_margin, &mut c.sat_cache)
    };
    if let (Some(m), Some(p)) = (manifold.as_mut(), &plan.parts) {
        let (a, b) = (&body_a.shape, &body_b.shape);
        mid_phase::correct_mesh_contact(m, a, body_a.pose(), b, body_b.pose(), c.sub);
        // Anchors from the parts' frames into the bodies'.
        for q in m.points.iter_mut().take(usize::from(m.len)) {
            if let Some(local) = &p.pose_a {
                q.local_a = local.transform_point(q.local_a);
            }
            if let Some(local) = &p.pose_b {
                q.local_b = local.transform_point(q.local_b);
            }
        }
    }
    c.len = 0;
    c.touching = false;
    c.built_pose = plan.b_in_a;
    c.built_rot_a = body_a.pose().rotation;
    c.built_rot_b = body_b.pose().rotation;
    c.built_margin = built_margin;
    let Some(m) = manifold.filter(|m| m.len > 0) else {
        return false;
    };
    if fill_from_manifold(c, &m, body_a, body_b, cfg) {
        true
    } else {
        // Something non-finite (coordinates near f32::MAX): no points, rebuild next step.
        c.len = 0;
        c.touching = false;
        c.built_margin = -1.0;
        false
    }
}

/// The friction patch of `c` after a rebuild: reset when it has no points, else its
/// impulse kept in the (possibly turned) tangent plane.
fn keep_patch_in_plane(c: &mut Contact) {
    if c.len == 0 {
        c.friction_impulse = Vec3::ZERO;
        c.twist_impulse = 0.0;
        c.sticking = false;
    } else {
        let n = c.normal;
        c.friction_impulse -= n * c.friction_impulse.dot(n);
    }
}

/// A part's world pose: the body's, moved by the part's pose in the body's frame when it
/// has one (`None`: the part's frame is the body's).
#[inline]
fn placed(body: &Iso, part: Option<&Iso>) -> Iso {
    match part {
        Some(p) => *body * *p,
        None => *body,
    }
}

/// True while the lever arms the solver keeps from the manifold's build (module docs,
/// "Lever arms kept from the build") are within `slack` (m) of the bodies' own (or
/// there are none: no point): each moving body turned, since the build, by an angle `θ`
/// with `2 sin(θ/2) R ≤ slack`, where `R` bounds its arms (its bounding radius about
/// its origin plus its centre of mass's offset, summed over the axes: no root). The
/// quaternions' difference bounds the turn without a product: `|q − q_built| =
/// 2 sin(θ/4) ≥ sin(θ/2)` for unit quaternions, so `4 |q − q_built|² R² ≤ slack²` is
/// enough (a body whose quaternion changed sign for the same rotation is rebuilt). A
/// static body's arms enter no row (no inverse mass or inertia, no velocity): it
/// passes.
#[inline(always)]
fn arms_kept(c: &Contact, body_a: &Body<'_>, body_b: &Body<'_>, slack: f32) -> bool {
    let kept = |built: Quat, body: &Body<'_>| arm_kept(turn2(built, body), body, slack);
    // An empty manifold keeps no arms.
    c.len == 0 || (kept(c.built_rot_a, body_a) && kept(c.built_rot_b, body_b))
}

/// `|q − q_built|²` of `body`'s rotation `q` now against `built`: `4 sin²(θ/4)` for a
/// turn by θ since (when the two quaternions lie in one hemisphere; larger otherwise).
#[inline(always)]
fn turn2(built: Quat, body: &Body<'_>) -> f32 {
    let q = body.pose().rotation;
    let (dx, dy, dz, dw) = (q.x - built.x, q.y - built.y, q.z - built.z, q.w - built.w);
    ((dx * dx + dy * dy) + dz * dz) + dw * dw
}

/// [`arms_kept`] for one body that turned by `turn2` ([`turn2`]) since the build.
#[inline(always)]
fn arm_kept(turn2: f32, body: &Body<'_>, slack: f32) -> bool {
    if body.kind == BodyKind::Static {
        return true;
    }
    let offset = body.center_local.abs();
    let reach = body.bounding_radius + ((offset.x + offset.y) + offset.z);
    4.0 * turn2 * (reach * reach) <= slack * slack
}

/// The reuse test of a convex pair (module docs, "Manifold reuse") from the bodies' own
/// poses, with this step's `margin`: no relative pose and no quaternion product. B's
/// points moved in A's frame, since the build, by at most `|Δt| + (c_a + c_b) R_b`:
/// `Δt` the change of B's origin in A's frame, `R_aᵀ (t_b − t_a)` now against the
/// build's, and `c = 2 |q − q_built|` bounds each body's turn chord `2 sin(θ/2)`
/// (`|q − q_built| = 2 sin(θ/4) ≥ sin(θ/2)`), the relative turn being at most the two
/// turns together. A looser bound than [`Plan::reusable`]'s (which the caller tries
/// when this one fails): both bound the same drift, so either passing is enough. The
/// lever arms as [`arms_kept`].
#[inline]
fn convex_reusable(c: &Contact, body_a: &Body<'_>, body_b: &Body<'_>, margin: f32) -> bool {
    if c.built_margin < 0.0 {
        return false;
    }
    let slack = reuse_slack(&body_a.shape, &body_b.shape);
    let d = body_b.pose().position - body_a.pose().position;
    let moved = (body_a.rotation_matrix().transpose_mul_vec(d) - c.built_pose.position).length();
    let (turn_a, turn_b) = (turn2(c.built_rot_a, body_a), turn2(c.built_rot_b, body_b));
    let chords = 2.0 * (scalar::sqrt(turn_a) + scalar::sqrt(turn_b));
    let drift = moved + chords * body_b.bounding_radius;
    let arms =
        || c.len == 0 || (arm_kept(turn_a, body_a, slack) && arm_kept(turn_b, body_b, slack));
    drift <= slack && margin + drift <= c.built_margin && arms()
}

/// An upper bound (m) on how far any point of B (within `radius_b` of B's origin) moved
/// in A's frame between the relative poses `from` and `to`: `|Δt| + 2 sin(θ/2) radius_b`,
/// the translation plus the chord a turn by θ moves a point at `radius_b`; `sin(θ/2)` is
/// the length of the vector part of the relative turn `Δq = q_from⁻¹ q_to`.
#[inline]
fn relative_drift(from: &Iso, to: &Iso, radius_b: f32) -> f32 {
    let dq = from.rotation.conjugate() * to.rotation;
    let sin_half = scalar::sqrt(dq.xyz().length_squared());
    (to.position - from.position).length() + 2.0 * sin_half * radius_b
}

/// The manifold at the current poses: same points and impulses, separations and the
/// world normal recomputed (module docs). A contact's anchors are in its bodies' frames
/// (a part contact's too) and its normal in A's, so with the rotation matrices the
/// bodies keep, `n = R_a n_A` and `(R_b l_b + t_b − R_a l_a − t_a)·n = (R_bᵀ n)·l_b −
/// n_A·l_a + n·(t_b − t_a)`: two matrix products per contact and two dot products per
/// point.
fn reuse(c: &mut Contact, body_a: &Body<'_>, body_b: &Body<'_>, cfg: &WorldConfig) {
    let was_touching = c.touching;
    c.touching = false;
    let n_a = c.normal_local;
    let n = body_a.rotation_matrix().mul_vec(n_a);
    c.normal = n;
    let n_b = body_b.rotation_matrix().transpose_mul_vec(n);
    let along = n.dot(body_b.pose().position - body_a.pose().position);
    for p in c.points.iter_mut().take(usize::from(c.len)) {
        p.separation = (n_b.dot(p.local_b) - n_a.dot(p.local_a)) + along;
        c.touching |= p.separation <= cfg.slop;
    }
    // Closing speeds are read by hit events only: a convex pair with points is due one
    // when it starts touching (`update_one`); a part contact when its group starts
    // touching (`update_group` forms them then).
    if !c.is_part() && c.touching && !was_touching {
        set_approach_speeds(c, body_a, body_b);
    }
}

/// The closing speed `(v_a(p) − v_b(p))·n` of each point of `c` (m/s), at the midpoint
/// `p` of its two anchors at the bodies' current poses, with their velocities now.
fn set_approach_speeds(c: &mut Contact, body_a: &Body<'_>, body_b: &Body<'_>) {
    let n = c.normal;
    let (center_a, center_b) = (body_a.world_center(), body_b.world_center());
    for p in c.points.iter_mut().take(usize::from(c.len)) {
        let p_a = body_a.pose().transform_point(p.local_a);
        let p_b = body_b.pose().transform_point(p.local_b);
        let mid = (p_a + p_b) * 0.5;
        let v_a = body_a.linear_velocity + body_a.angular_velocity.cross(mid - center_a);
        let v_b = body_b.linear_velocity + body_b.angular_velocity.cross(mid - center_b);
        p.approach_speed = (v_a - v_b).dot(n);
    }
}

/// Fill `c` (no points yet) from a manifold: world and local normal, body-frame anchors,
/// closing speeds, touching flag. False when the manifold holds something non-finite.
fn fill_from_manifold(
    c: &mut Contact,
    m: &Manifold,
    body_a: &Body<'_>,
    body_b: &Body<'_>,
    cfg: &WorldConfig,
) -> bool {
    let normal = m.normal;
    if !normal.is_finite() {
        return false;
    }
    c.normal = normal;
    c.normal_local = body_a.pose().inverse_transform_vector(normal);
    for (dst, src) in c.points.iter_mut().zip(m.points()) {
        if !kept_finite(src) {
            return false;
        }
        *dst = contact_point(src, normal, body_a, body_b, true);
        c.len += 1;
        c.touching |= src.separation <= cfg.slop;
    }
    true
}

/// True when what a contact keeps of manifold point `src` is finite: its separation and
/// both anchors (`&`, not `&&`: the usual answer is true, so every check runs anyway).
#[inline(always)]
fn kept_finite(src: &ManifoldPoint) -> bool {
    src.separation.is_finite() & src.local_a.is_finite() & src.local_b.is_finite()
}

/// The contact point of manifold point `src` (normal `normal`), no impulse yet; its
/// closing speed at the midpoint of the two surface points `with_speed`, else 0. The
/// shape frame is the body frame, so the manifold's local anchors are the contact's.
#[inline(always)]
fn contact_point(
    src: &ManifoldPoint,
    normal: Vec3,
    body_a: &Body<'_>,
    body_b: &Body<'_>,
    with_speed: bool,
) -> ContactPoint {
    let approach_speed = if with_speed {
        let mid = (src.point_a + src.point_b) * 0.5;
        (body_a.velocity_at(mid) - body_b.velocity_at(mid)).dot(normal)
    } else {
        0.0
    };
    ContactPoint {
        id: src.id.key(),
        local_a: src.local_a,
        local_b: src.local_b,
        separation: src.separation,
        approach_speed,
        ..ContactPoint::default()
    }
}

/// Stage 5 for two whole spheres (module docs, "Sphere pairs"): the one point measured
/// afresh in closed form, as a build would give it with the step's `margin`, its impulse
/// carried over as a build's is. Its closing speed is formed only when a hit may be due
/// (no point before, or touching only now), as a reuse's is.
fn spheres(
    c: &mut Contact,
    (a, b): (&Sphere, &Sphere),
    body_a: &Body<'_>,
    body_b: &Body<'_>,
    cfg: &WorldConfig,
    margin: f32,
) {
    let (old_len, was_touching) = (usize::from(c.len), c.touching);
    c.len = 0;
    c.touching = false;
    // Never reused: no manifold is kept to test against (and no separating-axis cache
    // is ever read: it stays as the contact was created or restored, empty).
    c.built_margin = -1.0;
    // Sphere boxes are exact: boxes apart by more than the margin, no point.
    let found = if apart(body_a, body_b, margin) {
        None
    } else {
        sphere_pair(a, body_a.pose(), b, body_b.pose(), margin)
    };
    if let Some((normal, src)) = found {
        if normal.is_finite() & kept_finite(&src) {
            let touching = src.separation <= cfg.slop;
            let hit_due = old_len == 0 || (touching && !was_touching);
            let mut new = [contact_point(&src, normal, body_a, body_b, hit_due)];
            let old = c.points.get(..old_len).unwrap_or(&[]);
            carry_impulses(&mut new, old, cfg.slop);
            c.points[0] = new[0];
            c.normal = normal;
            c.normal_local = body_a.pose().inverse_transform_vector(normal);
            c.len = 1;
            c.touching = touching;
        }
    }
    keep_patch_in_plane(c);
}

/// Carry accumulated normal impulses from `old_points` (the same pair, last step) to the
/// points of `c`: by feature id first, then by the nearest anchors within
/// `2 · slop` for points whose id matched nothing. Each old point is used at most once.
fn warm_start(c: &mut Contact, old_points: &[ContactPoint], slop: f32) {
    let len = usize::from(c.len);
    carry_impulses(c.points.get_mut(..len).unwrap_or(&mut []), old_points, slop);
}

/// [`warm_start`] for the points `new_points`.
fn carry_impulses(new_points: &mut [ContactPoint], old_points: &[ContactPoint], slop: f32) {
    let mut used = [false; 4];
    let mut matched = [false; 4];
    // Pass 1: the same pair of features.
    for (p, done) in new_points.iter_mut().zip(matched.iter_mut()) {
        for (q, taken) in old_points.iter().zip(used.iter_mut()) {
            if !*taken && q.id == p.id {
                inherit(p, q);
                *taken = true;
                *done = true;
                break;
            }
        }
    }
    // Pass 2: the nearest free old point, `max(|Δ local_a|, |Δ local_b|) <= 2 slop`
    // (lower old index on ties).
    let reach2 = (2.0 * slop) * (2.0 * slop);
    for (p, done) in new_points.iter_mut().zip(matched.iter()) {
        if *done {
            continue;
        }
        let mut best: Option<(usize, f32)> = None;
        for (k, (q, taken)) in old_points.iter().zip(used.iter()).enumerate() {
            let d2 = scalar::max(
                (p.local_a - q.local_a).length_squared(),
                (p.local_b - q.local_b).length_squared(),
            );
            if !*taken && d2 <= reach2 && best.is_none_or(|(_, b)| d2 < b) {
                best = Some((k, d2));
            }
        }
        if let Some((k, _)) = best {
            if let (Some(q), Some(taken)) = (old_points.get(k), used.get_mut(k)) {
                inherit(p, q);
                *taken = true;
            }
        }
    }
}

/// `p` takes over `q`'s accumulated normal impulse.
#[inline]
fn inherit(p: &mut ContactPoint, q: &ContactPoint) {
    p.normal_impulse = q.normal_impulse;
}

/// Begin/end (or sensor enter/leave) when the touching state of contact `c` changed this
/// step (`kept` false: the contact was removed).
fn touch_events<const N: usize, const E: usize>(
    was: bool,
    c: &Contact,
    kept: bool,
    bodies: &Pool<Body<'_>, N>,
    events: &mut HVec<Event, E>,
    report: &mut StepReport,
) {
    let is = kept && c.touching;
    if was == is {
        return;
    }
    let (Some(a), Some(b)) = (
        bodies.handle_at(c.a as usize),
        bodies.handle_at(c.b as usize),
    ) else {
        return;
    };
    let event = if c.sensor {
        // The sensor first; when both are sensors, the lower slot.
        let a_is_sensor = bodies.at(c.a as usize).is_some_and(|body| body.sensor);
        let (sensor, other) = if a_is_sensor { (a, b) } else { (b, a) };
        if is {
            Event::SensorEnter { sensor, other }
        } else {
            Event::SensorLeave { sensor, other }
        }
    } else if is {
        Event::ContactBegin { a, b }
    } else {
        Event::ContactEnd { a, b }
    };
    push_event(events, report, event);
}

/// One `Hit` per contact flagged `hit_due` whose fastest point closes faster than
/// `cfg.hit_event_speed`, in key order.
fn hit_events<const N: usize, const E: usize>(
    contacts: &[Contact],
    bodies: &Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    events: &mut HVec<Event, E>,
    report: &mut StepReport,
) {
    // The fastest due point among a mesh or compound pair's part contacts so far.
    let mut pending: Option<(&Contact, &ContactPoint)> = None;
    for c in contacts {
        let due = if c.is_part() {
            if let Some(p) = c.hit_due.then(|| fastest_point(c)).flatten() {
                if pending.is_none_or(|(_, q)| p.approach_speed > q.approach_speed) {
                    pending = Some((c, p));
                }
            }
            None
        } else if c.is_record() {
            pending.take()
        } else if c.hit_due {
            fastest_point(c).map(|p| (c, p))
        } else {
            None
        };
        let Some((c, fastest)) = due else {
            continue;
        };
        if fastest.approach_speed <= cfg.hit_event_speed {
            continue;
        }
        let (Some(body_a), Some(body_b)) = (bodies.at(c.a as usize), bodies.at(c.b as usize))
        else {
            continue;
        };
        let (Some(a), Some(b)) = (
            bodies.handle_at(c.a as usize),
            bodies.handle_at(c.b as usize),
        ) else {
            continue;
        };
        let point_a = body_a.pose().transform_point(fastest.local_a);
        let point_b = body_b.pose().transform_point(fastest.local_b);
        let event = Event::Hit {
            a,
            b,
            point: (point_a + point_b) * 0.5,
            normal: c.normal,
            speed: fastest.approach_speed,
        };
        push_event(events, report, event);
    }
}

/// The point of `c` with the largest closing speed (the first on ties).
fn fastest_point(c: &Contact) -> Option<&ContactPoint> {
    let mut best: Option<&ContactPoint> = None;
    for p in c.points() {
        if best.is_none_or(|b| p.approach_speed > b.approach_speed) {
            best = Some(p);
        }
    }
    best
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::vec64::Vec64;

    /// The fields every pass over the contacts reads (the pair, the point count, the
    /// flags) lie in the first 24 bytes (one cache line unless the contact starts in
    /// the last 16 bytes of one), and the reorder cost no byte.
    #[test]
    fn the_pair_and_flags_share_the_first_bytes() {
        use core::mem::{offset_of, size_of};
        let ends = [
            offset_of!(Contact, a) + size_of::<u32>(),
            offset_of!(Contact, b) + size_of::<u32>(),
            offset_of!(Contact, sub) + size_of::<u32>(),
            offset_of!(Contact, len) + 1,
            offset_of!(Contact, sensor) + 1,
            offset_of!(Contact, touching) + 1,
            offset_of!(Contact, sticking) + 1,
            offset_of!(Contact, hit_due) + 1,
            offset_of!(Contact, new_parts) + 1,
            offset_of!(Contact, sat_cache) + size_of::<PairCache>(),
        ];
        assert!(ends.iter().all(|&e| e <= 24), "{ends:?}");
        assert_eq!(size_of::<Contact>(), 344);
    }

    /// `copy_from` gives every field of the source and its first `len` points, and
    /// leaves the point slots past them as they were, for every point count; `same_as`
    /// reads the points in use only.
    #[test]
    fn copy_from_copies_every_field_and_the_points_in_use() {
        let mut rng = crate::rng::SplitMix64::new(23);
        let mut v = || rng.range(-5.0, 5.0);
        let mut filled = |seed: u32| {
            let mut c = Contact {
                a: seed,
                b: seed + 1,
                sub: seed + 2,
                len: 0,
                sensor: true,
                touching: true,
                sticking: true,
                hit_due: true,
                new_parts: 3,
                sat_cache: PairCache {
                    axis: crate::collide::SatAxis::Edges(seed as u16, 7),
                },
                normal: Vec3::new(v(), v(), v()),
                material: Material {
                    restitution: v(),
                    static_friction: v(),
                    kinetic_friction: v(),
                    rolling_resistance: v(),
                    twist_friction: v(),
                },
                friction_impulse: Vec3::new(v(), v(), v()),
                twist_impulse: v(),
                built_margin: v(),
                apart_gap: v(),
                points: [ContactPoint::default(); 4],
                built_rot_a: Quat::from_xyzw(v(), v(), v(), v()),
                built_rot_b: Quat::from_xyzw(v(), v(), v(), v()),
                normal_local: Vec3::new(v(), v(), v()),
                built_pose: Iso::new(
                    Vec3::new(v(), v(), v()),
                    Quat::from_xyzw(v(), v(), v(), v()),
                ),
            };
            for (j, p) in c.points.iter_mut().enumerate() {
                *p = ContactPoint {
                    id: u64::from(seed) * 10 + j as u64,
                    local_a: Vec3::new(v(), v(), v()),
                    local_b: Vec3::new(v(), v(), v()),
                    separation: v(),
                    normal_impulse: v(),
                    approach_speed: v(),
                };
            }
            c
        };
        for len in 0..=4u8 {
            let mut src = filled(100);
            src.len = len;
            let mut dst = filled(200);
            dst.len = 4 - len;
            let before = dst;
            dst.copy_from(&src);
            let mut want = src;
            let n = usize::from(len);
            want.points[n..].copy_from_slice(&before.points[n..]);
            assert_eq!(dst, want, "len {len}");
            assert_eq!(dst.points, want.points, "len {len}");
            // The same by meaning: the slots past `len` are not compared, the others are.
            assert!(dst.same_as(&src), "len {len}");
            if let Some(p) = dst.points.get_mut(n) {
                p.normal_impulse += 1.0;
                assert!(dst.same_as(&src), "len {len}");
            }
            if let Some(p) = dst.points.get_mut(n.wrapping_sub(1)) {
                p.normal_impulse += 1.0;
                assert!(!dst.same_as(&src), "len {len}");
            }
            dst.twist_impulse += 1.0;
            assert!(!dst.same_as(&src), "len {len}");
        }
    }

    fn point(id: u64, local_a: Vec3, local_b: Vec3, impulse: f32) -> ContactPoint {
        ContactPoint {
            id,
            local_a,
            local_b,
            normal_impulse: impulse,
            ..ContactPoint::default()
        }
    }

    fn contact(points: &[ContactPoint]) -> Contact {
        let mut c = Contact {
            normal: Vec3::Y,
            len: points.len() as u8,
            ..Contact::default()
        };
        c.points[..points.len()].copy_from_slice(points);
        c
    }

    /// Body point `l` (body frame) in the world, in f64, through the body's rotation
    /// matrix.
    fn in_world(body: &Body<'_>, l: Vec3) -> Vec64 {
        let r = body.rotation_matrix();
        let (x, y, z) = (Vec64::of(r.x), Vec64::of(r.y), Vec64::of(r.z));
        let (lx, ly, lz) = (f64::from(l.x), f64::from(l.y), f64::from(l.z));
        let scaled = |v: Vec64, s: f64| Vec64 {
            x: v.x * s,
            y: v.y * s,
            z: v.z * s,
        };
        scaled(x, lx) + scaled(y, ly) + scaled(z, lz) + Vec64::of(body.pose().position)
    }

    /// A reuse measures its separations with the bodies' rotation matrices, rearranged
    /// (`(R_bᵀ n)·l_b − n_A·l_a + n·(t_b − t_a)`): they agree with the world formula
    /// `(R_b l_b + t_b − R_a l_a − t_a)·n` formed in f64 to rounding, for every point
    /// count; the world normal is A's quaternion turning `n_A`, to rounding; and the
    /// touching flag follows the separations.
    #[test]
    fn reused_separations_follow_the_bodies_poses() {
        use crate::dynamics::body::BodyDesc;
        let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
        let cfg = WorldConfig::DEFAULT;
        let mut a = Body::from_desc_anywhere(&BodyDesc::dynamic(cube)).unwrap();
        let mut b = a;
        let mut rng = crate::rng::SplitMix64::new(41);
        let mut touching = [0u32; 2];
        for round in 0..500 {
            let pose = |rng: &mut crate::rng::SplitMix64| {
                Iso::new(rng.unit_vector() * rng.range(-20.0, 20.0), rng.rotation())
            };
            a.place(pose(&mut rng));
            b.place(pose(&mut rng));
            let len = round % 5;
            let points: [ContactPoint; 4] = core::array::from_fn(|j| {
                let v = |rng: &mut crate::rng::SplitMix64| rng.unit_vector() * rng.range(0.0, 0.9);
                point(j as u64, v(&mut rng), v(&mut rng), 0.0)
            });
            let mut c = contact(points.get(..len).unwrap());
            c.normal_local = rng.unit_vector();
            reuse(&mut c, &a, &b, &cfg);
            let n = a.pose().transform_vector(c.normal_local);
            assert!((c.normal - n).length() < 1e-6, "round {round}");
            let world = |body: &Body<'_>, l: Vec3| in_world(body, l);
            for p in c.points() {
                let gap = world(&b, p.local_b) - world(&a, p.local_a);
                let want = gap.dot(Vec64::of(n));
                assert!(
                    (f64::from(p.separation) - want).abs() < 2e-5,
                    "round {round}: {} against {want}",
                    p.separation
                );
            }
            let any = c.points().iter().any(|p| p.separation <= cfg.slop);
            assert_eq!(c.touching, any, "round {round}");
            if len > 0 {
                touching[usize::from(any)] += 1;
            }
        }
        // Random poses rarely touch: a few pairs placed to, below.
        let (mut a, mut b) = (a, b);
        a.place(Iso::IDENTITY);
        b.place(Iso::from_position(Vec3::new(0.0, 1.0 - 0.002, 0.0)));
        let mut c = contact(&[point(
            0,
            Vec3::new(0.5, 0.5, 0.5),
            Vec3::new(0.5, -0.5, 0.5),
            0.0,
        )]);
        c.normal_local = Vec3::Y;
        reuse(&mut c, &a, &b, &cfg);
        assert!((c.points[0].separation + 0.002).abs() < 1e-6 && c.touching);
        assert!(touching[0] > 100, "{touching:?}");
    }

    /// The convex pair's own reuse test (`convex_reusable`) is a bound: whenever it
    /// passes, no point of B within its bounding radius moved farther than the slack in
    /// A's frame since the build (a brute-force look at B's corners and at points on its
    /// bounding sphere, in f64), and the kept lever arms hold (`arms_kept`). Random moves
    /// and turns of both bodies, up to about twice the bounds: both answers come up.
    #[test]
    fn the_convex_reuse_test_bounds_every_points_drift() {
        use crate::dynamics::body::BodyDesc;
        use crate::math::Quat;
        let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
        let cfg = WorldConfig::DEFAULT;
        let a0 =
            Body::from_desc_anywhere(&BodyDesc::dynamic(cube).position(Vec3::new(3.0, -2.0, 1.0)))
                .unwrap();
        let b0 = Body::from_desc_anywhere(
            &BodyDesc::dynamic(cube).position(Vec3::new(3.1, -1.001, 1.05)),
        )
        .unwrap();
        let mut c = Contact::new_pair(0, 1, Material::DEFAULT, false);
        let p = plan(&c, &a0, &b0, &cfg, 0.0, None).unwrap();
        assert!(build(&mut c, &p, &a0, &b0, &cfg));
        let slack = reuse_slack(&cube, &cube);
        let radius = b0.bounding_radius;
        let mut rng = crate::rng::SplitMix64::new(9);
        let mut probes = [Vec3::ZERO; 64];
        for (k, q) in probes.iter_mut().enumerate() {
            *q = if k < 8 {
                let s = |bit: usize| if k & bit == 0 { -0.5 } else { 0.5 };
                Vec3::new(s(1), s(2), s(4))
            } else {
                rng.unit_vector() * radius
            };
        }
        // B's point `l` in A's frame, in f64.
        let in_a = |a: &Body<'_>, b: &Body<'_>, l: Vec3| {
            let d = in_world(b, l) - Vec64::of(a.pose().position);
            let r = a.rotation_matrix();
            let col = |v: Vec3| Vec64::of(v).dot(d);
            Vec64 {
                x: col(r.x),
                y: col(r.y),
                z: col(r.z),
            }
        };
        let (mut passed, mut failed) = (0, 0);
        for _ in 0..2000 {
            let (mut a, mut b) = (a0, b0);
            for body in [&mut a, &mut b] {
                let shift = rng.unit_vector() * rng.range(0.0, 0.6 * slack);
                let turn = Quat::from_axis_angle(rng.unit_vector(), rng.range(0.0, 1.2 * slack));
                let pose = *body.pose();
                body.place(Iso::new(
                    pose.position + shift,
                    (turn * pose.rotation).normalize(),
                ));
            }
            if !convex_reusable(&c, &a, &b, cfg.speculative_margin) {
                failed += 1;
                continue;
            }
            passed += 1;
            assert!(arms_kept(&c, &a, &b, slack));
            for &l in &probes {
                let moved = libm::sqrt((in_a(&a, &b, l) - in_a(&a0, &b0, l)).length_squared());
                assert!(moved <= f64::from(slack) + 1e-5, "a point moved {moved} m");
            }
        }
        assert!(
            passed > 200 && failed > 200,
            "{passed} passed, {failed} failed"
        );
        // Never built, or built too narrow for this margin: no reuse.
        let fresh = Contact::new_pair(0, 1, Material::DEFAULT, false);
        assert!(!convex_reusable(&fresh, &a0, &b0, cfg.speculative_margin));
        assert!(!convex_reusable(&c, &a0, &b0, c.built_margin + 1e-3));
    }

    /// A pair that turns together keeps its relative pose, but the reuse test refuses
    /// its manifold once a body has turned, since the build, farther than its kept lever
    /// arms allow (`arms_kept`: `2 sin(θ/2) R ≤ slack`): just inside the bound it is
    /// reused, just past it rebuilt, about any axis.
    #[test]
    fn a_pair_turning_together_is_rebuilt_past_the_arms_bound() {
        use crate::dynamics::body::BodyDesc;
        use crate::math::Quat;
        let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
        let cfg = WorldConfig::DEFAULT;
        let a0 = Body::from_desc_anywhere(&BodyDesc::dynamic(cube)).unwrap();
        let b0 = Body::from_desc_anywhere(
            &BodyDesc::dynamic(cube).position(Vec3::new(0.1, 0.999, 0.05)),
        )
        .unwrap();
        let mut c = Contact::new_pair(0, 1, Material::DEFAULT, false);
        let p = plan(&c, &a0, &b0, &cfg, 0.0, None).unwrap();
        assert!(build(&mut c, &p, &a0, &b0, &cfg));
        assert_eq!(c.len, 4);
        // Both centres of mass are their origins: R is the bounding radius.
        let reach = a0.bounding_radius;
        let slack = reuse_slack(&cube, &cube);
        let bound = 2.0 * libm::asinf(slack / (2.0 * reach));
        let mut rng = crate::rng::SplitMix64::new(5);
        for _ in 0..50 {
            let axis = rng.unit_vector();
            for (scale, reused) in [(0.0, true), (0.95, true), (1.05, false), (3.0, false)] {
                let turn = Iso::new(Vec3::ZERO, Quat::from_axis_angle(axis, scale * bound));
                let (mut a, mut b) = (a0, b0);
                a.place(turn * *a0.pose());
                b.place(turn * *b0.pose());
                let p = plan(&c, &a, &b, &cfg, 0.0, None).unwrap();
                // The relative pose moved by rounding only.
                assert!(relative_drift(&c.built_pose, &p.b_in_a, b.bounding_radius) < 1e-5);
                let got = p.reusable(&c, b.bounding_radius, &a, &b);
                assert_eq!(got, reused, "{scale} of the bound about {axis:?}");
            }
        }
    }

    /// Ids first, then the nearest free old point within 2 slop; each old point once.
    #[test]
    fn warm_start_matches_ids_then_nearest_anchor() {
        let slop = 0.005;
        let x = |v: f32| Vec3::new(v, 0.0, 0.0);
        let old = contact(&[
            point(1, x(0.0), x(0.0), 1.0),
            point(2, x(1.0), x(1.0), 2.0),
            point(3, x(2.0), x(2.0), 3.0),
        ]);
        let mut new = contact(&[
            // Same id as old 2 but far away: the id wins.
            point(2, x(5.0), x(5.0), 0.0),
            // Unknown id 0.004 from old 3 (within 2 slop = 0.01): old 3.
            point(8, x(2.004), x(2.004), 0.0),
            // Unknown id next to old 2, which the id match already took: nothing.
            point(9, x(1.001), x(1.001), 0.0),
            // Unknown id 0.011 from everything: nothing (beyond 2 slop).
            point(7, x(3.011), x(3.011), 0.0),
        ]);
        warm_start(&mut new, old.points(), slop);
        let got: [f32; 4] = core::array::from_fn(|i| new.points[i].normal_impulse);
        assert_eq!(got, [2.0, 3.0, 0.0, 0.0]);
    }

    /// A triangle group's shared reuse test gives [`Plan::reusable`]'s answer for every
    /// contact: random relative poses of a box or a hull over a height field, contacts
    /// built at poses moved by up to twice the slack (both sides of both bounds, the
    /// triangle's own bound among them), margins on both sides of the built one, keys
    /// past the last triangle and contacts never built; B turned since the build, both
    /// sides of the arms' bound. Two parts per group share one memo, with the same built
    /// pose and rotations, the same pose only, or neither.
    #[test]
    fn a_triangle_groups_reuse_test_is_the_plans() {
        use crate::dynamics::body::BodyDesc;
        use crate::rng::SplitMix64;
        use crate::shape::{ConvexHull, HeightField};
        let heights: [f32; 16] = core::array::from_fn(|k| 0.1 * (k % 5) as f32);
        let field = HeightField::new(&heights, 4, 4, 0.5).unwrap();
        let corners: [Vec3; 8] = core::array::from_fn(|i| {
            Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2) as f32 * 0.5) * 0.3
        });
        let hull = ConvexHull::new(&corners).unwrap();
        let shapes = [
            Shape::cuboid(Vec3::new(0.3, 0.2, 0.25)).unwrap(),
            Shape::hull(&hull),
        ];
        let cfg = WorldConfig::DEFAULT;
        let mut rng = SplitMix64::new(11);
        let (mut reused, mut refused, mut second_bound, mut arms_refused) = (0, 0, 0, 0);
        for i in 0..4000 {
            let mut ground = BodyDesc::fixed(Shape::HeightField(&field));
            ground.pose = Iso::new(Vec3::new(rng.range(-1.0, 1.0), 0.0, 0.0), rng.rotation());
            let a = Body::from_desc_anywhere(&ground).unwrap();
            let mut d = BodyDesc::dynamic(shapes[i % 2]);
            d.pose = Iso::new(Vec3::new(0.7, 0.4, 0.7), rng.rotation());
            let b = Body::from_desc_anywhere(&d).unwrap();
            let reach = rng.range(0.0, 0.02);
            let frame = TriangleFrame::of(&a, &b, cfg.speculative_margin + reach).unwrap();
            // Built where B was, moved by up to two slacks (turned, shifted or both).
            let now = a.pose().inv_mul(b.pose());
            let step = rng.range(0.0, 2.0 * frame.slack);
            let turn = rng.range(0.0, 2.0 * frame.slack);
            let axis = rng.unit_vector();
            let built = Iso::new(
                now.position + rng.unit_vector() * step,
                crate::math::Quat::from_axis_angle(axis, turn) * now.rotation,
            );
            let elsewhere = Iso::new(
                now.position + rng.unit_vector() * rng.range(0.0, 2.0 * frame.slack),
                now.rotation,
            );
            let mut part = |built: Iso| Contact {
                a: 0,
                b: 1,
                sub: 1 + (rng.next_u64() % 20) as u32, // 18 triangles: some keys past them
                built_pose: built,
                // B's turn since the build is the arms' test's (below), for a contact
                // with points.
                built_rot_a: a.pose().rotation,
                built_rot_b: crate::math::Quat::from_axis_angle(
                    axis,
                    rng.range(0.0, 8.0 * frame.slack),
                ) * b.pose().rotation,
                built_margin: if i % 17 == 0 {
                    -1.0
                } else {
                    frame.margin + rng.range(-0.5, 1.5) * frame.slack
                },
                len: u8::from(rng.next_u64().is_multiple_of(4)),
                ..Contact::default()
            };
            // Two parts of one group, scanned in turn with one memo: the second shares
            // the first's built pose and rotations, its pose, or neither.
            let first = part(built);
            let mut second = part(if i % 3 == 2 { elsewhere } else { built });
            if i % 3 == 0 {
                second.built_rot_b = first.built_rot_b;
            }
            let mut memo = GroupMemo::default();
            for c in [first, second] {
                let by_plan = plan(&c, &a, &b, &cfg, reach, None)
                    .is_some_and(|p| p.reusable(&c, p.shape_b.bounding_radius(), &a, &b));
                let by_frame = frame.reusable(&c, &a, &b, &mut memo);
                assert_eq!(by_frame, by_plan, "contact {i}: {c:?}");
                arms_refused += usize::from(!arms_kept(&c, &a, &b, frame.slack));
                if by_plan {
                    reused += 1;
                    let drift = relative_drift(&c.built_pose, &frame.b_in_a, frame.radius_b);
                    second_bound += usize::from(drift > frame.slack);
                } else {
                    refused += 1;
                }
            }
        }
        // Both answers are common, and some reuses hold only by the triangle's bound.
        assert!(
            reused > 400 && refused > 400,
            "{reused} reused, {refused} refused, {second_bound} by the second bound"
        );
        assert!(second_bound > 0, "the triangle's own bound never decided");
        assert!(arms_refused > 100, "{arms_refused} refused by the arms");
    }

    /// The empty-pair test is sound: whenever two bodies' boxes are more than the margin
    /// apart, a full manifold query with that margin finds nothing. Random poses of
    /// spheres, capsules, cuboids and a hull (bounding-sphere box), half of them near.
    #[test]
    fn apart_boxes_mean_no_point_within_the_margin() {
        use crate::dynamics::body::BodyDesc;
        use crate::math::Iso;
        use crate::rng::SplitMix64;
        use crate::shape::ConvexHull;
        let corners: [Vec3; 8] = core::array::from_fn(|i| {
            Vec3::new((i & 1) as f32, (i >> 1 & 1) as f32, (i >> 2) as f32 * 0.5)
        });
        let hull = ConvexHull::new(&corners).unwrap();
        let shapes = [
            Shape::sphere(0.3).unwrap(),
            Shape::capsule(0.4, 0.2).unwrap(),
            Shape::cuboid(Vec3::new(0.5, 0.2, 0.3)).unwrap(),
            Shape::hull(&hull),
        ];
        let mut rng = SplitMix64::new(7);
        let margin = 0.04;
        let (mut apart_count, mut touching) = (0, 0);
        for i in 0..4000 {
            let body = |rng: &mut SplitMix64, spread: f32| {
                let mut d = BodyDesc::dynamic(shapes[(rng.next_u64() % 4) as usize]);
                let p = Vec3::new(rng.range(-spread, spread), rng.range(-spread, spread), 0.0);
                d.pose = Iso::new(p, rng.rotation());
                let mut b = Body::from_desc_anywhere(&d).unwrap();
                b.refresh_bounds();
                b
            };
            let spread = if i % 2 == 0 { 0.6 } else { 1.2 };
            let (a, b) = (body(&mut rng, spread), body(&mut rng, spread));
            let found = crate::collide::contact(&a.shape, a.pose(), &b.shape, b.pose(), margin)
                .unwrap()
                .is_some();
            touching += usize::from(found);
            if apart(&a, &b, margin) {
                apart_count += 1;
                assert!(
                    !found,
                    "pair {i}: boxes apart, yet a point within the margin"
                );
            }
        }
        // Neither side vacuous: many pairs are told apart by their boxes, many touch.
        assert!(
            apart_count > 800 && touching > 800,
            "{apart_count} apart, {touching} touching"
        );
    }

    /// Two whole spheres are measured afresh every step (module docs, "Sphere pairs"):
    /// whatever the contact held, the narrow phase leaves the point the general query
    /// gives with the step's margin, to the bit, and the impulse of the old point (the
    /// same features) carried over; apart, no point and no friction kept. Coincident
    /// centres included, in both slot orders.
    #[test]
    fn sphere_pairs_are_measured_afresh_as_the_query_gives_them() {
        use crate::collide::ContactId;
        use crate::dynamics::body::BodyDesc;
        use crate::rng::SplitMix64;
        use crate::shape::FeatureId;
        let cfg = WorldConfig::default();
        let mut rng = SplitMix64::new(23);
        let (mut hits, mut misses) = (0, 0);
        for i in 0..3000 {
            let body = |rng: &mut SplitMix64, p: Vec3| {
                let mut d = BodyDesc::dynamic(Shape::sphere(rng.range(0.1, 0.6)).unwrap());
                d.pose = Iso::new(p, rng.rotation());
                d.linear_velocity = rng.unit_vector() * rng.range(0.0, 2.0);
                d.angular_velocity = rng.unit_vector() * rng.range(0.0, 3.0);
                Body::from_desc_anywhere(&d).unwrap()
            };
            let p = |rng: &mut SplitMix64| {
                Vec3::new(
                    rng.range(-0.7, 0.7),
                    rng.range(-0.7, 0.7),
                    rng.range(-0.7, 0.7),
                )
            };
            let at_a = p(&mut rng);
            let a = body(&mut rng, at_a);
            let at = if i % 100 == 0 { at_a } else { p(&mut rng) };
            let b = body(&mut rng, at);
            // Whatever the contact held before: a reusable-looking manifold with the
            // sphere pair's feature id, or another point, and a tangent impulse.
            let old_id = ContactId {
                a: FeatureId::vertex(0),
                b: FeatureId::vertex(0),
            };
            let id = if i % 3 == 0 { 99 } else { old_id.key() };
            let mut c = contact(&[point(id, Vec3::X, Vec3::Y, 2.5)]);
            c.built_margin = 1.0;
            c.friction_impulse = Vec3::new(0.3, -0.2, 0.1);
            narrow_phase(&mut c, &a, &b, &cfg);
            // The step's margin: speculative, grown by the pair's reach when swept.
            let margin = cfg.speculative_margin + pair_reach(&a, &b, &cfg);
            let want =
                crate::collide::contact(&a.shape, a.pose(), &b.shape, b.pose(), margin).unwrap();
            assert_eq!(c.built_margin, -1.0, "pair {i}: never reused");
            let Some(m) = want else {
                misses += 1;
                assert_eq!((c.len, c.touching), (0, false), "pair {i}");
                assert_eq!(c.friction_impulse, Vec3::ZERO, "pair {i}");
                continue;
            };
            hits += 1;
            assert_eq!((c.len, m.len), (1, 1), "pair {i}");
            let (got, src) = (c.points[0], m.points[0]);
            let bits = |v: Vec3| [v.x.to_bits(), v.y.to_bits(), v.z.to_bits()];
            assert_eq!(bits(c.normal), bits(m.normal), "pair {i}");
            assert_eq!(bits(got.local_a), bits(src.local_a), "pair {i}");
            assert_eq!(bits(got.local_b), bits(src.local_b), "pair {i}");
            assert_eq!(
                got.separation.to_bits(),
                src.separation.to_bits(),
                "pair {i}"
            );
            assert_eq!(got.id, src.id.key(), "pair {i}");
            assert_eq!(c.touching, src.separation <= cfg.slop, "pair {i}");
            // The old point's impulse when the features match (or the anchors are near).
            let near = (Vec3::X - got.local_a).length() <= 2.0 * cfg.slop
                && (Vec3::Y - got.local_b).length() <= 2.0 * cfg.slop;
            let carried = if id == old_id.key() || near { 2.5 } else { 0.0 };
            assert_eq!(got.normal_impulse, carried, "pair {i}");
            // The tangent impulse kept in the new tangent plane.
            assert!(c.friction_impulse.dot(c.normal).abs() < 1e-6, "pair {i}");
        }
        assert!(
            hits > 800 && misses > 800,
            "{hits} touching, {misses} apart"
        );
    }

    /// Anchors must be near on both bodies: a point that slid 1 cm on B is not matched.
    #[test]
    fn fallback_needs_both_anchors_close() {
        let old = contact(&[point(1, Vec3::ZERO, Vec3::ZERO, 4.0)]);
        let mut new = contact(&[point(5, Vec3::ZERO, Vec3::new(0.0, 0.0, 0.0101), 0.0)]);
        warm_start(&mut new, old.points(), 0.005);
        assert_eq!(new.points[0].normal_impulse, 0.0);
        let mut near = contact(&[point(5, Vec3::ZERO, Vec3::new(0.0, 0.0, 0.0099), 0.0)]);
        warm_start(&mut near, old.points(), 0.005);
        assert_eq!(near.points[0].normal_impulse, 4.0);
    }

    /// New pairs merge into the sorted list in place; beyond the capacity the highest keys
    /// are dropped, counted, and their bodies flagged to retry.
    #[test]
    fn insert_pairs_merges_in_order_and_drops_the_highest_keys() {
        use crate::dynamics::body::BodyDesc;
        use crate::shape::Shape;
        let mut bodies: Pool<Body<'static>, 8> = Pool::new();
        for i in 0..8 {
            let d = BodyDesc::dynamic(Shape::sphere(0.5).unwrap())
                .position(Vec3::new(i as f32, 0.0, 0.0));
            let mut b = Body::from_desc(&d).unwrap();
            b.moved = false;
            bodies.insert(b).unwrap();
        }
        let mut contacts: HVec<Contact, 6> = HVec::new();
        let mut report = StepReport::default();
        let cfg = WorldConfig::DEFAULT;
        insert_pairs(
            &mut contacts,
            &[(0, 3), (2, 5)],
            &mut bodies,
            &cfg,
            &mut report,
        );
        contacts[0].len = 2; // mark the old ones
        contacts[1].len = 2;
        insert_pairs(
            &mut contacts,
            &[(0, 1), (1, 2), (2, 6), (3, 4), (6, 7)],
            &mut bodies,
            &cfg,
            &mut report,
        );
        let keys: std::vec::Vec<(u32, u32, u8)> =
            contacts.iter().map(|c| (c.a, c.b, c.len)).collect();
        assert_eq!(
            keys,
            [
                (0, 1, 0),
                (0, 3, 2),
                (1, 2, 0),
                (2, 5, 2),
                (2, 6, 0),
                (3, 4, 0)
            ]
        );
        assert_eq!(report.dropped_contacts, 1);
        let moved: std::vec::Vec<bool> = (0..8).map(|i| bodies.at(i).unwrap().moved).collect();
        assert_eq!(
            moved,
            [false, false, false, false, false, false, true, true]
        );
        assert!(contains_pair(&contacts, (2, 6)) && !contains_pair(&contacts, (6, 7)));
    }

    /// The drift bound holds for random relative moves: every point within the radius
    /// moves by at most the bound.
    /// The index answers every lookup as the binary search does, built or not, with
    /// slots that have no contact, a last slot, and pairs beyond the contacts.
    #[test]
    fn pair_index_agrees_with_binary_search() {
        const N: usize = 24;
        let mut rng = crate::rng::SplitMix64::new(21);
        for round in 0..20 {
            let mut contacts = std::vec::Vec::new();
            for a in 0..N as u32 {
                for b in a + 1..N as u32 {
                    if rng.next_u64().is_multiple_of(1 + round % 5) {
                        contacts.push(Contact::new_pair(a, b, Material::DEFAULT, false));
                    }
                }
            }
            for build in [false, true] {
                let index: PairIndex<'_, N> = PairIndex::new(&contacts, build);
                for a in 0..N as u32 + 2 {
                    for b in a + 1..N as u32 + 3 {
                        assert_eq!(
                            index.contains((a, b)),
                            contains_pair(&contacts, (a, b)),
                            "round {round} ({a}, {b}) built {build}"
                        );
                    }
                }
            }
        }
    }

    /// The closing bound holds: two bodies moving at random for a short time `δ` (each
    /// centre of mass on a straight line, turning about it) come no closer than `δ` times
    /// the bound, for balls, capsules, boxes and a hull whose centre of mass lies off its
    /// origin; balls that only turn have a bound of zero.
    #[test]
    fn the_closing_bound_holds_the_gap_as_the_bodies_move() {
        use crate::dynamics::body::BodyDesc;
        use crate::math::Quat;
        let mut rng = crate::rng::SplitMix64::new(29);
        // A hull whose centre of mass lies well off its origin.
        let cloud: std::vec::Vec<Vec3> = (0..12)
            .map(|_| Vec3::new(0.9, -0.4, 0.6) + rng.unit_vector() * rng.range(0.2, 0.7))
            .collect();
        let hull = crate::shape::ConvexHull::new(&cloud).unwrap();
        let shapes = [
            Shape::sphere(0.4).unwrap(),
            Shape::capsule(0.6, 0.25).unwrap(),
            Shape::cuboid(Vec3::new(0.5, 0.2, 0.8)).unwrap(),
            Shape::hull(&hull),
        ];
        // Where a body is after `dt`: its centre of mass on a straight line, turned about
        // it (the integrator's motion).
        let moved = |b: &Body<'_>, dt: f32| {
            let w = b.angular_velocity;
            let turn = match w.normalize_and_length() {
                Some((axis, speed)) => Quat::from_axis_angle(axis, speed * dt),
                None => Quat::IDENTITY,
            };
            let q = (turn * b.pose().rotation).normalize();
            let c = b.world_center() + b.linear_velocity * dt;
            Iso::new(c - q.rotate(b.center_local), q)
        };
        let mut checked = 0;
        for k in 0..4000 {
            let (sa, sb) = (shapes[k % 4], shapes[(k / 4) % 4]);
            let mut a = Body::from_desc_anywhere(
                &BodyDesc::dynamic(sa)
                    .position(rng.unit_vector() * rng.range(0.0, 0.5))
                    .rotation(rng.rotation()),
            )
            .unwrap();
            let mut b = Body::from_desc_anywhere(
                &BodyDesc::dynamic(sb)
                    .position(rng.unit_vector() * rng.range(1.5, 3.5))
                    .rotation(rng.rotation()),
            )
            .unwrap();
            // Every fourth pair only turns: balls turning in place close on nothing.
            let still = k % 16 >= 12;
            for body in [&mut a, &mut b] {
                body.linear_velocity = if still {
                    Vec3::ZERO
                } else {
                    rng.unit_vector() * rng.range(0.0, 5.0)
                };
                body.angular_velocity = rng.unit_vector() * rng.range(0.0, 30.0);
                body.refresh_spin_reach();
            }
            let gap = |pa: &Iso, pb: &Iso| {
                crate::collide::distance(&sa, pa, &sb, pb, &mut Default::default())
                    .unwrap()
                    .distance
            };
            let d0 = gap(a.pose(), b.pose());
            if d0 <= 0.0 {
                continue;
            }
            let dt = 2.0e-3;
            let d1 = gap(&moved(&a, dt), &moved(&b, dt));
            let bound = closing_bound(&a, &b);
            // 1e-5 m: the rounding of two distances at a few metres.
            assert!(
                d1 >= d0 - dt * bound - 1.0e-5,
                "{k}: {d0} → {d1}, bound {bound}"
            );
            if still && matches!((sa, sb), (Shape::Sphere(_), Shape::Sphere(_))) {
                assert_eq!(bound, 0.0);
            }
            checked += 1;
        }
        assert!(checked > 3000, "{checked}");
    }

    #[test]
    fn relative_drift_bounds_point_motion() {
        let mut rng = crate::rng::SplitMix64::new(3);
        for _ in 0..2000 {
            let from = Iso::new(rng.unit_vector() * rng.range(0.0, 2.0), rng.rotation());
            let turn = crate::math::Quat::from_axis_angle(
                rng.unit_vector(),
                rng.range(0.0, core::f32::consts::PI),
            );
            let to = Iso::new(
                from.position + rng.unit_vector() * rng.range(0.0, 0.1),
                (turn * from.rotation).normalize(),
            );
            let r = rng.range(0.1, 2.0);
            let bound = relative_drift(&from, &to, r);
            for _ in 0..8 {
                let p = rng.unit_vector() * r;
                let moved = to.transform_point(p).distance(from.transform_point(p));
                assert!(moved <= bound * 1.0001 + 1e-6, "{moved} > {bound}");
            }
        }
    }
}
