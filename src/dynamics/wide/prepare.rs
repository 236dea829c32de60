//! Prepare, four contacts side by side: the scalar `contact_solver::prepare` (and its
//! patch and angular rows) run in the lanes of one group, written straight into the
//! group's slots.
//!
//! Each lane performs the scalar prepare's operations in the scalar prepare's order (the
//! lever arms, the Jacobians `r × n`, the products `I⁻¹ (r × n)`, the effective masses,
//! the friction centre and the twist arms), so a lane holds the bits the scalar prepare
//! and `Group::store_lane` give it (tested against them). Branches that differ per lane
//! (a point past a contact's count, a body without a solver entry, a singular tangent
//! mass, the stick state) are lane selects or short per-lane scalar steps. A lane whose
//! contact does not push (a sensor, no point, no moving dynamic body) is left as it was,
//! as the scalar plan leaves it: its contact index stays [`NONE`] and no pass reads it.

use super::super::body::{Body, BodyKind};
use super::super::contact::Contact;
use super::super::contact_solver::{clip_to_disc, sides, torque_free, Sides, Softness};
use super::super::pool::Pool;
use super::super::solver::{SolverBody, NONE};
use super::super::support::Supports;
use super::*;
use crate::config::WorldConfig;
use crate::math::lanes::M4;
use crate::math::scalar;

/// What the rows read of the four contacts and their bodies, gathered lane by lane. One
/// is kept for a whole step's groups ([`Inputs::clear_lanes`] between them).
#[derive(Default)]
pub(crate) struct Inputs {
    /// The lane's contact pushes (the scalar prepare would return true).
    on: [bool; 4],
    /// `contact_solver::torque_free` per lane.
    torque_free: [bool; 4],
    /// Point `j` exists in lane `l`: `point[j][l]`.
    point: [[bool; 4]; 4],
    len: [u8; 4],
    has_a: [bool; 4],
    has_b: [bool; 4],
    m_a: F4,
    m_b: F4,
    i_a: M4,
    i_b: M4,
    /// The bodies' rotations at the manifold's build (lanes of `x, y, z, w`) and their
    /// centres of mass in their frames: the lever arms the rows keep
    /// (`contact_solver`, "Lever arms").
    built_a: [F4; 4],
    built_b: [F4; 4],
    com_a: V4,
    com_b: V4,
    va: V4,
    wa: V4,
    vb: V4,
    wb: V4,
    center_a: V4,
    center_b: V4,
    /// The bodies' rotations now (lanes of `x, y, z, w`).
    now_a: [F4; 4],
    now_b: [F4; 4],
    rho_a: F4,
    rho_b: F4,
    n: V4,
    t1: V4,
    t2: V4,
    mu_s: F4,
    local_a: [V4; 4],
    local_b: [V4; 4],
    separation: [F4; 4],
    impulse: [F4; 4],
    /// Where [`touch`] leaves its reads (never read back).
    touched: u32,
}

impl Inputs {
    /// Ready for the next group: no lane on, no point, no count, no solver body. The
    /// numbers stay as the last group left them (zeroing the whole 2 KiB for each group
    /// was 0.2 to 0.3 % of a step's instructions on `boxes` and `spheres`): a lane is
    /// written whole when it holds a contact, and one that does not is masked out of
    /// every row and store (lanes do not mix), so what it holds never reaches a contact.
    fn clear_lanes(&mut self) {
        self.on = [false; 4];
        self.torque_free = [false; 4];
        self.point = [[false; 4]; 4];
        self.len = [0; 4];
        self.has_a = [false; 4];
        self.has_b = [false; 4];
    }
}

