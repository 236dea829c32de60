//! Convex shapes, one file each: support points, supporting faces with feature ids,
//! bounds under a pose, mass properties and ray casts, all in the shape's local frame.
//!
//! Every shape is a *core* (a point, a segment, a box, a hull, a triangle) inflated by a
//! *radius* (zero for polytopes): a sphere is a point core with a radius, a capsule a
//! segment core. GJK runs on the cores and adds the radii; supporting faces are faces of
//! the core.

mod capsule;
mod compound;
mod cuboid;
mod heightfield;
mod hull;
mod mesh;
mod plane;
mod sphere;
mod triangle;

pub use capsule::Capsule;
pub use compound::{Compound, CompoundPart, MAX_COMPOUND_PARTS};
pub use cuboid::Cuboid;
pub use heightfield::{HeightField, MAX_HEIGHT_FIELD_CELLS};
pub(crate) use hull::EDGE_TILT_SIN;
pub use hull::{
    ConvexHull, MAX_HULL_EDGES, MAX_HULL_FACES, MAX_HULL_INPUT_POINTS, MAX_HULL_VERTICES,
};
pub use mesh::{BvhNode, TriangleMesh, MAX_BVH_DEPTH, MAX_MESH_TRIANGLES};
pub use plane::HalfSpace;
pub use sphere::Sphere;
pub use triangle::Triangle;

use crate::error::{finite_vec, Error, Input};
use crate::math::{Aabb, Iso, Mat3, Vec3};

/// Most vertices a supporting face may have.
pub const MAX_FACE_VERTICES: usize = 16;

/// Smallest size (m) a sphere radius, capsule radius or half-height, or box half-extent may
/// have: below it `f32` rounding in the narrow phase is no longer small against the shape.
pub const MIN_SIZE: f32 = 1.0e-3;

/// Largest size (m) of the same: past it, distances within the shape lose the millimetre
/// precision the tolerances assume.
pub const MAX_SIZE: f32 = 1.0e3;

/// Check a size: finite, positive, and within [`MIN_SIZE`, `MAX_SIZE`].
pub(crate) fn size(x: f32, what: Input) -> Result<f32, Error> {
    crate::error::positive(x, what)?;
    if (MIN_SIZE..=MAX_SIZE).contains(&x) {
        Ok(x)
    } else {
        Err(Error::OutOfRange(what))
    }
}

/// Half-size (m) of the bounding box reported for an unbounded half-space.
pub const HALF_SPACE_EXTENT: f32 = 1.0e5;

/// What kind of feature a [`FeatureId`] names.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord)]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub enum FeatureKind {
    /// A vertex of the core.
    Vertex,
    /// An edge of the core.
    Edge,
    /// A face of the core.
    Face,
}

/// A vertex, edge or face of a shape's core, stable for as long as the shape exists.
/// Packed in a `u32`: the kind in bits 30–31, the index in bits 0–15.
/// Edges are named by their two vertex indices: `min · 256 + max`.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash, PartialOrd, Ord, Default)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
#[cfg_attr(feature = "defmt", derive(defmt::Format))]
pub struct FeatureId(pub u32);

impl FeatureId {
    /// Vertex `i`.
    #[inline]
    pub const fn vertex(i: u32) -> FeatureId {
        FeatureId(i & 0xffff)
    }

    /// The edge between vertices `a` and `b` (order does not matter).
    #[inline]
    pub const fn edge(a: u32, b: u32) -> FeatureId {
        let (lo, hi) = if a < b { (a, b) } else { (b, a) };
        FeatureId((1 << 30) | ((lo & 0xff) << 8) | (hi & 0xff))
    }

    /// Face `i`.
    #[inline]
    pub const fn face(i: u32) -> FeatureId {
        FeatureId((2 << 30) | (i & 0xffff))
    }

    /// The kind of feature.
    #[inline]
    pub const fn kind(self) -> FeatureKind {
        match self.0 >> 30 {
            0 => FeatureKind::Vertex,
            1 => FeatureKind::Edge,
            _ => FeatureKind::Face,
        }
    }

    /// The index within its kind.
    #[inline]
    pub const fn index(self) -> u32 {
        self.0 & 0xffff
    }
}

