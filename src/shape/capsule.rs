//! Capsule: a segment core along local Y from `(0, −h, 0)` to `(0, h, 0)`, inflated by a
//! radius. Core vertex 0 is the bottom end, 1 the top.

use super::{sphere::cast_ray_sphere, Face, FeatureId, MassProperties, Ray, RayHit};
use crate::error::{Error, Input};
use crate::math::{scalar, Aabb, Iso, Mat3, Vec3};

/// A capsule along local Y.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Capsule {
    /// Half the length of the core segment (m), finite and positive.
    pub half_height: f32,
    /// Radius (m), finite and positive.
    pub radius: f32,
}

/// Below this `|dir · axis|`, a capsule's supporting feature is its whole segment.
const SEGMENT_FACE_COS: f32 = 0.02;

impl Capsule {
    /// A capsule; both sizes must be finite and positive.
    pub fn new(half_height: f32, radius: f32) -> Result<Capsule, Error> {
        Ok(Capsule {
            half_height: super::size(half_height, Input::HalfHeight)?,
            radius: super::size(radius, Input::Radius)?,
        })
    }

    /// The segment's end points (bottom, top) in the local frame.
    #[inline]
    pub fn segment(&self) -> (Vec3, Vec3) {
        (
            Vec3::new(0.0, -self.half_height, 0.0),
            Vec3::new(0.0, self.half_height, 0.0),
        )
    }

    pub(crate) fn core_support(&self, dir: Vec3) -> (Vec3, u32) {
        if dir.y >= 0.0 {
            (Vec3::new(0.0, self.half_height, 0.0), 1)
        } else {
            (Vec3::new(0.0, -self.half_height, 0.0), 0)
        }
    }

    pub(crate) fn core_vertex(&self, index: u32) -> Vec3 {
        if index == 1 {
            Vec3::new(0.0, self.half_height, 0.0)
        } else {
            Vec3::new(0.0, -self.half_height, 0.0)
        }
    }

    /// The whole segment when `dir` is nearly perpendicular to the axis, else an end.
    pub(crate) fn supporting_face(&self, dir: Vec3) -> Face {
        let n = dir.normalize_or(Vec3::X);
        if scalar::abs(n.y) < SEGMENT_FACE_COS {
            let (a, b) = self.segment();
            let mut f = Face::new(n, FeatureId::edge(0, 1));
            f.push(a, FeatureId::vertex(0), FeatureId::edge(0, 1));
            f.push(b, FeatureId::vertex(1), FeatureId::edge(0, 1));
            f
        } else {
            let (p, i) = self.core_support(n);
            let mut f = Face::new(n, FeatureId::vertex(i));
            f.push(p, FeatureId::vertex(i), FeatureId::vertex(i));
            f
        }
    }

    pub(crate) fn aabb(&self, pose: &Iso) -> Aabb {
        let axis = pose
            .transform_vector(Vec3::new(0.0, self.half_height, 0.0))
            .abs();
        Aabb::from_center_half(pose.position, axis + Vec3::splat(self.radius))
    }

    /// Cylinder of length `2h` plus two hemispheres. Each hemisphere has its centre of
    /// mass `3r/8` from its flat face and inertia `83/320 m r²` about its own centre
    /// (perpendicular axis); parallel axis theorem moves it to the capsule's centre.
    pub fn mass_properties(&self, density: f32) -> MassProperties {
        let (h, r) = (self.half_height, self.radius);
        let pi = core::f32::consts::PI;
        let m_cyl = density * pi * r * r * (2.0 * h);
        let m_caps = density * (4.0 / 3.0) * pi * r * r * r;
        let i_axis = m_cyl * r * r * 0.5 + m_caps * r * r * 0.4;
        let d = h + 0.375 * r;
        let i_perp = m_cyl * (r * r * 0.25 + h * h / 3.0) + m_caps * (r * r * 83.0 / 320.0 + d * d);
        MassProperties {
            mass: m_cyl + m_caps,
            center: Vec3::ZERO,
            inertia: Mat3::from_diagonal(Vec3::new(i_perp, i_axis, i_perp)),
        }
    }

    /// Ray cast in the local frame: the infinite cylinder clipped to `|y| <= h`, then the
    /// two end spheres; the nearest hit wins.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let (h, r) = (self.half_height, self.radius);
        let o = ray.origin;
        let d = ray.direction;
        // Inside test: distance from origin to the segment.
        let cy = scalar::clamp(o.y, -h, h);
        if (o - Vec3::new(0.0, cy, 0.0)).length_squared() <= r * r {
            return Some(RayHit {
                t: 0.0,
                point: o,
                normal: -d,
            });
        }
        let mut best: Option<RayHit> = None;
        // Cylinder side, in the XZ plane: the ray's closest approach to the axis is at
        // `s = −(o·d)/a` (a = |d|²), at distance |q|; it meets |x| = r at
        // `t = s − √((r² − |q|²)/a)`. Taken from `q`, not from `b² − a c`, to avoid the
        // cancellation of the textbook quadratic for thin capsules far away.
        let a = d.x * d.x + d.z * d.z;
        if a > 1.0e-12 {
            let s = -(o.x * d.x + o.z * d.z) / a;
            let (qx, qz) = (o.x + s * d.x, o.z + s * d.z);
            let h2 = r * r - (qx * qx + qz * qz);
            if h2 >= 0.0 {
                let t = s - scalar::sqrt(h2 / a);
                if t >= 0.0 && t <= max_t {
                    let p = ray.at(t);
                    if scalar::abs(p.y) <= h {
                        best = Some(RayHit {
                            t,
                            point: p,
                            normal: Vec3::new(p.x, 0.0, p.z).normalize_or(-d),
                        });
                    }
                }
            }
        }
        for end in [Vec3::new(0.0, -h, 0.0), Vec3::new(0.0, h, 0.0)] {
            if let Some(hit) = cast_ray_sphere(ray, end, r, max_t) {
                if best.is_none_or(|b| hit.t < b.t) {
                    best = Some(hit);
                }
            }
        }
        best
    }
}
