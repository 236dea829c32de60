//! The separating axis test (SAT) for polytope pairs (box–box, box–hull, hull–hull) and for
//! a capsule against a box, and the contact manifolds built on its answer.
//!
//! # The test
//!
//! Two convex polytopes A and B are disjoint exactly when a plane separates them, and the
//! plane's normal can always be taken among the face normals of their Minkowski
//! difference `D = B − A` (Gregorius, "The Separating Axis Test between Convex Polyhedra",
//! GDC 2013). The faces of `D` are of three kinds:
//!
//! 1. a face of A swept by the feature of B that supports the opposite direction: normal
//!    = A's face normal;
//! 2. a face of B swept by a feature of A: normal = B's face normal, reversed;
//! 3. the parallelogram of an edge of A and an edge of B, when it is a face of `D` at all:
//!    normal ±(e_A × e_B).
//!
//! Along a unit axis `n` (from A towards B) the separation is
//! `s(n) = min_{b∈B} n·b − max_{a∈A} n·a`, computed with one support point per shape. The
//! largest `s` over the face normals of `D` is the signed distance of the shapes when they
//! overlap (minus the penetration depth): the point of `D`'s boundary nearest to the
//! origin is the origin's projection on `D`'s nearest face plane, and it lies inside that
//! face. When the shapes are apart the largest `s` is only a lower bound of the distance:
//! it is the distance when the closest points of `D` lie inside a face, and smaller when
//! they lie on an edge or a vertex of `D` (two boxes corner to corner).
//!
//! # Gauss-map pruning
//!
//! The Gauss map sends each feature of a polytope to the unit directions it supports: a
//! face to its normal, an edge to the great arc between the normals of its two faces. An
//! edge of A and an edge of B span a face of `D` exactly when A's arc and B's arc turned
//! inside out (`−n`) cross. For A's arc `(a, b)` and B's negated arc `(c, d)` the arcs
//! cross when `c` and `d` lie on opposite sides of the plane of `(a, b)`,
//! `(c·(b×a)) (d·(b×a)) < 0`; `a` and `b` on opposite sides of the plane of `(c, d)`,
//! `(a·(d×c)) (b·(d×c)) < 0`; and the two great circles cross on the arcs' side of the
//! sphere, not at the antipodes, `(c·(b×a)) (b·(d×c)) > 0` (Gregorius's three triple
//! products). For faces wound counter-clockwise about outward normals, `b×a` points along
//! A's edge reversed and `d×c` along B's edge reversed, so the edge vectors stand in for
//! the two cross products (which lose their direction when two faces are almost coplanar).
//! Only pairs that pass are measured, along `n = ±(e_A × e_B) / |e_A × e_B|` oriented away
//! from A's centre, `s = n · (p_B − p_A)` for any points on the two edges (the edges are
//! the supporting features along `±n`). Nearly parallel edges (`sin θ` below
//! [`EDGE_PARALLEL_SIN`]) are skipped: their axis is rounding noise, and the face axes
//! next to them carry the contact.
//!
//! # Bounds that skip whole faces and edges
//!
//! Each shape holds the ball of radius `r` (its centre's least distance to a face plane)
//! about its centre `c`, so its support along any unit `n` reaches at least `r` past `c`:
//! `min_B n·y ≤ n·c_B − r_B`. A face of A therefore separates by at most its separation at
//! B's centre less `r_B`, one product per face; the face with the largest bound is
//! measured first and a face whose bound is below the best so far is never measured
//! (`best_face`). An edge pair's axis lies on both edges' arcs, so its separation is at
//! most `max n·(c_B − p)` over A's arc, less `r_B` (`p` on A's edge), and the same from
//! B's side: an edge whose bound is below the best face separation takes no part in the
//! edge loop. An edge the centres keep is bounded once more from a vertex of the other
//! shape that lies where the two meet (`deepest_vertices`): `s(n) ≤ n · (y − p)` for any
//! point `y` of B, with no ball needed. Only an edge pair that separates more than the best face can change the
//! answer, so the result is the full test's, bit for bit (the test
//! `pruned_query_matches_the_full_test_bit_for_bit` compares them). Edges are pruned only
//! when every edge of both shapes runs along its faces' crossing line within `10⁻⁵` rad
//! (a merged, slightly non-planar hull face can break that), with the arc widened for
//! that tilt, and only when one of the two shapes holds a ball (a box or a hull, so a
//! triangle's edges too against one of them: see `edge_below`); every bound carries a slack of
//! ten axis-choice tolerances for rounding and for a hull's vertices lying up to its
//! build tolerance inside its planes. On the `hulls` scene this halves the test's work.
//!
//! Two boxes need no pruning: the arcs of one box's edges along one direction make up the
//! whole great circle perpendicular to it, so for every pair of edge directions `(i, j)`
//! exactly one pair of edges spans a face of `D` with a normal towards B, at
//! `±(e_i × b_j)`; its separation has the closed form of the 15-axis box test (Gottschalk,
//! Lin and Manocha, "OBBTree", 1996), and its edges are the box supports along `±n`.
//!
//! # The axis chosen, and the manifold
//!
//! The test keeps the best (largest) separation of each kind, ties to the lowest index,
//! and stops as soon as one axis separates the shapes by more than the margin. Then:
//! one shape's best face is preferred to the other's only when it separates by more than
//! the tolerance `SAT_TOLERANCE · scale`; within it, a tie rule that does not depend on
//! which shape is A picks the face (the shapes' geometry, then the face indices: see
//! `prefers_b`), so `contact(B, A)` chooses the face `contact(A, B)` chose; and the best
//! edge pair is preferred to that face only when better by more than the tolerance (see
//! [`SAT_TOLERANCE`]) and, for overlapping shapes, by more than a tenth of the face's depth
//! ([`EDGE_DEPTH_PREFERENCE`]: a face gives up to four points, an edge pair one). A
//! resting contact keeps a stable normal.
//!
//! - A face axis: the reference face is that face, the incident face the other shape's
//!   face most anti-parallel to it; the incident face is clipped against the reference
//!   face's side planes (Sutherland–Hodgman, [`super::clip`]), points within the margin
//!   are kept and reduced to 4, with the feature pair of each point as ids. The normal is
//!   the reference face's, exactly.
//! - An edge axis: one point, the closest points of the two edge segments (Ericson 5.1.9),
//!   ids (edge of A, edge of B).
//!
//! Guard: for shapes apart along the axis the deepest clipped point must be within
//! `2 · SAT_TOLERANCE · scale` of the axis's separation, for overlapping shapes within
//! that of the test's exact separation (the minimal penetration, which an edge pair the
//! face was preferred to may set), and an edge point of shapes that
//! are apart must lie inside both segments. Otherwise the closest (or deepest) features are not the ones the axis found
//! (shapes apart at a corner, or a near-tie the tolerance let through) and the test answers
//! [`SatOutcome::Fallback`]: the caller runs the general GJK/EPA path.
//!
//! Everything runs in A's frame with B's rotation as a matrix; loops are bounded by the
//! shapes' face and edge counts; no allocation, no arrays but the clipping buffers.

use super::analytic::{feature_at, segment_closest_points};
use super::clip;
use super::manifold::{clipped_face_manifold, Candidate, ContactId, LocalManifold};
use crate::math::{scalar, Iso, Mat3, Vec3};
use crate::shape::EDGE_TILT_SIN;
use crate::shape::{
    Capsule, ConvexHull, Cuboid, Face, FeatureId, Polygon, Triangle, MAX_HULL_EDGES, MAX_HULL_FACES,
};

/// Relative tolerance of the separating axis test's axis choice (box and hull pairs in
/// [`super::contact`]): one shape's best face must separate more than the other's (within
/// it a tie rule independent of the argument order decides), and the best edge pair more
/// than the chosen face, by `SAT_TOLERANCE · scale` (m) to be chosen, with
/// `scale = |t| + extent(A) + extent(B)` (`t` B's position in A's frame, the extent the
/// largest core coordinate; for a hull, its build tolerance over
/// [`crate::shape::ConvexHull::TOLERANCE`]). For 1 m shapes about 3e-5 m: a hundred times the
/// rounding of a separation (about 1e-7 of the scale), so resting contacts keep their
/// reference face and normal through rounding and solver jitter, and small enough that a
/// face chosen over a slightly better axis stays within 1e-4 m of the true depth.
pub const SAT_TOLERANCE: f32 = 1.0e-5;

/// Edge pairs whose directions make an angle with `sin θ` below this (about 0.06°) are
/// skipped: their cross product is then dominated by rounding, and the face axes at the
/// ends of the two nearly coinciding arcs carry the contact (for exactly parallel edges
/// they are the faces of `D`).
pub(crate) const EDGE_PARALLEL_SIN: f32 = 1.0e-3;

/// How much shallower than the chosen face an edge pair of two *overlapping* polytopes
/// must be to be chosen instead, as a fraction of the face's depth (on top of
/// [`SAT_TOLERANCE`]): the edge pair wins only when `s_edge > s_face + tol + 0.1 · |s_face|`.
///
/// An edge axis gives one contact point, a face up to four. Two boxes resting on each
/// other with a small tilt and an offset have an edge pair (the upper box's bottom edge
/// over the lower box's top edge, next to the overhanging corner) a few per cent
/// shallower than their face: with the exact minimum, half of such pairs got one point,
/// the upper box pivoted on it, and the falling columns of the `boxes` scene sank 0.5 m
/// into each other and toppled. Gregorius ("The Separating Axis Test between convex
/// polyhedra", GDC 2013) prefers faces by the same 10 %; Bullet's and ODE's box–box
/// tests by 5 %. The face's manifold is then at most `0.1 / 0.9 ≈ 11 %` deeper than the
/// minimal penetration (see `props::manifold_properties`). Shapes that are apart (or
/// touching) keep the exact choice.
pub const EDGE_DEPTH_PREFERENCE: f32 = 0.1;

/// The guard of a clipped manifold, in units of the axis tolerance.
const GUARD_FACTOR: f32 = 2.0;

/// The axis a pair's last separating axis test ended on, by shape-local index: a face of
/// A, a face of B or a pair of edges (box edges are numbered 0–11: edges along local
/// axis `i` are `4i + m`, `m` giving the signs of the other two coordinates; hull edges by
/// their place in the hull's edge list).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub enum SatAxis {
    /// Nothing known.
    #[default]
    Unknown,
    /// Face `index` of A.
    FaceA(u16),
    /// Face `index` of B.
    FaceB(u16),
    /// Edge `a` of A and edge `b` of B.
    Edges(u16, u16),
}

/// What one pair remembers between steps for [`super::contact_cached`]: the axis its
/// separating axis test ended on (the one that proved the shapes apart, or the contact's
/// axis). Six bytes, `Copy`; `Default` is an empty cache.
///
/// The cache only makes queries faster, never different: the remembered axis is tried
/// first and used only to answer "apart by more than the margin" when it proves that on
/// its own, computed exactly as the full test computes it; otherwise the full test runs
/// from scratch. So the same query gives bit-identical results with a fresh cache, a stale
/// one (from an earlier pose) or any garbage (indices out of range are ignored).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq, Hash)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct PairCache {
    /// The last axis.
    pub axis: SatAxis,
}

/// How a separating axis test ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(crate) enum SatOutcome {
    /// Apart by more than the margin.
    Separated,
    /// The manifold (A's frame) is in the caller's `out`.
    Contact,
    /// The test cannot build the manifold exactly (see the module docs, "Guard"): use the
    /// GJK/EPA path.
    Fallback,
}

/// B's pose in A's frame with its rotation as a matrix (columns: B's axes in A's frame).
#[derive(Clone, Copy, Debug)]
pub(crate) struct Frame {
    r: Mat3,
    t: Vec3,
}

impl Frame {
    pub(crate) fn new(b_in_a: &Iso) -> Frame {
        Frame {
            r: rotation_matrix(b_in_a.rotation),
            t: b_in_a.position,
        }
    }

    /// B-local point to A's frame.
    #[inline]
    fn point(&self, p: Vec3) -> Vec3 {
        self.r.mul_vec(p) + self.t
    }

    /// B-local direction to A's frame.
    #[inline]
    fn vector(&self, v: Vec3) -> Vec3 {
        self.r.mul_vec(v)
    }

    /// A-frame direction to B's local frame.
    #[inline]
    fn inv_vector(&self, v: Vec3) -> Vec3 {
        self.r.transpose_mul_vec(v)
    }
}

/// The rotation matrix of a unit quaternion `(x, y, z, w)` in one pass:
/// `1 − 2(y² + z²)`, `2(xy − wz)`, ... (the columns are the rotated axes).
#[inline]
pub(crate) fn rotation_matrix(q: crate::math::Quat) -> Mat3 {
    let (x, y, z, w) = (q.x, q.y, q.z, q.w);
    let (x2, y2, z2) = (x + x, y + y, z + z);
    let (xx, yy, zz) = (x * x2, y * y2, z * z2);
    let (xy, xz, yz) = (x * y2, x * z2, y * z2);
    let (wx, wy, wz) = (w * x2, w * y2, w * z2);
    Mat3::from_cols(
        Vec3::new(1.0 - (yy + zz), xy + wz, xz - wy),
        Vec3::new(xy - wz, 1.0 - (xx + zz), yz + wx),
        Vec3::new(xz + wy, yz - wx, 1.0 - (xx + yy)),
    )
}

/// An edge of a polytope (local frame): from vertex `v0` to vertex `v1`, between the face
/// with normal `n0` (which runs `v0 → v1` counter-clockwise) and the face with normal
/// `n1`, so `n1 × n0` points along `p0 − p1`.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct PolyEdge {
    /// Vertex index of `p0`.
    pub v0: u32,
    /// Vertex index of `p1`.
    pub v1: u32,
    /// Start point.
    pub p0: Vec3,
    /// End point.
    pub p1: Vec3,
    /// Normal of the face along `p0 → p1`.
    pub n0: Vec3,
    /// Normal of the face along `p1 → p0`.
    pub n1: Vec3,
}

