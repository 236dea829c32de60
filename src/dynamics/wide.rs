//! The contact rows four at a time: graph colouring, structure-of-arrays lanes, and the
//! sub-step kernels (warm start, soft solve, relax) of `contact_solver.rs` written for
//! four contacts side by side.
//!
//! # Colouring (Box2D v3's constraint graph)
//!
//! A colour holds contacts that share no moving dynamic body, so its contacts can be
//! solved at the same time. Contacts are coloured in their deterministic order, each
//! taking the lowest free colour: contacts between two dynamic bodies search colours
//! `0..DYNAMIC_COLORS` upwards, contacts with a static, kinematic or sleeping partner
//! search from the top colour downwards (so they tend to be solved late: Gauss-Seidel
//! gives the last word to the last row, and a wall must win over a ball knocked into
//! it). A contact that fits no colour goes to the overflow colour, whose groups are
//! solved in lane order, a run of lanes that share no moving body at a time. Kinematic
//! bodies never move in the solve (their velocity comes back unchanged), so they do not
//! take colours.
//!
//! # Lanes
//!
//! Within a colour, contacts are packed four to a group in colour order; a colour's last
//! partial group joins the overflow colour (so no lane is wasted but the last). Groups
//! are solved in colour order, the overflow groups last. A group lives in four consecutive
//! [`WideSlot`]s: slot `j` holds point `j` of the four contacts as `[f32; 4]` lanes,
//! plus a quarter of the per-contact data (normal, tangents, friction patch, rolling),
//! so the store costs what one scalar constraint per contact would. Every lane runs
//! exactly the scalar rows of `contact_solver.rs` (same operations, same order), so the
//! answer does not depend on whether the compiler vectorised the lanes, and the solve
//! order (colours, then groups, then lanes) is the same on every target.
//!
//! A point row past a contact's points is empty (zero mass, zero impulse) and pushes
//! nothing, so a full group whose contacts all have a single point (spheres, capsule
//! ends, corners) runs a kernel of one point row instead of four, and one whose contacts
//! have at most two (edges, capsules lying down) a kernel of two: the same velocities
//! (an empty row can at most turn a velocity component of −0 into +0) for less work.
//! The plan orders each colour's contacts by point count
//! (`solver::place_in_colour_order`), so most groups hold contacts of one count. (A
//! kernel of three rows saved nothing measurable: three-point manifolds are rare.)
//!
//! A soft pass leaves the friction, twist and rolling rows of torque-free contacts (balls:
//! `contact_solver::torque_free`) to the relax passes: a full group of them runs a kernel
//! without those rows, a group that mixes them with other contacts the masked kernel.

mod prepare;

use heapless::Vec as HVec;

use super::contact::Contact;
use super::contact_solver::{ConstraintPoint, ContactConstraint, Softness};
use super::solver::{SolverBody, NONE};
use crate::config::WorldConfig;
use crate::math::lanes::{F4, V4};
use crate::math::Vec3;

pub(crate) use prepare::{prepare_group, Inputs as PrepareInputs};

/// Colours of the constraint graph, overflow excluded (Box2D v3's count). At most 32: a
/// solver body's colours are the bits of a `u32`.
pub(crate) const COLORS: usize = 24;

/// Colours contacts between two dynamic bodies may take (the others fill from the top);
/// Box2D v3 keeps four for the static ones, as here. A box in a 3D stack touches up to a
/// dozen dynamic neighbours, and the greedy colouring needs more colours than that: with
/// 12 of 16, a fifth of `jolt_pyramid`'s contacts overflowed into groups solved one lane
/// at a time; with 20 none do, and the scene's step takes 19 % fewer instructions.
pub(crate) const DYNAMIC_COLORS: usize = 20;

// Every colour is a bit of `SolverBody::colours`, and the dynamic ones are a part of all.
const _: () = assert!(COLORS <= 32 && DYNAMIC_COLORS <= COLORS);

/// The overflow colour: groups solved in lane order, in runs of lanes that share no
/// moving body ([`overflow_runs`]).
pub(crate) const OVERFLOW: u32 = COLORS as u32;

/// Slots kept beside the `CONTACTS` main ones: one group, for the last partial overflow
/// group (every colour's partial group joins the overflow colour, so the groups hold at
/// most three empty lanes in all).
pub(crate) const PAD_SLOTS: usize = 4;

/// The mask of a pass over a full group.
const ALL_LANES: [bool; 4] = [true; 4];
/// No lane.
const NO_LANES: [bool; 4] = [false; 4];

/// Per-contact data per slot quarter.
const QUARTER: usize = 19;

/// Point `j` of four contacts, lane per contact (symbols as in `contact_solver.rs`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct WidePoint {
    local_a: V4,
    local_b: V4,
    adjusted: F4,
    rn_a: V4,
    rn_b: V4,
    in_a: V4,
    in_b: V4,
    normal_mass: F4,
    normal_impulse: F4,
    twist_arm: F4,
    separation: F4,
    separation0: F4,
    total_impulse: F4,
    normal_speed0: F4,
    bounced: F4,
}

/// A quarter of a group: one point of its four contacts, a quarter of their shared data,
/// and four integers per lane (see the field docs of [`Group`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct WideSlot {
    p: WidePoint,
    s: [F4; QUARTER],
    idx: [u32; 4],
}

// Quarter 0: normal, tangents, masses, softness, coefficients.
const NORMAL: usize = 0;
const T1: usize = 3;
const T2: usize = 6;
const INV_MASS_A: usize = 9;
const INV_MASS_B: usize = 10;
const BIAS_RATE: usize = 11;
const MASS_SCALE: usize = 12;
const IMPULSE_SCALE: usize = 13;
const MU_S: usize = 14;
const MU_K: usize = 15;
const ROLLING: usize = 16;
const TWIST: usize = 17;
const RESTITUTION: usize = 18;
// Quarter 1: patch Jacobians, tangent mass, patch impulse.
const RT_A0: usize = 0;
const RT_A1: usize = 3;
const RT_B0: usize = 6;
const RT_B1: usize = 9;
const TANGENT_MASS: usize = 12;
const TANGENT_IMPULSE: usize = 15;
const RADIUS_SUM: usize = 17;
// Quarter 2: patch inertia products, angular rows.
const IT_A0: usize = 0;
const IT_A1: usize = 3;
const IT_B0: usize = 6;
const IT_B1: usize = 9;
const AXIS_MASS: usize = 12;
const ANGULAR_IMPULSE: usize = 15;
// Quarter 3: I⁻¹ times the three axes, both bodies.
const IA_AXES: usize = 0;
const IB_AXES: usize = 9;

/// Flag bits of a lane's integer in slot 3 (above the point count in the low byte).
const STICKING: u32 = 1 << 8;
const ESTABLISHED: u32 = 1 << 9;
/// `contact_solver::torque_free`: no friction rows in the soft passes.
const TORQUE_FREE: u32 = 1 << 10;

#[inline]
fn v4(s: &[F4; QUARTER], at: usize) -> V4 {
    V4 {
        x: s.get(at).copied().unwrap_or_default(),
        y: s.get(at + 1).copied().unwrap_or_default(),
        z: s.get(at + 2).copied().unwrap_or_default(),
    }
}

#[inline]
fn f4(s: &[F4; QUARTER], at: usize) -> F4 {
    s.get(at).copied().unwrap_or_default()
}

#[inline]
fn set_lane(s: &mut [F4; QUARTER], at: usize, l: usize, x: f32) {
    if let Some(v) = s.get_mut(at) {
        v.set(l, x);
    }
}

#[inline]
fn set_lane_v(s: &mut [F4; QUARTER], at: usize, l: usize, v: Vec3) {
    set_lane(s, at, l, v.x);
    set_lane(s, at + 1, l, v.y);
    set_lane(s, at + 2, l, v.z);
}

#[inline]
fn lane_v(s: &[F4; QUARTER], at: usize, l: usize) -> Vec3 {
    Vec3::new(
        f4(s, at).lane(l),
        f4(s, at + 1).lane(l),
        f4(s, at + 2).lane(l),
    )
}

/// The four slots of one group, borrowed together.
pub(crate) struct Group<'s> {
    /// Point 0; per-contact quarter 0; per lane the solver index of body A.
    s0: &'s mut WideSlot,
    /// Point 1; quarter 1; per lane the solver index of body B.
    s1: &'s mut WideSlot,
    /// Point 2; quarter 2; per lane the contact index ([`NONE`]: an empty lane).
    s2: &'s mut WideSlot,
    /// Point 3; quarter 3; per lane the point count and the patch flags.
    s3: &'s mut WideSlot,
}

