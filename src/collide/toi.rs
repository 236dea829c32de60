//! Time of impact of two moving shapes by conservative advancement on GJK distance, with
//! a bounded march and bisection as the fallback; and movement bounds for the broad phase.
//!
//! # Conservative advancement
//!
//! Mirtich, "Impulse-based dynamic simulation of rigid body systems" (1996), ch. 5, and
//! Tang, Kim and Manocha, "C²A: controlled conservative advancement" (2009). At a time
//! `t` with gap `d > 0` and unit normal `n` (A towards B), the separation of the two
//! shapes along the fixed axis `n`,
//!
//! ```text
//! s(τ) = min_{y ∈ B(τ)} n·y − max_{x ∈ A(τ)} n·x,      s(t) = d,
//! ```
//!
//! lower-bounds their distance while it is positive. A point `x` of A moves with
//! `v_a + ω_a × r`, `r = x − c_a`, so `n·ẋ = n·v_a + ω_a·(r × n) <= n·v_a + |ω_a⊥| ρ_a`,
//! with `ω_a⊥ = ω_a − (ω_a·n) n` (spin about `n` itself moves nothing along `n`) and `ρ_a`
//! the largest distance of a core point from A's local origin (the radius that inflates a
//! sphere or capsule does not move under a rotation about the origin, so it does not
//! count). Hence
//!
//! ```text
//! s(τ) >= d − μ (τ − t),      μ = (v_a − v_b)·n + |ω_a⊥| ρ_a + |ω_b⊥| ρ_b     (m/s),
//! ```
//!
//! for every `τ >= t`. Stepping `Δ = (d − tol/2) / μ` keeps the shapes at least `tol/2`
//! apart on `[t, t + Δ]`; the loop stops when the gap is at most `tol`, so a hit is
//! reported with the gap in `[tol/2, tol]` up to GJK's accuracy. If `μ <= 0` the gap can
//! never shrink: separated.
//!
//! The rotation is the step's integrator, `q(τ) = normalise(q₀ + ½ τ (ω, 0) q₀)`: a
//! rotation about the fixed axis `ω` by the angle `φ(τ) = 2 atan(|ω| τ / 2)`, whose rate
//! `|ω| / (1 + (|ω| τ / 2)²)` never exceeds `|ω|`. So the bound above holds for it.
//!
//! # Fallback
//!
//! Advancement crawls when `μ` is much larger than the real closing speed (a fast spin
//! with a near miss). After [`MAX_TOI_ITERATIONS`] advances the rest of `[t, t_max]` is
//! marched in at least [`TOI_MARCH_STEPS`] equal steps (a step is longer when the bound
//! allows it); the first sample within the tolerance is bracketed with the previous one
//! and the crossing of `distance = tolerance` is found by [`MAX_TOI_BISECTIONS`] rounds of
//! bisection. Only this fallback can miss a contact: one that starts and ends between two
//! march samples. Measured on random close pairs of boxes, capsules, hulls and spheres:
//! no miss while the two shapes turn less than about 20 rad in total over `[0, t_max]`
//! (over 3 turns; a 1/60 s step at 1000 rad/s); misses appear beyond that. The turn is not
//! the whole story: what counts is how long the contact lasts against one march step, so
//! a large shape spinning fast past a small one can be missed at a smaller turn (fuzz
//! input `fuzz/open/toi/spinning-hull-passes-a-small-sphere-357f321c`: a 7.6 m hull at
//! 40 rad/s, 5.2 rad in all, comes within 7 cm of a 16 cm sphere, exhausts the advances
//! there and marches past a contact shorter than a march step: `Separated`; an open
//! finding, see FUZZING.md).

use super::{check_pose, distance_in_a, SimplexCache};
use crate::error::{finite_vec, positive, Error, Input};
use crate::math::{scalar, Aabb, Iso, Vec3};
use crate::shape::Shape;

/// Iteration cap of the time-of-impact loop: conservative advances before the fallback.
pub const MAX_TOI_ITERATIONS: u32 = 64;

/// Fewest equal steps the fallback march takes over what is left of `[0, t_max]`.
pub(crate) const TOI_MARCH_STEPS: u32 = 32;

/// Rounds of bisection that locate the crossing of `distance = tolerance` in the fallback.
/// 24 rounds shrink the bracket below one `f32` ulp of the time for any bracket.
pub(crate) const MAX_TOI_BISECTIONS: u32 = 24;

/// Relative size of the slack that [`movement_bounds`] adds for rounding: about 8 ulp of
/// the coordinates and sizes involved.
const BOUNDS_ROUNDING: f32 = 1.0e-6;

