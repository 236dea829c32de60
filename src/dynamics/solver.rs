//! Stage 7: the soft step (Catto, "Solver2D", 2024; Box2D v3's `solver.c`).
//!
//! One step of `dt` seconds, after the narrow phase has built this step's manifolds:
//!
//! ```text
//! wake        sleeping bodies that an awake body reaches this step
//! gather      awake dynamic and kinematic bodies -> a compact array of SolverBody
//!             (velocity, displacement since the step began, rotation, world inverse
//!             inertia, the per-sub-step velocity increment of gravity and forces);
//!             static and sleeping bodies have no entry: they read as zero velocity and
//!             infinite mass
//! support     in a step where two touching moving bodies differ 20-fold in mass, the
//!             islands the ground holds up: there a contact under a far heavier body
//!             sees its lighter support as a twentieth of it (`support.rs`)
//! prepare     the rows of every manifold, four manifolds at a time into their group's
//!             lanes (`wide/prepare.rs`): lever arms, Jacobians and effective masses,
//!             the separation s0, the closing speed before the solve; dynamic–dynamic
//!             contacts first, contacts with a static or kinematic body last
//!             (Gauss-Seidel gives the last word to the last row)
//! bounce      the collision pass: restitution from the speeds before this step's gravity
//! for each of `substeps` sub-steps of h = dt / substeps:
//!     integrate velocities     v += h (g + F/m), ω += h I⁻¹ τ, damping, speed limits
//!     warm start               apply the accumulated impulses again
//!     solve                    `velocity_iterations` soft iterations (push-out), with
//!                              friction, rolling and twist except on torque-free
//!                              contacts (balls: `contact_solver::torque_free`)
//!     integrate positions      speed limits again (the solve may exceed them),
//!                              Δp += v h, q ← q + ½ h ω q (normalised)
//!     relax                    `relax_iterations` iterations without push-out, with
//!                              friction, rolling and twist
//! restitution the points that were far at prepare and pushed: bounce from v_n0
//! store       accumulated impulses and stick/slip state back to the contacts
//! finalize    poses, velocities (within the speed limits) and R I⁻¹ Rᵀ back to the
//!             bodies
//! ```
//!
//! The rows themselves (soft normal rows, friction, rolling and twist, the collision
//! pass) are in `contact_solver.rs`. The world inverse inertia is taken once per step
//! at the starting rotation, as in Box2D: within a step a body turns little, and the
//! anchors of the separation follow the exact rotation.

use heapless::Vec as HVec;

use super::body::{Body, BodyKind};
use super::contact::Contact;
use super::contact_solver;
use super::pool::Pool;
use super::support;
use super::wide::{self, WideStore};
use crate::config::WorldConfig;
use crate::math::lanes::{F4, M4, V4};
use crate::math::{scalar, Mat3, Quat, Vec3};

/// Index of "no solver body": a static or sleeping body (zero velocity, infinite mass).
pub(crate) const NONE: u32 = u32::MAX;

/// "Not in a kept slot" in [`Solver::slot_of`].
const NO_SLOT: u8 = u8::MAX;

/// A moving body as the solver sees it, for one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct SolverBody {
    /// Linear velocity of the centre of mass (m/s).
    pub v: Vec3,
    /// Angular velocity (rad/s, world).
    pub w: Vec3,
    /// Displacement of the centre of mass since the step began (m).
    pub dp: Vec3,
    /// Current rotation.
    pub q: Quat,
    /// `R(q)`, refreshed after every position update (for the anchors).
    pub rot: Mat3,
    /// Inverse mass (1/kg); 0 for kinematic bodies.
    pub inv_mass: f32,
    /// World inverse inertia at the start of the step (0 for kinematic bodies).
    pub inv_inertia: Mat3,
    /// Velocity added per sub-step by gravity and forces (m/s).
    pub dv: Vec3,
    /// Angular velocity added per sub-step by torques (rad/s).
    pub dw: Vec3,
    /// Damping factors per sub-step, `1 / (1 + h c)`.
    pub linear_damping: f32,
    /// See `linear_damping`.
    pub angular_damping: f32,
    /// Distance (m) projection moved the body this step (bounded by `max_projection`).
    pub projected: f32,
    /// The body's pool slot.
    pub slot: u32,
    /// Bit `c` set: a contact of colour `c` moves this body (`wide.rs`).
    pub colours: u32,
}

impl SolverBody {
    pub(crate) const ZERO: SolverBody = SolverBody {
        v: Vec3::ZERO,
        w: Vec3::ZERO,
        dp: Vec3::ZERO,
        q: Quat::IDENTITY,
        rot: Mat3::IDENTITY,
        inv_mass: 0.0,
        inv_inertia: Mat3::ZERO,
        dv: Vec3::ZERO,
        dw: Vec3::ZERO,
        linear_damping: 1.0,
        angular_damping: 1.0,
        projected: 0.0,
        slot: NONE,
        colours: 0,
    };
}

/// The solver's per-step storage: solver bodies, the slot → solver index map, and the
/// contact constraints. Nothing in it outlives a step.
#[derive(Clone, Debug)]
pub(crate) struct Solver<const N: usize, const C: usize> {
    /// Awake dynamic and kinematic bodies, in slot order.
    pub bodies: HVec<SolverBody, N>,
    /// Slot → index in `bodies`, or [`NONE`].
    pub index: [u32; N],
    /// The constraints, coloured and packed four to a group.
    pub store: WideStore<C>,
    /// Whether this step has a heavy contact (`support.rs`): then `marks` holds which
    /// islands the ground holds up.
    pub heavy: bool,
    /// Support marks by solver body: union-find entries (`support.rs`), valid in a step
    /// with `heavy` only.
    pub marks: [u32; N],
    /// The plan's scratch by contact index: the slot (colour and point class) of a
    /// contact that stays in its colour, or [`NO_SLOT`] (`place_in_colour_order`).
    pub slot_of: [u8; C],
    /// The plan's scratch for the visit order's radix sort (`sort::sort_pairs_radix`).
    pub radix: [(u32, u32); C],
}

impl<const N: usize, const C: usize> Solver<N, C> {
    /// Empty.
    pub const fn new() -> Self {
        Solver {
            bodies: HVec::new(),
            index: [NONE; N],
            store: WideStore::new(),
            heavy: false,
            marks: [0; N],
            slot_of: [NO_SLOT; C],
            radix: [(0, 0); C],
        }
    }

    /// Back to [`Solver::new`]'s state where it lies. Every field is named, so a new one
    /// cannot be left out.
    pub fn reset(&mut self) {
        let Solver {
            bodies,
            index,
            store,
            heavy,
            marks,
            slot_of,
            radix,
        } = self;
        bodies.clear();
        index.fill(NONE);
        // Room for no group: no slot, every count and flag as new (cannot fail).
        let _ = store.reset(0);
        *heavy = false;
        marks.fill(0);
        slot_of.fill(NO_SLOT);
        radix.fill((0, 0));
    }

    /// The solver body of slot `slot`, if it has one.
    #[inline]
    pub fn body_of_slot(&self, slot: u32) -> Option<&SolverBody> {
        let i = *self.index.get(slot as usize)?;
        self.bodies.get(i as usize)
    }

    /// Mutable [`Solver::body_of_slot`].
    #[inline]
    pub fn body_of_slot_mut(&mut self, slot: u32) -> Option<&mut SolverBody> {
        let i = *self.index.get(slot as usize)?;
        self.bodies.get_mut(i as usize)
    }
}

