//! Stages 2 and 3: movement bounds, enlarged boxes, and the search for new pairs.
//!
//! # Movement bounds and enlarged boxes (stage 2)
//!
//! An awake body that moves gets the box its shape sweeps over the step `dt`
//! ([`crate::collide::movement_bounds`]) from its current pose with its velocity (plus
//! the gravity and force of this step), grown by the speculative margin, so two shapes
//! closer than the margin always have overlapping boxes. That box is compared with the
//! body's *enlarged box* `Body::fat`: while it fits, nothing changes; when it leaves,
//! the enlarged box becomes the movement box stretched two more steps' motion ahead
//! (at most the body's bounding radius: [`look_ahead`]) and grown by `aabb_margin`, and
//! the body is flagged `moved`. A body in steady motion (a falling pile) so leaves its
//! box every few steps instead of every step (`spheres`' first 100 steps: 11 % fewer
//! instructions). Static bodies have their exact box, set when they are added or
//! teleported; sleeping bodies keep theirs.
//!
//! # New pairs (stage 3)
//!
//! A contact lives as long as the enlarged boxes of its two bodies overlap
//! (`contact::update_contacts` removes it once they do not), so only pairs with a moved
//! body can be new. The enlarged boxes are the leaves of a dynamic AABB tree
//! ([`AabbTree`], Box2D v3's `b2DynamicTree`: insertion by the surface-area heuristic,
//! rotations), one leaf per body, tagged with the body's kind. When some body moved,
//! its leaf is inserted (a body that appeared) or moved to its new enlarged box, and
//! then the overlapping boxes are looked up in one of two ways, which find the same set:
//!
//! - **a few moved bodies** (fewer than one leaf in two): each asks the tree for the
//!   boxes that overlap its own: a dynamic body all of them, a static or kinematic one
//!   only the dynamic ones (the only kind it may pair with, [`may_pair`]). A pair of two
//!   moved bodies is taken from the lower slot's query only;
//! - **many**: one walk of the tree against itself ([`AabbTree::overlapping_pairs`])
//!   lists every pair of overlapping leaves with a moved body and a dynamic one, crossing
//!   the upper levels of the tree once instead of once per query (a walk whose stack
//!   overflows gives way to the queries).
//!
//! The pairs that may collide and have no contact yet are the new pairs, sorted by
//! `(a, b)`; when many bodies moved, "no contact yet" is looked up in a
//! per-body index of the contacts ([`PairIndex`]) rather than by binary search. A step in
//! which nothing moved out of its box does no tree work at all: a resting or sleeping
//! world costs one box test per awake body.
//!
//! One tree holds every kind of body, where Box2D v3 keeps one tree per body type: the
//! category bits of the internal nodes (the union of their leaves') let a static or
//! kinematic body's query skip the subtrees without a dynamic body, which is what a
//! separate tree of movable bodies would give, and one tree of `N` leaves needs `2N`
//! nodes where two trees, each of which may have to hold every body, would need `4N`.
//!
//! The tree's leaf of a body always holds `Body::fat` as of the body's last search:
//! whatever replaces `fat` (stage 2, `World::set_pose`, `World::add`) also flags the
//! body `moved`, and the search moves the leaf of every moved body before querying.
//!
//! Removing a body removes its leaf (`World::remove`). A snapshot does not store the
//! tree: `restore` marks it stale, and the next step builds it again from the bodies'
//! enlarged boxes in slot order ([`BroadPhase::invalidate`]).
//!
//! # Determinism
//!
//! The tree's shape depends on its history (the order of insertions and moves), and a
//! restored world's tree is built in another order than the original's, so nothing the
//! world computes may depend on the order a query visits the leaves. It does not: the
//! new pairs are a set, sorted afterwards, and when the pair buffer is full the pairs
//! kept are those with the smallest `(a, b)` keys, by a bounded max-heap over the
//! buffer: a pair is kept exactly when fewer than `P` of all the new pairs have a smaller
//! key, whatever the order they were found in. The others are counted in
//! `StepReport::dropped_pairs` and their bodies stay flagged `moved`, so they are offered
//! again next step. Continuous collision's query ([`BroadPhase::overlapping`]) sorts its
//! answer by slot.
//!
//! Work is bounded: a tree operation is `O(height)`, a query `O(height + answer)` (a
//! linear scan of the leaves if the tree is pathologically tall), and the heap `O(log P)`
//! per pair that does not fit.

use heapless::Vec as HVec;

use super::aabb_tree::{AabbTree, NULL};
use super::body::{Body, BodyKind};
use super::contact::{Contact, PairIndex};
use super::events::StepReport;
use super::pool::Pool;
use super::solver::clamp_length;
use crate::collide::{movement_bounds, Motion};
use crate::config::WorldConfig;
use crate::math::{scalar, Aabb, Vec3};

/// Category bit of a static body's leaf.
const STATIC: u8 = 0b001;
/// Category bit of a kinematic body's leaf.
const KINEMATIC: u8 = 0b010;
/// Category bit of a dynamic body's leaf.
const DYNAMIC: u8 = 0b100;
/// Every category.
const ANY: u8 = STATIC | KINEMATIC | DYNAMIC;

/// The category of a body's leaf.
fn category(kind: BodyKind) -> u8 {
    match kind {
        BodyKind::Static => STATIC,
        BodyKind::Kinematic => KINEMATIC,
        BodyKind::Dynamic => DYNAMIC,
    }
}

/// The categories a body of `kind` may pair with: everything for a dynamic body, only
/// dynamic bodies for the others ([`may_pair`]).
fn partners(kind: BodyKind) -> u8 {
    match kind {
        BodyKind::Dynamic => ANY,
        BodyKind::Static | BodyKind::Kinematic => DYNAMIC,
    }
}