/// A body's motion over one step: it starts at `pose` and moves with constant `linear`
/// (m/s) and `angular` (rad/s, world frame) velocity.
#[derive(Clone, Copy, Debug, PartialEq, Default)]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
pub struct Motion {
    /// Pose at time 0.
    pub pose: Iso,
    /// Linear velocity of the shape's local origin (m/s).
    pub linear: Vec3,
    /// Angular velocity about the shape's local origin (rad/s, world frame).
    pub angular: Vec3,
}

impl Motion {
    /// The pose at time `t` seconds: position `p + v t`, rotation integrated as in the step.
    pub fn pose_at(&self, t: f32) -> Iso {
        Iso::new(
            self.pose.position + self.linear * t,
            self.pose.rotation.integrate(self.angular, t),
        )
    }
}

/// The answer of [`time_of_impact`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Toi {
    /// The shapes come within the tolerance at `time`.
    Hit {
        /// Time of impact (s), in `[0, t_max]`.
        time: f32,
        /// Unit normal from A towards B at impact (world frame).
        normal: Vec3,
        /// Closest point on A at impact (world frame).
        point_a: Vec3,
        /// Closest point on B at impact (world frame).
        point_b: Vec3,
    },
    /// The shapes do not touch before `t_max`.
    Separated,
    /// The shapes already overlap at time 0.
    Overlapping,
}

/// When `a` and `b`, moving as `motion_a` and `motion_b`, first come within `tolerance`
/// metres of each other in `[0, t_max]` seconds.
///
/// - [`Toi::Overlapping`]: the shapes touch or overlap at time 0 (distance 0).
/// - [`Toi::Hit`]: at `time` the gap is in `(0, tolerance]` (about `tolerance/2` after an
///   advancement step) and the shapes did not touch before. Normal and points are GJK's
///   at that time, in the world frame. A gap within the tolerance at time 0 gives
///   `time = 0`. (One rare exception, in the fallback: when the gap drops from above the
///   tolerance to contact within one `f32` ulp of time, the last time above it.)
/// - [`Toi::Separated`]: the shapes do not touch in `[0, t_max]`; they may still come
///   closer than `tolerance` without touching.
///
/// The work is bounded: at most `1 + MAX_TOI_ITERATIONS + TOI_MARCH_STEPS + 1 +
/// MAX_TOI_BISECTIONS` = 122 GJK calls; a head-on approach takes 2 or 3. See the module
/// docs for the method and its one blind spot (the fallback march).
///
/// Fails on an invalid pose, a non-finite velocity, a non-positive or non-finite `t_max`
/// or `tolerance`.
pub fn time_of_impact(
    a: &Shape,
    motion_a: &Motion,
    b: &Shape,
    motion_b: &Motion,
    t_max: f32,
    tolerance: f32,
) -> Result<Toi, Error> {
    for m in [motion_a, motion_b] {
        check_pose(&m.pose)?;
        finite_vec(m.linear, Input::LinearVelocity)?;
        finite_vec(m.angular, Input::AngularVelocity)?;
    }
    positive(t_max, Input::Time)?;
    positive(tolerance, Input::Distance)?;
    Ok(time_of_impact_unchecked(
        a, motion_a, b, motion_b, t_max, tolerance,
    ))
}

/// [`time_of_impact`] without input checks (finite motions with unit rotations, positive
/// finite `t_max` and `tolerance`). Never panics; on other input the answer is
/// unspecified but the time stays in `[0, t_max]`.
pub(crate) fn time_of_impact_unchecked(
    a: &Shape,
    motion_a: &Motion,
    b: &Shape,
    motion_b: &Motion,
    t_max: f32,
    tolerance: f32,
) -> Toi {
    let mut pair = MovingPair::new(a, motion_a, b, motion_b);
    let start = pair.sample(0.0);
    if !apart(start.distance) {
        return Toi::Overlapping;
    }
    if start.distance <= tolerance {
        return start.hit();
    }
    let target = 0.5 * tolerance;
    // The last sample known to be apart, with no contact anywhere before it.
    let mut safe = start;
    for _ in 0..MAX_TOI_ITERATIONS {
        let speed = pair.closing_speed_bound(safe.normal);
        if !closing(speed) {
            return Toi::Separated;
        }
        let t = safe.time + (safe.distance - target) / speed;
        if t.is_nan() || t > t_max {
            return Toi::Separated;
        }
        if t <= safe.time {
            break; // the step underflowed the clock: let the march take over
        }
        let s = pair.sample(t);
        if !apart(s.distance) {
            // GJK or rounding error made the step overshoot into contact.
            return pair.bisect_crossing(safe, s, tolerance);
        }
        if s.distance <= tolerance {
            return s.hit();
        }
        safe = s;
    }
    pair.march(safe, t_max, tolerance)
}