/// Stage 7 (module docs). `contacts` get their accumulated impulses and stick/slip state;
/// bodies their new poses and velocities; the solver keeps the constraints (with their
/// final separations) for projection.
pub(crate) fn solve<const N: usize, const C: usize>(
    solver: &mut Solver<N, C>,
    contacts: &mut [Contact],
    bodies: &mut Pool<Body<'_>, N>,
    scratch: &mut HVec<(u32, u32), C>,
    cfg: &WorldConfig,
) {
    let h = cfg.substep();
    if h.is_nan() || h <= 0.0 {
        return;
    }
    // Only a sleeping dynamic body can be woken: one pass over the bodies spares a world
    // without one the pass over its contacts (two body lookups each).
    if bodies.iter().any(|(_, b)| b.is_dynamic() && !b.awake) {
        for c in contacts.iter() {
            contact_solver::wake_touched_sleepers(c, bodies, cfg.dt);
        }
    }
    let masses_differ = gather(solver, bodies, cfg, h);
    plan(solver, contacts, bodies, scratch, masses_differ, cfg);
    let (store, sbodies) = (&mut solver.store, &mut solver.bodies);
    bounce(store, sbodies, contacts, cfg);
    let inv_h = 1.0 / h;
    // Separations are measured again only after the bodies moved (`wide::Pass`).
    let mut moved = true;
    for sub in 0..cfg.substeps {
        integrate_velocities(sbodies, cfg);
        wide::warm_start(store, sbodies);
        for _ in 0..cfg.velocity_iterations {
            let pass = wide::Pass {
                use_bias: true,
                moved,
                last: false,
            };
            wide::solve(store, sbodies, cfg, inv_h, pass);
            moved = false;
        }
        integrate_positions(sbodies, h, cfg);
        moved = true;
        for k in 0..cfg.relax_iterations {
            let last = sub + 1 == cfg.substeps && k + 1 == cfg.relax_iterations;
            let pass = wide::Pass {
                use_bias: false,
                moved,
                last,
            };
            wide::solve(store, sbodies, cfg, inv_h, pass);
            moved = false;
        }
    }
    restitution_and_store(store, sbodies, contacts, cfg);
    finalize(solver, bodies, cfg);
}

/// Colour the contacts that push (`wide.rs`), pack them four to a group in colour
/// order, and prepare each into its lane. `scratch` holds `(colour, contact index)`.
/// With `masses_differ` (from [`gather`]), look for a heavy contact first and, if there
/// is one, mark the islands the ground holds up (`support.rs`).
fn plan<const N: usize, const C: usize>(
    solver: &mut Solver<N, C>,
    contacts: &[Contact],
    bodies: &Pool<Body<'_>, N>,
    scratch: &mut HVec<(u32, u32), C>,
    masses_differ: bool,
    cfg: &WorldConfig,
) {
    scratch.clear();
    // Whether two moving bodies of very different masses touch (`support.rs`): only
    // looked for when the lightest and heaviest moving bodies differ that much.
    let mut heavy = false;
    // Visit order: contacts between two dynamic bodies first, then those against
    // static, kinematic or sleeping bodies; within each, in the order of a fixed hash of
    // the pair. Colouring in key order gives a regular pattern on regular scenes (all
    // left supports of a pyramid row before all right ones), and Gauss-Seidel turns a
    // regular order into a drift: a wall pyramid crept 10 cm sideways. The hash
    // scrambles the order the same way on every target.
    for (i, c) in contacts.iter().enumerate() {
        if c.len == 0 || c.sensor {
            continue;
        }
        let ia = solver.index.get(c.a as usize).copied().unwrap_or(NONE);
        let ib = solver.index.get(c.b as usize).copied().unwrap_or(NONE);
        if !moves(&solver.bodies, ia) && !moves(&solver.bodies, ib) {
            continue;
        }
        if masses_differ && !heavy {
            let mass = |i: u32| solver.bodies.get(i as usize).map_or(0.0, |s| s.inv_mass);
            let (m_a, m_b) = (mass(ia), mass(ib));
            heavy = m_a > 0.0 && m_b > 0.0 && support::heavy_pair(m_a, m_b);
        }
        // A body that moves in the solve is dynamic: only the others need a look at the
        // pool (a pile's contacts between two moving bodies need none).
        let rigid =
            |slot: u32, i: u32| !moves(&solver.bodies, i) && contact_solver::is_rigid(slot, bodies);
        let class = u32::from(rigid(c.a, ia) || rigid(c.b, ib)) << 31;
        // Part contacts of one pair differ by `sub` (0 for a convex pair: its own key).
        let sub = u64::from(c.sub).wrapping_mul(0x9e37_79b9_7f4a_7c15);
        let key = class | (pair_hash(c.key() ^ sub) >> 1);
        // Cannot fail: one entry per contact at most.
        let _ = scratch.push((key, i as u32));
    }
    // Pushed in contact order: a stable sort by the key gives the (key, contact) order.
    crate::sort::sort_pairs_radix(scratch, &mut solver.radix);
    // Which islands the ground holds up, where a body may rest on one far lighter.
    solver.heavy = heavy;
    if heavy {
        let (marks, sb, si) = (&mut solver.marks, &solver.bodies, &solver.index);
        support::mark_supported(marks, sb, si, contacts, scratch);
    }
    // Colour in rank (visit) order.
    let mut count = [0u32; wide::COLORS + 1];
    for entry in scratch.iter_mut() {
        let Some(c) = contacts.get(entry.1 as usize) else {
            continue;
        };
        let ia = solver.index.get(c.a as usize).copied().unwrap_or(NONE);
        let ib = solver.index.get(c.b as usize).copied().unwrap_or(NONE);
        let colour = wide::colour(&mut solver.bodies, ia, ib);
        entry.0 = colour;
        if let Some(n) = count.get_mut(colour as usize) {
            *n += 1;
        }
    }
    let class = |ci| point_class(contacts, ci);
    place_in_colour_order(scratch, &count, class, &mut solver.slot_of, contacts.len());
    // Groups: a new one every four lanes and at every change of colour.
    let mut groups = 0usize;
    let mut last: Option<(u32, usize)> = None;
    for &(colour, _) in scratch.iter() {
        match last {
            Some((c, lanes)) if c == colour && lanes < 4 => last = Some((c, lanes + 1)),
            _ => {
                groups += 1;
                last = Some((colour, 1));
            }
        }
    }
    let store = &mut solver.store;
    if !store.reset(groups) {
        return;
    }
    let mut group = 0usize;
    let mut lane = 0usize;
    let mut last: Option<u32> = None;
    let mut batch = [NONE; 4];
    let mut overflow_from = None;
    let softness = contact_solver::Softness::for_contacts(cfg);
    let (sb, si) = (&solver.bodies, &solver.index);
    let supports = support::Supports {
        marks: &solver.marks,
        gravity: cfg.gravity,
    };
    let mut inputs = wide::PrepareInputs::default();
    let mut bouncy = false;
    let mut prepare = |g: usize, batch: &[u32; 4]| {
        let Some(mut group) = store.group(g) else {
            return;
        };
        let group = &mut group;
        // Capped contacts only in a step with a heavy contact (`support.rs`).
        let soft = &softness;
        if heavy {
            let sup = &supports;
            let x = &mut inputs;
            wide::prepare_group::<N, true>(
                x, group, batch, contacts, bodies, sb, si, soft, sup, cfg,
            );
        } else {
            let sup = &support::Supports::NONE;
            let x = &mut inputs;
            wide::prepare_group::<N, false>(
                x, group, batch, contacts, bodies, sb, si, soft, sup, cfg,
            );
        }
        // Whether the collision pass has a lane to visit: read while the group is hot.
        bouncy |= group.has_restitution();
    };
    for &(colour, ci) in scratch.iter() {
        if let Some(c) = last {
            if c != colour || lane == 4 {
                prepare(group, &batch);
                batch = [NONE; 4];
                group += 1;
                lane = 0;
            }
        }
        if colour == wide::OVERFLOW && last != Some(wide::OVERFLOW) {
            overflow_from = Some(group as u32);
        }
        last = Some(colour);
        if let Some(b) = batch.get_mut(lane) {
            *b = ci;
        }
        lane += 1;
    }
    if last.is_some() {
        prepare(group, &batch);
    }
    store.overflow_from = match overflow_from {
        Some(g) if last == Some(wide::OVERFLOW) => g,
        _ => store.groups,
    };
    store.bouncy = bouncy;
}

/// Classes of contacts by point count (1, 2, 3, 4 points), the order of a colour's
/// contacts (see [`place_in_colour_order`]).
const POINT_CLASSES: usize = 4;