/// Prepare the contacts `lanes` (contact indices, [`NONE`] for a lane without one) into
/// `group`: per lane exactly `contact_solver::prepare` followed by `Group::store_lane`.
/// `x` is the step's scratch for the gathered inputs.
#[allow(clippy::too_many_arguments)]
pub(crate) fn prepare_group<const N: usize, const CAPPED: bool>(
    x: &mut Inputs,
    group: &mut Group<'_>,
    lanes: &[u32; 4],
    contacts: &[Contact],
    bodies: &Pool<Body<'_>, N>,
    solver_bodies: &[SolverBody],
    solver_index: &[u32; N],
    softness: &[Softness; 2],
    supports: &Supports<'_>,
    cfg: &WorldConfig,
) {
    x.clear_lanes();
    let [c0, c1, c2, c3] = *lanes;
    // The four lanes' bodies first: each lane's first reads of its contact and of its
    // bodies miss the cache more often than not, and looked up together those misses
    // overlap instead of waiting on each other.
    let (b, sb, si) = (bodies, solver_bodies, solver_index);
    let side = |ci: u32| {
        let c = contacts.get(ci as usize)?;
        Some((c, sides::<N, CAPPED>(c, b, sb, si, supports)?))
    };
    let four = [side(c0), side(c1), side(c2), side(c3)];
    x.touched = touch(&four);
    // Lane by lane with the lane a constant, so each lane's writes are plain stores.
    let [s0, s1, s2, s3] = four;
    let mut lane = |l: usize, ci: u32, found: Option<(&Contact, Sides<'_, '_>)>| {
        if let Some((c, side)) = found {
            gather_lane(group, x, l, ci, c, side, softness);
        }
    };
    lane(0, c0, s0);
    lane(1, c1, s1);
    lane(2, c2, s2);
    lane(3, c3, s3);
    if x.on == [false; 4] {
        return;
    }
    prepare_rows(group, x, lanes, contacts, cfg);
}

/// One read from each part of memory the gather of the lanes `four` will read: each
/// contact's points, normal and friction impulse, each body's pose and centre, each
/// solver body's velocity and rotation. Those are cache misses more often than not
/// (`spheres`, `pyramid100`: the contacts and bodies outgrow the cache; the prepare
/// visits them in colour order), and the gather reads them lane after lane, each miss
/// waiting on the last. Read here first, all four lanes' misses are in flight at once.
/// The values are folded into one word the caller stores, so the reads stay: they
/// change nothing else. (`jolt_pyramid` about 4 % less time, `spheres` 3 to 7 %,
/// `pyramid100` 2 %.)
#[inline(always)]
fn touch(four: &[Option<(&Contact, Sides<'_, '_>)>; 4]) -> u32 {
    let mut t = 0u32;
    for (c, side) in four.iter().flatten() {
        t ^= c.normal.x.to_bits() ^ c.friction_impulse.x.to_bits();
        for p in c.points() {
            t ^= p.separation.to_bits();
        }
        for b in [side.body_a, side.body_b] {
            t ^= b.pose().position.x.to_bits() ^ b.world_center().x.to_bits();
        }
        for sb in [side.sa, side.sb].into_iter().flatten() {
            t ^= sb.v.x.to_bits() ^ sb.rot.z.z.to_bits();
        }
    }
    t
}