/// What the separating axis test needs of a polytope, in its local frame.
pub(crate) trait Polytope {
    /// Number of faces.
    fn face_count(&self) -> usize;
    /// True when every edge runs along its faces' crossing line within [`EDGE_TILT_SIN`]
    /// (the condition for pruning edge pairs; see the module docs).
    fn has_well_formed_edges(&self) -> bool;
    /// The radius (m) of a ball about [`Polytope::center`] inside the polytope (0 when
    /// there is none): the bounds of the module docs' pruning.
    fn inner_radius(&self) -> f32;
    /// Face `f`'s outward unit normal and offset (`n · p = d` on the face).
    fn plane(&self, f: usize) -> (Vec3, f32);
    /// `min_v v · dir` over the vertices: `dir · support(−dir)`, bit for bit.
    fn min_dot(&self, dir: Vec3) -> f32;
    /// A vertex with the smallest `v · dir`.
    fn min_vertex(&self, dir: Vec3) -> Vec3;
    /// `out[f] = n_f · v` for every face normal `n_f` that fits in `out`: the products of
    /// [`Polytope::plane`]'s normals, bit for bit.
    #[inline]
    fn normal_dots(&self, v: Vec3, out: &mut [f32]) {
        for (f, d) in out.iter_mut().enumerate().take(self.face_count()) {
            *d = self.normal_dot(f, v);
        }
    }
    /// `n_f · v` for face `f`'s normal: one product of [`Polytope::normal_dots`], bit for
    /// bit.
    #[inline]
    fn normal_dot(&self, f: usize, v: Vec3) -> f32 {
        self.plane(f).0.dot(v)
    }
    /// `out[f] = n_f · c − d_f`, the height of `c` (in this shape's frame) over each face
    /// plane, for each face that fits in `out`.
    fn face_heights(&self, c: Vec3, out: &mut [f32]) {
        for (f, h) in out.iter_mut().enumerate().take(self.face_count()) {
            let (n, d) = self.plane(f);
            *h = n.dot(c) - d;
        }
    }
    /// Number of edges.
    fn edge_count(&self) -> usize;
    /// Edge `e`, `None` past the last.
    fn edge(&self, e: usize) -> Option<PolyEdge>;
    /// The faces of edge `e` (along `p0 → p1`, along `p1 → p0`), `None` past the last.
    fn edge_faces(&self, e: usize) -> Option<(usize, usize)>;
    /// True when edge `e` has the same end points as edge `e − 1` (and so the same
    /// vector), bit for bit: a triangle's edge `2i + 1`, the back half of edge `2i`.
    fn repeats_previous_edge(&self, _e: usize) -> bool {
        false
    }
    /// Its faces as polygons: `Face<4>` for a box, a full [`Face`] for the rest.
    type FacePolygon: Polygon;
    /// Face `f` as a polygon with feature ids.
    fn polygon(&self, f: usize) -> Self::FacePolygon;
    /// The face whose normal is most aligned with `dir`.
    fn face_along(&self, dir: Vec3) -> Self::FacePolygon;
    /// A point well inside.
    fn center(&self) -> Vec3;
    /// The largest core coordinate (m): the size that rounding scales with.
    fn extent(&self) -> f32;
    /// The largest distance of a vertex from the local origin (m), or more.
    fn radius(&self) -> f32;
    /// The shape's geometry, for the tie rule of the axis choice ([`prefers_b`]).
    fn geometry(&self) -> Geometry<'_>;
}

/// A polytope's geometry in its local frame, ordered independently of which shape of a
/// pair is A: boxes before hulls, then by half-extents or by vertex count and vertices
/// (`total_cmp`, lexicographic).
#[derive(Clone, Copy, Debug)]
pub(crate) enum Geometry<'h> {
    /// A box's half-extents.
    Cuboid(Vec3),
    /// A hull's vertices.
    Hull(&'h [Vec3]),
    /// A triangle's vertices.
    Triangle(&'h [Vec3; 3]),
}

impl Geometry<'_> {
    fn order(&self, other: &Geometry) -> core::cmp::Ordering {
        use core::cmp::Ordering;
        let vec = |u: &Vec3, v: &Vec3| {
            u.x.total_cmp(&v.x)
                .then(u.y.total_cmp(&v.y))
                .then(u.z.total_cmp(&v.z))
        };
        let points = |p: &[Vec3], q: &[Vec3]| {
            let mut o = p.len().cmp(&q.len());
            for (u, v) in p.iter().zip(q.iter()) {
                if o != Ordering::Equal {
                    break;
                }
                o = vec(u, v);
            }
            o
        };
        let kind = |g: &Geometry| match g {
            Geometry::Cuboid(_) => 0u8,
            Geometry::Hull(_) => 1,
            Geometry::Triangle(_) => 2,
        };
        match (self, other) {
            (Geometry::Cuboid(x), Geometry::Cuboid(y)) => vec(x, y),
            (Geometry::Hull(p), Geometry::Hull(q)) => points(p, q),
            (Geometry::Triangle(p), Geometry::Triangle(q)) => points(&p[..], &q[..]),
            _ => kind(self).cmp(&kind(other)),
        }
    }
}

/// The tie rule of the axis choice: within the tolerance, B's face `g` is preferred to
/// A's face `f` when B is the larger shape (its [`Polytope::extent`]: the ground's face
/// carries a box resting on it), for shapes of the same extent when B's geometry orders
/// after A's ([`Geometry`]), and for the same geometry when `g > f` (upright boxes: the
/// lower one's top face, +y, index 3, carries the one above, whose bottom is index 2).
/// None of it depends on which shape the caller passed first, so `contact(B, A)` picks the
/// physical face that `contact(A, B)` picked, and none of it changes as the bodies move,
/// so a resting contact keeps its reference face. The one case it cannot decide, two
/// copies of one shape touching with faces of the same index, keeps A's face (both are
/// then within the tolerance of the best depth).
fn prefers_b<A: Polytope, B: Polytope>(a: &A, f: usize, b: &B, g: usize) -> bool {
    use core::cmp::Ordering;
    let order = b
        .extent()
        .total_cmp(&a.extent())
        .then_with(|| b.geometry().order(&a.geometry()));
    match order {
        Ordering::Greater => true,
        Ordering::Less => false,
        Ordering::Equal => g > f,
    }
}

/// The unit vector along local axis `k` (0, 1, anything else → 2), times `s`.
#[inline]
fn axis_vector(k: usize, s: f32) -> Vec3 {
    match k {
        0 => Vec3::new(s, 0.0, 0.0),
        1 => Vec3::new(0.0, s, 0.0),
        _ => Vec3::new(0.0, 0.0, s),
    }
}

/// Box edge `4i + m` runs along axis `i` (from the vertex with bit `i` clear to the one
/// with it set); bit 0 of `m` is the sign of axis `u = i + 1`, bit 1 the sign of axis
/// `w = i + 2` (mod 3).
#[inline]
fn cuboid_edge_index(i: usize, positive_u: bool, positive_w: bool) -> usize {
    4 * i + positive_u as usize + 2 * positive_w as usize
}

impl Polytope for Cuboid {
    fn has_well_formed_edges(&self) -> bool {
        // Every edge runs along an axis, both its faces' normals perpendicular to it.
        true
    }

    fn inner_radius(&self) -> f32 {
        // The centre is the origin; the nearest faces are at the smallest half-extent.
        self.half_extents.min_elem()
    }

    fn face_count(&self) -> usize {
        6
    }

    fn plane(&self, f: usize) -> (Vec3, f32) {
        let axis = (f / 2).min(2);
        let s = if f % 2 == 1 { 1.0 } else { -1.0 };
        (axis_vector(axis, s), self.half_extents[axis])
    }

    #[inline]
    fn min_dot(&self, dir: Vec3) -> f32 {
        dir.dot(self.core_support(-dir).0)
    }

    fn min_vertex(&self, dir: Vec3) -> Vec3 {
        self.core_support(-dir).0
    }

    fn edge_count(&self) -> usize {
        12
    }

    fn edge(&self, e: usize) -> Option<PolyEdge> {
        if e >= 12 {
            return None;
        }
        let i = e / 4;
        let (u, w) = ((i + 1) % 3, (i + 2) % 3);
        let (pu, pw) = (e & 1 != 0, e & 2 != 0);
        let v0 = ((pu as u32) << u) | ((pw as u32) << w);
        let v1 = v0 | (1 << i);
        let nu = axis_vector(u, if pu { 1.0 } else { -1.0 });
        let nw = axis_vector(w, if pw { 1.0 } else { -1.0 });
        // (±e_u) × (±e_w) = ±e_i: the face whose normal comes first in a product along
        // +e_i runs along the edge (+e_i) counter-clockwise.
        let (n0, n1) = if pu == pw { (nu, nw) } else { (nw, nu) };
        Some(PolyEdge {
            v0,
            v1,
            p0: self.core_vertex(v0),
            p1: self.core_vertex(v1),
            n0,
            n1,
        })
    }

    fn edge_faces(&self, e: usize) -> Option<(usize, usize)> {
        if e >= 12 {
            return None;
        }
        let i = e / 4;
        let (u, w) = ((i + 1) % 3, (i + 2) % 3);
        let (pu, pw) = (e & 1 != 0, e & 2 != 0);
        let fu = 2 * u + pu as usize;
        let fw = 2 * w + pw as usize;
        Some(if pu == pw { (fu, fw) } else { (fw, fu) })
    }

    type FacePolygon = Face<4>;

    fn polygon(&self, f: usize) -> Face<4> {
        self.quad((f / 2).min(2), f % 2 == 1)
    }

    fn face_along(&self, dir: Vec3) -> Face<4> {
        self.supporting_quad(dir)
    }

    fn center(&self) -> Vec3 {
        Vec3::ZERO
    }

    fn extent(&self) -> f32 {
        self.half_extents.max_elem()
    }

    fn radius(&self) -> f32 {
        self.half_extents.length()
    }
    fn geometry(&self) -> Geometry<'_> {
        Geometry::Cuboid(self.half_extents)
    }
}

impl Polytope for ConvexHull {
    fn has_well_formed_edges(&self) -> bool {
        ConvexHull::has_well_formed_edges(self)
    }

    fn inner_radius(&self) -> f32 {
        ConvexHull::inner_radius(self)
    }

    fn face_count(&self) -> usize {
        ConvexHull::face_count(self)
    }

    fn plane(&self, f: usize) -> (Vec3, f32) {
        ConvexHull::plane(self, f)
    }

    #[inline]
    fn min_dot(&self, dir: Vec3) -> f32 {
        ConvexHull::min_dot(self, dir)
    }

    fn min_vertex(&self, dir: Vec3) -> Vec3 {
        ConvexHull::core_support(self, -dir).0
    }

    #[inline]
    fn normal_dots(&self, v: Vec3, out: &mut [f32]) {
        // The normals in place: no per-face range check (see `ConvexHull::plane`).
        let normals = self.normals.get(..self.face_count()).unwrap_or(&[]);
        for (d, n) in out.iter_mut().zip(normals) {
            *d = n.dot(v);
        }
    }

    #[inline]
    fn normal_dot(&self, f: usize, v: Vec3) -> f32 {
        // As `normal_dots` reads it; a face past the last (never asked) reads 0.
        self.normals.get(f).map_or(0.0, |n| n.dot(v))
    }

    #[inline]
    fn face_heights(&self, c: Vec3, out: &mut [f32]) {
        // The planes in place, as `normal_dots` reads the normals.
        let count = self.face_count();
        let normals = self.normals.get(..count).unwrap_or(&[]);
        let offsets = self.offsets.get(..count).unwrap_or(&[]);
        for ((h, n), d) in out.iter_mut().zip(normals).zip(offsets) {
            *h = n.dot(c) - d;
        }
    }

    fn edge_count(&self) -> usize {
        ConvexHull::edge_count(self)
    }

    #[inline]
    fn edge(&self, e: usize) -> Option<PolyEdge> {
        let h = ConvexHull::edge(self, e)?;
        Some(PolyEdge {
            v0: h.v0 as u32,
            v1: h.v1 as u32,
            p0: self.core_vertex(h.v0 as u32),
            p1: self.core_vertex(h.v1 as u32),
            n0: self.plane(h.face0 as usize).0,
            n1: self.plane(h.face1 as usize).0,
        })
    }

    #[inline]
    fn edge_faces(&self, e: usize) -> Option<(usize, usize)> {
        let h = ConvexHull::edge(self, e)?;
        Some((h.face0 as usize, h.face1 as usize))
    }

    type FacePolygon = Face;

    fn polygon(&self, f: usize) -> Face {
        self.face(f)
    }

    fn face_along(&self, dir: Vec3) -> Face {
        self.supporting_face(dir)
    }

    fn center(&self) -> Vec3 {
        self.centroid()
    }

    fn extent(&self) -> f32 {
        // The build tolerance is TOLERANCE times the largest |coordinate|.
        self.tolerance() / ConvexHull::TOLERANCE
    }

    fn radius(&self) -> f32 {
        self.bounding_radius()
    }
    fn geometry(&self) -> Geometry<'_> {
        Geometry::Hull(self.vertices())
    }
}

/// A triangle as the separating axis test sees it: a flat polytope with five faces (the
/// front, index 0, and back, index 1, as [`Triangle::supporting_face`] numbers them, then
/// a side face `2 + i` through edge `i`, from vertex `i` to `i + 1`, along its outward
/// in-plane normal) and six edges.
///
/// A flat polygon's edge maps to half a great circle on the Gauss map, from the front
/// normal `n` through the edge's outward normal `m` to `−n`: its end points are opposite,
/// so the arc test of the edge pairs cannot tell it from any other half circle. Each
/// triangle edge is therefore two edges of the test, `2i` from `n` to `m` (faces front and
/// side) and `2i + 1` from `m` to `−n` (side and back), each a quarter circle, with the
/// same end points and feature ids. The side faces are true separating axes (the edge is
/// the triangle's support along `m`) but have no polygon: a side face chosen as the
/// reference makes the clipping find nothing, and the caller falls back to the general
/// path. There is no ball inside a triangle ([`Polytope::inner_radius`] is 0): its edges
/// are pruned by the other shape's ball (see `edge_below`).
#[derive(Clone, Copy, Debug)]
pub(crate) struct TrianglePolytope {
    vertices: [Vec3; 3],
    /// Front unit normal, [`Triangle::normal`].
    normal: Vec3,
    /// Outward unit normal of each edge in the triangle's plane.
    sides: [Vec3; 3],
}

impl TrianglePolytope {
    pub(crate) fn new(t: &Triangle) -> TrianglePolytope {
        let normal = t.normal();
        let v = t.vertices;
        let side = |i: usize| {
            let (p, q) = (v[i], v[(i + 1) % 3]);
            (q - p).cross(normal).normalize_or(Vec3::ZERO)
        };
        TrianglePolytope {
            vertices: v,
            normal,
            sides: [side(0), side(1), side(2)],
        }
    }

    fn triangle(&self) -> Triangle {
        Triangle {
            vertices: self.vertices,
        }
    }
}

impl Polytope for TrianglePolytope {
    fn has_well_formed_edges(&self) -> bool {
        // Each edge runs along the crossing line of its two faces: the front (or back)
        // face and a side face built perpendicular to it through the edge. With no ball
        // inside, its edges are pruned only against a shape that holds one (`query_with`).
        true
    }

    fn inner_radius(&self) -> f32 {
        0.0
    }

    fn face_count(&self) -> usize {
        5
    }

    fn plane(&self, f: usize) -> (Vec3, f32) {
        let [v0, v1, v2] = self.vertices;
        let n = match f {
            0 => self.normal,
            1 => -self.normal,
            _ => {
                let i = (f - 2).min(2);
                let m = self.sides[i];
                return (m, m.dot([v0, v1, v2][i]));
            }
        };
        (n, n.dot(v0))
    }

    #[inline]
    fn min_dot(&self, dir: Vec3) -> f32 {
        let [a, b, c] = self.vertices;
        scalar::min(scalar::min(dir.dot(a), dir.dot(b)), dir.dot(c))
    }

    fn min_vertex(&self, dir: Vec3) -> Vec3 {
        let [a, b, c] = self.vertices;
        let ab = if dir.dot(b) < dir.dot(a) { b } else { a };
        if dir.dot(c) < dir.dot(ab) {
            c
        } else {
            ab
        }
    }

    fn edge_count(&self) -> usize {
        6
    }

    fn edge(&self, e: usize) -> Option<PolyEdge> {
        if e >= 6 {
            return None;
        }
        let i = e / 2;
        let j = (i + 1) % 3;
        let m = self.sides[i];
        // Counter-clockwise about `n`: the front face runs along `v_i → v_j`, and
        // `n × m` and `m × (−n)` both point along the edge.
        let (n0, n1) = if e & 1 == 0 {
            (self.normal, m)
        } else {
            (m, -self.normal)
        };
        Some(PolyEdge {
            v0: i as u32,
            v1: j as u32,
            p0: self.vertices[i],
            p1: self.vertices[j],
            n0,
            n1,
        })
    }

