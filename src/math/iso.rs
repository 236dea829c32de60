use core::ops::Mul;

use super::{Quat, Vec3};

/// A rigid transform: rotate by `rotation`, then translate by `position`.
/// Maps a body's local frame to the world frame.
///
/// # Examples
///
/// ```
/// use carom::{Iso, Quat, Vec3};
/// use core::f32::consts::FRAC_PI_2;
///
/// // A pose 2 m up, turned a quarter about +Y.
/// let pose = Iso::new(Vec3::new(0.0, 2.0, 0.0), Quat::from_axis_angle(Vec3::Y, FRAC_PI_2));
/// let world = pose.transform_point(Vec3::X); // a point 1 m along the body's local +X
/// assert!((world - Vec3::new(0.0, 2.0, -1.0)).length() < 1e-6);
/// let back = pose.inverse_transform_point(world);
/// assert!((back - Vec3::X).length() < 1e-6);
/// ```
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Iso {
    /// Translation (m).
    pub position: Vec3,
    /// Rotation (unit quaternion).
    pub rotation: Quat,
}

impl Iso {
    /// The identity transform.
    pub const IDENTITY: Iso = Iso::new(Vec3::ZERO, Quat::IDENTITY);

    /// A transform from a position and a rotation.
    #[inline]
    pub const fn new(position: Vec3, rotation: Quat) -> Iso {
        Iso { position, rotation }
    }

    /// A pure translation.
    #[inline]
    pub const fn from_position(position: Vec3) -> Iso {
        Iso::new(position, Quat::IDENTITY)
    }

    /// Local point to world: `R p + t`.
    #[inline]
    pub fn transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation.rotate(p) + self.position
    }

    /// World point to local: `Rᵀ (p − t)`.
    #[inline]
    pub fn inverse_transform_point(&self, p: Vec3) -> Vec3 {
        self.rotation.inverse_rotate(p - self.position)
    }

    /// Local direction to world: `R v`.
    #[inline]
    pub fn transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation.rotate(v)
    }

    /// World direction to local: `Rᵀ v`.
    #[inline]
    pub fn inverse_transform_vector(&self, v: Vec3) -> Vec3 {
        self.rotation.inverse_rotate(v)
    }

    /// The inverse transform.
    #[inline]
    pub fn inverse(&self) -> Iso {
        let r = self.rotation.conjugate();
        Iso::new(-r.rotate(self.position), r)
    }

    /// `self⁻¹ ∘ other`: the pose of `other` seen in this frame (`b_in_a = a.inv_mul(&b)`).
    #[inline]
    pub fn inv_mul(&self, other: &Iso) -> Iso {
        Iso::new(
            self.inverse_transform_point(other.position),
            (self.rotation.conjugate() * other.rotation).normalize(),
        )
    }

    /// True when position and rotation are finite and the rotation is unit length.
    pub fn is_valid(&self) -> bool {
        self.position.is_finite() && self.rotation.is_unit()
    }
}

impl Mul for Iso {
    type Output = Iso;
    /// Composition: `(a * b).transform_point(p) == a.transform_point(b.transform_point(p))`.
    #[inline]
    fn mul(self, o: Iso) -> Iso {
        Iso::new(
            self.transform_point(o.position),
            (self.rotation * o.rotation).normalize(),
        )
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_round_trips() {
        let a = Iso::new(
            Vec3::new(1.0, 2.0, 3.0),
            Quat::from_axis_angle(Vec3::new(0.2, 1.0, -0.4), 1.3),
        );
        let p = Vec3::new(-0.5, 0.7, 2.0);
        let q = a.inverse_transform_point(a.transform_point(p));
        assert!((p - q).length() < 1e-5);
        let b = Iso::new(
            Vec3::new(-2.0, 0.0, 1.0),
            Quat::from_axis_angle(Vec3::X, 0.4),
        );
        let b_in_a = a.inv_mul(&b);
        let w1 = b.transform_point(p);
        let w2 = a.transform_point(b_in_a.transform_point(p));
        assert!((w1 - w2).length() < 1e-5);
        assert!(((a * a.inverse()).position).length() < 1e-5);
    }
}