/// The point class of contact `ci` ([`POINT_CLASSES`]): its point count less one.
#[inline]
fn point_class(contacts: &[Contact], ci: u32) -> usize {
    contacts
        .get(ci as usize)
        .map_or(0, |c| usize::from(c.len.clamp(1, 4)) - 1)
}

/// Reorder `scratch` (entries `(colour, contact)` in visit order, `count[c]` of colour
/// `c`) into solve order: colours ascending; within a colour, by point class (`class`
/// of the contact index, below [`POINT_CLASSES`]), then by contact index; each colour's
/// last partial group of fewer than four (its last entries in visit order) moved to the
/// overflow colour (solved in runs of lanes without a shared body, packed four to a
/// group, in visit order: the store then needs at most one group beyond the contacts
/// themselves). On return each entry's first component is its final colour.
///
/// The contacts of one colour share no moving body, so the order among them changes no
/// velocity and no position (beyond what the shorter kernels already allow: an empty
/// point row left out can at most turn a velocity component of −0 into +0, `wide.rs`).
/// Two orders are used for speed:
/// - by point count, which packs groups whose contacts have the same number of points,
///   so they run the kernel of that many point rows instead of the largest count among
///   four mixed contacts;
/// - then by contact index, which is memory order: the prepare reads the contacts, and
///   the impulses are stored back, front to back within each class instead of at the
///   visit order's random places (`pyramid100`, whose 15 000 contacts do not fit in
///   the cache, steps about 12 % faster). Contacts are kept in pair order, so their
///   bodies follow in much the same order.
///
/// Built without sorting, in O(n): a pass in visit order gives each entry its slot
/// (`colour · POINT_CLASSES + class` for one that stays, the overflow slot otherwise)
/// and counts the slots; the overflow entries move, in visit order, to the end of
/// `scratch` (a pass from the back, which overwrites only entries already read); then a
/// pass in contact index order over the first `contacts` entries of `slot_of` (each
/// kept contact's slot, [`NO_SLOT`] for the others) writes the kept entries at their
/// slots' offsets.
fn place_in_colour_order<const C: usize>(
    scratch: &mut HVec<(u32, u32), C>,
    count: &[u32; wide::COLORS + 1],
    class: impl Fn(u32) -> usize,
    slot_of: &mut [u8; C],
    contacts: usize,
) {
    let overflow = wide::OVERFLOW as usize;
    // Entries that stay in their colour: whole groups of four.
    let mut keep = [0u32; wide::COLORS + 1];
    for (k, n) in keep.iter_mut().zip(count.iter()).take(overflow) {
        *k = *n / 4 * 4;
    }
    const SLOTS: usize = wide::COLORS * POINT_CLASSES;
    const _: () = assert!(SLOTS < NO_SLOT as usize);
    let contacts = contacts.min(C);
    if let Some(head) = slot_of.get_mut(..contacts) {
        head.fill(NO_SLOT);
    }
    // Visit order: each kept entry's slot (by contact), how many each slot gets, and
    // which entries overflow (their first component: the overflow colour).
    let mut in_slot = [0u32; SLOTS];
    let mut seen = [0u32; wide::COLORS + 1];
    let mut overflowing = 0usize;
    for entry in scratch.iter_mut() {
        let c = (entry.0 as usize).min(overflow);
        let place = seen.get(c).copied().unwrap_or(0);
        if let Some(s) = seen.get_mut(c) {
            *s += 1;
        }
        let stays = c != overflow && place < keep.get(c).copied().unwrap_or(0);
        let slot = c * POINT_CLASSES + class(entry.1).min(POINT_CLASSES - 1);
        match (
            stays,
            slot_of.get_mut(entry.1 as usize),
            in_slot.get_mut(slot),
        ) {
            (true, Some(at), Some(n)) => {
                *at = slot as u8;
                *n += 1;
                entry.0 = c as u32;
            }
            _ => {
                entry.0 = wide::OVERFLOW;
                overflowing += 1;
            }
        }
    }
    // The overflow entries to the end, in visit order.
    let len = scratch.len();
    let kept = len - overflowing;
    let mut to = len;
    for from in (0..len).rev() {
        let Some(&entry) = scratch.get(from) else {
            continue;
        };
        if entry.0 == wide::OVERFLOW {
            to -= 1;
            if let Some(e) = scratch.get_mut(to) {
                *e = entry;
            }
        }
    }
    // The kept entries at their slots' offsets, in contact index order.
    let mut offset = [0u32; SLOTS];
    let mut at = 0u32;
    for (o, n) in offset.iter_mut().zip(in_slot.iter()) {
        *o = at;
        at += *n;
    }
    for (ci, &slot) in slot_of.iter().enumerate().take(contacts) {
        let Some(o) = offset.get_mut(usize::from(slot)) else {
            continue;
        };
        let dest = *o as usize;
        *o += 1;
        if let (true, Some(e)) = (dest < kept, scratch.get_mut(dest)) {
            *e = ((usize::from(slot) / POINT_CLASSES) as u32, ci as u32);
        }
    }
}

/// A fixed 32-bit hash of a contact key (splitmix64's finaliser).
#[inline]
fn pair_hash(key: u64) -> u32 {
    let mut z = key.wrapping_add(0x9e37_79b9_7f4a_7c15);
    z = (z ^ (z >> 30)).wrapping_mul(0xbf58_476d_1ce4_e5b9);
    z = (z ^ (z >> 27)).wrapping_mul(0x94d0_49bb_1331_11eb);
    (z ^ (z >> 31)) as u32
}

/// The collision pass over the lanes with restitution (`contact_solver::bounce`): up to
/// `MAX_BOUNCE_PASSES` sweeps in group order.
fn bounce<const C: usize>(
    store: &mut WideStore<C>,
    bodies: &mut [SolverBody],
    contacts: &[Contact],
    cfg: &WorldConfig,
) {
    // No lane has restitution (the plan noted it): the sweeps below would skip every one.
    if !store.bouncy {
        return;
    }
    for _ in 0..contact_solver::MAX_BOUNCE_PASSES {
        let mut bounced = false;
        for g in 0..store.groups as usize {
            let Some(mut group) = store.group(g) else {
                break;
            };
            for l in 0..4 {
                if group.contact(l) == NONE || group.restitution(l) <= 0.0 {
                    continue;
                }
                let mut k = group.load_lane(l, contacts);
                if contact_solver::bounce_constraint(&mut k, bodies, cfg) {
                    group.store_lane(l, &k);
                    bounced = true;
                }
            }
        }
        if !bounced {
            break;
        }
    }
}

/// The restitution pass after the sub-steps (lanes with restitution), then every lane's
/// accumulated impulses and stick/slip state back to its contact.
fn restitution_and_store<const C: usize>(
    store: &mut WideStore<C>,
    bodies: &mut [SolverBody],
    contacts: &mut [Contact],
    cfg: &WorldConfig,
) {
    for g in 0..store.groups as usize {
        let Some(group) = store.group(g) else {
            break;
        };
        for l in 0..4 {
            let ci = group.contact(l);
            if ci == NONE {
                continue;
            }
            if group.restitution(l) > 0.0 {
                let k = group.load_lane(l, contacts);
                contact_solver::restitution(&k, bodies, cfg);
            }
            if let Some(c) = contacts.get_mut(ci as usize) {
                group.store_impulses(l, c);
            }
        }
    }
}

