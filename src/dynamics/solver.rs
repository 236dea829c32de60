//! Stage 7: the velocity solve. Sequential impulses with accumulated clamping and warm
//! starting (Catto, "Iterative dynamics with temporal coherence", GDC 2005), speculative
//! contacts (Catto, "Physics for game programmers: continuous collision", GDC 2013), a
//! collision pass for restitution (Guendelman, Bridson and Fedkiw, "Nonconvex rigid bodies
//! with stacking", SIGGRAPH 2003, section 5) and Coulomb friction with a static and a
//! kinetic coefficient.
//!
//! # Notation
//!
//! Per contact point: world anchors `p_a`, `p_b` (the surface points of the narrow phase),
//! lever arms `r = p − c` from each world centre of mass `c`, unit normal `n` from A to B,
//! relative velocity `Δv = v_b(p_b) − v_a(p_a)` with `v(p) = v + ω × r`, normal speed
//! `v_n = Δv·n` (negative when closing), separation `s` (m, negative when penetrating).
//! An impulse `P` acts as `+P` on B and `−P` on A. Along a unit direction `d` the effective
//! mass is
//!
//! ```text
//! m_d = 1 / (1/m_a + 1/m_b + (I_a⁻¹ (r_a × d))·(r_a × d) + (I_b⁻¹ (r_b × d))·(r_b × d))
//! ```
//!
//! (the triple product `d·((I⁻¹ (r × d)) × r)` rewritten), with the world inverse inertia
//! `I⁻¹ = R I_local⁻¹ Rᵀ`. Static, kinematic and sleeping bodies have `1/m = 0`,
//! `I⁻¹ = 0`: they push and are not pushed.
//!
//! # One sub-step of `h` seconds
//!
//! 1. **Wake**: a sleeping dynamic body that an awake dynamic body or a moving kinematic
//!    body touches (`s <= 0`) or reaches within the sub-step (`approach · h > s`) wakes, so
//!    a hit on a sleeping stack moves the body it hits. `sleep.rs` wakes the rest of its
//!    island at the end of the step.
//! 2. **Prepare**: anchors, lever arms and effective masses from the current poses; the
//!    approach speed `−v_n`; the restitution target `e · approach` when the approach is
//!    above `restitution_threshold` and the gap closes within the sub-step, else 0;
//!    `sticking` as below.
//! 3. **Warm start**: last step's accumulated `λ_n n + λ_t` applied again.
//! 4. **Collision pass** (restitution, only when `e > 0`): up to `velocity_iterations`
//!    sweeps over the contacts in order; each contact with a point closing faster than
//!    the threshold (measured *now*, from the current velocities) gets a transient
//!    impulse that makes those points separate at `e · approach`: a small accumulated
//!    solve over that contact's colliding points alone ([`BOUNCE_ITERATIONS`] rounds,
//!    `λ ≥ 0` per visit, with friction in the cone of that impulse). A sweep that bounces
//!    nothing ends the pass. These impulses are not accumulated into the warm-start
//!    impulses. Each bounce alone can only lose energy (`ΔE = ½ λ (1 − e) v_n <= 0`).
//!
//!    *Departure from the plain sequential-impulse target `v_n >= e · approach₀`*: with
//!    that target, measured once before the solve, only the first contact of a chain of
//!    touching bodies sees an approach, and a Newton's cradle solves to `−0.6 v` and
//!    `0.4 v` instead of passing the speed down the row. Measuring the approach when a
//!    contact is visited makes the impulse travel along the chain, one contact per
//!    sweep at worst (contacts in chain order: all in one sweep). The cost is that
//!    several contacts hit at once are treated one after another.
//! 5. **Contact iterations**: `velocity_iterations` rounds, contacts in order; per contact,
//!    friction for every point first and then the normal for every point (Box2D's order:
//!    non-penetration matters more than friction, so it is solved last).
//!    - Normal: `λ = −m_n (v_n − target)`, accumulated `λ_n ≥ 0`, with `target = 0` for a
//!      touching or penetrating point and `target = −s / h` for a speculative one
//!      (`s > 0`: it may close the gap, not more). No Baumgarte bias: `projection.rs`
//!      removes penetration. The normal rows of a contact are swept [`NORMAL_SWEEPS`]
//!      times per visit (block Gauss-Seidel, see there).
//!    - Friction: a 2D impulse `λ_t = −(m_t1 (Δv·t1) t1 + m_t2 (Δv·t2) t2)`, accumulated
//!      and clipped to the disc of radius `μ λ_n`.
//!
//! # The static and kinetic friction rule
//!
//! A sticking point uses `μ = static_friction`, a sliding one `μ = kinetic_friction`.
//!
//! - At prepare, a point *sticks* if it stuck last step, or its tangential speed
//!   `|Δv − (Δv·n) n|` is below `stick_speed`, or it carried no normal impulse last step
//!   (a new or a speculative point: it has no friction state yet, the solve decides).
//! - In the last contact iteration, when the normal impulse has converged, a sticking
//!   point that the static cone clipped *and* that still slips faster than `stick_speed`
//!   after its friction row starts sliding: it is clipped to `kinetic_friction · λ_n` at
//!   once. A clipped point alone is not enough: Gauss-Seidel loads the first points of a
//!   manifold up to their cones while the later points hold the rest, and flipping those
//!   would let a box that static friction holds slide. Nor is the first iteration, where
//!   the normal impulse of a new contact is still small.
//! - After the last iteration, a sliding point whose tangential speed is now below
//!   `stick_speed` sticks again. *Departure* from testing the speed at prepare alone:
//!   on a slope gravity adds `g h sin θ` (0.08 m/s at 30°, 60 Hz) of slip before every
//!   prepare, so a point that slid once would slide for ever.