/// The lane store of one step: the groups of the coloured constraints.
#[derive(Clone, Debug)]
pub(crate) struct WideStore<const C: usize> {
    main: HVec<WideSlot, C>,
    extra: HVec<WideSlot, PAD_SLOTS>,
    /// Groups in use.
    pub groups: u32,
    /// The first overflow group (groups from here on are solved in runs of lanes that
    /// share no moving body).
    pub overflow_from: u32,
    /// Whether some point was left deeper than `projection::DEEP_SLOPS` slops by the
    /// step's last pass (which measures every point's separation as projection reads
    /// it); `None` before that pass, as after [`WideStore::reset`].
    pub deep: Option<bool>,
    /// Whether some lane holding a contact has restitution (set by the plan as it
    /// prepares the groups): the collision pass has none to look at otherwise.
    pub bouncy: bool,
}

impl<const C: usize> WideStore<C> {
    /// Empty.
    pub const fn new() -> Self {
        WideStore {
            main: HVec::new(),
            extra: HVec::new(),
            groups: 0,
            overflow_from: 0,
            deep: None,
            bouncy: false,
        }
    }

    /// Room for `groups` groups, every lane marked empty (no contact, no points); false
    /// when the store cannot hold them. Slots kept from the last step keep their old
    /// numbers: a lane is written whole when a constraint is stored in it, and an empty
    /// lane is never in a pass's mask, so what it holds never reaches a body (lanes do not
    /// mix). Only slots new to the store are zeroed.
    pub fn reset(&mut self, groups: usize) -> bool {
        self.groups = 0;
        self.overflow_from = 0;
        self.deep = None;
        self.bouncy = false;
        let slots = groups.saturating_mul(4);
        if slots > C + PAD_SLOTS {
            return false;
        }
        let in_main = slots.min(C);
        // Cannot fail: both lengths are within capacity. Shrinking truncates, growing
        // zeroes the new slots only.
        let _ = self.main.resize_default(in_main);
        let _ = self.extra.resize_default(slots - in_main);
        for g in 0..groups {
            if let Some(group) = self.group(g) {
                group.s0.idx = [NONE; 4];
                group.s1.idx = [NONE; 4];
                group.s2.idx = [NONE; 4];
                group.s3.idx = [0; 4];
            }
        }
        self.groups = groups as u32;
        true
    }

    /// The four slots of group `g`. Inline: every pass asks for every group, and every
    /// group but the last few lies in the main slots, four slots of one slice.
    #[inline]
    pub fn group(&mut self, g: usize) -> Option<Group<'_>> {
        let start = g.checked_mul(4)?;
        let end = start.saturating_add(4);
        if end <= self.main.len() {
            return match self.main.get_mut(start..end) {
                Some([s0, s1, s2, s3]) => Some(Group { s0, s1, s2, s3 }),
                _ => None,
            };
        }
        self.group_across(start)
    }

    /// The four slots from slot `start` on, across the main and the extra slots.
    #[cold]
    #[inline(never)]
    fn group_across(&mut self, start: usize) -> Option<Group<'_>> {
        let (head, tail) = (&mut self.main, &mut self.extra);
        let main_len = head.len();
        let from_main = head.get_mut(start.min(main_len)..).unwrap_or(&mut []);
        let skip = start.saturating_sub(main_len);
        let from_extra = tail.get_mut(skip.min(PAD_SLOTS)..).unwrap_or(&mut []);
        let mut it = from_main.iter_mut().chain(from_extra.iter_mut());
        let (Some(s0), Some(s1), Some(s2), Some(s3)) = (it.next(), it.next(), it.next(), it.next())
        else {
            return None;
        };
        Some(Group { s0, s1, s2, s3 })
    }
}

