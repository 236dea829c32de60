//! The contact rows of the soft step: soft normal rows with a bounded push-out, Coulomb
//! friction with a static and a kinetic coefficient, rolling resistance and twist
//! friction, and the collision pass (restitution).
//!
//! # Notation
//!
//! Per contact point: lever arms `r = p − c` from each centre of mass `c` (world, fixed
//! at prepare), unit normal `n` from A to B, tangents `t₁, t₂` with `(t₁, t₂, n)`
//! right-handed, relative velocity `Δv = (v_b + ω_b × r_b) − (v_a + ω_a × r_a)`, normal
//! speed `v_n = Δv·n` (negative when closing). An impulse `P` acts as `+P` on B and `−P`
//! on A. Along a unit direction `d` the effective mass is
//!
//! ```text
//! m_d = 1 / (1/m_a + 1/m_b + (r_a × d)·I_a⁻¹ (r_a × d) + (r_b × d)·I_b⁻¹ (r_b × d))
//! ```
//!
//! with the world inverse inertia `I⁻¹ = R I_local⁻¹ Rᵀ`. Static, kinematic and sleeping
//! bodies have `1/m = 0`, `I⁻¹ = 0`. Prepare stores the angular Jacobians `r × d` and the
//! products `I⁻¹ (r × d)` of every row, so a row costs a few dot products and no 3×3
//! product.
//!
//! # Lever arms
//!
//! The normal rows' arms are the anchors turned as the bodies were when the manifold was
//! built, `r = R_built (l − c_local)` (`l` the anchor and `c_local` the centre of mass,
//! in body axes), not as they are now: while a manifold is reused (`contact`, "Lever
//! arms kept from the build") the rows keep one linearisation, so a leaning box's large
//! warm-started normal impulses do not tip it further through arms that lean with it;
//! its loaded tower stands (rapier3d keeps its recycled contacts' world arms for the
//! same reason). A rebuild takes the bodies' rotations of that step, and a reuse needs
//! each kept arm within the pair's slack of the body's own. The friction patch, whose
//! centre is re-formed from the points every step, and the closing speeds restitution
//! reads use the current arms.
//!
//! # Separation inside the step
//!
//! Each point keeps its anchors fixed in the two bodies (`l`, relative to the centre of
//! mass, in body axes). After a body moved by `Δp` and turned to `R`, the anchor sits at
//! `Δp + R l` relative to where the centre of mass started, so
//!
//! ```text
//! s = n·(c_b − c_a) − ρ_a − ρ_b + n·((Δp_b + R_b l_b) − (Δp_a + R_a l_a))
//! ```
//!
//! (Box2D v3's `adjustedSeparation`). The anchors are the points of the shapes' *cores*:
//! the surface point moved inwards by the rounding radius `ρ` (a sphere's or capsule's
//! radius, 0 for polytopes), and the separation subtracts `ρ_a + ρ_b` again. For a
//! polytope that is the surface point; for a sphere it is the centre, so a ball spinning
//! fast along a wall does not carry its anchor away from the wall (Box2D's surface
//! anchors would: the contact would read as opening while the ball slides into the
//! wall). The narrow phase runs once per step; every sub-step sees the separation its
//! motion made.
//!
//! # Soft normal row (Catto, "Solver2D"; `SOLVER.md`)
//!
//! For a stiffness `f` (Hz), damping ratio `ζ` and sub-step `h`: `ω = 2π f`,
//! `a₁ = 2ζ + hω`, `a₂ = hω a₁`, `a₃ = 1 / (1 + a₂)`; `bias_rate = ω / a₁` (1/s),
//! `mass_scale = a₂ a₃`, `impulse_scale = a₃`. Then
//!
//! ```text
//! s > 0 (speculative):  bias = s / h,  mass_scale = 1, impulse_scale = 0  (rigid: close the gap, no more)
//! s ≤ 0, solve:         bias = max(mass_scale · bias_rate · s, −max_push_speed), soft scales
//! s ≤ 0, relax:         bias = 0, mass_scale = 1, impulse_scale = 0
//! λ = −m_n (mass_scale · v_n + bias) − impulse_scale · λ_acc,  λ_acc = max(λ_acc + λ, 0)
//! ```
//!
//! (the push-out speed is `mass_scale · bias_rate · s`, at most `max_push_speed`).
//! Contacts against static or kinematic bodies use twice the stiffness (Box2D v3's
//! `staticSoftness`); the stiffness is capped at a quarter of the sub-step rate. As in
//! Box2D v3, no slop is left in place: a stack of `k` boxes would sink `k` slops.
//!
//! # Patch friction, static and kinetic
//!
//! Friction acts once per manifold, at its *friction centre* `c` (the points' mean,
//! weighted by last step's normal impulses), as a 2D impulse in the tangent plane with
//! the coupled 2×2 effective mass `K⁻¹` of the two tangents at `c`:
//!
//! ```text
//! λ_t = clip(λ_t,acc − K⁻¹ v_t(c),  μ Σλ_n)          (disc of the Coulomb cone)
//! λ_τ = clamp(λ_τ,acc − m_τ (ω_b − ω_a)·n,  ±μ Σ λ_n,i d_i)   (twist: d_i = |p_i − c|)
//! ```
//!
//! (rapier's default "simplified" friction model works the same way). Per-point friction
//! rows under Gauss-Seidel load the first points of a manifold before the others, and
//! at a few iterations per step that bias tilts loaded boxes: tall stacks and walls
//! buckled out of plane. One patch row sees the whole manifold at once, and costs three
//! rows instead of eight. Friction, twist and rolling run in both the biased and the
//! relax iterations (*departure* from Box2D v3's latest, which skips them in the biased
//! one: the positions integrated after it then slide by what the push-out's lever arms
//! turned into tangential speed, and a 100-row wall crept sideways).
//!
//! A sticking patch uses `μ = static_friction`, a sliding one `kinetic_friction`:
//!
//! - at prepare a patch *sticks* if it stuck last step, or its tangential speed is
//!   below `stick_speed`, or it carried no normal impulse last step (a new or
//!   speculative manifold has no friction state yet: the solve decides);
//! - in the last relax iteration of the step, a sticking patch that carried a normal
//!   impulse into the step (a new one's normal impulse is still building up), that the
//!   static cone clipped *and* that still slips faster than `stick_speed` after its row
//!   starts sliding, clipped to the kinetic cone at once; a sliding patch whose slip fell
//!   below `stick_speed` sticks again. (Testing the speed at prepare alone fails on a
//!   slope: gravity adds `g h sin θ` of slip before every prepare, so a patch that slid
//!   once would slide for ever.)
//!
//! # Rolling resistance and twist friction of small manifolds
//!
//! Two angular rows along `t₁, t₂` resist the relative rolling `(ω_b − ω_a)` of
//! manifolds with one or two points, clipped to the disc of radius
//! `rolling_resistance · Σλ_n · ℓ`; a single-point manifold's twist row is clipped to
//! `twist_friction · Σλ_n · ℓ` (it has no spread of points to resist twist with). `ℓ` is
//! the lever arm `|r|` of the (smaller) moving body to the first point; the effective
//! mass along an axis `d` is `1 / (d·(I_a⁻¹ + I_b⁻¹) d)`. A flat patch of three or more
//! points does not roll.
//!
//! # Collision pass (restitution)
//!
//! Before the sub-steps, from the velocities at the start of the step (before this
//! step's gravity: a bounce target that included it would add energy every bounce):
//! up to [`MAX_BOUNCE_PASSES`] sweeps over the constraints in order; each constraint
//! with a point closing faster than `restitution_threshold` (measured *now*) whose gap
//! closes within the step gets a transient impulse making those points separate at
//! `e · approach` ([`BOUNCE_ITERATIONS`] rounds over its colliding points, with
//! friction in the cone of that impulse). A sweep that bounces nothing ends the pass.
//! These impulses are not warm-started. Each bounce alone can only lose energy.
//!
//! *Departure from Box2D v3*, which applies restitution after the sub-steps with the
//! normal speed measured at prepare: that speed is seen only by the first contact of a
//! chain of touching bodies, and a Newton's cradle then solves to `−0.6 v, 0.4 v`
//! instead of passing the speed down the row. Measuring the approach when a contact is
//! visited makes the impulse travel along the chain, one contact per sweep at worst.

