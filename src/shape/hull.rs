//! Convex hull: built on the stack from a point cloud, with a fixed bound on vertices and
//! faces. Faces are convex polygons (coplanar triangles merged), each with its plane.
//!
//! [`ConvexHull::new`] runs in three stages, each in its own section below:
//! 1. validation and the initial tetrahedron (the extreme points), which also classify a
//!    degenerate cloud as coincident, collinear or coplanar;
//! 2. quickhull (Barber, Dobkin and Huhdanpaa 1996, "The Quickhull Algorithm for Convex
//!    Hulls") on a triangle mesh held in fixed working arrays;
//! 3. faces: triangles within tolerance of a common plane merge into one convex polygon,
//!    and vertices left inside a polygon or on a straight edge are dropped.
//!
//! Mass properties sum tetrahedra (Tonon 2004; the covariance form of Blow and Binstock
//! 2004); ray casts clip the ray against every face plane (Cyrus and Beck 1978).

use super::{Face, FeatureId, MassProperties, Ray, RayHit, MAX_FACE_VERTICES};
use crate::error::{Error, HullError, Input};
use crate::math::lanes::{F4, V4};
use crate::math::vec64::Vec64;
use crate::math::{scalar, Aabb, Iso, Mat3, Vec3};

/// Most vertices a hull keeps.
pub const MAX_HULL_VERTICES: usize = 64;
/// Most faces a hull keeps (a triangulated hull of `V` vertices has `2V − 4`).
pub const MAX_HULL_FACES: usize = 2 * MAX_HULL_VERTICES - 4;
/// Most polygon corners over all faces (twice the edge bound `3V − 6`).
pub const MAX_HULL_FACE_INDICES: usize = 2 * (3 * MAX_HULL_VERTICES - 6);
/// Most edges a hull keeps: a polyhedron of `V` vertices has at most `3V − 6`.
pub const MAX_HULL_EDGES: usize = 3 * MAX_HULL_VERTICES - 6;
/// Most points [`ConvexHull::new`] accepts.
pub const MAX_HULL_INPUT_POINTS: usize = 1024;

/// A convex polytope. Build it with [`ConvexHull::new`]; it is plain data, `Copy`, and about
/// 4.9 KiB (0.75 KiB of it a second copy of the vertices, laid out for the support scans).
///
/// # Examples
///
/// ```
/// use carom::{ConvexHull, Error, HullError, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// // A unit cube's corners and one point inside it.
/// let mut points = [Vec3::ZERO; 9];
/// for (i, p) in points.iter_mut().take(8).enumerate() {
///     *p = Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32);
/// }
/// points[8] = Vec3::splat(0.5);
/// let hull = ConvexHull::new(&points)?;
/// assert_eq!(hull.vertices().len(), 8); // the inner point is not a vertex
///
/// // Shapes borrow hulls: many bodies can share this one.
/// let shape = Shape::hull(&hull);
/// assert!((shape.mass_properties(1.0)?.mass - 1.0).abs() < 1e-4);
///
/// // Flat clouds have no volume.
/// let flat = [Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::new(1.0, 0.0, 1.0)];
/// assert_eq!(ConvexHull::new(&flat), Err(Error::Hull(HullError::Coplanar)));
/// # Ok(())
/// # }
/// ```
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ConvexHull {
    /// Vertices (local frame, m); the first `vertex_count` are used.
    pub(crate) vertices: [Vec3; MAX_HULL_VERTICES],
    pub(crate) vertex_count: u8,
    /// Face planes: outward unit normal and offset `d` with `n · p = d` on the face.
    pub(crate) normals: [Vec3; MAX_HULL_FACES],
    pub(crate) offsets: [f32; MAX_HULL_FACES],
    /// Face `f`'s corners are `face_indices[face_start[f] .. face_start[f] + face_len[f]]`,
    /// counter-clockwise about its normal.
    pub(crate) face_start: [u16; MAX_HULL_FACES],
    pub(crate) face_len: [u8; MAX_HULL_FACES],
    pub(crate) face_count: u8,
    pub(crate) face_indices: [u8; MAX_HULL_FACE_INDICES],
    /// Edges between faces that are not coplanar, `[v0, v1, face0, face1]` with `v0 < v1`,
    /// `face0` the face that runs `v0 → v1` counter-clockwise, `face1` the one that runs
    /// `v1 → v0` (see [`HullEdge`]); the first `edge_count` are used, in the order of
    /// their first corner. The seams of a face split into fan pieces are left out.
    pub(crate) edges: [[u8; 4]; MAX_HULL_EDGES],
    pub(crate) edge_count: u8,
    /// True when every corner's edge found the face on its other side (always, for a
    /// closed mesh): the edge list is complete and the separating axis test may use it.
    pub(crate) closed: bool,
    /// Centroid of the volume (local frame).
    pub(crate) centroid: Vec3,
    /// The distance tolerance the hull was built with (m).
    pub(crate) tolerance: f32,
    /// True when the cloud needed more than [`MAX_HULL_VERTICES`] vertices and the hull
    /// keeps the greedy subset described at [`ConvexHull::new`].
    pub(crate) reduced: bool,
    /// Thinnest width (m), computed once at build ([`ConvexHull::min_extent`]): the
    /// continuous-collision test asks for it for every body every step.
    pub(crate) thinnest: f32,
    /// True when every edge runs along its two faces' crossing line within
    /// [`EDGE_TILT_SIN`], computed once at build: the separating axis test prunes edge
    /// pairs only between such shapes.
    pub(crate) well_formed_edges: bool,
    /// The centroid's least distance to a face plane (m), 0 if that is not positive,
    /// computed once at build: the radius of a ball about the centroid inside the hull,
    /// which the separating axis test's bounds use on every query.
    pub(crate) inner_radius: f32,
    /// The largest vertex distance from the local origin (m), computed once at build:
    /// [`Shape::bounding_radius`](crate::Shape::bounding_radius), asked for on every part
    /// contact and every swept pair.
    pub(crate) outer_radius: f32,
    /// The vertices four to a group as lanes (`vertex_lanes[g]` holds vertices
    /// `4g .. 4g + 4`), written once at build: the support scans read them four products
    /// at a time. A last partial group's padding lanes repeat vertex 0.
    pub(crate) vertex_lanes: [V4; MAX_HULL_VERTICES / 4],
}

/// Largest `|u · n|` (u an edge's unit vector, n the normal of a face beside it) for
/// which a hull edge counts as running along its faces' crossing line. A merged, slightly
/// non-planar face can leave edges tilted more than that.
pub(crate) const EDGE_TILT_SIN: f32 = 1.0e-5;

/// One edge of a hull between two faces that are not coplanar: its end vertices
/// `v0 < v1` and the faces on either side. `face0` runs along `v0 → v1` counter-clockwise
/// about its normal, `face1` along `v1 → v0`, so `normal(face1) × normal(face0)` points
/// along `v0 − v1`: the edge vector stands in for that cross product in the separating
/// axis test.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) struct HullEdge {
    /// Lower vertex index.
    pub v0: u8,
    /// Higher vertex index.
    pub v1: u8,
    /// Face along `v0 → v1`.
    pub face0: u8,
    /// Face along `v1 → v0`.
    pub face1: u8,
}

/// A hull with nothing in it, filled by the builder.
const EMPTY_HULL: ConvexHull = ConvexHull {
    vertices: [Vec3::ZERO; MAX_HULL_VERTICES],
    vertex_lanes: [V4::ZERO; MAX_HULL_VERTICES / 4],
    vertex_count: 0,
    normals: [Vec3::ZERO; MAX_HULL_FACES],
    offsets: [0.0; MAX_HULL_FACES],
    face_start: [0; MAX_HULL_FACES],
    face_len: [0; MAX_HULL_FACES],
    face_count: 0,
    face_indices: [0; MAX_HULL_FACE_INDICES],
    edges: [[0; 4]; MAX_HULL_EDGES],
    edge_count: 0,
    closed: false,
    centroid: Vec3::ZERO,
    tolerance: 0.0,
    reduced: false,
    thinnest: 0.0,
    well_formed_edges: false,
    inner_radius: 0.0,
    outer_radius: 0.0,
};

/// The hull of the unit tetrahedron's corners `0, x, y, z`, field for field what
/// [`ConvexHull::new`] builds from them (a test holds the two to the bit), written out so
/// it can be a constant.
const fn unit_tetrahedron() -> ConvexHull {
    let mut h = EMPTY_HULL;
    write_unit_tetrahedron(&mut h);
    h
}

/// Write [`unit_tetrahedron`]'s fields over `h`, an [`EMPTY_HULL`] (the fields it leaves
/// are those of the empty hull): in place, with no hull staged on the stack.
const fn write_unit_tetrahedron(h: &mut ConvexHull) {
    // 1/√3 and 1/(4√3) as the builder rounds them (f64, then f32).
    const ROOT_THIRD: f32 = 0.577_350_26;
    const DEPTH: f32 = 0.144_337_56;
    h.vertices[1] = Vec3::X;
    h.vertices[2] = Vec3::Y;
    h.vertices[3] = Vec3::Z;
    h.vertex_count = 4;
    h.vertex_lanes[0] = V4 {
        x: F4([0.0, 1.0, 0.0, 0.0]),
        y: F4([0.0, 0.0, 1.0, 0.0]),
        z: F4([0.0, 0.0, 0.0, 1.0]),
    };
    // The slanted face first, then the faces on z = 0, x = 0 and y = 0.
    h.normals[0] = Vec3::new(ROOT_THIRD, ROOT_THIRD, ROOT_THIRD);
    h.normals[1] = Vec3::new(0.0, 0.0, -1.0);
    h.normals[2] = Vec3::new(-1.0, 0.0, 0.0);
    h.normals[3] = Vec3::new(0.0, -1.0, 0.0);
    h.offsets[0] = ROOT_THIRD;
    let corners: [[u8; 3]; 4] = [[1, 2, 3], [0, 2, 1], [0, 3, 2], [0, 1, 3]];
    let mut f = 0;
    while f < 4 {
        h.face_start[f] = 3 * f as u16;
        h.face_len[f] = 3;
        let mut k = 0;
        while k < 3 {
            h.face_indices[3 * f + k] = corners[f][k];
            k += 1;
        }
        f += 1;
    }
    h.face_count = 4;
    let edges: [[u8; 4]; 6] = [
        [1, 2, 0, 1],
        [2, 3, 0, 2],
        [0, 2, 1, 2],
        [0, 3, 2, 3],
        [0, 1, 3, 1],
        [1, 3, 3, 0],
    ];
    let mut e = 0;
    while e < 6 {
        h.edges[e] = edges[e];
        e += 1;
    }
    h.edge_count = 6;
    h.closed = true;
    h.centroid = Vec3::new(0.25, 0.25, 0.25);
    h.tolerance = ConvexHull::TOLERANCE;
    h.thinnest = ROOT_THIRD;
    h.well_formed_edges = true;
    h.inner_radius = DEPTH;
    h.outer_radius = 1.0;
}

impl ConvexHull {
    /// Relative distance tolerance: the build tolerance is this times the largest
    /// `|coordinate|` of the input (at least [`ConvexHull::MIN_TOLERANCE`]). It is measured
    /// from the origin, not the cloud's centre, because `f32` resolves coordinates far from
    /// the origin more coarsely: about 170 ulp of the largest coordinate.
    pub const TOLERANCE: f32 = 1.0e-5;
    /// Smallest build tolerance (m): keeps squared areas of the smallest accepted
    /// triangles (`tolerance⁴`) far above `f32`'s smallest normal number.
    pub const MIN_TOLERANCE: f32 = 1.0e-8;
    /// Largest `|coordinate|` accepted (m): the inertia of a hull this size (`~ L⁵`) stays
    /// finite in `f32` for densities up to 10⁶ kg/m³.
    pub const MAX_COORDINATE: f32 = 1.0e6;