impl Group<'_> {
    fn point(&self, j: usize) -> &WidePoint {
        match j {
            0 => &self.s0.p,
            1 => &self.s1.p,
            2 => &self.s2.p,
            _ => &self.s3.p,
        }
    }

    fn point_mut(&mut self, j: usize) -> &mut WidePoint {
        match j {
            0 => &mut self.s0.p,
            1 => &mut self.s1.p,
            2 => &mut self.s2.p,
            _ => &mut self.s3.p,
        }
    }

    /// The contact index of lane `l`, or [`NONE`] for an empty lane.
    pub fn contact(&self, l: usize) -> u32 {
        self.s2.idx.get(l).copied().unwrap_or(NONE)
    }

    /// The most points any contact of the group has: the point rows past it are empty in
    /// every lane (module docs).
    #[inline(always)]
    fn point_rows(&self) -> usize {
        // An empty lane's flags are 0 (`WideStore::reset`).
        let [f0, f1, f2, f3] = self.s3.idx.map(|f| f & 0xff);
        (f0.max(f1).max(f2.max(f3)) as usize).min(4)
    }

    /// Lanes whose contact is torque-free (`contact_solver::torque_free`).
    #[inline]
    fn torque_free(&self) -> [bool; 4] {
        self.s3.idx.map(|f| f & TORQUE_FREE != 0)
    }

    /// Lane `l`'s friction impulses: the two tangent, two rolling and the twist impulse
    /// (the solver's tests).
    #[cfg(test)]
    pub(crate) fn friction_impulses(&self, l: usize) -> [f32; 5] {
        let (q1, q2) = (&self.s1.s, &self.s2.s);
        [
            f4(q1, TANGENT_IMPULSE).lane(l),
            f4(q1, TANGENT_IMPULSE + 1).lane(l),
            f4(q2, ANGULAR_IMPULSE).lane(l),
            f4(q2, ANGULAR_IMPULSE + 1).lane(l),
            f4(q2, ANGULAR_IMPULSE + 2).lane(l),
        ]
    }

    /// Whether lane `l` is marked torque-free (the solver's tests).
    #[cfg(test)]
    pub(crate) fn is_torque_free(&self, l: usize) -> bool {
        self.torque_free().get(l).copied().unwrap_or(false)
    }

    /// Some lane is torque-free.
    #[inline]
    fn has_torque_free(&self) -> bool {
        let [f0, f1, f2, f3] = self.s3.idx;
        (f0 | f1 | f2 | f3) & TORQUE_FREE != 0
    }

    /// Body A stays still in every lane: no solver body (static, or sleeping and not
    /// woken), so its velocities are zero through the whole solve. Contacts with a static
    /// partner search the colours from the top (module docs), so they fill whole groups
    /// of their own, and the ground or terrain, made before the bodies on it, is their
    /// body A. `mesh_pile`: about 70 % of its full groups; `boxes` and `spheres` 7 to 9 %.
    #[inline]
    fn still_a(&self) -> bool {
        self.s0.idx == [NONE; 4]
    }

    /// Lanes holding a contact.
    fn active(&self) -> [bool; 4] {
        core::array::from_fn(|l| self.contact(l) != NONE)
    }

    /// Copy lane `l`'s accumulated impulses and stick/slip state into contact `c`.
    pub fn store_impulses(&self, l: usize, c: &mut Contact) {
        let flags = self.s3.idx.get(l).copied().unwrap_or(0);
        let len = usize::from(c.len).min((flags & 0xff) as usize);
        for (j, q) in c.points.iter_mut().take(len).enumerate() {
            q.normal_impulse = stored(self.point(j).normal_impulse.lane(l));
        }
        let (q0, q1, q2) = (&self.s0.s, &self.s1.s, &self.s2.s);
        let t1 = lane_v(q0, T1, l);
        let t2 = lane_v(q0, T2, l);
        let f = t1 * f4(q1, TANGENT_IMPULSE).lane(l) + t2 * f4(q1, TANGENT_IMPULSE + 1).lane(l);
        c.friction_impulse = Vec3::new(stored(f.x), stored(f.y), stored(f.z));
        c.twist_impulse = stored(f4(q2, ANGULAR_IMPULSE + 2).lane(l));
        c.sticking = flags & STICKING != 0;
    }

    /// True when some point of lane `l` ended the solve deeper than `depth` (negative).
    pub fn deeper_than(&self, l: usize, depth: f32) -> bool {
        let len = self.s3.idx.get(l).map_or(0, |f| (f & 0xff) as usize);
        (0..len.min(4)).any(|j| self.point(j).separation.lane(l) < depth)
    }

    /// The restitution of lane `l`.
    pub fn restitution(&self, l: usize) -> f32 {
        f4(&self.s0.s, RESTITUTION).lane(l)
    }

    /// True when a lane holding a contact has restitution (the lanes the restitution
    /// passes visit).
    pub fn has_restitution(&self) -> bool {
        (0..4).any(|l| self.contact(l) != NONE && self.restitution(l) > 0.0)
    }

    /// True when some lane has restitution: only those lanes' restitution records are
    /// read (by the restitution pass), so a group without any skips keeping them.
    #[inline]
    fn bouncy(&self) -> bool {
        f4(&self.s0.s, RESTITUTION).0.iter().any(|&e| e > 0.0)
    }

    /// Write constraint `k` into lane `l` (its points, patch and rows).
    pub fn store_lane(&mut self, l: usize, k: &ContactConstraint) {
        let (s0, s1, s2, s3) = (
            &mut self.s0.s,
            &mut self.s1.s,
            &mut self.s2.s,
            &mut self.s3.s,
        );
        set_lane_v(s0, NORMAL, l, k.normal);
        set_lane_v(s0, T1, l, k.tangents[0]);
        set_lane_v(s0, T2, l, k.tangents[1]);
        set_lane(s0, INV_MASS_A, l, k.inv_mass_a);
        set_lane(s0, INV_MASS_B, l, k.inv_mass_b);
        set_lane(s0, BIAS_RATE, l, k.softness.bias_rate);
        set_lane(s0, MASS_SCALE, l, k.softness.mass_scale);
        set_lane(s0, IMPULSE_SCALE, l, k.softness.impulse_scale);
        set_lane(s0, MU_S, l, k.friction[0]);
        set_lane(s0, MU_K, l, k.friction[1]);
        set_lane(s0, ROLLING, l, k.rolling);
        set_lane(s0, TWIST, l, k.twist);
        set_lane(s0, RESTITUTION, l, k.restitution);
        set_lane_v(s1, RT_A0, l, k.rt_a[0]);
        set_lane_v(s1, RT_A1, l, k.rt_a[1]);
        set_lane_v(s1, RT_B0, l, k.rt_b[0]);
        set_lane_v(s1, RT_B1, l, k.rt_b[1]);
        for (i, m) in k.tangent_mass.iter().enumerate() {
            set_lane(s1, TANGENT_MASS + i, l, *m);
        }
        for (i, t) in k.tangent_impulse.iter().enumerate() {
            set_lane(s1, TANGENT_IMPULSE + i, l, *t);
        }
        set_lane(s1, RADIUS_SUM, l, k.radius_sum);
        set_lane_v(s2, IT_A0, l, k.it_a[0]);
        set_lane_v(s2, IT_A1, l, k.it_a[1]);
        set_lane_v(s2, IT_B0, l, k.it_b[0]);
        set_lane_v(s2, IT_B1, l, k.it_b[1]);
        for i in 0..3 {
            set_lane(
                s2,
                AXIS_MASS + i,
                l,
                k.axis_mass.get(i).copied().unwrap_or(0.0),
            );
            set_lane(
                s2,
                ANGULAR_IMPULSE + i,
                l,
                k.angular_impulse.get(i).copied().unwrap_or(0.0),
            );
            set_lane_v(
                s3,
                IA_AXES + 3 * i,
                l,
                k.ia_axes.get(i).copied().unwrap_or_default(),
            );
            set_lane_v(
                s3,
                IB_AXES + 3 * i,
                l,
                k.ib_axes.get(i).copied().unwrap_or_default(),
            );
        }
        if let Some(x) = self.s0.idx.get_mut(l) {
            *x = k.a;
        }
        if let Some(x) = self.s1.idx.get_mut(l) {
            *x = k.b;
        }
        if let Some(x) = self.s2.idx.get_mut(l) {
            *x = k.contact;
        }
        let flags = u32::from(k.len)
            | if k.sticking { STICKING } else { 0 }
            | if k.established { ESTABLISHED } else { 0 }
            | if k.torque_free { TORQUE_FREE } else { 0 };
        if let Some(x) = self.s3.idx.get_mut(l) {
            *x = flags;
        }
        for j in 0..4 {
            let src = k.points.get(j).copied().unwrap_or_default();
            let used = j < usize::from(k.len);
            let p = self.point_mut(j);
            let src = if used {
                src
            } else {
                ConstraintPoint::default()
            };
            // A body without a solver entry keeps its world lever arm as its anchor.
            let local_a = if k.a == NONE { src.core_a } else { src.local_a };
            let local_b = if k.b == NONE { src.core_b } else { src.local_b };
            p.local_a.set(l, local_a);
            p.local_b.set(l, local_b);
            p.adjusted.set(l, src.adjusted_separation);
            p.rn_a.set(l, src.rn_a);
            p.rn_b.set(l, src.rn_b);
            p.in_a.set(l, src.in_a);
            p.in_b.set(l, src.in_b);
            p.normal_mass.set(l, src.normal_mass);
            p.normal_impulse.set(l, src.normal_impulse);
            p.twist_arm.set(l, src.twist_arm);
            p.separation.set(l, src.separation);
            p.separation0.set(l, src.separation0);
            p.total_impulse.set(l, src.total_impulse);
            p.normal_speed0.set(l, src.normal_speed0);
            p.bounced.set(l, if src.bounced { 1.0 } else { 0.0 });
        }
    }

    /// Lane `l` as a scalar constraint (the inverse of [`Group::store_lane`]; the pool
    /// slots are taken from `contacts`).
    pub fn load_lane(&self, l: usize, contacts: &[Contact]) -> ContactConstraint {
        let (s0, s1, s2, s3) = (&self.s0.s, &self.s1.s, &self.s2.s, &self.s3.s);
        let contact = self.contact(l);
        let (slot_a, slot_b) = contacts
            .get(contact as usize)
            .map_or((NONE, NONE), |c| (c.a, c.b));
        let flags = self.s3.idx.get(l).copied().unwrap_or(0);
        let a = self.s0.idx.get(l).copied().unwrap_or(NONE);
        let b = self.s1.idx.get(l).copied().unwrap_or(NONE);
        let mut k = ContactConstraint {
            contact,
            slot_a,
            slot_b,
            a,
            b,
            inv_mass_a: f4(s0, INV_MASS_A).lane(l),
            inv_mass_b: f4(s0, INV_MASS_B).lane(l),
            normal: lane_v(s0, NORMAL, l),
            tangents: [lane_v(s0, T1, l), lane_v(s0, T2, l)],
            len: (flags & 0xff).min(4) as u8,
            rt_a: [lane_v(s1, RT_A0, l), lane_v(s1, RT_A1, l)],
            rt_b: [lane_v(s1, RT_B0, l), lane_v(s1, RT_B1, l)],
            it_a: [lane_v(s2, IT_A0, l), lane_v(s2, IT_A1, l)],
            it_b: [lane_v(s2, IT_B0, l), lane_v(s2, IT_B1, l)],
            tangent_mass: core::array::from_fn(|i| f4(s1, TANGENT_MASS + i).lane(l)),
            tangent_impulse: core::array::from_fn(|i| f4(s1, TANGENT_IMPULSE + i).lane(l)),
            ia_axes: core::array::from_fn(|i| lane_v(s3, IA_AXES + 3 * i, l)),
            ib_axes: core::array::from_fn(|i| lane_v(s3, IB_AXES + 3 * i, l)),
            axis_mass: core::array::from_fn(|i| f4(s2, AXIS_MASS + i).lane(l)),
            angular_impulse: core::array::from_fn(|i| f4(s2, ANGULAR_IMPULSE + i).lane(l)),
            friction: [f4(s0, MU_S).lane(l), f4(s0, MU_K).lane(l)],
            restitution: f4(s0, RESTITUTION).lane(l),
            rolling: f4(s0, ROLLING).lane(l),
            twist: f4(s0, TWIST).lane(l),
            softness: Softness {
                bias_rate: f4(s0, BIAS_RATE).lane(l),
                mass_scale: f4(s0, MASS_SCALE).lane(l),
                impulse_scale: f4(s0, IMPULSE_SCALE).lane(l),
            },
            radius_sum: f4(s1, RADIUS_SUM).lane(l),
            sticking: flags & STICKING != 0,
            established: flags & ESTABLISHED != 0,
            torque_free: flags & TORQUE_FREE != 0,
            ..ContactConstraint::default()
        };
        for j in 0..usize::from(k.len) {
            let p = self.point(j);
            let local_a = p.local_a.lane(l);
            let local_b = p.local_b.lane(l);
            if let Some(dst) = k.points.get_mut(j) {
                *dst = ConstraintPoint {
                    local_a,
                    local_b,
                    core_a: local_a,
                    core_b: local_b,
                    adjusted_separation: p.adjusted.lane(l),
                    rn_a: p.rn_a.lane(l),
                    rn_b: p.rn_b.lane(l),
                    in_a: p.in_a.lane(l),
                    in_b: p.in_b.lane(l),
                    normal_mass: p.normal_mass.lane(l),
                    normal_impulse: p.normal_impulse.lane(l),
                    twist_arm: p.twist_arm.lane(l),
                    separation0: p.separation0.lane(l),
                    separation: p.separation.lane(l),
                    total_impulse: p.total_impulse.lane(l),
                    normal_speed0: p.normal_speed0.lane(l),
                    bounced: p.bounced.lane(l) != 0.0,
                };
            }
        }
        k
    }
}