/// Lane `l`'s inputs (contact `ci`, whose bodies are `side`: the checks of the scalar
/// prepare passed) and the per-lane values the rows copy as they are (the softness too).
#[inline(always)]
fn gather_lane(
    group: &mut Group<'_>,
    x: &mut Inputs,
    l: usize,
    ci: u32,
    c: &Contact,
    side: Sides<'_, '_>,
    softness: &[Softness; 2],
) {
    let (body_a, body_b, sa, sb) = (side.body_a, side.body_b, side.sa, side.sb);
    let (ia, ib) = (side.ia, side.ib);
    let (m_a, i_a, m_b, i_b) = (side.m_a, side.i_a, side.m_b, side.i_b);
    if let Some(on) = x.on.get_mut(l) {
        *on = true;
    }
    if let Some(t) = x.torque_free.get_mut(l) {
        *t = torque_free(&side);
    }
    let n = c.normal;
    let t1 = n.any_perpendicular();
    let t2 = n.cross(t1);
    x.m_a.set(l, m_a);
    x.m_b.set(l, m_b);
    x.i_a.set(l, &i_a);
    x.i_b.set(l, &i_b);
    x.com_a.set(l, body_a.center_local);
    x.com_b.set(l, body_b.center_local);
    if let (Some(a), Some(b)) = (x.has_a.get_mut(l), x.has_b.get_mut(l)) {
        (*a, *b) = (sa.is_some(), sb.is_some());
    }
    let (va, wa) = sa.map_or((Vec3::ZERO, Vec3::ZERO), |s| (s.v, s.w));
    let (vb, wb) = sb.map_or((Vec3::ZERO, Vec3::ZERO), |s| (s.v, s.w));
    x.va.set(l, va);
    x.wa.set(l, wa);
    x.vb.set(l, vb);
    x.wb.set(l, wb);
    x.center_a.set(l, body_a.world_center());
    x.center_b.set(l, body_b.world_center());
    // A manifold never reused (a sphere pair's, `built_margin` < 0) takes its arms as
    // the bodies turn now; a built one was built at the rotations it keeps.
    let (now_a, now_b) = (body_a.pose().rotation, body_b.pose().rotation);
    let (built_a, built_b) = if c.built_margin < 0.0 {
        (now_a, now_b)
    } else {
        (c.built_rot_a, c.built_rot_b)
    };
    for (lanes, q) in [
        (&mut x.now_a, now_a),
        (&mut x.now_b, now_b),
        (&mut x.built_a, built_a),
        (&mut x.built_b, built_b),
    ] {
        for (lane, v) in lanes.iter_mut().zip([q.x, q.y, q.z, q.w]) {
            lane.set(l, v);
        }
    }
    x.rho_a.set(l, body_a.shape.radius());
    x.rho_b.set(l, body_b.shape.radius());
    x.n.set(l, n);
    x.t1.set(l, t1);
    x.t2.set(l, t2);
    let m = c.material;
    x.mu_s.set(l, m.static_friction);
    let len = c.points().len().min(4);
    if let Some(v) = x.len.get_mut(l) {
        *v = len as u8;
    }
    for (j, p) in c.points().iter().enumerate().take(4) {
        if let Some(on) = x.point.get_mut(j).and_then(|row| row.get_mut(l)) {
            *on = true;
        }
        if let (Some(a), Some(b), Some(s), Some(i)) = (
            x.local_a.get_mut(j),
            x.local_b.get_mut(j),
            x.separation.get_mut(j),
            x.impulse.get_mut(j),
        ) {
            a.set(l, p.local_a);
            b.set(l, p.local_b);
            s.set(l, p.separation);
            i.set(l, p.normal_impulse);
        }
    }
    let q0 = &mut group.s0.s;
    set_lane_v(q0, NORMAL, l, n);
    set_lane_v(q0, T1, l, t1);
    set_lane_v(q0, T2, l, t2);
    set_lane(q0, INV_MASS_A, l, m_a);
    set_lane(q0, INV_MASS_B, l, m_b);
    set_lane(q0, MU_S, l, m.static_friction);
    set_lane(q0, MU_K, l, m.kinetic_friction);
    set_lane(q0, RESTITUTION, l, m.restitution);
    // Twice the stiffness against a body that does not respond (static or kinematic)
    // and against a capped support, which gives way a twentieth as much as this body.
    let rigid_partner =
        body_a.kind != BodyKind::Dynamic || body_b.kind != BodyKind::Dynamic || side.capped;
    let soft = if rigid_partner {
        softness[1]
    } else {
        softness[0]
    };
    set_lane(q0, BIAS_RATE, l, soft.bias_rate);
    set_lane(q0, MASS_SCALE, l, soft.mass_scale);
    set_lane(q0, IMPULSE_SCALE, l, soft.impulse_scale);
    if let Some(v) = group.s0.idx.get_mut(l) {
        *v = if sa.is_some() { ia } else { NONE };
    }
    if let Some(v) = group.s1.idx.get_mut(l) {
        *v = if sb.is_some() { ib } else { NONE };
    }
    if let Some(v) = group.s2.idx.get_mut(l) {
        *v = ci;
    }
}