/// Copy the awake dynamic and kinematic bodies into `solver.bodies` (slot order) and
/// fill the index map; remember each body's pose at the step start (`pose0`). Returns
/// whether the lightest and heaviest awake dynamic bodies differ by
/// `support::HEAVY_RATIO` or more (else no contact can be capped).
fn gather<const N: usize, const C: usize>(
    solver: &mut Solver<N, C>,
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    h: f32,
) -> bool {
    // Inverse masses (1/kg) of the lightest and the heaviest awake dynamic body.
    let (mut lightest, mut heaviest) = (0.0f32, f32::INFINITY);
    solver.bodies.clear();
    for e in solver.index.iter_mut() {
        *e = NONE;
    }
    for (slot, b) in bodies.iter_mut() {
        b.pose0 = *b.pose();
        if b.kind == BodyKind::Static || !b.awake {
            b.force = Vec3::ZERO;
            b.torque = Vec3::ZERO;
            continue;
        }
        let dynamic = b.is_dynamic();
        let mut sb = SolverBody {
            v: b.linear_velocity,
            w: b.angular_velocity,
            q: b.pose().rotation,
            rot: *b.rotation_matrix(),
            slot: slot as u32,
            ..SolverBody::ZERO
        };
        if dynamic {
            lightest = scalar::max(lightest, b.inv_mass);
            heaviest = scalar::min(heaviest, b.inv_mass);
            sb.inv_mass = b.inv_mass;
            sb.inv_inertia = b.inv_inertia_world;
            sb.dv = (cfg.gravity + b.force * b.inv_mass) * h;
            sb.dw = b.inv_inertia_world.mul_vec(b.torque) * h;
            sb.linear_damping = 1.0 / (1.0 + h * b.linear_damping);
            sb.angular_damping = 1.0 / (1.0 + h * b.angular_damping);
        } else {
            // Kinematic: the velocity the user set, within the speed limits.
            sb.v = clamp_length(sb.v, cfg.max_linear_speed);
            sb.w = clamp_length(sb.w, cfg.max_angular_speed);
        }
        b.force = Vec3::ZERO;
        b.torque = Vec3::ZERO;
        let index = solver.bodies.len() as u32;
        if solver.bodies.push(sb).is_ok() {
            if let Some(e) = solver.index.get_mut(slot) {
                *e = index;
            }
        }
    }
    support::masses_differ(lightest, heaviest)
}

/// `v += dv`, `ω += dω`, damping, speed limits, for every dynamic solver body
/// ([`by_fours`]: [`velocities_four`] where it can, [`velocities_one`] otherwise).
fn integrate_velocities(bodies: &mut [SolverBody], cfg: &WorldConfig) {
    by_fours(
        bodies,
        |four| velocities_four(four, cfg),
        |b| velocities_one(b, cfg),
    );
}

/// Whether the per-body integrations take four bodies at a time in lanes: only where the
/// compiler has vector registers for them (x86 SSE2, AArch64 NEON, WebAssembly SIMD).
/// Elsewhere the lanes are four scalar loops with a gather and a scatter on top: on a
/// Cortex-M4F they cost 3 to 6 % more instructions per step than one body at a time
/// (QEMU, `demos/cortex-m`). Either way each body gets the same operations in the same
/// order, so the same bits (tested below; the golden lines hold on every target).
const BODY_LANES: bool = cfg!(any(
    target_feature = "sse2",
    target_feature = "neon",
    target_feature = "simd128"
));

/// `four` on each run of four bodies where [`BODY_LANES`] and it succeeds (it writes
/// nothing when it returns false), else `one` on each body of the run; `one` on the last
/// few.
#[inline]
fn by_fours(
    bodies: &mut [SolverBody],
    mut four: impl FnMut(&mut [SolverBody]) -> bool,
    mut one: impl FnMut(&mut SolverBody),
) {
    let wide = if BODY_LANES { bodies.len() / 4 * 4 } else { 0 };
    let (fours, rest) = bodies.split_at_mut(wide);
    for run in fours.chunks_exact_mut(4) {
        if !four(run) {
            run.iter_mut().for_each(&mut one);
        }
    }
    rest.iter_mut().for_each(one);
}

/// The squares of the linear and angular speed limits, when both are finite: then a
/// velocity whose square is at most its limit's is one `clamp_length` leaves as it is
/// (its first test), which the lanes check instead of clamping.
#[inline]
fn squared_limits(cfg: &WorldConfig) -> Option<(f32, f32)> {
    let (v2, w2) = (
        cfg.max_linear_speed * cfg.max_linear_speed,
        cfg.max_angular_speed * cfg.max_angular_speed,
    );
    (v2 < f32::INFINITY && w2 < f32::INFINITY).then_some((v2, w2))
}

/// [`integrate_velocities`] for one body.
#[inline]
fn velocities_one(b: &mut SolverBody, cfg: &WorldConfig) {
    if b.inv_mass <= 0.0 {
        return;
    }
    let v = (b.v + b.dv) * b.linear_damping;
    let w = (b.w + b.dw) * b.angular_damping;
    b.v = clamp_length(v, cfg.max_linear_speed);
    b.w = clamp_length(w, cfg.max_angular_speed);
}

/// [`velocities_one`] for four dynamic bodies side by side, each lane the same
/// operations in the same order, when every new velocity is within its limit
/// (`clamp_length`'s first test, which then leaves it as it is); false, with nothing
/// written, when a body is not dynamic or a velocity is past its limit.
#[inline]
fn velocities_four(four: &mut [SolverBody], cfg: &WorldConfig) -> bool {
    let Some((max_v2, max_w2)) = squared_limits(cfg) else {
        return false;
    };
    let (mut v, mut w, mut dv, mut dw) = (V4::ZERO, V4::ZERO, V4::ZERO, V4::ZERO);
    let (mut lin, mut ang) = (F4::ZERO, F4::ZERO);
    let mut dynamic = true;
    for (l, b) in four.iter().enumerate() {
        dynamic &= b.inv_mass > 0.0;
        v.set(l, b.v);
        w.set(l, b.w);
        dv.set(l, b.dv);
        dw.set(l, b.dw);
        lin.set(l, b.linear_damping);
        ang.set(l, b.angular_damping);
    }
    let v = v.add(&dv).scale(lin);
    let w = w.add(&dw).scale(ang);
    let (v2, w2) = (v.dot(&v), w.dot(&w));
    let within = (0..4).all(|l| v2.lane(l) <= max_v2 && w2.lane(l) <= max_w2);
    if !(dynamic && within) {
        return false;
    }
    for (l, b) in four.iter_mut().enumerate() {
        b.v = v.lane(l);
        b.w = w.lane(l);
    }
    true
}

/// The speed limits (the solve just ran and may have passed them; a non-finite
/// velocity becomes zero), then `Δp += v h`, `q ← normalise(q + ½ h (ω, 0) q)`,
/// `R = R(q)` ([`by_fours`]: [`integrate_four`] where it can, [`integrate_one`]
/// otherwise).
fn integrate_positions(bodies: &mut [SolverBody], h: f32, cfg: &WorldConfig) {
    by_fours(
        bodies,
        |four| integrate_four(four, h, cfg),
        |b| integrate_one(b, h, cfg),
    );
}

/// [`integrate_positions`] for one body.
#[inline]
fn integrate_one(b: &mut SolverBody, h: f32, cfg: &WorldConfig) {
    b.v = clamp_length(b.v, cfg.max_linear_speed);
    b.w = clamp_length(b.w, cfg.max_angular_speed);
    b.dp += b.v * h;
    b.q = b.q.integrate(b.w, h);
    b.rot = Mat3::from_quat(b.q);
}

