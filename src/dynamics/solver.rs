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
//! prepare     one ContactConstraint per manifold: lever arms, Jacobians and effective
//!             masses, the separation s0, the closing speed before the solve;
//!             dynamic–dynamic contacts first, contacts with a static or kinematic body
//!             last (Gauss-Seidel gives the last word to the last row)
//! bounce      the collision pass: restitution from the speeds before this step's gravity
//! for each of `substeps` sub-steps of h = dt / substeps:
//!     integrate velocities     v += h (g + F/m), ω += h I⁻¹ τ, damping, speed limits
//!     warm start               apply the accumulated impulses again
//!     solve                    `velocity_iterations` soft iterations (push-out)
//!     integrate positions      Δp += v h, q ← q + ½ h ω q (normalised)
//!     relax                    `relax_iterations` iterations without push-out, with
//!                              friction, rolling and twist
//! restitution the points that were far at prepare and pushed: bounce from v_n0
//! store       accumulated impulses and stick/slip state back to the contacts
//! finalize    poses, velocities and R I⁻¹ Rᵀ back to the bodies
//! ```
//!
//! The rows themselves (soft normal rows, friction, rolling and twist, the collision
//! pass) are in `contact_solver.rs`. The world inverse inertia is taken once per step
//! at the starting rotation, as in Box2D: within a step a body turns little, and the
//! anchors of the separation follow the exact rotation.

use heapless::Vec as HVec;

use super::body::{Body, BodyKind};
use super::contact::Contact;
use super::contact_solver::{self, ContactConstraint};
use super::pool::Pool;
use crate::config::WorldConfig;
use crate::math::{scalar, Mat3, Quat, Vec3};

/// Index of "no solver body": a static or sleeping body (zero velocity, infinite mass).
pub(crate) const NONE: u32 = u32::MAX;

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
}

impl SolverBody {
    const ZERO: SolverBody = SolverBody {
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
    /// One constraint per manifold that pushes, in contact order.
    pub constraints: HVec<ContactConstraint, C>,
}

impl<const N: usize, const C: usize> Solver<N, C> {
    /// Empty.
    pub const fn new() -> Self {
        Solver {
            bodies: HVec::new(),
            index: [NONE; N],
            constraints: HVec::new(),
        }
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
    cfg: &WorldConfig,
) {
    let h = cfg.substep();
    if h.is_nan() || h <= 0.0 {
        return;
    }
    for c in contacts.iter() {
        contact_solver::wake_touched_sleepers(c, bodies, cfg.dt);
    }
    gather(solver, bodies, cfg, h);
    solver.constraints.clear();
    // Contacts between two dynamic bodies first, then those against static and kinematic
    // bodies: Gauss-Seidel gives the last word to what is solved last, and a wall must
    // win over a ball knocked into it (Box2D v3 orders its colours the same way).
    for rigid_partner in [false, true] {
        for (i, c) in contacts.iter().enumerate() {
            if c.len == 0 || c.sensor || contact_solver::has_rigid_partner(c, bodies) != rigid_partner
            {
                continue;
            }
            let (sbodies, sindex, constraints) =
                (&solver.bodies, &solver.index, &mut solver.constraints);
            // Built in place: a constraint is about a kilobyte.
            if constraints.push(ContactConstraint::default()).is_err() {
                continue;
            }
            let Some(k) = constraints.last_mut() else {
                continue;
            };
            if !contact_solver::prepare(c, i as u32, bodies, sbodies, sindex, cfg, k) {
                constraints.pop();
            }
        }
    }
    let (constraints, sbodies) = (&mut solver.constraints, &mut solver.bodies);
    contact_solver::bounce(constraints, sbodies, cfg);
    let inv_h = 1.0 / h;
    for sub in 0..cfg.substeps {
        integrate_velocities(sbodies, cfg);
        contact_solver::warm_start(constraints, sbodies);
        for _ in 0..cfg.velocity_iterations {
            contact_solver::solve(constraints, sbodies, cfg, inv_h, true, false);
        }
        integrate_positions(sbodies, h);
        for k in 0..cfg.relax_iterations {
            let last = sub + 1 == cfg.substeps && k + 1 == cfg.relax_iterations;
            contact_solver::solve(constraints, sbodies, cfg, inv_h, false, last);
        }
    }
    contact_solver::restitution(constraints, sbodies, cfg);
    contact_solver::store(constraints, contacts);
    finalize(solver, bodies);
}

/// Copy the awake dynamic and kinematic bodies into `solver.bodies` (slot order) and
/// fill the index map; remember each body's pose at the step start (`pose0`).
fn gather<const N: usize, const C: usize>(
    solver: &mut Solver<N, C>,
    bodies: &mut Pool<Body<'_>, N>,
    cfg: &WorldConfig,
    h: f32,
) {
    solver.bodies.clear();
    for e in solver.index.iter_mut() {
        *e = NONE;
    }
    for (slot, b) in bodies.iter_mut() {
        b.pose0 = b.pose;
        if b.kind == BodyKind::Static || !b.awake {
            b.force = Vec3::ZERO;
            b.torque = Vec3::ZERO;
            continue;
        }
        let dynamic = b.is_dynamic();
        let mut sb = SolverBody {
            v: b.linear_velocity,
            w: b.angular_velocity,
            q: b.pose.rotation,
            rot: Mat3::from_quat(b.pose.rotation),
            slot: slot as u32,
            ..SolverBody::ZERO
        };
        if dynamic {
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
}

/// `v += dv`, `ω += dω`, damping, speed limits, for every dynamic solver body.
fn integrate_velocities(bodies: &mut [SolverBody], cfg: &WorldConfig) {
    for b in bodies.iter_mut() {
        if b.inv_mass <= 0.0 {
            continue;
        }
        let v = (b.v + b.dv) * b.linear_damping;
        let w = (b.w + b.dw) * b.angular_damping;
        b.v = clamp_length(v, cfg.max_linear_speed);
        b.w = clamp_length(w, cfg.max_angular_speed);
    }
}

/// `Δp += v h`, `q ← normalise(q + ½ h (ω, 0) q)`, `R = R(q)`.
fn integrate_positions(bodies: &mut [SolverBody], h: f32) {
    for b in bodies.iter_mut() {
        b.dp += b.v * h;
        b.q = b.q.integrate(b.w, h);
        b.rot = Mat3::from_quat(b.q);
    }
}

/// Write the solver bodies back: centre of mass moved by `Δp`, rotation, velocities,
/// `R I⁻¹ Rᵀ`.
fn finalize<const N: usize, const C: usize>(solver: &Solver<N, C>, bodies: &mut Pool<Body<'_>, N>) {
    for sb in solver.bodies.iter() {
        let Some(b) = bodies.at_mut(sb.slot as usize) else {
            continue;
        };
        let c = b.world_center() + sb.dp;
        b.set_center_pose(c, sb.q);
        b.linear_velocity = sb.v;
        b.angular_velocity = sb.w;
    }
}

/// `v` shortened to at most `max` (m/s or rad/s). A vector too large to square in `f32`
/// is first scaled down by its largest component; one that is not finite stops: zero is
/// the documented answer.
#[inline]
pub(crate) fn clamp_length(v: Vec3, max: f32) -> Vec3 {
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