/// `if mask { a } else { b }`, lane-wise, for vectors.
#[inline]
fn select_v(mask: [bool; 4], a: &V4, b: &V4) -> V4 {
    V4 {
        x: b.x.select_where(mask, a.x),
        y: b.y.select_where(mask, a.y),
        z: b.z.select_where(mask, a.z),
    }
}

/// A lane mask with its "all four" test made once: the writes and keeps below take a
/// plain copy for a full mask (most groups' and points') and a blend otherwise.
#[derive(Clone, Copy)]
struct Mask {
    lanes: [bool; 4],
    all: bool,
}

impl Mask {
    #[inline]
    fn of(lanes: [bool; 4]) -> Mask {
        Mask {
            lanes,
            all: lanes == ALL_LANES,
        }
    }
}

/// Write `v` into the lanes of `dst` where `on` (all four: a plain copy).
#[inline]
fn put(dst: &mut F4, on: Mask, v: F4) {
    *dst = if on.all {
        v
    } else {
        dst.select_where(on.lanes, v)
    };
}

/// Write `v` into the lanes of `dst` where `on`.
#[inline]
fn put_v(dst: &mut V4, on: Mask, v: &V4) {
    *dst = if on.all {
        *v
    } else {
        select_v(on.lanes, v, dst)
    };
}

/// `v` where `on`, zero elsewhere.
#[inline]
fn keep(on: Mask, v: F4) -> F4 {
    if on.all {
        v
    } else {
        F4::ZERO.select_where(on.lanes, v)
    }
}

/// `v` where `on`, zero elsewhere.
#[inline]
fn keep_v(on: Mask, v: &V4) -> V4 {
    if on.all {
        *v
    } else {
        select_v(on.lanes, v, &V4::default())
    }
}

/// Write `v` into the lanes of quarter entry `at..at + 3` where `on`.
#[inline(always)]
fn put_q(q: &mut [F4; QUARTER], at: usize, on: Mask, v: &V4) {
    for (i, c) in [v.x, v.y, v.z].into_iter().enumerate() {
        if let Some(d) = q.get_mut(at + i) {
            put(d, on, c);
        }
    }
}