/// A supporting face of a core: a convex polygon in the shape's local frame, vertices in
/// counter-clockwise order seen from outside (right-handed about `normal`). One vertex
/// means a point, two a segment.
///
/// `N` is its capacity: [`MAX_FACE_VERTICES`] for the faces the public API hands out; the
/// narrow phase keeps a box's faces in `Face<4>` and a triangle's in `Face<3>`, under a
/// third of the bytes to build, move and clip.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Face<const N: usize = MAX_FACE_VERTICES> {
    /// Outward unit normal (local frame). For a point or segment: the query direction.
    pub normal: Vec3,
    /// The face's own id (a face, edge or vertex feature).
    pub id: FeatureId,
    /// Number of vertices used, 1 to `N`.
    pub len: u8,
    /// Vertices (local frame, m).
    pub vertices: [Vec3; N],
    /// Feature id of each vertex.
    pub vertex_ids: [FeatureId; N],
    /// Feature id of the edge from vertex `i` to vertex `i + 1` (wrapping).
    pub edge_ids: [FeatureId; N],
}

impl<const N: usize> Face<N> {
    /// An empty face with the given normal and id; fill it with [`Face::push`].
    pub const fn new(normal: Vec3, id: FeatureId) -> Face<N> {
        Face {
            normal,
            id,
            len: 0,
            vertices: [Vec3::ZERO; N],
            vertex_ids: [FeatureId(0); N],
            edge_ids: [FeatureId(0); N],
        }
    }

    /// Append a vertex and the id of the edge that leaves it; ignored when full.
    pub fn push(&mut self, v: Vec3, vertex_id: FeatureId, edge_id: FeatureId) {
        let i = self.len as usize;
        if i < N {
            self.vertices[i] = v;
            self.vertex_ids[i] = vertex_id;
            self.edge_ids[i] = edge_id;
            self.len += 1;
        }
    }

    /// The number of vertices in use: `len`, at most `N` (a `len` set beyond it through
    /// the public field reads as a full face).
    #[inline]
    fn used(&self) -> usize {
        (self.len as usize).min(N)
    }

    /// The vertices in use: the first `len`, at most `N`.
    #[inline]
    pub fn points(&self) -> &[Vec3] {
        self.vertices.get(..self.used()).unwrap_or(&[])
    }

    /// The ids of the vertices in use.
    #[inline]
    pub(crate) fn used_vertex_ids(&self) -> &[FeatureId] {
        self.vertex_ids.get(..self.used()).unwrap_or(&[])
    }

    /// The ids of the edges leaving the vertices in use.
    #[inline]
    pub(crate) fn used_edge_ids(&self) -> &[FeatureId] {
        self.edge_ids.get(..self.used()).unwrap_or(&[])
    }

    /// Move the face into another frame in place: `x ↦ r x + t` for its vertices, `r n`
    /// for its normal (`r` a rotation matrix).
    #[inline]
    pub(crate) fn transform_by(&mut self, r: &Mat3, t: Vec3) {
        self.normal = r.mul_vec(self.normal);
        let n = self.used();
        for v in self.vertices.iter_mut().take(n) {
            *v = r.mul_vec(*v) + t;
        }
    }

    /// The face moved into another frame by `iso`.
    pub fn transformed(&self, iso: &Iso) -> Face<N> {
        let mut f = *self;
        f.normal = iso.transform_vector(self.normal);
        let n = f.used();
        for v in f.vertices.iter_mut().take(n) {
            *v = iso.transform_point(*v);
        }
        f
    }

    /// The same face with room for `M` vertices (the first `M` when `M < len`).
    pub(crate) fn with_capacity<const M: usize>(&self) -> Face<M> {
        let mut f = Face::new(self.normal, self.id);
        for ((v, vid), eid) in self
            .points()
            .iter()
            .zip(self.used_vertex_ids())
            .zip(self.used_edge_ids())
        {
            f.push(*v, *vid, *eid);
        }
        f
    }
}

