//! Triangle: three vertices, two-sided, no volume (static bodies only). Vertex ids 0–2,
//! edges by vertex pair, face 0 for the side its normal points to, face 1 for the back.

use super::{Face, FeatureId, Ray, RayHit};
use crate::error::{finite_vec, Error, Input};
use crate::math::{scalar, Aabb, Iso, Vec3};

/// A triangle with vertices counter-clockwise about `normal()`.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Triangle {
    /// The three vertices (local frame, m).
    pub vertices: [Vec3; 3],
}

/// Smallest area (m²) of a usable triangle.
const MIN_AREA: f32 = 1.0e-12;

/// Below this `|cos|` of the angle between a ray and the triangle's normal, the ray is
/// treated as parallel to the triangle (a miss).
const PARALLEL_COS: f32 = 1.0e-7;

impl Triangle {
    /// A triangle; vertices must be finite, within ±[`crate::MAX_COORDINATE`] and not
    /// collinear.
    pub fn new(a: Vec3, b: Vec3, c: Vec3) -> Result<Triangle, Error> {
        for v in [a, b, c] {
            finite_vec(v, Input::Point)?;
            if v.abs().max_elem() > crate::error::MAX_COORDINATE {
                return Err(Error::OutOfRange(Input::Point));
            }
        }
        let n = (b - a).cross(c - a);
        if 0.5 * n.length() <= MIN_AREA || n.length_squared().is_nan() {
            return Err(Error::NotPositive(Input::Point));
        }
        Ok(Triangle {
            vertices: [a, b, c],
        })
    }

    /// Unit normal, `(b − a) × (c − a)` normalised.
    pub fn normal(&self) -> Vec3 {
        let [a, b, c] = self.vertices;
        (b - a).cross(c - a).normalize_or(Vec3::Y)
    }

    pub(crate) fn core_support(&self, dir: Vec3) -> (Vec3, u32) {
        let mut best = 0;
        let mut best_d = self.vertices[0].dot(dir);
        for i in 1..3 {
            let d = self.vertices[i].dot(dir);
            if d > best_d {
                best = i;
                best_d = d;
            }
        }
        (self.vertices[best], best as u32)
    }

    pub(crate) fn core_vertex(&self, index: u32) -> Vec3 {
        self.vertices[(index as usize).min(2)]
    }

    /// The triangle itself, facing `dir`'s side.
    pub(crate) fn supporting_face(&self, dir: Vec3) -> Face {
        let n = self.normal();
        let order: [usize; 3] = if n.dot(dir) >= 0.0 {
            [0, 1, 2]
        } else {
            [0, 2, 1]
        };
        let front = order[1] == 1;
        let mut f = Face::new(
            if front { n } else { -n },
            FeatureId::face(if front { 0 } else { 1 }),
        );
        for (k, &i) in order.iter().enumerate() {
            let j = order[(k + 1) % 3];
            let v = self.vertices[i.min(2)];
            f.push(
                v,
                FeatureId::vertex(i as u32),
                FeatureId::edge(i as u32, j as u32),
            );
        }
        f
    }

    pub(crate) fn aabb(&self, pose: &Iso) -> Aabb {
        let p0 = pose.transform_point(self.vertices[0]);
        let mut b = Aabb::new(p0, p0);
        for v in &self.vertices[1..] {
            let p = pose.transform_point(*v);
            b = Aabb::new(b.min.min(p), b.max.max(p));
        }
        b
    }

    pub(crate) fn bounding_radius(&self) -> f32 {
        let mut r = 0.0;
        for v in &self.vertices {
            r = scalar::max(r, v.length());
        }
        r
    }

    /// Two-sided Möller–Trumbore ray cast in the local frame. The ray counts as parallel
    /// when the cosine of its angle to the triangle's normal is below 1e-7 (a test
    /// relative to the triangle's size, so small triangles are not missed); NaN-safe
    /// compares keep an overflowed barycentric from slipping through as a hit.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let [a, b, c] = self.vertices;
        let e1 = b - a;
        let e2 = c - a;
        let p = ray.direction.cross(e2);
        // det = e1 · (d × e2) = −d · (e1 × e2) = −|e1 × e2| cos θ.
        let det = e1.dot(p);
        let parallel = PARALLEL_COS * e1.cross(e2).length();
        if scalar::abs(det) <= parallel || det.is_nan() {
            return None;
        }
        let inv = 1.0 / det;
        let s = ray.origin - a;
        let u = s.dot(p) * inv;
        if !(0.0..=1.0).contains(&u) {
            return None;
        }
        let q = s.cross(e1);
        let v = ray.direction.dot(q) * inv;
        if !(v >= 0.0 && u + v <= 1.0) {
            return None;
        }
        let t = e2.dot(q) * inv;
        if !(t >= 0.0 && t <= max_t) {
            return None;
        }
        let n = self.normal();
        Some(RayHit {
            t,
            point: ray.at(t),
            normal: if n.dot(ray.direction) <= 0.0 { n } else { -n },
        })
    }
}