use super::body::{Body, BodyKind};
use super::contact::Contact;
use super::pool::Pool;
use super::solver::NONE;
use super::solver::{is_active, is_moving_kinematic, SolverBody};
use super::support::{self, Held, Supports};
use crate::config::WorldConfig;
use crate::math::{scalar, Mat3, Vec3};

/// Rounds of the small accumulated solve the collision pass runs over one contact's
/// colliding points. One is exact for a single point; four bring a flat face landing on
/// four points to within a few per cent of the simultaneous answer.
pub(crate) const BOUNCE_ITERATIONS: u32 = 4;

/// Most sweeps of the collision pass (a chain of `k` touching bodies in the worst order
/// needs `k − 1`).
pub(crate) const MAX_BOUNCE_PASSES: u32 = 16;

/// Soft constraint coefficients for one sub-step (module docs).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Softness {
    /// `ω / a₁` (1/s).
    pub bias_rate: f32,
    /// `a₂ a₃`.
    pub mass_scale: f32,
    /// `a₃`.
    pub impulse_scale: f32,
}

impl Softness {
    /// The step's two contact softnesses: `[dynamic–dynamic, against a static or
    /// kinematic body]` (twice the stiffness), the stiffness capped at a quarter of the
    /// sub-step rate.
    pub fn for_contacts(cfg: &WorldConfig) -> [Softness; 2] {
        let h = cfg.substep();
        let hertz = scalar::min(cfg.contact_hertz, 0.25 / h);
        [
            Softness::new(hertz, cfg.contact_damping_ratio, h),
            Softness::new(2.0 * hertz, cfg.contact_damping_ratio, h),
        ]
    }

    /// The coefficients of a spring of `hertz` with damping ratio `zeta`, sub-step `h`.
    pub fn new(hertz: f32, zeta: f32, h: f32) -> Softness {
        if hertz <= 0.0 {
            return Softness {
                bias_rate: 0.0,
                mass_scale: 1.0,
                impulse_scale: 0.0,
            };
        }
        let omega = core::f32::consts::TAU * hertz;
        let a1 = 2.0 * zeta + h * omega;
        let a2 = h * omega * a1;
        let a3 = 1.0 / (1.0 + a2);
        Softness {
            bias_rate: omega / a1,
            mass_scale: a2 * a3,
            impulse_scale: a3,
        }
    }
}

