//! The one-shot minimal translation: signed separation, normal and witness points of two
//! shapes, whether they are apart or overlap.
//!
//! [`super::distance`] answers for shapes that are apart (0 when they touch or overlap)
//! and [`super::penetration`] for shapes that overlap (`None` when they are apart); a
//! caller who wants "how far, and which way, to move B" must otherwise run both and stitch
//! the answers. [`separation`] runs GJK once on the cores and, when the shapes overlap,
//! EPA seeded with GJK's simplex: the same computations as the two queries, so its
//! answers are theirs to the bit (tested in `tests/gjk_epa.rs`).

use super::epa::{self, EpaCaps, EpaStatus, Penetration};
use super::gjk::{self, DistanceOutput, GjkStatus, SimplexCache, MAX_GJK_ITERATIONS};
use super::{check_pose, Placement, Proxy};
use crate::error::Error;
use crate::math::{Iso, Vec3};
use crate::shape::Shape;

/// How [`separation`] got its answer.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SeparationStatus {
    /// GJK (apart) or EPA (overlapping) converged, or a closed form answered: the answer
    /// is exact up to their tolerances (about 2e-7 m at a 1 m scale apart, 1e-5 of the
    /// shapes' size overlapping).
    Converged,
    /// GJK or EPA stopped at its iteration or polytope bound and answered with the best
    /// bound it had: apart, `separation` is at least the true distance (an upper bound);
    /// overlapping, moving B by `−separation · normal` still separates the shapes (the
    /// depth is an upper bound), except when GJK itself hit its cap on cores that are
    /// apart (then the depth is a lower bound).
    Bounded,
    /// Both shapes are half-spaces: no finite translation separates them. Reported as
    /// touching (`separation` 0, A's plane normal, each plane's origin as a witness), as
    /// [`super::distance`] reports them. Half-spaces are static-only and never collide.
    HalfSpaces,
}

/// The answer of [`separation`], in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Separation {
    /// Signed separation (m): the distance when the shapes are apart (`> 0`), minus the
    /// penetration depth when they overlap (`< 0`), 0 when they touch. Moving B by
    /// `−separation · normal` makes them touch.
    pub separation: f32,
    /// Unit normal from A towards B (world frame): the direction in which B must move to
    /// separate (by `−separation` when overlapping) or to touch (by `separation` against
    /// it when apart).
    pub normal: Vec3,
    /// Witness point on A (world frame): the closest point of A when apart, the deepest
    /// point of B inside A, on A's surface, when overlapping.
    pub point_a: Vec3,
    /// Witness point on B (world frame): the closest point of B when apart, the deepest
    /// point of A inside B, on B's surface, when overlapping. When converged,
    /// `point_b − point_a = separation · normal` up to rounding.
    pub point_b: Vec3,
    /// How the answer was found.
    pub status: SeparationStatus,
}