use super::body::{Body, BodyKind};
use super::contact::{Contact, ContactPoint};
use super::pool::Pool;
use crate::config::WorldConfig;
use crate::math::{scalar, Mat3, Vec3};

/// Rounds of the small accumulated solve the collision pass runs over one contact's
/// colliding points. One is exact for a single point; four bring a flat face landing on
/// four points to within a few per cent of the simultaneous answer.
pub(crate) const BOUNCE_ITERATIONS: u32 = 4;

/// Sweeps over one contact's normal rows per visit in a contact iteration (block
/// Gauss-Seidel). One sweep per visit leaves a four-point face contact far from its own
/// solution: each point mostly turns the body (at a cube's corner the turn takes three
/// quarters of the effective mass), so the rows undo each other and a tower of ten boxes
/// sways and falls at 8 iterations. Four sweeps solve each manifold nearly exactly before
/// moving on (Box2D v2.4 solves its two-point manifolds exactly with a block solver; four
/// coplanar points make a singular block, so sweeps stand in for it).
pub(crate) const NORMAL_SWEEPS: u32 = 4;

/// How far (in `|t|² − 1` and `t·n`) a stored tangent may be from a unit vector
/// perpendicular to the normal before the solver builds its own basis.
const TANGENT_TOLERANCE: f32 = 1.0e-3;