/// One contact point of a constraint: its normal row (module docs for the symbols).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ConstraintPoint {
    /// Core anchor on A relative to A's centre of mass, in A's body axes (m): the
    /// surface point moved in by A's rounding radius (module docs).
    pub local_a: Vec3,
    /// Core anchor on B, as `local_a`.
    pub local_b: Vec3,
    /// Core anchor on A relative to its centre of mass at prepare (world, m).
    pub core_a: Vec3,
    /// Core anchor on B at prepare (world, m).
    pub core_b: Vec3,
    /// `n·(c_b − c_a) − ρ_a − ρ_b` at prepare (m): with the core anchors' motion it gives
    /// the separation.
    pub adjusted_separation: f32,
    /// `r_a × n`, with `r_a` the surface point's lever arm on A at prepare.
    pub rn_a: Vec3,
    /// `r_b × n`.
    pub rn_b: Vec3,
    /// `I_a⁻¹ (r_a × n)`.
    pub in_a: Vec3,
    /// `I_b⁻¹ (r_b × n)`.
    pub in_b: Vec3,
    /// Effective mass along the normal (kg).
    pub normal_mass: f32,
    /// Accumulated normal impulse of a sub-step (N·s).
    pub normal_impulse: f32,
    /// Distance from the friction centre (m): the point's lever against twist.
    pub twist_arm: f32,
    /// Separation at prepare (m).
    pub separation0: f32,
    /// Separation at the last row solved (m).
    pub separation: f32,
    /// Sum of the normal impulses applied this step (N·s): zero when the point never
    /// pushed (a speculative point that was not reached).
    pub total_impulse: f32,
    /// Normal speed `v_n` at prepare, before this step's gravity (m/s); the solve lowers
    /// it to the closing speed the point had when it first pushed (the impact speed,
    /// with the gravity of the sub-steps before it). Read by the restitution passes
    /// only, so 0 (not formed) for a contact without restitution.
    pub normal_speed0: f32,
    /// Bounced by the collision pass before the sub-steps.
    pub bounced: bool,
}

/// The rows of one manifold for one step: a normal row per point, one friction patch
/// (two tangent rows and a twist row at the friction centre), rolling rows.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct ContactConstraint {
    /// Index of the contact in the contact list.
    pub contact: u32,
    /// Pool slot of A.
    pub slot_a: u32,
    /// Pool slot of B.
    pub slot_b: u32,
    /// Solver index of A, or [`NONE`].
    pub a: u32,
    /// Solver index of B, or [`NONE`].
    pub b: u32,
    /// Inverse masses (1/kg), 0 for bodies that do not move.
    pub inv_mass_a: f32,
    /// See `inv_mass_a`.
    pub inv_mass_b: f32,
    /// Unit normal from A to B (world).
    pub normal: Vec3,
    /// Tangents.
    pub tangents: [Vec3; 2],
    /// Points in use.
    pub len: u8,
    /// The points.
    pub points: [ConstraintPoint; 4],
    /// `r_a(c) × tᵢ` at the friction centre `c`.
    pub rt_a: [Vec3; 2],
    /// `r_b(c) × tᵢ`.
    pub rt_b: [Vec3; 2],
    /// `I_a⁻¹ (r_a(c) × tᵢ)`.
    pub it_a: [Vec3; 2],
    /// `I_b⁻¹ (r_b(c) × tᵢ)`.
    pub it_b: [Vec3; 2],
    /// The inverse of the 2×2 tangent effective mass matrix at `c`: `[xx, xy, yy]`.
    pub tangent_mass: [f32; 3],
    /// Accumulated friction impulse along the tangents (N·s).
    pub tangent_impulse: [f32; 2],
    /// `I_a⁻¹ t₁, I_a⁻¹ t₂, I_a⁻¹ n` (rolling and twist rows).
    pub ia_axes: [Vec3; 3],
    /// `I_b⁻¹ t₁, I_b⁻¹ t₂, I_b⁻¹ n`.
    pub ib_axes: [Vec3; 3],
    /// Effective masses of the rolling (t₁, t₂) and twist (n) rows (kg·m²).
    pub axis_mass: [f32; 3],
    /// Accumulated rolling (t₁, t₂) and twist (n) angular impulses (N·m·s).
    pub angular_impulse: [f32; 3],
    /// Static and kinetic friction coefficients.
    pub friction: [f32; 2],
    /// Coefficient of restitution.
    pub restitution: f32,
    /// Largest rolling impulse per unit of total normal impulse (m), 0 when off.
    pub rolling: f32,
    /// Largest twist impulse per unit of total normal impulse of a single-point
    /// manifold (m), 0 when off.
    pub twist: f32,
    /// Soft coefficients of the normal rows.
    pub softness: Softness,
    /// `ρ_a + ρ_b`: the shapes' rounding radii (sphere and capsule radius, 0 otherwise).
    pub radius_sum: f32,
    /// True while the patch sticks (static friction).
    pub sticking: bool,
    /// The manifold carried a normal impulse into this step (it is not new): only such a
    /// patch may start sliding, once its normal impulse has settled.
    pub established: bool,
    /// No normal impulse of this contact turns a body ([`torque_free`]): its friction,
    /// twist and rolling rows are left to the relax passes.
    pub torque_free: bool,
}