    fn repeats_previous_edge(&self, e: usize) -> bool {
        e & 1 == 1
    }

    fn edge_faces(&self, e: usize) -> Option<(usize, usize)> {
        if e >= 6 {
            return None;
        }
        let side = 2 + e / 2;
        Some(if e & 1 == 0 { (0, side) } else { (side, 1) })
    }

    type FacePolygon = Face<3>;

    fn polygon(&self, f: usize) -> Face<3> {
        match f {
            0 => self.triangle().supporting_tri(self.normal),
            1 => self.triangle().supporting_tri(-self.normal),
            // A side face has no area: no polygon (the caller falls back).
            _ => Face::new(self.sides[(f.max(2) - 2).min(2)], FeatureId::face(f as u32)),
        }
    }

    fn face_along(&self, dir: Vec3) -> Face<3> {
        // The triangle itself, front or back: never a side, which has no area.
        self.triangle().supporting_tri(dir)
    }

    fn center(&self) -> Vec3 {
        let [a, b, c] = self.vertices;
        ((a + b) + c) * (1.0 / 3.0)
    }

    fn extent(&self) -> f32 {
        triangle_extent(&self.triangle())
    }

    fn radius(&self) -> f32 {
        self.triangle().bounding_radius()
    }

    fn geometry(&self) -> Geometry<'_> {
        Geometry::Triangle(&self.vertices)
    }
}

/// A triangle's largest coordinate (m), as `manifold::polytope_order` measures it.
fn triangle_extent(t: &Triangle) -> f32 {
    let [u, v, w] = t.vertices;
    u.abs().max(v.abs()).max(w.abs()).max_elem()
}

/// The best face of one shape.
#[derive(Clone, Copy, Debug)]
struct FaceBest {
    index: usize,
    separation: f32,
}

/// The best edge pair: the edges' indices, the axis (A's frame, from A towards B) and its
/// separation.
#[derive(Clone, Copy, Debug)]
struct EdgeBest {
    index_a: usize,
    index_b: usize,
    normal: Vec3,
    separation: f32,
}

/// The axis chosen for the manifold.
#[derive(Clone, Copy, Debug)]
enum Choice {
    FaceA(FaceBest),
    FaceB(FaceBest),
    Edges(EdgeBest),
}

impl Choice {
    fn axis(&self) -> SatAxis {
        match self {
            Choice::FaceA(f) => SatAxis::FaceA(f.index as u16),
            Choice::FaceB(f) => SatAxis::FaceB(f.index as u16),
            Choice::Edges(e) => SatAxis::Edges(e.index_a as u16, e.index_b as u16),
        }
    }

    fn separation(&self) -> f32 {
        match self {
            Choice::FaceA(f) | Choice::FaceB(f) => f.separation,
            Choice::Edges(e) => e.separation,
        }
    }
}

/// The axis choice with its bias (see [`SAT_TOLERANCE`]): the face that separates more by
/// more than `tol`, else the one the tie rule `prefer_b` ([`prefers_b`], called only on a
/// tie) names; an edge pair over that face only when better by more than `tol` (and, when
/// overlapping, by more than [`EDGE_DEPTH_PREFERENCE`] of the face's depth).
fn choose(
    face_a: FaceBest,
    face_b: FaceBest,
    edge: Option<EdgeBest>,
    tol: f32,
    prefer_b: impl FnOnce(usize, usize) -> bool,
) -> Choice {
    let face = if face_b.separation > face_a.separation + tol {
        Choice::FaceB(face_b)
    } else if face_a.separation > face_b.separation + tol {
        Choice::FaceA(face_a)
    } else if prefer_b(face_a.index, face_b.index) {
        Choice::FaceB(face_b)
    } else {
        // A tie, or a NaN.
        Choice::FaceA(face_a)
    };
    match edge {
        Some(e) if e.separation > face.separation() + tol + face_preference(face.separation()) => {
            Choice::Edges(e)
        }
        _ => face,
    }
}

/// The exact separation of the test: the largest of the best faces' and the best edge
/// pair's (the minimal penetration, negated, when the shapes overlap).
#[inline]
fn exact_separation(face_a: &FaceBest, face_b: &FaceBest, edge: &Option<EdgeBest>) -> f32 {
    let face = scalar::max(face_a.separation, face_b.separation);
    edge.as_ref()
        .map_or(face, |e| scalar::max(face, e.separation))
}

/// The extra margin by which an edge pair must beat a face whose separation is `s`
/// ([`EDGE_DEPTH_PREFERENCE`] of the depth when overlapping, else 0).
#[inline]
fn face_preference(s: f32) -> f32 {
    EDGE_DEPTH_PREFERENCE * scalar::max(-s, 0.0)
}

/// Separation along face `f` of A: B's support along `−n` above A's plane `n · x = d`.
#[inline]
fn face_a_separation<A: Polytope, B: Polytope>(a: &A, b: &B, fr: &Frame, f: usize) -> f32 {
    let (n, d) = a.plane(f);
    let n_b = fr.inv_vector(n);
    b.min_dot(n_b) + n.dot(fr.t) - d
}

/// Separation along face `g` of B: A's support along `−m` above B's plane, which is
/// `m · x = e + m · t` in A's frame for B's local plane `m_b · y = e` (`m = R m_b`).
#[inline]
fn face_b_separation<A: Polytope, B: Polytope>(a: &A, b: &B, fr: &Frame, g: usize) -> f32 {
    let (m_b, e) = b.plane(g);
    let m = fr.vector(m_b);
    a.min_dot(m) - m.dot(fr.t) - e
}

/// The separation along the unit axis `n` (A's frame, from A towards B) from both
/// shapes' support points: `min_B n·x − max_A n·x`, exact for any axis.
///
/// An edge pair's separation `n · (p_B − p_A)` is that value only when the two edges are
/// the supporting features along `±n`, which the Gauss-map test decides from the faces'
/// normals. A hull whose merged, slightly non-planar face meets a neighbour along an edge
/// of 0.2 mm (fuzz finding `sat_edge_of_a_merged_face`) has an edge that does not run
/// along the cross product of its faces' normals; the test then passed a pair whose edge
/// points were not the supports, and its separation read +4 mm for shapes overlapping by
/// 39 mm: "apart". Measured with the supports, a wrong pair can only read too low, never
/// end the test or win the axis choice on a separation the shapes do not have.
#[inline]
fn support_separation<A: Polytope, B: Polytope>(a: &A, b: &B, fr: &Frame, n: Vec3) -> f32 {
    b.min_dot(fr.inv_vector(n)) + n.dot(fr.t) + a.min_dot(-n)
}

/// A's edge seen from B's frame, for the Gauss-map test: its arc's normals and its vector.
#[derive(Clone, Copy, Debug)]
struct ArcA {
    edge: PolyEdge,
    /// `p1 − p0`, A's frame.
    vector: Vec3,
    n0_b: Vec3,
    n1_b: Vec3,
    vector_b: Vec3,
}

impl ArcA {
    #[inline]
    fn new(edge: PolyEdge, fr: &Frame) -> ArcA {
        let vector = edge.p1 - edge.p0;
        ArcA {
            edge,
            vector,
            n0_b: fr.inv_vector(edge.n0),
            n1_b: fr.inv_vector(edge.n1),
            vector_b: fr.inv_vector(vector),
        }
    }
}

/// Gregorius's test (module docs): A's arc `(a, b) = (n0, n1)` with `b × a ∥ −e_A`, B's
/// arc negated, `(c, d) = (−n0_B, −n1_B)` with `d × c ∥ −e_B`, all in B's frame:
/// `c·(b×a) = n0_B · e_A` and `d·(b×a) = n1_B · e_A` (given, see [`query`]),
/// `a·(d×c) = −n0_A · e_B`, `b·(d×c) = −n1_A · e_B`.
#[inline]
fn is_minkowski_face(arc: &ArcA, cba: f32, dba: f32, e_b: Vec3) -> bool {
    let straddles = cba * dba < 0.0; // false for NaN too
    if !straddles {
        return false;
    }
    let adc = -arc.n0_b.dot(e_b);
    let bdc = -arc.n1_b.dot(e_b);
    adc * bdc < 0.0 && cba * bdc > 0.0
}

/// The axis of two edges, `p1 + s e1` of A and `p2 + t e2` of B (both in A's frame, with
/// the shapes' centres `c1`, `c2`): `n = e1 × e2 / |e1 × e2|`, turned away from A (by the
/// centre with the larger lever, so a thin shape does not flip it), and the separation
/// `n · (p2 − p1)`; `None` for nearly parallel edges ([`EDGE_PARALLEL_SIN`]).
#[inline]
fn edge_axis(p1: Vec3, e1: Vec3, c1: Vec3, p2: Vec3, e2: Vec3, c2: Vec3) -> Option<(Vec3, f32)> {
    let u = e1.cross(e2);
    let uu = u.length_squared();
    let limit = EDGE_PARALLEL_SIN * EDGE_PARALLEL_SIN * e1.length_squared() * e2.length_squared();
    let crossing = uu > limit; // false for NaN too
    if !crossing {
        return None;
    }
    let (n, _) = u.normalize_and_length()?;
    let sign1 = n.dot(p1 - c1);
    let sign2 = n.dot(p2 - c2);
    let flip = if scalar::abs(sign1) > scalar::abs(sign2) {
        sign1 < 0.0
    } else {
        sign2 > 0.0
    };
    let n = if flip { -n } else { n };
    Some((n, n.dot(p2 - p1)))
}

/// The edge pair of `arc` and B's edge from `p0_b` along `e_b` (B's frame): its axis and
/// separation when it spans a face of `D`; `cba`, `dba` are B's two face normals dotted
/// with A's edge (B's frame).
#[inline]
fn edge_pair(
    arc: &ArcA,
    (p0_b, e_b): (Vec3, Vec3),
    (cba, dba): (f32, f32),
    fr: &Frame,
    centers: (Vec3, Vec3),
) -> Option<(Vec3, f32)> {
    edge_pair_placed(
        arc,
        e_b,
        (fr.point(p0_b), fr.vector(e_b)),
        (cba, dba),
        centers,
    )
}

/// [`edge_pair`] with B's edge also given in A's frame (`placed`: start and vector), as
/// [`query`] computes it once per edge: the same operations, so the same answer.
#[inline]
fn edge_pair_placed(
    arc: &ArcA,
    e_b: Vec3,
    placed: (Vec3, Vec3),
    (cba, dba): (f32, f32),
    centers: (Vec3, Vec3),
) -> Option<(Vec3, f32)> {
    if !is_minkowski_face(arc, cba, dba, e_b) {
        return None;
    }
    edge_axis(
        arc.edge.p0,
        arc.vector,
        centers.0,
        placed.0,
        placed.1,
        centers.1,
    )
}

/// One of B's edges as [`query`] uses it.
#[derive(Clone, Copy, Debug)]
struct EdgeB {
    /// Edge index in B.
    index: u8,
    /// `p1 − p0`, B's frame.
    vector: Vec3,
    /// `p0` and `p1 − p0` in A's frame.
    placed: (Vec3, Vec3),
    /// The faces on either side.
    faces: (u8, u8),
}

/// The full test: `Err(axis)` when `axis` separates the shapes by more than `margin`, else
/// the best face of each shape and the best edge pair. Work: `F_A + F_B` support values,
/// `E_A (F_B + E_B)` cheap products and look-ups, the full Gauss-map test on the pairs that
/// pass the first product only. Stack: B's edge list and the look-up tables, about 7 KiB
/// at most (sized for the largest hull; box–box never comes here).
fn query<A: Polytope, B: Polytope>(
    a: &A,
    b: &B,
    fr: &Frame,
    margin: f32,
) -> Result<(FaceBest, FaceBest, Option<EdgeBest>), SatAxis> {
    query_with(a, b, fr, margin, true)
}