    /// The hull of the unit tetrahedron's corners `(0, 0, 0)`, `(1, 0, 0)`, `(0, 1, 0)`,
    /// `(0, 0, 1)`: what [`ConvexHull::new`] gives for them, as a constant. A valid hull
    /// to fill arrays and `static`s with before [`ConvexHull::rebuild`] builds each slot
    /// in place (a hull is about 5 KB: on a microcontroller, a `static` array of them
    /// costs no stack, where one built by value is staged on it).
    ///
    /// ```
    /// use carom::{ConvexHull, Vec3};
    ///
    /// # fn main() -> Result<(), carom::Error> {
    /// let corners = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    /// assert_eq!(ConvexHull::new(&corners)?, ConvexHull::UNIT_TETRAHEDRON);
    /// # Ok(())
    /// # }
    /// ```
    pub const UNIT_TETRAHEDRON: ConvexHull = unit_tetrahedron();

    /// Build the convex hull of `points` (local frame, m), on the stack (about 26 KiB of
    /// working memory: 16 KiB of quickhull state, 5 KiB of polygons, the result), without
    /// allocating. The geometric tests run in f64 (only IEEE `+ − × ÷`, so the same bits on
    /// every target; soft-float on an MCU without a double-precision FPU).
    ///
    /// The build tolerance is `eps = max(TOLERANCE · max |coordinate|, MIN_TOLERANCE)`
    /// (see [`ConvexHull::TOLERANCE`]): a point less than `eps` outside the hull built so far
    /// is treated as on it, and triangles whose corners lie within `eps` of a common plane
    /// are merged into one face. Every input point ends up inside or within a few `eps` of
    /// every face plane (unless the hull is reduced, below). Where a point would be left
    /// more than `2 eps` outside (a small feature next to long, nearly coplanar faces,
    /// where the cone to it folds at the scale of `eps`), the mesh is built again at
    /// `eps / 16`, then `eps / 256`, in place; faces still merge within `eps`.
    ///
    /// The result:
    /// - vertices are input points (bit for bit), in input order; interior points, points
    ///   inside a face and points on a straight edge are dropped; of duplicate points the
    ///   first is kept;
    /// - faces are convex polygons counter-clockwise about their outward normal, each
    ///   starting at its lowest-index vertex. Coplanar triangles are merged; a merged face
    ///   of more than [`MAX_FACE_VERTICES`] corners is split into a fan of pieces from its
    ///   first corner, each of at most [`MAX_FACE_VERTICES`] corners (corners `0, 1..=15`,
    ///   then `0, 15..=29`, ...);
    /// - the same input (same points in the same order) gives the same hull, bit for bit.
    ///
    /// **Reduction.** When the cloud needs more than [`MAX_HULL_VERTICES`] vertices, the
    /// hull keeps the first [`MAX_HULL_VERTICES`] that quickhull picks: the initial
    /// tetrahedron (the two axis-extreme points farthest apart, the point farthest from
    /// their line, the point farthest from that plane), then again and again the input
    /// point farthest outside the hull so far (lowest index on ties). The result is the
    /// hull of those points: a polytope inside the true hull that approximates it
    /// greedily; [`ConvexHull::is_reduced`] reports it.
    ///
    /// Errors, checked in this order:
    /// - more than [`MAX_HULL_INPUT_POINTS`] points: `Hull(TooManyPoints)`;
    /// - a non-finite coordinate: `NonFinite(Input::Point)`;
    /// - a coordinate beyond `±MAX_COORDINATE`: `OutOfRange(Input::Point)`;
    /// - fewer than 4 points: `Hull(TooFewPoints)`;
    /// - all points within `eps` of one point, one line or one plane (duplicates do not
    ///   count as distinct): `Hull(Coincident)`, `Hull(Collinear)`, `Hull(Coplanar)`;
    /// - a numerically broken intermediate mesh (not seen in testing, but the builder
    ///   checks for it rather than trusting it): `Hull(TooComplex)`.
    #[inline(never)]
    pub fn new(points: &[Vec3]) -> Result<ConvexHull, Error> {
        let eps = validate(points)? as f64;
        let mut builder = Builder::new(points, eps);
        build_mesh(points, eps, &mut builder)?;
        // Made once the mesh stands, so the compiler builds it in the result.
        let mut hull = EMPTY_HULL;
        builder.finish(&mut hull)?;
        Ok(hull)
    }

    /// Build the convex hull of `points` into `self`, in place: the hull
    /// [`ConvexHull::new`] returns, bit for bit, without the result on the stack (the
    /// builder's working memory still is). For hulls kept in `static` storage or in a
    /// caller's array, filled first with [`ConvexHull::UNIT_TETRAHEDRON`].
    ///
    /// Fails as [`ConvexHull::new`] does. After an error `self` is
    /// [`ConvexHull::UNIT_TETRAHEDRON`], whatever it held before: a valid hull, never a
    /// partly written one (the one exception to [`Error`]'s "the call changed nothing":
    /// keeping the old hull would take a second one on the stack, the copy this method
    /// exists to avoid). No world can be using the slot meanwhile: a world borrows its
    /// hulls for as long as it lives.
    ///
    /// ```
    /// use carom::{ConvexHull, Error, HullError, Vec3};
    ///
    /// # fn main() -> Result<(), Error> {
    /// let mut hulls = [ConvexHull::UNIT_TETRAHEDRON; 2];
    /// let cube: [Vec3; 8] = core::array::from_fn(|i| {
    ///     Vec3::new((i & 1) as f32, ((i >> 1) & 1) as f32, ((i >> 2) & 1) as f32)
    /// });
    /// hulls[0].rebuild(&cube)?;
    /// assert_eq!(hulls[0], ConvexHull::new(&cube)?);
    ///
    /// let flat = [Vec3::ZERO, Vec3::X, Vec3::Z, Vec3::new(1.0, 0.0, 1.0)];
    /// assert_eq!(hulls[1].rebuild(&flat), Err(Error::Hull(HullError::Coplanar)));
    /// assert_eq!(hulls[1], ConvexHull::UNIT_TETRAHEDRON);
    /// # Ok(())
    /// # }
    /// ```
    pub fn rebuild(&mut self, points: &[Vec3]) -> Result<(), Error> {
        let built = self.build_in_place(points);
        if built.is_err() {
            // Field by field: assigning the constant would stage a hull on the stack.
            self.clear();
            write_unit_tetrahedron(self);
        }
        built
    }

    /// [`ConvexHull::new`] into `self`, cleared once the mesh stands (untouched when an
    /// error comes before that; unspecified after a later one).
    fn build_in_place(&mut self, points: &[Vec3]) -> Result<(), Error> {
        let eps = validate(points)? as f64;
        let mut builder = Builder::new(points, eps);
        build_mesh(points, eps, &mut builder)?;
        self.clear();
        builder.finish(self)
    }
}

/// The triangle mesh of `points` in `builder` (made by `Builder::new` with `eps`, the
/// tolerance [`validate`] gave): the first build, then the finer ones a point left far
/// outside asks for. Inlined into both callers, whose frame holds the builder.
#[inline(always)]
fn build_mesh<'p>(points: &'p [Vec3], eps: f64, builder: &mut Builder<'p>) -> Result<(), Error> {
    let simplex = initial_simplex(points, eps)?;
    let mut build_eps = eps;
    builder.restart(build_eps, simplex)?;
    builder.run()?;
    // A point the builder had to leave out (see `Builder::run`) can sit far outside
    // when a small feature meets long, nearly coplanar faces: the cone to it would
    // fold at the scale of `eps`. Build again at a finer scale, where the faces it
    // is nearly coplanar with are told apart; faces still merge at `eps`.
    for _ in 0..FINER_BUILDS {
        if builder.reduced || !builder.leaves_a_point_outside(RETRY_OUTSIDE * eps) {
            break;
        }
        let finer = build_eps * FINER_BUILD_FACTOR;
        builder.restart(finer, simplex)?;
        if builder.run().is_err() {
            // The finer mesh broke down: the coarser build stands (built again, in
            // place: one builder on the stack).
            builder.restart(build_eps, simplex)?;
            builder.run()?;
            break;
        }
        build_eps = finer;
    }
    Ok(())
}

impl ConvexHull {
    /// Make `self` [`EMPTY_HULL`] field by field, in place (assigning the constant staged
    /// a whole hull on the stack first). Every field is named: a new one fails to compile
    /// here until it is cleared too.
    fn clear(&mut self) {
        let ConvexHull {
            vertices,
            vertex_count,
            normals,
            offsets,
            face_start,
            face_len,
            face_count,
            face_indices,
            edges,
            edge_count,
            closed,
            centroid,
            tolerance,
            reduced,
            thinnest,
            well_formed_edges,
            inner_radius,
            outer_radius,
            vertex_lanes,
        } = self;
        vertices.fill(Vec3::ZERO);
        *vertex_count = 0;
        normals.fill(Vec3::ZERO);
        offsets.fill(0.0);
        face_start.fill(0);
        face_len.fill(0);
        *face_count = 0;
        face_indices.fill(0);
        edges.fill([0; 4]);
        *edge_count = 0;
        *closed = false;
        *centroid = Vec3::ZERO;
        *tolerance = 0.0;
        *reduced = false;
        *thinnest = 0.0;
        *well_formed_edges = false;
        *inner_radius = 0.0;
        *outer_radius = 0.0;
        vertex_lanes.fill(V4::ZERO);
    }

    /// The vertices.
    pub fn vertices(&self) -> &[Vec3] {
        let n = (self.vertex_count as usize).min(MAX_HULL_VERTICES);
        &self.vertices[..n]
    }

    /// Number of faces.
    pub fn face_count(&self) -> usize {
        (self.face_count as usize).min(MAX_HULL_FACES)
    }

    /// Face `f`'s outward unit normal and plane offset (`n · p = d` on the face).
    /// Out-of-range indices give face 0.
    pub fn plane(&self, f: usize) -> (Vec3, f32) {
        let f = if f < self.face_count() { f } else { 0 };
        (
            self.normals.get(f).copied().unwrap_or(Vec3::Y),
            self.offsets.get(f).copied().unwrap_or(0.0),
        )
    }

    /// Face `f`'s vertex indices, counter-clockwise about its normal.
    /// Out-of-range indices give face 0.
    pub fn face_vertices(&self, f: usize) -> &[u8] {
        let f = if f < self.face_count() { f } else { 0 };
        let s = self.face_start.get(f).copied().unwrap_or(0) as usize;
        let len = self.face_len.get(f).copied().unwrap_or(0) as usize;
        self.face_indices.get(s..s + len).unwrap_or(&[])
    }

    /// Centroid of the hull's volume (local frame).
    pub fn centroid(&self) -> Vec3 {
        self.centroid
    }

    /// The distance tolerance the hull was built with (m); see [`ConvexHull::new`].
    pub fn tolerance(&self) -> f32 {
        self.tolerance
    }

    /// True when the cloud needed more than [`MAX_HULL_VERTICES`] vertices and the hull
    /// keeps the greedy subset described at [`ConvexHull::new`]; input points may then lie
    /// outside it.
    pub fn is_reduced(&self) -> bool {
        self.reduced
    }