/// A search walks the tree against itself when at least one leaf in `WALK_MOVES` moved.
/// Half: with a quarter (the first choice) the `spheres` scene's first 100 steps ran
/// 0.7 % more instructions, with an eighth 3.4 % more; between a quarter and a half of
/// the leaves, their queries cost less than the walk.
const WALK_MOVES: usize = 2;

/// Node pairs that may wait at once in the walk (a walk needs about three per level of
/// the tree; one that needs more gives way to the queries).
const WALK_STACK: usize = 256;

/// The broad phase: a dynamic AABB tree over the bodies' enlarged boxes.
#[derive(Clone, Debug)]
pub(crate) struct BroadPhase<const N: usize> {
    /// One leaf per body that has been through a search, with the body's enlarged box
    /// and its kind's category; the user value is the slot.
    tree: AabbTree<N>,
    /// Per slot: the body's leaf in `tree`, or [`NULL`].
    proxies: [u32; N],
    /// The tree does not describe the bodies (a snapshot was restored): build it again
    /// before using it.
    stale: bool,
    /// Tree operations (insertions, moves, removals, queries) so far: tests check that a
    /// step in which nothing moved does none.
    #[cfg(test)]
    pub work: u32,
}

impl<const N: usize> BroadPhase<N> {
    /// Empty.
    pub const fn new() -> Self {
        BroadPhase {
            tree: AabbTree::new(),
            proxies: [NULL; N],
            stale: false,
            #[cfg(test)]
            work: 0,
        }
    }

    /// Back to [`BroadPhase::new`]'s state where it lies.
    pub fn reset(&mut self) {
        self.tree.reset();
        self.proxies.fill(NULL);
        self.stale = false;
        #[cfg(test)]
        {
            self.work = 0;
        }
    }

    /// Forget the tree (the bodies were replaced, as by a restore): the next search
    /// builds it again from the bodies' enlarged boxes, in slot order.
    pub fn invalidate(&mut self) {
        self.stale = true;
    }

    /// Drop the leaf of the body in `slot` (it is being removed).
    pub fn remove_body(&mut self, slot: u32) {
        let Some(p) = self.proxies.get_mut(slot as usize) else {
            return;
        };
        if *p != NULL {
            self.tree.remove(*p);
            *p = NULL;
            self.count_work();
        }
    }

    #[inline]
    fn count_work(&mut self) {
        #[cfg(test)]
        {
            self.work = self.work.saturating_add(1);
        }
    }

    /// Build the tree from scratch: one leaf per live body, in slot order.
    fn rebuild(&mut self, bodies: &Pool<Body<'_>, N>) {
        self.tree.clear();
        self.proxies = [NULL; N];
        for (slot, b) in bodies.iter() {
            self.insert(slot, b);
        }
        self.stale = false;
    }

    fn insert(&mut self, slot: usize, b: &Body<'_>) {
        let proxy = self.tree.insert(b.fat, slot as u32, category(b.kind));
        if let Some(p) = self.proxies.get_mut(slot) {
            // `None` cannot happen: one leaf per slot, at most `N`.
            *p = proxy.unwrap_or(NULL);
        }
        self.count_work();
    }

    /// Make the leaf of the body in `slot` hold its current enlarged box and kind:
    /// insert it if it has none, move it if its box changed.
    fn sync(&mut self, slot: usize, b: &Body<'_>) {
        let proxy = self.proxies.get(slot).copied().unwrap_or(NULL);
        if proxy == NULL {
            self.insert(slot, b);
            return;
        }
        if self.tree.category(proxy) != Some(category(b.kind)) {
            // Another body took the slot without a removal: start afresh.
            self.tree.remove(proxy);
            self.insert(slot, b);
            return;
        }
        if self.tree.aabb(proxy) != Some(b.fat) {
            if !self.tree.move_proxy(proxy, b.fat) {
                self.insert(slot, b);
            }
            self.count_work();
        }
    }

    /// Stage 3: the pairs `(lower slot, higher slot)` whose enlarged boxes overlap, with
    /// at least one body flagged `moved`, that may pair ([`may_pair`]) and have no
    /// contact in `contacts` yet, sorted by `(a, b)`. Clears the `moved` flags.
    ///
    /// When there are more than `P` such pairs, the `P` with the smallest keys are kept
    /// (whatever the tree's shape, module docs); the rest are counted in
    /// `report.dropped_pairs` and both bodies of each stay flagged, so the search offers
    /// them again next step.
    pub fn find_new_pairs<const P: usize>(
        &mut self,
        bodies: &mut Pool<Body<'_>, N>,
        contacts: &[Contact],
        pairs: &mut HVec<(u32, u32), P>,
        report: &mut StepReport,
    ) {
        self.find_new_pairs_with::<P, WALK_STACK>(bodies, contacts, pairs, report);
    }