/// The signed separation of `a` at `pose_a` and `b` at `pose_b` (world frame): distance
/// and closest points when they are apart, minus the depth and the deepest points when
/// they overlap, with the unit normal from A towards B either way.
///
/// The same numbers as [`super::distance`] (with a fresh cache) when the shapes are apart
/// and as [`super::penetration`] when they overlap: `separation = distance` when
/// `distance > 0`, else `separation = −depth`. Swapping A and B negates the normal and
/// swaps the witnesses (up to rounding; exactly when the normal comes from a closed form
/// or a face).
///
/// Fails only on an invalid pose, exactly like the other queries: a non-finite position
/// or rotation (`Error::NonFinite`), a coordinate beyond ±[`crate::error::MAX_COORDINATE`]
/// (`Error::OutOfRange`), a rotation that is not unit length (`Error::NotUnit`).
pub fn separation(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> Result<Separation, Error> {
    check_pose(pose_a)?;
    check_pose(pose_b)?;
    a.check_convex()?;
    b.check_convex()?;
    let placement = Placement::between(pose_a, pose_b);
    let (local, from_penetration) = separation_placed(a, b, &placement);
    let normal = pose_a.transform_vector(local.normal);
    let world = Separation {
        // Renormalised after the rotation, as `penetration` does (not `distance`), so
        // that both answers are the queries' to the bit.
        normal: if from_penetration {
            normal.normalize_or(Vec3::Y)
        } else {
            normal
        },
        point_a: pose_a.transform_point(local.point_a),
        point_b: pose_a.transform_point(local.point_b),
        ..local
    };
    // Only coordinates near f32::MAX can overflow here (the poses are bounded).
    let finite = world.separation.is_finite()
        && world.normal.is_finite()
        && world.point_a.is_finite()
        && world.point_b.is_finite();
    Ok(if finite {
        world
    } else {
        Separation {
            separation: if world.separation.is_finite() {
                world.separation
            } else {
                0.0
            },
            normal: world.normal.normalize_or(Vec3::Y),
            point_a: pose_a.position,
            point_b: pose_b.position,
            status: SeparationStatus::Bounded,
        }
    })
}

/// [`separation`] in A's frame, and true when the answer is the penetration's.
fn separation_placed(a: &Shape, b: &Shape, placement: &Placement) -> (Separation, bool) {
    let half_space = |s: &Shape| matches!(s, Shape::HalfSpace(_));
    if half_space(a) || half_space(b) {
        let mut cache = SimplexCache::default();
        let d = gjk::distance_placed(a, b, placement, &mut cache, MAX_GJK_ITERATIONS);
        if half_space(a) && half_space(b) {
            let s = Separation {
                status: SeparationStatus::HalfSpaces,
                ..apart(&d)
            };
            return (s, false);
        }
        if d.distance > 0.0 {
            return (apart(&d), false);
        }
        return match epa::penetration_placed(a, b, placement, EpaCaps::DEFAULT) {
            Some(p) => (overlapping(&p), true),
            None => (touching(&d), false),
        };
    }
    let pa = Proxy::at_origin(a);
    let pb = Proxy::placed(b, placement);
    let core = gjk::gjk_cores(&pa, &pb, &mut SimplexCache::default(), MAX_GJK_ITERATIONS);
    let d = gjk::finite_or_fallback(
        gjk::inflate(&core, a.radius(), b.radius()),
        Vec3::ZERO,
        placement.iso.position,
    );
    if d.status != GjkStatus::Overlapping && d.distance > 0.0 {
        let mut s = apart(&d);
        if core.ambiguous {
            // GJK's direction is rounding noise (a vertex or an edge of the Minkowski
            // difference within 1e-5 of its size from the origin): EPA's normal instead,
            // as the contact manifold does; distance and points stay GJK's.
            let n = epa::touching_normal(&pa, &pb, &core, EpaCaps::DEFAULT);
            if let Some((n, _)) = n
                .normalize_and_length()
                .filter(|(n, _)| n.dot(d.normal) > 0.0)
            {
                s.normal = n;
            }
        }
        return (s, false);
    }
    match epa::penetration_from_gjk(&pa, &pb, &core, EpaCaps::DEFAULT) {
        Some(p) => (overlapping(&p), true),
        None => (touching(&d), false),
    }
}

/// Apart: GJK's distance, normal and closest points.
fn apart(d: &DistanceOutput) -> Separation {
    Separation {
        separation: d.distance,
        normal: d.normal,
        point_a: d.point_a,
        point_b: d.point_b,
        status: match d.status {
            GjkStatus::IterationLimit => SeparationStatus::Bounded,
            _ => SeparationStatus::Converged,
        },
    }
}

/// GJK says touching and EPA finds no depth: touching at 0 along GJK's normal.
fn touching(d: &DistanceOutput) -> Separation {
    Separation {
        separation: 0.0,
        ..apart(d)
    }
}

/// Overlapping: minus EPA's depth, its normal and deepest points.
fn overlapping(p: &Penetration) -> Separation {
    Separation {
        // `0 − depth`, not `−depth`: a depth of 0 gives +0, not −0.
        separation: 0.0 - p.depth,
        normal: p.normal,
        point_a: p.point_a,
        point_b: p.point_b,
        status: match p.status {
            EpaStatus::Converged => SeparationStatus::Converged,
            _ => SeparationStatus::Bounded,
        },
    }
}