/// The normal rows, the friction centre, the patch and the angular rows of the lanes
/// in `x.on` (module docs).
fn prepare_rows(
    group: &mut Group<'_>,
    x: &Inputs,
    lanes: &[u32; 4],
    contacts: &[Contact],
    cfg: &WorldConfig,
) {
    let on = Mask::of(x.on);
    let zero = F4::ZERO;
    let n = &x.n;
    let radius_sum = x.rho_a + x.rho_b;
    let speed_bound = F4::splat(2.0 * cfg.max_linear_speed + cfg.max_push_speed);
    let adjusted = n.dot(&x.center_b.sub(&x.center_a)) - radius_sum;
    let (n_rho_a, n_rho_b) = (n.scale(x.rho_a), n.scale(x.rho_b));
    let (now_a, now_b) = (M4::from_quat(&x.now_a), M4::from_quat(&x.now_b));
    let (built_a, built_b) = (M4::from_quat(&x.built_a), M4::from_quat(&x.built_b));
    // A solver body's anchors are in its axes: `d − Rᵀ n ρ` (the core's point; its
    // solver rotation is `Mat3::from_quat` of the same quaternion, `now_a`'s lane).
    let n_rho_local_a = now_a.transpose_mul_vec(n).scale(x.rho_a);
    let n_rho_local_b = now_b.transpose_mul_vec(n).scale(x.rho_b);
    let mut plain = V4::default();
    let mut carried = zero;
    let mut largest = zero;
    let mut mids = [V4::default(); 4];
    let mut impulses = [zero; 4];
    // The point rows some lane has (a group of spheres has one).
    let rows = usize::from(x.len.iter().copied().max().unwrap_or(0)).min(4);
    for j in 0..rows {
        let Some(&point) = x.point.get(j) else {
            break;
        };
        let here = Mask::of(point);
        let (Some(la), Some(lb)) = (x.local_a.get(j), x.local_b.get(j)) else {
            break;
        };
        // The anchors about the centres of mass, in body axes, and turned as now.
        let d_a = la.sub(&x.com_a);
        let d_b = lb.sub(&x.com_b);
        let r_a = now_a.mul_vec(&d_a);
        let r_b = now_b.mul_vec(&d_b);
        let p_a = x.center_a.add(&r_a);
        let p_b = x.center_b.add(&r_b);
        let core_a = r_a.sub(&n_rho_a);
        let core_b = r_b.add(&n_rho_b);
        // The rows' lever arms: the anchors turned as the bodies were at the build.
        let kept_a = built_a.mul_vec(&d_a);
        let kept_b = built_b.mul_vec(&d_b);
        let rn_a = kept_a.cross(n);
        let rn_b = kept_b.cross(n);
        let in_a = x.i_a.mul_vec(&rn_a);
        let in_b = x.i_b.mul_vec(&rn_b);
        let k = x.m_a + x.m_b + rn_a.dot(&in_a) + rn_b.dot(&in_b);
        let normal_mass = k.recip_or_zero();
        let stored = x.impulse.get(j).copied().unwrap_or_default();
        let cap = normal_mass * speed_bound;
        let impulse = F4(core::array::from_fn(|l| {
            scalar::min(stored.lane(l), cap.lane(l))
        }));
        // A body without a solver entry keeps its world lever arm as its anchor.
        let local_a = select_v(x.has_a, &d_a.sub(&n_rho_local_a), &core_a);
        let local_b = select_v(x.has_b, &d_b.add(&n_rho_local_b), &core_b);
        let mid = p_a.add(&p_b).scale(F4::splat(0.5));
        plain = select_v(point, &plain.add(&mid), &plain);
        carried = carried.select_where(point, carried + impulse);
        largest = largest.select_where(point, largest.max(impulse));
        if let (Some(m), Some(i)) = (mids.get_mut(j), impulses.get_mut(j)) {
            *m = mid;
            *i = impulse;
        }
        // Points past a lane's count are empty: zero in every field.
        let sep = x.separation.get(j).copied().unwrap_or_default();
        let p = group.point_mut(j);
        put_v(&mut p.local_a, on, &keep_v(here, &local_a));
        put_v(&mut p.local_b, on, &keep_v(here, &local_b));
        put(&mut p.adjusted, on, keep(here, adjusted));
        put_v(&mut p.rn_a, on, &keep_v(here, &rn_a));
        put_v(&mut p.rn_b, on, &keep_v(here, &rn_b));
        put_v(&mut p.in_a, on, &keep_v(here, &in_a));
        put_v(&mut p.in_b, on, &keep_v(here, &in_b));
        put(&mut p.normal_mass, on, keep(here, normal_mass));
        put(&mut p.normal_impulse, on, keep(here, impulse));
        put(&mut p.separation, on, keep(here, sep));
        put(&mut p.separation0, on, keep(here, sep));
        put(&mut p.total_impulse, on, zero);
        put(&mut p.normal_speed0, on, zero);
        put(&mut p.bounced, on, zero);
    }
    normal_speeds(group, x, rows, (&now_a, &now_b));
    // Point rows no lane has: empty.
    for j in rows..4 {
        let p = group.point_mut(j);
        let zero_v = V4::default();
        for v in [&mut p.local_a, &mut p.local_b, &mut p.rn_a, &mut p.rn_b] {
            put_v(v, on, &zero_v);
        }
        for v in [&mut p.in_a, &mut p.in_b] {
            put_v(v, on, &zero_v);
        }
        for v in [
            &mut p.adjusted,
            &mut p.normal_mass,
            &mut p.normal_impulse,
            &mut p.twist_arm,
            &mut p.separation,
            &mut p.separation0,
            &mut p.total_impulse,
            &mut p.normal_speed0,
            &mut p.bounced,
        ] {
            put(v, on, zero);
        }
    }
    // The friction centre: the points' mean weighted by last step's normal impulses
    // relative to the largest, or their plain mean.
    let count = F4(x.len.map(f32::from));
    let mut weighted = V4::default();
    let mut weight = zero;
    for j in 0..rows {
        let (Some(&here), Some(mid), Some(&impulse)) =
            (x.point.get(j), mids.get(j), impulses.get(j))
        else {
            break;
        };
        let w = impulse.div(largest);
        weighted = select_v(here, &weighted.add(&mid.scale(w)), &weighted);
        weight = weight.select_where(here, weight + w);
    }
    let one = F4::splat(1.0);
    let center = select_v(
        core::array::from_fn(|l| largest.lane(l) > 0.0),
        &weighted.scale(one.div(weight)),
        &plain.scale(one.div(count)),
    );
    let mut arms = [zero; 4];
    for j in 0..rows {
        let (Some(&here), Some(mid)) = (x.point.get(j), mids.get(j)) else {
            break;
        };
        let d = mid.sub(&center);
        let arm = keep(Mask::of(here), d.dot(&d).sqrt());
        if let Some(a) = arms.get_mut(j) {
            *a = arm;
        }
        put(&mut group.point_mut(j).twist_arm, on, arm);
    }
    let r_a = center.sub(&x.center_a);
    let r_b = center.sub(&x.center_b);
    prepare_patch(group, x, &r_a, &r_b, &impulses, &arms, lanes, contacts, cfg);
    let flags: [u32; 4] = core::array::from_fn(|l| {
        let est = carried.lane(l) > 0.0;
        let free = x.torque_free.get(l).copied().unwrap_or(false);
        u32::from(x.len.get(l).copied().unwrap_or(0))
            | if est { ESTABLISHED } else { 0 }
            | if free { TORQUE_FREE } else { 0 }
    });
    for (l, f) in flags.iter().enumerate() {
        if on.lanes.get(l).copied().unwrap_or(false) {
            if let Some(v) = group.s3.idx.get_mut(l) {
                // The sticking bit was set by the patch.
                *v = (*v & STICKING) | f;
            }
        }
    }
    prepare_angular_rows(group, x, &r_a, &r_b, lanes, contacts, radius_sum);
}