/// [`query`], with the pruning of faces and edges that cannot matter (`prune`) or without
/// (every face and edge pair measured, the oracle of the pruning test). Both give the
/// same result, bit for bit, in everything the caller uses: the separating axis found,
/// the best faces, and the best edge pair whenever it separates more than the best face.
fn query_with<A: Polytope, B: Polytope>(
    a: &A,
    b: &B,
    fr: &Frame,
    margin: f32,
    prune: bool,
) -> Result<(FaceBest, FaceBest, Option<EdgeBest>), SatAxis> {
    // Bounds for pruning the face loops (see `best_face`): each shape holds the ball of
    // radius `inner_radius` about its centre, within `slack`.
    let slack = if prune {
        PRUNE_SLACK * tolerance(fr, a.extent(), b.extent())
    } else {
        // Every bound infinite (or NaN): nothing is skipped.
        f32::INFINITY
    };
    let (center_a, center_b) = (a.center(), b.center());
    let (r_a, r_b) = (a.inner_radius(), b.inner_radius());
    // Each centre in the other shape's frame, once: a bound is then one product per face.
    // (A bound only has to hold within the slack, which is far above its rounding, so it
    // need not be formed as the separation is.)
    let center_b_in_a = fr.point(center_b);
    let center_a_in_b = fr.inv_vector(center_a - fr.t);
    // The height of the other shape's centre over each face plane, `n·c − d`, once:
    // the face bounds read them, and so do the edge bounds' ends (`edge_below_by_heights`).
    // One table of 256 on the stack for everything per face: A's heights in its upper
    // half throughout; B's in its lower half until the edge loop over A, which then keeps
    // B's face products with each A edge there (`dots`). A hull's faces fit a half
    // (checked at compile time below).
    const _: () = assert!(MAX_HULL_FACES <= 128);
    let mut table = [0.0f32; 256];
    let (dots, heights_a) = table.split_at_mut(128);
    a.face_heights(center_b_in_a, heights_a);
    b.face_heights(center_a_in_b, dots);
    // Past the table (never, for the shapes here): no bound, nothing skipped.
    let height = |t: &[f32], f: usize| t.get(f).copied().unwrap_or(f32::INFINITY);
    // Each shape's heights, one per face: every polytope has at most `MAX_HULL_FACES`
    // faces, which fit a half of the table (checked above).
    let (heights_of_a, heights_of_b) = (
        heights_a.get(..a.face_count()).unwrap_or(heights_a),
        dots.get(..b.face_count()).unwrap_or(dots),
    );
    // Face f of A: `s_f = min_B n·y − d ≤ n·c_B − r_B − d` (`c_B` in A's frame).
    let face_a = best_face(
        heights_of_a,
        r_b,
        |f| face_a_separation(a, b, fr, f),
        margin,
        slack,
    )
    .map_err(|f| SatAxis::FaceA(f as u16))?;
    // Face g of B: `s_g = min_A m·x − e ≤ m·c_A − r_A − e` (in B's frame).
    let face_b = best_face(
        heights_of_b,
        r_a,
        |g| face_b_separation(a, b, fr, g),
        margin,
        slack,
    )
    .map_err(|g| SatAxis::FaceB(g as u16))?;
    let centers = (center_a, center_b_in_a);
    let mut edge: Option<EdgeBest> = None;
    // Edge pairs that cannot beat the best face are skipped a whole edge at a time (see
    // `edge_below`): only an edge pair that separates more than the best face can end
    // the test, win the axis choice or raise the exact separation.
    let best_face_separation = scalar::max(face_a.separation, face_b.separation);
    // Edges may be pruned when both shapes' edges are well formed and one of the shapes
    // holds a ball (see `edge_below`): every box or hull pair, a triangle against either.
    let well_formed = prune && a.has_well_formed_edges() && b.has_well_formed_edges();
    let either_ball = r_a > 0.0 || r_b > 0.0;
    let (prune_a, prune_b) = (well_formed && either_ball, well_formed && either_ball);
    // An edge is first judged by its faces' heights (no edge formed), and measured by
    // `edge_below` only when they cannot tell. `|w| ≤ |c| + radius` for `w` from any
    // vertex to the other centre `c`.
    let (threshold_a, threshold_b) = (
        best_face_separation + r_b - slack,
        best_face_separation + r_a - slack,
    );
    let (reach_a, reach_b) = (
        center_b_in_a.length() + a.radius(),
        center_a_in_b.length() + b.radius(),
    );
    // A second bound from a vertex of the other shape, for the edges the centres keep
    // (see `deepest_vertices`): an edge pair's separation is at most `n · (y − p)` for any
    // point `y` of B and `p` on A's edge, with no radius to subtract.
    let deepest = (prune_a || prune_b).then(|| deepest_vertices(a, b, fr, &face_a, &face_b));
    let threshold = best_face_separation - slack;
    // B's edges once: index, vector (B's frame), start and vector in A's frame, faces.
    let mut edges_b: heapless::Vec<EdgeB, MAX_HULL_EDGES> = heapless::Vec::new();
    for ib in 0..b.edge_count().min(MAX_HULL_EDGES) {
        let Some((f0, f1)) = b.edge_faces(ib) else {
            continue;
        };
        let quick = if prune_b {
            let (h0, h1) = (height(dots, f0), height(dots, f1));
            edge_below_by_heights(h0, h1, slack, reach_b, threshold_b)
        } else {
            None
        };
        if quick == Some(true) {
            continue;
        }
        let Some(e) = b.edge(ib) else {
            continue;
        };
        let vector = e.p1 - e.p0;
        // B supports along `−n`, so `−n` is on B's arc: `s ≤ m·(c_A − q) − r_A`, m on it.
        if prune_b && quick.is_none() && edge_below(&e, center_a_in_b, threshold_b) {
            continue;
        }
        // And `s ≤ m·(x − q)` for A's vertex `x`.
        if let (true, Some((_, x))) = (prune_b, deepest) {
            if edge_below(&e, x, threshold) {
                continue;
            }
        }
        // Cannot be full: at most MAX_HULL_EDGES edges.
        let _ = edges_b.push(EdgeB {
            index: ib as u8,
            vector,
            placed: (fr.point(e.p0), fr.vector(vector)),
            faces: (f0 as u8, f1 as u8),
        });
    }
    // B's face normals dotted with the current A edge (B's frame): the first triple
    // product of every B edge is a look-up, and most pairs stop there. The pairs that
    // pass it are collected without a branch (which one passes is data), then tested.
    // B's heights are no longer needed: `dots` holds these products from here on.
    let faces_b = b.face_count().min(MAX_HULL_FACES);
    let mut passing = [0u8; 256];
    let mut pairs_b = [(0u8, 0u8); MAX_HULL_EDGES];
    for (slot, e) in pairs_b.iter_mut().zip(edges_b.iter()) {
        *slot = e.faces;
    }
    let pairs_b = pairs_b.get(..edges_b.len()).unwrap_or(&[]);
    // With every B edge pruned no pair is left to measure.
    if pairs_b.is_empty() {
        return Ok((face_a, face_b, edge));
    }
    // Few B edges left (two faces each, fewer than B has): only their faces' products
    // are formed; the pairs read no other.
    let sparse = 2 * pairs_b.len() < faces_b;
    // The A edge whose products `dots` and passing pairs `passing[..count]` are: an edge
    // with the same vector (a triangle's two halves of one edge) reads them as they are.
    let mut dots_of: Option<usize> = None;
    let mut count = 0usize;
    for ia in 0..a.edge_count() {
        let quick = match a.edge_faces(ia) {
            Some((f0, f1)) if prune_a => {
                let (h0, h1) = (height(heights_a, f0), height(heights_a, f1));
                edge_below_by_heights(h0, h1, slack, reach_a, threshold_a)
            }
            _ => None,
        };
        if quick == Some(true) {
            continue;
        }
        let Some(ea) = a.edge(ia) else { continue };
        // A supports along `n`, so `n` is on A's arc: `s ≤ n·(c_B − p) − r_B`.
        if prune_a && quick.is_none() && edge_below(&ea, centers.1, threshold_a) {
            continue;
        }
        // And `s ≤ n·(y − p)` for B's vertex `y`.
        if let (true, Some((y, _))) = (prune_a, deepest) {
            if edge_below(&ea, y, threshold) {
                continue;
            }
        }
        let arc = ArcA::new(ea, fr);
        let twin = a.repeats_previous_edge(ia) && dots_of.is_some_and(|d| d + 1 == ia);
        if !twin {
            if sparse {
                for &(f0, f1) in pairs_b {
                    for f in [f0 as usize, f1 as usize] {
                        if let Some(d) = dots.get_mut(f) {
                            *d = b.normal_dot(f, arc.vector_b);
                        }
                    }
                }
            } else {
                b.normal_dots(arc.vector_b, dots.get_mut(..faces_b).unwrap_or(&mut []));
            }
            count = 0;
            for (k, &(f0, f1)) in pairs_b.iter().enumerate() {
                let cba = dots.get(f0 as usize).copied().unwrap_or(0.0);
                let dba = dots.get(f1 as usize).copied().unwrap_or(0.0);
                let straddles = cba * dba < 0.0; // false for NaN too
                if let Some(slot) = passing.get_mut(count & 0xff) {
                    *slot = k as u8;
                }
                count += straddles as usize;
            }
        }
        dots_of = Some(ia);
        for &k in passing.iter().take(count) {
            let Some(eb) = edges_b.get(k as usize) else {
                continue;
            };
            let ib = eb.index as usize;
            let cba = dots.get(eb.faces.0 as usize).copied().unwrap_or(0.0);
            let dba = dots.get(eb.faces.1 as usize).copied().unwrap_or(0.0);
            let pair = edge_pair_placed(&arc, eb.vector, eb.placed, (cba, dba), centers);
            let Some((normal, s_edges)) = pair else {
                continue;
            };
            // Only a pair that would end the test or become the best one is measured
            // again, with the support points (see `support_separation`).
            let decisive = s_edges > margin || edge.is_none_or(|e| s_edges > e.separation);
            if !decisive {
                continue;
            }
            let s = support_separation(a, b, fr, normal);
            if s > margin {
                return Err(SatAxis::Edges(ia as u16, ib as u16));
            }
            if edge.is_none_or(|e| s > e.separation) {
                edge = Some(EdgeBest {
                    index_a: ia,
                    index_b: ib,
                    normal,
                    separation: s,
                });
            }
        }
    }
    Ok((face_a, face_b, edge))
}

/// A vertex of each shape deep in the other, for the edges' second bound: B's vertex
/// lowest along A's best face normal (in A's frame) and A's vertex lowest along B's best
/// face normal (in B's frame).
///
/// Any point `y` of B and any point `p` of A bound the separation along every axis `n`:
/// `min_B n·x ≤ n·y` and `max_A n·x ≥ n·p`, so `s(n) ≤ n·(y − p)`. For the axis of an edge
/// pair, `n` lies on the A edge's arc and `p` may be its start, so [`edge_below`] with
/// `y` in place of B's centre (and no radius) bounds every pair of that edge; the same
/// from B's side with `−n` on the B edge's arc and A's vertex. The centres' bound holds
/// for a ball that fits inside, which for a flat hull or one seen edge-on is far from its
/// surface; these vertices lie where the shapes meet, so edges away from the contact
/// fall below the best face by about their distance from it (`hulls`: of the edges the
/// centres keep, two fifths go on either side, and the edge pairs tested drop by 60 %).
/// Like every bound here it only skips work: the answer is the full test's.
fn deepest_vertices<A: Polytope, B: Polytope>(
    a: &A,
    b: &B,
    fr: &Frame,
    face_a: &FaceBest,
    face_b: &FaceBest,
) -> (Vec3, Vec3) {
    let n_a = a.plane(face_a.index).0;
    let y = fr.point(b.min_vertex(fr.inv_vector(n_a)));
    let m_b = b.plane(face_b.index).0;
    let x = fr.inv_vector(a.min_vertex(fr.vector(m_b)) - fr.t);
    (y, x)
}

/// Pruning slack, in units of the axis-choice tolerance ([`tolerance`]): how much an upper
/// bound of [`best_face`] may be too low through rounding, or through a hull's vertices
/// lying up to its build tolerance inside its face planes (which shrinks the ball the
/// bound assumes). Rounding is about `10⁻⁶` of the same scale, a hull's tolerance `10⁻⁵`.
const PRUNE_SLACK: f32 = 10.0;

/// The best (largest) of the face separations `separation(f)`, one face per entry of
/// `heights`, ties to the lowest index, or `Err(f)` for the first face in index order that
/// separates by more than `margin`: what a loop over every face in order returns, bit for
/// bit, while skipping faces that cannot matter.
///
/// `heights[f] − radius` is an upper bound of `separation(f)` within `slack`: the other
/// shape lies on the far side of a ball of `radius` about its centre, whose height over
/// face `f` is `heights[f]`, so its support along a face normal is at most the centre's
/// minus the ball's radius. The face with the largest bound is measured first, so the
/// best separation is usually known at once; a face whose bound is below the best so far,
/// or (when looking for a separating face) at most the margin, is never measured. Work:
/// one subtraction and one addition per face and typically a quarter of the support
/// queries.
#[inline]
fn best_face(
    heights: &[f32],
    radius: f32,
    separation: impl Fn(usize) -> f32,
    margin: f32,
    slack: f32,
) -> Result<FaceBest, usize> {
    // The bounds are computed again where needed rather than kept in a table: a table
    // sized for the largest hull would add half a kibibyte to the stack of every contact.
    // Each is one subtraction and one addition from the face's height, read in place.
    let bound_of = |h: f32| (h - radius) + slack;
    let mut first = 0usize;
    let mut first_bound = f32::NEG_INFINITY;
    for (f, &h) in heights.iter().enumerate() {
        let u = bound_of(h);
        if u > first_bound {
            (first, first_bound) = (f, u);
        }
    }
    let mut best = FaceBest {
        index: 0,
        separation: f32::NEG_INFINITY,
    };
    let s_first = if heights.is_empty() {
        f32::NEG_INFINITY
    } else {
        separation(first)
    };
    if s_first > margin {
        // Separated: the first face in order that shows it (`first` at the latest).
        for (f, &h) in heights.iter().enumerate().take(first) {
            if bound_of(h) > margin && separation(f) > margin {
                return Err(f);
            }
        }
        return Err(first);
    }
    if s_first > best.separation {
        best = FaceBest {
            index: first,
            separation: s_first,
        };
    }
    for (f, &h) in heights.iter().enumerate() {
        // A NaN bound compares false: the face is measured.
        if f == first || bound_of(h) < best.separation {
            continue;
        }
        let s = separation(f);
        if s > margin {
            return Err(f);
        }
        if s > best.separation || (s == best.separation && f < best.index) {
            best = FaceBest {
                index: f,
                separation: s,
            };
        }
    }
    Ok(best)
}

/// How far (rad) an edge pair's axis can lie outside the arc of a well-formed edge
/// (tilted at most [`EDGE_TILT_SIN`] from its faces' crossing line): the tilt is turned
/// into an angle on the Gauss map by at most `1 / EDGE_PARALLEL_SIN` (the pair's edges are
/// at least that far from parallel), doubled for rounding.
const ARC_WIDENING: f32 = 2.0 * EDGE_TILT_SIN / EDGE_PARALLEL_SIN;

/// [`edge_below`] decided from the heights `h0`, `h1` of the other shape's centre over
/// the edge's two face planes, when they suffice: `Some(false)` when an end reaches
/// `threshold` (the edge is kept: keeping an edge is always right), `Some(true)` when
/// both faces turn away from the centre by more than `slack` and the far-side bound,
/// with `reach ≥ |w|`, is below `threshold`; `None` to measure the edge itself.
///
/// A height is the edge's own product `n0 · w` (`w` from the edge's start to the centre)
/// but for the start's distance from the face plane (at most the hull's build
/// tolerance) and rounding, both well inside `slack`, which also keeps the far-side
/// bound's premise (both products negative) true of the products themselves.
#[inline(always)]
fn edge_below_by_heights(h0: f32, h1: f32, slack: f32, reach: f32, threshold: f32) -> Option<bool> {
    let ends = scalar::max(h0, h1);
    if ends >= threshold {
        return Some(false);
    }
    let away = h0 <= -slack && h1 <= -slack;
    if away && ends + ARC_WIDENING * reach < threshold {
        return Some(true);
    }
    None
}

/// True when no edge pair with this edge can separate the shapes by `threshold` or more:
/// `max n · w < threshold` over the unit vectors `n` on the edge's arc of the Gauss map
/// (the short great-circle arc from `n0` to `n1`), widened by [`ARC_WIDENING`], with `w`
/// the vector from the edge's start to the other shape's centre. That maximum bounds
/// `n · (c − p)` for the axis `n` of any edge pair this edge is part of (the edge supports
/// its shape along `n`, so `n · p` is the same at both ends); with the other shape holding
/// the ball of radius `r` about `c`, the pair's separation is at most that less `r`, so
/// the caller passes `threshold = best face separation + r − slack`.
///
/// Edge pairs are only pruned when both shapes' edges are well formed, since the
/// Gauss-map test then puts the axis on both arcs (within the widening), and only when
/// one of the shapes holds a ball (inner radius `r > 0`), either one: along the true axis
/// `X` (on both arcs) each shape's lever `±X · (p − c)` is at least 0, and the one with
/// the ball's at least `r`, so the larger lever, which the centre rule of [`edge_axis`]
/// signs the axis by, is at least `r` and signs it `X`, never the antipode. Then the
/// axis lies on the arc of each edge of the pair, a triangle's included. A shape's edges
/// are bounded from the other shape's centre, which that shape only has to contain (`r`
/// may be 0 there: a triangle's centroid).
#[inline(always)]
fn edge_below(e: &PolyEdge, c: Vec3, threshold: f32) -> bool {
    let w = c - e.p0;
    let (dot0, dot1) = (e.n0.dot(w), e.n1.dot(w));
    let ends = scalar::max(dot0, dot1);
    // The ends are on the arc: the maximum is at least theirs. The usual case for an edge
    // on the near side, decided without a square root.
    if ends >= threshold {
        return false;
    }
    let w_len = w.length();
    // Both ends turned away from `w`: any `n = (α n0 + β n1) / |α n0 + β n1|` on the arc
    // (α, β ≥ 0, the length at most α + β) gives `n · w ≤ (α dot0 + β dot1) / (α + β)`,
    // at most the larger end. The usual case for an edge on the far side.
    if dot0 <= 0.0 && dot1 <= 0.0 {
        return ends + ARC_WIDENING * w_len < threshold;
    }
    let k = e.n0.cross(e.n1);
    let kk = k.length_squared();
    // Nearly equal or opposite normals: no arc to speak of, bound by |w|.
    if kk.is_nan() || kk <= 1.0e-8 {
        return w_len + ARC_WIDENING * w_len < threshold;
    }
    // `w` projected on the arc's plane; the arc holds its direction when it lies between
    // `n0` and `n1` (turning about `k`).
    let wp = w - k * (w.dot(k) / kk);
    let inside = e.n0.cross(wp).dot(k) >= 0.0 && wp.cross(e.n1).dot(k) >= 0.0;
    let on_arc = if inside { wp.length() } else { ends };
    on_arc + ARC_WIDENING * w_len < threshold
}

