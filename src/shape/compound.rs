//! Compound: a body made of up to [`MAX_COMPOUND_PARTS`] convex parts, each at its own
//! pose in the body's frame. The parts are borrowed from the caller (a `static`, the
//! stack or a `Box`), like hulls; the compound keeps each part's bounds so the mid phase
//! can skip parts far from the other body.

use super::{MassProperties, Ray, RayHit, Shape};
use crate::error::{Error, Input};
use crate::math::{Aabb, Iso, Mat3, Vec3};

/// Most parts a [`Compound`] may have.
pub const MAX_COMPOUND_PARTS: usize = 16;

/// One convex part of a [`Compound`]: a sphere, capsule, box or hull at `pose` in the
/// compound's frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CompoundPart<'a> {
    /// Where the part sits in the compound's frame.
    pub pose: Iso,
    /// The part's shape (in its own frame).
    pub shape: Shape<'a>,
}

impl<'a> CompoundPart<'a> {
    /// A part: `shape` at `pose` in the compound's frame.
    pub const fn new(pose: Iso, shape: Shape<'a>) -> CompoundPart<'a> {
        CompoundPart { pose, shape }
    }
}

/// A rigid union of convex parts: dumbbells, tables, chairs, cars. Mass properties are
/// the parts' combined exactly (the parallel-axis theorem; overlapping parts count their
/// shared volume twice), contacts are found per part (the mid phase tests each part's
/// bounds against the other body's), and ray casts report the nearest part.
///
/// # Examples
///
/// ```
/// use carom::shape::{Compound, CompoundPart};
/// use carom::{Iso, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// // A dumbbell: two balls on a bar along X.
/// let parts = [
///     CompoundPart::new(Iso::from_position(Vec3::new(-1.0, 0.0, 0.0)), Shape::sphere(0.3)?),
///     CompoundPart::new(Iso::IDENTITY, Shape::capsule(0.8, 0.05)?),
///     CompoundPart::new(Iso::from_position(Vec3::new(1.0, 0.0, 0.0)), Shape::sphere(0.3)?),
/// ];
/// let dumbbell = Compound::new(&parts)?;
/// let shape = Shape::Compound(&dumbbell);
/// let props = shape.mass_properties(1000.0)?;
/// assert!(props.center.length() < 1e-6); // symmetric
/// assert!((shape.local_aabb().max.x - 1.3).abs() < 1e-6);
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Compound<'a> {
    parts: &'a [CompoundPart<'a>],
    /// Each part's bounds in the compound's frame (the first `parts.len()`).
    bounds: [Aabb; MAX_COMPOUND_PARTS],
    /// Union of `bounds`.
    aabb: Aabb,
    /// Largest distance from the compound's origin to any point of a part (m).
    bounding_radius: f32,
    /// Smallest `min_extent` of any part (m).
    min_extent: f32,
}