/// The normal speeds `v_n` at prepare of the point rows, in the lanes with restitution
/// (the only ones the restitution passes read; the others keep 0), as the scalar
/// prepare forms them. A group without restitution (most) skips them.
/// `now`: the bodies' rotations, as the point rows turned the anchors.
fn normal_speeds(group: &mut Group<'_>, x: &Inputs, rows: usize, now: (&M4, &M4)) {
    let restitution = f4(&group.s0.s, RESTITUTION);
    let bouncy: [bool; 4] = core::array::from_fn(|l| {
        x.on.get(l).copied().unwrap_or(false) && restitution.lane(l) > 0.0
    });
    if bouncy == [false; 4] {
        return;
    }
    let (now_a, now_b) = now;
    for j in 0..rows {
        let (Some(&here), Some(la), Some(lb)) =
            (x.point.get(j), x.local_a.get(j), x.local_b.get(j))
        else {
            break;
        };
        let r_a = now_a.mul_vec(&la.sub(&x.com_a));
        let r_b = now_b.mul_vec(&lb.sub(&x.com_b));
        let closing =
            x.vb.add(&x.wb.cross(&r_b))
                .sub(&x.va.add(&x.wa.cross(&r_a)));
        let vn = keep(Mask::of(here), closing.dot(&x.n));
        let p = group.point_mut(j);
        p.normal_speed0 = p.normal_speed0.select_where(bouncy, vn);
    }
}