/// A sleeping dynamic body that an awake dynamic or moving kinematic body touches or
/// reaches within `dt` wakes, so a hit on a sleeping stack moves the body it hits
/// (`sleep.rs` wakes the rest of its island at the end of the step).
pub(crate) fn wake_touched_sleepers<const N: usize>(
    c: &Contact,
    bodies: &mut Pool<Body<'_>, N>,
    dt: f32,
) {
    if c.sensor || c.len == 0 {
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
    let reached = c.points().iter().any(|p| {
        let p_a = a.pose().transform_point(p.local_a);
        let p_b = b.pose().transform_point(p.local_b);
        let approach = -(b.velocity_at(p_b) - a.velocity_at(p_a)).dot(n);
        closes_within(p.separation, approach, dt)
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

/// Whether a point `s` metres apart, closing at `approach` m/s, touches within `dt`
/// seconds (a touching or penetrating point always does).
#[inline]
fn closes_within(separation: f32, approach: f32, dt: f32) -> bool {
    separation <= 0.0 || approach * dt > separation
}

/// True when the body in pool slot `slot` is static or kinematic (or missing): one side
/// of a contact with a rigid partner, which the plan visits after the others.
#[inline]
pub(crate) fn is_rigid<const N: usize>(slot: u32, bodies: &Pool<Body<'_>, N>) -> bool {
    bodies
        .at(slot as usize)
        .is_none_or(|b| b.kind != BodyKind::Dynamic)
}

/// `1 / k` for `k > 0` finite, else 0 (nothing moves along that row). The scalar oracle
/// of `F4::recip_or_zero`, which the wide prepare uses.
#[cfg(test)]
#[inline]
pub(crate) fn inverse_or_zero(k: f32) -> f32 {
    if k > 0.0 && k.is_finite() {
        1.0 / k
    } else {
        0.0
    }
}

/// The two bodies of a contact that pushes, as the rows see them.
pub(crate) struct Sides<'s, 'a> {
    /// Body A.
    pub body_a: &'s Body<'a>,
    /// Body B.
    pub body_b: &'s Body<'a>,
    /// A's solver body, `None` for a body that does not move in the solve.
    pub sa: Option<&'s SolverBody>,
    /// B's solver body.
    pub sb: Option<&'s SolverBody>,
    /// A's solver index ([`NONE`] without a solver body).
    pub ia: u32,
    /// B's solver index.
    pub ib: u32,
    /// A's inverse mass (1/kg), 0 without a solver body.
    pub m_a: f32,
    /// A's world inverse inertia, 0 without a solver body.
    pub i_a: Mat3,
    /// B's inverse mass.
    pub m_b: f32,
    /// B's world inverse inertia.
    pub i_b: Mat3,
    /// One side holds up a far heavier other (`support.rs`): its inverse mass and
    /// inertia above are scaled so that it weighs `1 / HEAVY_RATIO` of the other.
    pub capped: bool,
}

/// A contact whose normal line passes through the centre of mass of every body it can
/// turn: each side is a ball (the normal runs through its centre) or does not turn in
/// the solve (static, kinematic or sleeping: not a dynamic body with a solver entry).
/// Its normal rows then change linear velocities only, so the push-out of the soft
/// passes gives its points no tangential slip and no spin for friction to answer there:
/// the relax passes (which follow each position update) solve its friction, twist and
/// rolling rows alone. Half the friction work of a pile of balls; a box's off-centre
/// push-out, which does turn it, keeps its friction in both passes (a box landing flat
/// on a tessellated plane walks 8 mm without).
pub(crate) fn torque_free(side: &Sides<'_, '_>) -> bool {
    let round = |body: &Body<'_>, solved: bool| {
        !solved
            || body.kind != BodyKind::Dynamic
            || matches!(body.shape, crate::shape::Shape::Sphere(_))
    };
    round(side.body_a, side.sa.is_some()) && round(side.body_b, side.sb.is_some())
}

/// The [`Sides`] of contact `c`, or `None` when it does not push: a sensor, no point, a
/// missing body, or no moving dynamic body. `CAPPED` in a step where a contact's mass
/// ratio may be capped, as `supports` says (`support.rs`); the other steps run without
/// the test.
#[inline(always)]
pub(crate) fn sides<'s, 'a, const N: usize, const CAPPED: bool>(
    c: &Contact,
    bodies: &'s Pool<Body<'a>, N>,
    solver_bodies: &'s [SolverBody],
    solver_index: &[u32; N],
    supports: &Supports<'_>,
) -> Option<Sides<'s, 'a>> {
    if c.sensor || c.len == 0 {
        return None;
    }
    let (Some(body_a), Some(body_b)) = (bodies.at(c.a as usize), bodies.at(c.b as usize)) else {
        return None;
    };
    let ia = solver_index.get(c.a as usize).copied().unwrap_or(NONE);
    let ib = solver_index.get(c.b as usize).copied().unwrap_or(NONE);
    let sa = solver_bodies.get(ia as usize);
    let sb = solver_bodies.get(ib as usize);
    let (m_a, i_a) = sa.map_or((0.0, Mat3::ZERO), |s| (s.inv_mass, s.inv_inertia));
    let (m_b, i_b) = sb.map_or((0.0, Mat3::ZERO), |s| (s.inv_mass, s.inv_inertia));
    if m_a <= 0.0 && m_b <= 0.0 {
        return None;
    }
    let mut side = Sides {
        body_a,
        body_b,
        sa,
        sb,
        ia,
        ib,
        m_a,
        i_a,
        m_b,
        i_b,
        capped: false,
    };
    // Under a far heavier body, the lighter support weighs a twentieth of it in this
    // contact (`support.rs`); only in an island the ground holds up, in a step with a
    // heavy contact.
    if CAPPED {
        if let (Some(a), Some(b)) = (sa, sb) {
            if supports.held(ia) {
                let held = support::held_side(a, b, c.normal, supports.gravity);
                cap_support_mass(&mut side, held);
            }
        }
    }
    Some(side)
}

/// Cap the mass ratio of `side` as `held` says: the holding side's inverse mass and
/// inertia scaled by `HEAVY_RATIO · m_heavy⁻¹ / m_support⁻¹` (below 1), so that it weighs
/// `1 / HEAVY_RATIO` of the heavy body in the contact's rows.
#[inline(never)]
fn cap_support_mass(side: &mut Sides<'_, '_>, held: Held) {
    match held {
        Held::SupportA => {
            let s = support::HEAVY_RATIO * side.m_b / side.m_a;
            (side.m_a, side.i_a) = (side.m_a * s, side.i_a.scale(s));
        }
        Held::SupportB => {
            let s = support::HEAVY_RATIO * side.m_a / side.m_b;
            (side.m_b, side.i_b) = (side.m_b * s, side.i_b.scale(s));
        }
        Held::Neither => return,
    }
    side.capped = true;
}

/// Fill `k` with the constraint of contact `index`; false when it does not push: a
/// sensor, no point, or no moving dynamic body. The reference the wide prepare
/// (`wide/prepare.rs`, which the solver runs) is tested against, lane for lane.
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
pub(crate) fn prepare<const N: usize>(
    c: &Contact,
    index: u32,
    bodies: &Pool<Body<'_>, N>,
    solver_bodies: &[SolverBody],
    solver_index: &[u32; N],
    softness: &[Softness; 2],
    supports: Option<&Supports<'_>>,
    cfg: &WorldConfig,
    k: &mut ContactConstraint,
) -> bool {
    let side = match supports {
        Some(s) => sides::<N, true>(c, bodies, solver_bodies, solver_index, s),
        None => sides::<N, false>(c, bodies, solver_bodies, solver_index, &Supports::NONE),
    };
    let Some(side) = side else {
        return false;
    };
    let (body_a, body_b, sa, sb) = (side.body_a, side.body_b, side.sa, side.sb);
    let (ia, ib) = (side.ia, side.ib);
    let (m_a, i_a, m_b, i_b) = (side.m_a, side.i_a, side.m_b, side.i_b);
    let n = c.normal;
    let t1 = n.any_perpendicular();
    let t2 = n.cross(t1);
    // Twice the stiffness against a body that does not respond (static or kinematic)
    // and against a capped support, which gives way a twentieth as much as this body.
    let rigid_partner =
        body_a.kind != BodyKind::Dynamic || body_b.kind != BodyKind::Dynamic || side.capped;
    let center_a = body_a.world_center();
    let center_b = body_b.world_center();
    let (va, wa) = sa.map_or((Vec3::ZERO, Vec3::ZERO), |s| (s.v, s.w));
    let (vb, wb) = sb.map_or((Vec3::ZERO, Vec3::ZERO), |s| (s.v, s.w));
    let m = c.material;
    let (rho_a, rho_b) = (body_a.shape.radius(), body_b.shape.radius());
    // Every field is written below (the patch and angular rows in their functions); the
    // points past `len` keep what they held, and nothing reads them.
    k.contact = index;
    k.slot_a = c.a;
    k.slot_b = c.b;
    k.a = if sa.is_some() { ia } else { NONE };
    k.b = if sb.is_some() { ib } else { NONE };
    k.inv_mass_a = m_a;
    k.inv_mass_b = m_b;
    k.normal = n;
    k.tangents = [t1, t2];
    k.len = 0;
    k.friction = [m.static_friction, m.kinetic_friction];
    k.restitution = m.restitution;
    k.softness = if rigid_partner {
        softness[1]
    } else {
        softness[0]
    };
    k.radius_sum = rho_a + rho_b;
    // Warm-start impulses are bounded: none may change a normal speed by more than twice
    // the speed limit plus the push-out (a real one never comes near). So no stored
    // impulse, however it came to be (a crafted snapshot included), can send a body to a
    // non-finite speed.
    let speed_bound = 2.0 * cfg.max_linear_speed + cfg.max_push_speed;
    let mut plain = Vec3::ZERO;
    let mut carried = 0.0f32;
    let mut largest = 0.0f32;
    let mut mids = [Vec3::ZERO; 4];
    let (now_a, now_b) = (
        Mat3::from_quat(body_a.pose().rotation),
        Mat3::from_quat(body_b.pose().rotation),
    );
    // A manifold never reused (a sphere pair's, `built_margin` < 0) takes its arms as
    // the bodies turn now; a built one was built at the rotations it keeps.
    let (built_a, built_b) = if c.built_margin < 0.0 {
        (now_a, now_b)
    } else {
        (
            Mat3::from_quat(c.built_rot_a),
            Mat3::from_quat(c.built_rot_b),
        )
    };
    // A solver body's anchors are in its axes: `d − Rᵀ n ρ` (the core's point).
    let n_rho_local_a = sa.map(|_| now_a.transpose_mul_vec(n) * rho_a);
    let n_rho_local_b = sb.map(|_| now_b.transpose_mul_vec(n) * rho_b);
    for (dst, p) in k.points.iter_mut().zip(c.points()) {
        // The anchors about the centres of mass, in body axes, and turned as now.
        let d_a = p.local_a - body_a.center_local;
        let d_b = p.local_b - body_b.center_local;
        let r_a = now_a.mul_vec(d_a);
        let r_b = now_b.mul_vec(d_b);
        let p_a = center_a + r_a;
        let p_b = center_b + r_b;
        // The cores' points: a sphere's is its centre, so its spin does not carry the
        // anchor away from the contact.
        let core_a = r_a - n * rho_a;
        let core_b = r_b + n * rho_b;
        // The rows' lever arms: the anchors turned as the bodies were at the build.
        let kept_a = built_a.mul_vec(d_a);
        let kept_b = built_b.mul_vec(d_b);
        let rn_a = kept_a.cross(n);
        let rn_b = kept_b.cross(n);
        let in_a = i_a.mul_vec(rn_a);
        let in_b = i_b.mul_vec(rn_b);
        let normal_mass = inverse_or_zero(m_a + m_b + rn_a.dot(in_a) + rn_b.dot(in_b));
        let vn = if k.restitution > 0.0 {
            ((vb + wb.cross(r_b)) - (va + wa.cross(r_a))).dot(n)
        } else {
            0.0
        };
        let normal_impulse = scalar::min(p.normal_impulse, normal_mass * speed_bound);
        *dst = ConstraintPoint {
            local_a: n_rho_local_a.map_or(core_a, |m| d_a - m),
            local_b: n_rho_local_b.map_or(core_b, |m| d_b + m),
            core_a,
            core_b,
            adjusted_separation: n.dot(center_b - center_a) - k.radius_sum,
            rn_a,
            rn_b,
            in_a,
            in_b,
            normal_mass,
            normal_impulse,
            twist_arm: 0.0,
            separation0: p.separation,
            separation: p.separation,
            total_impulse: 0.0,
            normal_speed0: vn,
            bounced: false,
        };
        let mid = (p_a + p_b) * 0.5;
        if let Some(m) = mids.get_mut(usize::from(k.len)) {
            *m = mid;
        }
        plain += mid;
        carried += normal_impulse;
        largest = scalar::max(largest, normal_impulse);
        k.len += 1;
    }
    let count = f32::from(k.len);
    // The points' mean weighted by last step's normal impulses, each relative to the
    // largest (so the weights lie in [0, 1] and sum to at least 1 whatever the impulses'
    // scale: subnormal impulses cannot divide by zero).
    let center = if largest > 0.0 {
        let mut weighted = Vec3::ZERO;
        let mut weight = 0.0f32;
        for (p, mid) in k.points.iter().zip(mids).take(usize::from(k.len)) {
            let w = p.normal_impulse / largest;
            weighted += mid * w;
            weight += w;
        }
        weighted * (1.0 / weight)
    } else {
        plain * (1.0 / count)
    };
    // Each point's twist arm: its distance from the centre, measured at the midpoint
    // between its two surface points.
    for (p, mid) in k.points.iter_mut().zip(mids).take(usize::from(k.len)) {
        p.twist_arm = (mid - center).length();
    }
    prepare_patch(
        k,
        c,
        center - center_a,
        center - center_b,
        &i_a,
        &i_b,
        va,
        wa,
        vb,
        wb,
        cfg,
    );
    k.established = carried > 0.0;
    k.torque_free = torque_free(&side);
    prepare_angular_rows(
        k,
        &i_a,
        &i_b,
        center - center_a,
        center - center_b,
        m.rolling_resistance,
        m.twist_friction,
    );
    true
}

/// The friction patch at the centre (lever arms `r_a`, `r_b`): Jacobians, the inverse
/// tangent mass matrix, the warm-start impulse (kept in the static cone) and the
/// sticking state (module docs).
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
fn prepare_patch(
    k: &mut ContactConstraint,
    c: &Contact,
    r_a: Vec3,
    r_b: Vec3,
    i_a: &Mat3,
    i_b: &Mat3,
    va: Vec3,
    wa: Vec3,
    vb: Vec3,
    wb: Vec3,
    cfg: &WorldConfig,
) {
    let [t1, t2] = k.tangents;
    let n = k.normal;
    k.rt_a = [r_a.cross(t1), r_a.cross(t2)];
    k.rt_b = [r_b.cross(t1), r_b.cross(t2)];
    k.it_a = [i_a.mul_vec(k.rt_a[0]), i_a.mul_vec(k.rt_a[1])];
    k.it_b = [i_b.mul_vec(k.rt_b[0]), i_b.mul_vec(k.rt_b[1])];
    let m = k.inv_mass_a + k.inv_mass_b;
    let kxx = m + k.rt_a[0].dot(k.it_a[0]) + k.rt_b[0].dot(k.it_b[0]);
    let kyy = m + k.rt_a[1].dot(k.it_a[1]) + k.rt_b[1].dot(k.it_b[1]);
    let kxy = k.rt_a[0].dot(k.it_a[1]) + k.rt_b[0].dot(k.it_b[1]);
    let det = kxx * kyy - kxy * kxy;
    k.tangent_mass = if det > 0.0 && det.is_finite() {
        let inv = 1.0 / det;
        [kyy * inv, -kxy * inv, kxx * inv]
    } else {
        [inverse_or_zero(kxx), 0.0, inverse_or_zero(kyy)]
    };
    let total: f32 = k
        .points
        .iter()
        .take(usize::from(k.len))
        .map(|p| p.normal_impulse)
        .sum();
    let tangent = c.friction_impulse - n * c.friction_impulse.dot(n);
    let (clipped, _) = clip_to_disc([tangent.dot(t1), tangent.dot(t2)], k.friction[0] * total);
    k.tangent_impulse = clipped;
    let dv = (vb + wb.cross(r_b)) - (va + wa.cross(r_a));
    let slip = dv - n * dv.dot(n);
    k.sticking =
        c.sticking || slip.length_squared() < cfg.stick_speed * cfg.stick_speed || total <= 0.0;
    let twist_limit = k.friction[0] * twist_lever_sum(k);
    let twist = scalar::clamp(c.twist_impulse, -twist_limit, twist_limit);
    k.angular_impulse = [0.0, 0.0, twist];
}

/// `Σ λ_n,i d_i`: the twist the patch's normal impulses can hold per unit of friction.
#[cfg(test)]
#[inline]
fn twist_lever_sum(k: &ContactConstraint) -> f32 {
    let mut s = 0.0f32;
    for p in k.points.iter().take(usize::from(k.len)) {
        s += p.normal_impulse * p.twist_arm;
    }
    s
}

/// Rolling rows for manifolds of one or two points, the single-point twist coefficient,
/// and the angular effective masses (module docs).
#[cfg(test)]
#[allow(clippy::too_many_arguments)]
fn prepare_angular_rows(
    k: &mut ContactConstraint,
    i_a: &Mat3,
    i_b: &Mat3,
    r_a: Vec3,
    r_b: Vec3,
    rolling: f32,
    twist: f32,
) {
    let rolls = k.len <= 2 && rolling > 0.0;
    let twists = k.len == 1 && twist > 0.0;
    k.rolling = 0.0;
    k.twist = 0.0;
    k.ia_axes = [Vec3::ZERO; 3];
    k.ib_axes = [Vec3::ZERO; 3];
    k.axis_mass = [0.0; 3];
    if rolls || twists {
        let lever = match (k.inv_mass_a > 0.0, k.inv_mass_b > 0.0) {
            (true, true) => scalar::min(r_a.length(), r_b.length()),
            (true, false) => r_a.length(),
            _ => r_b.length(),
        };
        k.rolling = if rolls { rolling * lever } else { 0.0 };
        k.twist = if twists { twist * lever } else { 0.0 };
    }
    let [t1, t2] = k.tangents;
    let axes = [t1, t2, k.normal];
    // The tangent rows only when the manifold rolls; the twist row always (the patch).
    let first = if k.rolling > 0.0 { 0 } else { 2 };
    for (i, d) in axes.iter().enumerate().skip(first) {
        let ia = i_a.mul_vec(*d);
        let ib = i_b.mul_vec(*d);
        if let (Some(x), Some(y), Some(m)) = (
            k.ia_axes.get_mut(i),
            k.ib_axes.get_mut(i),
            k.axis_mass.get_mut(i),
        ) {
            *x = ia;
            *y = ib;
            *m = inverse_or_zero(d.dot(ia) + d.dot(ib));
        }
    }
}

/// Velocities of a solver body (zero for [`NONE`]).
#[inline]
fn velocities(bodies: &[SolverBody], i: u32) -> (Vec3, Vec3) {
    bodies
        .get(i as usize)
        .map_or((Vec3::ZERO, Vec3::ZERO), |b| (b.v, b.w))
}

/// Write velocities back (ignored for [`NONE`]).
#[inline]
fn set_velocities(bodies: &mut [SolverBody], i: u32, v: Vec3, w: Vec3) {
    if let Some(b) = bodies.get_mut(i as usize) {
        b.v = v;
        b.w = w;
    }
}

/// The working state of one constraint's two bodies while its rows run.
struct Pair {
    va: Vec3,
    wa: Vec3,
    vb: Vec3,
    wb: Vec3,
}

impl Pair {
    #[inline]
    fn load(k: &ContactConstraint, bodies: &[SolverBody]) -> Pair {
        let (va, wa) = velocities(bodies, k.a);
        let (vb, wb) = velocities(bodies, k.b);
        Pair { va, wa, vb, wb }
    }

    #[inline]
    fn save(&self, k: &ContactConstraint, bodies: &mut [SolverBody]) {
        set_velocities(bodies, k.a, self.va, self.wa);
        set_velocities(bodies, k.b, self.vb, self.wb);
    }

    /// Normal speed `v_n` at point `p`.
    #[inline]
    fn normal_speed(&self, n: Vec3, p: &ConstraintPoint) -> f32 {
        n.dot(self.vb - self.va) + self.wb.dot(p.rn_b) - self.wa.dot(p.rn_a)
    }

    /// Tangential speeds along `t₁, t₂` at the friction centre.
    #[inline]
    fn tangent_speeds(&self, k: &ContactConstraint) -> [f32; 2] {
        let dv = self.vb - self.va;
        let [t1, t2] = k.tangents;
        [
            t1.dot(dv) + self.wb.dot(k.rt_b[0]) - self.wa.dot(k.rt_a[0]),
            t2.dot(dv) + self.wb.dot(k.rt_b[1]) - self.wa.dot(k.rt_a[1]),
        ]
    }

    /// Apply `λ` along the normal at `p`.
    #[inline]
    fn push_normal(&mut self, k: &ContactConstraint, p: &ConstraintPoint, lambda: f32) {
        let j = k.normal * lambda;
        self.va -= j * k.inv_mass_a;
        self.wa -= p.in_a * lambda;
        self.vb += j * k.inv_mass_b;
        self.wb += p.in_b * lambda;
    }

    /// Apply `(λ₁, λ₂)` along the tangents at the friction centre.
    #[inline]
    fn push_tangent(&mut self, k: &ContactConstraint, l: [f32; 2]) {
        let [t1, t2] = k.tangents;
        let j = t1 * l[0] + t2 * l[1];
        self.va -= j * k.inv_mass_a;
        self.wa -= k.it_a[0] * l[0] + k.it_a[1] * l[1];
        self.vb += j * k.inv_mass_b;
        self.wb += k.it_b[0] * l[0] + k.it_b[1] * l[1];
    }
}

/// `v` shortened to length at most `radius` (a non-positive radius gives zero), and
/// whether it was shortened.
#[inline]
pub(crate) fn clip_to_disc(v: [f32; 2], radius: f32) -> ([f32; 2], bool) {
    if radius.is_nan() || radius <= 0.0 {
        return ([0.0, 0.0], v != [0.0, 0.0]);
    }
    let l2 = v[0] * v[0] + v[1] * v[1];
    if l2 > radius * radius {
        let s = radius / scalar::sqrt(l2);
        ([v[0] * s, v[1] * s], true)
    } else {
        (v, false)
    }
}

/// One constraint of one sweep of the collision pass (module docs): true when some
/// point bounced. Only points already within the speculative margin at the start of the
/// step bounce here; points further out are stopped at the surface by their speculative
/// rows and bounce in [`restitution`] after the sub-steps. The transient impulse makes
/// the colliding points separate at `e · approach`, with patch friction in the cone of
/// that impulse.
pub(crate) fn bounce_constraint(
    k: &mut ContactConstraint,
    bodies: &mut [SolverBody],
    cfg: &WorldConfig,
) -> bool {
    let e = k.restitution;
    if e <= 0.0 {
        return false;
    }
    let mut pair = Pair::load(k, bodies);
    let n = k.normal;
    let len = usize::from(k.len);
    let mut target = [0.0f32; 4];
    let mut hit = [false; 4];
    let mut any = false;
    for i in 0..len {
        let (Some(p), Some(t), Some(h)) = (k.points.get(i), target.get_mut(i), hit.get_mut(i))
        else {
            break;
        };
        let approach = -pair.normal_speed(n, p);
        let near = p.separation0 <= cfg.speculative_margin;
        if near
            && approach > cfg.restitution_threshold
            && closes_within(p.separation0, approach, cfg.dt)
        {
            *h = true;
            *t = e * approach;
            any = true;
        }
    }
    if !any {
        return false;
    }
    let [mu_s, mu_k] = k.friction;
    let mu = if k.sticking { mu_s } else { mu_k };
    let [mxx, mxy, myy] = k.tangent_mass;
    let mut normal = [0.0f32; 4];
    let mut tangent = [0.0f32; 2];
    for _ in 0..BOUNCE_ITERATIONS {
        let v = pair.tangent_speeds(k);
        let total: f32 = normal.iter().sum();
        let wanted = [
            tangent[0] - (mxx * v[0] + mxy * v[1]),
            tangent[1] - (mxy * v[0] + myy * v[1]),
        ];
        let (new, _) = clip_to_disc(wanted, mu * total);
        pair.push_tangent(k, [new[0] - tangent[0], new[1] - tangent[1]]);
        tangent = new;
        for i in 0..len {
            let (Some(p), Some(true), Some(t), Some(lambda)) = (
                k.points.get(i),
                hit.get(i).copied(),
                target.get(i),
                normal.get_mut(i),
            ) else {
                continue;
            };
            let vn = pair.normal_speed(n, p);
            let new = scalar::max(*lambda - p.normal_mass * (vn - *t), 0.0);
            pair.push_normal(k, p, new - *lambda);
            *lambda = new;
        }
    }
    pair.save(k, bodies);
    for (p, h) in k.points.iter_mut().zip(hit) {
        p.bounced |= h;
    }
    true
}

/// The restitution pass after the sub-steps (Box2D v3's `b2ApplyRestitution`) for one
/// constraint, for the points the collision pass left alone: a point that closed faster
/// than the threshold when it hit (`v_n0 < −threshold`, the closing speed when it first
/// pushed) during the sub-steps (a speculative point far away at the start of the step,
/// stopped at the surface by its row) gets `λ = −m_n (v_n + e v_n0)`, `≥ 0`, in a pass of
/// its own (not warm-started). *Departure from Box2D*, which takes `v_n0` at prepare: a
/// ball that falls for part of the step before it hits would bounce with the speed it
/// had at the step's start, losing `g · Δt` (2 % per bounce from 10 m).
pub(crate) fn restitution(k: &ContactConstraint, bodies: &mut [SolverBody], cfg: &WorldConfig) {
    let mut pair = Pair::load(k, bodies);
    let mut any = false;
    for p in k.points.iter().take(usize::from(k.len)) {
        if p.bounced || p.normal_speed0 > -cfg.restitution_threshold || p.total_impulse <= 0.0 {
            continue;
        }
        let vn = pair.normal_speed(k.normal, p);
        let lambda = scalar::max(-p.normal_mass * (vn + k.restitution * p.normal_speed0), 0.0);
        pair.push_normal(k, p, lambda);
        any = true;
    }
    if any {
        pair.save(k, bodies);
    }
}