    /// Number of edges (see [`HullEdge`]).
    pub(crate) fn edge_count(&self) -> usize {
        (self.edge_count as usize).min(MAX_HULL_EDGES)
    }

    /// Edge `e`, or `None` past the last.
    #[inline]
    pub(crate) fn edge(&self, e: usize) -> Option<HullEdge> {
        if e >= self.edge_count() {
            return None;
        }
        let [v0, v1, face0, face1] = *self.edges.get(e)?;
        Some(HullEdge {
            v0,
            v1,
            face0,
            face1,
        })
    }

    /// The radius (m) of a ball about the centroid inside the hull, computed at build.
    pub(crate) fn inner_radius(&self) -> f32 {
        self.inner_radius
    }

    /// The centroid's least distance to a face plane, 0 when that is negative or NaN.
    fn centroid_depth(&self) -> f32 {
        let mut r = f32::INFINITY;
        for f in 0..self.face_count() {
            let (n, d) = self.plane(f);
            r = scalar::min(r, d - n.dot(self.centroid));
        }
        if r > 0.0 {
            r
        } else {
            0.0
        }
    }

    /// True when every edge runs along its faces' crossing line ([`EDGE_TILT_SIN`]).
    pub(crate) fn has_well_formed_edges(&self) -> bool {
        self.well_formed_edges
    }

    /// [`ConvexHull::has_well_formed_edges`], measured: `|v · n0|` and `|v · n1|` at most
    /// `EDGE_TILT_SIN |v|` for every edge vector `v` (false for NaN).
    fn edges_run_along_faces(&self) -> bool {
        (0..self.edge_count()).all(|e| {
            self.edge(e).is_some_and(|h| {
                let v = self.core_vertex(u32::from(h.v1)) - self.core_vertex(u32::from(h.v0));
                let limit = EDGE_TILT_SIN * v.length();
                let n0 = self.plane(usize::from(h.face0)).0;
                let n1 = self.plane(usize::from(h.face1)).0;
                scalar::abs(v.dot(n0)) <= limit && scalar::abs(v.dot(n1)) <= limit
            })
        })
    }

    /// True when the edge list is complete (see [`ConvexHull::closed`]).
    pub(crate) fn is_closed(&self) -> bool {
        self.closed
    }

    /// Face `f` as a polygon with feature ids (local frame); out-of-range indices give
    /// face 0.
    pub(crate) fn face(&self, f: usize) -> Face {
        let f = if f < self.face_count() { f } else { 0 };
        let (normal, _) = self.plane(f);
        let mut face = Face::new(normal, FeatureId::face(f as u32));
        let idx = self.face_vertices(f);
        let next = idx.iter().skip(1).chain(idx.first());
        for (&i, &j) in idx.iter().zip(next) {
            let (i, j) = (i as u32, j as u32);
            face.push(
                self.core_vertex(i),
                FeatureId::vertex(i),
                FeatureId::edge(i, j),
            );
        }
        face
    }

    /// The face planes in use, `(normal, offset)`, in face order.
    fn planes(&self) -> impl Iterator<Item = (Vec3, f32)> + '_ {
        self.normals
            .iter()
            .copied()
            .zip(self.offsets.iter().copied())
            .take(self.face_count())
    }

    /// The vertex with the largest `v · dir`, the lowest index on ties (vertex 0 when no
    /// product is above `−∞`, e.g. all NaN): the same answer as one scan in index order.
    /// Two passes over [`ConvexHull::vertex_lanes`]: four running maxima (lane `k` over
    /// the vertices `k, k + 4, ...`; NaN products never taken) give the largest product
    /// `m`; then the products equal to `m`, recomputed to the bit, gather into one mask
    /// whose lowest set bit is the lowest index. Padding lanes repeat vertex 0, so they
    /// match `m` only after vertex 0 itself has. No index is carried through the first
    /// pass, whose four compare chains are independent (GJK waits on every support
    /// point). Always inlined, as are `Proxy::support` and GJK's `support`: returned
    /// from a call, the point and index came back through memory stored in pieces and
    /// read as one, a store-forwarding stall per support.
    #[inline(always)]
    pub(crate) fn core_support(&self, dir: Vec3) -> (Vec3, u32) {
        let d = V4::splat(dir);
        let groups = self.vertex_lanes.get(..self.vertex_groups()).unwrap_or(&[]);
        let mut best = F4::splat(f32::NEG_INFINITY);
        for group in groups {
            let p = group.dot(&d);
            // `if p > best { p } else { best }`: NaN products never taken.
            best = p.max(best);
        }
        let [b0, b1, b2, b3] = best.0;
        let take = |m: f32, x: f32| if x > m { x } else { m };
        let m = take(take(b0, b1), take(b2, b3));
        if m > f32::NEG_INFINITY {
            // Every group's hits in one mask, group `g` in bits `4g..4g + 4`, so the
            // lowest set bit is the lowest index: no branch on where the maximum lies.
            // (Built from the last group down, a shift per group.)
            let m4 = F4::splat(m);
            let mut hits = 0u64;
            for group in groups.iter().rev() {
                hits = (hits << 4) | u64::from(group.dot(&d).eq_bits(m4));
            }
            if hits != 0 {
                let i = hits.trailing_zeros();
                return (self.core_vertex(i), i);
            }
        }
        (self.core_vertex(0), 0)
    }

    /// The groups of [`ConvexHull::vertex_lanes`] in use: the vertices' count over four,
    /// rounded up.
    #[inline]
    fn vertex_groups(&self) -> usize {
        usize::from(self.vertex_count).div_ceil(4)
    }

    /// The smallest `v · dir` over the vertices (`+∞` for none; NaN products are
    /// skipped): the same number as `dir · v` for the vertex [`ConvexHull::core_support`]
    /// picks along `−dir` (the products only change sign), without finding the vertex.
    /// Four running minima over [`ConvexHull::vertex_lanes`] (lane `k` over the vertices
    /// `k, k + 4, ...`; padding lanes repeat vertex 0), then merged: lanes 0 and 1, 2 and
    /// 3, then the two.
    pub(crate) fn min_dot(&self, dir: Vec3) -> f32 {
        #[inline(always)]
        fn take(best: &mut f32, d: f32) {
            *best = if d < *best { d } else { *best };
        }
        let d = V4::splat(dir);
        let mut low = F4::splat(f32::INFINITY);
        for group in self.vertex_lanes.iter().take(self.vertex_groups()) {
            let p = group.dot(&d);
            // `if p < low { p } else { low }`: NaN products never taken.
            low = p.min(low);
        }
        let [mut l0, l1, mut l2, l3] = low.0;
        take(&mut l0, l1);
        take(&mut l2, l3);
        take(&mut l0, l2);
        l0
    }

    pub(crate) fn core_vertex(&self, index: u32) -> Vec3 {
        let vs = self.vertices();
        vs.get(index as usize)
            .or(vs.first())
            .copied()
            .unwrap_or(Vec3::ZERO)
    }

    /// The face whose normal is most aligned with `dir` (lowest index on ties).
    pub(crate) fn supporting_face(&self, dir: Vec3) -> Face {
        let mut best = 0usize;
        let mut best_d = f32::NEG_INFINITY;
        for (f, (n, _)) in self.planes().enumerate() {
            let d = n.dot(dir);
            if d > best_d {
                best_d = d;
                best = f;
            }
        }
        self.face(best)
    }

    /// The world box of the hull at `pose`: its faces are the hull's supports along the
    /// world axes, `t_k + min / max_v v · r_k` with `r_k = Rᵀ e_k` (row `k` of the
    /// rotation matrix) world axis `k` seen in the hull's frame. Three passes of
    /// [`ConvexHull::dot_range`] over the vertex lanes instead of turning every vertex by
    /// the quaternion (a fifth of the work for 16 vertices); the box differs from the
    /// turned vertices' box by rounding only (a few units in the last place).
    pub(crate) fn aabb(&self, pose: &Iso) -> Aabb {
        self.aabb_turned(pose, &Mat3::from_quat(pose.rotation))
    }

    /// [`ConvexHull::aabb`] given `r = Mat3::from_quat(pose.rotation)`.
    pub(crate) fn aabb_turned(&self, pose: &Iso, r: &Mat3) -> Aabb {
        let (x0, x1) = self.dot_range(r.row(0));
        let (y0, y1) = self.dot_range(r.row(1));
        let (z0, z1) = self.dot_range(r.row(2));
        Aabb::new(
            pose.position + Vec3::new(x0, y0, z0),
            pose.position + Vec3::new(x1, y1, z1),
        )
    }

    /// The smallest and largest `v · dir` over the vertices, in one pass over
    /// [`ConvexHull::vertex_lanes`] (four running minima and maxima, merged as in
    /// [`ConvexHull::min_dot`]).
    fn dot_range(&self, dir: Vec3) -> (f32, f32) {
        #[inline(always)]
        fn lower(best: &mut f32, d: f32) {
            *best = if d < *best { d } else { *best };
        }
        #[inline(always)]
        fn upper(best: &mut f32, d: f32) {
            *best = if d > *best { d } else { *best };
        }
        let d = V4::splat(dir);
        let mut low = F4::splat(f32::INFINITY);
        let mut high = F4::splat(f32::NEG_INFINITY);
        for group in self.vertex_lanes.iter().take(self.vertex_groups()) {
            let p = group.dot(&d);
            low = p.min(low);
            high = p.max(high);
        }
        let ([mut l0, l1, mut l2, l3], [mut h0, h1, mut h2, h3]) = (low.0, high.0);
        lower(&mut l0, l1);
        lower(&mut l2, l3);
        lower(&mut l0, l2);
        upper(&mut h0, h1);
        upper(&mut h2, h3);
        upper(&mut h0, h2);
        (l0, h0)
    }

    pub(crate) fn bounding_radius(&self) -> f32 {
        self.outer_radius
    }

    /// The largest vertex distance from the local origin (m), for [`Self::outer_radius`].
    fn farthest_vertex(&self) -> f32 {
        let mut r = 0.0;
        for v in self.vertices() {
            r = scalar::max(r, v.length());
        }
        r
    }

    /// Thinnest width: the smallest, over faces, of the largest depth of a vertex below
    /// that face's plane (m). Computed once when the hull is built.
    #[inline]
    pub(crate) fn min_extent(&self) -> f32 {
        self.thinnest
    }

    /// [`ConvexHull::min_extent`] from the faces and vertices (`O(F V)`).
    fn thinnest_width(&self) -> f32 {
        let mut w = f32::INFINITY;
        for (n, d) in self.planes() {
            let mut deepest = 0.0;
            for v in self.vertices() {
                deepest = scalar::max(deepest, d - n.dot(*v));
            }
            w = scalar::min(w, deepest);
        }
        if w.is_finite() {
            w
        } else {
            0.0
        }
    }

    /// Mass properties for a uniform density (kg/m³): the volume, centroid and second
    /// moments summed over tetrahedra, then `I = tr(C) 𝟙 − C` for the covariance `C` about
    /// the centroid (Blow and Binstock 2004). The density is not checked here; use
    /// [`super::Shape::mass_properties`] for a checked call.
    pub fn mass_properties(&self, density: f32) -> MassProperties {
        match self.volume_integrals() {
            Some((volume, center, cov)) => {
                let trace = cov.x.x + cov.y.y + cov.z.z;
                let inertia = Mat3::from_diagonal(Vec3::splat(trace)) + cov.scale(-1.0);
                MassProperties {
                    mass: density * volume,
                    center,
                    inertia: inertia.scale(density),
                }
            }
            None => MassProperties {
                mass: 0.0,
                center: self.centroid,
                inertia: Mat3::ZERO,
            },
        }
    }

    /// Volume (m³), centroid (local frame, m) and covariance `C = ∫ (x − c)(x − c)ᵀ dV`
    /// about the centroid (m⁵), or `None` for an empty or flat hull. Summed in f64: a
    /// needle-thin hull's volume is a small difference of large products.
    ///
    /// Each face is fanned into triangles `(a, b, c)` from its first corner; each triangle
    /// and the reference point `r` (the vertex mean, inside the hull, which keeps the
    /// coordinates small whatever the hull's offset) span a tetrahedron with
    /// `6 V = a · (b × c)` (coordinates relative to `r`, positive for outward
    /// counter-clockwise faces). For a tetrahedron with one corner at the origin
    /// (Tonon 2004): `∫ x dV = V (a + b + c) / 4` and
    /// `∫ x xᵀ dV = V / 20 · (a aᵀ + b bᵀ + c cᵀ + s sᵀ)` with `s = a + b + c`.
    /// The parallel-axis step `C = ∫ x xᵀ dV − V c cᵀ` moves the moments to the centroid.
    /// Faces and fan triangles are summed in index order.
    fn volume_integrals(&self) -> Option<(f32, Vec3, Mat3)> {
        let vs = self.vertices();
        if vs.is_empty() {
            return None;
        }
        let mut r = Vec64::ZERO;
        for v in vs {
            r = r + Vec64::of(*v);
        }
        r = r * (1.0 / vs.len() as f64);
        let mut six_volume = 0.0f64; // Σ det
        let mut moment = Vec64::ZERO; // Σ det · s
        let mut second = Sym64::default(); // Σ det · (a aᵀ + b bᵀ + c cᵀ + s sᵀ)
        for f in 0..self.face_count() {
            let idx = self.face_vertices(f);
            let Some((&first, rest)) = idx.split_first() else {
                continue;
            };
            let at = |i: u8| Vec64::of(self.core_vertex(i as u32)) - r;
            let a = at(first);
            for pair in rest.windows(2) {
                let (Some(&i), Some(&j)) = (pair.first(), pair.get(1)) else {
                    continue;
                };
                let (b, c) = (at(i), at(j));
                let det = a.dot(b.cross(c));
                let s = a + b + c;
                six_volume += det;
                moment = moment + s * det;
                second.add_outer(a, det);
                second.add_outer(b, det);
                second.add_outer(c, det);
                second.add_outer(s, det);
            }
        }
        let volume = six_volume / 6.0;
        if !(volume > 0.0 && volume.is_finite()) {
            return None;
        }
        // ∫ x dV = Σ det s / 24, divided by V = Σ det / 6.
        let c = moment * (1.0 / (4.0 * six_volume));
        // ∫ x xᵀ dV = Σ det (...) / 120, then C = ∫ x xᵀ dV − V c cᵀ.
        let mut cov = second.scaled(1.0 / 120.0);
        cov.add_outer(c, -volume);
        Some((volume as f32, (r + c).rounded(), cov.to_mat3()))
    }

    /// Ray cast in the local frame by clipping the ray against every face plane
    /// (Cyrus and Beck 1978): each plane with `n · d < 0` raises the entry distance, each
    /// with `n · d > 0` lowers the exit distance, a plane parallel to the ray with the
    /// origin outside it is a miss. An origin inside (or on) the hull gives `t = 0` with
    /// normal `−direction`, like the other shapes.
    pub fn cast_ray(&self, ray: &Ray, max_t: f32) -> Option<RayHit> {
        let mut t_enter = 0.0f32;
        let mut t_exit = max_t;
        let mut entry_normal: Option<Vec3> = None;
        for (n, d) in self.planes() {
            // Signed distance of the origin below the plane (≥ 0: inside this plane) and
            // the ray's speed along the normal; the plane is hit at `t = depth / speed`.
            let depth = d - n.dot(ray.origin);
            let speed = n.dot(ray.direction);
            if speed < 0.0 {
                let t = depth / speed;
                if t > t_enter {
                    t_enter = t;
                    entry_normal = Some(n);
                }
            } else if speed > 0.0 {
                t_exit = scalar::min(t_exit, depth / speed);
            } else if depth < 0.0 {
                return None;
            }
            if t_enter > t_exit {
                return None;
            }
        }
        Some(RayHit {
            t: t_enter,
            point: ray.at(t_enter),
            normal: entry_normal.unwrap_or(-ray.direction),
        })
    }
}