/// [`integrate_one`] for four bodies side by side, each lane the same operations in the
/// same order: `Quat::integrate` (its Hamilton product and `Quat::normalize`, whose
/// three outcomes are lane selects) and `Mat3::from_quat` (`M4::from_quat`). Only when
/// every velocity is already within its limit (`clamp_length`'s first test, which then
/// leaves it as it is); false, with nothing written, otherwise.
#[inline]
fn integrate_four(four: &mut [SolverBody], h: f32, cfg: &WorldConfig) -> bool {
    let Some((max_v2, max_w2)) = squared_limits(cfg) else {
        return false;
    };
    let within = |b: &SolverBody| b.v.length_squared() <= max_v2 && b.w.length_squared() <= max_w2;
    if !four.iter().all(within) {
        return false;
    }
    let (mut v, mut w, mut dp) = (V4::ZERO, V4::ZERO, V4::ZERO);
    let mut q = [F4::ZERO; 4];
    for (l, b) in four.iter().enumerate() {
        v.set(l, b.v);
        w.set(l, b.w);
        dp.set(l, b.dp);
        for (lane, x) in q.iter_mut().zip([b.q.x, b.q.y, b.q.z, b.q.w]) {
            lane.set(l, x);
        }
    }
    let dp = dp.add(&v.scale(F4::splat(h)));
    // `(a, 0) q` with `a = ω h / 2`, as `Quat::integrate` forms it.
    let a = w.scale(F4::splat(0.5 * h));
    let [qx, qy, qz, qw] = q;
    let sum = [
        qx + ((a.x * qw + a.y * qz) - a.z * qy),
        qy + ((-(a.x * qz) + a.y * qw) + a.z * qx),
        qz + ((a.x * qy - a.y * qx) + a.z * qw),
        qw + ((-(a.x * qx) - a.y * qy) - a.z * qz),
    ];
    // `Quat::normalize`: unchanged when |q|² is 1 to the last bit, scaled by 1/√|q|²
    // when that is above 1e-20 and finite, the identity otherwise.
    let [sx, sy, sz, sw] = sum;
    let l2 = sx * sx + sy * sy + sz * sz + sw * sw;
    let inv = F4::splat(1.0).div(l2.sqrt());
    let one = F4::splat(1.0);
    let unit: [bool; 4] = core::array::from_fn(|l| l2.lane(l) == 1.0);
    let scales: [bool; 4] = core::array::from_fn(|l| {
        let x = l2.lane(l);
        x > 1.0e-20 && x.is_finite()
    });
    let identity = [F4::ZERO, F4::ZERO, F4::ZERO, one];
    let q: [F4; 4] = core::array::from_fn(|i| {
        let (s, id) = (sum[i], identity[i]);
        id.select_where(scales, s * inv).select_where(unit, s)
    });
    let rot = M4::from_quat(&q);
    for (l, b) in four.iter_mut().enumerate() {
        b.dp = dp.lane(l);
        b.q = Quat::from_xyzw(q[0].lane(l), q[1].lane(l), q[2].lane(l), q[3].lane(l));
        b.rot = rot.lane(l);
    }
    true
}

/// Write the solver bodies back: centre of mass moved by `Δp`, rotation, velocities,
/// `R I⁻¹ Rᵀ`.
fn finalize<const N: usize, const C: usize>(
    solver: &Solver<N, C>,
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
) {
    for sb in solver.bodies.iter() {
        let Some(b) = bodies.at_mut(sb.slot as usize) else {
            continue;
        };
        let c = b.world_center() + sb.dp;
        // `sb.rot` is `R(sb.q)`, formed at the last position update.
        b.set_center_pose_turned(c, sb.q, &sb.rot);
        b.linear_velocity = clamp_length(sb.v, cfg.max_linear_speed);
        b.angular_velocity = clamp_length(sb.w, cfg.max_angular_speed);
    }
}

/// `v` shortened to at most `max` (m/s or rad/s). A vector too large to square in `f32`
/// is first scaled down by its largest component; one that is not finite stops: zero is
/// the documented answer.
#[inline]
pub(crate) fn clamp_length(v: Vec3, max: f32) -> Vec3 {
    // The common case first: a finite vector within the limit comes back as it is (what
    // the full path below returns for it too). Below a finite `max²`, `|v|²` is finite
    // itself: the one test on `max²` does not depend on `v` and leaves a loop over bodies.
    let l2 = v.length_squared();
    let max2 = max * max;
    if l2 <= max2 && max2 < f32::INFINITY {
        return v;
    }
    if !v.is_finite() {
        return Vec3::ZERO;
    }
    let big = v.abs().max_elem();
    let v = if big > max { v * (max / big) } else { v };
    let l2 = v.length_squared();
    if l2 > max * max {
        v * (max / scalar::sqrt(l2))
    } else {
        v
    }
}

/// Whether solver body `i` moves in the solve: it has an entry and a dynamic body's
/// inverse mass (kinematic bodies have 0).
#[inline]
pub(crate) fn moves(bodies: &[SolverBody], i: u32) -> bool {
    bodies.get(i as usize).is_some_and(|s| s.inv_mass > 0.0)
}

/// True for a body the solver moves: dynamic and awake.
#[inline]
pub(crate) fn is_active(b: &Body<'_>) -> bool {
    b.is_dynamic() && b.awake
}

/// True for a kinematic body with a non-zero velocity.
#[inline]
pub(crate) fn is_moving_kinematic(b: &Body<'_>) -> bool {
    b.kind == BodyKind::Kinematic
        && b.awake
        && (b.linear_velocity.length_squared() > 0.0 || b.angular_velocity.length_squared() > 0.0)
}