/// True when the cached axis, computed exactly as [`query`] computes it, separates the
/// shapes by more than `margin`. Indices out of range prove nothing.
fn cached_separates<A: Polytope, B: Polytope>(
    a: &A,
    b: &B,
    fr: &Frame,
    margin: f32,
    axis: SatAxis,
) -> bool {
    match axis {
        SatAxis::Unknown => false,
        SatAxis::FaceA(f) => {
            (f as usize) < a.face_count() && face_a_separation(a, b, fr, f as usize) > margin
        }
        SatAxis::FaceB(g) => {
            (g as usize) < b.face_count() && face_b_separation(a, b, fr, g as usize) > margin
        }
        SatAxis::Edges(ia, ib) => {
            let (Some(ea), Some(eb)) = (a.edge(ia as usize), b.edge(ib as usize)) else {
                return false;
            };
            let centers = (a.center(), fr.point(b.center()));
            let arc = ArcA::new(ea, fr);
            // The same products as `query`'s look-up table: B's face normals (the
            // edge's `n0`, `n1` are those normals) dotted with A's edge.
            let dots = (eb.n0.dot(arc.vector_b), eb.n1.dot(arc.vector_b));
            let edge_b = (eb.p0, eb.p1 - eb.p0);
            edge_pair(&arc, edge_b, dots, fr, centers)
                .is_some_and(|(n, s)| s > margin && support_separation(a, b, fr, n) > margin)
        }
    }
}

/// The tolerance of the axis choice for a pair (see [`SAT_TOLERANCE`]).
#[inline]
fn tolerance(fr: &Frame, extent_a: f32, extent_b: f32) -> f32 {
    // `|t|`, not a component of `t`: the length is the same in either shape's frame (up
    // to rounding), so both argument orders use the same tolerance.
    SAT_TOLERANCE * (fr.t.length() + extent_a + extent_b)
}

/// Two polytopes (B at `b_in_a`): the separating axis test with the cached axis first,
/// then the manifold of the chosen axis. The cache is updated with the axis the test
/// ended on. Out of line: each pair of shape types is its own function, whose tables
/// (about 7 KiB for hulls) take stack only while it runs; inlined, every instance's
/// tables sat in the manifold dispatcher's frame (9.6 KiB on a Cortex-M4F) under every
/// pair, a box pair too.
#[inline(never)]
pub(crate) fn polytopes<A: Polytope, B: Polytope>(
    a: &A,
    b: &B,
    b_in_a: &Iso,
    margin: f32,
    cache: &mut PairCache,
    out: &mut LocalManifold,
) -> SatOutcome {
    let fr = Frame::new(b_in_a);
    if cached_separates(a, b, &fr, margin, cache.axis) {
        return SatOutcome::Separated;
    }
    let (face_a, face_b, edge) = match query(a, b, &fr, margin) {
        Ok(found) => found,
        Err(axis) => {
            cache.axis = axis;
            return SatOutcome::Separated;
        }
    };
    let tol = tolerance(&fr, a.extent(), b.extent());
    let exact = exact_separation(&face_a, &face_b, &edge);
    let choice = choose(face_a, face_b, edge, tol, |f, g| prefers_b(a, f, b, g));
    cache.axis = choice.axis();
    build(a, b, &fr, &choice, exact, margin, tol, out)
}

/// The manifold of the chosen axis, into `out`.
#[allow(clippy::too_many_arguments)]
fn build<A: Polytope, B: Polytope>(
    a: &A,
    b: &B,
    fr: &Frame,
    choice: &Choice,
    exact: f32,
    margin: f32,
    tol: f32,
    out: &mut LocalManifold,
) -> SatOutcome {
    if !choice.separation().is_finite() {
        return SatOutcome::Fallback;
    }
    match choice {
        Choice::FaceA(f) => {
            let reference = a.polygon(f.index);
            let mut incident = b.face_along(fr.inv_vector(-reference.normal()));
            incident.transform_by(&fr.r, fr.t);
            guarded(
                &reference,
                &incident,
                true,
                f.separation,
                exact,
                margin,
                tol,
                out,
            )
        }
        Choice::FaceB(f) => {
            let mut reference = b.polygon(f.index);
            reference.transform_by(&fr.r, fr.t);
            let incident = a.face_along(-reference.normal());
            guarded(
                &reference,
                &incident,
                false,
                f.separation,
                exact,
                margin,
                tol,
                out,
            )
        }
        Choice::Edges(e) => match (a.edge(e.index_a), b.edge(e.index_b)) {
            (Some(ea), Some(eb)) => edge_contact(&ea, &eb, e, fr, margin, out),
            _ => SatOutcome::Fallback,
        },
    }
}

/// The clipped face manifold, or [`SatOutcome::Fallback`] when it is empty, or when the
/// shapes are apart along the axis and its deepest point is shallower than the axis's
/// separation by more than the guard, or when they overlap and its deepest point is
/// shallower than the test's `exact` separation (the minimal penetration) by more than
/// the guard. Overlapping shapes are not held to the chosen face's own depth: where a face
/// was preferred to a slightly shallower edge pair ([`EDGE_DEPTH_PREFERENCE`]), the
/// incident shape's deepest corner along the face normal lies beside the reference face,
/// outside its side planes, and the clipped points can be as shallow as the shapes really
/// overlap (the edge pair's depth) but no shallower: a manifold is never shallower than
/// the minimal penetration, and at most the preference deeper.
#[allow(clippy::too_many_arguments)]
fn guarded(
    reference: &impl Polygon,
    incident: &impl Polygon,
    reference_is_a: bool,
    separation: f32,
    exact: f32,
    margin: f32,
    tol: f32,
    out: &mut LocalManifold,
) -> SatOutcome {
    let found = clipped_face_manifold(reference, incident, reference_is_a, margin, out);
    let deepest = out.min_separation();
    let shows = if separation < 0.0 {
        // At least as deep as the minimal penetration (the face's own depth, or the
        // slightly shallower edge pair's it was preferred to).
        deepest <= exact + GUARD_FACTOR * tol
    } else {
        deepest <= separation + GUARD_FACTOR * tol
    };
    if found && shows {
        SatOutcome::Contact
    } else {
        SatOutcome::Fallback
    }
}

/// The closest points `(s, t)` of segments `p1 + s d1` and `p2 + t d2` that are not
/// parallel (an edge pair of the test): the lines' closest points (Ericson 5.1.9, one
/// division) when both lie inside the segments, else [`segment_closest_points`].
#[inline]
fn edge_closest_points(p1: Vec3, d1: Vec3, p2: Vec3, d2: Vec3) -> (f32, f32) {
    let r = p1 - p2;
    let (a, e, b) = (d1.length_squared(), d2.length_squared(), d1.dot(d2));
    let (c, f) = (d1.dot(r), d2.dot(r));
    let denom = a * e - b * b;
    if denom > 0.0 {
        let inv = 1.0 / denom;
        let s = (b * f - c * e) * inv;
        let t = (a * f - b * c) * inv;
        if (0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t) {
            return (s, t);
        }
    }
    segment_closest_points(p1, p1 + d1, p2, p2 + d2)
}

/// One point at the closest points of the two edges (A's edge in A's frame, B's in B's),
/// ids (edge of A, edge of B), into `out`. Shapes that are apart need both closest points
/// strictly inside their segments (else a vertex is closer than the axis says):
/// [`SatOutcome::Fallback`].
fn edge_contact(
    ea: &PolyEdge,
    eb: &PolyEdge,
    e: &EdgeBest,
    fr: &Frame,
    margin: f32,
    out: &mut LocalManifold,
) -> SatOutcome {
    let (pa0, da) = (ea.p0, ea.p1 - ea.p0);
    let (pb0, db) = (fr.point(eb.p0), fr.vector(eb.p1 - eb.p0));
    let (s, t) = edge_closest_points(pa0, da, pb0, db);
    let inside = s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0;
    if e.separation > 0.0 && !inside {
        return SatOutcome::Fallback;
    }
    let id = ContactId {
        a: FeatureId::edge(ea.v0, ea.v1),
        b: FeatureId::edge(eb.v0, eb.v1),
    };
    out.reset(e.normal);
    out.push_within(
        Candidate::new(pa0 + da * s, pb0 + db * t, e.normal, id),
        margin,
    );
    if out.len > 0 {
        SatOutcome::Contact
    } else {
        SatOutcome::Fallback
    }
}

// ---------------------------------------------------------------------------------------
// Box against box: the 15 axes in closed form.
// ---------------------------------------------------------------------------------------

/// Two boxes in A's frame: `r` B's rotation (`R_ij = e_i · b_j`, `m[i][j]`), `abs` its
/// absolute values, `t` B's centre and `tb = Rᵀ t` the same in B's axes; every index
/// below is a compile-time constant or checked.
struct BoxPair {
    ha: [f32; 3],
    hb: [f32; 3],
    r: Mat3,
    m: [[f32; 3]; 3],
    abs: [[f32; 3]; 3],
    t: [f32; 3],
    tb: [f32; 3],
}

/// Entry `(i, j)` of a 3×3 table, 0 out of range (never, for the indices used).
#[inline(always)]
fn entry(table: &[[f32; 3]; 3], i: usize, j: usize) -> f32 {
    table
        .get(i)
        .and_then(|row| row.get(j))
        .copied()
        .unwrap_or(0.0)
}

/// Entry `i` of a triple, 0 out of range.
#[inline(always)]
fn elem(v: &[f32; 3], i: usize) -> f32 {
    v.get(i).copied().unwrap_or(0.0)
}

impl BoxPair {
    fn new(a: &Cuboid, b: &Cuboid, fr: &Frame) -> BoxPair {
        let (x, y, z) = (fr.r.x, fr.r.y, fr.r.z);
        let m = [[x.x, y.x, z.x], [x.y, y.y, z.y], [x.z, y.z, z.z]];
        let abs = |v: Vec3| [scalar::abs(v.x), scalar::abs(v.y), scalar::abs(v.z)];
        let (ax, ay, az) = (abs(x), abs(y), abs(z));
        let tb = fr.inv_vector(fr.t);
        BoxPair {
            ha: a.half_extents.to_array(),
            hb: b.half_extents.to_array(),
            r: fr.r,
            m,
            abs: [
                [ax[0], ay[0], az[0]],
                [ax[1], ay[1], az[1]],
                [ax[2], ay[2], az[2]],
            ],
            t: fr.t.to_array(),
            tb: tb.to_array(),
        }
    }

    /// Face axis `i` of A: `|t_i| − ha_i − Σ_j |R_ij| hb_j`, and the face towards B
    /// (`2i` for the negative side, also on a tie).
    #[inline]
    fn face_a(&self, i: usize) -> (f32, usize) {
        let rb = entry(&self.abs, i, 0) * self.hb[0]
            + entry(&self.abs, i, 1) * self.hb[1]
            + entry(&self.abs, i, 2) * self.hb[2];
        let ti = elem(&self.t, i);
        (
            scalar::abs(ti) - elem(&self.ha, i) - rb,
            2 * i + (ti > 0.0) as usize,
        )
    }

    /// Face axis `j` of B: `|(Rᵀ t)_j| − hb_j − Σ_i |R_ij| ha_i`, and B's face towards A.
    #[inline]
    fn face_b(&self, j: usize) -> (f32, usize) {
        let ra = entry(&self.abs, 0, j) * self.ha[0]
            + entry(&self.abs, 1, j) * self.ha[1]
            + entry(&self.abs, 2, j) * self.ha[2];
        let tj = elem(&self.tb, j);
        (
            scalar::abs(tj) - elem(&self.hb, j) - ra,
            2 * j + (tj < 0.0) as usize,
        )
    }

    /// Edge axis `(I, J)`, `L = b_J × e_I`: the separation
    /// `(|t·L| − Σ_k ha_k |L_k| − Σ_k hb_k |b_k·L|) / |L|` and `(t·L, |L|)`; `None` for
    /// nearly parallel edges. With `(I, u, w)` and `(J, v, x)` cyclic and `b_J` the column
    /// `R_·J`: `L = R_wJ e_u − R_uJ e_w`, `t·L = t_u R_wJ − t_w R_uJ`,
    /// `Σ ha_k |L_k| = ha_u |R_wJ| + ha_w |R_uJ|`, and `b_k · L = e_I · (b_k × b_J)`, which
    /// is `−R_Ix` for `k = v` and `R_Iv` for `k = x`:
    /// `Σ hb_k |b_k·L| = hb_v |R_Ix| + hb_x |R_Iv|` (the 15-axis box test; Gottschalk et
    /// al. 1996, Ericson 4.4.1).
    #[inline(always)]
    fn edge<const I: usize, const J: usize>(&self) -> Option<(f32, f32, f32)> {
        let (u, w) = ((I + 1) % 3, (I + 2) % 3);
        let (v, x) = ((J + 1) % 3, (J + 2) % 3);
        let (r_uj, r_wj) = (entry(&self.m, u, J), entry(&self.m, w, J));
        let ll = r_uj * r_uj + r_wj * r_wj;
        let crossing = ll > EDGE_PARALLEL_SIN * EDGE_PARALLEL_SIN; // false for NaN too
        if !crossing {
            return None;
        }
        let ra =
            elem(&self.ha, u) * entry(&self.abs, w, J) + elem(&self.ha, w) * entry(&self.abs, u, J);
        let rb =
            elem(&self.hb, v) * entry(&self.abs, I, x) + elem(&self.hb, x) * entry(&self.abs, I, v);
        let tl = elem(&self.t, u) * r_wj - elem(&self.t, w) * r_uj;
        let len = scalar::sqrt(ll);
        Some(((scalar::abs(tl) - ra - rb) / len, tl, len))
    }

    /// [`BoxPair::edge`] for indices known at run time (the cached axis).
    fn edge_at(&self, i: usize, j: usize) -> Option<(f32, f32, f32)> {
        match (i, j) {
            (0, 0) => self.edge::<0, 0>(),
            (0, 1) => self.edge::<0, 1>(),
            (0, 2) => self.edge::<0, 2>(),
            (1, 0) => self.edge::<1, 0>(),
            (1, 1) => self.edge::<1, 1>(),
            (1, 2) => self.edge::<1, 2>(),
            (2, 0) => self.edge::<2, 0>(),
            (2, 1) => self.edge::<2, 1>(),
            (2, 2) => self.edge::<2, 2>(),
            _ => None,
        }
    }

    /// The unit axis of edge pair `(i, j)` towards B, from [`BoxPair::edge`]'s `t·L` and
    /// `|L|`.
    fn edge_normal(&self, i: usize, j: usize, tl: f32, len: f32) -> Vec3 {
        let r_uj = entry(&self.m, (i + 1) % 3, j);
        let r_wj = entry(&self.m, (i + 2) % 3, j);
        let k = scalar::sign(tl) / len;
        let (a, b) = (r_wj * k, -r_uj * k);
        match i {
            0 => Vec3::new(0.0, a, b),
            1 => Vec3::new(b, 0.0, a),
            _ => Vec3::new(a, b, 0.0),
        }
    }
}

