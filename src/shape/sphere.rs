//! Sphere: a point core inflated by a radius.

use super::{MassProperties, Ray, RayHit};
use crate::error::{Error, Input};
use crate::math::{scalar, Mat3, Vec3};

/// A ball of `radius` metres centred on the local origin.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct Sphere {
    /// Radius (m), finite and positive.
    pub radius: f32,
}

impl Sphere {
    /// A sphere; the radius must be finite and positive.
    pub fn new(radius: f32) -> Result<Sphere, Error> {
        Ok(Sphere {
            radius: super::size(radius, Input::Radius)?,
        })
    }

    /// `m = 4/3 π r³ ρ`, `I = 2/5 m r²` on every axis.
    pub fn mass_properties(&self, density: f32) -> MassProperties {
        let r = self.radius;
        let mass = density * (4.0 / 3.0) * core::f32::consts::PI * r * r * r;
        let i = 0.4 * mass * r * r;
        MassProperties {
            mass,
            center: Vec3::ZERO,
            inertia: Mat3::from_diagonal(Vec3::splat(i)),
        }
    }

    /// Ray cast in the local frame.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        cast_ray_sphere(ray, Vec3::ZERO, self.radius, max_t)
    }
}

/// Ray against a ball at `center`. With `m = o − c` and `b = m · d` (d unit), the ray's
/// closest approach to the centre is `q = m − b d`, and it meets the sphere at
/// `t = −b − √(r² − |q|²)`. Taking `r² − |q|²` from `q`, not the textbook `b² − (|m|² − r²)`,
/// avoids the cancellation that loses the root for a small sphere far from the origin, and
/// the overflow of `b²` that turned a miss 10²⁰ m away into a hit at `t = 0` (Haines et
/// al., "Precision Improvements for Ray/Sphere Intersection", Ray Tracing Gems, 2019).
pub(crate) fn cast_ray_sphere(ray: &Ray, center: Vec3, radius: f32, max_t: f32) -> Option<RayHit> {
    let m = ray.origin - center;
    let r2 = radius * radius;
    if m.length_squared() <= r2 {
        return Some(RayHit {
            t: 0.0,
            point: ray.origin,
            normal: -ray.direction,
        });
    }
    let b = m.dot(ray.direction);
    if b > 0.0 || b.is_nan() {
        return None; // outside and moving away (NaN only from overflow)
    }
    let q = m - ray.direction * b;
    let h2 = r2 - q.length_squared();
    if h2 < 0.0 || h2.is_nan() {
        return None;
    }
    let t = scalar::max(-b - scalar::sqrt(h2), 0.0);
    if t > max_t || t.is_nan() {
        return None;
    }
    let point = ray.at(t);
    Some(RayHit {
        t,
        point,
        normal: (point - center).normalize_or(-ray.direction),
    })
}