/// The colour of a contact between solver bodies `a` and `b` (indices into `bodies`,
/// [`NONE`] for none) that moves at least one of them, marking the colour on the moving
/// bodies; [`OVERFLOW`] when none is free (module docs).
pub(crate) fn colour(bodies: &mut [SolverBody], a: u32, b: u32) -> u32 {
    let moving =
        |bodies: &[SolverBody], i: u32| bodies.get(i as usize).is_some_and(|s| s.inv_mass > 0.0);
    let (ma, mb) = (moving(bodies, a), moving(bodies, b));
    let used = |bodies: &[SolverBody], i: u32, on: bool| {
        if on {
            bodies.get(i as usize).map_or(0, |s| s.colours)
        } else {
            0
        }
    };
    let taken = used(bodies, a, ma) | used(bodies, b, mb);
    let pick = if ma && mb {
        (0..DYNAMIC_COLORS as u32).find(|c| taken & (1 << c) == 0)
    } else {
        (0..COLORS as u32).rev().find(|c| taken & (1 << c) == 0)
    };
    let Some(c) = pick else {
        return OVERFLOW;
    };
    for (i, on) in [(a, ma), (b, mb)] {
        if on {
            if let Some(s) = bodies.get_mut(i as usize) {
                s.colours |= 1 << c;
            }
        }
    }
    c
}

/// Velocities of four solver bodies (zero for [`NONE`] lanes).
struct Bodies4 {
    v: V4,
    w: V4,
}

impl Bodies4 {
    /// Four bodies that stay still, the body A of a group without it (`MOVES_A` false in
    /// the kernels). The kernels with A form A's terms from zero velocities and add to
    /// them only products with A's zero inverse mass and inertia: `+0 − (±0)` is `+0`, so
    /// A's velocities stay `+0`, every term of A is a zero, and `y − 0` is `y`. Left out,
    /// the rows give the same numbers; only a result that is exactly zero can take the
    /// other sign.
    const STILL: Bodies4 = Bodies4 {
        v: V4::ZERO,
        w: V4::ZERO,
    };
}

/// What a lane without a solver body reads: at rest, identity rotation, infinite mass.
const AT_REST: SolverBody = SolverBody::ZERO;

/// The four solver bodies of `idx`, [`AT_REST`] for [`NONE`] (or any index out of range).
#[inline]
fn four<'b>(bodies: &'b [SolverBody], idx: &[u32; 4]) -> [&'b SolverBody; 4] {
    let at = |i: u32| bodies.get(i as usize).unwrap_or(&AT_REST);
    [at(idx[0]), at(idx[1]), at(idx[2]), at(idx[3])]
}

/// `f(body)` of four bodies as lanes.
#[inline]
fn lanes3(b: &[&SolverBody; 4], f: impl Fn(&SolverBody) -> Vec3) -> V4 {
    let [p, q, r, s] = [f(b[0]), f(b[1]), f(b[2]), f(b[3])];
    V4 {
        x: F4([p.x, q.x, r.x, s.x]),
        y: F4([p.y, q.y, r.y, s.y]),
        z: F4([p.z, q.z, r.z, s.z]),
    }
}

/// How four bodies' motion in the step moves their anchors along the contact normal
/// `n`: an anchor `l` (body axes) of a body displaced by `Δp` and turned to `R` moved
/// `n·(Δp + R l) = n·Δp + (Rᵀ n)·l` along it. One `Rᵀ n` per body and group, then one
/// dot product per point, instead of a rotation per point.
struct NormalReach {
    /// `n·Δp` (m).
    along: F4,
    /// `Rᵀ n`: the normal in the body's axes.
    local: V4,
}

impl NormalReach {
    #[inline(always)]
    fn gather(b: &[&SolverBody; 4], n: &V4) -> NormalReach {
        NormalReach {
            along: n.dot(&lanes3(b, |b| b.dp)),
            local: V4 {
                x: n.dot(&lanes3(b, |b| b.rot.x)),
                y: n.dot(&lanes3(b, |b| b.rot.y)),
                z: n.dot(&lanes3(b, |b| b.rot.z)),
            },
        }
    }
}

impl Bodies4 {
    /// Velocities of four solver bodies.
    #[inline]
    fn gather(bodies: &[SolverBody], idx: &[u32; 4]) -> Bodies4 {
        Bodies4::of(&four(bodies, idx))
    }

    /// Velocities of the four solver bodies `b`.
    #[inline]
    fn of(b: &[&SolverBody; 4]) -> Bodies4 {
        Bodies4 {
            v: lanes3(b, |b| b.v),
            w: lanes3(b, |b| b.w),
        }
    }

    fn scatter(&self, bodies: &mut [SolverBody], idx: &[u32; 4], active: [bool; 4]) {
        for (l, (i, on)) in idx.iter().zip(active).enumerate() {
            if !on {
                continue;
            }
            if let Some(b) = bodies.get_mut(*i as usize) {
                b.v = self.v.lane(l);
                b.w = self.w.lane(l);
            }
        }
    }
}

/// The lanes solved in each pass over a group (up to four masks) and how many passes.
type Passes = ([[bool; 4]; 4], usize);

/// How an overflow group is cut into passes, from its active lanes and the solver indices
/// of its bodies A and B ([`overflow_runs`]; the tests' lane-by-lane reference).
type Runs = fn([bool; 4], [u32; 4], [u32; 4]) -> Passes;

/// The passes over an overflow group (whose lanes may share bodies): its active lanes in
/// lane order, in runs of consecutive lanes that share no solver body. The lanes of a run
/// are independent (none reads a velocity another writes), so solving them at once is the
/// same arithmetic, lane for lane, as solving them one after another: the same bits as
/// one lane at a time, in fewer passes. Out of line: a step has a few overflow groups.
///
/// Takes the group's lanes (`active`, the solver indices of body A and body B) by value:
/// a group passed by reference was kept in memory through the solve loop (its four slot
/// references reloaded, one load stalled on the stores before it), and the loop ran 4 %
/// slower for it (`spheres`, fewer instructions).
#[inline(never)]
fn overflow_runs(active: [bool; 4], ia: [u32; 4], ib: [u32; 4]) -> Passes {
    let mut out = [[false; 4]; 4];
    let mut n = 0usize;
    // The solver bodies the current run moves ([`NONE`]: a static or sleeping side).
    let mut moved = [NONE; 8];
    let mut used = 0usize;
    for l in 0..4 {
        if !active.get(l).copied().unwrap_or(false) {
            continue;
        }
        let sides = [ia.get(l).copied(), ib.get(l).copied()].map(|i| i.unwrap_or(NONE));
        let shares = moved
            .iter()
            .take(used)
            .any(|m| sides.iter().any(|s| *s != NONE && s == m));
        if n == 0 || shares {
            n += 1;
            used = 0;
        }
        for side in sides {
            if let Some(m) = moved.get_mut(used) {
                *m = side;
                used += 1;
            }
        }
        if let Some(x) = out.get_mut(n - 1).and_then(|run| run.get_mut(l)) {
            *x = true;
        }
    }
    (out, n)
}

/// Apply the accumulated impulses of every group (start of each sub-step).
pub(crate) fn warm_start<const C: usize>(store: &mut WideStore<C>, bodies: &mut [SolverBody]) {
    warm_start_with(store, bodies, overflow_runs, true);
}

/// [`warm_start`] with the passes over an overflow group given by `runs`, and with the
/// kernels without body A for groups where it stays still when `still` (the tests'
/// reference runs without).
#[inline(always)]
fn warm_start_with<const C: usize>(
    store: &mut WideStore<C>,
    bodies: &mut [SolverBody],
    runs: Runs,
    still: bool,
) {
    for g in 0..store.groups as usize {
        let overflow = g as u32 >= store.overflow_from;
        let Some(mut group) = store.group(g) else {
            break;
        };
        let (masks, n) = passes(&group, overflow, runs);
        let rows = group.point_rows();
        let still_a = still && group.still_a();
        for mask in masks.iter().take(n) {
            // As in `solve`: full groups of a colour get their own copies of the kernel,
            // with one, two or four point rows, and without body A where it stays still.
            let g = &mut group;
            match (!overflow && *mask == ALL_LANES, rows, still_a) {
                (true, 1, false) => warm_start_group::<1, true>(g, bodies, ALL_LANES),
                (true, 2, false) => warm_start_group::<2, true>(g, bodies, ALL_LANES),
                (true, _, false) => warm_start_group::<4, true>(g, bodies, ALL_LANES),
                (true, 1, true) => warm_start_group::<1, false>(g, bodies, ALL_LANES),
                (true, 2, true) => warm_start_group::<2, false>(g, bodies, ALL_LANES),
                (true, _, true) => warm_start_group::<4, false>(g, bodies, ALL_LANES),
                _ => warm_start_group::<4, true>(g, bodies, *mask),
            }
        }
    }
}