/// The supporting edge of box `c` along `dir` (local frame) among its edges along axis
/// `i`: the other two coordinates take the signs of `dir` (`>= 0` positive, as
/// [`Cuboid::core_support`]). Only the end points and vertex ids are filled (the face
/// normals are not needed for a contact point).
fn box_edge_along(c: &Cuboid, i: usize, dir: Vec3) -> (usize, Option<PolyEdge>) {
    let h = c.half_extents;
    let (pu, pw) = match i {
        0 => (dir.y >= 0.0, dir.z >= 0.0),
        1 => (dir.z >= 0.0, dir.x >= 0.0),
        _ => (dir.x >= 0.0, dir.y >= 0.0),
    };
    let sign = |p: bool, x: f32| if p { x } else { -x };
    // The end point with coordinate i negative, and the edge vector +2 h_i e_i.
    let (p0, along, bits) = match i {
        0 => (
            Vec3::new(-h.x, sign(pu, h.y), sign(pw, h.z)),
            Vec3::new(h.x, 0.0, 0.0),
            ((pu as u32) << 1) | ((pw as u32) << 2),
        ),
        1 => (
            Vec3::new(sign(pw, h.x), -h.y, sign(pu, h.z)),
            Vec3::new(0.0, h.y, 0.0),
            ((pu as u32) << 2) | (pw as u32),
        ),
        _ => (
            Vec3::new(sign(pu, h.x), sign(pw, h.y), -h.z),
            Vec3::new(0.0, 0.0, h.z),
            (pu as u32) | ((pw as u32) << 1),
        ),
    };
    let i = i.min(2);
    let edge = PolyEdge {
        v0: bits,
        v1: bits | (1 << i),
        p0,
        p1: p0 + along + along,
        n0: Vec3::ZERO,
        n1: Vec3::ZERO,
    };
    (cuboid_edge_index(i, pu, pw), Some(edge))
}

/// Box against box: [`polytopes`] with the closed-form axes. Out of line, as
/// [`polytopes`]: its clip buffers take stack only under box pairs.
#[inline(never)]
pub(crate) fn cuboids(
    a: &Cuboid,
    b: &Cuboid,
    b_in_a: &Iso,
    margin: f32,
    cache: &mut PairCache,
    out: &mut LocalManifold,
) -> SatOutcome {
    let fr = Frame::new(b_in_a);
    let p = BoxPair::new(a, b, &fr);
    let separates = match cache.axis {
        SatAxis::Unknown => false,
        SatAxis::FaceA(f) => f < 6 && p.face_a(f as usize / 2).0 > margin,
        SatAxis::FaceB(g) => g < 6 && p.face_b(g as usize / 2).0 > margin,
        SatAxis::Edges(ea, eb) => {
            ea < 12 && eb < 12 && {
                let pair = p.edge_at(ea as usize / 4, eb as usize / 4);
                pair.is_some_and(|(s, _, _)| s > margin)
            }
        }
    };
    if separates {
        return SatOutcome::Separated;
    }
    let (face_a, face_b, edge) = match box_query(a, b, &p, margin) {
        Ok(found) => found,
        Err(axis) => {
            cache.axis = axis;
            return SatOutcome::Separated;
        }
    };
    let tol = tolerance(&fr, a.extent(), b.extent());
    let exact = exact_separation(&face_a, &face_b, &edge);
    let choice = choose(face_a, face_b, edge, tol, |f, g| prefers_b(a, f, b, g));
    cache.axis = choice.axis();
    build(a, b, &fr, &choice, exact, margin, tol, out)
}

/// The box test's 15 axes in the order of [`query`] (A's faces, B's faces, edge pairs),
/// with the same early exit.
fn box_query(
    a: &Cuboid,
    b: &Cuboid,
    p: &BoxPair,
    margin: f32,
) -> Result<(FaceBest, FaceBest, Option<EdgeBest>), SatAxis> {
    let mut face_a = FaceBest {
        index: 0,
        separation: f32::NEG_INFINITY,
    };
    for i in 0..3 {
        let (s, f) = p.face_a(i);
        if s > margin {
            return Err(SatAxis::FaceA(f as u16));
        }
        if s > face_a.separation {
            face_a = FaceBest {
                index: f,
                separation: s,
            };
        }
    }
    let mut face_b = FaceBest {
        index: 0,
        separation: f32::NEG_INFINITY,
    };
    for j in 0..3 {
        let (s, g) = p.face_b(j);
        if s > margin {
            return Err(SatAxis::FaceB(g as u16));
        }
        if s > face_b.separation {
            face_b = FaceBest {
                index: g,
                separation: s,
            };
        }
    }
    // (i, j, separation, t·L, |L|) of the best pair, pairs in order (0, 0), (0, 1), ...
    let mut best = (0usize, 0usize, f32::NEG_INFINITY, 0.0f32, 1.0f32);
    macro_rules! pair {
        ($i:literal, $j:literal) => {
            if let Some((s, tl, len)) = p.edge::<$i, $j>() {
                if s > margin {
                    let n = p.edge_normal($i, $j, tl, len);
                    let (ea, _) = box_edge_along(a, $i, n);
                    let (eb, _) = box_edge_along(b, $j, p.r.transpose_mul_vec(-n));
                    return Err(SatAxis::Edges(ea as u16, eb as u16));
                }
                if s > best.2 {
                    best = ($i, $j, s, tl, len);
                }
            }
        };
    }
    pair!(0, 0);
    pair!(0, 1);
    pair!(0, 2);
    pair!(1, 0);
    pair!(1, 1);
    pair!(1, 2);
    pair!(2, 0);
    pair!(2, 1);
    pair!(2, 2);
    let (i, j, s, tl, len) = best;
    let edge = (s > f32::NEG_INFINITY).then(|| {
        let n = p.edge_normal(i, j, tl, len);
        let (index_a, _) = box_edge_along(a, i, n);
        let (index_b, _) = box_edge_along(b, j, p.r.transpose_mul_vec(-n));
        EdgeBest {
            index_a,
            index_b,
            normal: n,
            separation: s,
        }
    });
    Ok((face_a, face_b, edge))
}

// ---------------------------------------------------------------------------------------
// Capsule against box.
// ---------------------------------------------------------------------------------------

/// Capsule `c` (A, local frame) against box `b` at `b_in_a`, by the separating axis test on
/// the capsule's segment and the box, in the box's frame. The segment's Minkowski sum with
/// the box has face normals `e_k` (the box's faces) and `e_k × d` (`d` the segment, one
/// axis per box edge direction; its Gauss map is the great circle perpendicular to `d`,
/// which crosses every box edge direction's circle at `±(e_k × d)`), so six axes give the
/// core separation exactly when the cores overlap. The capsule's separation is that minus
/// the radius.
///
/// - A box face axis: the segment clipped against the face's side planes, up to 2 points
///   (one when the segment stands on the face: the far end is beyond the margin): the
///   capsule's surface point facing the face at each clipped segment point (end cap or
///   cylinder) and the segment point's projection on the face.
/// - An edge axis: one point from the closest points of the segment and the box edge.
///
/// With the same guard and fallback as the polytope pairs.
pub(crate) fn capsule_cuboid(
    c: &Capsule,
    b: &Cuboid,
    b_in_a: &Iso,
    margin: f32,
    out: &mut LocalManifold,
) -> SatOutcome {
    let (s0, s1) = c.segment();
    let p0 = b_in_a.inverse_transform_point(s0);
    let p1 = b_in_a.inverse_transform_point(s1);
    let d = p1 - p0;
    let h = b.half_extents;
    let r = c.radius;
    // Core separation beyond which the capsule is apart by more than the margin.
    let limit = margin + r;
    // Box faces (box frame, from the box towards the capsule), face order 0..6.
    let mut face = FaceBest {
        index: 0,
        separation: f32::NEG_INFINITY,
    };
    for k in 0..3 {
        let (lo, hi) = if p0[k] <= p1[k] {
            (p0[k], p1[k])
        } else {
            (p1[k], p0[k])
        };
        for (f, s) in [(2 * k, -h[k] - hi), (2 * k + 1, lo - h[k])] {
            if s > limit {
                return SatOutcome::Separated;
            }
            if s > face.separation {
                face = FaceBest {
                    index: f,
                    separation: s,
                };
            }
        }
    }
    // Segment × box edge directions.
    let dd = d.length_squared();
    let mut edge: Option<(usize, Vec3, f32)> = None;
    for k in 0..3 {
        let l = axis_vector(k, 1.0).cross(d);
        let ll = l.length_squared();
        let crossing = ll > EDGE_PARALLEL_SIN * EDGE_PARALLEL_SIN * dd; // false for NaN too
        if !crossing {
            continue;
        }
        let len = scalar::sqrt(ll);
        let cl = l.dot(p0);
        let s = (scalar::abs(cl) - l.abs().dot(h)) / len;
        if s > limit {
            return SatOutcome::Separated;
        }
        if edge.is_none_or(|(_, _, es)| s > es) {
            edge = Some((k, l * (scalar::sign(cl) / len), s));
        }
    }
    let tol = SAT_TOLERANCE
        * (b_in_a.position.abs().max_elem() + h.max_elem() + c.half_height + c.radius);
    if !face.separation.is_finite() {
        return SatOutcome::Fallback;
    }
    // The cores' separation by the six axes: positive means the segment is apart from the
    // box (a lower bound of their distance).
    let core_separation = edge.map_or(face.separation, |(_, _, s)| scalar::max(s, face.separation));
    // Rotation of the box frame into A's.
    let to_a = |p: Vec3| b_in_a.transform_point(p);
    let outcome = match edge {
        Some((k, n, s)) if s > face.separation + tol => {
            // The box's edge along axis k that supports n.
            let (_, Some(e)) = box_edge_along(b, k, n) else {
                return SatOutcome::Fallback;
            };
            let (ts, te) = segment_closest_points(p0, p1, e.p0, e.p1);
            let inside = ts > 0.0 && ts < 1.0 && te > 0.0 && te < 1.0;
            if s > 0.0 && !inside {
                // Apart, and a segment end or an edge end is the closest: see below.
                SatOutcome::Fallback
            } else {
                let on_segment = p0 + d * ts;
                let on_box = e.p0 + (e.p1 - e.p0) * te;
                let normal = b_in_a.transform_vector(-n);
                let id = ContactId {
                    a: feature_at(ts),
                    b: FeatureId::edge(e.v0, e.v1),
                };
                out.reset(normal);
                out.push_within(
                    Candidate::new(to_a(on_segment - n * r), to_a(on_box), normal, id),
                    margin,
                );
                if out.len > 0 {
                    SatOutcome::Contact
                } else {
                    SatOutcome::Fallback
                }
            }
        }
        _ => {
            let f = b.quad(face.index / 2, face.index % 2 == 1);
            let (mut front, mut back) = (clip::ClipPolygon::new(), clip::ClipPolygon::new());
            let mut buffers = clip::ClipBuffers::new(&mut front, &mut back);
            let clipped = buffers.segment(
                &f,
                p0,
                p1,
                [FeatureId::vertex(0), FeatureId::vertex(1)],
                FeatureId::edge(0, 1),
            );
            capsule_on_face(clipped, &f, d, r, b_in_a, margin, out);
            let guard = face.separation - r + GUARD_FACTOR * tol;
            if out.len > 0 && out.min_separation() <= guard {
                SatOutcome::Contact
            } else {
                SatOutcome::Fallback
            }
        }
    };
    if outcome == SatOutcome::Fallback && core_separation > 0.0 {
        // Apart, but closest at a box vertex or a segment end the axes do not name.
        return segment_box_apart(c, b, (p0, p1), b_in_a, margin, out);
    }
    outcome
}

/// Capsule `c` (A, local frame) against triangle `t` at `b_in_a` (a mesh or height-field
/// part), in the triangle's frame, from the exact closest points of the core segment and
/// the triangle: the nearest of each segment end against the triangle (its Voronoi
/// regions, [`super::analytic::closest_on_triangle`]) and the segment against each of the
/// three edges (Ericson 5.1.9). When the segment does not pass through the triangle, their
/// closest pair is one of those.
///
/// - The segment clipped against the triangle's side planes, when its nearest point there
///   is as near as the closest pair (within the tolerance): up to 2 points along the face
///   normal facing the segment, as a capsule on a box face gets them.
/// - Else one point along the closest pair's direction, ids (segment feature, triangle
///   edge or vertex).
///
/// [`SatOutcome::Fallback`] when the cores meet (the segment crosses the triangle or
/// touches it): the general path's EPA gives the depth.
pub(crate) fn capsule_triangle(
    c: &Capsule,
    t: &Triangle,
    b_in_a: &Iso,
    margin: f32,
    out: &mut LocalManifold,
) -> SatOutcome {
    let (s0, s1) = c.segment();
    let p0 = b_in_a.inverse_transform_point(s0);
    let p1 = b_in_a.inverse_transform_point(s1);
    let d = p1 - p0;
    let r = c.radius;
    // The plane and the face polygons only (no side normals: `TrianglePolytope` forms
    // those for the polytope test).
    let n = t.normal();
    let [v0, v1, v2] = t.vertices;
    let (h0, h1) = (n.dot(p0 - v0), n.dot(p1 - v0));
    if h0 * h1 <= 0.0 {
        // The segment meets the plane (or a NaN): through the triangle, the cores overlap.
        let dh = h0 - h1;
        let x = if dh != 0.0 { p0 + d * (h0 / dh) } else { p0 };
        if super::analytic::closest_on_triangle(t, x).1.is_none() || !dh.is_finite() {
            return SatOutcome::Fallback;
        }
        // Through an edge or a vertex (within rounding): the closest pair below has a gap
        // of rounding size, and the guard on it falls back.
    }
    let tol = SAT_TOLERANCE
        * (b_in_a.position.abs().max_elem() + triangle_extent(t) + c.half_height + c.radius);
    // Both ends on one side of the plane and higher above it than the radius and the
    // margin: the closest pair below is at least that far apart, so it would answer
    // `Separated`; answered at once, with the guard that covers the rounding of both.
    let height = scalar::min(scalar::abs(h0), scalar::abs(h1));
    if h0 * h1 > 0.0 && height - r > margin + GUARD_FACTOR * tol {
        return SatOutcome::Separated;
    }
    // (squared gap, segment parameter, segment point, triangle point, triangle feature);
    // ends first, then edges in order, strict `<`.
    let mut best: Option<(f32, f32, Vec3, Vec3, FeatureId)> = None;
    let mut consider = |s: f32, on_segment: Vec3, on_tri: Vec3, feature: FeatureId| {
        let gap2 = (on_segment - on_tri).length_squared();
        if best.is_none_or(|(g, ..)| gap2 < g) {
            best = Some((gap2, s, on_segment, on_tri, feature));
        }
    };
    for (s, p) in [(0.0, p0), (1.0, p1)] {
        let (q, feature) = super::analytic::closest_on_triangle(t, p);
        let on_tri = if feature.is_none() {
            p - n * n.dot(p - v0)
        } else {
            q
        };
        consider(s, p, on_tri, feature.unwrap_or(FeatureId::face(0)));
    }
    for (i, (a, b)) in [(v0, v1), (v1, v2), (v2, v0)].into_iter().enumerate() {
        let (s, u) = segment_closest_points(p0, p1, a, b);
        let j = (i + 1) % 3;
        let feature = match feature_at(u) {
            f if f == FeatureId::vertex(0) => FeatureId::vertex(i as u32),
            f if f == FeatureId::vertex(1) => FeatureId::vertex(j as u32),
            _ => FeatureId::edge(i as u32, j as u32),
        };
        consider(s, p0 + d * s, a + (b - a) * u, feature);
    }
    let Some((_, s, on_segment, on_tri, feature)) = best else {
        return SatOutcome::Fallback;
    };
    let Some((toward, gap)) = (on_tri - on_segment).normalize_and_length() else {
        return SatOutcome::Fallback;
    };
    if gap <= GUARD_FACTOR * tol {
        // The cores touch within rounding (a segment through an edge): no direction.
        return SatOutcome::Fallback;
    }
    let within = gap - r <= margin; // false for NaN too
    if !within {
        return SatOutcome::Separated;
    }
    let to_a = |p: Vec3| b_in_a.transform_point(p);
    // The face on the closest segment point's side (where the clipped part lies when it
    // matters); the segment clipped to the side planes.
    let facing = if n.dot(on_segment - v0) >= 0.0 { n } else { -n };
    let f = t.supporting_tri(facing);
    let nf = f.normal;
    let (mut front, mut back) = (clip::ClipPolygon::new(), clip::ClipPolygon::new());
    let mut buffers = clip::ClipBuffers::new(&mut front, &mut back);
    let clipped = buffers.segment(
        &f,
        p0,
        p1,
        [FeatureId::vertex(0), FeatureId::vertex(1)],
        FeatureId::edge(0, 1),
    );
    let f0 = f.vertices[0];
    let lowest = clipped
        .vertices()
        .iter()
        .map(|v| (v.point - f0).dot(nf))
        .fold(f32::INFINITY, scalar::min);
    if lowest <= gap + tol {
        // Face contact, as capsule_cuboid's.
        capsule_on_face(clipped, &f, d, r, b_in_a, margin, out);
        // As deep as the closest pair says (a clipped point inside the segment measures
        // the cylinder straight down, `r cos β` for a capsule tilted by β, shallower than
        // the closest pair where that lies on an edge), and never deeper: the cores do
        // not meet, so every clipped point is at least `gap` from the triangle. A deeper
        // face contact is a segment crossing the plane just outside an edge whose part
        // inside the (slanted) prism lies behind the face chosen (fuzz finding
        // `capsule-past-a-triangle-edge-1f4f15f4`: 2.55 m deep for 7.2 mm). Else the one
        // point below.
        let deepest = out.min_separation();
        let slack = GUARD_FACTOR * tol;
        if out.len > 0 && deepest <= gap - r + slack && deepest >= gap - r - slack {
            return SatOutcome::Contact;
        }
    }
    // One point along the closest pair, from the capsule towards the triangle.
    let normal = b_in_a.transform_vector(toward);
    let id = ContactId {
        a: feature_at(s),
        b: feature,
    };
    out.reset(normal);
    out.push_within(
        Candidate::new(to_a(on_segment + toward * r), to_a(on_tri), normal, id),
        margin,
    );
    if out.len > 0 {
        SatOutcome::Contact
    } else {
        SatOutcome::Fallback
    }
}

