use core::ops::Mul;

use super::{scalar, Vec3};

/// A rotation quaternion `w + xi + yj + zk`. Unit length when used as a rotation.
///
/// # Examples
///
/// ```
/// use carom::{Quat, Vec3};
/// use core::f32::consts::FRAC_PI_2;
///
/// // A quarter turn about +Y takes +X to −Z (right-handed).
/// let q = Quat::from_axis_angle(Vec3::Y, FRAC_PI_2);
/// let v = q.rotate(Vec3::X);
/// assert!((v - Vec3::new(0.0, 0.0, -1.0)).length() < 1e-6);
/// assert!(q.is_unit());
/// // Composition: `a * b` rotates by `b`, then by `a`.
/// let half_turn = q * q;
/// assert!((half_turn.rotate(Vec3::X) + Vec3::X).length() < 1e-6);
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Quat {
    /// i component.
    pub x: f32,
    /// j component.
    pub y: f32,
    /// k component.
    pub z: f32,
    /// Real component.
    pub w: f32,
}

impl Default for Quat {
    fn default() -> Self {
        Quat::IDENTITY
    }
}

/// How far `|q|²` may be from 1 for a quaternion given at the API to count as a rotation.
pub(crate) const UNIT_TOLERANCE: f32 = 1.0e-3;

impl Quat {
    /// The identity rotation.
    pub const IDENTITY: Quat = Quat::from_xyzw(0.0, 0.0, 0.0, 1.0);

    /// A quaternion from its components (not normalised).
    #[inline]
    pub const fn from_xyzw(x: f32, y: f32, z: f32, w: f32) -> Quat {
        Quat { x, y, z, w }
    }

    /// Rotation of `angle` radians about the unit vector `axis` (right-handed).
    /// Uses sine and cosine: an API helper, never called inside the step.
    ///
    /// With the feature `micromath` the sine and cosine are approximations (within
    /// 1.1e-3, so `sin² + cos²` may miss 1 by 2e-3, outside [`Quat::is_unit`]'s
    /// tolerance), and the quaternion is normalised: a unit rotation about `axis` whose
    /// angle is off by at most 2.2e-3 rad (measured over ±2π).
    pub fn from_axis_angle(axis: Vec3, angle: f32) -> Quat {
        let a = axis.normalize_or(Vec3::Y);
        let h = 0.5 * angle;
        let s = scalar::sin(h);
        let q = Quat::from_xyzw(a.x * s, a.y * s, a.z * s, scalar::cos(h));
        #[cfg(feature = "micromath")]
        let q = q.normalize();
        q
    }

    /// The vector part `(x, y, z)`.
    #[inline]
    pub fn xyz(self) -> Vec3 {
        Vec3::new(self.x, self.y, self.z)
    }

    /// Squared norm.
    #[inline]
    pub fn length_squared(self) -> f32 {
        self.x * self.x + self.y * self.y + self.z * self.z + self.w * self.w
    }

    /// The unit quaternion along `self`, or the identity when `self` is (nearly) zero or
    /// not finite.
    #[inline]
    pub fn normalize(self) -> Quat {
        let l2 = self.length_squared();
        if l2 == 1.0 {
            // Already unit to the last bit: the general path would scale by `1 / √1 = 1`
            // (exact in IEEE arithmetic), so skip its square root and division.
            return self;
        }
        if l2 > 1.0e-20 && l2.is_finite() {
            let inv = 1.0 / scalar::sqrt(l2);
            Quat::from_xyzw(self.x * inv, self.y * inv, self.z * inv, self.w * inv)
        } else {
            Quat::IDENTITY
        }
    }

    /// True when all components are finite and `| |q|² − 1 |` is within a small tolerance.
    pub fn is_unit(self) -> bool {
        let l2 = self.length_squared();
        l2.is_finite() && scalar::abs(l2 - 1.0) <= UNIT_TOLERANCE
    }

    /// True when every component is finite.
    pub fn is_finite(self) -> bool {
        // `&`, not `&&`: four compares and no branch between them.
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite() & self.w.is_finite()
    }

    /// Conjugate, the inverse of a unit quaternion.
    #[inline]
    pub fn conjugate(self) -> Quat {
        Quat::from_xyzw(-self.x, -self.y, -self.z, self.w)
    }

    /// Rotate `v`: `q v q*`, computed as `v + 2w (u × v) + 2 u × (u × v)` with `u` the
    /// vector part.
    #[inline]
    pub fn rotate(self, v: Vec3) -> Vec3 {
        let u = self.xyz();
        let t = u.cross(v) * 2.0;
        v + t * self.w + u.cross(t)
    }

    /// Rotate `v` by the inverse rotation.
    #[inline]
    pub fn inverse_rotate(self, v: Vec3) -> Vec3 {
        self.conjugate().rotate(v)
    }

    /// Integrate an angular velocity `omega` (rad/s, world frame) over `dt` seconds:
    /// `q' = normalise(q + ½ dt (ω, 0) q)`. Uses no trigonometry.
    #[inline]
    pub fn integrate(self, omega: Vec3, dt: f32) -> Quat {
        let h = 0.5 * dt;
        let (a, b) = (omega * h, self);
        // `(a, 0) * q`, the Hamilton product with the terms of `a.w = 0` left out (each
        // a product by zero, so only the sign of a zero result can differ).
        let dq = Quat::from_xyzw(
            (a.x * b.w + a.y * b.z) - a.z * b.y,
            (-(a.x * b.z) + a.y * b.w) + a.z * b.x,
            (a.x * b.y - a.y * b.x) + a.z * b.w,
            (-(a.x * b.x) - a.y * b.y) - a.z * b.z,
        );
        Quat::from_xyzw(self.x + dq.x, self.y + dq.y, self.z + dq.z, self.w + dq.w).normalize()
    }