/// The warm start of one group in the lanes `mask`, its first `ROWS` point rows; without
/// `MOVES_A`, a group whose body A stays still in every lane ([`Group::still_a`]).
#[inline(always)]
fn warm_start_group<const ROWS: usize, const MOVES_A: bool>(
    group: &mut Group<'_>,
    bodies: &mut [SolverBody],
    mask: [bool; 4],
) {
    let ia = group.s0.idx;
    let ib = group.s1.idx;
    let mut a = if MOVES_A {
        Bodies4::gather(bodies, &ia)
    } else {
        Bodies4::STILL
    };
    let mut b = Bodies4::gather(bodies, &ib);
    let keep = |x: F4| F4::ZERO.select_where(mask, x);
    let shared = Shared::load(&group.s0.s);
    // The points share the normal: their impulses move the linear velocities once, as
    // their sum (as in `solve_group`).
    let mut pushed = F4::ZERO;
    for j in 0..ROWS {
        let p = &group.point(j);
        let lambda = keep(p.normal_impulse);
        pushed += lambda;
        if MOVES_A {
            a.w.sub_scaled(&p.in_a, lambda);
        }
        b.w.add_scaled(&p.in_b, lambda);
    }
    let (q1, q2, q3) = (&group.s1.s, &group.s2.s, &group.s3.s);
    let l0 = keep(f4(q1, TANGENT_IMPULSE));
    let l1 = keep(f4(q1, TANGENT_IMPULSE + 1));
    // The normal's linear push on its own here: merged with the tangents' (as in the
    // solve), the warm start took the Cortex-M4F firmware's solve 3.3 KiB more stack.
    let jn = shared.n.scale(pushed);
    if MOVES_A {
        a.v.sub_scaled(&jn, shared.ma);
    }
    b.v.add_scaled(&jn, shared.mb);
    push_tangent::<MOVES_A>(&mut a, &mut b, &shared, q2, [l0, l1]);
    for i in 0..3 {
        let lambda = keep(f4(q2, ANGULAR_IMPULSE + i));
        if lambda.0 != [0.0; 4] {
            if MOVES_A {
                a.w.sub_scaled(&v4(q3, IA_AXES + 3 * i), lambda);
            }
            b.w.add_scaled(&v4(q3, IB_AXES + 3 * i), lambda);
        }
    }
    if MOVES_A {
        a.scatter(bodies, &ia, mask);
    }
    b.scatter(bodies, &ib, mask);
}

/// The per-contact values of quarter 0 the rows read, copied once per group visit.
struct Shared {
    n: V4,
    t1: V4,
    t2: V4,
    ma: F4,
    mb: F4,
    bias_rate: F4,
    mass_scale: F4,
    impulse_scale: F4,
    mu_s: F4,
    mu_k: F4,
    rolling: F4,
    twist: F4,
}

impl Shared {
    #[inline]
    fn load(q0: &[F4; QUARTER]) -> Shared {
        Shared {
            n: v4(q0, NORMAL),
            t1: v4(q0, T1),
            t2: v4(q0, T2),
            ma: f4(q0, INV_MASS_A),
            mb: f4(q0, INV_MASS_B),
            bias_rate: f4(q0, BIAS_RATE),
            mass_scale: f4(q0, MASS_SCALE),
            impulse_scale: f4(q0, IMPULSE_SCALE),
            mu_s: f4(q0, MU_S),
            mu_k: f4(q0, MU_K),
            rolling: f4(q0, ROLLING),
            twist: f4(q0, TWIST),
        }
    }
}

/// What a group's normal rows summed, per lane: the new impulses (`total`), the same
/// times each point's twist arm (`levers`), and the impulse they added (`pushed`, not
/// yet applied to the linear velocities).
struct Sums {
    total: F4,
    levers: F4,
    pushed: F4,
}

/// Apply `(λ₁, λ₂)` along the tangents at the friction centres and `λ_n` along the
/// normal to the linear velocities only (the normal rows moved the angular ones): one
/// push of `t₁ λ₁ + t₂ λ₂ + n λ_n`.
#[inline]
fn push_tangent_and_normal<const MOVES_A: bool>(
    a: &mut Bodies4,
    b: &mut Bodies4,
    sh: &Shared,
    q2: &[F4; QUARTER],
    l: [F4; 2],
    normal: F4,
) {
    let j = sh
        .t1
        .scale(l[0])
        .add(&sh.t2.scale(l[1]))
        .add(&sh.n.scale(normal));
    push_at_patch::<MOVES_A>(a, b, sh, q2, &j, l);
}

/// Apply `(λ₁, λ₂)` along the tangents at the friction centres.
#[inline]
fn push_tangent<const MOVES_A: bool>(
    a: &mut Bodies4,
    b: &mut Bodies4,
    sh: &Shared,
    q2: &[F4; QUARTER],
    l: [F4; 2],
) {
    let j = sh.t1.scale(l[0]).add(&sh.t2.scale(l[1]));
    push_at_patch::<MOVES_A>(a, b, sh, q2, &j, l);
}

/// Apply the linear impulse `j` to both bodies' velocities and `(λ₁, λ₂)` along the
/// tangents to their angular velocities (to B's alone without `MOVES_A`).
#[inline(always)]
fn push_at_patch<const MOVES_A: bool>(
    a: &mut Bodies4,
    b: &mut Bodies4,
    sh: &Shared,
    q2: &[F4; QUARTER],
    j: &V4,
    l: [F4; 2],
) {
    if MOVES_A {
        a.v.sub_scaled(j, sh.ma);
        a.w.sub_scaled(&v4(q2, IT_A0), l[0]);
        a.w.sub_scaled(&v4(q2, IT_A1), l[1]);
    }
    b.v.add_scaled(j, sh.mb);
    b.w.add_scaled(&v4(q2, IT_B0), l[0]);
    b.w.add_scaled(&v4(q2, IT_B1), l[1]);
}

/// An accumulated impulse (N·s) as a contact keeps it: within the
/// [`MAX_STATE_FORCE`](super::snapshot::MAX_STATE_FORCE) bound a snapshot accepts, and zero
/// when not finite. Only an ill-conditioned pair (kilometre-long slivers of 1e8 kg) comes
/// near the bound; the next warm start bounds the impulse far tighter anyway.
fn stored(x: f32) -> f32 {
    let max = super::snapshot::MAX_STATE_FORCE;
    if x.is_finite() {
        x.clamp(-max, max)
    } else {
        0.0
    }
}

/// What one iteration over the groups does ([`solve`]).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Pass {
    /// Soft normal rows with push-out (the solve iterations), or rigid rows without
    /// (relax).
    pub use_bias: bool,
    /// The bodies moved since the points' separations were last measured (the step's
    /// first pass, and the first after each position update): measure them again. Only
    /// the position update moves bodies, so the passes between two updates measure the
    /// same separations; all but the first keep them as they are.
    pub moved: bool,
    /// The last relax iteration of the step, where stick/slip changes.
    pub last: bool,
}

/// One iteration over every group: normal rows, the friction patch, twist and rolling,
/// as `pass` says.
pub(crate) fn solve<const C: usize>(
    store: &mut WideStore<C>,
    bodies: &mut [SolverBody],
    cfg: &WorldConfig,
    inv_h: f32,
    pass: Pass,
) {
    solve_with(store, bodies, (cfg, inv_h, pass), overflow_runs, true);
}