/// The friction patch at the centre (lever arms `r_a`, `r_b`), as
/// `contact_solver::prepare_patch`; sets each lane's sticking bit.
#[allow(clippy::too_many_arguments)]
fn prepare_patch(
    group: &mut Group<'_>,
    x: &Inputs,
    r_a: &V4,
    r_b: &V4,
    impulses: &[F4; 4],
    arms: &[F4; 4],
    lanes: &[u32; 4],
    contacts: &[Contact],
    cfg: &WorldConfig,
) {
    let on = Mask::of(x.on);
    let rt_a = [r_a.cross(&x.t1), r_a.cross(&x.t2)];
    let rt_b = [r_b.cross(&x.t1), r_b.cross(&x.t2)];
    let it_a = [x.i_a.mul_vec(&rt_a[0]), x.i_a.mul_vec(&rt_a[1])];
    let it_b = [x.i_b.mul_vec(&rt_b[0]), x.i_b.mul_vec(&rt_b[1])];
    let m = x.m_a + x.m_b;
    let kxx = m + rt_a[0].dot(&it_a[0]) + rt_b[0].dot(&it_b[0]);
    let kyy = m + rt_a[1].dot(&it_a[1]) + rt_b[1].dot(&it_b[1]);
    let kxy = rt_a[0].dot(&it_a[1]) + rt_b[0].dot(&it_b[1]);
    let det = kxx * kyy - kxy * kxy;
    let dv = x.vb.add(&x.wb.cross(r_b)).sub(&x.va.add(&x.wa.cross(r_a)));
    let slip = dv.sub(&x.n.scale(dv.dot(&x.n)));
    let slip2 = slip.dot(&slip);
    let q1 = &mut group.s1.s;
    put_q(q1, RT_A0, on, &rt_a[0]);
    put_q(q1, RT_A1, on, &rt_a[1]);
    put_q(q1, RT_B0, on, &rt_b[0]);
    put_q(q1, RT_B1, on, &rt_b[1]);
    let q2 = &mut group.s2.s;
    put_q(q2, IT_A0, on, &it_a[0]);
    put_q(q2, IT_A1, on, &it_a[1]);
    put_q(q2, IT_B0, on, &it_b[0]);
    put_q(q2, IT_B1, on, &it_b[1]);
    // The inverse of the 2×2 tangent mass where its determinant is positive and finite,
    // else the inverse of each diagonal alone.
    let inv = F4::splat(1.0).div(det);
    let regular: [bool; 4] = core::array::from_fn(|l| {
        let d = det.lane(l);
        d > 0.0 && d.is_finite()
    });
    let tangent_mass = [
        kxx.recip_or_zero().select_where(regular, kyy * inv),
        F4::ZERO.select_where(regular, -kxy * inv),
        kyy.recip_or_zero().select_where(regular, kxx * inv),
    ];
    for (i, v) in tangent_mass.iter().enumerate() {
        if let Some(d) = q1.get_mut(TANGENT_MASS + i) {
            put(d, on, *v);
        }
    }
    for l in 0..4 {
        if !on.lanes.get(l).copied().unwrap_or(false) {
            continue;
        }
        let Some(c) = lanes.get(l).and_then(|&ci| contacts.get(ci as usize)) else {
            continue;
        };
        let len = usize::from(x.len.get(l).copied().unwrap_or(0));
        let total: f32 = impulses.iter().take(len).map(|i| i.lane(l)).sum();
        let (n, t1, t2) = (x.n.lane(l), x.t1.lane(l), x.t2.lane(l));
        let mu_s = x.mu_s.lane(l);
        let tangent = c.friction_impulse - n * c.friction_impulse.dot(n);
        let (clipped, _) = clip_to_disc([tangent.dot(t1), tangent.dot(t2)], mu_s * total);
        let sticking =
            c.sticking || slip2.lane(l) < cfg.stick_speed * cfg.stick_speed || total <= 0.0;
        let mut levers = 0.0f32;
        for (i, a) in impulses.iter().zip(arms).take(len) {
            levers += i.lane(l) * a.lane(l);
        }
        let twist_limit = mu_s * levers;
        let twist = scalar::clamp(c.twist_impulse, -twist_limit, twist_limit);
        let q1 = &mut group.s1.s;
        set_lane(q1, TANGENT_IMPULSE, l, clipped[0]);
        set_lane(q1, TANGENT_IMPULSE + 1, l, clipped[1]);
        let q2 = &mut group.s2.s;
        set_lane(q2, ANGULAR_IMPULSE, l, 0.0);
        set_lane(q2, ANGULAR_IMPULSE + 1, l, 0.0);
        set_lane(q2, ANGULAR_IMPULSE + 2, l, twist);
        if let Some(v) = group.s3.idx.get_mut(l) {
            *v = if sticking { STICKING } else { 0 };
        }
    }
}

