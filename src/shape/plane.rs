//! Half-space: every point on or below a plane through the local origin,
//! `{p : n · p <= 0}`. Unbounded, so static bodies only; its pairs use closed forms.

use super::{Face, FeatureId, Ray, RayHit, HALF_SPACE_EXTENT};
use crate::error::{finite_vec, Error, Input};
use crate::math::{Aabb, Iso, Vec3};

/// A half-space with outward unit normal `normal` (local frame).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct HalfSpace {
    /// Outward unit normal (local frame).
    pub normal: Vec3,
}

impl HalfSpace {
    /// A half-space; the normal must be finite and non-zero (it is normalised).
    pub fn new(normal: Vec3) -> Result<HalfSpace, Error> {
        finite_vec(normal, Input::Direction)?;
        let (n, _) = normal
            .normalize_and_length()
            .ok_or(Error::NotPositive(Input::Direction))?;
        Ok(HalfSpace { normal: n })
    }

    /// The boundary plane as a single "face" (its only feature, id face 0) with no
    /// vertices of its own: one vertex at the origin stands for it.
    pub(crate) fn supporting_face(&self, _dir: Vec3) -> Face {
        let mut f = Face::new(self.normal, FeatureId::face(0));
        f.push(Vec3::ZERO, FeatureId::face(0), FeatureId::face(0));
        f
    }

    /// A huge box, clipped on the side the normal points to when the normal is along
    /// a world axis.
    pub(crate) fn aabb(&self, pose: &Iso) -> Aabb {
        let n = pose.transform_vector(self.normal);
        let e = HALF_SPACE_EXTENT;
        let mut b = Aabb::from_center_half(pose.position, Vec3::splat(e));
        let p = pose.position;
        const AXIS: f32 = 0.999_999;
        if n.x >= AXIS {
            b.max.x = p.x;
        } else if n.x <= -AXIS {
            b.min.x = p.x;
        } else if n.y >= AXIS {
            b.max.y = p.y;
        } else if n.y <= -AXIS {
            b.min.y = p.y;
        } else if n.z >= AXIS {
            b.max.z = p.z;
        } else if n.z <= -AXIS {
            b.min.z = p.z;
        }
        b
    }

    /// Ray cast in the local frame: `n · (o + t d) = 0`.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let n = self.normal;
        let s = n.dot(ray.origin);
        if s <= 0.0 {
            return Some(RayHit {
                t: 0.0,
                point: ray.origin,
                normal: -ray.direction,
            });
        }
        let dn = n.dot(ray.direction);
        if dn >= 0.0 {
            return None;
        }
        let t = -s / dn;
        if t > max_t {
            return None;
        }
        Some(RayHit {
            t,
            point: ray.at(t),
            normal: n,
        })
    }
}