/// [`solve`] with the passes over an overflow group given by `runs`, and with the kernels
/// without body A where it stays still when `still` (as [`warm_start_with`]).
#[inline(always)]
fn solve_with<const C: usize>(
    store: &mut WideStore<C>,
    bodies: &mut [SolverBody],
    a: (&WorldConfig, f32, Pass),
    runs: Runs,
    still: bool,
) {
    // The last pass notes whether projection has a point to look at (its threshold).
    let deep = -super::projection::DEEP_SLOPS * a.0.slop;
    let mut any_deep = false;
    for g in 0..store.groups as usize {
        let overflow = g as u32 >= store.overflow_from;
        let Some(mut group) = store.group(g) else {
            break;
        };
        let (masks, n) = passes(&group, overflow, runs);
        let rows = group.point_rows();
        let bouncy = group.bouncy();
        let still_a = still && group.still_a();
        // A soft pass leaves the friction rows of torque-free lanes to the relax passes
        // (`contact_solver::torque_free`).
        let skips = a.2.use_bias && group.has_torque_free();
        for mask in masks.iter().take(n) {
            // A full group of a colour (every coloured group but the last) gets its own
            // copy of the kernel, where the lane selects fold away, with one, two or four
            // point rows (module docs), with or without the restitution records; the
            // point loop unrolls in each. Overflow runs take the masked kernel, whatever
            // their lanes.
            let (g, bodies) = (&mut group, &mut *bodies);
            let full = !overflow && *mask == ALL_LANES;
            if skips {
                skip_torque_free(g, bodies, a, *mask, (full, rows), bouncy);
                continue;
            }
            let all = (ALL_LANES, ALL_LANES, 4, bouncy);
            // One arm per kernel: each arm is an inlined copy (kilobytes of flash on a
            // Cortex-M), so restitution is a flag, not a copy.
            match (full, rows, still_a) {
                (true, 1, false) => solve_group::<1, true, true>(g, bodies, a, all),
                (true, 2, false) => solve_group::<2, true, true>(g, bodies, a, all),
                (true, _, false) => solve_group::<4, true, true>(g, bodies, a, all),
                (true, 1, true) => solve_group::<1, true, false>(g, bodies, a, all),
                (true, 2, true) => solve_group::<2, true, false>(g, bodies, a, all),
                (true, _, true) => solve_group::<4, true, false>(g, bodies, a, all),
                _ => solve_group::<4, true, true>(g, bodies, a, (*mask, *mask, rows, true)),
            }
        }
        if a.2.last && !any_deep {
            any_deep = (0..4).any(|l| group.contact(l) != NONE && group.deeper_than(l, deep));
        }
    }
    if a.2.last {
        store.deep = Some(any_deep);
    }
}

/// A soft pass over the lanes `mask` of a group with torque-free lanes: their friction
/// rows are left out. A full group of one-point rows (`full_single`) whose lanes are all
/// torque-free (balls) takes kernels without friction rows; the rest (an overflow run, a
/// group that mixes them with other contacts) the masked kernel with the friction rows of
/// the others.
#[inline(always)]
fn skip_torque_free(
    g: &mut Group<'_>,
    bodies: &mut [SolverBody],
    a: (&WorldConfig, f32, Pass),
    mask: [bool; 4],
    (full, rows): (bool, usize),
    bouncy: bool,
) {
    let free = g.torque_free();
    let rubs: [bool; 4] = core::array::from_fn(|l| {
        mask.get(l).copied().unwrap_or(false) && !free.get(l).copied().unwrap_or(false)
    });
    let none = (ALL_LANES, NO_LANES, 1, bouncy);
    if full && rows == 1 && rubs == NO_LANES {
        solve_group::<1, false, true>(g, bodies, a, none);
    } else {
        solve_group::<4, true, true>(g, bodies, a, (mask, rubs, rows, true));
    }
}

/// The passes over one group: all active lanes of a group of a colour, `runs` of an
/// overflow group.
#[inline(always)]
fn passes(group: &Group<'_>, overflow: bool, runs: Runs) -> Passes {
    let active = group.active();
    if !overflow {
        return ([active, [false; 4], [false; 4], [false; 4]], 1);
    }
    runs(active, group.s0.idx, group.s1.idx)
}

/// [`overflow_runs`] for the solver's tests.
#[cfg(test)]
pub(crate) fn overflow_runs_for_tests(group: &Group<'_>) -> Passes {
    overflow_runs(group.active(), group.s0.idx, group.s1.idx)
}

/// One lane at a time: the overflow passes before [`overflow_runs`] (the tests'
/// reference).
#[cfg(test)]
fn one_lane_at_a_time(active: [bool; 4], _: [u32; 4], _: [u32; 4]) -> Passes {
    let mut out = [[false; 4]; 4];
    let mut n = 0;
    for (l, on) in active.iter().enumerate() {
        if *on {
            out[n][l] = true;
            n += 1;
        }
    }
    (out, n)
}

/// The tests' references for [`warm_start`] then one [`solve`] pass.
#[cfg(test)]
#[derive(Clone, Copy, Debug)]
pub(crate) enum Reference {
    /// Every overflow lane on its own, in lane order.
    LaneByLane,
    /// The kernels of two moving bodies in every group, body A still or not.
    AMoving,
}

/// [`warm_start`] then one [`solve`] pass the way `reference` says.
#[cfg(test)]
pub(crate) fn warm_start_and_solve_as<const C: usize>(
    reference: Reference,
    store: &mut WideStore<C>,
    bodies: &mut [SolverBody],
    cfg: &WorldConfig,
    inv_h: f32,
    pass: Pass,
) {
    let (runs, still): (Runs, bool) = match reference {
        Reference::LaneByLane => (one_lane_at_a_time, true),
        Reference::AMoving => (overflow_runs, false),
    };
    warm_start_with(store, bodies, runs, still);
    solve_with(store, bodies, (cfg, inv_h, pass), runs, still);
}

/// [`Group::still_a`] for the solver's tests.
#[cfg(test)]
pub(crate) fn still_a_for_tests(group: &Group<'_>) -> bool {
    group.still_a()
}

/// One pass over one group (`solve`'s arguments in `(cfg, inv_h, pass)`) in the lanes
/// `mask`: the first `rows` of its `ROWS` point rows (a full group's kernel has `rows =
/// ROWS`; the masked kernel's `ROWS` is 4 and `rows` the group's own count, past which no
/// lane holds a point), with `bouncy` the records the restitution pass reads (the closing
/// speed at impact and the impulse so far; a group without restitution in any lane skips
/// them, as that pass never reads its lanes; a flag and not a copy of the kernel, tested
/// once after the rows), and with `RUB` the friction, twist and
/// rolling rows of the lanes `rubs`. Without `MOVES_A`, for a group whose body A stays
/// still in every lane ([`Group::still_a`]): its velocities are zero and stay zero, and
/// the kernel leaves out every term of A (see [`Bodies4::STILL`] for why the bits are
/// the same).
#[inline(always)]
fn solve_group<const ROWS: usize, const RUB: bool, const MOVES_A: bool>(
    group: &mut Group<'_>,
    bodies: &mut [SolverBody],
    (cfg, inv_h, pass): (&WorldConfig, f32, Pass),
    (mask, rubs, rows, bouncy): ([bool; 4], [bool; 4], usize, bool),
) {
    let rows = rows.min(ROWS);
    let ia = group.s0.idx;
    let ib = group.s1.idx;
    let sh = Shared::load(&group.s0.s);
    let n = sh.n;
    let body_a = if MOVES_A {
        four(bodies, &ia)
    } else {
        [&AT_REST; 4]
    };
    let body_b = four(bodies, &ib);
    // The separations first: they depend on the positions only, and the velocity rows
    // below then keep fewer values live. Unmoved bodies keep the last pass's.
    if pass.moved {
        let reach_b = NormalReach::gather(&body_b, &n);
        // A body that stays still: `Δp_a = 0`, `R_a = 1`, so `R_aᵀ n = n`.
        let (moved, local_a) = if MOVES_A {
            let reach_a = NormalReach::gather(&body_a, &n);
            (reach_b.along - reach_a.along, reach_a.local)
        } else {
            (reach_b.along, n)
        };
        for j in 0..rows {
            let p = group.point_mut(j);
            // s = adjusted + n·((Δp_b + R_b l_b) − (Δp_a + R_a l_a))
            //   = adjusted + (n·Δp_b − n·Δp_a) + ((R_bᵀ n)·l_b − (R_aᵀ n)·l_a)
            let turned = reach_b.local.dot(&p.local_b) - local_a.dot(&p.local_a);
            let s = p.adjusted + (moved + turned);
            p.separation = p.separation.select_where(mask, s);
        }
    }
    let mut a = if MOVES_A {
        Bodies4::of(&body_a)
    } else {
        Bodies4::STILL
    };
    let mut b = Bodies4::of(&body_b);
    let (one, zero) = (F4::splat(1.0), F4::ZERO);
    let (soft_bias, soft_mass, soft_impulse) = if pass.use_bias {
        (
            sh.mass_scale * sh.bias_rate,
            sh.mass_scale,
            sh.impulse_scale,
        )
    } else {
        (zero, one, zero)
    };
    let max_push = F4::splat(-cfg.max_push_speed);
    let inv_h = F4::splat(inv_h);
    let mut total = zero;
    let mut levers = zero;
    // The points share the normal, so the bodies' linear velocities enter every row only
    // through `n·(v_b − v_a)`: one number per lane, formed once and moved by each row's
    // impulse `δ` by `δ (m_a + m_b)` (`n` is unit). The velocities themselves take the
    // rows' summed impulse along `n` after the last row: per row, two products and sums
    // instead of twelve, and six fewer values live through the loop.
    let mut linear = if MOVES_A {
        n.dot(&b.v.sub(&a.v))
    } else {
        n.dot(&b.v)
    };
    let mass_sum = sh.ma + sh.mb;
    let mut pushed = zero;
    // Each row's closing speed and added impulse, for the restitution records.
    let mut records = [(zero, zero); ROWS];
    for j in 0..rows {
        let p = group.point_mut(j);
        // This pass's separation in the lanes of `mask` (the others' rows are dropped).
        let s = p.separation;
        // Speculative (s > 0): rigid, close the gap; else soft push-out (or none).
        let soft_push = (soft_bias * s).max(max_push);
        let bias = s.gt_select(zero, s * inv_h, soft_push);
        let mass_scale = s.gt_select(zero, one, soft_mass);
        let impulse_scale = s.gt_select(zero, zero, soft_impulse);
        let vn = if MOVES_A {
            linear + b.w.dot(&p.rn_b) - a.w.dot(&p.rn_a)
        } else {
            linear + b.w.dot(&p.rn_b)
        };
        let lambda = -(p.normal_mass * (mass_scale * vn + bias)) - impulse_scale * p.normal_impulse;
        // Lanes outside `mask` keep their impulse (and are not written back).
        let old = p.normal_impulse;
        let new = old.select_where(mask, (old + lambda).max(zero));
        let delta = new - old;
        linear += delta * mass_sum;
        pushed += delta;
        if MOVES_A {
            a.w.sub_scaled(&p.in_a, delta);
        }
        b.w.add_scaled(&p.in_b, delta);
        total += new;
        levers += new * p.twist_arm;
        p.normal_impulse = new;
        if let Some(r) = records.get_mut(j) {
            *r = (vn, delta);
        }
    }
    if bouncy {
        for (j, &(vn, delta)) in records.iter().enumerate().take(rows) {
            // The speed at impact, for restitution: the closing speed the point had when
            // it first pushed this step (it includes the gravity of the sub-steps
            // before). Per lane: if (in the mask) the point had not pushed before (total
            // 0), pushes now (delta > 0) and closes faster than recorded (vn < speed0),
            // record vn. Each point's record reads its own row's numbers only, so it is
            // kept after the rows, out of their loop.
            let p = group.point_mut(j);
            let s0 = p.normal_speed0;
            let faster = s0.gt_select(vn, vn, s0);
            let pushes = delta.gt_select(zero, faster, s0);
            let first = p.total_impulse.eq_select(zero, pushes, s0);
            p.normal_speed0 = s0.select_where(mask, first);
            p.total_impulse = p.total_impulse.select_where(mask, p.total_impulse + delta);
        }
    }
    if RUB {
        // The rows' linear push goes with the friction's (see `solve_patch`).
        let sums = Sums {
            total,
            levers,
            pushed,
        };
        solve_patch::<MOVES_A>(group, &sh, &mut a, &mut b, cfg, sums, pass.last, rows, rubs);
        solve_rolling::<MOVES_A>(group, &sh, &mut a, &mut b, total, rubs);
    } else {
        let jn = n.scale(pushed);
        if MOVES_A {
            a.v.sub_scaled(&jn, sh.ma);
        }
        b.v.add_scaled(&jn, sh.mb);
    }
    if MOVES_A {
        a.scatter(bodies, &ia, mask);
    }
    b.scatter(bodies, &ib, mask);
}

