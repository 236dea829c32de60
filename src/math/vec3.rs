use core::ops::{Add, AddAssign, Div, Index, Mul, MulAssign, Neg, Sub, SubAssign};

use super::scalar;

/// A 3D vector of `f32` (metres, metres per second, newtons: the unit is the caller's).
///
/// # Examples
///
/// ```
/// use carom::Vec3;
///
/// let a = Vec3::new(1.0, 2.0, 3.0);
/// let b = Vec3::X * 2.0;
/// assert_eq!(a + b, Vec3::new(3.0, 2.0, 3.0));
/// assert_eq!(a.dot(Vec3::Y), 2.0);
/// assert_eq!(Vec3::X.cross(Vec3::Y), Vec3::Z); // right-handed
/// assert_eq!(Vec3::new(3.0, 4.0, 0.0).length(), 5.0);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Vec3 {
    /// X component.
    pub x: f32,
    /// Y component (up).
    pub y: f32,
    /// Z component.
    pub z: f32,
}

impl Vec3 {
    /// (0, 0, 0).
    pub const ZERO: Vec3 = Vec3::new(0.0, 0.0, 0.0);
    /// (1, 1, 1).
    pub const ONE: Vec3 = Vec3::new(1.0, 1.0, 1.0);
    /// Unit X.
    pub const X: Vec3 = Vec3::new(1.0, 0.0, 0.0);
    /// Unit Y (up).
    pub const Y: Vec3 = Vec3::new(0.0, 1.0, 0.0);
    /// Unit Z.
    pub const Z: Vec3 = Vec3::new(0.0, 0.0, 1.0);

    /// A vector from its components.
    #[inline]
    pub const fn new(x: f32, y: f32, z: f32) -> Vec3 {
        Vec3 { x, y, z }
    }

    /// All three components set to `v`.
    #[inline]
    pub const fn splat(v: f32) -> Vec3 {
        Vec3::new(v, v, v)
    }

    /// Dot product `a·b`, summed in the fixed order x, y, z.
    #[inline]
    pub fn dot(self, o: Vec3) -> f32 {
        self.x * o.x + self.y * o.y + self.z * o.z
    }

    /// Cross product `a × b`.
    #[inline]
    pub fn cross(self, o: Vec3) -> Vec3 {
        Vec3::new(
            self.y * o.z - self.z * o.y,
            self.z * o.x - self.x * o.z,
            self.x * o.y - self.y * o.x,
        )
    }

    /// Squared length.
    #[inline]
    pub fn length_squared(self) -> f32 {
        self.dot(self)
    }

    /// Euclidean length.
    #[inline]
    pub fn length(self) -> f32 {
        scalar::sqrt(self.length_squared())
    }

    /// The unit vector along `self`, or `fallback` when `self` is shorter than `1e-20`
    /// in squared length (or not finite).
    #[inline]
    pub fn normalize_or(self, fallback: Vec3) -> Vec3 {
        let l2 = self.length_squared();
        if l2 > 1.0e-20 && l2.is_finite() {
            self * (1.0 / scalar::sqrt(l2))
        } else {
            fallback
        }
    }

    /// The unit vector along `self` and its length, or `None` when too short.
    #[inline]
    pub fn normalize_and_length(self) -> Option<(Vec3, f32)> {
        let l2 = self.length_squared();
        if l2 > 1.0e-20 && l2.is_finite() {
            let l = scalar::sqrt(l2);
            Some((self * (1.0 / l), l))
        } else {
            None
        }
    }