/// Solve contact velocities for one sub-step of `h` seconds (see the module docs).
pub(crate) fn solve_velocities<const N: usize>(
    contacts: &mut [Contact],
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    h: f32,
) {
    if h.is_nan() || h <= 0.0 {
        return;
    }
    for c in contacts.iter() {
        wake_touched_sleepers(c, bodies, h);
    }
    for c in contacts.iter_mut() {
        prepare_contact(c, bodies, cfg, h);
    }
    for c in contacts.iter() {
        warm_start_contact(c, bodies);
    }
    for _ in 0..cfg.velocity_iterations {
        let mut bounced = false;
        for c in contacts.iter_mut() {
            bounced |= bounce_contact(c, bodies, cfg, h);
        }
        if !bounced {
            break;
        }
    }
    let inv_h = 1.0 / h;
    let last = cfg.velocity_iterations.saturating_sub(1);
    for iteration in 0..cfg.velocity_iterations {
        for c in contacts.iter_mut() {
            solve_contact(c, bodies, inv_h, cfg.stick_speed, iteration == last);
        }
    }
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

/// `v` shortened to length at most `radius` (a non-positive radius gives zero).
#[inline]
fn clip_to_disc(v: Vec3, radius: f32) -> Vec3 {
    if radius.is_nan() || radius <= 0.0 {
        return Vec3::ZERO;
    }
    let l2 = v.length_squared();
    if l2 > radius * radius {
        v * (radius / scalar::sqrt(l2))
    } else {
        v
    }
}

/// The contact's tangent basis, or one built from the normal when the stored one is not
/// an orthonormal pair perpendicular to it.
fn tangent_basis(c: &Contact) -> [Vec3; 2] {
    let n = c.normal;
    let [t1, t2] = c.tangents;
    let unit = |t: Vec3| scalar::abs(t.length_squared() - 1.0) < TANGENT_TOLERANCE;
    let ok = unit(t1)
        && unit(t2)
        && scalar::abs(t1.dot(n)) < TANGENT_TOLERANCE
        && scalar::abs(t2.dot(n)) < TANGENT_TOLERANCE
        && scalar::abs(t1.dot(t2)) < TANGENT_TOLERANCE;
    if ok {
        [t1, t2]
    } else {
        let t1 = n.any_perpendicular();
        [t1, n.cross(t1)]
    }
}

/// Whether a point `s` metres apart, closing at `approach` m/s, touches within `h`
/// seconds (a touching or penetrating point always does).
#[inline]
fn closes_within(separation: f32, approach: f32, h: f32) -> bool {
    separation <= 0.0 || approach * h > separation
}

/// The two bodies of a contact as the solver sees them: their masses are zero unless the
/// body is dynamic and awake.
struct Pair<'p, 'a> {
    a: &'p mut Body<'a>,
    b: &'p mut Body<'a>,
    inv_mass_a: f32,
    inv_mass_b: f32,
    inv_inertia_a: Mat3,
    inv_inertia_b: Mat3,
}

impl<'p, 'a> Pair<'p, 'a> {
    /// The pair of a contact, or `None` for a sensor contact, a stale slot, or two bodies
    /// that cannot move.
    fn of<const N: usize>(c: &Contact, bodies: &'p mut Pool<Body<'a>, N>) -> Option<Self> {
        if c.sensor {
            return None;
        }
        let (a, b) = bodies.pair_mut(c.a as usize, c.b as usize)?;
        let (active_a, active_b) = (is_active(a), is_active(b));
        if !active_a && !active_b {
            return None;
        }
        let (inv_mass_a, inv_inertia_a) = if active_a {
            (a.inv_mass, a.inv_inertia_world)
        } else {
            (0.0, Mat3::ZERO)
        };
        let (inv_mass_b, inv_inertia_b) = if active_b {
            (b.inv_mass, b.inv_inertia_world)
        } else {
            (0.0, Mat3::ZERO)
        };
        Some(Pair {
            a,
            b,
            inv_mass_a,
            inv_mass_b,
            inv_inertia_a,
            inv_inertia_b,
        })
    }

    /// Effective mass along the unit direction `d` at lever arms `r_a`, `r_b` (kg).
    #[inline]
    fn mass_along(&self, r_a: Vec3, r_b: Vec3, d: Vec3) -> f32 {
        effective_mass(
            self.inv_mass_a,
            &self.inv_inertia_a,
            r_a,
            self.inv_mass_b,
            &self.inv_inertia_b,
            r_b,
            d,
        )
    }

    /// `Δv = (v_b + ω_b × r_b) − (v_a + ω_a × r_a)` (m/s, world).
    #[inline]
    fn relative_velocity(&self, r_a: Vec3, r_b: Vec3) -> Vec3 {
        (self.b.linear_velocity + self.b.angular_velocity.cross(r_b))
            - (self.a.linear_velocity + self.a.angular_velocity.cross(r_a))
    }

    /// Squared tangential slip `|Δv − (Δv·n) n|²` at a point ((m/s)²).
    #[inline]
    fn slip_squared(&self, p: &ContactPoint, n: Vec3) -> f32 {
        let dv = self.relative_velocity(p.r_a, p.r_b);
        (dv - n * dv.dot(n)).length_squared()
    }

    /// Apply `impulse` (N·s, world) to B at `r_b` and its opposite to A at `r_a`.
    #[inline]
    fn apply(&mut self, r_a: Vec3, r_b: Vec3, impulse: Vec3) {
        if self.inv_mass_a > 0.0 {
            self.a.linear_velocity -= impulse * self.inv_mass_a;
            self.a.angular_velocity -= self.inv_inertia_a.mul_vec(r_a.cross(impulse));
        }
        if self.inv_mass_b > 0.0 {
            self.b.linear_velocity += impulse * self.inv_mass_b;
            self.b.angular_velocity += self.inv_inertia_b.mul_vec(r_b.cross(impulse));
        }
    }

    /// One normal row: `λ = −m_n (v_n − target)`, accumulated into `acc` with `acc ≥ 0`.
    #[inline]
    fn solve_normal(&mut self, p: &ContactPoint, n: Vec3, target: f32, acc: &mut f32) {
        let vn = self.relative_velocity(p.r_a, p.r_b).dot(n);
        let new = scalar::max(*acc - p.normal_mass * (vn - target), 0.0);
        let delta = new - *acc;
        *acc = new;
        self.apply(p.r_a, p.r_b, n * delta);
    }

    /// One friction row: the 2D impulse that stops the tangential slip, accumulated into
    /// `acc` and clipped to the disc of radius `radius`. Returns true when it was clipped.
    #[inline]
    fn solve_friction(
        &mut self,
        p: &ContactPoint,
        t: &[Vec3; 2],
        radius: f32,
        acc: &mut Vec3,
    ) -> bool {
        let [t1, t2] = *t;
        let dv = self.relative_velocity(p.r_a, p.r_b);
        let [m1, m2] = p.tangent_mass;
        let wanted = *acc - t1 * (m1 * dv.dot(t1)) - t2 * (m2 * dv.dot(t2));
        let new = clip_to_disc(wanted, radius);
        let clipped = new != wanted;
        let delta = new - *acc;
        *acc = new;
        self.apply(p.r_a, p.r_b, delta);
        clipped
    }
}

/// Step 1: wake a sleeping dynamic body that an awake dynamic or moving kinematic body
/// touches or reaches within the sub-step.
fn wake_touched_sleepers<const N: usize>(c: &Contact, bodies: &mut Pool<Body<'_>, N>, h: f32) {
    if c.sensor {
        return;
    }
    let Some((a, b)) = bodies.pair_mut(c.a as usize, c.b as usize) else {
        return;
    };
    let pushes = |x: &Body<'_>| is_active(x) || is_moving_kinematic(x);
    let sleeps = |x: &Body<'_>| x.is_dynamic() && !x.awake;
    let wake_a = sleeps(a) && pushes(b);
    let wake_b = sleeps(b) && pushes(a);
    if !wake_a && !wake_b {
        return;
    }
    let n = c.normal;
    let reached = c.points.iter().take(c.len as usize).any(|p| {
        let p_a = a.pose.transform_point(p.local_a);
        let p_b = b.pose.transform_point(p.local_b);
        let approach = -(b.velocity_at(p_b) - a.velocity_at(p_a)).dot(n);
        closes_within(p.separation, approach, h)
    });
    if reached {
        for (x, wake) in [(a, wake_a), (b, wake_b)] {
            if wake {
                x.awake = true;
                x.sleep_time = 0.0;
            }
        }
    }
}

/// Step 2: lever arms, effective masses, approach speed, restitution target, sticking.
fn prepare_contact<const N: usize>(
    c: &mut Contact,
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    h: f32,
) {
    let Some(pair) = Pair::of(c, bodies) else {
        return;
    };
    let n = c.normal;
    let [t1, t2] = tangent_basis(c);
    let e = c.material.restitution;
    let center_a = pair.a.world_center();
    let center_b = pair.b.world_center();
    let stick2 = cfg.stick_speed * cfg.stick_speed;
    let len = c.len as usize;
    for p in c.points.iter_mut().take(len) {
        p.r_a = pair.a.pose.transform_point(p.local_a) - center_a;
        p.r_b = pair.b.pose.transform_point(p.local_b) - center_b;
        p.normal_mass = pair.mass_along(p.r_a, p.r_b, n);
        p.tangent_mass = [
            pair.mass_along(p.r_a, p.r_b, t1),
            pair.mass_along(p.r_a, p.r_b, t2),
        ];
        let dv = pair.relative_velocity(p.r_a, p.r_b);
        let approach = -dv.dot(n);
        p.approach_speed = approach;
        p.restitution_velocity =
            if approach > cfg.restitution_threshold && closes_within(p.separation, approach, h) {
                e * approach
            } else {
                0.0
            };
        let slip = dv + n * approach; // Δv − (Δv·n) n
        p.sticking = p.sticking || slip.length_squared() < stick2 || p.normal_impulse <= 0.0;
        // The normal may have turned since last step: keep the friction impulse tangent.
        p.tangent_impulse -= n * p.tangent_impulse.dot(n);
    }
}

/// Step 3: apply last step's accumulated impulses again.
fn warm_start_contact<const N: usize>(c: &Contact, bodies: &mut Pool<Body<'_>, N>) {
    let Some(mut pair) = Pair::of(c, bodies) else {
        return;
    };
    for p in c.points.iter().take(c.len as usize) {
        pair.apply(
            p.r_a,
            p.r_b,
            c.normal * p.normal_impulse + p.tangent_impulse,
        );
    }
}

/// Step 4, one contact of one sweep: bounce the points that close faster than the
/// threshold now. Returns true when some point bounced.
fn bounce_contact<const N: usize>(
    c: &mut Contact,
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    h: f32,
) -> bool {
    let e = c.material.restitution;
    if e <= 0.0 {
        return false;
    }
    let Some(mut pair) = Pair::of(c, bodies) else {
        return false;
    };
    let n = c.normal;
    let len = c.len as usize;
    let mut colliding = [false; 4];
    let mut any = false;
    for (p, hit) in c.points.iter_mut().take(len).zip(colliding.iter_mut()) {
        let approach = -pair.relative_velocity(p.r_a, p.r_b).dot(n);
        if approach > cfg.restitution_threshold && closes_within(p.separation, approach, h) {
            *hit = true;
            any = true;
            p.restitution_velocity = e * approach;
        }
    }
    if !any {
        return false;
    }
    let t = tangent_basis(c);
    let m = c.material;
    let mut normal = [0.0f32; 4];
    let mut tangent = [Vec3::ZERO; 4];
    for _ in 0..BOUNCE_ITERATIONS {
        for (((p, hit), lambda), tau) in c
            .points
            .iter()
            .take(len)
            .zip(colliding)
            .zip(normal.iter())
            .zip(tangent.iter_mut())
        {
            if hit {
                let mu = if p.sticking {
                    m.static_friction
                } else {
                    m.kinetic_friction
                };
                pair.solve_friction(p, &t, mu * *lambda, tau);
            }
        }
        for ((p, hit), lambda) in c
            .points
            .iter()
            .take(len)
            .zip(colliding)
            .zip(normal.iter_mut())
        {
            if hit {
                pair.solve_normal(p, n, p.restitution_velocity, lambda);
            }
        }
    }
    true
}

/// Step 5, one contact of one iteration: friction rows, then normal rows; after the last
/// iteration, sliding points that stopped stick again.
fn solve_contact<const N: usize>(
    c: &mut Contact,
    bodies: &mut Pool<Body<'_>, N>,
    inv_h: f32,
    stick_speed: f32,
    last: bool,
) {
    let Some(mut pair) = Pair::of(c, bodies) else {
        return;
    };
    let n = c.normal;
    let t = tangent_basis(c);
    let m = c.material;
    let len = c.len as usize;
    let stick2 = stick_speed * stick_speed;
    for p in c.points.iter_mut().take(len) {
        let mut tau = p.tangent_impulse;
        if p.sticking {
            let clipped =
                pair.solve_friction(p, &t, m.static_friction * p.normal_impulse, &mut tau);
            // A clipped point alone proves nothing: Gauss-Seidel loads the first points of
            // a manifold up to their cones while the later ones hold the rest. The
            // manifold fails to hold when the point still slips after its row.
            if clipped && last && pair.slip_squared(p, n) >= stick2 {
                p.sticking = false;
                let kinetic = clip_to_disc(tau, m.kinetic_friction * p.normal_impulse);
                pair.apply(p.r_a, p.r_b, kinetic - tau);
                tau = kinetic;
            }
        } else {
            pair.solve_friction(p, &t, m.kinetic_friction * p.normal_impulse, &mut tau);
        }
        p.tangent_impulse = tau;
    }
    for _ in 0..NORMAL_SWEEPS {
        for p in c.points.iter_mut().take(len) {
            let target = if p.separation > 0.0 {
                -p.separation * inv_h
            } else {
                0.0
            };
            let mut lambda = p.normal_impulse;
            pair.solve_normal(p, n, target, &mut lambda);
            p.normal_impulse = lambda;
        }
    }
    if last {
        // A sliding point that the solve brought (nearly) to rest sticks again.
        for p in c.points.iter_mut().take(len) {
            if !p.sticking {
                p.sticking = pair.slip_squared(p, n) < stick2;
            }
        }
    }
}