    /// `-0.0` components replaced by `+0.0` (for hashing and snapshots).
    #[inline]
    pub fn canonical(self) -> Quat {
        Quat::from_xyzw(
            scalar::canonical(self.x),
            scalar::canonical(self.y),
            scalar::canonical(self.z),
            scalar::canonical(self.w),
        )
    }
}

impl Mul for Quat {
    type Output = Quat;
    /// Hamilton product: `(a * b).rotate(v) == a.rotate(b.rotate(v))`.
    #[inline]
    fn mul(self, b: Quat) -> Quat {
        let a = self;
        Quat::from_xyzw(
            a.w * b.x + a.x * b.w + a.y * b.z - a.z * b.y,
            a.w * b.y - a.x * b.z + a.y * b.w + a.z * b.x,
            a.w * b.z + a.x * b.y - a.y * b.x + a.z * b.w,
            a.w * b.w - a.x * b.x - a.y * b.y - a.z * b.z,
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3) -> bool {
        (a - b).length() < 1e-5
    }

    #[test]
    fn normalize_keeps_a_unit_quaternion_to_the_bit() {
        // The `|q|² = 1` shortcut returns `q` as it is; the general path must agree, which
        // needs `√1 = 1` exactly from the square root in use (libm or micromath's).
        assert_eq!(scalar::sqrt(1.0).to_bits(), 1.0f32.to_bits());
        let mut rng = crate::rng::SplitMix64::new(5);
        let mut shortcut = 0;
        for _ in 0..2000 {
            let q = rng.rotation();
            let n = q.normalize();
            if q.length_squared() == 1.0 {
                shortcut += 1;
                let inv = 1.0 / scalar::sqrt(1.0);
                let general = Quat::from_xyzw(q.x * inv, q.y * inv, q.z * inv, q.w * inv);
                for (a, b) in [
                    (n.x, general.x),
                    (n.y, general.y),
                    (n.z, general.z),
                    (n.w, general.w),
                ] {
                    assert_eq!(a.to_bits(), b.to_bits());
                }
            }
        }
        // The case is common: random unit rotations hit it often.
        assert!(shortcut > 100, "{shortcut}");
    }

    #[test]
    fn integrate_matches_the_hamilton_product_to_the_bit() {
        // The written-out `(a, 0) * q` against the general product: equal values.
        let mut rng = crate::rng::SplitMix64::new(11);
        for _ in 0..1000 {
            let q = rng.rotation();
            let omega = rng.unit_vector() * rng.range(0.0, 50.0);
            let dt = rng.range(0.001, 0.05);
            let h = 0.5 * dt;
            let dq = Quat::from_xyzw(omega.x * h, omega.y * h, omega.z * h, 0.0) * q;
            let want = Quat::from_xyzw(q.x + dq.x, q.y + dq.y, q.z + dq.z, q.w + dq.w).normalize();
            let got = q.integrate(omega, dt);
            assert!(got.x == want.x && got.y == want.y && got.z == want.z && got.w == want.w);
        }
    }

    #[test]
    fn quarter_turn_about_y_maps_x_to_minus_z() {
        let q = Quat::from_axis_angle(Vec3::Y, core::f32::consts::FRAC_PI_2);
        assert!(close(q.rotate(Vec3::X), -Vec3::Z));
        assert!(close(q.inverse_rotate(-Vec3::Z), Vec3::X));
    }

    #[test]
    fn axis_angle_rotations_are_unit_and_turn_by_their_angle() {
        // libm: within rounding; micromath: its sine and cosine, normalised.
        let bound = if cfg!(feature = "micromath") {
            2.3e-3
        } else {
            1.0e-6
        };
        for i in -200..=200 {
            let angle = i as f32 * (core::f32::consts::TAU / 200.0);
            let q = Quat::from_axis_angle(Vec3::new(0.3, -1.0, 0.5), angle);
            assert!(q.is_unit(), "{angle}: {q:?}");
            assert!(scalar::abs(q.length_squared() - 1.0) < 1.0e-6, "{q:?}");
            let turned = 2.0 * libm::atan2f(q.xyz().length(), q.w);
            let off = scalar::abs(turned - scalar::abs(angle));
            let off = if off > core::f32::consts::PI {
                core::f32::consts::TAU - off
            } else {
                off
            };
            assert!(off < bound, "{angle}: turned {turned}");
        }
    }

    #[test]
    fn product_composes_rotations() {
        let a = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0), 0.7);
        let b = Quat::from_axis_angle(Vec3::new(-1.0, 0.5, 0.2), 1.9);
        let v = Vec3::new(0.3, -2.0, 1.1);
        assert!(close((a * b).rotate(v), a.rotate(b.rotate(v))));
    }

    #[test]
    fn integration_matches_axis_angle_for_small_steps() {
        let omega = Vec3::new(0.0, 0.0, 2.0);
        let mut q = Quat::IDENTITY;
        for _ in 0..1000 {
            q = q.integrate(omega, 0.001);
        }
        // X turned by 2 rad about Z (libm's trig: `integrate` uses none, and micromath's
        // approximate sine would hide what is tested here).
        let exact = Vec3::new(libm::cosf(2.0), libm::sinf(2.0), 0.0);
        assert!(close(q.rotate(Vec3::X), exact));
    }
}