/// What the narrow phase reads of a face, whatever its capacity: the clipper and the
/// separating axis test take any `Face<N>` through it.
pub(crate) trait Polygon: Copy {
    /// Outward unit normal.
    fn normal(&self) -> Vec3;
    /// The face's own id.
    fn id(&self) -> FeatureId;
    /// The vertices in use.
    fn points(&self) -> &[Vec3];
    /// The ids of the vertices in use.
    fn vertex_ids(&self) -> &[FeatureId];
    /// The ids of the edges leaving the vertices in use.
    fn edge_ids(&self) -> &[FeatureId];
    /// Move into another frame in place ([`Face::transform_by`]).
    fn transform_by(&mut self, r: &Mat3, t: Vec3);
    /// True for a face whose corners are all right angles: a box's face (`Face<4>`,
    /// which holds nothing else). Its side planes meet square, so a clipped point that
    /// passes them lies in the face up to rounding, and the clip leaves out the box test
    /// that catches points past a sliver's tip (`collide::clip`).
    const RIGHT_ANGLED: bool = false;
}

impl<const N: usize> Polygon for Face<N> {
    /// `Face<4>` holds a box's faces only (type docs).
    const RIGHT_ANGLED: bool = N == 4;
    #[inline]
    fn normal(&self) -> Vec3 {
        self.normal
    }
    #[inline]
    fn id(&self) -> FeatureId {
        self.id
    }
    #[inline]
    fn points(&self) -> &[Vec3] {
        Face::points(self)
    }
    #[inline]
    fn vertex_ids(&self) -> &[FeatureId] {
        self.used_vertex_ids()
    }
    #[inline]
    fn edge_ids(&self) -> &[FeatureId] {
        self.used_edge_ids()
    }
    #[inline]
    fn transform_by(&mut self, r: &Mat3, t: Vec3) {
        Face::transform_by(self, r, t)
    }
}

/// Mass, centre of mass and inertia of a shape of uniform density.
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct MassProperties {
    /// Mass (kg).
    pub mass: f32,
    /// Centre of mass in the shape's local frame (m).
    pub center: Vec3,
    /// Inertia tensor about the centre of mass, in the local frame's axes (kg·m²).
    pub inertia: Mat3,
}

/// A ray: `origin + t · direction` for `t >= 0`, `direction` of unit length, `t` in metres.
///
/// # Examples
///
/// ```
/// use carom::{Iso, Ray, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// // From x = -5 towards +x (the direction is normalised).
/// let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::new(2.0, 0.0, 0.0))?;
/// let ball = Shape::sphere(1.0)?;
/// let hit = ball.cast_ray(&Iso::IDENTITY, &ray, 100.0)?.expect("the ray meets the ball");
/// assert!((hit.t - 4.0).abs() < 1e-5); // enters at x = -1
/// assert!((hit.normal.x + 1.0).abs() < 1e-5);
/// assert_eq!(ball.cast_ray(&Iso::IDENTITY, &ray, 3.0)?, None); // too short
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
#[cfg_attr(feature = "arbitrary", derive(arbitrary::Arbitrary))]
pub struct Ray {
    /// Start point (m).
    pub origin: Vec3,
    /// Unit direction.
    pub direction: Vec3,
}

impl Ray {
    /// A ray from an origin and a direction; the direction is normalised. Fails on
    /// non-finite input or a zero direction.
    pub fn new(origin: Vec3, direction: Vec3) -> Result<Ray, Error> {
        crate::error::position(origin)?;
        finite_vec(direction, Input::Direction)?;
        let (d, _) = direction
            .normalize_and_length()
            .ok_or(Error::NotPositive(Input::Direction))?;
        Ok(Ray {
            origin,
            direction: d,
        })
    }

    /// The point at distance `t`.
    #[inline]
    pub fn at(&self, t: f32) -> Vec3 {
        self.origin + self.direction * t
    }
}

/// Where a ray first meets a shape.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct RayHit {
    /// Distance along the ray (m); 0 when the origin is inside the shape.
    pub t: f32,
    /// The hit point (same frame as the ray).
    pub point: Vec3,
    /// Outward unit surface normal at the hit (same frame as the ray); for an origin
    /// inside the shape, the reversed ray direction.
    pub normal: Vec3,
}

