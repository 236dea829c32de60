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
pub use sat::{PairCache, SatAxis};
pub use toi::{movement_bounds, time_of_impact, Motion, Toi, MAX_TOI_ITERATIONS};

pub(crate) use gjk::distance_in_a;
pub(crate) use manifold::contact_unchecked;
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

/// A shape placed in the query frame (A's frame): what GJK and EPA see.
#[derive(Clone, Copy, Debug)]
pub(crate) struct Proxy<'s, 'a> {
    /// The shape.
    pub shape: &'s Shape<'a>,
    /// Its pose in the query frame.
    pub pose: Iso,
}

impl Proxy<'_, '_> {
    /// Core support point along `dir` (query frame) and its vertex index.
    #[inline]
    pub fn support(&self, dir: crate::math::Vec3) -> (crate::math::Vec3, u32) {
        let (p, i) = self
            .shape
            .core_support(self.pose.inverse_transform_vector(dir));
        (self.pose.transform_point(p), i)
    }

    /// Core vertex `i` in the query frame.
    #[inline]
    pub fn vertex(&self, i: u32) -> crate::math::Vec3 {
        self.pose.transform_point(self.shape.core_vertex(i))
    }
}