// ---------------------------------------------------------------------------------------
// Building works in f64. The inputs are f32 and the tolerance is f32-sized (1e-5 of the
// largest coordinate), but the orientation tests must resolve much finer than that: a
// triangle only `eps` tall computed in f32 has a normal off by ~0.06 rad, enough to flip
// which side a distant point is on. f64 `+ − × ÷` are IEEE-exact and the same on every
// target (soft-float on an MCU: slower, but a hull is built once).
// ---------------------------------------------------------------------------------------

/// `v / |v|`, or `None` when zero, not finite, or outside the range where the f32 seed
/// of [`sqrt64`] is valid (never for accepted inputs: `|v|²` lies between
/// `MIN_TOLERANCE⁴ = 10⁻³²` and `(2 · MAX_COORDINATE)⁴ ≈ 10²⁵`).
fn unit(v: Vec64) -> Option<Vec64> {
    let l = sqrt64(v.length_squared())?;
    Some(v * (1.0 / l))
}

/// A symmetric 3×3 matrix in f64 (xx, yy, zz, xy, yz, zx), for second moments.
#[derive(Clone, Copy, Debug, Default)]
struct Sym64 {
    xx: f64,
    yy: f64,
    zz: f64,
    xy: f64,
    yz: f64,
    zx: f64,
}

impl Sym64 {
    /// `self += w · v vᵀ`.
    fn add_outer(&mut self, v: Vec64, w: f64) {
        self.xx += w * v.x * v.x;
        self.yy += w * v.y * v.y;
        self.zz += w * v.z * v.z;
        self.xy += w * v.x * v.y;
        self.yz += w * v.y * v.z;
        self.zx += w * v.z * v.x;
    }

    fn scaled(self, s: f64) -> Sym64 {
        Sym64 {
            xx: self.xx * s,
            yy: self.yy * s,
            zz: self.zz * s,
            xy: self.xy * s,
            yz: self.yz * s,
            zx: self.zx * s,
        }
    }

    fn to_mat3(self) -> Mat3 {
        let (xx, yy, zz) = (self.xx as f32, self.yy as f32, self.zz as f32);
        let (xy, yz, zx) = (self.xy as f32, self.yz as f32, self.zx as f32);
        Mat3::from_cols(
            Vec3::new(xx, xy, zx),
            Vec3::new(xy, yy, yz),
            Vec3::new(zx, yz, zz),
        )
    }
}

/// `√x` in f64 from only `+ − × ÷`: the f32 square root (correctly rounded, via
/// [`scalar::sqrt`]) as the seed, then three Newton steps `s ← (s + x/s) / 2`, each
/// doubling the correct digits (7 → 14 → 28). `None` when `x` is not positive, not
/// finite, or outside f32's normal range.
fn sqrt64(x: f64) -> Option<f64> {
    let x32 = x as f32;
    if !(x32.is_normal() && x32 > 0.0 && x.is_finite()) {
        return None;
    }
    let mut s = scalar::sqrt(x32) as f64;
    for _ in 0..3 {
        s = 0.5 * (s + x / s);
    }
    Some(s)
}

/// Input point `i` in f64, or the origin for an index out of range.
fn point_at(points: &[Vec3], i: usize) -> Vec64 {
    points.get(i).copied().map_or(Vec64::ZERO, Vec64::of)
}

// ---------------------------------------------------------------------------------------
// Stage 1: validation and the initial tetrahedron.
// ---------------------------------------------------------------------------------------

/// Check the cloud (in the order documented at [`ConvexHull::new`]) and return the build
/// tolerance `eps` (m).
fn validate(points: &[Vec3]) -> Result<f32, Error> {
    if points.len() > MAX_HULL_INPUT_POINTS {
        return Err(Error::Hull(HullError::TooManyPoints));
    }
    let mut largest = 0.0f32;
    for p in points {
        if !p.is_finite() {
            return Err(Error::NonFinite(Input::Point));
        }
        largest = scalar::max(largest, p.abs().max_elem());
    }
    if largest > ConvexHull::MAX_COORDINATE {
        return Err(Error::OutOfRange(Input::Point));
    }
    if points.len() < 4 {
        return Err(Error::Hull(HullError::TooFewPoints));
    }
    Ok(scalar::max(
        ConvexHull::TOLERANCE * largest,
        ConvexHull::MIN_TOLERANCE,
    ))
}

/// Indices `[a, b, c, d]` of a tetrahedron with `d` below the plane of `(a, b, c)` (so
/// `(a, b, c)` is counter-clockwise seen from outside): `a, b` the two of the six
/// axis-extreme points farthest apart, `c` the point farthest from their line, `d` the
/// point farthest from the plane `(a, b, c)`. Lowest index on ties. Each distance must
/// exceed `eps`, else the cloud is coincident, collinear or coplanar.
fn initial_simplex(points: &[Vec3], eps: f64) -> Result<[u16; 4], Error> {
    let at = |i: usize| point_at(points, i);
    let mut lo = [0usize; 3];
    let mut hi = [0usize; 3];
    for (i, p) in points.iter().enumerate() {
        let lo_p = lo.map(|j| points.get(j).copied().unwrap_or(*p));
        let hi_p = hi.map(|j| points.get(j).copied().unwrap_or(*p));
        for k in 0..3 {
            if p[k] < lo_p[k][k] {
                lo[k] = i;
            }
            if p[k] > hi_p[k][k] {
                hi[k] = i;
            }
        }
    }
    let extremes = [lo[0], hi[0], lo[1], hi[1], lo[2], hi[2]];
    let (mut a, mut b, mut best) = (0usize, 0usize, -1.0f64);
    for (k, &i) in extremes.iter().enumerate() {
        for &j in extremes.iter().skip(k + 1) {
            let d2 = (at(j) - at(i)).length_squared();
            if d2 > best {
                (a, b, best) = (i, j, d2);
            }
        }
    }
    // Inputs are finite, so no distance below is NaN.
    if best <= eps * eps {
        return Err(Error::Hull(HullError::Coincident));
    }
    let (pa, pb) = (at(a), at(b));
    let axis = unit(pb - pa).ok_or(Error::Hull(HullError::Coincident))?;
    let (mut c, mut best) = (0usize, -1.0f64);
    for i in 0..points.len() {
        let d2 = (at(i) - pa).cross(axis).length_squared();
        if d2 > best {
            (c, best) = (i, d2);
        }
    }
    if best <= eps * eps {
        return Err(Error::Hull(HullError::Collinear));
    }
    let pc = at(c);
    let normal = unit((pb - pa).cross(pc - pa)).ok_or(Error::Hull(HullError::Collinear))?;
    let (mut d, mut best, mut side) = (0usize, -1.0f64, 0.0f64);
    for i in 0..points.len() {
        let h = normal.dot(at(i) - pa);
        let dist = if h < 0.0 { -h } else { h };
        if dist > best {
            (d, best, side) = (i, dist, h);
        }
    }
    if best <= eps {
        return Err(Error::Hull(HullError::Coplanar));
    }
    if side > 0.0 {
        core::mem::swap(&mut b, &mut c);
    }
    Ok([a as u16, b as u16, c as u16, d as u16])
}

// ---------------------------------------------------------------------------------------
// Stage 2: quickhull on a triangle mesh in fixed working arrays.
// ---------------------------------------------------------------------------------------

