use core::ops::{Add, Mul};

use super::{scalar, Quat, Vec3};

/// A 3×3 matrix stored as three columns. Used for rotations and inertia tensors
/// (kg·m², or its inverse).
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Mat3 {
    /// First column.
    pub x: Vec3,
    /// Second column.
    pub y: Vec3,
    /// Third column.
    pub z: Vec3,
}

impl Default for Mat3 {
    fn default() -> Self {
        Mat3::IDENTITY
    }
}

impl Mat3 {
    /// The identity matrix.
    pub const IDENTITY: Mat3 = Mat3::from_cols(Vec3::X, Vec3::Y, Vec3::Z);
    /// The zero matrix.
    pub const ZERO: Mat3 = Mat3::from_cols(Vec3::ZERO, Vec3::ZERO, Vec3::ZERO);

    /// A matrix from its columns.
    #[inline]
    pub const fn from_cols(x: Vec3, y: Vec3, z: Vec3) -> Mat3 {
        Mat3 { x, y, z }
    }

    /// A diagonal matrix.
    #[inline]
    pub const fn from_diagonal(d: Vec3) -> Mat3 {
        Mat3::from_cols(
            Vec3::new(d.x, 0.0, 0.0),
            Vec3::new(0.0, d.y, 0.0),
            Vec3::new(0.0, 0.0, d.z),
        )
    }

    /// The rotation matrix of a unit quaternion: its columns are `q.rotate(X)`,
    /// `q.rotate(Y)` and `q.rotate(Z)`, written out with the products by the basis
    /// vectors' zeros and ones left out (`v + w t + u × t` with `t = 2 u × v`, each term
    /// in [`Quat::rotate`]'s order). A term left out is a product by zero, so a column
    /// can differ from `rotate`'s only in the sign of a zero component.
    #[inline]
    pub fn from_quat(q: Quat) -> Mat3 {
        let (x, y, z, w) = (q.x, q.y, q.z, q.w);
        let (x2, y2, z2) = (x * 2.0, y * 2.0, z * 2.0);
        // Column X: t = (0, 2z, −2y).
        let cx = Vec3::new(1.0 + (y * -y2 - z * z2), z2 * w - x * -y2, -y2 * w + x * z2);
        // Column Y: t = (−2z, 0, 2x).
        let cy = Vec3::new(-z2 * w + y * x2, 1.0 + (z * -z2 - x * x2), x2 * w - y * -z2);
        // Column Z: t = (2y, −2x, 0).
        let cz = Vec3::new(y2 * w - z * -x2, -x2 * w + z * y2, 1.0 + (x * -x2 - y * y2));
        Mat3::from_cols(cx, cy, cz)
    }

    /// Row `i` (0, 1, anything else → 2).
    #[inline]
    pub fn row(&self, i: usize) -> Vec3 {
        Vec3::new(self.x[i], self.y[i], self.z[i])
    }

    /// The diagonal.
    #[inline]
    pub fn diagonal(&self) -> Vec3 {
        Vec3::new(self.x.x, self.y.y, self.z.z)
    }

    /// Transpose.
    #[inline]
    pub fn transpose(&self) -> Mat3 {
        Mat3::from_cols(self.row(0), self.row(1), self.row(2))
    }

    /// `M v`.
    #[inline]
    pub fn mul_vec(&self, v: Vec3) -> Vec3 {
        self.x * v.x + self.y * v.y + self.z * v.z
    }

    /// `Mᵀ v`.
    #[inline]
    pub fn transpose_mul_vec(&self, v: Vec3) -> Vec3 {
        Vec3::new(self.x.dot(v), self.y.dot(v), self.z.dot(v))
    }

    /// `M s`, every entry scaled.
    #[inline]
    pub fn scale(&self, s: f32) -> Mat3 {
        Mat3::from_cols(self.x * s, self.y * s, self.z * s)
    }

    /// Determinant.
    #[inline]
    pub fn determinant(&self) -> f32 {
        self.x.dot(self.y.cross(self.z))
    }

    /// Inverse, or `None` when the matrix is singular or the inverse is not finite.
    ///
    /// The matrix is first scaled by its largest entry, so the determinant is formed of
    /// numbers near 1: an inertia tensor of 10¹³ kg·m² (a 84 m ball of water) has a
    /// determinant of 10³⁹, beyond `f32`, yet a perfectly good inverse. `M⁻¹ = (M/s)⁻¹ / s`.
    pub fn inverse(&self) -> Option<Mat3> {
        let s = self.max_abs();
        if s == 0.0 || !s.is_finite() {
            return None;
        }
        let inv_s = 1.0 / s;
        let m = self.scale(inv_s);
        let det = m.determinant();
        if det == 0.0 || !det.is_finite() {
            return None;
        }
        let k = (1.0 / det) * inv_s;
        // Rows of the inverse are the cross products of column pairs.
        let r0 = m.y.cross(m.z) * k;
        let r1 = m.z.cross(m.x) * k;
        let r2 = m.x.cross(m.y) * k;
        let inv = Mat3::from_cols(r0, r1, r2).transpose();
        if inv.is_finite() {
            Some(inv)
        } else {
            None
        }
    }