    /// [`BroadPhase::find_new_pairs`] with a walk stack of `S` node pairs.
    fn find_new_pairs_with<const P: usize, const S: usize>(
        &mut self,
        bodies: &mut Pool<Body<'_>, N>,
        contacts: &[Contact],
        pairs: &mut HVec<(u32, u32), P>,
        report: &mut StepReport,
    ) {
        pairs.clear();
        if self.stale {
            self.rebuild(bodies);
        }
        let mut moved = 0usize;
        for (slot, b) in bodies.iter() {
            if b.moved {
                self.sync(slot, b);
                moved += 1;
            }
        }
        if moved == 0 {
            return;
        }
        // Some 8 lookups per moved body, each a binary search of about 16 probes, against
        // one pass over the contacts and the slots.
        let build = moved.saturating_mul(128) >= contacts.len().saturating_add(bodies.high());
        let index: PairIndex<'_, N> = PairIndex::new(contacts, build);
        let mut kept = SmallestPairs::new(pairs);
        let mut retry = [false; N];
        // Offer the pair of the distinct slots `i` and `j` (boxes that overlap, one moved).
        let offer = |kept: &mut SmallestPairs<'_, P>, retry: &mut [bool; N], i: u32, j: u32| {
            let (Some(body_i), Some(body_j)) = (bodies.at(i as usize), bodies.at(j as usize))
            else {
                return;
            };
            if !body_i.fat.overlaps(&body_j.fat) || !may_pair(body_i, body_j) {
                return;
            }
            let pair = if i < j { (i, j) } else { (j, i) };
            if index.contains(pair) {
                return;
            }
            if let Some((a, b)) = kept.offer(pair) {
                for s in [a, b] {
                    if let Some(r) = retry.get_mut(s as usize) {
                        *r = true;
                    }
                }
            }
        };
        // Many moved bodies: the tree against itself in one walk (module docs).
        let mut found = false;
        if moved.saturating_mul(WALK_MOVES) >= self.tree.len() {
            let is_moved = |slot: u32| bodies.at(slot as usize).is_some_and(|b| b.moved);
            found = self.tree.overlapping_pairs::<S>(is_moved, DYNAMIC, |i, j| {
                offer(&mut kept, &mut retry, i, j);
            });
            self.count_work();
            if !found {
                // The walk's stack overflowed: start over, one query per moved body.
                kept = SmallestPairs::new(kept.pairs);
                kept.pairs.clear();
                retry = [false; N];
            }
        }
        if !found {
            for (i, body_i) in bodies.iter() {
                if !body_i.moved {
                    continue;
                }
                let slot_i = i as u32;
                self.tree
                    .query(&body_i.fat, partners(body_i.kind), |slot_j| {
                        // A pair of two moved bodies comes from the lower slot's query.
                        let moved_j = bodies.at(slot_j as usize).is_some_and(|b| b.moved);
                        if slot_j == slot_i || (moved_j && slot_j < slot_i) {
                            return;
                        }
                        offer(&mut kept, &mut retry, slot_i, slot_j);
                    });
                self.count_work();
            }
        }
        let dropped = kept.dropped;
        // Keys are unique (each unordered pair is offered once), so an unstable sort is
        // deterministic.
        crate::sort::sort_pairs(pairs);
        for (i, b) in bodies.iter_mut() {
            // The mid phase lists this body's part pairs again (`mid_phase`, "Lists kept").
            b.relist |= b.moved;
            b.moved = retry.get(i).copied().unwrap_or(false);
        }
        report.dropped_pairs = report.dropped_pairs.saturating_add(dropped);
    }

    /// The slots of every body whose enlarged box overlaps `aabb`, in slot order, into
    /// `out` (cleared first). Uses the tree unless it is stale, then the bodies' boxes.
    /// Valid after the step's search (stage 3): every box that changed since is the box of
    /// a body flagged `moved`, which the search has put into the tree.
    pub fn overlapping(&self, bodies: &Pool<Body<'_>, N>, aabb: &Aabb, out: &mut HVec<u32, N>) {
        out.clear();
        if self.stale {
            for (slot, b) in bodies.iter() {
                if b.fat.overlaps(aabb) {
                    // Cannot fail: at most `N` distinct slots.
                    let _ = out.push(slot as u32);
                }
            }
            return;
        }
        self.tree.query(aabb, ANY, |slot| {
            if bodies
                .at(slot as usize)
                .is_some_and(|b| b.fat.overlaps(aabb))
            {
                let _ = out.push(slot);
            }
        });
        // Distinct slots: an unstable sort is deterministic.
        crate::sort::sort_unstable(out);
    }
}

/// The pair buffer of one search, keeping the `P` smallest keys offered: plain pushes
/// until it is full, then a max-heap on the key (the largest kept pair at the root), so
/// a new pair smaller than the root replaces it. The result is the `P` smallest, in heap
/// order: sort it afterwards.
struct SmallestPairs<'p, const P: usize> {
    pairs: &'p mut HVec<(u32, u32), P>,
    /// The buffer is full and a heap.
    heap: bool,
    /// Pairs offered and not kept (dropped at once, or pushed out by a smaller one).
    dropped: u32,
}

impl<'p, const P: usize> SmallestPairs<'p, P> {
    fn new(pairs: &'p mut HVec<(u32, u32), P>) -> Self {
        SmallestPairs {
            pairs,
            heap: false,
            dropped: 0,
        }
    }

    /// Offer a pair (distinct from every pair offered before); returns the pair dropped
    /// for it, if any: itself, or the largest kept pair it pushed out.
    fn offer(&mut self, pair: (u32, u32)) -> Option<(u32, u32)> {
        if !self.heap {
            if self.pairs.push(pair).is_ok() {
                return None;
            }
            // Full: make it a max-heap, sifting down every parent from the last one.
            for i in (0..self.pairs.len() / 2).rev() {
                sift_down(self.pairs, i);
            }
            self.heap = true;
        }
        self.dropped = self.dropped.saturating_add(1);
        match self.pairs.first_mut() {
            Some(root) if pair < *root => {
                let out = core::mem::replace(root, pair);
                sift_down(self.pairs, 0);
                Some(out)
            }
            _ => Some(pair),
        }
    }
}

/// Restore the max-heap below position `i` (children of `k` at `2k + 1`, `2k + 2`).
fn sift_down(heap: &mut [(u32, u32)], mut i: usize) {
    // The position at least doubles every round: at most log₂ len rounds.
    while let Some(&here) = heap.get(i) {
        let (l, r) = (2 * i + 1, 2 * i + 2);
        let mut top = i;
        let mut top_pair = here;
        for c in [l, r] {
            if let Some(&p) = heap.get(c) {
                if p > top_pair {
                    top = c;
                    top_pair = p;
                }
            }
        }
        if top == i || i >= heap.len() || top >= heap.len() {
            return;
        }
        heap.swap(i, top);
        i = top;
    }
}

