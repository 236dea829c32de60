//! Time of impact of two moving shapes by conservative advancement on GJK distance, with
//! a certified bisection search as the fallback; and movement bounds for the broad phase.
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
//! `v_a + ω_a × r`, `r = x − c_a`, so `n·ẋ = n·v_a + n·(ω_a × r) <= n·v_a + |ω_a⊥| ρ_a`,
//! with `ω_a⊥ = ω_a − (ω_a·n) n` (spin about `n` itself moves nothing along `n`; `|ω_a⊥|`
//! is `|n × ω_a|`) and `ρ_a` the largest distance of a core point from A's spin axis
//! through its local origin ([`spin_reach`]: `ω × r` only sees the part of `r` across the
//! axis; the radius that inflates a sphere or capsule does not move under a rotation about
//! the origin, so it does not count). Hence
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
//! # Certified search
//!
//! Advancement crawls when `μ` is much larger than the real closing speed (a fast spin
//! with a near miss: a long shape turning past a small one). After [`MAX_TOI_ITERATIONS`]
//! advances the rest of `[t, t_max]` is searched by bisection in which every interval is
//! either certified free of contact or split. The bound above also runs backwards: from a
//! sample at `t₁` with gap `d₁` and normal `n₁`,
//!
//! ```text
//! s(τ) >= d₁ − μ'₁ (t₁ − τ),   μ'₁ = (v_b − v_a)·n₁ + |ω_a⊥| ρ_a + |ω_b⊥| ρ_b,   τ <= t₁,
//! ```
//!
//! so two samples at `t₀ < t₁` keep the gap above a level `c > 0` on `[t₀, u₀]` and on
//! `[u₁, t₁]`, with `u₀ = t₀ + (d₀ − c)/μ₀` and `u₁ = t₁ − (d₁ − c)/μ'₁`. When `u₀ >= u₁`
//! the interval is certified; otherwise it is split in the middle of `[u₀, u₁]`, the part
//! nobody vouches for. Intervals are taken in time order (a stack of right ends), so the
//! first sample within the tolerance that closes a certified interval is the first
//! approach; the crossing of `distance = tolerance` is then found by
//! [`MAX_TOI_BISECTIONS`] rounds of bisection inside that certified interval.
//!
//! The search never misses a contact (up to GJK's accuracy, which the level `c`, half the
//! tolerance, absorbs). What it cannot promise is to finish: a shape grazing another for
//! a long time at a gap far below `μ` times that time (a many-sided polygonal wheel
//! spinning beside a wall: its bound counts the rim speed, its gap barely changes) needs
//! more samples
//! than [`TOI_SEARCH_SAMPLES`]. It then answers [`Toi::Unresolved`] with the last time
//! up to which no contact is certain: the work stays bounded and nothing is missed
//! silently. (The earlier fallback, 32 equal march steps, missed short contacts: fuzz
//! finding `spinning-hull-passes-a-small-sphere-357f321c`, a 7.6 m hull at 40 rad/s
//! passing a 16 cm sphere.)

use super::{check_pose, distance_in_a, SimplexCache};
use crate::error::{finite_vec, positive, Error, Input};
use crate::math::{scalar, Aabb, Iso, Vec3};
use crate::shape::Shape;

/// Iteration cap of the time-of-impact loop: conservative advances before the fallback.
pub const MAX_TOI_ITERATIONS: u32 = 64;

/// Most GJK samples the certified search takes after the advances (module docs): the
/// work budget of the fallback.
pub const TOI_SEARCH_SAMPLES: u32 = 256;