    /// `R M Rᵀ` for a rotation `R`: a body-frame inertia (or inverse inertia) tensor seen
    /// in the world frame.
    #[inline]
    pub fn rotated(&self, r: &Mat3) -> Mat3 {
        *r * *self * r.transpose()
    }

    /// True when every entry is finite.
    pub fn is_finite(&self) -> bool {
        self.x.is_finite() && self.y.is_finite() && self.z.is_finite()
    }

    /// Outer product `a bᵀ`.
    #[inline]
    pub fn outer(a: Vec3, b: Vec3) -> Mat3 {
        Mat3::from_cols(a * b.x, a * b.y, a * b.z)
    }

    /// Largest absolute entry.
    pub fn max_abs(&self) -> f32 {
        scalar::max(
            self.x.abs().max_elem(),
            scalar::max(self.y.abs().max_elem(), self.z.abs().max_elem()),
        )
    }
}

impl Mul for Mat3 {
    type Output = Mat3;
    #[inline]
    fn mul(self, o: Mat3) -> Mat3 {
        Mat3::from_cols(self.mul_vec(o.x), self.mul_vec(o.y), self.mul_vec(o.z))
    }
}

impl Add for Mat3 {
    type Output = Mat3;
    #[inline]
    fn add(self, o: Mat3) -> Mat3 {
        Mat3::from_cols(self.x + o.x, self.y + o.y, self.z + o.z)
    }
}

impl Mul<Vec3> for Mat3 {
    type Output = Vec3;
    #[inline]
    fn mul(self, v: Vec3) -> Vec3 {
        self.mul_vec(v)
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn inverse_times_matrix_is_identity() {
        let m = Mat3::from_cols(
            Vec3::new(2.0, 0.5, 0.1),
            Vec3::new(0.3, 3.0, -0.2),
            Vec3::new(0.0, 0.4, 1.5),
        );
        let p = m * m.inverse().unwrap();
        for (a, b) in [(p.x, Vec3::X), (p.y, Vec3::Y), (p.z, Vec3::Z)] {
            assert!((a - b).length() < 1e-6);
        }
        assert!(Mat3::ZERO.inverse().is_none());
    }

    #[test]
    fn from_quat_columns_are_the_rotated_axes_to_the_bit() {
        // The written-out matrix against `Quat::rotate` of the axes: equal values (`==`
        // lets the sign of a zero differ, the one difference the docs allow), for random
        // rotations and for the axis-aligned ones whose products by zero matter most.
        let mut rng = crate::rng::SplitMix64::new(7);
        let mut rotations = [Quat::IDENTITY; 1006];
        for q in rotations.iter_mut().skip(6) {
            *q = rng.rotation();
        }
        let quarter = core::f32::consts::FRAC_PI_2;
        for (q, axis) in rotations.iter_mut().zip([Vec3::X, Vec3::Y, Vec3::Z]) {
            *q = Quat::from_axis_angle(axis, quarter);
        }
        rotations[3] = Quat::from_xyzw(0.0, 0.0, 0.0, -1.0);
        rotations[4] = Quat::from_xyzw(-0.0, 1.0, -0.0, 0.0);
        for q in rotations {
            let m = Mat3::from_quat(q);
            for (col, axis) in [(m.x, Vec3::X), (m.y, Vec3::Y), (m.z, Vec3::Z)] {
                let r = q.rotate(axis);
                assert!(
                    col.x == r.x && col.y == r.y && col.z == r.z,
                    "{q:?} {axis:?}"
                );
            }
        }
    }

    #[test]
    fn rotated_diagonal_keeps_trace() {
        let i = Mat3::from_diagonal(Vec3::new(1.0, 2.0, 3.0));
        let r = Mat3::from_quat(Quat::from_axis_angle(Vec3::new(1.0, 1.0, 0.0), 0.8));
        let w = i.rotated(&r);
        let tr = w.x.x + w.y.y + w.z.z;
        assert!((tr - 6.0).abs() < 1e-5);
        // Symmetric.
        assert!((w.x.y - w.y.x).abs() < 1e-6);
    }
}