/// Tangent speeds at the friction centres (B's terms alone without `MOVES_A`).
#[inline]
fn tangent_speeds<const MOVES_A: bool>(
    a: &Bodies4,
    b: &Bodies4,
    sh: &Shared,
    q1: &[F4; QUARTER],
) -> [F4; 2] {
    if !MOVES_A {
        return [
            sh.t1.dot(&b.v) + b.w.dot(&v4(q1, RT_B0)),
            sh.t2.dot(&b.v) + b.w.dot(&v4(q1, RT_B1)),
        ];
    }
    let dv = b.v.sub(&a.v);
    [
        sh.t1.dot(&dv) + b.w.dot(&v4(q1, RT_B0)) - a.w.dot(&v4(q1, RT_A0)),
        sh.t2.dot(&dv) + b.w.dot(&v4(q1, RT_B1)) - a.w.dot(&v4(q1, RT_A1)),
    ]
}

/// Lane-wise `v` shortened to length at most `radius` (zero where the radius is not
/// positive); as `contact_solver::clip_to_disc`, lane for lane: `r / |v|` is formed in
/// every lane and used only where `|v|² > r²` (so `|v| > 0`).
///
/// With `skip`, the square roots and the division are formed only when some lane with
/// a positive radius needs them: the same bits either way. Patches of several points
/// (boxes at rest) stick in all four lanes most of the time and gain (pyramid20: 4 %
/// less time per step); single points (spheres) slide often enough that the branch
/// costs more than it saves (spheres: 2 % more), and rolling rows clip as often.
#[inline]
fn clip_to_disc(v: [F4; 2], radius: F4, skip: bool) -> [F4; 2] {
    let l2 = v[0] * v[0] + v[1] * v[1];
    let r2 = radius * radius;
    let zero = F4::ZERO;
    let clipping = l2.gt_select(r2, radius, zero);
    let out = if !skip || clipping.0.iter().any(|&r| r > 0.0) {
        let s = radius.div(l2.sqrt());
        [
            l2.gt_select(r2, v[0] * s, v[0]),
            l2.gt_select(r2, v[1] * s, v[1]),
        ]
    } else {
        // No lane with a positive radius has |v|² > r²: each such lane keeps v (as the
        // selects above would), and the others become zero below.
        v
    };
    // A NaN radius compares false: zero, as the scalar row.
    [
        radius.gt_select(zero, out[0], zero),
        radius.gt_select(zero, out[1], zero),
    ]
}

/// Which lanes [`clip_to_disc`] shortens (a non-zero `v` with no positive radius counts).
fn clipped_lanes(v: [F4; 2], radius: F4) -> [bool; 4] {
    let l2 = v[0] * v[0] + v[1] * v[1];
    let r2 = radius * radius;
    core::array::from_fn(|l| {
        let (x, y, r) = (v[0].lane(l), v[1].lane(l), radius.lane(l));
        if r.is_nan() || r <= 0.0 {
            x != 0.0 || y != 0.0
        } else {
            l2.lane(l) > r2.lane(l)
        }
    })
}

#[allow(clippy::too_many_arguments)]
#[inline(always)]
fn solve_patch<const MOVES_A: bool>(
    group: &mut Group<'_>,
    sh: &Shared,
    a: &mut Bodies4,
    b: &mut Bodies4,
    cfg: &WorldConfig,
    Sums {
        total,
        levers,
        pushed,
    }: Sums,
    last: bool,
    rows: usize,
    mask: [bool; 4],
) {
    let flags = group.s3.idx;
    let (q1, q2, q3) = (&mut group.s1.s, &mut group.s2.s, &group.s3.s);
    let sticking: [bool; 4] =
        core::array::from_fn(|l| flags.get(l).is_some_and(|f| f & STICKING != 0));
    let mu = sh.mu_k.select_where(sticking, sh.mu_s);
    let v = tangent_speeds::<MOVES_A>(a, b, sh, q1);
    let (mxx, mxy, myy) = (
        f4(q1, TANGENT_MASS),
        f4(q1, TANGENT_MASS + 1),
        f4(q1, TANGENT_MASS + 2),
    );
    let old = [f4(q1, TANGENT_IMPULSE), f4(q1, TANGENT_IMPULSE + 1)];
    let wanted = [
        old[0] - (mxx * v[0] + mxy * v[1]),
        old[1] - (mxy * v[0] + myy * v[1]),
    ];
    let radius = mu * total;
    let clipped_new = clip_to_disc(wanted, radius, rows > 1);
    let mut new = [
        old[0].select_where(mask, clipped_new[0]),
        old[1].select_where(mask, clipped_new[1]),
    ];
    // The tangent speeds above are those before the normal rows' linear push: it is
    // along `n`, orthogonal to both tangents, so it does not change them. It is applied
    // here, with the friction's, in one push of the linear velocities.
    let dl = [new[0] - old[0], new[1] - old[1]];
    push_tangent_and_normal::<MOVES_A>(a, b, sh, q2, dl, pushed);
    let mut flags_out = flags;
    if last {
        let after = tangent_speeds::<MOVES_A>(a, b, sh, q1);
        let stick2 = cfg.stick_speed * cfg.stick_speed;
        let clipped = clipped_lanes(wanted, radius);
        let kinetic = clip_to_disc(new, sh.mu_k * total, rows > 1);
        let mut fix = [F4::ZERO; 2];
        for l in 0..4 {
            if !mask.get(l).copied().unwrap_or(false) {
                continue;
            }
            let slip2 = after[0].lane(l) * after[0].lane(l) + after[1].lane(l) * after[1].lane(l);
            let f = flags.get(l).copied().unwrap_or(0);
            let (st, est) = (f & STICKING != 0, f & ESTABLISHED != 0);
            let was_clipped = clipped.get(l).copied().unwrap_or(false);
            if st && est && was_clipped && slip2 >= stick2 {
                // The static cone gave way: slide, at the kinetic cone from now on.
                if let Some(x) = flags_out.get_mut(l) {
                    *x &= !STICKING;
                }
                fix[0].set(l, kinetic[0].lane(l) - new[0].lane(l));
                fix[1].set(l, kinetic[1].lane(l) - new[1].lane(l));
                new[0].set(l, kinetic[0].lane(l));
                new[1].set(l, kinetic[1].lane(l));
            } else if !st && slip2 < stick2 {
                if let Some(x) = flags_out.get_mut(l) {
                    *x |= STICKING;
                }
            }
        }
        push_tangent::<MOVES_A>(a, b, sh, q2, fix);
    }
    if let Some(x) = q1.get_mut(TANGENT_IMPULSE) {
        *x = new[0];
    }
    if let Some(y) = q1.get_mut(TANGENT_IMPULSE + 1) {
        *y = new[1];
    }
    // Twist about the normal at the centre: the points' spread, or a single point's
    // twist friction.
    let sticking: [bool; 4] =
        core::array::from_fn(|l| flags_out.get(l).is_some_and(|f| f & STICKING != 0));
    let mu = sh.mu_k.select_where(sticking, sh.mu_s);
    let limit = mu * levers + sh.twist * total;
    let old = f4(q2, ANGULAR_IMPULSE + 2);
    let dw = if MOVES_A { b.w.sub(&a.w) } else { b.w };
    let wanted = old - f4(q2, AXIS_MASS + 2) * dw.dot(&sh.n);
    let new_twist = wanted.clamp(-limit, limit);
    // Lanes without a limit keep their impulse (as the scalar row skips them).
    let new_twist = old.select_where(mask, limit.gt_select(F4::ZERO, new_twist, old));
    let delta = new_twist - old;
    if MOVES_A {
        a.w.sub_scaled(&v4(q3, IA_AXES + 6), delta);
    }
    b.w.add_scaled(&v4(q3, IB_AXES + 6), delta);
    if let Some(x) = q2.get_mut(ANGULAR_IMPULSE + 2) {
        *x = new_twist;
    }
    group.s3.idx = flags_out;
}