/// Working triangles. A closed triangulated hull of `V` vertices has `2V − 4` triangles;
/// the builder never lets `V` pass [`MAX_HULL_VERTICES`] and retires the visible triangles
/// before it adds the cone, so `2 · MAX_HULL_VERTICES` slots always suffice (running out
/// would be a broken mesh: `TooComplex`).
const MAX_WORK_TRIS: usize = 2 * MAX_HULL_VERTICES;
/// Horizon edges: a simple horizon loop visits each hull vertex at most once.
const MAX_HORIZON: usize = MAX_HULL_VERTICES;
/// Points added before giving up as `TooComplex`: each insertion makes a point a vertex,
/// and only a point buried by a later insertion can be added twice.
const MAX_INSERTIONS: usize = 2 * MAX_HULL_INPUT_POINTS;
/// Full re-tests of the non-vertex points against the finished mesh (see `Builder::run`);
/// the first almost always finds nothing.
const MAX_RESCANS: usize = 8;
/// Rebuilds at a finer build tolerance when a point is left outside (see
/// [`ConvexHull::new`]), each at [`FINER_BUILD_FACTOR`] times the last one's: down to
/// `eps / 256`, still ten million times coarser than `f64` rounding at the cloud's scale.
const FINER_BUILDS: usize = 2;
/// The build tolerance of each finer build relative to the last.
const FINER_BUILD_FACTOR: f64 = 1.0 / 16.0;
/// A point left more than this many `eps` outside asks for a finer build.
const RETRY_OUTSIDE: f64 = 2.0;
/// A cone triangle with a hull vertex more than this fraction of `eps` above it is a fold
/// (see [`Builder::settle_horizon`]).
const FOLD_FRACTION: f64 = 0.1;
/// "No triangle": an input point that is inside (or a vertex), or a missing neighbour.
const NONE: u8 = u8::MAX;
/// An input point whose triangle was just retired, waiting for the new cone.
const PENDING: u8 = u8::MAX - 1;

/// A working triangle: corners (input indices) counter-clockwise about the outward normal,
/// the neighbour across each edge `v[k] → v[k + 1]`, and its plane `n · p = d` (f64).
#[derive(Clone, Copy)]
struct Tri {
    v: [u16; 3],
    adj: [u8; 3],
    n: Vec64,
    d: f64,
    alive: bool,
    visible: bool,
}

const DEAD_TRI: Tri = Tri {
    v: [0; 3],
    adj: [NONE; 3],
    n: Vec64::ZERO,
    d: 0.0,
    alive: false,
    visible: false,
};

impl Tri {
    /// Signed height of `p` above the plane (m).
    #[inline]
    fn height(&self, p: Vec64) -> f64 {
        self.n.dot(p) - self.d
    }

    /// The corner after corner `k`.
    #[inline]
    fn next(&self, k: usize) -> u16 {
        match k {
            0 => self.v[1],
            1 => self.v[2],
            _ => self.v[0],
        }
    }

    /// Which edge `k` runs `from → to`, if any.
    fn edge_index(&self, from: u16, to: u16) -> Option<usize> {
        (0..3).find(|&k| self.v[k] == from && self.next(k) == to)
    }
}

/// What [`Builder::absorb_folds`] found.
enum Folds {
    /// Some triangles beyond folds were made visible: look again.
    Absorbed,
    /// No fold leaves a vertex more than `eps` outside: build the cone.
    Mild,
    /// A fold that absorbing cannot mend leaves a vertex more than `eps` outside.
    Stuck,
}

/// A directed edge `a → b` of the region being replaced, and the triangle on its far side.
#[derive(Clone, Copy, Default)]
struct Edge {
    a: u16,
    b: u16,
    outer: u8,
}

/// The quickhull state. Each input point is either a hull vertex, inside, or *outside*:
/// owned by the triangle it lies farthest above (by more than `eps`), with that height.
struct Builder<'p> {
    points: &'p [Vec3],
    /// The tolerance of the current stage (m): the build tolerance while the mesh grows,
    /// `merge_eps` once it is turned into faces.
    eps: f64,
    /// The hull's tolerance (m), [`ConvexHull::tolerance`]: faces merge within it.
    merge_eps: f64,
    tris: [Tri; MAX_WORK_TRIS],
    /// Owning triangle of each point, or [`NONE`] / [`PENDING`]. An owner is always a
    /// live triangle with the plane it had when it took the point (a triangle's points
    /// wait as [`PENDING`] before it is retired, and a slot gets a new plane only when
    /// free), so the point's height above it is formed again where it is needed rather
    /// than kept (8 KiB of `f64`s on the stack).
    owner: [u8; MAX_HULL_INPUT_POINTS],
    /// Number of live triangles using each point as a corner.
    degree: [u8; MAX_HULL_INPUT_POINTS],
    /// Points with a non-zero degree: the current hull's vertices.
    vertex_count: usize,
    reduced: bool,
}