/// True when two bodies whose boxes overlap get a contact: at least one is dynamic
/// (static and kinematic bodies never push each other) and their filters agree,
/// `a.group & b.mask != 0 && b.group & a.mask != 0`.
pub(crate) fn may_pair(a: &Body<'_>, b: &Body<'_>) -> bool {
    let some_dynamic = a.kind == BodyKind::Dynamic || b.kind == BodyKind::Dynamic;
    let filters_agree = a.group & b.mask != 0 && b.group & a.mask != 0;
    some_dynamic && filters_agree
}

/// True when the narrow phase should look at a contact's two bodies: they may pair and
/// at least one is awake (two sleeping bodies, or a sleeping body and a static one, keep
/// their contact unchanged instead; see `contact::update_contacts`).
pub(crate) fn may_collide(a: &Body<'_>, b: &Body<'_>) -> bool {
    may_pair(a, b) && (a.awake || b.awake)
}

/// Stage 2: clamp the velocities of every awake, non-static body to the speed limits
/// (a setter may have left them above), then refresh the enlarged box of those whose
/// movement bounds over the step left it (module docs).
pub(crate) fn update_fat_boxes<const N: usize>(bodies: &mut Pool<Body<'_>, N>, cfg: &WorldConfig) {
    for (_, body) in bodies.iter_mut() {
        if body.kind == BodyKind::Static || !body.awake {
            continue;
        }
        body.linear_velocity = clamp_length(body.linear_velocity, cfg.max_linear_speed);
        body.angular_velocity = clamp_length(body.angular_velocity, cfg.max_angular_speed);
        let (motion, arc) = body_motion(body, cfg);
        let grown = |b: Aabb| {
            arc.map_or(b, |a| b.expanded(a))
                .expanded(cfg.speculative_margin)
        };
        // The shape's box now: the narrow phase's bounds and the cover's start.
        let now = body.shape.aabb_turned(body.pose(), body.rotation_matrix());
        body.refresh_bounds_from(now);
        // Most bodies stay well inside their enlarged box: a cheap cover of the movement
        // bounds settles it (the same answer: the bounds lie inside the cover).
        let cover = movement_cover(
            body.bounding_radius,
            body.core_reach(),
            &motion,
            now,
            cfg.dt,
        );
        if body.fat.contains(&grown(cover)) {
            continue;
        }
        let tight = grown(movement_bounds(&body.shape, &motion, cfg.dt));
        if !body.fat.contains(&tight) {
            body.fat = tight
                .union(&tight.translated(look_ahead(body, &motion, cfg.dt)))
                .expanded(cfg.aabb_margin);
            body.moved = true;
        }
    }
}

/// How far ahead (m) a body's new enlarged box reaches beyond this step's movement: the
/// step's displacement `v dt` taken [`LOOK_AHEAD_STEPS`] times more, at most the body's
/// bounding radius (Box2D v2's `aabbMultiplier`). A body in steady motion (a falling
/// pile) then leaves its box every few steps instead of every step; the length cap keeps
/// a fast small body (a bullet) from dragging a long box through the world.
fn look_ahead(body: &Body<'_>, motion: &Motion, dt: f32) -> Vec3 {
    let d = motion.linear * (LOOK_AHEAD_STEPS * scalar::abs(dt));
    clamp_length(d, body.bounding_radius)
}

/// Steps of motion a new enlarged box looks ahead ([`look_ahead`]).
const LOOK_AHEAD_STEPS: f32 = 2.0;

/// The box `body` covers over the next step (without the margins): its velocity plus
/// what gravity and the accumulated force add in the step.
///
/// Body velocities are those of the centre of mass `c`; [`Motion`] moves the body frame's
/// origin `o` on a straight line with `v_o = v + ω × (o − c)` and turns the shape about
/// it. The integrator instead moves `c` on the straight line and turns about `c`, so the
/// origin follows an arc: with `ℓ = o − c` and `R(t)` the step's rotation by `φ ≤ |ω| t`,
/// the true origin is off the straight line by `d(t) = R(t) ℓ − ℓ − t ω × ℓ`. Taylor's
/// bound on the rotation gives `|d| ≤ |ℓ| W²` for `W = |ω| dt ≤ 1` (the
/// `1 − cos φ ≤ W²/2` term plus `|W − sin φ| ≤ W³/4`), and `|d| ≤ |ℓ| (2 + W)` always. The
/// box grows by that bound; it is zero for shapes whose centre of mass is their origin.
#[cfg(test)]
pub(crate) fn body_bounds(body: &Body<'_>, cfg: &WorldConfig) -> Aabb {
    if body.kind == BodyKind::Static || !body.awake {
        return body.shape.aabb(body.pose());
    }
    let (motion, arc) = body_motion(body, cfg);
    let swept = movement_bounds(&body.shape, &motion, cfg.dt);
    arc.map_or(swept, |a| swept.expanded(a))
}

/// The straight-line motion of `body`'s frame origin over the next step and, for a body
/// whose centre of mass is off its origin, the arc bound (m) to grow its bounds by
/// ([`body_bounds`]).
fn body_motion(body: &Body<'_>, cfg: &WorldConfig) -> (Motion, Option<f32>) {
    let dt = cfg.dt;
    let center = body.world_center();
    let origin_from_center = body.pose().position - center;
    let mut v = body.linear_velocity;
    if body.is_dynamic() {
        // What the step can reach: the integrator clamps to the speed limit.
        v = clamp_length(
            v + (cfg.gravity + body.force * body.inv_mass) * dt,
            cfg.max_linear_speed,
        );
    }
    let motion = Motion {
        pose: *body.pose(),
        linear: v + body.angular_velocity.cross(origin_from_center),
        angular: body.angular_velocity,
    };
    let arm = origin_from_center.length();
    let arc = (arm > 0.0).then(|| {
        let w = body.angular_velocity.length() * scalar::abs(dt);
        if w <= 1.0 {
            arm * w * w
        } else {
            arm * (2.0 + w)
        }
    });
    (motion, arc)
}

