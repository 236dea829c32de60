use super::{Iso, Vec3};

/// An axis-aligned bounding box in the world frame (m). `min <= max` component-wise.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct Aabb {
    /// Lower corner.
    pub min: Vec3,
    /// Upper corner.
    pub max: Vec3,
}

impl Aabb {
    /// A box from its corners (the caller keeps `min <= max`).
    #[inline]
    pub const fn new(min: Vec3, max: Vec3) -> Aabb {
        Aabb { min, max }
    }

    /// The box around `center` with half-extents `half`.
    #[inline]
    pub fn from_center_half(center: Vec3, half: Vec3) -> Aabb {
        Aabb::new(center - half, center + half)
    }

    /// The box around a local box of half-extents `half` (centred on the local origin)
    /// under the pose `iso`: half-extents `|R| half`.
    pub fn from_local_box(iso: &Iso, half: Vec3) -> Aabb {
        Aabb::from_local_box_turned(iso.position, &super::Mat3::from_quat(iso.rotation), half)
    }

    /// [`Aabb::from_local_box`] given the rotation as the matrix `r`, the box centred at
    /// `center`.
    #[inline]
    pub(crate) fn from_local_box_turned(center: Vec3, r: &super::Mat3, half: Vec3) -> Aabb {
        let h = Vec3::new(
            r.row(0).abs().dot(half),
            r.row(1).abs().dot(half),
            r.row(2).abs().dot(half),
        );
        Aabb::from_center_half(center, h)
    }

    /// The box around this box moved by `iso` (a box given in some frame, bounded in the
    /// frame `iso` maps it to): centre `iso · c`, half-extents `|R| h`.
    pub fn transformed(&self, iso: &Iso) -> Aabb {
        let c = (self.min + self.max) * 0.5;
        let h = (self.max - self.min) * 0.5;
        Aabb::from_local_box(&Iso::new(iso.transform_point(c), iso.rotation), h)
    }

    /// The smallest box holding both.
    #[inline]
    pub fn union(&self, o: &Aabb) -> Aabb {
        Aabb::new(self.min.min(o.min), self.max.max(o.max))
    }

    /// True when the boxes overlap or touch. All six comparisons are made, without a
    /// branch between them: in a tree walk the answer is data, and a branch per axis was
    /// mispredicted often enough to cost more than the comparisons.
    #[inline]
    pub fn overlaps(&self, o: &Aabb) -> bool {
        (self.min.x <= o.max.x)
            & (o.min.x <= self.max.x)
            & (self.min.y <= o.max.y)
            & (o.min.y <= self.max.y)
            & (self.min.z <= o.max.z)
            & (o.min.z <= self.max.z)
    }

    /// True when `p` is inside or on the boundary.
    #[inline]
    pub fn contains_point(&self, p: Vec3) -> bool {
        p.x >= self.min.x
            && p.x <= self.max.x
            && p.y >= self.min.y
            && p.y <= self.max.y
            && p.z >= self.min.z
            && p.z <= self.max.z
    }

    /// True when `o` lies entirely inside `self`.
    #[inline]
    pub fn contains(&self, o: &Aabb) -> bool {
        self.contains_point(o.min) && self.contains_point(o.max)
    }

    /// Grown by `margin` on every side.
    #[inline]
    pub fn expanded(&self, margin: f32) -> Aabb {
        Aabb::new(
            self.min - Vec3::splat(margin),
            self.max + Vec3::splat(margin),
        )
    }

    /// Moved by `d`.
    #[inline]
    pub fn translated(&self, d: Vec3) -> Aabb {
        Aabb::new(self.min + d, self.max + d)
    }

    /// Centre point.
    #[inline]
    pub fn center(&self) -> Vec3 {
        (self.min + self.max) * 0.5
    }

    /// Half-extents.
    #[inline]
    pub fn half_extents(&self) -> Vec3 {
        (self.max - self.min) * 0.5
    }

    /// True when both corners are finite and `min <= max`.
    pub fn is_valid(&self) -> bool {
        self.min.is_finite()
            && self.max.is_finite()
            && self.min.x <= self.max.x
            && self.min.y <= self.max.y
            && self.min.z <= self.max.z
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;

    #[test]
    fn rotated_box_bounds_grow_by_sqrt2() {
        let iso = Iso::new(
            Vec3::ZERO,
            Quat::from_axis_angle(Vec3::Y, core::f32::consts::FRAC_PI_4),
        );
        let b = Aabb::from_local_box(&iso, Vec3::new(1.0, 1.0, 1.0));
        assert!((b.max.x - core::f32::consts::SQRT_2).abs() < 1e-5);
        assert!((b.max.y - 1.0).abs() < 1e-5);
    }

    #[test]
    fn overlap_is_inclusive() {
        let a = Aabb::new(Vec3::ZERO, Vec3::ONE);
        let b = Aabb::new(Vec3::ONE, Vec3::splat(2.0));
        assert!(a.overlaps(&b));
        assert!(!a.overlaps(&b.translated(Vec3::new(0.01, 0.0, 0.0))));
        assert!(a.union(&b).contains(&a));
    }
}