impl<'p> Builder<'p> {
    /// An empty builder whose faces will merge within `merge_eps`: [`Builder::restart`]
    /// starts it. Infallible and filled by `restart`, so the caller's local is the only
    /// copy (a `Result<Builder>` and array literals were each a 16 KiB copy on the stack,
    /// most of `ConvexHull::new`'s frame on a Cortex-M).
    fn new(points: &'p [Vec3], merge_eps: f64) -> Builder<'p> {
        Builder {
            points,
            eps: merge_eps,
            merge_eps,
            tris: [DEAD_TRI; MAX_WORK_TRIS],
            owner: [NONE; MAX_HULL_INPUT_POINTS],
            degree: [0; MAX_HULL_INPUT_POINTS],
            vertex_count: 0,
            reduced: false,
        }
    }

    /// Start again, in place, at build tolerance `eps`: the tetrahedron `[a, b, c, d]`
    /// (from [`initial_simplex`]) as four triangles, and every other point given to the
    /// face it is farthest above.
    fn restart(&mut self, eps: f64, simplex: [u16; 4]) -> Result<(), Error> {
        self.eps = eps;
        // Filled where they lie: an assigned array literal can be built on the stack
        // first and copied.
        self.tris.fill(DEAD_TRI);
        self.owner.fill(NONE);
        self.degree.fill(0);
        self.vertex_count = 0;
        self.reduced = false;
        let [a, bb, c, d] = simplex;
        let faces = [[a, bb, c], [a, d, bb], [bb, d, c], [c, d, a]];
        for (slot, v) in faces.iter().enumerate() {
            self.add_tri(slot, *v)?;
        }
        // Link each edge to the face holding its reverse.
        for s in 0..faces.len() {
            for k in 0..3 {
                let (from, to) = (self.tris[s].v[k], self.tris[s].next(k));
                let other = (0..faces.len()).find(|&o| self.tris[o].edge_index(to, from).is_some());
                self.tris[s].adj[k] = other.map_or(NONE, |o| o as u8);
            }
        }
        let new_faces = [0u8, 1, 2, 3];
        for i in 0..self.points.len().min(MAX_HULL_INPUT_POINTS) {
            if simplex.contains(&(i as u16)) {
                continue;
            }
            self.assign(i, &new_faces);
        }
        Ok(())
    }

    fn point(&self, i: u16) -> Vec64 {
        point_at(self.points, i as usize)
    }

    fn tri(&self, t: u8) -> Option<&Tri> {
        self.tris.get(t as usize).filter(|t| t.alive)
    }

    /// Give point `i` to the triangle among `candidates` it is farthest above, if it is
    /// more than `eps` above it (first candidate on ties); else mark it inside.
    fn assign(&mut self, i: usize, candidates: &[u8]) {
        let p = point_at(self.points, i);
        let mut best = (NONE, self.eps);
        for &t in candidates {
            if let Some(tri) = self.tri(t) {
                let h = tri.height(p);
                if h > best.1 {
                    best = (t, h);
                }
            }
        }
        if let Some(o) = self.owner.get_mut(i) {
            *o = best.0;
        }
    }

    /// Put triangle `v` (counter-clockwise seen from outside) in `slot` with its plane.
    /// Fails on a zero-area triangle, which a consistent mesh never makes.
    fn add_tri(&mut self, slot: usize, v: [u16; 3]) -> Result<(), Error> {
        let [pa, pb, pc] = v.map(|i| self.point(i));
        let n = unit((pb - pa).cross(pc - pa)).ok_or(Error::Hull(HullError::TooComplex))?;
        // Offset averaged over the corners, summed in corner order.
        let d = (n.dot(pa) + n.dot(pb) + n.dot(pc)) * (1.0 / 3.0);
        let tri = self
            .tris
            .get_mut(slot)
            .ok_or(Error::Hull(HullError::TooComplex))?;
        *tri = Tri {
            v,
            adj: [NONE; 3],
            n,
            d,
            alive: true,
            visible: false,
        };
        for i in v {
            if let Some(deg) = self.degree.get_mut(i as usize) {
                if *deg == 0 {
                    self.vertex_count += 1;
                }
                *deg = deg.saturating_add(1);
            }
        }
        Ok(())
    }

    /// Retire triangle `slot`; a corner left in no triangle stops being a vertex.
    fn remove_tri(&mut self, slot: usize) {
        let Some(tri) = self.tris.get_mut(slot) else {
            return;
        };
        tri.alive = false;
        let v = tri.v;
        for i in v {
            if let Some(deg) = self.degree.get_mut(i as usize) {
                *deg = deg.saturating_sub(1);
                if *deg == 0 {
                    self.vertex_count = self.vertex_count.saturating_sub(1);
                }
            }
        }
    }

    /// Add outside points one at a time, farthest first, until none is left or the hull
    /// has [`MAX_HULL_VERTICES`] vertices (then the hull is *reduced*).
    ///
    /// Departure from Barber et al.: a point less than `eps` above a triangle is dropped
    /// as "on the hull", but near a sharp edge of a thin hull it can be farther than `eps`
    /// from the hull, and a later triangle there may leave it more than `eps` outside.
    /// So when no outside point is left, every non-vertex point is tested against every
    /// triangle again ([`Builder::rescan`]), at most [`MAX_RESCANS`] times.
    fn run(&mut self) -> Result<(), Error> {
        let mut rescans = 0;
        for _ in 0..MAX_INSERTIONS {
            let mut next = self.farthest_outside();
            if next.is_none() && rescans < MAX_RESCANS {
                rescans += 1;
                self.rescan();
                next = self.farthest_outside();
            }
            let Some(i) = next else {
                return Ok(());
            };
            if self.vertex_count >= MAX_HULL_VERTICES {
                self.reduced = true;
                return Ok(());
            }
            self.add_point(i)?;
        }
        Err(Error::Hull(HullError::TooComplex))
    }

    /// Give every point that is not a vertex to the live triangle it is farthest above,
    /// if more than `eps`.
    fn rescan(&mut self) {
        let mut live = [NONE; MAX_WORK_TRIS];
        let mut count = 0;
        for (slot, t) in self.tris.iter().enumerate() {
            if let (true, Some(l)) = (t.alive, live.get_mut(count)) {
                *l = slot as u8;
                count += 1;
            }
        }
        let live = live.get(..count).unwrap_or(&[]);
        for i in 0..self.points.len().min(MAX_HULL_INPUT_POINTS) {
            if self.degree[i] == 0 {
                self.assign(i, live);
            }
        }
    }

    /// Is an input point that is not a vertex more than `limit` above a live triangle?
    fn leaves_a_point_outside(&self, limit: f64) -> bool {
        (0..self.points.len().min(MAX_HULL_INPUT_POINTS)).any(|i| {
            let p = point_at(self.points, i);
            self.degree.get(i) == Some(&0)
                && self.tris.iter().any(|t| t.alive && t.height(p) > limit)
        })
    }

    /// The outside point highest above its owner (lowest index on ties).
    fn farthest_outside(&self) -> Option<usize> {
        let mut best = None;
        let mut best_h = 0.0f64;
        let n = self.points.len();
        for (i, &o) in self.owner.iter().enumerate().take(n) {
            // Its height as `assign` formed it (the owner's plane has not changed).
            let Some(t) = self.tris.get(o as usize) else {
                continue;
            };
            let h = t.height(point_at(self.points, i));
            if h > best_h {
                best = Some(i);
                best_h = h;
            }
        }
        best
    }

    /// One quickhull step: retire every triangle the point sees (a connected region grown
    /// from its owner), and close the hole with a cone of triangles from the point to the
    /// region's boundary (the horizon). Points above retired triangles are shared out
    /// among the new ones.
    fn add_point(&mut self, i: usize) -> Result<(), Error> {
        let p = point_at(self.points, i);
        let seed = self.owner.get(i).copied().unwrap_or(NONE);
        if let Some(o) = self.owner.get_mut(i) {
            *o = NONE;
        }
        self.mark_visible(p, seed);
        let mut horizon = [Edge::default(); MAX_HORIZON];
        let Some(count) = self.settle_horizon(p, &mut horizon) else {
            // No convex cone: the point is inconsistent with the mesh at the scale of
            // `eps` (a few `eps` above one triangle, as far below its nearly coplanar
            // neighbour). Leave it out; a rescan retries it once the hull has grown.
            return Ok(());
        };
        let horizon = horizon.get(..count).unwrap_or(&[]);

        // Points above retired triangles wait for the cone.
        let n = self.points.len();
        for o in self.owner.iter_mut().take(n) {
            if self
                .tris
                .get(*o as usize)
                .is_some_and(|t| t.alive && t.visible)
            {
                *o = PENDING;
            }
        }
        for s in 0..MAX_WORK_TRIS {
            if self.tris[s].alive && self.tris[s].visible {
                self.remove_tri(s);
            }
        }

        // The cone: triangle k is (a_k, b_k, p); its neighbours are the outer triangle
        // across the horizon edge and the cone triangles k + 1 (across b_k → p) and k − 1
        // (across p → a_k).
        let mut slots = [NONE; MAX_HORIZON];
        let mut free = (0..MAX_WORK_TRIS).filter(|&s| !self.tris[s].alive);
        for slot in slots.iter_mut().take(count) {
            *slot = free.next().ok_or(Error::Hull(HullError::TooComplex))? as u8;
        }
        let slots = slots.get(..count).unwrap_or(&[]);
        for (k, (e, &slot)) in horizon.iter().zip(slots).enumerate() {
            self.add_tri(slot as usize, [e.a, e.b, i as u16])?;
            let after = slots.get((k + 1) % count).copied().unwrap_or(NONE);
            let before = slots.get((k + count - 1) % count).copied().unwrap_or(NONE);
            if let Some(t) = self.tris.get_mut(slot as usize) {
                t.adj = [e.outer, after, before];
            }
            let outer = self
                .tris
                .get_mut(e.outer as usize)
                .filter(|t| t.alive)
                .ok_or(Error::Hull(HullError::TooComplex))?;
            let j = outer
                .edge_index(e.b, e.a)
                .ok_or(Error::Hull(HullError::TooComplex))?;
            outer.adj[j] = slot;
        }

        for j in 0..n {
            if self.owner.get(j) == Some(&PENDING) {
                self.assign(j, slots);
            }
        }
        Ok(())
    }

    /// Mark the triangles `p` sees: the connected region, grown through shared edges
    /// from `seed`, of triangles `p` is more than `eps` above (Barber et al.).
    fn mark_visible(&mut self, p: Vec64, seed: u8) {
        for t in self.tris.iter_mut() {
            t.visible = false;
        }
        let mut stack = [0u8; MAX_WORK_TRIS];
        let mut len = 0;
        if let Some(t) = self.tris.get_mut(seed as usize).filter(|t| t.alive) {
            t.visible = true;
            stack[0] = seed;
            len = 1;
        }
        // Each triangle is pushed at most once (when it turns visible).
        while len > 0 {
            len -= 1;
            let top = stack.get(len).copied().unwrap_or(NONE);
            let adj = self.tris.get(top as usize).map_or([NONE; 3], |t| t.adj);
            for nb in adj {
                let Some(t) = self.tris.get_mut(nb as usize) else {
                    continue;
                };
                if t.alive && !t.visible && t.height(p) > self.eps {
                    if let Some(slot) = stack.get_mut(len) {
                        t.visible = true;
                        *slot = nb;
                        len += 1;
                    }
                }
            }
        }
    }

    /// Grow the visible region until its horizon is one simple loop and the cone from
    /// `p` to it is convex: no hull vertex more than `FOLD_FRACTION · eps` above any cone
    /// triangle, where that can be mended (see [`Builder::absorb_folds`]). Returns the
    /// horizon's length, or `None` when there is no such cone.
    ///
    /// Departure from Barber et al.: a triangle that `p` is above by less than `eps` is
    /// not visible, and the cone triangle `(a, b, p)` on its edge then folds over it. On a
    /// thin hull that fold leaves vertices several `eps` outside, and when `p` is nearly in
    /// the plane of a flat region the cone triangle can even come out upside down. Each
    /// round makes the triangle beyond every offending horizon edge visible; each round
    /// that does not finish makes at least one more triangle visible.
    fn settle_horizon(&mut self, p: Vec64, horizon: &mut [Edge; MAX_HORIZON]) -> Option<usize> {
        let mut vertices = [0u16; MAX_HULL_VERTICES];
        let mut nv = 0usize;
        let n = self.points.len().min(MAX_HULL_INPUT_POINTS);
        for (i, &d) in self.degree.iter().enumerate().take(n) {
            if d > 0 {
                *vertices.get_mut(nv)? = i as u16;
                nv += 1;
            }
        }
        let vertices = vertices.get(..nv)?;
        for _ in 0..MAX_WORK_TRIS {
            let grew = match self.horizon_loop(horizon) {
                Some(c) => match self.absorb_folds(p, horizon.get(..c)?, vertices) {
                    Folds::Absorbed => true,
                    Folds::Mild => return Some(c),
                    Folds::Stuck => return None,
                },
                None => self.grow_visible(p),
            };
            if !grew {
                return None;
            }
        }
        None
    }

    /// Check the cone over `horizon` for folds: cone triangles with a hull vertex more
    /// than `FOLD_FRACTION · eps` above them (or no area). The triangle beyond a fold is
    /// made visible when `p` is not more than `eps` below it ([`Folds::Absorbed`]). A fold
    /// whose triangle `p` is farther below cannot be mended that way; when it leaves a
    /// vertex more than `eps` outside, the cone is refused ([`Folds::Stuck`]), else
    /// accepted ([`Folds::Mild`]).
    fn absorb_folds(&mut self, p: Vec64, horizon: &[Edge], vertices: &[u16]) -> Folds {
        let limit = FOLD_FRACTION * self.eps;
        let mut absorbed = false;
        let mut stuck = false;
        for e in horizon {
            let a = self.point(e.a);
            let worst = match unit((self.point(e.b) - a).cross(p - a)) {
                Some(n) => vertices
                    .iter()
                    .map(|&v| n.dot(self.point(v) - a))
                    .fold(f64::NEG_INFINITY, |m, h| if h > m { h } else { m }),
                None => f64::INFINITY,
            };
            if worst <= limit {
                continue;
            }
            let eps = self.eps;
            match self.tris.get_mut(e.outer as usize).filter(|t| t.alive) {
                Some(t) if !t.visible && t.height(p) > -eps => {
                    t.visible = true;
                    absorbed = true;
                }
                _ => stuck |= worst > eps,
            }
        }
        if absorbed {
            Folds::Absorbed
        } else if stuck {
            Folds::Stuck
        } else {
            Folds::Mild
        }
    }

    /// When the horizon is not one simple loop (never seen in testing, but not ruled out
    /// by rounding), add to the visible set every triangle next to it that `p` is less
    /// than `eps` below. Returns false when there was none.
    fn grow_visible(&mut self, p: Vec64) -> bool {
        let mut grow = [false; MAX_WORK_TRIS];
        for (g, t) in grow.iter_mut().zip(self.tris.iter()) {
            let touches = t
                .adj
                .iter()
                .any(|&nb| self.tri(nb).is_some_and(|u| u.visible));
            *g = t.alive && !t.visible && t.height(p) > -self.eps && touches;
        }
        let mut grew = false;
        for (g, t) in grow.iter().zip(self.tris.iter_mut()) {
            if *g {
                t.visible = true;
                grew = true;
            }
        }
        grew
    }

    /// The boundary of the visible region as one loop of edges `out[k].b == out[k+1].a`,
    /// or `None` when it is not a single simple loop (or longer than [`MAX_HORIZON`]).
    fn horizon_loop(&self, out: &mut [Edge; MAX_HORIZON]) -> Option<usize> {
        let mut edges = [Edge::default(); MAX_HORIZON];
        let mut count = 0;
        for t in self.tris.iter().filter(|t| t.alive && t.visible) {
            for k in 0..3 {
                let nb = t.adj[k];
                if self.tri(nb).is_some_and(|u| u.visible) {
                    continue;
                }
                *edges.get_mut(count)? = Edge {
                    a: t.v[k],
                    b: t.next(k),
                    outer: nb,
                };
                count += 1;
            }
        }
        chain_loop(edges.get(..count)?, 0, out)
    }

    // -----------------------------------------------------------------------------------
    // Stage 3: faces.
    // -----------------------------------------------------------------------------------

    /// Turn the triangle mesh into the hull's polygon faces and fill `hull` (an
    /// [`EMPTY_HULL`]; unspecified after an error). Out of line, with the hull the
    /// caller's: the polygons' scratch is on the stack only while they are made, and the
    /// hull is not built in a local and copied out.
    #[inline(never)]
    fn finish(&mut self, hull: &mut ConvexHull) -> Result<(), Error> {
        self.eps = self.merge_eps;
        // Between two planes 2 eps apart: within eps of the plane between them.
        if self.width() <= 2.0 * self.eps {
            return Err(Error::Hull(HullError::Coplanar));
        }
        let mut polys = Polygons::new();
        self.merge_coplanar(&mut polys)?;
        self.drop_flat_vertices(&mut polys);

        hull.tolerance = self.eps as f32;
        hull.reduced = self.reduced;
        // Vertices: the points still used, in input order; `owner` now maps an input index
        // to its output index.
        let n = self.points.len();
        let mut vc = 0usize;
        for (i, (o, &deg)) in self
            .owner
            .iter_mut()
            .zip(self.degree.iter())
            .take(n)
            .enumerate()
        {
            *o = NONE;
            if deg > 0 {
                let slot = hull
                    .vertices
                    .get_mut(vc)
                    .ok_or(Error::Hull(HullError::TooComplex))?;
                *slot = self.points.get(i).copied().unwrap_or(Vec3::ZERO);
                *o = vc as u8;
                vc += 1;
            }
        }
        hull.vertex_count = vc as u8;
        // Four to a group, the last group's padding lanes repeating vertex 0.
        let first = hull.vertices.first().copied().unwrap_or(Vec3::ZERO);
        for (i, v) in hull.vertices.iter().take(vc.div_ceil(4) * 4).enumerate() {
            if let Some(group) = hull.vertex_lanes.get_mut(i / 4) {
                group.set(i % 4, if i < vc { *v } else { first });
            }
        }

        for k in 0..polys.count {
            let mut corners = [0u8; MAX_HULL_VERTICES];
            let mut len = 0usize;
            for &c in polys.corners(k) {
                let o = self.owner.get(c as usize).copied().unwrap_or(NONE);
                if o == NONE {
                    return Err(Error::Hull(HullError::TooComplex));
                }
                *corners
                    .get_mut(len)
                    .ok_or(Error::Hull(HullError::TooComplex))? = o;
                len += 1;
            }
            let corners = corners.get_mut(..len).unwrap_or(&mut []);
            // Start at the lowest-index vertex.
            let first = lowest_at(corners.iter().copied());
            crate::sort::rotate_left(corners, first);
            emit_split(hull, corners, polys.plane(k))?;
        }

        if hull.face_count < 4 || hull.vertex_count < 4 {
            return Err(Error::Hull(HullError::Coplanar));
        }
        link_edges(hull);
        // Not seen after the width test, but a hull without volume is flat.
        let (_, centroid, _) = hull
            .volume_integrals()
            .ok_or(Error::Hull(HullError::Coplanar))?;
        hull.centroid = centroid;
        hull.thinnest = hull.thinnest_width();
        hull.well_formed_edges = hull.edges_run_along_faces();
        hull.inner_radius = hull.centroid_depth();
        hull.outer_radius = hull.farthest_vertex();
        Ok(())
    }

    /// The mesh's smallest width over its triangle normals: for each triangle, the depth
    /// of the deepest vertex below it. The initial tetrahedron only proves the cloud
    /// thicker than `eps` along one normal; when the finished hull fits between two
    /// planes `2 eps` apart, every point is within `eps` of the plane between them: the
    /// cloud is coplanar after all (and merging near-coplanar triangles could fold it
    /// flat).
    fn width(&self) -> f64 {
        let mut width = f64::INFINITY;
        for t in self.tris.iter().filter(|t| t.alive) {
            let mut deepest = 0.0f64;
            for (i, _) in self.degree.iter().enumerate().filter(|(_, &d)| d > 0) {
                let depth = -t.height(point_at(self.points, i));
                if depth > deepest {
                    deepest = depth;
                }
            }
            if deepest < width {
                width = deepest;
            }
        }
        width
    }

    /// Are all corners of `t` within `eps` of the plane of `seed`, on the same side?
    fn near_plane(&self, seed: &Tri, t: &Tri) -> bool {
        seed.n.dot(t.n) > 0.0
            && t.v.iter().all(|&i| {
                let h = seed.height(self.point(i));
                h <= self.eps && h >= -self.eps
            })
    }

    /// Group the triangles into near-coplanar patches, each grown (breadth first, through
    /// shared edges) from its lowest-slot triangle and judged against that seed's plane,
    /// so a patch cannot drift; then write each patch's boundary loop as one polygon. A
    /// patch whose boundary is not one simple loop keeps its triangles as faces.
    fn merge_coplanar(&self, polys: &mut Polygons) -> Result<(), Error> {
        // Seeds by decreasing area (ties: lower slot), so a patch is judged against the
        // plane of its largest triangle and slivers join a large neighbour.
        let mut order = [0u8; MAX_WORK_TRIS];
        let mut area2 = [0.0f64; MAX_WORK_TRIS];
        let mut live = 0usize;
        for (slot, t) in self.tris.iter().enumerate().filter(|(_, t)| t.alive) {
            let [a, b, c] = t.v.map(|i| self.point(i));
            if let (Some(area), Some(o)) = (area2.get_mut(slot), order.get_mut(live)) {
                *area = (b - a).cross(c - a).length_squared();
                *o = slot as u8;
                live += 1;
            }
        }
        let order = order.get_mut(..live).unwrap_or(&mut []);
        // Largest area first, then the lower slot: a strict order on distinct slots.
        crate::sort::sort_unstable_by(order, |&x, &y| {
            let area = |i: u8| area2.get(i as usize).copied().unwrap_or(0.0);
            area(y).total_cmp(&area(x)).then(x.cmp(&y)).is_lt()
        });

        let mut group = [NONE; MAX_WORK_TRIS];
        let mut stack = [0u8; MAX_WORK_TRIS];
        let mut groups = 0u8;
        for &seed in order.iter() {
            let seed = seed as usize;
            let Some(&seed_tri) = self.tris.get(seed) else {
                continue;
            };
            let Some(seed_group) = group.get_mut(seed).filter(|g| **g == NONE) else {
                continue;
            };
            if !seed_tri.alive {
                continue;
            }
            let g = groups;
            groups = groups.saturating_add(1);
            *seed_group = g;
            stack[0] = seed as u8;
            let mut len = 1;
            // Each triangle is pushed at most once (when it joins the group).
            while len > 0 {
                len -= 1;
                let top = stack.get(len).copied().unwrap_or(NONE);
                let adj = self.tris.get(top as usize).map_or([NONE; 3], |t| t.adj);
                for nb in adj {
                    let Some(t) = self.tri(nb) else {
                        continue;
                    };
                    let joins = self.near_plane(&seed_tri, t);
                    let free = group.get_mut(nb as usize).filter(|x| **x == NONE);
                    if let (true, Some(member), Some(top)) = (joins, free, stack.get_mut(len)) {
                        *member = g;
                        *top = nb;
                        len += 1;
                    }
                }
            }
            if !self.push_patch(g, &group, &seed_tri, polys)? {
                for (t, _) in self
                    .tris
                    .iter()
                    .zip(group.iter())
                    .filter(|(_, &gg)| gg == g)
                {
                    let first = lowest_at(t.v.iter().copied());
                    let mut v = t.v;
                    crate::sort::rotate_left(&mut v, first);
                    polys.push(&v, self.plane_over(t.n, &v))?;
                }
            }
        }
        Ok(())
    }

    /// Write patch `g`'s boundary as one polygon, starting at its lowest-index corner.
    /// Returns false (writing nothing) when the boundary is not a single simple loop or
    /// not convex within `eps` about the seed's normal (a patch can wrap around a sliver
    /// that another patch took).
    fn push_patch(
        &self,
        g: u8,
        group: &[u8; MAX_WORK_TRIS],
        seed: &Tri,
        polys: &mut Polygons,
    ) -> Result<bool, Error> {
        let mut edges = [Edge::default(); MAX_HORIZON];
        let mut count = 0usize;
        for (t, _) in self
            .tris
            .iter()
            .zip(group.iter())
            .filter(|(_, &gg)| gg == g)
        {
            for k in 0..3 {
                if group.get(t.adj[k] as usize) == Some(&g) {
                    continue;
                }
                let Some(e) = edges.get_mut(count) else {
                    return Ok(false);
                };
                *e = Edge {
                    a: t.v[k],
                    b: t.next(k),
                    outer: t.adj[k],
                };
                count += 1;
            }
        }
        let edges = edges.get(..count).unwrap_or(&[]);
        let start = lowest_at(edges.iter().map(|e| e.a));
        let mut ordered = [Edge::default(); MAX_HORIZON];
        let Some(len) = chain_loop(edges, start, &mut ordered) else {
            return Ok(false);
        };
        let mut corners = [0u16; MAX_HORIZON];
        for (c, e) in corners.iter_mut().zip(ordered.iter()).take(len) {
            *c = e.a;
        }
        let corners = corners.get(..len).unwrap_or(&[]);
        if !self.is_convex(corners, seed.n) {
            return Ok(false);
        }
        // The plane: the seed's normal, raised over every corner of every triangle in the
        // patch, so the points the merge drops from the middle stay under it.
        let mut d = f64::NEG_INFINITY;
        for (t, _) in self
            .tris
            .iter()
            .zip(group.iter())
            .filter(|(_, &gg)| gg == g)
        {
            let (_, dt) = self.plane_over(seed.n, &t.v);
            if dt > d {
                d = dt;
            }
        }
        polys.push(corners, (seed.n, d))?;
        Ok(true)
    }

    /// The plane with normal `n` through the highest of `corners`.
    fn plane_over(&self, n: Vec64, corners: &[u16]) -> (Vec64, f64) {
        let mut d = f64::NEG_INFINITY;
        for &i in corners {
            let h = n.dot(self.point(i));
            if h > d {
                d = h;
            }
        }
        (n, d)
    }

    /// Is the polygon convex and counter-clockwise about `n`, within `eps`: every corner
    /// at most `eps` to the right of every edge, `((b − a) × (c − a)) · n ≥ −eps |b − a|`?
    fn is_convex(&self, corners: &[u16], n: Vec64) -> bool {
        let next = corners.iter().skip(1).chain(corners.first());
        for (&i, &j) in corners.iter().zip(next) {
            let (a, b) = (self.point(i), self.point(j));
            let ab = b - a;
            let slack = self.eps * sqrt64(ab.length_squared()).unwrap_or(0.0);
            for &k in corners {
                if ab.cross(self.point(k) - a).dot(n) < -slack {
                    return false;
                }
            }
        }
        true
    }

    /// Count each point's polygons into `degree`, then drop the points that no longer
    /// shape the hull: in no polygon (inside a merged face) or in exactly two (on a
    /// straight edge between two faces, removed from both, when both keep at least three
    /// corners).
    fn drop_flat_vertices(&mut self, polys: &mut Polygons) {
        for d in self.degree.iter_mut() {
            *d = 0;
        }
        for k in 0..polys.count {
            for &c in polys.corners(k) {
                if let Some(d) = self.degree.get_mut(c as usize) {
                    *d = d.saturating_add(1);
                }
            }
        }
        let n = self.points.len();
        for i in 0..n.min(MAX_HULL_INPUT_POINTS) {
            if self.degree[i] != 2 {
                continue;
            }
            let mut holders = [0usize; 2];
            let mut found = 0;
            for k in 0..polys.count {
                if polys.corners(k).contains(&(i as u16)) {
                    if let Some(h) = holders.get_mut(found) {
                        *h = k;
                    }
                    found += 1;
                }
            }
            if found == 2 && holders.iter().all(|&k| polys.corners(k).len() > 3) {
                for &k in &holders {
                    polys.remove_corner(k, i as u16);
                }
                self.degree[i] = 0;
            }
        }
    }
}

/// Order `edges` into one loop starting at `edges[start]`, each edge's `b` the next one's
/// `a`, into `out`; `None` unless they form exactly one simple loop (every start vertex
/// distinct, every edge used once, at least 3 edges).
fn chain_loop(edges: &[Edge], start: usize, out: &mut [Edge; MAX_HORIZON]) -> Option<usize> {
    let count = edges.len();
    if !(3..=MAX_HORIZON).contains(&count) {
        return None;
    }
    for (k, e) in edges.iter().enumerate() {
        if edges.iter().skip(k + 1).any(|f| f.a == e.a) {
            return None;
        }
    }
    let mut used = [false; MAX_HORIZON];
    let mut current = *edges.get(start)?;
    *used.get_mut(start)? = true;
    out[0] = current;
    for slot in out.iter_mut().take(count).skip(1) {
        let j = (0..count).find(|&j| !used[j] && edges[j].a == current.b)?;
        used[j] = true;
        current = edges[j];
        *slot = current;
    }
    if current.b == out[0].a {
        Some(count)
    } else {
        None
    }
}

/// Polygons (corner lists of input indices) between the merge and the output.
/// Every triangle edge is a boundary edge of at most one polygon, so the corners of all
/// polygons number at most three per triangle.
struct Polygons {
    start: [u16; MAX_WORK_TRIS],
    len: [u8; MAX_WORK_TRIS],
    corners: [u16; 3 * MAX_WORK_TRIS],
    /// Each polygon's plane `n · p = d`.
    planes: [(Vec64, f64); MAX_WORK_TRIS],
    count: usize,
    used: usize,
}

impl Polygons {
    fn new() -> Polygons {
        Polygons {
            start: [0; MAX_WORK_TRIS],
            len: [0; MAX_WORK_TRIS],
            corners: [0; 3 * MAX_WORK_TRIS],
            planes: [(Vec64::ZERO, 0.0); MAX_WORK_TRIS],
            count: 0,
            used: 0,
        }
    }

