//! Stateless geometry: pure functions of (shape, pose) pairs.
//!
//! Every query takes world poses at the door, moves B into A's frame (`b_in_a`), works
//! there, and answers in the world frame. Nothing here knows about bodies or worlds.
//!
//! - [`distance`] (GJK): distance, closest points, separating normal.
//! - [`penetration`] (EPA): depth and normal of overlapping shapes.
//! - [`contact`]: a contact manifold of up to 4 points with feature ids; [`contact_cached`]
//!   the same with a per-pair [`PairCache`] (box and hull pairs by the separating axis
//!   test), [`contact_gjk_epa`] the general GJK/EPA path for every pair.
//! - [`time_of_impact`]: when two moving shapes first touch.
//! - [`movement_bounds`]: the box a shape sweeps over a step.

mod analytic;
mod clip;
mod epa;
mod gjk;
mod manifold;
mod sat;
mod toi;

pub use analytic::segment_closest_points;
pub use epa::{penetration, EpaStatus, Penetration, MAX_EPA_FACES, MAX_EPA_VERTICES};
pub use gjk::{distance, intersects, DistanceOutput, GjkStatus, SimplexCache, MAX_GJK_ITERATIONS};
pub use manifold::{
    contact, contact_cached, contact_gjk_epa, ContactId, Manifold, ManifoldPoint,
    MAX_MANIFOLD_POINTS,
};
pub use sat::{PairCache, SatAxis, SAT_TOLERANCE};
pub use toi::{movement_bounds, time_of_impact, Motion, Toi, MAX_TOI_ITERATIONS};

pub(crate) use gjk::distance_in_a;
pub(crate) use manifold::contact_cached_unchecked;
pub(crate) use toi::time_of_impact_unchecked;

use crate::error::{Error, Input};
use crate::math::Iso;
use crate::shape::Shape;

/// Check a pose given at a public door: a finite position within
/// ±[`crate::error::MAX_COORDINATE`], a finite unit rotation.
pub(crate) fn check_pose(pose: &Iso) -> Result<(), Error> {
    crate::error::position(pose.position)?;
    if !pose.rotation.is_finite() {
        return Err(Error::NonFinite(Input::Rotation));
    }
    if !pose.rotation.is_unit() {
        return Err(Error::NotUnit(Input::Rotation));
    }
    Ok(())
}

/// A shape placed in the query frame (A's frame): what GJK and EPA see. The pose's
/// rotation is kept as a matrix too (support points move through it twice per GJK step),
/// and a shape at the query frame's origin (A itself) skips the transforms altogether.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Proxy<'s, 'a> {
    /// The shape.
    pub shape: &'s Shape<'a>,
    /// Its pose in the query frame.
    pub pose: Iso,
    /// `pose`'s rotation as a matrix.
    rotation: crate::math::Mat3,
    /// True for the identity pose: points and directions are used as they are.
    identity: bool,
}

impl<'s, 'a> Proxy<'s, 'a> {
    /// `shape` at `pose` (query frame).
    #[inline]
    pub fn new(shape: &'s Shape<'a>, pose: Iso) -> Proxy<'s, 'a> {
        Proxy {
            shape,
            pose,
            rotation: sat::rotation_matrix(pose.rotation),
            identity: false,
        }
    }

    /// `shape` at the query frame's origin (A in its own frame).
    #[inline]
    pub fn at_origin(shape: &'s Shape<'a>) -> Proxy<'s, 'a> {
        Proxy {
            shape,
            pose: Iso::IDENTITY,
            rotation: crate::math::Mat3::IDENTITY,
            identity: true,
        }
    }

    /// Core support point along `dir` (query frame) and its vertex index.
    #[inline]
    pub fn support(&self, dir: crate::math::Vec3) -> (crate::math::Vec3, u32) {
        if self.identity {
            return self.shape.core_support(dir);
        }
        let (p, i) = self
            .shape
            .core_support(self.rotation.transpose_mul_vec(dir));
        (self.rotation.mul_vec(p) + self.pose.position, i)
    }

    /// Core vertex `i` in the query frame.
    #[inline]
    pub fn vertex(&self, i: u32) -> crate::math::Vec3 {
        let p = self.shape.core_vertex(i);
        if self.identity {
            p
        } else {
            self.rotation.mul_vec(p) + self.pose.position
        }
    }
}