/// The face contact of a capsule whose core segment `d` (B's frame), clipped against the
/// side planes of B's face `f`, gave `clipped`: at each clipped point, the capsule's
/// surface point facing the face and its projection on the face, into `out` (A's frame,
/// normal `−n` from the capsule towards B) when within `margin`. The surface point is on
/// the end cap, along `−n`, when `n` points out past that end of the segment; else on the
/// cylinder, along the part of `n` perpendicular to the segment (a tilted capsule's middle
/// is `r cos α` above its axis, not `r`).
fn capsule_on_face(
    clipped: &clip::ClipPolygon,
    f: &impl Polygon,
    d: Vec3,
    r: f32,
    b_in_a: &Iso,
    margin: f32,
    out: &mut LocalManifold,
) {
    let nf = f.normal();
    let f0 = f.points().first().copied().unwrap_or(Vec3::ZERO);
    let normal = b_in_a.transform_vector(-nf);
    let dd = d.length_squared();
    let along = nf.dot(d);
    let across = if dd > 0.0 { nf - d * (along / dd) } else { nf };
    let cylinder = across.normalize_or(nf);
    out.reset(normal);
    for v in clipped.vertices() {
        // Height (m) of the segment point above the face plane.
        let height = (v.point - f0).dot(nf);
        let id = ContactId {
            a: v.inc_id,
            b: v.ref_id,
        };
        let past_end = (v.inc_id == FeatureId::vertex(0) && along >= 0.0)
            || (v.inc_id == FeatureId::vertex(1) && along <= 0.0);
        let toward_face = if past_end { nf } else { cylinder };
        let point_a = b_in_a.transform_point(v.point - toward_face * r);
        let point_b = b_in_a.transform_point(v.point - nf * height);
        out.push_within(Candidate::new(point_a, point_b, normal, id), margin);
    }
}