    fn push(&mut self, corners: &[u16], plane: (Vec64, f64)) -> Result<(), Error> {
        let full = Error::Hull(HullError::TooComplex);
        *self.planes.get_mut(self.count).ok_or(full)? = plane;
        let dst = self
            .corners
            .get_mut(self.used..self.used + corners.len())
            .ok_or(full)?;
        dst.copy_from_slice(corners);
        *self.start.get_mut(self.count).ok_or(full)? = self.used as u16;
        *self.len.get_mut(self.count).ok_or(full)? = corners.len() as u8;
        self.count += 1;
        self.used += corners.len();
        Ok(())
    }

    fn plane(&self, k: usize) -> (Vec64, f64) {
        self.planes.get(k).copied().unwrap_or((Vec64::ZERO, 0.0))
    }

    fn corners(&self, k: usize) -> &[u16] {
        let s = self.start.get(k).copied().unwrap_or(0) as usize;
        let l = self.len.get(k).copied().unwrap_or(0) as usize;
        self.corners.get(s..s + l).unwrap_or(&[])
    }

    fn remove_corner(&mut self, k: usize, vertex: u16) {
        let s = self.start.get(k).copied().unwrap_or(0) as usize;
        let Some(len) = self.len.get_mut(k) else {
            return;
        };
        let Some(c) = self.corners.get_mut(s..s + *len as usize) else {
            return;
        };
        if let Some(j) = c.iter().position(|&v| v == vertex) {
            // The removed corner moves to the end, out of the shortened face.
            if let Some(tail) = c.get_mut(j..) {
                crate::sort::rotate_left(tail, 1);
            }
            *len -= 1;
        }
    }
}

/// Fill the hull's edge list: every directed edge `i → j` (`i < j`) of a face, paired with
/// the face that holds `j → i`, unless the two faces are coplanar (the seam of a split
/// face). Quadratic in the number of corners (at most 372), once per hull. `closed` says
/// whether every corner found its twin.
fn link_edges(hull: &mut ConvexHull) {
    let faces = hull.face_count();
    // The directed edge leaving corner k of face f.
    let edge_at = |h: &ConvexHull, f: usize, k: usize| -> Option<(u8, u8)> {
        let v = h.face_vertices(f);
        Some((*v.get(k)?, *v.get((k + 1) % v.len().max(1))?))
    };
    let mut closed = true;
    let mut count = 0usize;
    for f in 0..faces {
        for k in 0..hull.face_vertices(f).len() {
            let Some((i, j)) = edge_at(hull, f, k) else {
                continue;
            };
            let twin = (0..faces).filter(|&g| g != f).find(|&g| {
                (0..hull.face_vertices(g).len()).any(|m| edge_at(hull, g, m) == Some((j, i)))
            });
            let Some(g) = twin else {
                closed = false;
                continue;
            };
            let coplanar = hull.normals.get(f) == hull.normals.get(g);
            if i < j && !coplanar {
                match hull.edges.get_mut(count) {
                    Some(slot) => {
                        *slot = [i, j, f as u8, g as u8];
                        count += 1;
                    }
                    None => closed = false,
                }
            }
        }
    }
    hull.edge_count = count as u8;
    hull.closed = closed;
}

/// Write one polygon (output vertex indices, counter-clockwise, first corner lowest) with
/// its plane as faces: whole when it has at most [`MAX_FACE_VERTICES`] corners, else as a
/// fan of pieces from corner 0: `0, 1..=15`, `0, 15..=29`, ... (each piece a convex
/// sub-polygon in the same plane).
fn emit_split(hull: &mut ConvexHull, corners: &[u8], plane: (Vec64, f64)) -> Result<(), Error> {
    let len = corners.len();
    if len <= MAX_FACE_VERTICES {
        return emit_face(hull, corners, plane);
    }
    let mut piece = [0u8; MAX_FACE_VERTICES];
    piece[0] = corners.first().copied().unwrap_or(0);
    let mut s = 1usize;
    // Each piece advances s by MAX_FACE_VERTICES − 2 ≥ 1.
    while s + 1 < len {
        let end = (s + MAX_FACE_VERTICES - 2).min(len - 1);
        let src = corners.get(s..=end).unwrap_or(&[]);
        let dst = piece.get_mut(1..1 + src.len()).unwrap_or(&mut []);
        crate::sort::copy_into(dst, src);
        emit_face(hull, piece.get(..1 + src.len()).unwrap_or(&[]), plane)?;
        s = end;
    }
    Ok(())
}

/// Append one face with its plane `(n, d)` rounded to f32; the offset is raised, if
/// rounding needs it, to the largest `n · c` over the corners in f32, so every corner lies
/// on or below the stored plane.
fn emit_face(hull: &mut ConvexHull, corners: &[u8], plane: (Vec64, f64)) -> Result<(), Error> {
    let full = Error::Hull(HullError::TooComplex);
    let f = hull.face_count as usize;
    let start = hull
        .face_start
        .get(f.wrapping_sub(1))
        .zip(hull.face_len.get(f.wrapping_sub(1)))
        .map_or(0, |(&s, &l)| s as usize + l as usize);
    let dst = hull
        .face_indices
        .get_mut(start..start + corners.len())
        .ok_or(full)?;
    dst.copy_from_slice(corners);
    let (n64, d64) = plane;
    let n = unit(n64).ok_or(full)?.rounded();
    let mut d = d64 as f32;
    for &c in corners {
        d = scalar::max(d, n.dot(hull.core_vertex(c as u32)));
    }
    if !d.is_finite() {
        return Err(full);
    }
    *hull.normals.get_mut(f).ok_or(full)? = n;
    *hull.offsets.get_mut(f).ok_or(full)? = d;
    *hull.face_start.get_mut(f).ok_or(full)? = start as u16;
    *hull.face_len.get_mut(f).ok_or(full)? = corners.len() as u8;
    hull.face_count += 1;
    Ok(())
}

/// Index of the first smallest item (0 when empty).
fn lowest_at<T: Ord>(items: impl Iterator<Item = T>) -> usize {
    let mut best: Option<(usize, T)> = None;
    for (i, x) in items.enumerate() {
        if best.as_ref().is_none_or(|(_, b)| x < *b) {
            best = Some((i, x));
        }
    }
    best.map_or(0, |(i, _)| i)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::rng::SplitMix64;

    /// The support scan in index order, strict `>`: the reference for the four-lane scan.
    fn sequential_support(h: &ConvexHull, dir: Vec3) -> u32 {
        let mut best = 0usize;
        let mut best_d = f32::NEG_INFINITY;
        for (i, v) in h.vertices().iter().enumerate() {
            let d = v.dot(dir);
            if d > best_d {
                best_d = d;
                best = i;
            }
        }
        best as u32
    }

    /// The box from the lane passes holds every vertex turned by the quaternion and
    /// touches the extreme ones, within rounding (1e-6 of the coordinates' size), for
    /// random hulls at random poses, and is exact for an unturned hull.
    #[test]
    fn the_lane_box_is_the_box_of_the_turned_vertices() {
        let mut rng = SplitMix64::new(36);
        for n in 4..40 {
            let pts: std::vec::Vec<Vec3> = (0..n)
                .map(|_| rng.unit_vector() * rng.range(0.1, 3.0))
                .collect();
            let Ok(h) = ConvexHull::new(&pts) else {
                continue;
            };
            for _ in 0..20 {
                let pose = Iso::new(
                    Vec3::new(
                        rng.range(-50.0, 50.0),
                        rng.range(-50.0, 50.0),
                        rng.range(-50.0, 50.0),
                    ),
                    rng.rotation(),
                );
                let turned = h.vertices().iter().map(|v| pose.transform_point(*v));
                let first = pose.transform_point(h.vertices()[0]);
                let oracle = turned.fold(Aabb::new(first, first), |b, p| {
                    Aabb::new(b.min.min(p), b.max.max(p))
                });
                let b = h.aabb(&pose);
                let tol = 1.0e-6 * (pose.position.abs().max_elem() + 3.0);
                assert!(
                    (b.min - oracle.min).abs().max_elem() <= tol,
                    "{b:?} {oracle:?}"
                );
                assert!(
                    (b.max - oracle.max).abs().max_elem() <= tol,
                    "{b:?} {oracle:?}"
                );
            }
            let still = h.aabb(&Iso::IDENTITY);
            let first = h.vertices()[0];
            let exact = h.vertices().iter().fold(Aabb::new(first, first), |b, v| {
                Aabb::new(b.min.min(*v), b.max.max(*v))
            });
            assert_eq!(still, exact);
        }
    }

    #[test]
    fn four_lane_support_and_min_dot_are_the_sequential_scans() {
        let mut rng = SplitMix64::new(21);
        // A cube's corners (ties along the axes and diagonals) and random clouds of
        // every remainder mod 4, up to the 64 vertices (16 groups) of a full hull.
        let cube: std::vec::Vec<Vec3> = (0..8)
            .map(|i| {
                let s = |b: u32| if i & b != 0 { 1.0 } else { -1.0 };
                Vec3::new(s(1), s(2), s(4))
            })
            .collect();
        let mut hulls = std::vec![ConvexHull::new(&cube).unwrap()];
        for n in (4..40).chain(60..=MAX_HULL_VERTICES) {
            let pts: std::vec::Vec<Vec3> = (0..n).map(|_| rng.unit_vector()).collect();
            if let Ok(h) = ConvexHull::new(&pts) {
                hulls.push(h);
            }
        }
        let axes = [
            Vec3::X,
            Vec3::Y,
            Vec3::Z,
            -Vec3::X,
            Vec3::new(1.0, 1.0, 0.0),
            Vec3::ZERO,
            // Infinite products (+∞ ties, −∞ everywhere) and NaN ones (0 · ∞) beside
            // finite ones.
            Vec3::new(f32::INFINITY, 0.0, 0.0),
            Vec3::new(f32::NEG_INFINITY, 1.0, 0.0),
            Vec3::new(f32::INFINITY, f32::INFINITY, 0.0),
        ];
        assert!(hulls
            .iter()
            .any(|h| h.vertices().len() == MAX_HULL_VERTICES));
        for h in &hulls {
            for dir in axes
                .iter()
                .copied()
                .chain((0..50).map(|_| rng.unit_vector()))
            {
                let (p, i) = h.core_support(dir);
                assert_eq!(i, sequential_support(h, dir), "{dir:?}");
                assert_eq!(p, h.core_vertex(i));
                // The smallest product, against a scan in index order.
                let low = h.vertices().iter().fold(f32::INFINITY, |m, v| {
                    if v.dot(dir) < m {
                        v.dot(dir)
                    } else {
                        m
                    }
                });
                assert_eq!(h.min_dot(dir), low, "{dir:?}");
            }
            let nan = Vec3::new(f32::NAN, 0.0, 0.0);
            assert_eq!(h.core_support(nan).1, sequential_support(h, nan));
        }
    }
}