#[inline(always)]
fn solve_rolling<const MOVES_A: bool>(
    group: &mut Group<'_>,
    sh: &Shared,
    a: &mut Bodies4,
    b: &mut Bodies4,
    total: F4,
    mask: [bool; 4],
) {
    let on: [bool; 4] =
        core::array::from_fn(|l| mask.get(l).copied().unwrap_or(false) && sh.rolling.lane(l) > 0.0);
    if !on.iter().any(|x| *x) {
        return;
    }
    let (q2, q3) = (&mut group.s2.s, &group.s3.s);
    let dw = if MOVES_A { b.w.sub(&a.w) } else { b.w };
    let old = [f4(q2, ANGULAR_IMPULSE), f4(q2, ANGULAR_IMPULSE + 1)];
    let wanted = [
        old[0] - f4(q2, AXIS_MASS) * dw.dot(&sh.t1),
        old[1] - f4(q2, AXIS_MASS + 1) * dw.dot(&sh.t2),
    ];
    let clip = clip_to_disc(wanted, sh.rolling * total, false);
    let new = [
        old[0].select_where(on, clip[0]),
        old[1].select_where(on, clip[1]),
    ];
    for i in 0..2 {
        let d = new.get(i).copied().unwrap_or_default() - old.get(i).copied().unwrap_or_default();
        if MOVES_A {
            a.w.sub_scaled(&v4(q3, IA_AXES + 3 * i), d);
        }
        b.w.add_scaled(&v4(q3, IB_AXES + 3 * i), d);
        if let Some(x) = q2.get_mut(ANGULAR_IMPULSE + i) {
            *x = new.get(i).copied().unwrap_or_default();
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::dynamics::snapshot::MAX_STATE_FORCE;

    /// Finding `fuzz/findings/mesh/impulse-past-the-snapshot-bound-487019bf` (replayed by
    /// CI): two 6.6e8 kg compounds with kilometre-long sliver parts ended a step with a
    /// twist impulse of −3.8e30 N·s, past the 1e30 a snapshot holds, and restore refused
    /// the world's own snapshot. Impulses are now stored within the bound, and a
    /// non-finite one as zero; ordinary values pass bit for bit.
    #[test]
    fn stored_impulses_stay_within_what_a_snapshot_holds() {
        assert_eq!(stored(-3.830862e30), -MAX_STATE_FORCE);
        assert_eq!(stored(f32::MAX), MAX_STATE_FORCE);
        assert_eq!(stored(f32::NAN), 0.0);
        assert_eq!(stored(f32::NEG_INFINITY), 0.0);
        for x in [0.0, -0.0, 1.0e-40, 12.5, -7.25e29, MAX_STATE_FORCE] {
            assert_eq!(stored(x).to_bits(), x.to_bits());
        }
    }

    /// An overflow group's runs: every active lane exactly once, in lane order, no two
    /// lanes of a run sharing a solver body ([`NONE`] shares nothing), and a new run only
    /// where the next lane shares a body with the run so far (brute force over random
    /// groups).
    #[test]
    fn overflow_runs_are_the_longest_runs_without_a_shared_body() {
        let mut rng = crate::rng::SplitMix64::new(41);
        let mut store = WideStore::<8>::new();
        for _ in 0..2000 {
            assert!(store.reset(1));
            let group = store.group(0).unwrap();
            let pick = |rng: &mut crate::rng::SplitMix64| match rng.next_u64() % 6 {
                0 => NONE,
                k => k as u32,
            };
            for l in 0..4 {
                group.s0.idx[l] = pick(&mut rng);
                group.s1.idx[l] = pick(&mut rng);
                group.s2.idx[l] = if rng.next_u64().is_multiple_of(5) {
                    NONE
                } else {
                    l as u32
                };
            }
            let (runs, n) = overflow_runs_for_tests(&group);
            let bodies = |l: usize| [group.s0.idx[l], group.s1.idx[l]];
            let shares = |x: usize, y: usize| {
                bodies(x)
                    .iter()
                    .any(|a| *a != NONE && bodies(y).contains(a))
            };
            let order: std::vec::Vec<(usize, usize)> = (0..n)
                .flat_map(|r| (0..4).filter(move |&l| runs[r][l]).map(move |l| (r, l)))
                .collect();
            let active: std::vec::Vec<usize> =
                (0..4).filter(|&l| group.contact(l) != NONE).collect();
            assert_eq!(
                order.iter().map(|e| e.1).collect::<std::vec::Vec<_>>(),
                active
            );
            for (i, &(r, l)) in order.iter().enumerate() {
                let earlier: std::vec::Vec<usize> = order[..i]
                    .iter()
                    .filter(|e| e.0 == r)
                    .map(|e| e.1)
                    .collect();
                assert!(
                    earlier.iter().all(|&k| !shares(k, l)),
                    "lane {l} shares in run {r}"
                );
                let starts_run = i > 0 && order[i - 1].0 != r;
                if starts_run {
                    let previous: std::vec::Vec<usize> = order[..i]
                        .iter()
                        .filter(|e| e.0 == r - 1)
                        .map(|e| e.1)
                        .collect();
                    assert!(
                        previous.iter().any(|&k| shares(k, l)),
                        "needless run at lane {l}"
                    );
                }
            }
            assert!(runs[n..].iter().all(|m| *m == [false; 4]));
        }
    }

    /// Group `g` is slots `4g..4g + 4` in order, counted through the main slots and on
    /// into the extra ones: a group wholly in the main slots (the direct path) and one
    /// that straddles both (the chained path) alike; past the groups there is none.
    #[test]
    fn a_group_is_its_four_consecutive_slots() {
        let mut store = WideStore::<10>::new();
        assert!(store.reset(3));
        for g in 0..3u32 {
            let mut group = store.group(g as usize).unwrap();
            for (k, slot) in [&mut group.s0, &mut group.s1, &mut group.s2, &mut group.s3]
                .into_iter()
                .enumerate()
            {
                slot.idx[0] = 4 * g + k as u32;
            }
        }
        assert_eq!((store.main.len(), store.extra.len()), (10, 2));
        let mut tags = [u32::MAX; 12];
        for (t, slot) in tags
            .iter_mut()
            .zip(store.main.iter().chain(store.extra.iter()))
        {
            *t = slot.idx[0];
        }
        assert_eq!(tags, core::array::from_fn(|i| i as u32));
        assert!(store.group(3).is_none());
        assert!(store.group(usize::MAX).is_none());
    }
}