/// A GJK answer at one time, in the world frame.
#[derive(Clone, Copy, Debug)]
struct Sample {
    /// Time (s).
    time: f32,
    /// Distance between the full shapes (m), 0 when they overlap.
    distance: f32,
    /// Unit normal from A towards B.
    normal: Vec3,
    /// Closest point on A.
    point_a: Vec3,
    /// Closest point on B.
    point_b: Vec3,
}

impl Sample {
    fn hit(&self) -> Toi {
        Toi::Hit {
            time: self.time,
            normal: self.normal,
            point_a: self.point_a,
            point_b: self.point_b,
        }
    }
}

/// The two shapes and their motions, with GJK's simplex cache carried from one sample to
/// the next (the poses change little between samples).
struct MovingPair<'q, 's> {
    a: &'q Shape<'s>,
    motion_a: &'q Motion,
    b: &'q Shape<'s>,
    motion_b: &'q Motion,
    /// `ρ_a`, `ρ_b`: core reach of each shape (m), see [`core_reach`].
    reach_a: f32,
    reach_b: f32,
    cache: SimplexCache,
}

impl<'q, 's> MovingPair<'q, 's> {
    fn new(a: &'q Shape<'s>, motion_a: &'q Motion, b: &'q Shape<'s>, motion_b: &'q Motion) -> Self {
        MovingPair {
            a,
            motion_a,
            b,
            motion_b,
            reach_a: core_reach(a),
            reach_b: core_reach(b),
            cache: SimplexCache::default(),
        }
    }

    /// GJK between the shapes at time `t`, run in A's frame, answered in the world frame.
    fn sample(&mut self, t: f32) -> Sample {
        let pose_a = self.motion_a.pose_at(t);
        let pose_b = self.motion_b.pose_at(t);
        let b_in_a = pose_a.inv_mul(&pose_b);
        let out = distance_in_a(self.a, self.b, &b_in_a, &mut self.cache);
        Sample {
            time: t,
            distance: out.distance,
            normal: pose_a.transform_vector(out.normal),
            point_a: pose_a.transform_point(out.point_a),
            point_b: pose_a.transform_point(out.point_b),
        }
    }

    /// `μ = (v_a − v_b)·n + |ω_a⊥| ρ_a + |ω_b⊥| ρ_b` (m/s): no point pair closes faster along
    /// the world normal `n` (module docs).
    fn closing_speed_bound(&self, normal: Vec3) -> f32 {
        (self.motion_a.linear - self.motion_b.linear).dot(normal)
            + across(self.motion_a.angular, normal) * self.reach_a
            + across(self.motion_b.angular, normal) * self.reach_b
    }

    /// The fallback after the advancement budget: march from `safe` to `t_max`, each step
    /// the longer of the certified advance and `(t_max − safe.time) / TOI_MARCH_STEPS`.
    fn march(&mut self, safe: Sample, t_max: f32, tolerance: f32) -> Toi {
        let min_step = (t_max - safe.time) * (1.0 / TOI_MARCH_STEPS as f32);
        let target = 0.5 * tolerance;
        let mut prev = safe;
        // Every step covers at least `min_step`, so TOI_MARCH_STEPS steps reach `t_max`;
        // one more absorbs rounding of the sum.
        for _ in 0..=TOI_MARCH_STEPS {
            if prev.time >= t_max {
                return Toi::Separated;
            }
            let speed = self.closing_speed_bound(prev.normal);
            if !closing(speed) {
                return Toi::Separated;
            }
            let advance = (prev.distance - target) / speed;
            let t = scalar::min(prev.time + scalar::max(min_step, advance), t_max);
            let s = self.sample(t);
            if !apart(s.distance - tolerance) {
                return self.bisect_crossing(prev, s, tolerance);
            }
            prev = s;
        }
        Toi::Separated
    }

    /// Bisection on the sign of `distance − tolerance` between `lo` (gap above the
    /// tolerance) and `hi` (gap at most the tolerance, perhaps overlapping). Reports the
    /// final `hi` when it is still apart (gap in `(0, tolerance]`), else `lo`: never a
    /// time at which the shapes overlap.
    fn bisect_crossing(&mut self, lo: Sample, hi: Sample, tolerance: f32) -> Toi {
        let (mut lo, mut hi) = (lo, hi);
        for _ in 0..MAX_TOI_BISECTIONS {
            let t = 0.5 * (lo.time + hi.time);
            if !(t > lo.time && t < hi.time) {
                break; // the bracket is one ulp wide
            }
            let s = self.sample(t);
            if s.distance > tolerance {
                lo = s;
            } else {
                hi = s;
            }
        }
        if hi.distance > 0.0 {
            hi.hit()
        } else {
            lo.hit()
        }
    }
}