/// Most right ends of intervals the certified search keeps waiting (a stack): its depth
/// of subdivision. Halving a window of `[0, 10]` s 32 times leaves 2.3 ns; a search that
/// would go deeper answers [`Toi::Unresolved`].
const TOI_SEARCH_DEPTH: usize = 32;

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
    /// The work budget ran out (module docs, certified search): the shapes do not touch
    /// in `[0, time]`, but whether they touch in `(time, t_max]` is not known. A caller
    /// that must not tunnel treats it as a hit at `time` (a conservative stop short of
    /// contact); the gap at `time` is positive but may exceed the tolerance.
    Unresolved {
        /// Last time (s) up to which the shapes are certainly apart, in `[0, t_max]`.
        time: f32,
    },
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
/// - [`Toi::Unresolved`]: the work budget ran out; no contact before `time`, the rest is
///   unknown (a long grazing pass under a loose closing-speed bound, module docs).
///
/// The work is bounded: at most `1 + MAX_TOI_ITERATIONS + TOI_SEARCH_SAMPLES +
/// MAX_TOI_BISECTIONS` = 345 GJK calls; a head-on approach takes 2 or 3. See the module
/// docs for the method.
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
    a.check_convex()?;
    b.check_convex()?;
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
    pair.search(safe, t_max, tolerance)
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
    /// `ρ_a`, `ρ_b`: core reach of each shape (m), see [`Shape::core_reach`].
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
            reach_a: spin_reach(a, motion_a),
            reach_b: spin_reach(b, motion_b),
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

    /// `μ' = (v_b − v_a)·n + |ω_a⊥| ρ_a + |ω_b⊥| ρ_b` (m/s): no point pair opened the gap
    /// along `n` faster than this before the sample (module docs, certified search).
    fn opening_speed_bound(&self, normal: Vec3) -> f32 {
        (self.motion_b.linear - self.motion_a.linear).dot(normal)
            + across(self.motion_a.angular, normal) * self.reach_a
            + across(self.motion_b.angular, normal) * self.reach_b
    }

    /// The fallback after the advancement budget: the certified search of `(safe.time,
    /// t_max]` (module docs). `safe` is apart by more than the tolerance, with no contact
    /// before it.
    fn search(&mut self, safe: Sample, t_max: f32, tolerance: f32) -> Toi {
        let mut ends: heapless::Vec<Sample, TOI_SEARCH_DEPTH> = heapless::Vec::new();
        let mut lo = safe;
        if lo.time >= t_max {
            return Toi::Separated;
        }
        // The first sample cannot fail to fit: the stack is empty.
        if ends.push(self.sample(t_max)).is_err() {
            return Toi::Unresolved { time: lo.time };
        }
        for _ in 0..TOI_SEARCH_SAMPLES {
            let Some(&hi) = ends.last() else {
                return Toi::Separated;
            };
            match self.uncertain_window(&lo, &hi, tolerance) {
                None if hi.distance > tolerance => {
                    // Certified and still far: the interval is cleared.
                    lo = hi;
                    ends.pop();
                }
                None => return self.bisect_crossing(lo, hi, tolerance),
                Some(t) => {
                    let s = self.sample(t);
                    if ends.push(s).is_err() {
                        break;
                    }
                }
            }
        }
        Toi::Unresolved { time: lo.time }
    }

    /// Where to sample inside `[lo.time, hi.time]`, or `None` when the two samples
    /// certify the gap above `c = ½ min(tolerance, hi's gap)` on the whole interval, or
    /// when no time lies strictly between them.
    ///
    /// `lo` is apart by more than the tolerance. Certified when `u₀ >= u₁` (module docs);
    /// else the middle of `[u₀, u₁] ∩ [lo.time, hi.time]`. A contact at `hi` (gap 0, so
    /// `c = 0` and `u₁ = t₁`) is never certified: the window then shrinks by halves
    /// towards the crossing.
    fn uncertain_window(&self, lo: &Sample, hi: &Sample, tolerance: f32) -> Option<f32> {
        let level = 0.5 * scalar::min(tolerance, scalar::max(hi.distance, 0.0));
        let (t0, t1) = (lo.time, hi.time);
        let speed_0 = self.closing_speed_bound(lo.normal);
        let speed_1 = self.opening_speed_bound(hi.normal);
        let u0 = if closing(speed_0) {
            t0 + (lo.distance - level) / speed_0
        } else {
            t1
        };
        let u1 = if closing(speed_1) && level > 0.0 {
            t1 - (hi.distance - level) / speed_1
        } else if level > 0.0 {
            t0
        } else {
            t1
        };
        if u0 >= u1 && level > 0.0 {
            return None;
        }
        let (w0, w1) = (scalar::max(u0, t0), scalar::min(u1, t1));
        let mid = 0.5 * (w0 + w1);
        let t = if mid > t0 && mid < t1 {
            mid
        } else {
            0.5 * (t0 + t1)
        };
        // NaN fails both compares: an unusable bound splits in the middle or stops.
        (t > t0 && t < t1).then_some(t)
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

/// `ρ`: the largest distance of a core point from the spin axis through the shape's local
/// origin (m), for the closing-speed bound (module docs); at most [`Shape::core_reach`].
///
/// A core point at `r` from the origin moves along a unit normal `n` at
/// `n·(ω × r) <= |n × ω| |r⊥|`, with `r⊥` its part across the axis `ω̂` (`ω × r` is
/// across `ω` and has length `|ω| |r⊥|`). The integrator turns the shape about the fixed
/// world axis `ω̂`, so that axis stays put in the shape's frame (`R(τ)ᵀ ω̂ = R₀ᵀ ω̂`) and
/// `|r⊥|` does not change with time. A convex function peaks at a vertex: the largest
/// `|r⊥|` over the core is over its vertices. A wheel spinning on its axle, a rod about
/// its length, a capsule about its axis get the small reach of their cross-section
/// instead of their length. A slack of `1e-6` of the reach covers rounding of the axis.
fn spin_reach(shape: &Shape, motion: &Motion) -> f32 {
    let reach = shape.core_reach();
    let spin = motion.angular.length();
    let Some(count) = shape.core_vertex_count() else {
        return reach;
    };
    // Not spinning (or a NaN spin): the plain reach, which the bound multiplies by 0.
    if spin.is_nan() || spin <= 0.0 {
        return reach;
    }
    let axis = motion
        .pose
        .rotation
        .inverse_rotate(motion.angular * (1.0 / spin));
    let mut across_axis = 0.0f32;
    for i in 0..count {
        let r = shape.core_vertex(i);
        across_axis = scalar::max(across_axis, (r - axis * r.dot(axis)).length_squared());
    }
    scalar::min(reach, scalar::sqrt(across_axis) + BOUNDS_ROUNDING * reach)
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
    let bulge = shape.core_reach() * w * w * (1.0 / 7.0);
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