/// Rolling rows for manifolds of one or two points, the single-point twist coefficient
/// and the angular effective masses, as `contact_solver::prepare_angular_rows`.
fn prepare_angular_rows(
    group: &mut Group<'_>,
    x: &Inputs,
    r_a: &V4,
    r_b: &V4,
    lanes: &[u32; 4],
    contacts: &[Contact],
    radius_sum: F4,
) {
    let on = Mask::of(x.on);
    let mut rolling = F4::ZERO;
    let mut twist = F4::ZERO;
    for l in 0..4 {
        if !on.lanes.get(l).copied().unwrap_or(false) {
            continue;
        }
        let Some(c) = lanes.get(l).and_then(|&ci| contacts.get(ci as usize)) else {
            continue;
        };
        let len = x.len.get(l).copied().unwrap_or(0);
        let m = c.material;
        let rolls = len <= 2 && m.rolling_resistance > 0.0;
        let twists = len == 1 && m.twist_friction > 0.0;
        if rolls || twists {
            let lever = match (x.m_a.lane(l) > 0.0, x.m_b.lane(l) > 0.0) {
                (true, true) => scalar::min(r_a.lane(l).length(), r_b.lane(l).length()),
                (true, false) => r_a.lane(l).length(),
                _ => r_b.lane(l).length(),
            };
            rolling.set(
                l,
                if rolls {
                    m.rolling_resistance * lever
                } else {
                    0.0
                },
            );
            twist.set(
                l,
                if twists {
                    m.twist_friction * lever
                } else {
                    0.0
                },
            );
        }
    }
    // The tangent rows only where the manifold rolls; the twist row always (the patch).
    let rolls: [bool; 4] = core::array::from_fn(|l| rolling.lane(l) > 0.0);
    let q0 = &mut group.s0.s;
    if let Some(d) = q0.get_mut(ROLLING) {
        put(d, on, rolling);
    }
    if let Some(d) = q0.get_mut(TWIST) {
        put(d, on, twist);
    }
    let q1 = &mut group.s1.s;
    if let Some(d) = q1.get_mut(RADIUS_SUM) {
        put(d, on, radius_sum);
    }
    let axes = [x.t1, x.t2, x.n];
    let zero_v = V4::default();
    for (i, d) in axes.iter().enumerate() {
        let wanted = Mask::of(if i == 2 { ALL_LANES } else { rolls });
        let (ia, ib, mass) = if wanted.lanes == [false; 4] {
            // No lane rolls: the tangent rows are empty.
            (zero_v, zero_v, F4::ZERO)
        } else {
            let ia = x.i_a.mul_vec(d);
            let ib = x.i_b.mul_vec(d);
            let mass = (d.dot(&ia) + d.dot(&ib)).recip_or_zero();
            (ia, ib, mass)
        };
        put_q(&mut group.s3.s, IA_AXES + 3 * i, on, &keep_v(wanted, &ia));
        put_q(&mut group.s3.s, IB_AXES + 3 * i, on, &keep_v(wanted, &ib));
        if let Some(dst) = group.s2.s.get_mut(AXIS_MASS + i) {
            put(dst, on, keep(wanted, mass));
        }
    }
}