/// `|ω − (ω·n) n|` (rad/s): the part of the spin `ω` that turns points towards or away from
/// the unit normal `n`. A point at `r` from the origin moves along `n` at
/// `n·(ω × r) = ω·(r × n)`, and `r × n ⊥ n`, so only this part counts, times `|r × n| <= ρ`.
fn across(spin: Vec3, normal: Vec3) -> f32 {
    (spin - normal * spin.dot(normal)).length()
}

/// True when a gap (m) is positive: the shapes are apart. False for NaN, so a broken
/// distance counts as contact, the conservative reading.
fn apart(gap: f32) -> bool {
    gap > 0.0
}

/// True when a closing-speed bound (m/s) is positive: the gap may shrink. False for NaN.
fn closing(speed: f32) -> bool {
    speed > 0.0
}

/// Largest distance from the local origin to a point of the shape's core (m): how far a
/// rotation about the origin can move a supporting point, per radian. The inflating radius
/// is rotation invariant, so a sphere has reach 0.
fn core_reach(shape: &Shape) -> f32 {
    scalar::max(shape.bounding_radius() - shape.radius(), 0.0)
}

/// The box that holds `shape` over `dt` seconds of `motion`: its box at the start unioned
/// with its box at the end, grown by how far a rotating point may bulge between them, and
/// cut down to the box swept by the shape's bounding sphere.
///
/// Why it holds (for `s = t/dt`, a core point `x`, `W = |ω| |dt|`): the point is at
/// `c(t) + R(t) x`, with `c` linear in `s`, so it differs from `(1 − s) p₀ + s p₁` (inside
/// the union of the end boxes) only by how far `R(t) x` strays from the chord between
/// `R₀ x` and `R₁ x`. That curve is a circle arc of radius `ρ <= reach` run with angle
/// `φ(s) = 2 atan(W s / 2)`; its second derivative in `s` is at most
/// `ρ W² √(1 + 0.325²)`, so the stray is at most `ρ W² · 1.052 / 8 < ρ W² / 7`. This
/// departs from the uniform-speed bound `ρ (1 − cos(W/2)) <= ρ W²/8` because the
/// integrator's angle is not linear in time. It needs no trigonometry. Independently, the
/// shape stays in its bounding sphere around `c(t)`, whose box lies in the union of the
/// boxes around `c(0)` and `c(dt)`; the answer is the intersection of the two bounds.
///
/// A slack of `1e-6` times the sizes involved covers rounding. A rotating
/// half-space gets the bounding-sphere boxes only. The motion must be finite (as
/// [`time_of_impact`] checks); a non-finite `dt` is taken as 0, a negative one sweeps
/// backwards.
pub fn movement_bounds(shape: &Shape, motion: &Motion, dt: f32) -> Aabb {
    let dt = if dt.is_finite() { dt } else { 0.0 };
    let pose_0 = motion.pose_at(0.0);
    let pose_1 = motion.pose_at(dt);
    let radius = shape.bounding_radius();
    let c0 = pose_0.position;
    let c1 = pose_1.position;
    let slack = BOUNDS_ROUNDING * (radius + c0.abs().max_elem() + c1.abs().max_elem());
    // Bound 1: the bounding sphere's sweep.
    let sphere_sweep = Aabb::from_center_half(c0, Vec3::splat(radius))
        .union(&Aabb::from_center_half(c1, Vec3::splat(radius)))
        .expanded(slack);
    let spinning = motion.angular.length_squared() > 0.0;
    if spinning && matches!(shape, Shape::HalfSpace(_)) {
        return sphere_sweep;
    }
    // Bound 2: end boxes grown by the rotational bulge ρ W² / 7.
    let w = motion.angular.length() * scalar::abs(dt);
    let bulge = core_reach(shape) * w * w * (1.0 / 7.0);
    let swept_ends = shape
        .aabb(&pose_0)
        .union(&shape.aabb(&pose_1))
        .expanded(bulge + slack);
    intersection(&swept_ends, &sphere_sweep)
}

/// The common part of two boxes that both hold the same shape (so it is not empty).
fn intersection(p: &Aabb, q: &Aabb) -> Aabb {
    Aabb::new(p.min.max(q.min), p.max.min(q.max))
}