/// `1 / (1/m_a + 1/m_b + (I_a⁻¹ (r_a × d))·(r_a × d) + (I_b⁻¹ (r_b × d))·(r_b × d))` (kg),
/// or 0 when nothing can move along `d`.
#[inline]
pub(crate) fn effective_mass(
    inv_mass_a: f32,
    inv_inertia_a: &Mat3,
    r_a: Vec3,
    inv_mass_b: f32,
    inv_inertia_b: &Mat3,
    r_b: Vec3,
    d: Vec3,
) -> f32 {
    let rd_a = r_a.cross(d);
    let rd_b = r_b.cross(d);
    let k = inv_mass_a
        + inv_mass_b
        + inv_inertia_a.mul_vec(rd_a).dot(rd_a)
        + inv_inertia_b.mul_vec(rd_b).dot(rd_b);
    if k > 0.0 && k.is_finite() {
        1.0 / k
    } else {
        0.0
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::body::{BodyDesc, Material};
    use crate::rng::SplitMix64;
    use crate::shape::Shape;
    use crate::world::World;

    /// A world with every kind of lane the prepare meets: box stacks (four-point
    /// patches), balls with rolling resistance and twist friction (one point), capsules
    /// lying down (two points), a bouncing ball, a box sliding to a stop, a kinematic
    /// paddle, and a static ground.
    fn prepare_world() -> World<'static, 64, 512, 64> {
        let mut w: World<64, 512, 64> = World::new();
        let grippy = Material {
            restitution: 0.0,
            static_friction: 0.9,
            kinetic_friction: 0.5,
            rolling_resistance: 0.05,
            twist_friction: 0.02,
        };
        let bouncy = Material {
            restitution: 0.7,
            ..grippy
        };
        let ground = Shape::cuboid(Vec3::new(20.0, 0.5, 20.0)).unwrap();
        w.add(BodyDesc::fixed(ground).position(Vec3::new(0.0, -0.5, 0.0)))
            .unwrap();
        let cube = Shape::cuboid(Vec3::new(0.5, 0.5, 0.5)).unwrap();
        let mut rng = SplitMix64::new(17);
        for i in 0..12 {
            let x = (i % 4) as f32 * 1.3 - 2.0;
            let y = 0.5 + (i / 4) as f32 * 1.01;
            let q = Quat::from_axis_angle(Vec3::Y, rng.range(-0.1, 0.1));
            w.add(
                BodyDesc::dynamic(cube)
                    .position(Vec3::new(x, y, 0.0))
                    .rotation(q),
            )
            .unwrap();
        }
        let ball = Shape::sphere(0.3).unwrap();
        for i in 0..6 {
            let spin = Vec3::new(0.0, rng.range(-3.0, 3.0), rng.range(-3.0, 3.0));
            w.add(
                BodyDesc::dynamic(ball)
                    .material(grippy)
                    .position(Vec3::new(i as f32 - 3.0, 0.3, 3.0))
                    .velocity(Vec3::new(rng.range(-1.0, 1.0), 0.0, 0.0))
                    .angular_velocity(spin),
            )
            .unwrap();
        }
        w.add(
            BodyDesc::dynamic(ball)
                .material(bouncy)
                .position(Vec3::new(3.0, 2.0, -3.0)),
        )
        .unwrap();
        let rod = Shape::capsule(0.6, 0.2).unwrap();
        for i in 0..3 {
            let q = Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_2);
            w.add(
                BodyDesc::dynamic(rod)
                    .material(grippy)
                    .rotation(q)
                    .position(Vec3::new(i as f32 * 2.0 - 2.0, 0.2, -3.0)),
            )
            .unwrap();
        }
        w.add(
            BodyDesc::dynamic(cube)
                .position(Vec3::new(-5.0, 0.5, -5.0))
                .velocity(Vec3::new(4.0, 0.0, 0.0)),
        )
        .unwrap();
        w.add(
            BodyDesc::kinematic(cube)
                .position(Vec3::new(5.0, 0.6, 3.0))
                .velocity(Vec3::new(-1.0, 0.0, 0.0)),
        )
        .unwrap();
        // A heavy box on the first column: capped lanes (`support.rs`).
        w.add(
            BodyDesc::dynamic(cube)
                .position(Vec3::new(-2.0, 3.53, 0.0))
                .density(1.0e6),
        )
        .unwrap();
        w
    }

    /// A copy of `world` gathered and planned as a step begins: the copy, its
    /// configuration and the sub-step.
    fn planned(
        world: &World<'static, 64, 512, 64>,
    ) -> (World<'static, 64, 512, 64>, WorldConfig, f32) {
        let mut w = world.clone();
        let cfg = w.config;
        let h = cfg.substep();
        let differ = gather(&mut w.solver, &mut w.bodies, &cfg, h);
        plan(
            &mut w.solver,
            &w.contacts,
            &w.bodies,
            &mut w.pairs,
            differ,
            &cfg,
        );
        (w, cfg, h)
    }

    /// Support marks follow islands: a column of five boxes on the ground under a heavy
    /// box is held up (and the heavy box's contact is capped), a box in flight is not,
    /// and a world without a heavy contact marks nothing.
    #[test]
    fn support_marks_the_islands_the_ground_holds_up() {
        on_a_big_stack(check_support_marks);
    }

    fn check_support_marks() {
        let build = |density: f32| {
            let mut w: World<64, 512, 64> = World::new();
            let ground = Shape::cuboid(Vec3::new(20.0, 0.5, 20.0)).unwrap();
            w.add(BodyDesc::fixed(ground).position(Vec3::new(0.0, -0.5, 0.0)))
                .unwrap();
            let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
            let column: [crate::BodyHandle; 5] = core::array::from_fn(|i| {
                let d = if i == 4 { density } else { 1000.0 };
                let at = Vec3::new(0.0, 0.5 + i as f32, 0.0);
                w.add(BodyDesc::dynamic(cube).position(at).density(d))
                    .unwrap()
            });
            // Two boxes touching in flight: an island nothing holds up.
            let flying = w
                .add(BodyDesc::dynamic(cube).position(Vec3::new(5.0, 5.0, 0.0)))
                .unwrap();
            w.add(BodyDesc::dynamic(cube).position(Vec3::new(5.0, 6.0, 0.0)))
                .unwrap();
            w.step();
            (w, column, flying)
        };
        let held = |w: &World<'static, 64, 512, 64>, h: crate::BodyHandle| {
            let supports = support::Supports {
                marks: &w.solver.marks,
                gravity: w.config.gravity,
            };
            supports.held(w.solver.index[h.index as usize])
        };
        let (world, column, flying) = build(1.0e6);
        let (mut w, _, _) = planned(&world);
        assert!(w.solver.heavy);
        for (i, h) in column.iter().enumerate() {
            assert!(held(&w, *h), "box {i}");
        }
        assert!(!held(&w, flying));
        // The heavy box's contact: capped (the lane's inverse mass of the support is
        // 20 times the heavy box's, not the support's own 1000 times).
        let (top, heavy) = (column[3].index, column[4].index);
        let capped = |support: f32, held: f32| {
            let want = support::HEAVY_RATIO * held;
            (support - want).abs() <= 1e-6 * want
        };
        let mut seen = 0;
        let (store, contacts) = (&mut w.solver.store, &w.contacts);
        for g in 0..store.groups as usize {
            let group = store.group(g).unwrap();
            for l in 0..4 {
                let k = group.load_lane(l, contacts);
                if k.contact == NONE {
                    continue;
                }
                let (ma, mb) = (k.inv_mass_a, k.inv_mass_b);
                if (k.slot_a, k.slot_b) == (top, heavy) {
                    assert!(capped(ma, mb), "{ma} {mb}");
                    seen += 1;
                } else if (k.slot_a, k.slot_b) == (heavy, top) {
                    assert!(capped(mb, ma), "{ma} {mb}");
                    seen += 1;
                } else {
                    assert!(k.slot_a == 0 || ma > 0.0, "{k:?}");
                    assert!(k.slot_b == 0 || mb > 0.0, "{k:?}");
                }
            }
        }
        assert_eq!(seen, 1);
        // Equal densities: no heavy contact, so no marks are read.
        let (world, _, _) = build(1000.0);
        let (w, _, _) = planned(&world);
        assert!(!w.solver.heavy);
    }

    /// Run `f` on a thread with a 64 MiB stack: worlds, their clones and the stores are
    /// large for a debug build's test thread.
    fn on_a_big_stack(f: fn()) {
        std::thread::Builder::new()
            .stack_size(64 << 20)
            .spawn(f)
            .unwrap()
            .join()
            .unwrap();
    }

    /// The wide prepare (`wide/prepare.rs`) gives every lane the bits the scalar
    /// `contact_solver::prepare` and `Group::store_lane` give it, at the start and in
    /// the middle of a pile's motion (warm impulses, sticking and sliding patches).
    #[test]
    fn the_wide_prepare_gives_each_lane_the_scalar_prepare() {
        on_a_big_stack(compare_wide_and_scalar_prepare);
    }

    fn compare_wide_and_scalar_prepare() {
        let mut world = prepare_world();
        let mut lanes = 0usize;
        for step in 0..90 {
            if step % 6 == 1 {
                let (w, cfg, _) = planned(&world);
                let mut reference = w.solver.store.clone();
                let softness = contact_solver::Softness::for_contacts(&cfg);
                let mut k = contact_solver::ContactConstraint::default();
                for g in 0..reference.groups as usize {
                    let mut group = reference.group(g).unwrap();
                    for l in 0..4 {
                        let ci = group.contact(l);
                        if ci == NONE {
                            continue;
                        }
                        let c = &w.contacts[ci as usize];
                        let (sb, si) = (&w.solver.bodies, &w.solver.index);
                        // The support marks in a step with a heavy contact.
                        let supports = support::Supports {
                            marks: &w.solver.marks,
                            gravity: cfg.gravity,
                        };
                        let under = w.solver.heavy.then_some(&supports);
                        assert!(contact_solver::prepare(
                            c, ci, &w.bodies, sb, si, &softness, under, &cfg, &mut k
                        ));
                        group.store_lane(l, &k);
                        lanes += 1;
                    }
                }
                // Debug output tells -0.0 from 0.0 and shows NaN: a bitwise comparison.
                assert_eq!(
                    std::format!("{:?}", w.solver.store),
                    std::format!("{reference:?}"),
                    "step {step}"
                );
            }
            world.step();
        }
        assert!(lanes > 200, "{lanes} lanes compared");
    }

    /// A soft pass leaves the friction, twist and rolling impulses of torque-free lanes
    /// (a ball on the ground: no normal impulse turns a body) bit for bit as the warm
    /// start left them and moves the others'; the relax pass then moves those of the
    /// torque-free lanes too. Each lane's mark against the rule from its bodies.
    #[test]
    fn soft_passes_leave_the_friction_of_torque_free_lanes_to_the_relax() {
        on_a_big_stack(compare_soft_and_relax_friction);
    }

    fn compare_soft_and_relax_friction() {
        let mut world = prepare_world();
        let (mut free, mut others, mut moved_soft, mut moved_relax) = (0, 0, 0, 0);
        for step in 0..60 {
            let (mut w, cfg, h) = planned(&world);
            let (store, sbodies) = (&mut w.solver.store, &mut w.solver.bodies);
            wide::warm_start(store, sbodies);
            let impulses = |store: &mut WideStore<512>| {
                let mut out = std::vec::Vec::new();
                for g in 0..store.groups as usize {
                    let group = store.group(g).unwrap();
                    for l in 0..4 {
                        if group.contact(l) != NONE {
                            out.push((group.is_torque_free(l), group.friction_impulses(l)));
                        }
                    }
                }
                out
            };
            // The mark against the rule: each side a ball or not a moving dynamic body.
            for g in 0..store.groups as usize {
                let group = store.group(g).unwrap();
                for l in 0..4 {
                    let ci = group.contact(l);
                    if ci == NONE {
                        continue;
                    }
                    let c = &w.contacts[ci as usize];
                    let round = |slot: u32| {
                        let b = w.bodies.at(slot as usize).unwrap();
                        let solved = w.solver.index[slot as usize] != NONE;
                        matches!(b.shape, Shape::Sphere(_))
                            || b.kind != BodyKind::Dynamic
                            || !solved
                    };
                    assert_eq!(
                        group.is_torque_free(l),
                        round(c.a) && round(c.b),
                        "step {step}"
                    );
                }
            }
            // A soft (`true`) or relax (`false`) pass, after the bodies moved.
            let pass = |use_bias| wide::Pass {
                use_bias,
                moved: true,
                last: false,
            };
            let before = impulses(store);
            wide::solve(store, sbodies, &cfg, 1.0 / h, pass(true));
            let after_soft = impulses(store);
            integrate_positions(sbodies, h, &cfg);
            wide::solve(store, sbodies, &cfg, 1.0 / h, pass(false));
            let after_relax = impulses(store);
            let bits = |x: [f32; 5]| x.map(f32::to_bits);
            for ((b, s), r) in before.iter().zip(&after_soft).zip(&after_relax) {
                if b.0 {
                    free += 1;
                    assert_eq!(bits(b.1), bits(s.1), "step {step}");
                    moved_relax += usize::from(bits(s.1) != bits(r.1));
                } else {
                    others += 1;
                    moved_soft += usize::from(bits(b.1) != bits(s.1));
                }
            }
            world.step();
        }
        assert!(free > 100 && others > 100, "{free} {others}");
        assert!(moved_soft > others / 2, "{moved_soft} of {others}");
        assert!(moved_relax > free / 2, "{moved_relax} of {free}");
    }

    /// The warm start and a soft and a last relax pass over the groups of `w` (planned),
    /// the solver's way and `reference`'s, compared bit for bit: bodies and groups.
    fn solve_both_ways(
        w: &World<'static, 64, 512, 64>,
        cfg: &WorldConfig,
        h: f32,
        reference: wide::Reference,
        step: usize,
    ) {
        let store = &w.solver.store;
        for use_bias in [true, false] {
            let pass = wide::Pass {
                use_bias,
                moved: true,
                last: !use_bias,
            };
            let (mut store_a, mut bodies_a) = (store.clone(), w.solver.bodies.clone());
            wide::warm_start(&mut store_a, &mut bodies_a);
            wide::solve(&mut store_a, &mut bodies_a, cfg, 1.0 / h, pass);
            let (mut store_b, mut bodies_b) = (store.clone(), w.solver.bodies.clone());
            let (sb, bb) = (&mut store_b, &mut bodies_b);
            wide::warm_start_and_solve_as(reference, sb, bb, cfg, 1.0 / h, pass);
            // Debug output tells -0.0 from 0.0 and shows NaN: a bitwise comparison.
            assert_eq!(
                std::format!("{:?}", bodies_a),
                std::format!("{:?}", bodies_b),
                "step {step}"
            );
            assert_eq!(
                std::format!("{:?}", store_a),
                std::format!("{:?}", store_b),
                "step {step}"
            );
        }
    }

    /// Overflow groups solved in runs of lanes without a shared body give the bits of the
    /// same groups solved one lane at a time: the warm start and a soft and a relax pass
    /// over a world's groups both ways, its bodies compared bit for bit, at steps where
    /// some overflow group holds a run of several lanes and another has to split.
    #[test]
    fn overflow_runs_give_the_bits_of_one_lane_at_a_time() {
        on_a_big_stack(compare_runs_and_lanes);
    }

    fn compare_runs_and_lanes() {
        let mut world = prepare_world();
        let (mut shared_runs, mut split_groups) = (0, 0);
        for step in 0..90 {
            let (mut w, cfg, h) = planned(&world);
            let store = &mut w.solver.store;
            for g in store.overflow_from..store.groups {
                let group = store.group(g as usize).unwrap();
                let active = (0..4).filter(|&l| group.contact(l) != NONE).count();
                let (_, n) = wide::overflow_runs_for_tests(&group);
                shared_runs += usize::from(n < active);
                split_groups += usize::from(n > 1);
            }
            solve_both_ways(&w, &cfg, h, wide::Reference::LaneByLane, step);
            world.step();
        }
        assert!(
            shared_runs > 0 && split_groups > 0,
            "{shared_runs} {split_groups}"
        );
    }

    /// A group whose body A stays still in every lane (the ground under a pile) takes
    /// kernels without A; they give the bits of the kernels of two moving bodies: the
    /// warm start and a soft and a last relax pass over a world's groups both ways (with
    /// restitution, rolling resistance and twist friction in play), its bodies and groups
    /// compared bit for bit, at steps where full groups of each kind are solved.
    #[test]
    fn groups_without_a_moving_body_a_give_the_bits_of_two_moving_bodies() {
        on_a_big_stack(compare_still_and_moving_a);
    }

    fn compare_still_and_moving_a() {
        let mut world = prepare_world();
        let (mut still, mut moving) = (0usize, 0usize);
        for step in 0..120 {
            let (mut w, cfg, h) = planned(&world);
            let store = &mut w.solver.store;
            for g in 0..store.overflow_from {
                let group = store.group(g as usize).unwrap();
                let full = (0..4).all(|l| group.contact(l) != NONE);
                let a_still = wide::still_a_for_tests(&group);
                still += usize::from(full && a_still);
                moving += usize::from(full && !a_still);
            }
            solve_both_ways(&w, &cfg, h, wide::Reference::AMoving, step);
            world.step();
        }
        assert!(still > 100 && moving > 40, "{still} {moving}");
    }

    /// The placement gives the order of a stable sort: by final colour (each colour's
    /// last partial group, in visit order, moved to the overflow colour), then by point
    /// class and contact index within a colour that stays; the overflow colour in visit
    /// order. Contact indices are scrambled against the visit order, so the two orders
    /// differ.
    #[test]
    fn colour_placement_matches_a_stable_sort() {
        let mut rng = SplitMix64::new(3);
        for n in [0usize, 1, 3, 4, 5, 17, 64, 300] {
            let mut scratch: HVec<(u32, u32), 512> = HVec::new();
            let mut count = [0u32; wide::COLORS + 1];
            for i in 0..n {
                let c = (rng.next_u64() % (wide::COLORS as u64 + 1)) as u32;
                count[c as usize] += 1;
                // 263 is odd: `263 i mod 512` is a permutation of 0..512.
                scratch.push((c, (263 * i as u32) % 512)).unwrap();
            }
            // The reference: demote the tail of each colour, then a stable sort.
            let mut want: std::vec::Vec<(u32, u32)> = scratch.iter().copied().collect();
            let mut seen = [0u32; wide::COLORS + 1];
            for e in want.iter_mut() {
                let c = e.0 as usize;
                let place = seen[c];
                seen[c] += 1;
                if c != wide::OVERFLOW as usize && place >= count[c] / 4 * 4 {
                    e.0 = wide::OVERFLOW;
                }
            }
            // Within a colour that stays, by class (here the contact index mod 4), then
            // by contact index; the overflow colour in visit order.
            let class = |ci: u32| (ci % 4) as usize;
            want.sort_by_key(|e| {
                let kept = e.0 != wide::OVERFLOW;
                if kept {
                    (e.0, class(e.1), e.1)
                } else {
                    (e.0, 0, 0)
                }
            });
            // Stale marks from an earlier step must not matter.
            let mut slot_of = [7u8; 512];
            place_in_colour_order(&mut scratch, &count, class, &mut slot_of, 512);
            assert_eq!(scratch.as_slice(), want.as_slice(), "n {n}");
        }
    }

    /// The flags the skipped passes read are what their scans would have found: after a
    /// step, `deep` says whether some lane holding a contact has a point deeper than
    /// projection's threshold (brute force over the store), and `bouncy` whether some
    /// such lane has restitution. Both answers are seen: a box sunk 20 cm into the ground
    /// (deep, no bounce) and a resting box beside a bouncing ball (bounce, nothing deep).
    #[test]
    fn skipped_passes_see_what_their_scans_would() {
        let ground = Shape::cuboid(Vec3::new(20.0, 0.5, 20.0)).unwrap();
        let cube = Shape::cuboid(Vec3::new(0.5, 0.5, 0.5)).unwrap();
        let ball = Shape::sphere(0.3).unwrap();
        let bouncy = Material {
            restitution: 0.7,
            ..Material::DEFAULT
        };
        let scan = |w: &mut World<'static, 64, 512, 64>| {
            let deep = -crate::dynamics::projection::DEEP_SLOPS * w.config.slop;
            let store = &mut w.solver.store;
            let (mut any_deep, mut any_bouncy) = (false, false);
            for g in 0..store.groups as usize {
                let group = store.group(g).unwrap();
                for l in 0..4 {
                    if group.contact(l) != NONE {
                        any_deep |= group.deeper_than(l, deep);
                        any_bouncy |= group.restitution(l) > 0.0;
                    }
                }
            }
            (store.deep, any_deep, store.bouncy, any_bouncy)
        };
        let mut sunk: World<64, 512, 64> = World::new();
        sunk.add(BodyDesc::fixed(ground).position(Vec3::new(0.0, -0.5, 0.0)))
            .unwrap();
        sunk.add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, 0.3, 0.0)))
            .unwrap();
        sunk.step();
        assert_eq!(scan(&mut sunk), (Some(true), true, false, false));
        let mut resting: World<64, 512, 64> = World::new();
        resting
            .add(BodyDesc::fixed(ground).position(Vec3::new(0.0, -0.5, 0.0)))
            .unwrap();
        resting
            .add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, 0.5, 0.0)))
            .unwrap();
        resting
            .add(
                BodyDesc::dynamic(ball)
                    .material(bouncy)
                    .position(Vec3::new(3.0, 0.31, 0.0))
                    .velocity(Vec3::new(0.0, -2.0, 0.0)),
            )
            .unwrap();
        resting.step();
        assert_eq!(scan(&mut resting), (Some(false), false, true, true));
    }

    /// The speed limit: within it a vector comes back bit for bit, beyond it it is
    /// shortened to the limit in its own direction, and anything non-finite is zero.
    #[test]
    fn clamp_length_keeps_short_vectors_and_shortens_long_ones() {
        let mut rng = SplitMix64::new(5);
        let max = 100.0f32;
        for _ in 0..2000 {
            let mut c = || (rng.next_u64() % 20_001) as f32 * 0.01 - 100.0;
            let v = Vec3::new(c(), c(), c());
            let out = clamp_length(v, max);
            if v.length_squared() <= max * max {
                assert_eq!(out, v);
            } else {
                assert!(
                    (out.length() - max).abs() <= 1.0e-4 * max,
                    "{v:?} -> {out:?}"
                );
                assert!(out.dot(v) > 0.0 && out.cross(v).length() <= 1.0e-3 * v.length() * max);
            }
        }
        // Too large to square in f32: scaled by its largest component first.
        let huge = clamp_length(Vec3::new(3.0e38, -3.0e38, 1.0), max);
        assert!((huge.length() - max).abs() <= 1.0e-3, "{huge:?}");
        for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
            assert_eq!(clamp_length(Vec3::new(1.0, bad, 0.0), max), Vec3::ZERO);
        }
        // Exactly at the limit: unchanged.
        assert_eq!(
            clamp_length(Vec3::new(0.0, -max, 0.0), max),
            Vec3::new(0.0, -max, 0.0)
        );
        // A limit whose square is infinite: finite vectors unchanged (even those whose
        // square is infinite too), non-finite ones zero.
        for limit in [f32::MAX, f32::INFINITY] {
            for v in [Vec3::new(3.0e38, -3.0e38, 1.0), Vec3::new(0.5, -2.0, 7.0)] {
                assert_eq!(clamp_length(v, limit), v);
            }
            for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
                assert_eq!(clamp_length(Vec3::new(bad, 1.0, 0.0), limit), Vec3::ZERO);
            }
        }
    }

    /// A solver body for the integration test: random velocities (some past the speed
    /// limits, some not finite), a rotation that is unit, exactly the identity, tiny, or
    /// not finite.
    fn random_solver_body(rng: &mut SplitMix64, cfg: &WorldConfig) -> SolverBody {
        let kind = rng.next_u64() % 16;
        let mut c = |scale: f32| (rng.next_u64() % 20_001) as f32 * 1.0e-4 * scale - scale;
        let mut b = SolverBody::ZERO;
        let fast = if kind == 0 { 4.0 } else { 0.5 };
        b.v = Vec3::new(c(1.0), c(1.0), c(1.0)) * (fast * cfg.max_linear_speed);
        b.w = Vec3::new(c(1.0), c(1.0), c(1.0)) * (fast * cfg.max_angular_speed);
        b.dp = Vec3::new(c(0.3), c(0.3), c(0.3));
        b.q = match kind {
            1 => Quat::IDENTITY,
            2 => Quat::from_xyzw(0.0, 0.0, 0.0, 1.0e-12),
            3 => Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0),
            _ => Quat::from_xyzw(c(1.0), c(1.0), c(1.0), c(1.0)).normalize(),
        };
        if kind == 4 {
            b.v.y = f32::NAN;
        }
        // Gravity's increment, a torque's, damping; kinematic (inverse mass 0) now and then.
        b.inv_mass = if kind == 6 { 0.0 } else { 0.5 };
        b.dv = Vec3::new(0.0, -9.81 * cfg.substep(), 0.0);
        b.dw = Vec3::new(c(0.1), c(0.1), c(0.1));
        (b.linear_damping, b.angular_damping) = (1.0 / (1.0 + c(0.01).abs()), 0.999);
        if kind == 5 {
            // Resting: ω = 0 keeps an identity rotation's |q|² exactly 1.
            (b.w, b.q) = (Vec3::ZERO, Quat::IDENTITY);
        }
        b
    }

    #[test]
    fn four_bodies_in_lanes_integrate_to_the_bits_of_one_at_a_time() {
        // Velocities, then positions, as a sub-step does.
        let cfg = WorldConfig::DEFAULT;
        let h = cfg.substep();
        let mut rng = SplitMix64::new(41);
        let mut lanes_taken = 0;
        for round in 0..3000 {
            // 0 to 11 bodies: full groups of four and a remainder.
            let n = (rng.next_u64() % 12) as usize;
            let mut bodies = [SolverBody::ZERO; 11];
            for b in bodies.iter_mut().take(n) {
                *b = random_solver_body(&mut rng, &cfg);
            }
            let mut one_at_a_time = bodies;
            for b in one_at_a_time.iter_mut().take(n) {
                velocities_one(b, &cfg);
                integrate_one(b, h, &cfg);
            }
            let mut copy = bodies;
            lanes_taken += usize::from(n >= 4 && velocities_four(&mut copy[..4], &cfg));
            lanes_taken += usize::from(n >= 4 && integrate_four(&mut copy[..4], h, &cfg));
            integrate_velocities(&mut bodies[..n], &cfg);
            integrate_positions(&mut bodies[..n], h, &cfg);
            // Bits, so NaN rotations compare too.
            let bits = |b: &SolverBody| {
                let q = [b.q.x, b.q.y, b.q.z, b.q.w].map(f32::to_bits);
                let r = [b.rot.x, b.rot.y, b.rot.z, b.dp, b.v, b.w]
                    .map(|v| [v.x, v.y, v.z].map(f32::to_bits));
                (q, r)
            };
            for (i, (x, y)) in bodies.iter().zip(&one_at_a_time).enumerate() {
                assert_eq!(bits(x), bits(y), "round {round}, body {i} of {n}");
            }
        }
        // Both paths ran: groups within the limits, and groups that fell back.
        assert!(lanes_taken > 400, "{lanes_taken}");
    }
}