/// A box that holds [`movement_bounds`]`(shape, motion, dt)` of a shape of bounding
/// radius `r` (`Shape::bounding_radius`) and core reach `rho` (`Shape::core_reach`), for
/// about a tenth of its cost (no rotation is integrated; `now` is the shape's box at
/// `motion.pose`): that box and the same box moved by `v dt`, grown by how far a turn of
/// `W = |ω| dt` moves a point of the shape (its core's points, within `rho` of the
/// origin: a chord, at most `rho W`; the inflating radius turns onto itself), by the
/// bulge the bounds allow (`rho W² / 7`) and by a rounding guard ten times theirs.
fn movement_cover(r: f32, rho: f32, motion: &Motion, now: Aabb, dt: f32) -> Aabb {
    let shift = motion.linear * dt;
    let w = motion.angular.length() * scalar::abs(dt);
    let c0 = motion.pose.position;
    let guard = COVER_ROUNDING * (r + c0.abs().max_elem() + (c0 + shift).abs().max_elem());
    now.union(&now.translated(shift))
        .expanded(rho * w * (1.0 + w * (1.0 / 7.0)) + guard)
}

/// Relative rounding guard of [`movement_cover`] (ten times the movement bounds').
const COVER_ROUNDING: f32 = 1.0e-5;

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::body::BodyDesc;
    use crate::dynamics::contact::contains_pair;
    use crate::math::Vec3;
    use crate::rng::SplitMix64;
    use crate::shape::Shape;

    fn body(kind: BodyKind, p: Vec3, r: f32) -> Body<'static> {
        let shape = Shape::sphere(r).unwrap();
        let desc = match kind {
            BodyKind::Dynamic => BodyDesc::dynamic(shape),
            BodyKind::Static => BodyDesc::fixed(shape),
            BodyKind::Kinematic => BodyDesc::kinematic(shape),
        };
        Body::from_desc(&desc.position(p)).unwrap()
    }

    /// Random bodies: dynamic, static and kinematic spheres with random filters.
    fn random_body(rng: &mut SplitMix64) -> Body<'static> {
        let kinds = [BodyKind::Dynamic, BodyKind::Static, BodyKind::Kinematic];
        let kind = kinds[(rng.next_u64() % 3) as usize];
        let p = Vec3::new(
            rng.range(-6.0, 6.0),
            rng.range(-2.0, 2.0),
            rng.range(-2.0, 2.0),
        );
        let mut b = body(kind, p, rng.range(0.1, 1.0));
        b.group = 1 << (rng.next_u64() % 3);
        b.mask = if rng.next_u64().is_multiple_of(4) {
            0b101
        } else {
            u32::MAX
        };
        b
    }

    /// Some random contacts between live bodies, sorted by key.
    fn random_contacts<const N: usize>(
        pool: &Pool<Body<'static>, N>,
        rng: &mut SplitMix64,
    ) -> std::vec::Vec<Contact> {
        let mut contacts = std::vec::Vec::new();
        for (i, _) in pool.iter() {
            for (j, _) in pool.iter() {
                if i < j && rng.next_u64().is_multiple_of(7) {
                    contacts.push(Contact::new_pair(
                        i as u32,
                        j as u32,
                        crate::Material::DEFAULT,
                        false,
                    ));
                }
            }
        }
        contacts
    }

    /// What the search must find, by an O(n²) loop over all pairs with the same rules.
    fn brute_force<const N: usize>(
        pool: &Pool<Body<'static>, N>,
        contacts: &[Contact],
    ) -> std::vec::Vec<(u32, u32)> {
        let mut expected = std::vec::Vec::new();
        for (i, a) in pool.iter() {
            for (j, b) in pool.iter() {
                if i < j
                    && (a.moved || b.moved)
                    && a.fat.overlaps(&b.fat)
                    && may_pair(a, b)
                    && !contains_pair(contacts, (i as u32, j as u32))
                {
                    expected.push((i as u32, j as u32));
                }
            }
        }
        expected
    }

    fn moved_flags<const N: usize>(pool: &Pool<Body<'static>, N>) -> std::vec::Vec<bool> {
        pool.iter().map(|(_, b)| b.moved).collect()
    }

    /// The search against the brute-force loop, over random scenes with removals and
    /// additions in between (some removals tell the broad phase, some do not: a slot
    /// taken over without a removal must still work), random `moved` flags (a moved body
    /// gets a new box, the others keep theirs, as in the step) and existing contacts.
    /// With a small buffer, the smallest keys are kept and the bodies of the others stay
    /// flagged. The tree stays valid and holds every body's box. Rounds with many moved
    /// bodies take the walk, the others the queries (both checked to run), and a walk
    /// whose stack overflows gives the queries' answer.
    #[test]
    fn search_matches_brute_force_over_steps() {
        const N: usize = 48;
        let mut rng = SplitMix64::new(7);
        // Rounds searched by queries, by the walk.
        let mut paths = [0; 2];
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        let mut bp: BroadPhase<N> = BroadPhase::new();
        for round in 0..12 {
            // Every other round a few bodies move and none come or go (one query each),
            // else many (the walk).
            let few = round % 2 == 1;
            let handles: std::vec::Vec<_> = (0..N).filter_map(|i| pool.handle_at(i)).collect();
            for h in handles.iter().step_by(5).filter(|_| !few) {
                pool.remove(*h);
                if round % 3 != 1 {
                    bp.remove_body(h.index);
                }
            }
            let share = if few { 6 } else { 2 };
            for (_, b) in pool.iter_mut() {
                b.moved = rng.next_u64().is_multiple_of(share);
                if b.moved {
                    let shift = Vec3::new(rng.range(-0.3, 0.3), 0.0, 0.0);
                    b.place(crate::math::Iso::new(
                        b.pose().position + shift,
                        b.pose().rotation,
                    ));
                    b.fat = b.shape.aabb(b.pose()).expanded(rng.range(0.0, 0.2));
                }
            }
            while pool.len() < N - 3 {
                // New bodies are flagged `moved`.
                pool.insert(random_body(&mut rng)).unwrap();
            }
            let contacts = random_contacts(&pool, &mut rng);
            let expected = brute_force(&pool, &contacts);
            assert!(
                expected.len() > 4,
                "round {round}: scene too sparse to test"
            );
            let moved = pool.iter().filter(|(_, b)| b.moved).count();
            paths[usize::from(moved * WALK_MOVES >= pool.len())] += 1;

            // A small buffer: the 4 smallest keys.
            let (mut small_pool, mut small_bp) = (pool.clone(), bp.clone());
            let mut pairs: HVec<(u32, u32), 4> = HVec::new();
            let mut report = StepReport::default();
            small_bp.find_new_pairs(&mut small_pool, &contacts, &mut pairs, &mut report);
            assert_eq!(pairs.as_slice(), &expected[..4], "round {round}");
            assert_eq!(report.dropped_pairs as usize, expected.len() - 4);
            let mut retry = [false; N];
            for &(a, b) in &expected[4..] {
                retry[a as usize] = true;
                retry[b as usize] = true;
            }
            let retry: std::vec::Vec<bool> = pool.iter().map(|(i, _)| retry[i]).collect();
            assert_eq!(moved_flags(&small_pool), retry, "round {round}");

            // A walk stack of 2 overflows at once: the queries take over, same answer.
            let (mut tiny_pool, mut tiny_bp) = (pool.clone(), bp.clone());
            let mut pairs: HVec<(u32, u32), 2048> = HVec::new();
            let mut report = StepReport::default();
            tiny_bp.find_new_pairs_with::<2048, 2>(
                &mut tiny_pool,
                &contacts,
                &mut pairs,
                &mut report,
            );
            assert_eq!(pairs.as_slice(), expected.as_slice(), "round {round}");
            assert!(tiny_pool.iter().all(|(_, b)| !b.moved), "flags cleared");

            let mut pairs: HVec<(u32, u32), 2048> = HVec::new();
            let mut report = StepReport::default();
            bp.find_new_pairs(&mut pool, &contacts, &mut pairs, &mut report);
            assert_eq!(pairs.as_slice(), expected.as_slice(), "round {round}");
            assert_eq!(report.dropped_pairs, 0);
            assert!(pool.iter().all(|(_, b)| !b.moved), "flags cleared");
            bp.tree.validate().unwrap();
            for (i, b) in pool.iter() {
                assert_eq!(bp.tree.aabb(bp.proxies[i]), Some(b.fat), "round {round}");
            }
        }
        assert!(
            paths[0] > 2 && paths[1] > 2,
            "rounds by queries, by walk: {paths:?}"
        );
    }

    /// A broad phase whose tree grew through a long history (bodies inserted in reverse
    /// slot order, moved about, then put in place), one built by the first search in slot
    /// order, and one rebuilt after `invalidate` have different trees and give the same
    /// pairs, the same overflow and the same flags.
    #[test]
    fn pairs_do_not_depend_on_the_tree_shape() {
        const N: usize = 64;
        let mut rng = SplitMix64::new(11);
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        while pool.len() < N {
            pool.insert(random_body(&mut rng)).unwrap();
        }
        let contacts = random_contacts(&pool, &mut rng);
        let fresh: BroadPhase<N> = BroadPhase::new();
        let mut history: BroadPhase<N> = BroadPhase::new();
        for _ in 0..5 {
            for (i, b) in pool.iter().collect::<std::vec::Vec<_>>().into_iter().rev() {
                let mut elsewhere = *b;
                elsewhere.fat = b.fat.translated(Vec3::new(rng.range(-5.0, 5.0), 0.0, 0.0));
                history.sync(i, &elsewhere);
            }
        }
        for (i, b) in pool.iter().collect::<std::vec::Vec<_>>().into_iter().rev() {
            history.sync(i, b);
        }
        let mut rebuilt = history.clone();
        rebuilt.invalidate();

        fn search<const N: usize, const P: usize>(
            bp: &BroadPhase<N>,
            pool: &Pool<Body<'static>, N>,
            contacts: &[Contact],
        ) -> (
            std::vec::Vec<(u32, u32)>,
            u32,
            std::vec::Vec<bool>,
            BroadPhase<N>,
        ) {
            let (mut bp, mut pool) = (bp.clone(), pool.clone());
            let mut pairs: HVec<(u32, u32), P> = HVec::new();
            let mut report = StepReport::default();
            bp.find_new_pairs(&mut pool, contacts, &mut pairs, &mut report);
            (pairs.to_vec(), report.dropped_pairs, moved_flags(&pool), bp)
        }
        let full = search::<N, 4096>(&fresh, &pool, &contacts);
        assert!(full.0.len() > 40 && full.1 == 0);
        let small = search::<N, 16>(&fresh, &pool, &contacts);
        assert!(small.1 > 20, "{} dropped", small.1);
        assert_eq!(small.0, full.0[..16]);
        for bp in [&history, &rebuilt] {
            let f = search::<N, 4096>(bp, &pool, &contacts);
            let s = search::<N, 16>(bp, &pool, &contacts);
            assert_eq!((&f.0, f.1, &f.2), (&full.0, full.1, &full.2));
            assert_eq!((&s.0, s.1, &s.2), (&small.0, small.1, &small.2));
        }
        // The trees really differ: leaves in other nodes.
        let built = search::<N, 16>(&fresh, &pool, &contacts).3;
        assert_ne!(built.proxies, history.proxies);
        assert_ne!(
            search::<N, 16>(&rebuilt, &pool, &contacts).3.proxies,
            history.proxies
        );
    }

    /// Continuous collision's query: the slots whose boxes overlap a box, in slot order,
    /// from the tree and from the stale fallback alike.
    #[test]
    fn overlapping_lists_slots_in_order() {
        const N: usize = 40;
        let mut rng = SplitMix64::new(5);
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        while pool.len() < N {
            pool.insert(random_body(&mut rng)).unwrap();
        }
        let mut bp: BroadPhase<N> = BroadPhase::new();
        let mut pairs: HVec<(u32, u32), 1024> = HVec::new();
        bp.find_new_pairs(&mut pool, &[], &mut pairs, &mut StepReport::default());
        let mut stale = bp.clone();
        stale.invalidate();
        let mut out: HVec<u32, N> = HVec::new();
        for _ in 0..30 {
            let c = Vec3::new(rng.range(-6.0, 6.0), 0.0, 0.0);
            let q = Aabb::from_center_half(c, Vec3::new(rng.range(0.0, 2.0), 1.0, 1.0));
            let expected: std::vec::Vec<u32> = pool
                .iter()
                .filter(|(_, b)| b.fat.overlaps(&q))
                .map(|(i, _)| i as u32)
                .collect();
            bp.overlapping(&pool, &q, &mut out);
            assert_eq!(out.as_slice(), expected.as_slice());
            stale.overlapping(&pool, &q, &mut out);
            assert_eq!(out.as_slice(), expected.as_slice());
        }
    }

    /// A world at rest does no tree work: once every body sleeps (or nothing leaves its
    /// box), steps neither move leaves nor query.
    #[test]
    fn resting_world_does_no_tree_work() {
        let mut world: crate::World<16, 64> = crate::World::new();
        let ground = Shape::cuboid(Vec3::new(10.0, 0.5, 10.0)).unwrap();
        world
            .add(BodyDesc::fixed(ground).position(Vec3::new(0.0, -0.5, 0.0)))
            .unwrap();
        for i in 0..4 {
            let p = Vec3::new(2.0 * i as f32, 0.5, 0.0);
            let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
            world.add(BodyDesc::dynamic(cube).position(p)).unwrap();
        }
        let mut steps = 0;
        while world.step().awake_bodies > 0 {
            steps += 1;
            assert!(steps < 600, "never fell asleep");
        }
        assert!(world.broad.work > 0);
        let work = world.broad.work;
        for _ in 0..30 {
            world.step();
        }
        assert_eq!(world.broad.work, work, "tree work while everything sleeps");
    }

    /// A body in steady motion leaves its enlarged box every few steps, not every step:
    /// a ball falling at 6 m/s without gravity (10 cm per step, twice the `aabb_margin`)
    /// gets a new box every third step (8 of 24; without the look-ahead, every step),
    /// each reaching 20 cm further down (two steps' motion, within its 0.5 m radius); a
    /// small fast ball's look-ahead stops at its radius.
    #[test]
    fn steady_motion_refreshes_the_box_every_few_steps() {
        let mut cfg = WorldConfig::DEFAULT;
        cfg.gravity = Vec3::ZERO;
        let mut bodies: Pool<Body<'static>, 4> = Pool::new();
        let mut ball = body(BodyKind::Dynamic, Vec3::new(0.0, 10.0, 0.0), 0.5);
        ball.linear_velocity = Vec3::new(0.0, -6.0, 0.0);
        let slot = bodies.insert(ball).unwrap();
        let mut refreshed = 0;
        for _ in 0..24 {
            update_fat_boxes(&mut bodies, &cfg);
            let b = bodies.get_mut(slot).unwrap();
            if b.moved {
                refreshed += 1;
                // Below: this step's 10 cm, two more steps' 20 cm, both margins.
                let below = b.world_center().y - 0.5 - b.fat.min.y;
                let want = 0.1 + 0.2 + cfg.speculative_margin + cfg.aabb_margin;
                assert!((below - want).abs() < 1e-4, "below {below}, want {want}");
                b.moved = false;
            }
            let p = b.world_center() + b.linear_velocity * cfg.dt;
            b.place(crate::math::Iso::from_position(p));
        }
        assert_eq!(refreshed, 8);
        // A bullet: 0.05 m radius at 500 m/s looks ahead 0.05 m, not 16.7 m.
        let mut bullet = body(BodyKind::Dynamic, Vec3::ZERO, 0.05);
        bullet.linear_velocity = Vec3::new(500.0, 0.0, 0.0);
        let (motion, _) = body_motion(&bullet, &cfg);
        let d = look_ahead(&bullet, &motion, cfg.dt);
        assert!((d.length() - 0.05).abs() < 1e-6 && d.x > 0.0, "{d:?}");
        bullet.linear_velocity = Vec3::new(f32::NAN, 0.0, 0.0);
        let (motion, _) = body_motion(&bullet, &cfg);
        assert_eq!(look_ahead(&bullet, &motion, cfg.dt), Vec3::ZERO);
    }

    /// A spinning body's box covers its shape at the end of any part of the step, with
    /// the rotation about the centre of mass (not the origin) taken into account.
    #[test]
    fn bounds_cover_end_pose_of_off_centre_body() {
        let shape = Shape::capsule(1.0, 0.2).unwrap();
        let mut b =
            Body::from_desc(&BodyDesc::dynamic(shape).position(Vec3::new(1.0, 2.0, 3.0))).unwrap();
        // Pretend the centre of mass is off the origin, as for an asymmetric hull.
        b.center_local = Vec3::new(0.5, 0.0, 0.0);
        b.place(*b.pose());
        b.angular_velocity = Vec3::new(0.0, 0.0, 20.0);
        b.linear_velocity = Vec3::new(3.0, 0.0, 0.0);
        let mut cfg = WorldConfig::DEFAULT;
        cfg.gravity = Vec3::ZERO;
        let bounds = body_bounds(&b, &cfg);
        let c0 = b.world_center();
        let mut end = *b.pose();
        for k in 1..=16 {
            let t = cfg.dt * k as f32 / 16.0;
            let q = b.pose().rotation.integrate(b.angular_velocity, t);
            let c = c0 + b.linear_velocity * t;
            end = crate::math::Iso::new(c - q.rotate(b.center_local), q);
            let aabb = b.shape.aabb(&end);
            assert!(
                bounds.contains(&aabb),
                "k={k}: {bounds:?} does not contain {aabb:?}"
            );
        }
        assert!(end.position.distance(b.pose().position) > 0.04);
    }

    /// A full pair buffer keeps the pairs with the smallest keys, counts the rest, and
    /// leaves their bodies flagged for the next search. The spheres lie right to left in
    /// slot order, so a sweep along x would meet the largest keys first.
    /// The cheap cover holds the movement bounds it stands in for, on random shapes and
    /// motions from still to fast spins: so skipping the exact bounds when the cover is
    /// inside the enlarged box never changes a box.
    #[test]
    fn movement_cover_holds_the_movement_bounds() {
        let mut rng = SplitMix64::new(17);
        let hull_points: std::vec::Vec<Vec3> = (0..10)
            .map(|_| rng.unit_vector() * rng.range(0.1, 2.0))
            .collect();
        let hull = crate::shape::ConvexHull::new(&hull_points).unwrap();
        let shapes = [
            Shape::sphere(0.3).unwrap(),
            Shape::cuboid(Vec3::new(0.5, 0.1, 2.0)).unwrap(),
            Shape::capsule(1.0, 0.2).unwrap(),
            Shape::hull(&hull),
        ];
        for i in 0..20_000 {
            let shape = shapes[i % shapes.len()];
            let spin = [0.0, 0.1, 1.0, 10.0, 100.0][i % 5];
            let motion = Motion {
                pose: crate::math::Iso::new(
                    rng.unit_vector() * rng.range(0.0, 1000.0),
                    rng.rotation(),
                ),
                linear: rng.unit_vector() * rng.range(0.0, 50.0),
                angular: rng.unit_vector() * rng.range(0.0, spin),
            };
            let dt = 1.0 / 60.0;
            let exact = movement_bounds(&shape, &motion, dt);
            let cover = movement_cover(
                shape.bounding_radius(),
                shape.core_reach(),
                &motion,
                shape.aabb(&motion.pose),
                dt,
            );
            assert!(
                cover.contains(&exact),
                "case {i}: {cover:?} misses {exact:?}"
            );
        }
    }

    #[test]
    fn full_pair_buffer_keeps_smallest_keys() {
        const N: usize = 6;
        let mut pool: Pool<Body<'static>, N> = Pool::new();
        // Six spheres on a line 0.5 apart, slot 0 rightmost.
        for i in 0..N {
            pool.insert(body(
                BodyKind::Dynamic,
                Vec3::new((N - 1 - i) as f32 * 0.5, 0.0, 0.0),
                0.3,
            ))
            .unwrap();
        }
        let mut bp: BroadPhase<N> = BroadPhase::new();
        let mut pairs: HVec<(u32, u32), 3> = HVec::new();
        let mut report = StepReport::default();
        bp.find_new_pairs(&mut pool, &[], &mut pairs, &mut report);
        // Overlapping neighbours: (0,1) (1,2) (2,3) (3,4) (4,5): the three smallest kept.
        assert_eq!(pairs.as_slice(), &[(0, 1), (1, 2), (2, 3)]);
        assert_eq!(report.dropped_pairs, 2);
        assert_eq!(moved_flags(&pool), [false, false, false, true, true, true]);
        // Offered again: the contacts now exist, so the two left over fit.
        let contacts: std::vec::Vec<Contact> = pairs
            .iter()
            .map(|&(a, b)| Contact::new_pair(a, b, crate::Material::DEFAULT, false))
            .collect();
        let mut report = StepReport::default();
        bp.find_new_pairs(&mut pool, &contacts, &mut pairs, &mut report);
        assert_eq!(pairs.as_slice(), &[(3, 4), (4, 5)]);
        assert_eq!(report.dropped_pairs, 0);
        assert!(pool.iter().all(|(_, b)| !b.moved));
    }

    /// The heap keeps the smallest keys whatever the order they come in, for buffers of
    /// several sizes (none included), and hands back exactly the others.
    #[test]
    fn smallest_pairs_whatever_the_order() {
        fn check<const P: usize>(all: &[(u32, u32)], rng: &mut SplitMix64) {
            for _ in 0..5 {
                // Shuffle (Fisher–Yates).
                let mut order = all.to_vec();
                for i in (1..order.len()).rev() {
                    let j = (rng.next_u64() % (i as u64 + 1)) as usize;
                    order.swap(i, j);
                }
                let mut buf: HVec<(u32, u32), P> = HVec::new();
                let mut kept = SmallestPairs::new(&mut buf);
                let mut dropped = std::vec::Vec::new();
                for &p in &order {
                    dropped.extend(kept.offer(p));
                }
                assert_eq!(kept.dropped as usize, all.len() - P);
                buf.sort_unstable();
                assert_eq!(buf.as_slice(), &all[..P]);
                dropped.sort_unstable();
                assert_eq!(dropped, all[P..]);
            }
        }
        let mut rng = SplitMix64::new(9);
        let mut all: std::vec::Vec<(u32, u32)> =
            (0..60u32).map(|i| ((i * 37) % 61, (i * 11) % 13)).collect();
        all.sort_unstable();
        all.dedup();
        assert!(all.len() > 40);
        check::<0>(&all, &mut rng);
        check::<1>(&all, &mut rng);
        check::<5>(&all, &mut rng);
        check::<40>(&all, &mut rng);
    }
}