/// A convex collision shape. Hulls are borrowed, so a world full of the same hull keeps one
/// copy of it (in a `static`, on the stack or in a `Box`).
///
/// # Examples
///
/// ```
/// use carom::{Error, Input, Iso, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// let ball = Shape::sphere(0.5)?;
/// let pill = Shape::capsule(0.5, 0.25)?; // along local Y: 1.5 m long in all
/// let crate_box = Shape::cuboid(Vec3::new(0.5, 0.5, 0.5))?;
/// let floor = Shape::half_space(Vec3::Y)?; // static bodies only
///
/// // Sizes are checked when a shape is built.
/// assert_eq!(Shape::sphere(0.0), Err(Error::NotPositive(Input::Radius)));
///
/// // Mass properties at a density (kg/m³), and bounds at a pose.
/// assert!((crate_box.mass_properties(1000.0)?.mass - 1000.0).abs() < 1e-2);
/// let bounds = pill.aabb(&Iso::from_position(Vec3::new(0.0, 2.0, 0.0)));
/// assert!((bounds.max.y - 2.75).abs() < 1e-6);
/// assert_eq!(ball.radius(), 0.5);
/// assert!(floor.is_static_only());
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Shape<'a> {
    /// A ball.
    Sphere(Sphere),
    /// A segment along local Y with a radius.
    Capsule(Capsule),
    /// A box.
    Cuboid(Cuboid),
    /// A convex polytope built from points.
    Hull(&'a ConvexHull),
    /// A half-space below a plane through the local origin (static bodies only).
    HalfSpace(HalfSpace),
    /// A single triangle (static bodies only; no volume).
    Triangle(Triangle),
    /// A triangle mesh with its hierarchy (static and kinematic bodies only; no volume).
    /// Not convex: the world's mid phase pairs each nearby triangle with the other body,
    /// and the convex-shape queries of [`crate::collide`] refuse it with
    /// [`Error::NotConvex`].
    Mesh(&'a TriangleMesh<'a>),
    /// A height field: terrain as a grid of heights (static and kinematic bodies only; no
    /// volume). Not convex: the mid phase pairs each nearby triangle of its cells with the
    /// other body, and the convex-shape queries refuse it with [`Error::NotConvex`].
    HeightField(&'a HeightField<'a>),
    /// Convex parts at poses in the body's frame. Not convex as a whole: the mid phase
    /// pairs each nearby part with the other body, and the convex-shape queries refuse it
    /// with [`Error::NotConvex`].
    Compound(&'a Compound<'a>),
}

impl Shape<'static> {
    /// A sphere of `radius` metres (in [`MIN_SIZE`, `MAX_SIZE`]).
    pub fn sphere(radius: f32) -> Result<Shape<'static>, Error> {
        Ok(Shape::Sphere(Sphere::new(radius)?))
    }

    /// A capsule along local Y: a segment of length `2 half_height` inflated by `radius`
    /// (both in [`MIN_SIZE`, `MAX_SIZE`]).
    pub fn capsule(half_height: f32, radius: f32) -> Result<Shape<'static>, Error> {
        Ok(Shape::Capsule(Capsule::new(half_height, radius)?))
    }

    /// A box with the given half-extents (m, each in [`MIN_SIZE`, `MAX_SIZE`]).
    pub fn cuboid(half_extents: Vec3) -> Result<Shape<'static>, Error> {
        Ok(Shape::Cuboid(Cuboid::new(half_extents)?))
    }

    /// The half-space `{p : normal · p <= 0}` in local coordinates.
    pub fn half_space(normal: Vec3) -> Result<Shape<'static>, Error> {
        Ok(Shape::HalfSpace(HalfSpace::new(normal)?))
    }

    /// A triangle with vertices `a, b, c` (counter-clockwise about its normal).
    pub fn triangle(a: Vec3, b: Vec3, c: Vec3) -> Result<Shape<'static>, Error> {
        Ok(Shape::Triangle(Triangle::new(a, b, c)?))
    }
}