/// A capsule whose core segment `p0 → p1` (box frame) is apart from box `b`: the exact
/// closest points, the nearest of each segment end against the box (the end clamped to
/// the box) and the segment against each of the 12 box edges (Ericson 5.1.9). When the
/// two are apart their closest pair is one of those: an end over a face, edge or vertex,
/// or an inner segment point against an edge or a vertex (an edge's end). One point, along
/// the closest points' direction; ids (segment feature, box face, edge or vertex).
fn segment_box_apart(
    c: &Capsule,
    b: &Cuboid,
    (p0, p1): (Vec3, Vec3),
    b_in_a: &Iso,
    margin: f32,
    out: &mut LocalManifold,
) -> SatOutcome {
    let h = b.half_extents;
    let d = p1 - p0;
    let clamp = |p: Vec3| {
        Vec3::new(
            scalar::clamp(p.x, -h.x, h.x),
            scalar::clamp(p.y, -h.y, h.y),
            scalar::clamp(p.z, -h.z, h.z),
        )
    };
    // (squared gap, segment parameter, segment point, box point, box feature); ends first,
    // then edges in index order, strict `<`.
    let mut best: Option<(f32, f32, Vec3, Vec3, FeatureId)> = None;
    let mut consider = |t: f32, on_segment: Vec3, on_box: Vec3, feature: FeatureId| {
        let gap2 = (on_segment - on_box).length_squared();
        if best.is_none_or(|(g, ..)| gap2 < g) {
            best = Some((gap2, t, on_segment, on_box, feature));
        }
    };
    for (t, p) in [(0.0, p0), (1.0, p1)] {
        consider(t, p, clamp(p), super::analytic::clamped_feature(p, h));
    }
    for e in 0..12 {
        let Some(edge) = Polytope::edge(b, e) else {
            continue;
        };
        let (s, u) = segment_closest_points(p0, p1, edge.p0, edge.p1);
        let feature = match feature_at(u) {
            f if f == FeatureId::vertex(0) => FeatureId::vertex(edge.v0),
            f if f == FeatureId::vertex(1) => FeatureId::vertex(edge.v1),
            _ => FeatureId::edge(edge.v0, edge.v1),
        };
        consider(s, p0 + d * s, edge.p0 + (edge.p1 - edge.p0) * u, feature);
    }
    let Some((_, t, on_segment, on_box, feature)) = best else {
        return SatOutcome::Fallback;
    };
    let Some((n, gap)) = (on_segment - on_box).normalize_and_length() else {
        return SatOutcome::Fallback;
    };
    let r = c.radius;
    let within = gap - r <= margin; // false for NaN too
    if !within {
        return SatOutcome::Separated;
    }
    let normal = b_in_a.transform_vector(-n);
    let id = ContactId {
        a: feature_at(t),
        b: feature,
    };
    out.reset(normal);
    out.push_within(
        Candidate::new(
            b_in_a.transform_point(on_segment - n * r),
            b_in_a.transform_point(on_box),
            normal,
            id,
        ),
        margin,
    );
    if out.len > 0 {
        SatOutcome::Contact
    } else {
        SatOutcome::Fallback
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::Quat;
    use crate::rng::SplitMix64;

    /// The arcs' crossing by brute force: the two great circles meet at `±q`,
    /// `q = (b × a) × (d × c)`; the arcs cross when one of them lies on both (a point `x`
    /// is on arc `(p, r)` when it is a non-negative combination `x = α p + β r`).
    fn arcs_cross(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> Option<bool> {
        let q = b.cross(a).cross(d.cross(c)).normalize_and_length()?.0;
        let on_arc = |x: Vec3, p: Vec3, r: Vec3| {
            // Solve x = α p + β r in the plane of p and r.
            let (pp, pr, rr) = (p.dot(p), p.dot(r), r.dot(r));
            let (xp, xr) = (x.dot(p), x.dot(r));
            let det = pp * rr - pr * pr;
            let alpha = (xp * rr - xr * pr) / det;
            let beta = (xr * pp - xp * pr) / det;
            alpha > 1e-4 && beta > 1e-4
        };
        Some((on_arc(q, a, b) && on_arc(q, c, d)) || (on_arc(-q, a, b) && on_arc(-q, c, d)))
    }

    #[test]
    fn gauss_map_test_matches_brute_force_arc_crossing() {
        let mut rng = SplitMix64::new(11);
        let mut crossing = 0;
        for _ in 0..20000 {
            let (a, b, c, d) = (
                rng.unit_vector(),
                rng.unit_vector(),
                rng.unit_vector(),
                rng.unit_vector(),
            );
            // Arcs shorter than a half circle, as a convex polytope's are.
            if a.dot(b) < -0.9 || c.dot(d) < -0.9 {
                continue;
            }
            let Some(expected) = arcs_cross(a, b, c, d) else {
                continue;
            };
            // A's edge along −(b × a), B's arc (c, d) = (−n0_B, −n1_B), edge along −(d × c).
            let fr = Frame::new(&Iso::IDENTITY);
            let arc = ArcA::new(
                PolyEdge {
                    v0: 0,
                    v1: 1,
                    p0: Vec3::ZERO,
                    p1: -b.cross(a),
                    n0: a,
                    n1: b,
                },
                &fr,
            );
            let eb = PolyEdge {
                v0: 0,
                v1: 1,
                p0: Vec3::ZERO,
                p1: -d.cross(c),
                n0: -c,
                n1: -d,
            };
            let dots = (eb.n0.dot(arc.vector_b), eb.n1.dot(arc.vector_b));
            let got = is_minkowski_face(&arc, dots.0, dots.1, eb.p1 - eb.p0);
            // Near-tangent cases are rounding either way; compare clear ones only.
            let margin = [a, b]
                .iter()
                .map(|x| x.dot(d.cross(c).normalize_or(Vec3::Y)).abs())
                .chain(
                    [c, d]
                        .iter()
                        .map(|x| x.dot(b.cross(a).normalize_or(Vec3::Y)).abs()),
                )
                .fold(f32::INFINITY, f32::min);
            if margin < 1e-3 {
                continue;
            }
            assert_eq!(got, expected, "{a:?} {b:?} {c:?} {d:?}");
            crossing += got as u32;
        }
        assert!(crossing > 1000, "{crossing}");
    }

    #[test]
    fn box_edges_follow_the_winding_convention() {
        let c = Cuboid::new(Vec3::new(0.5, 0.7, 0.9)).unwrap();
        for e in 0..12 {
            let edge = Polytope::edge(&c, e).unwrap();
            // n1 × n0 points along p0 − p1.
            let along = edge.n1.cross(edge.n0).dot(edge.p0 - edge.p1);
            assert!(along > 0.0, "{e} {edge:?}");
            // Both end points lie on both faces.
            for p in [edge.p0, edge.p1] {
                for n in [edge.n0, edge.n1] {
                    let f = (0..6).find(|&f| Polytope::plane(&c, f).0 == n).unwrap();
                    let (m, d) = Polytope::plane(&c, f);
                    assert!((m.dot(p) - d).abs() < 1e-6);
                }
            }
            // The face along n0 runs p0 → p1 counter-clockwise: its polygon has the
            // directed edge.
            let f = (0..6)
                .find(|&f| Polytope::plane(&c, f).0 == edge.n0)
                .unwrap();
            let poly = Polytope::polygon(&c, f);
            let ids = &poly.vertex_ids[..poly.len as usize];
            let k = ids
                .iter()
                .position(|v| *v == FeatureId::vertex(edge.v0))
                .unwrap();
            assert_eq!(ids[(k + 1) % 4], FeatureId::vertex(edge.v1), "{e}");
        }
    }

    #[test]
    fn box_edge_along_matches_the_edge_table() {
        let c = Cuboid::new(Vec3::new(0.5, 0.7, 0.9)).unwrap();
        let mut rng = SplitMix64::new(14);
        for _ in 0..200 {
            let dir = rng.unit_vector();
            for i in 0..3 {
                let (e, quick) = box_edge_along(&c, i, dir);
                let quick = quick.unwrap();
                let full = Polytope::edge(&c, e).unwrap();
                assert_eq!(
                    (quick.v0, quick.v1, quick.p0, quick.p1),
                    (full.v0, full.v1, full.p0, full.p1)
                );
                // It supports dir among the edges along axis i.
                for k in 0..4 {
                    let other = Polytope::edge(&c, 4 * i + k).unwrap();
                    assert!(other.p0.dot(dir) <= full.p0.dot(dir) + 1e-6);
                }
            }
        }
    }

    #[test]
    fn hull_edges_follow_the_winding_convention() {
        let mut rng = SplitMix64::new(12);
        for _ in 0..20 {
            let pts: std::vec::Vec<Vec3> = (0..24).map(|_| rng.unit_vector()).collect();
            let h = ConvexHull::new(&pts).unwrap();
            assert!(h.is_closed());
            // Euler: V − E + F = 2 for a hull whose faces are not split.
            let v = h.vertices().len() as i32;
            let e = h.edge_count() as i32;
            let f = h.face_count() as i32;
            assert_eq!(v - e + f, 2);
            for i in 0..h.edge_count() {
                let edge = Polytope::edge(&h, i).unwrap();
                assert!(edge.v0 < edge.v1);
                let along = edge.n1.cross(edge.n0).dot(edge.p0 - edge.p1);
                assert!(along > 0.0, "{edge:?}");
            }
        }
    }

    /// Clip `incident` against `reference` as they are and widened to full `Face`s; assert
    /// that both give the same manifold, bit for bit (Debug prints every float and the
    /// sign of a zero exactly), and return whether there is one.
    fn clips_alike<const R: usize, const I: usize>(
        reference: &Face<R>,
        incident: &Face<I>,
        reference_is_a: bool,
        margin: f32,
    ) -> bool {
        let (wide_ref, wide_inc): (Face, Face) =
            (reference.with_capacity(), incident.with_capacity());
        let (mut small, mut wide) = (LocalManifold::new(Vec3::Y), LocalManifold::new(Vec3::Y));
        let found = clipped_face_manifold(reference, incident, reference_is_a, margin, &mut small);
        let found_wide =
            clipped_face_manifold(&wide_ref, &wide_inc, reference_is_a, margin, &mut wide);
        assert_eq!(found, found_wide);
        assert_eq!(std::format!("{small:?}"), std::format!("{wide:?}"));
        found
    }

    /// A box's faces clipped as `Face<4>` give the manifold the full-capacity `Face` gives,
    /// bit for bit (the clipper is one generic code; only the storage differs), for every
    /// face of A as the reference against B's face along it, and for B's faces against A's.
    #[test]
    fn box_faces_clip_as_four_corners_exactly_as_full_faces() {
        let mut rng = SplitMix64::new(16);
        let a = Cuboid::new(Vec3::new(0.5, 0.3, 0.8)).unwrap();
        let b = Cuboid::new(Vec3::new(0.4, 0.6, 0.2)).unwrap();
        let mut with_points = 0;
        for _ in 0..400 {
            let b_in_a = Iso::new(rng.unit_vector() * rng.range(0.0, 1.2), rng.rotation());
            let fr = Frame::new(&b_in_a);
            for f in 0..6 {
                let reference = a.polygon(f);
                let mut incident = b.face_along(fr.inv_vector(-reference.normal));
                incident.transform_by(&fr.r, fr.t);
                with_points += usize::from(clips_alike(&reference, &incident, true, 0.1));
                let mut reference = b.polygon(f);
                reference.transform_by(&fr.r, fr.t);
                let incident = a.face_along(-reference.normal);
                with_points += usize::from(clips_alike(&reference, &incident, false, 0.1));
            }
        }
        assert!(with_points > 300, "{with_points}");
    }

    /// The same for a triangle's faces (`Face<3>`) against a box's, either as the reference.
    #[test]
    fn triangle_faces_clip_as_three_corners_exactly_as_full_faces() {
        let mut rng = SplitMix64::new(17);
        let b = Cuboid::new(Vec3::new(0.4, 0.6, 0.2)).unwrap();
        let mut with_points = 0;
        for _ in 0..400 {
            let corner = |rng: &mut SplitMix64| rng.unit_vector() * rng.range(0.3, 1.5);
            let t = Triangle {
                vertices: [corner(&mut rng), corner(&mut rng), corner(&mut rng)],
            };
            let a = TrianglePolytope::new(&t);
            let b_in_a = Iso::new(rng.unit_vector() * rng.range(0.0, 1.0), rng.rotation());
            let fr = Frame::new(&b_in_a);
            for f in 0..2 {
                let reference = a.polygon(f);
                let mut incident = b.face_along(fr.inv_vector(-reference.normal));
                incident.transform_by(&fr.r, fr.t);
                with_points += usize::from(clips_alike(&reference, &incident, true, 0.1));
                with_points += usize::from(clips_alike(&incident, &reference, false, 0.3));
            }
        }
        assert!(with_points > 200, "{with_points}");
    }

    /// The closed-form box test and the generic polytope test find the same separations.
    #[test]
    fn box_closed_form_matches_the_generic_test() {
        let mut rng = SplitMix64::new(13);
        let a = Cuboid::new(Vec3::new(0.5, 0.3, 0.8)).unwrap();
        let b = Cuboid::new(Vec3::new(0.4, 0.6, 0.2)).unwrap();
        let mut compared = 0;
        for _ in 0..2000 {
            let b_in_a = Iso::new(rng.unit_vector() * rng.range(0.0, 1.8), rng.rotation());
            let fr = Frame::new(&b_in_a);
            let p = BoxPair::new(&a, &b, &fr);
            let margin = 0.05;
            let closed = box_query(&a, &b, &p, margin);
            let generic = query_with(&a, &b, &fr, margin, false);
            match (closed, generic) {
                (Ok((fa, fb, ea)), Ok((ga, gb, eg))) => {
                    compared += 1;
                    assert!((fa.separation - ga.separation).abs() < 1e-5);
                    assert!((fb.separation - gb.separation).abs() < 1e-5);
                    let es = ea.map_or(f32::NEG_INFINITY, |e| e.separation);
                    let gs = eg.map_or(f32::NEG_INFINITY, |e| e.separation);
                    assert!(
                        (es - gs).abs() < 1e-4 || (es < -1.0 && gs < -1.0),
                        "{es} {gs}"
                    );
                    if let (Some(ea), Some(eg)) = (ea, eg) {
                        if (ea.separation - eg.separation).abs() < 1e-6 {
                            assert!(ea.normal.dot(eg.normal) > 0.999);
                        }
                    }
                }
                (Err(_), Err(_)) => {}
                (c, g) => {
                    // Only right at the margin may they disagree.
                    let s = |r: &Result<(FaceBest, FaceBest, Option<EdgeBest>), SatAxis>| {
                        r.as_ref().map_or(margin, |(fa, fb, e)| {
                            fa.separation
                                .max(fb.separation)
                                .max(e.map_or(f32::NEG_INFINITY, |e| e.separation))
                        })
                    };
                    assert!((s(&c) - margin).abs() < 1e-4 && (s(&g) - margin).abs() < 1e-4);
                }
            }
        }
        assert!(compared > 500, "{compared}");
    }

    /// What the caller of [`query`] uses from its result, for comparing the pruned test
    /// with the full one bit for bit: the separating axis, or the best faces (index and
    /// separation bits) and the best edge pair when it separates more than both faces.
    fn used(r: Result<(FaceBest, FaceBest, Option<EdgeBest>), SatAxis>) -> std::string::String {
        match r {
            Err(axis) => std::format!("separated along {axis:?}"),
            Ok((fa, fb, e)) => {
                let best_face = fa.separation.max(fb.separation);
                let e = e
                    .filter(|e| e.separation > best_face)
                    .map(|e| (e.index_a, e.index_b, e.separation.to_bits(), e.normal));
                std::format!(
                    "A {} {:#x}, B {} {:#x}, edge {e:?}",
                    fa.index,
                    fa.separation.to_bits(),
                    fb.index,
                    fb.separation.to_bits()
                )
            }
        }
    }

    /// Asserts that the pruned test answers what the full test answers for `a` and `b`
    /// at `fr` (`what` names the case), and returns the full test's answer.
    fn pruned_is_full<A: Polytope, B: Polytope>(
        a: &A,
        b: &B,
        fr: &Frame,
        margin: f32,
        what: &str,
    ) -> Result<(FaceBest, FaceBest, Option<EdgeBest>), SatAxis> {
        let full = query_with(a, b, fr, margin, false);
        let pruned = query_with(a, b, fr, margin, true);
        assert_eq!(used(pruned), used(full), "{what}");
        full
    }

    /// How many answers were "apart", how many "overlapping", and how many of those had
    /// an edge pair beating the best face.
    #[derive(Debug, Default)]
    struct Outcomes {
        separated: usize,
        overlapping: usize,
        edge_wins: usize,
    }

    impl Outcomes {
        fn add(&mut self, r: &Result<(FaceBest, FaceBest, Option<EdgeBest>), SatAxis>) {
            match r {
                Err(_) => self.separated += 1,
                Ok((fa, fb, e)) => {
                    self.overlapping += 1;
                    let face = fa.separation.max(fb.separation);
                    self.edge_wins += usize::from(e.is_some_and(|e| e.separation > face));
                }
            }
        }

        /// More than `each` answers apart and `each` overlapping, and more than `edges`
        /// won by an edge pair.
        fn cover(&self, each: usize, edges: usize) -> bool {
            self.separated > each && self.overlapping > each && self.edge_wins > edges
        }
    }

    /// The pruned test (faces by the ball bound, edges by the Gauss-map arc bound) answers
    /// exactly what measuring every face and edge pair answers, on hull–hull and
    /// hull–box pairs from apart to deeply overlapping, flat and stretched hulls included.
    #[test]
    fn pruned_query_matches_the_full_test_bit_for_bit() {
        let mut rng = SplitMix64::new(14);
        let boxed = Cuboid::new(Vec3::new(0.5, 0.2, 0.35)).unwrap();
        let (mut seen, mut edges_pruned) = (Outcomes::default(), 0);
        for round in 0..300 {
            let hull = |rng: &mut SplitMix64| {
                let count = 4 + (rng.next_u64() % 28) as usize;
                let stretch = Vec3::new(
                    rng.range(0.2, 1.5),
                    rng.range(0.2, 1.5),
                    rng.range(0.01, 1.5),
                );
                let pts: std::vec::Vec<Vec3> = (0..count)
                    .map(|_| {
                        let u = rng.unit_vector();
                        Vec3::new(u.x * stretch.x, u.y * stretch.y, u.z * stretch.z)
                    })
                    .collect();
                ConvexHull::new(&pts).unwrap()
            };
            let (a, b) = (hull(&mut rng), hull(&mut rng));
            // Edge pairs are pruned only between hulls with well-formed edges.
            edges_pruned += usize::from(a.has_well_formed_edges() && b.has_well_formed_edges());
            for _ in 0..40 {
                let b_in_a = Iso::new(rng.unit_vector() * rng.range(0.0, 2.5), rng.rotation());
                let fr = Frame::new(&b_in_a);
                let margin = if round % 2 == 0 { 0.02 } else { 0.3 };
                let case = |what: &str| std::format!("{what}, round {round}, {b_in_a:?}");
                seen.add(&pruned_is_full(&a, &b, &fr, margin, &case("hull pair")));
                seen.add(&pruned_is_full(
                    &a,
                    &boxed,
                    &fr,
                    margin,
                    &case("hull-box pair"),
                ));
                seen.add(&pruned_is_full(
                    &boxed,
                    &b,
                    &fr,
                    margin,
                    &case("box-hull pair"),
                ));
            }
        }
        // Every kind of outcome was compared, edge pairs winning included, and most hull
        // pairs had their edges pruned.
        assert!(
            seen.cover(1000, 100) && edges_pruned > 150,
            "{seen:?} {edges_pruned}"
        );
    }

    /// The vertices of `deepest_vertices` bound the separation along every axis, from
    /// every point of the other shape: `s(n) ≤ n · (y − p)` for each vertex `p` of A
    /// (edge starts) and `s(n) ≤ (−n) · (x − q)` in B's frame for each vertex `q` of B,
    /// within rounding; and each is its shape's lowest vertex along the other's best face
    /// normal. Random hull pairs, overlapping and apart within the margin, random axes.
    #[test]
    fn deepest_vertices_bound_the_separation_along_any_axis() {
        let mut rng = SplitMix64::new(16);
        let mut checked = 0usize;
        for _ in 0..100 {
            let hull = |rng: &mut SplitMix64| {
                let pts: std::vec::Vec<Vec3> = (0..4 + (rng.next_u64() % 20) as usize)
                    .map(|_| rng.unit_vector() * rng.range(0.3, 1.2))
                    .collect();
                ConvexHull::new(&pts).unwrap()
            };
            let (a, b) = (hull(&mut rng), hull(&mut rng));
            for _ in 0..10 {
                let b_in_a = Iso::new(rng.unit_vector() * rng.range(0.0, 2.0), rng.rotation());
                let fr = Frame::new(&b_in_a);
                let Ok((face_a, face_b, _)) = query_with(&a, &b, &fr, 0.3, false) else {
                    continue;
                };
                let (y, x) = deepest_vertices(&a, &b, &fr, &face_a, &face_b);
                // Lowest along the other's best face normal.
                let n_a = a.plane(face_a.index).0;
                let m_b = b.plane(face_b.index).0;
                assert!(n_a.dot(y) <= fr.t.dot(n_a) + b.min_dot(fr.inv_vector(n_a)) + 1e-5);
                assert!(fr.vector(m_b).dot(fr.point(x)) <= a.min_dot(fr.vector(m_b)) + 1e-5);
                for _ in 0..20 {
                    let n = rng.unit_vector();
                    let s = support_separation(&a, &b, &fr, n);
                    let m = fr.inv_vector(-n);
                    for e in 0..a.edge_count() {
                        let p = Polytope::edge(&a, e).unwrap().p0;
                        assert!(s <= n.dot(y - p) + 1e-5, "{s} {n:?} {y:?} {p:?}");
                    }
                    for e in 0..b.edge_count() {
                        let q = Polytope::edge(&b, e).unwrap().p0;
                        assert!(s <= m.dot(x - q) + 1e-5, "{s} {m:?} {x:?} {q:?}");
                    }
                    checked += 1;
                }
            }
        }
        assert!(checked > 5_000, "{checked}");
    }

    /// The same against triangles, whose edges are pruned by the box's or hull's ball
    /// (the triangle holds none): hull–triangle, triangle–hull, box–triangle and
    /// triangle–box pairs, thin and wide triangles, some far from their frame's origin as
    /// a mesh's are, apart to deeply overlapping.
    #[test]
    fn pruned_query_against_triangles_matches_the_full_test_bit_for_bit() {
        let mut rng = SplitMix64::new(15);
        let boxed = Cuboid::new(Vec3::new(0.4, 0.3, 0.35)).unwrap();
        let mut seen = Outcomes::default();
        for round in 0..200 {
            let count = 4 + (rng.next_u64() % 20) as usize;
            let pts: std::vec::Vec<Vec3> = (0..count)
                .map(|_| rng.unit_vector() * rng.range(0.3, 0.8))
                .collect();
            let hull = ConvexHull::new(&pts).unwrap();
            let size = [0.3, 1.0, 2.5][round % 3];
            let corner = |rng: &mut SplitMix64| rng.unit_vector() * rng.range(0.2, 1.0) * size;
            let (p, q) = (corner(&mut rng), corner(&mut rng));
            // Every fifth triangle thin: its third corner near the first edge.
            let r = if round % 5 == 0 {
                p + (q - p) * 0.5 + rng.unit_vector() * 0.01 * size
            } else {
                corner(&mut rng)
            };
            // Every fourth far from its frame's origin, as a mesh's triangles lie.
            let offset = if round % 4 == 3 {
                Vec3::new(11.5, -3.0, 7.25)
            } else {
                Vec3::ZERO
            };
            let Ok(t) = Triangle::new(p + offset, q + offset, r + offset) else {
                continue;
            };
            let tri = TrianglePolytope::new(&t);
            for _ in 0..40 {
                let (u, rot) = (rng.unit_vector() * rng.range(0.0, 1.5), rng.rotation());
                // The other shape about the triangle: moved by the offset when the triangle
                // is A, the triangle's offset turned back when it is B.
                let tri_a = Frame::new(&Iso::new(u + offset, rot));
                let tri_b = Frame::new(&Iso::new(u - rot.rotate(offset), rot));
                let margin = if round % 2 == 0 { 0.02 } else { 0.3 };
                let case = |what: &str| std::format!("{what}, round {round}, {u:?} {rot:?}");
                seen.add(&pruned_is_full(
                    &hull,
                    &tri,
                    &tri_b,
                    margin,
                    &case("hull-triangle"),
                ));
                seen.add(&pruned_is_full(
                    &tri,
                    &hull,
                    &tri_a,
                    margin,
                    &case("triangle-hull"),
                ));
                seen.add(&pruned_is_full(
                    &boxed,
                    &tri,
                    &tri_b,
                    margin,
                    &case("box-triangle"),
                ));
                seen.add(&pruned_is_full(
                    &tri,
                    &boxed,
                    &tri_a,
                    margin,
                    &case("triangle-box"),
                ));
            }
        }
        // Every kind of outcome was compared, edge pairs winning included.
        assert!(seen.cover(500, 50), "{seen:?}");
    }

    #[test]
    fn capsule_standing_on_a_box_gives_one_point_lying_two() {
        let b = Cuboid::new(Vec3::new(2.0, 0.5, 2.0)).unwrap();
        let c = Capsule::new(0.5, 0.2).unwrap();
        // Capsule (A) at the origin; the box below it.
        for (rot, expect) in [
            (Quat::IDENTITY, 1),
            (
                Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_2),
                2,
            ),
        ] {
            let below = if expect == 1 { 0.69 } else { 0.19 };
            let pose_box = Iso::new(
                rot.conjugate().rotate(Vec3::new(0.0, -0.5 - below, 0.0)),
                rot.conjugate(),
            );
            let mut m = LocalManifold::new(Vec3::Y);
            match capsule_cuboid(&c, &b, &pose_box, 0.02, &mut m) {
                SatOutcome::Contact => {
                    assert_eq!(m.len, expect, "{m:?}");
                    for p in m.points() {
                        assert!((p.separation + 0.01).abs() < 1e-5, "{p:?}");
                    }
                }
                other => panic!("{other:?}"),
            }
        }
    }
}