    /// Component-wise product.
    #[inline]
    pub fn mul_elem(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x * o.x, self.y * o.y, self.z * o.z)
    }

    /// Component-wise minimum (see [`scalar::min`]).
    #[inline]
    pub fn min(self, o: Vec3) -> Vec3 {
        Vec3::new(
            scalar::min(self.x, o.x),
            scalar::min(self.y, o.y),
            scalar::min(self.z, o.z),
        )
    }

    /// Component-wise maximum (see [`scalar::max`]).
    #[inline]
    pub fn max(self, o: Vec3) -> Vec3 {
        Vec3::new(
            scalar::max(self.x, o.x),
            scalar::max(self.y, o.y),
            scalar::max(self.z, o.z),
        )
    }

    /// Component-wise absolute value.
    #[inline]
    pub fn abs(self) -> Vec3 {
        Vec3::new(
            scalar::abs(self.x),
            scalar::abs(self.y),
            scalar::abs(self.z),
        )
    }

    /// The largest component.
    #[inline]
    pub fn max_elem(self) -> f32 {
        scalar::max(self.x, scalar::max(self.y, self.z))
    }

    /// The smallest component.
    #[inline]
    pub fn min_elem(self) -> f32 {
        scalar::min(self.x, scalar::min(self.y, self.z))
    }

    /// True when every component is finite.
    #[inline]
    pub fn is_finite(self) -> bool {
        // `&`, not `&&`: three compares and no branch between them.
        self.x.is_finite() & self.y.is_finite() & self.z.is_finite()
    }

    /// Linear interpolation `self + (o − self) t`.
    #[inline]
    pub fn lerp(self, o: Vec3, t: f32) -> Vec3 {
        self + (o - self) * t
    }

    /// A unit vector perpendicular to `self` (which should be a unit vector).
    #[inline]
    pub fn any_perpendicular(self) -> Vec3 {
        // Cross with the axis least aligned with self.
        let a = self.abs();
        let other = if a.x <= a.y && a.x <= a.z {
            Vec3::X
        } else if a.y <= a.z {
            Vec3::Y
        } else {
            Vec3::Z
        };
        self.cross(other).normalize_or(Vec3::X)
    }

    /// Distance between two points.
    #[inline]
    pub fn distance(self, o: Vec3) -> f32 {
        (self - o).length()
    }

    /// Components as an array `[x, y, z]`.
    #[inline]
    pub fn to_array(self) -> [f32; 3] {
        [self.x, self.y, self.z]
    }

    /// `-0.0` components replaced by `+0.0` (for hashing and snapshots).
    #[inline]
    pub fn canonical(self) -> Vec3 {
        Vec3::new(
            scalar::canonical(self.x),
            scalar::canonical(self.y),
            scalar::canonical(self.z),
        )
    }
}

impl Add for Vec3 {
    type Output = Vec3;
    #[inline]
    fn add(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Sub for Vec3 {
    type Output = Vec3;
    #[inline]
    fn sub(self, o: Vec3) -> Vec3 {
        Vec3::new(self.x - o.x, self.y - o.y, self.z - o.z)
    }
}

impl Neg for Vec3 {
    type Output = Vec3;
    #[inline]
    fn neg(self) -> Vec3 {
        Vec3::new(-self.x, -self.y, -self.z)
    }
}

impl Mul<f32> for Vec3 {
    type Output = Vec3;
    #[inline]
    fn mul(self, s: f32) -> Vec3 {
        Vec3::new(self.x * s, self.y * s, self.z * s)
    }
}

impl Mul<Vec3> for f32 {
    type Output = Vec3;
    #[inline]
    fn mul(self, v: Vec3) -> Vec3 {
        v * self
    }
}

impl Div<f32> for Vec3 {
    type Output = Vec3;
    #[inline]
    fn div(self, s: f32) -> Vec3 {
        Vec3::new(self.x / s, self.y / s, self.z / s)
    }
}

impl AddAssign for Vec3 {
    #[inline]
    fn add_assign(&mut self, o: Vec3) {
        *self = *self + o;
    }
}

impl SubAssign for Vec3 {
    #[inline]
    fn sub_assign(&mut self, o: Vec3) {
        *self = *self - o;
    }
}

impl MulAssign<f32> for Vec3 {
    #[inline]
    fn mul_assign(&mut self, s: f32) {
        *self = *self * s;
    }
}

impl Index<usize> for Vec3 {
    type Output = f32;
    /// Component by index: 0 → x, 1 → y, anything else → z (never panics).
    #[inline]
    fn index(&self, i: usize) -> &f32 {
        match i {
            0 => &self.x,
            1 => &self.y,
            _ => &self.z,
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn cross_follows_right_hand_rule() {
        assert_eq!(Vec3::X.cross(Vec3::Y), Vec3::Z);
        assert_eq!(Vec3::Y.cross(Vec3::Z), Vec3::X);
        assert_eq!(Vec3::Z.cross(Vec3::X), Vec3::Y);
    }

    #[test]
    fn normalize_falls_back_on_zero() {
        assert_eq!(Vec3::ZERO.normalize_or(Vec3::Y), Vec3::Y);
        let n = Vec3::new(3.0, 0.0, 4.0).normalize_or(Vec3::Y);
        assert!((n.length() - 1.0).abs() < 1e-6);
    }

    #[test]
    fn perpendicular_is_perpendicular() {
        for v in [Vec3::X, Vec3::Y, Vec3::Z, Vec3::new(0.6, 0.8, 0.0)] {
            let p = v.any_perpendicular();
            assert!(p.dot(v).abs() < 1e-6);
            assert!((p.length() - 1.0).abs() < 1e-6);
        }
    }
}