impl<'a> Shape<'a> {
    /// A shape from a built convex hull.
    pub fn hull(hull: &'a ConvexHull) -> Shape<'a> {
        Shape::Hull(hull)
    }

    /// True for shapes a dynamic body may not use (half-space, triangle, mesh: they have
    /// no volume); kinematic bodies may use triangles and meshes.
    pub fn is_static_only(&self) -> bool {
        matches!(
            self,
            Shape::HalfSpace(_) | Shape::Triangle(_) | Shape::Mesh(_) | Shape::HeightField(_)
        )
    }

    /// True for the shapes the narrow phase takes as they are; false for a mesh, a height
    /// field or a compound, whose parts it takes one at a time.
    #[inline]
    pub fn is_convex(&self) -> bool {
        !matches!(
            self,
            Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_)
        )
    }

    /// [`Error::NotConvex`] for a mesh, height field or compound (the convex-shape queries' door).
    pub(crate) fn check_convex(&self) -> Result<(), Error> {
        if self.is_convex() {
            Ok(())
        } else {
            Err(Error::NotConvex)
        }
    }

    /// The radius that inflates the core (m); zero for polytopes.
    #[inline]
    pub fn radius(&self) -> f32 {
        match self {
            Shape::Sphere(s) => s.radius,
            Shape::Capsule(c) => c.radius,
            _ => 0.0,
        }
    }

    /// Largest distance from the local origin to a point of the core (m): how far a turn
    /// about the origin moves a point of the shape, per radian. The inflating radius turns
    /// onto itself, so a ball has reach 0 and a capsule its half-height.
    #[inline]
    pub(crate) fn core_reach(&self) -> f32 {
        core_reach_within(self.bounding_radius(), self.radius())
    }

    /// The core's furthest point along `dir` (local frame) and its vertex index.
    /// A half-space has no support point; it answers with the origin.
    #[inline]
    pub fn core_support(&self, dir: Vec3) -> (Vec3, u32) {
        match self {
            Shape::Sphere(_) => (Vec3::ZERO, 0),
            Shape::Capsule(c) => c.core_support(dir),
            Shape::Cuboid(b) => b.core_support(dir),
            Shape::Hull(h) => h.core_support(dir),
            Shape::HalfSpace(_) => (Vec3::ZERO, 0),
            Shape::Triangle(t) => t.core_support(dir),
            Shape::Mesh(m) => mesh_support(m, dir),
            Shape::HeightField(f) => field_support(f, dir),
            Shape::Compound(c) => c.support(dir),
        }
    }

    /// Core vertex `index` (local frame); out-of-range indices give vertex 0.
    #[inline]
    pub fn core_vertex(&self, index: u32) -> Vec3 {
        match self {
            Shape::Sphere(_) => Vec3::ZERO,
            Shape::Capsule(c) => c.core_vertex(index),
            Shape::Cuboid(b) => b.core_vertex(index),
            Shape::Hull(h) => h.core_vertex(index),
            Shape::HalfSpace(_) => Vec3::ZERO,
            Shape::Triangle(t) => t.core_vertex(index),
            Shape::Mesh(m) => m
                .vertices()
                .get(index as usize)
                .copied()
                .unwrap_or_default(),
            Shape::HeightField(_) | Shape::Compound(_) => Vec3::ZERO,
        }
    }

    /// How many core vertices [`Shape::core_vertex`] numbers (the core is their convex
    /// hull): 1 for a sphere (its centre), 2 for a capsule, 8 for a box, a hull's vertex
    /// count, 3 for a triangle; `None` for a half-space, which has no finite core, and
    /// for a mesh or compound, which are not convex.
    pub fn core_vertex_count(&self) -> Option<u32> {
        match self {
            Shape::Sphere(_) => Some(1),
            Shape::Capsule(_) => Some(2),
            Shape::Cuboid(_) => Some(8),
            Shape::Hull(h) => Some(h.vertices().len() as u32),
            Shape::HalfSpace(_) | Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => {
                None
            }
            Shape::Triangle(_) => Some(3),
        }
    }

    /// The furthest surface point along `dir` (local frame): core support plus radius.
    pub fn support(&self, dir: Vec3) -> Vec3 {
        let (p, _) = self.core_support(dir);
        let r = self.radius();
        if r > 0.0 {
            p + dir.normalize_or(Vec3::Y) * r
        } else {
            p
        }
    }