impl<'a> Compound<'a> {
    /// A compound of `parts` (1 to [`MAX_COMPOUND_PARTS`]).
    ///
    /// # Errors
    ///
    /// Checked in this order; nothing is kept on error:
    /// 1. no parts: [`Error::NotPositive`]`(`[`Input::PartCount`]`)`; more than
    ///    [`MAX_COMPOUND_PARTS`]: [`Error::OutOfRange`]`(`[`Input::PartCount`]`)`;
    /// 2. then each part in order: its pose as every query checks one (a finite position
    ///    within ±[`crate::MAX_COORDINATE`], a finite unit rotation); a shape that is
    ///    not a convex solid (a half-space, triangle, mesh or another compound):
    ///    [`Error::OutOfRange`]`(`[`Input::Part`]`)`; a shape built from invalid public
    ///    fields: the error its constructor gives.
    pub fn new(parts: &'a [CompoundPart<'a>]) -> Result<Compound<'a>, Error> {
        if parts.is_empty() {
            return Err(Error::NotPositive(Input::PartCount));
        }
        if parts.len() > MAX_COMPOUND_PARTS {
            return Err(Error::OutOfRange(Input::PartCount));
        }
        for p in parts {
            crate::collide::check_pose(&p.pose)?;
            if !matches!(
                p.shape,
                Shape::Sphere(_) | Shape::Capsule(_) | Shape::Cuboid(_) | Shape::Hull(_)
            ) {
                return Err(Error::OutOfRange(Input::Part));
            }
            crate::dynamics::body::check_shape(&p.shape)?;
        }
        let mut bounds = [Aabb::default(); MAX_COMPOUND_PARTS];
        let mut aabb: Option<Aabb> = None;
        let mut bounding_radius = 0.0f32;
        let mut min_extent = f32::INFINITY;
        for (slot, p) in bounds.iter_mut().zip(parts) {
            let b = p.shape.aabb(&p.pose);
            *slot = b;
            aabb = Some(aabb.map_or(b, |a| a.union(&b)));
            let r = p.pose.position.length() + p.shape.bounding_radius();
            bounding_radius = bounding_radius.max(r);
            min_extent = min_extent.min(p.shape.min_extent());
        }
        Ok(Compound {
            parts,
            bounds,
            aabb: aabb.unwrap_or_default(),
            bounding_radius,
            min_extent,
        })
    }

    /// The parts, in the order given.
    #[inline]
    pub fn parts(&self) -> &'a [CompoundPart<'a>] {
        self.parts
    }

    /// Number of parts (1 to [`MAX_COMPOUND_PARTS`]).
    #[inline]
    pub fn part_count(&self) -> u32 {
        self.parts.len() as u32
    }

    /// Part `i` and its bounds in the compound's frame; `None` past the last.
    #[inline]
    pub fn part(&self, i: u32) -> Option<(&'a CompoundPart<'a>, Aabb)> {
        let p = self.parts.get(i as usize)?;
        Some((p, self.bounds.get(i as usize).copied().unwrap_or_default()))
    }

    /// Bounds of all parts in the compound's frame (m).
    #[inline]
    pub fn local_aabb(&self) -> Aabb {
        self.aabb
    }

    /// Bounds under `pose` (world frame): the union of each part's bounds at its world
    /// pose.
    pub fn aabb(&self, pose: &Iso) -> Aabb {
        let mut out: Option<Aabb> = None;
        for p in self.parts {
            let b = p.shape.aabb(&(*pose * p.pose));
            out = Some(out.map_or(b, |a| a.union(&b)));
        }
        out.unwrap_or_default()
    }

    /// Largest distance from the compound's origin to any point of a part (m).
    #[inline]
    pub fn bounding_radius(&self) -> f32 {
        self.bounding_radius
    }

    /// Smallest extent of any part (m): what a fast compound can tunnel by.
    #[inline]
    pub fn min_extent(&self) -> f32 {
        self.min_extent
    }

    /// Call `f` with the index of every part whose bounds (compound frame) overlap or
    /// touch `aabb` (compound frame), in increasing order.
    pub fn query_aabb(&self, aabb: &Aabb, mut f: impl FnMut(u32)) {
        for (i, b) in self.bounds.iter().take(self.parts.len()).enumerate() {
            if b.overlaps(aabb) {
                f(i as u32);
            }
        }
    }

    /// Mass properties at a uniform `density` (kg/m³; checked by the caller): masses
    /// summed, the centre of mass their weighted mean, and the inertia about it
    /// `Σ Rᵢ Iᵢ Rᵢᵀ + mᵢ (|dᵢ|² E − dᵢ dᵢᵀ)`, `dᵢ` from the compound's centre to part
    /// `i`'s, summed in part order.
    pub fn mass_properties(&self, density: f32) -> Result<MassProperties, Error> {
        let mut mass = 0.0f32;
        let mut moment = Vec3::ZERO;
        // (mass, centre in the compound's frame, inertia in the compound's axes) per part.
        let mut each = [(0.0f32, Vec3::ZERO, Mat3::ZERO); MAX_COMPOUND_PARTS];
        for (slot, p) in each.iter_mut().zip(self.parts) {
            let m = p.shape.mass_properties(density)?;
            let r = Mat3::from_quat(p.pose.rotation);
            let c = p.pose.transform_point(m.center);
            *slot = (m.mass, c, r * m.inertia * r.transpose());
            mass += m.mass;
            moment += c * m.mass;
        }
        let center = moment * (1.0 / mass);
        let mut inertia = Mat3::ZERO;
        for &(m, c, i) in each.iter().take(self.parts.len()) {
            let d = c - center;
            let shift = Mat3::IDENTITY.scale(d.dot(d)) + Mat3::outer(d, d).scale(-1.0);
            inertia = inertia + i + shift.scale(m);
        }
        Ok(MassProperties {
            mass,
            center,
            inertia,
        })
    }

    /// The nearest hit of a ray (compound frame) on any part up to `max_t`, ties to the
    /// lowest part, with the part's index.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<(u32, RayHit)> {
        let mut best: Option<(u32, RayHit)> = None;
        for (i, p) in self.parts.iter().enumerate() {
            let limit = best.map_or(max_t, |(_, h)| h.t);
            if let Some(h) = p.shape.cast_ray_unchecked(&p.pose, ray, limit) {
                if best.is_none_or(|(_, b)| h.t < b.t) {
                    best = Some((i as u32, h));
                }
            }
        }
        best
    }

    /// The furthest point of any part along `dir` (compound frame), surface included, and
    /// the part it belongs to: the support of the compound's convex hull.
    pub fn support(&self, dir: Vec3) -> (Vec3, u32) {
        let mut best = (Vec3::ZERO, 0u32);
        let mut best_d = f32::NEG_INFINITY;
        for (i, p) in self.parts.iter().enumerate() {
            let local = p.pose.inverse_transform_vector(dir);
            let s = p.pose.transform_point(p.shape.support(local));
            let d = s.dot(dir);
            if d > best_d {
                best_d = d;
                best = (s, i as u32);
            }
        }
        best
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;
    use crate::shape::ConvexHull;

    fn at(x: f32, y: f32, z: f32, s: Shape<'static>) -> CompoundPart<'static> {
        CompoundPart::new(Iso::from_position(Vec3::new(x, y, z)), s)
    }

    #[test]
    fn dumbbell_inertia_matches_the_closed_form() {
        // Two balls of radius r at ±l on X and a box bar between them.
        let (r, l, rho) = (0.25f32, 1.0f32, 700.0f32);
        let bar = Vec3::new(0.7, 0.05, 0.05);
        let parts = [
            at(-l, 0.0, 0.0, Shape::sphere(r).unwrap()),
            at(0.0, 0.0, 0.0, Shape::cuboid(bar).unwrap()),
            at(l, 0.0, 0.0, Shape::sphere(r).unwrap()),
        ];
        let c = Compound::new(&parts).unwrap();
        let got = c.mass_properties(rho).unwrap();
        let pi = core::f64::consts::PI;
        let (r, l, rho) = (r as f64, l as f64, rho as f64);
        let (hx, hy, hz) = (bar.x as f64, bar.y as f64, bar.z as f64);
        let m_ball = rho * 4.0 / 3.0 * pi * r * r * r;
        let m_bar = rho * 8.0 * hx * hy * hz;
        let i_ball = 0.4 * m_ball * r * r;
        let ixx = 2.0 * i_ball + m_bar / 3.0 * (hy * hy + hz * hz);
        let iyy = 2.0 * (i_ball + m_ball * l * l) + m_bar / 3.0 * (hx * hx + hz * hz);
        let izz = 2.0 * (i_ball + m_ball * l * l) + m_bar / 3.0 * (hx * hx + hy * hy);
        let mass = 2.0 * m_ball + m_bar;
        assert!(((got.mass as f64) - mass).abs() < 1e-5 * mass);
        assert!(got.center.length() < 1e-6);
        let d = got.inertia.diagonal();
        for (g, want) in [(d.x, ixx), (d.y, iyy), (d.z, izz)] {
            assert!(((g as f64) - want).abs() < 1e-5 * want, "{g} vs {want}");
        }
        // Off-diagonal terms vanish for this symmetric body.
        let full = got.inertia;
        for (i, j) in [(0, 1), (0, 2), (1, 2)] {
            assert!(full.row(i)[j].abs() < 1e-4 * ixx as f32);
        }
    }

    #[test]
    fn an_offset_rotated_single_part_is_the_part_moved() {
        // One box turned and moved: the compound's inertia is R I Rᵀ about the moved
        // centre, the same as the part's own tensor rotated.
        let q = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0).normalize_or(Vec3::X), 0.7);
        let b = Shape::cuboid(Vec3::new(0.3, 0.5, 0.9)).unwrap();
        let parts = [CompoundPart::new(Iso::new(Vec3::new(1.0, -2.0, 0.5), q), b)];
        let c = Compound::new(&parts).unwrap();
        let got = c.mass_properties(10.0).unwrap();
        let own = b.mass_properties(10.0).unwrap();
        let r = Mat3::from_quat(q);
        let want = r * own.inertia * r.transpose();
        assert!((got.center - Vec3::new(1.0, -2.0, 0.5)).length() < 1e-6);
        for j in 0..3 {
            assert!(
                (got.inertia.row(j) - want.row(j)).length()
                    < 1e-4 * own.inertia.diagonal().max_elem()
            );
        }
    }

    #[test]
    fn parallel_axis_for_two_off_centre_cubes() {
        // Two unit cubes at x = 0 and x = 3: centre at 1.5, Iyy = 2 (m/6 + m 1.5²).
        let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
        let parts = [at(0.0, 0.0, 0.0, cube), at(3.0, 0.0, 0.0, cube)];
        let got = Compound::new(&parts).unwrap().mass_properties(2.0).unwrap();
        let m = 2.0f32;
        assert_eq!(got.mass, 2.0 * m);
        assert!((got.center - Vec3::new(1.5, 0.0, 0.0)).length() < 1e-6);
        let want_yy = 2.0 * (m / 6.0 + m * 2.25);
        assert!((got.inertia.diagonal().y - want_yy).abs() < 1e-5);
        assert!((got.inertia.diagonal().x - 2.0 * m / 6.0).abs() < 1e-6);
    }

    #[test]
    fn bounds_and_queries_follow_the_parts() {
        let parts = [
            at(-2.0, 0.0, 0.0, Shape::sphere(0.5).unwrap()),
            at(2.0, 1.0, 0.0, Shape::cuboid(Vec3::splat(0.25)).unwrap()),
        ];
        let c = Compound::new(&parts).unwrap();
        assert_eq!(c.local_aabb().min, Vec3::new(-2.5, -0.5, -0.5));
        assert_eq!(c.local_aabb().max, Vec3::new(2.25, 1.25, 0.5));
        assert!((c.bounding_radius() - (5.0f32.sqrt() + 0.1875f32.sqrt())).abs() < 1e-6);
        assert_eq!(c.min_extent(), 0.5);
        let mut hit = [false; 2];
        c.query_aabb(
            &Aabb::new(Vec3::new(1.5, 0.5, -0.1), Vec3::new(1.8, 1.0, 0.1)),
            |i| hit[i as usize] = true,
        );
        assert_eq!(hit, [false, true]);
        // A ray along X from the left meets the ball first; from the right the box.
        let ray = Ray::new(Vec3::new(-10.0, 0.0, 0.0), Vec3::X).unwrap();
        let (i, h) = c.cast_ray(&ray, 100.0).unwrap();
        assert_eq!(i, 0);
        assert!((h.t - 7.5).abs() < 1e-5);
        let ray = Ray::new(Vec3::new(10.0, 1.0, 0.0), -Vec3::X).unwrap();
        let (i, h) = c.cast_ray(&ray, 100.0).unwrap();
        assert_eq!(i, 1);
        assert!((h.t - 7.75).abs() < 1e-5);
        assert!(c.cast_ray(&ray, 7.0).is_none());
        // The support is the furthest part's.
        let (p, i) = c.support(Vec3::X);
        assert_eq!(i, 1);
        assert_eq!(p.x, 2.25);
        // World bounds under a turn of 90° about Z: x ↦ y.
        let pose = Iso::new(
            Vec3::ZERO,
            Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_2),
        );
        let w = c.aabb(&pose);
        assert!((w.min.y + 2.5).abs() < 1e-5 && (w.max.y - 2.25).abs() < 1e-5);
    }

    #[test]
    fn bad_parts_are_refused_with_their_errors() {
        assert_eq!(
            Compound::new(&[]),
            Err(Error::NotPositive(Input::PartCount))
        );
        let ball = at(0.0, 0.0, 0.0, Shape::sphere(1.0).unwrap());
        let many = [ball; MAX_COMPOUND_PARTS + 1];
        assert_eq!(
            Compound::new(&many),
            Err(Error::OutOfRange(Input::PartCount))
        );
        assert!(Compound::new(&many[..MAX_COMPOUND_PARTS]).is_ok());
        let plane = at(0.0, 0.0, 0.0, Shape::half_space(Vec3::Y).unwrap());
        assert_eq!(
            Compound::new(&[ball, plane]),
            Err(Error::OutOfRange(Input::Part))
        );
        let tri = Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::Z).unwrap();
        assert_eq!(
            Compound::new(&[at(0.0, 0.0, 0.0, tri)]),
            Err(Error::OutOfRange(Input::Part))
        );
        let inner = [ball];
        let c = Compound::new(&inner).unwrap();
        let nested = [CompoundPart::new(Iso::IDENTITY, Shape::Compound(&c))];
        assert_eq!(Compound::new(&nested), Err(Error::OutOfRange(Input::Part)));
        let nan = at(f32::NAN, 0.0, 0.0, Shape::sphere(1.0).unwrap());
        assert_eq!(
            Compound::new(&[nan]),
            Err(Error::NonFinite(Input::Position))
        );
        let bad_rot = CompoundPart::new(
            Iso::new(Vec3::ZERO, Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
            Shape::sphere(1.0).unwrap(),
        );
        assert_eq!(
            Compound::new(&[bad_rot]),
            Err(Error::NotUnit(Input::Rotation))
        );
        let bad_ball = at(
            0.0,
            0.0,
            0.0,
            Shape::Sphere(crate::shape::Sphere { radius: -1.0 }),
        );
        assert_eq!(
            Compound::new(&[bad_ball]),
            Err(Error::NotPositive(Input::Radius))
        );
        // A hull part is fine.
        let pts = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
        let hull = ConvexHull::new(&pts).unwrap();
        let with_hull = [CompoundPart::new(Iso::IDENTITY, Shape::hull(&hull))];
        assert!(Compound::new(&with_hull).is_ok());
    }
}