    /// The face of the core that best supports `dir` (local frame): the face whose normal
    /// is most aligned with `dir`, or an edge or vertex where the core has no such face.
    /// For a mesh or compound, the supporting point as a one-vertex face.
    pub fn supporting_face(&self, dir: Vec3) -> Face {
        match self {
            Shape::Sphere(_) | Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => {
                let (p, i) = self.core_support(dir);
                let mut f = Face::new(dir.normalize_or(Vec3::Y), FeatureId::vertex(i));
                f.push(p, FeatureId::vertex(i), FeatureId::vertex(i));
                f
            }
            Shape::Capsule(c) => c.supporting_face(dir),
            Shape::Cuboid(b) => b.supporting_face(dir),
            Shape::Hull(h) => h.supporting_face(dir),
            Shape::HalfSpace(p) => p.supporting_face(dir),
            Shape::Triangle(t) => t.supporting_face(dir),
        }
    }

    /// Bounding box in the shape's local frame.
    pub fn local_aabb(&self) -> Aabb {
        self.aabb(&Iso::IDENTITY)
    }

    /// Bounding box under `pose` (world frame).
    pub fn aabb(&self, pose: &Iso) -> Aabb {
        match self {
            Shape::Sphere(s) => Aabb::from_center_half(pose.position, Vec3::splat(s.radius)),
            Shape::Capsule(c) => c.aabb(pose),
            Shape::Cuboid(b) => Aabb::from_local_box(pose, b.half_extents),
            Shape::Hull(h) => h.aabb(pose),
            Shape::HalfSpace(p) => p.aabb(pose),
            Shape::Triangle(t) => t.aabb(pose),
            Shape::Mesh(m) => m.aabb().transformed(pose),
            Shape::HeightField(f) => f.aabb().transformed(pose),
            Shape::Compound(c) => c.aabb(pose),
        }
    }

    /// [`Shape::aabb`] given `r = Mat3::from_quat(pose.rotation)`: the same box, without
    /// forming the matrix again for a cuboid or a hull.
    #[inline]
    pub(crate) fn aabb_turned(&self, pose: &Iso, r: &crate::math::Mat3) -> Aabb {
        match self {
            Shape::Cuboid(b) => Aabb::from_local_box_turned(pose.position, r, b.half_extents),
            Shape::Hull(h) => h.aabb_turned(pose, r),
            _ => self.aabb(pose),
        }
    }

    /// Largest distance from the local origin to any point of the shape (m); for a
    /// half-space, [`HALF_SPACE_EXTENT`].
    pub fn bounding_radius(&self) -> f32 {
        match self {
            Shape::Sphere(s) => s.radius,
            Shape::Capsule(c) => c.half_height + c.radius,
            Shape::Cuboid(b) => b.half_extents.length(),
            Shape::Hull(h) => h.bounding_radius(),
            Shape::HalfSpace(_) => HALF_SPACE_EXTENT,
            Shape::Triangle(t) => t.bounding_radius(),
            Shape::Mesh(_) | Shape::HeightField(_) => {
                let b = self.local_aabb();
                b.min.abs().max(b.max.abs()).length()
            }
            Shape::Compound(c) => c.bounding_radius(),
        }
    }

    /// Smallest extent: the thickness a fast body can tunnel through in one step (m).
    /// For a triangle or mesh, zero; for a compound, its thinnest part's.
    pub fn min_extent(&self) -> f32 {
        match self {
            Shape::Sphere(s) => 2.0 * s.radius,
            Shape::Capsule(c) => 2.0 * c.radius,
            Shape::Cuboid(b) => 2.0 * b.half_extents.min_elem(),
            Shape::Hull(h) => h.min_extent(),
            Shape::HalfSpace(_) => HALF_SPACE_EXTENT,
            Shape::Triangle(_) | Shape::Mesh(_) | Shape::HeightField(_) => 0.0,
            Shape::Compound(c) => c.min_extent(),
        }
    }

    /// Mass properties for a uniform `density` (kg/m³). Fails for a non-positive or
    /// non-finite density and for shapes without volume.
    pub fn mass_properties(&self, density: f32) -> Result<MassProperties, Error> {
        crate::error::positive(density, Input::Density)?;
        let props = match self {
            Shape::Sphere(s) => s.mass_properties(density),
            Shape::Capsule(c) => c.mass_properties(density),
            Shape::Cuboid(b) => b.mass_properties(density),
            Shape::Hull(h) => h.mass_properties(density),
            Shape::Compound(c) => c.mass_properties(density)?,
            Shape::HalfSpace(_) | Shape::Triangle(_) | Shape::Mesh(_) | Shape::HeightField(_) => {
                return Err(Error::NoVolume)
            }
        };
        // A huge density times a large shape can overflow `f32`.
        if props.mass.is_finite() && props.mass > 0.0 && props.inertia.is_finite() {
            Ok(props)
        } else {
            Err(Error::OutOfRange(Input::Density))
        }
    }

    /// Cast a ray (world frame) against the shape under `pose`, up to `max_t` metres.
    /// `Ok(None)` means no hit. Fails on a non-finite ray, pose or `max_t`, or a negative
    /// `max_t`.
    pub fn cast_ray(&self, pose: &Iso, ray: &Ray, max_t: f32) -> Result<Option<RayHit>, Error> {
        crate::error::non_negative(max_t, Input::Distance)?;
        crate::error::position(ray.origin)?;
        finite_vec(ray.direction, Input::Direction)?;
        if crate::math::scalar::abs(ray.direction.length_squared() - 1.0) > 1.0e-3 {
            return Err(Error::NotUnit(Input::Direction));
        }
        crate::collide::check_pose(pose)?;
        Ok(self.cast_ray_unchecked(pose, ray, max_t))
    }

    /// [`Shape::cast_ray`] without input checks (inputs must be finite, the ray direction
    /// unit length).
    pub(crate) fn cast_ray_unchecked(&self, pose: &Iso, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let local = Ray {
            origin: pose.inverse_transform_point(ray.origin),
            direction: pose.inverse_transform_vector(ray.direction),
        };
        let hit = match self {
            Shape::Sphere(s) => s.cast_ray(&local, max_t),
            Shape::Capsule(c) => c.cast_ray(&local, max_t),
            Shape::Cuboid(b) => b.cast_ray(&local, max_t),
            Shape::Hull(h) => h.cast_ray(&local, max_t),
            Shape::HalfSpace(p) => p.cast_ray(&local, max_t),
            Shape::Triangle(t) => t.cast_ray(&local, max_t),
            Shape::Mesh(m) => m.cast_ray(&local, max_t).map(|(_, h)| h),
            Shape::HeightField(f) => f.cast_ray(&local, max_t).map(|(_, h)| h),
            Shape::Compound(c) => c.cast_ray(&local, max_t).map(|(_, h)| h),
        }?;
        Some(RayHit {
            t: hit.t,
            point: pose.transform_point(hit.point),
            normal: pose.transform_vector(hit.normal),
        })
    }
}

/// A mesh's furthest vertex along `dir` (the first of equals) and its index: the support
/// of the mesh's convex hull, by a scan of every vertex.
fn mesh_support(m: &TriangleMesh<'_>, dir: Vec3) -> (Vec3, u32) {
    let mut best = (Vec3::ZERO, 0u32);
    let mut best_d = f32::NEG_INFINITY;
    for (i, &v) in m.vertices().iter().enumerate() {
        let d = v.dot(dir);
        if d > best_d {
            best_d = d;
            best = (v, i as u32);
        }
    }
    best
}

/// A height field's furthest sample along `dir` (the first of equals) and its index: the
/// support of the field's convex hull, by a scan of every sample.
fn field_support(f: &HeightField<'_>, dir: Vec3) -> (Vec3, u32) {
    let mut best = (Vec3::ZERO, 0u32);
    let mut best_d = f32::NEG_INFINITY;
    let columns = f.columns().max(1);
    for (k, &h) in f.heights().iter().enumerate() {
        let (i, j) = (k as u32 % columns, k as u32 / columns);
        let v = Vec3::new(i as f32 * f.cell_size(), h, j as f32 * f.cell_size());
        let d = v.dot(dir);
        if d > best_d {
            best_d = d;
            best = (v, k as u32);
        }
    }
    best
}

/// [`Shape::core_reach`] from a shape's bounding radius and inflating radius (m).
#[inline]
pub(crate) fn core_reach_within(bounding_radius: f32, radius: f32) -> f32 {
    crate::math::scalar::max(bounding_radius - radius, 0.0)
}
