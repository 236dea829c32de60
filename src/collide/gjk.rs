//! GJK: distance and closest points between two convex cores, then the radii.
//!
//! The query runs in A's frame on the Minkowski difference `D = B − A` of the two cores
//! (the points `b − a`). The point `v` of `D` closest to the origin gives the core distance
//! `|v|` and the normal `v / |v|` from A towards B; its barycentric coordinates on the
//! simplex give the closest point on each core. The radii are subtracted at the end:
//! `distance = max(|v| − ra − rb, 0)`, points moved along the normal by their radius.
//!
//! Closest point on a simplex: the signed-volumes sub-algorithm of Montanari, Madera and
//! Pellegrino (2017), "Improving the GJK algorithm for faster and more reliable distance
//! queries between convex objects", ACM TOG 36(3). It projects the origin on the affine
//! hull of the simplex and reads the barycentric coordinates from signed lengths, areas
//! or volumes in the coordinate axis or plane where the simplex is largest, which avoids
//! the cancellation of Johnson's determinants. Departures: f32 throughout; the sub-simplex
//! search is three small functions ([`s1d`], [`s2d`], [`s3d`]) with no recursion; and the
//! closest point itself is the origin's projection on the chosen sub-simplex, not `Σ λ w`:
//! on sliver faces of `D` (a millimetre box edge against a metre-long triangle) the
//! coordinates lose about four digits and the projection does not, which keeps the
//! normal accurate.
//!
//! Termination (each test is enough on its own; none can cycle):
//! 1. the new support point `w` brings the lower bound `v·w / |v|` to within a relative
//!    tolerance of the upper bound `|v|` (van den Bergen 1999);
//! 2. `w` repeats a vertex of the simplex (same vertex pair on A and B);
//! 3. the sub-algorithm drops `w` from the grown simplex, or its closest point is
//!    farther than `v` beyond rounding: no progress, the previous simplex, the best, is
//!    kept; a few steps in a row that leave `|v|²` unchanged within rounding also stop;
//! 4. [`MAX_GJK_ITERATIONS`] support points were taken ([`GjkStatus::IterationLimit`]).
//!
//! Stops 1–3 say "apart" unless the last support point lies clearly past the origin (the
//! origin within rounding of a triangle inside `D`: [`beyond_origin`]), which means the
//! cores overlap. The cores count as touching when the simplex is a tetrahedron holding
//! the origin, when `v` is too short to normalise, or when `v` is on a vertex or an edge
//! of `D` within f32 rounding of the origin ([`GJK_OVERLAP_TOLERANCE`]); on a face of `D`
//! the distance is reported down to rounding, so a gap of 1e-6 m reads as 1e-6 m. The
//! public doors compose B's pose in A's frame in f64 ([`super::Placement::between`]) so
//! that the pose's own rounding stays below that.
//!
//! A half-space has no support point: its pairs are closed forms.

use super::{check_pose, gjk_f64, Placement, Proxy};
use crate::error::Error;
use crate::math::{scalar, Iso, Vec3};
use crate::shape::Shape;

/// Iteration cap of the GJK loop.
pub const MAX_GJK_ITERATIONS: u32 = 32;

/// Termination test 1: stop when `|v|² − v·w <= GJK_RELATIVE_TOLERANCE · |v| |w|`: the gap
/// between the upper bound `|v|` and the lower bound `v·w / |v|` on the core distance is
/// then at most this fraction of `|w|`. The rounding of `|v|² − v·w` is a few ulps of
/// `|v| |w|` (f32: 1.2e-7 each), so 4e-6 lets the test fire on rounding noise instead of
/// spinning, and bounds the distance error by 4e-6 of the shapes' size. Cores are
/// polytopes, so the exact answer is normally reached first (tests 2 and 3).
pub(crate) const GJK_RELATIVE_TOLERANCE: f32 = 4.0e-6;

/// Termination test 3 accepts steps that leave `|v|²` unchanged within rounding: this
/// fraction (eight f32 ulps) of `|v| · max |w|`. The closest point is computed from the
/// simplex vertices, so its error is a few ulps of their size `max |w|`, not of `|v|`;
/// `|v|²` moves by twice `|v|` times that. (Relative to `|v|²` alone, a point 0.5 mm from
/// the origin inside an 11 m simplex would be held to 1e-10 m: GJK would stop on the
/// rounding of a sliver triangle and call cores apart that overlap.)...
const GJK_ROUNDING: f32 = 1.0e-6;

/// ...and this many such steps in a row end the search.
const GJK_MAX_PLATEAU: u32 = 4;

/// Cores closer than this fraction of the size of `D` seen by the run (the longest `|w|`
/// of any point of `D` it took, the simplex's included) count as touching (distance 0).
/// `v` is the origin's projection on the closest face, edge or vertex of the simplex,
/// computed from its vertex nearest the origin ([`s1d`], [`s2d`]), so its error is a few
/// ulps of the coordinates of `D` (f32: 1.2e-7 relative each): two boxes resting face on
/// face come out about 1e-7 |w| apart. 2e-7 is that rounding, and no more: at a 1 m scale a
/// gap of 5e-7 m already reads as itself (`tests/touching.rs` sweeps gaps from 1e-7 m).
///
/// This used to be 1e-5: gaps up to 2.5e-5 m between unit boxes read as touching, and the
/// distance was not monotonic in the gap. The looser value is still what guards the
/// *direction* of `v` on a vertex or an edge of `D` (see [`GJK_DIRECTION_TOLERANCE`]).
pub(crate) const GJK_OVERLAP_TOLERANCE: f32 = 2.0e-7;

/// A closest point on a vertex or an edge of `D` (a simplex of 1 or 2 points) closer to
/// the origin than this fraction of the size of `D` has an accurate length but not an
/// accurate direction: `v` carries the absolute rounding of the coordinates (about
/// 1e-7 |w|), and its direction is that error over `|v|`. (On a face of `D` the direction
/// is the triangle's normal, accurate at any distance.) Such an answer is
/// [`CoreDistance::ambiguous`]: [`distance`] still reports the exact gap, and EPA, which
/// takes its normal from faces of `D`, gives the normal of the penetration and of the
/// contact manifold. 1e-5 bounds the direction's error by 1e-2 rad.
pub(crate) const GJK_DIRECTION_TOLERANCE: f32 = 1.0e-5;

/// Cores stopped apart closer than this fraction of the size of `D` on a segment or a
/// triangle: see [`refined_near`].
const GJK_REFINE_NEAR: f32 = 1.0e-3;

/// `|v|²` (m²) at or below which `v` has no direction: the floor of
/// [`Vec3::normalize_and_length`]. Cores this close count as touching whatever their size.
const GJK_NO_DIRECTION: f32 = 1.0e-20;

/// The simplex GJK ended with, as vertex indices on A and B, to warm-start the next call
/// for the same pair. `Default` is an empty cache.
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
#[cfg_attr(feature = "serde", derive(serde::Serialize, serde::Deserialize))]
pub struct SimplexCache {
    /// Number of simplex vertices, 0 to 4.
    pub count: u8,
    /// Core vertex indices on A.
    pub index_a: [u32; 4],
    /// Core vertex indices on B.
    pub index_b: [u32; 4],
}

/// How GJK ended.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum GjkStatus {
    /// The cores are apart; the result is their distance.
    Separated,
    /// The cores overlap (the full shapes penetrate); use EPA for the depth.
    Overlapping,
    /// The iteration cap was hit; the result is the best found (an upper bound).
    IterationLimit,
}

/// The result of [`distance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct DistanceOutput {
    /// Distance between the full shapes (radii included), `>= 0`; 0 when they overlap.
    pub distance: f32,
    /// Closest point on A (world frame).
    pub point_a: Vec3,
    /// Closest point on B (world frame).
    pub point_b: Vec3,
    /// Unit normal from A towards B (world frame); meaningful when `distance > 0` or the
    /// cores are apart.
    pub normal: Vec3,
    /// GJK iterations used.
    pub iterations: u32,
    /// How GJK ended.
    pub status: GjkStatus,
}

/// Distance between `a` at `pose_a` and `b` at `pose_b` (world frame), warm-started from
/// and updating `cache`. Fails only on an invalid pose.
///
/// When the cores are apart, `point_a` and `point_b` are the closest points of the full
/// shapes (each core point moved by its radius along the normal); when the shapes
/// overlap but the cores do not, they are the deepest points. When the cores overlap,
/// both are the same point of the overlap and `distance` is 0.
///
/// Accuracy: the distance is within `4e-6` of the shapes' size (and a gap down to `f32`
/// rounding reads as itself). The normal is the direction of GJK's closest point `v`,
/// which `f32` resolves through `|v|²`: where the closest features are two parallel faces
/// the normal may lean by up to about `√(2⁻²³) ≈ 3.5e-4` rad (`props::GJK_NORMAL_ANGLE`
/// allows 1e-3), and the closest points may then sit anywhere on the faces' overlap.
///
/// # Examples
///
/// ```
/// use carom::collide::{distance, SimplexCache};
/// use carom::{Iso, Shape, Vec3};
///
/// # fn main() -> Result<(), carom::Error> {
/// let a = Shape::cuboid(Vec3::splat(0.5))?;
/// let b = Shape::sphere(0.5)?;
/// let mut cache = SimplexCache::default(); // keep one per pair to warm-start the next query
/// let d = distance(&a, &Iso::IDENTITY, &b, &Iso::from_position(Vec3::new(3.0, 0.0, 0.0)), &mut cache)?;
/// assert!((d.distance - 2.0).abs() < 1e-5); // from x = 0.5 to x = 2.5
/// assert!((d.normal - Vec3::X).length() < 1e-5);
/// # Ok(())
/// # }
/// ```
pub fn distance(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    cache: &mut SimplexCache,
) -> Result<DistanceOutput, Error> {
    check_pose(pose_a)?;
    check_pose(pose_b)?;
    a.check_convex()?;
    b.check_convex()?;
    let placement = Placement::between(pose_a, pose_b);
    let out = distance_placed(a, b, &placement, cache, MAX_GJK_ITERATIONS);
    let world = DistanceOutput {
        point_a: pose_a.transform_point(out.point_a),
        point_b: pose_a.transform_point(out.point_b),
        normal: pose_a.transform_vector(out.normal),
        ..out
    };
    // Only coordinates near f32::MAX can overflow here; answer with the origins.
    Ok(finite_or_fallback(world, pose_a.position, pose_b.position))
}

/// True when the shapes overlap or touch.
pub fn intersects(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> Result<bool, Error> {
    let mut cache = SimplexCache::default();
    Ok(distance(a, pose_a, b, pose_b, &mut cache)?.distance <= 0.0)
}

/// [`distance`] in A's frame: B placed at `b_in_a`, answer in A's frame.
pub(crate) fn distance_in_a(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    cache: &mut SimplexCache,
) -> DistanceOutput {
    distance_in_a_capped(a, b, b_in_a, cache, MAX_GJK_ITERATIONS)
}

/// [`distance_in_a`] with an explicit iteration cap (tests force the capped exit with it).
pub(crate) fn distance_in_a_capped(
    a: &Shape,
    b: &Shape,
    b_in_a: &Iso,
    cache: &mut SimplexCache,
    max_iterations: u32,
) -> DistanceOutput {
    distance_placed(a, b, &Placement::new(b_in_a), cache, max_iterations)
}

/// [`distance_in_a_capped`] with B's placement (pose and matrix) given.
pub(crate) fn distance_placed(
    a: &Shape,
    b: &Shape,
    placement: &Placement,
    cache: &mut SimplexCache,
    max_iterations: u32,
) -> DistanceOutput {
    let b_in_a = &placement.iso;
    let out = match (a, b) {
        (Shape::HalfSpace(_), Shape::HalfSpace(_)) => {
            *cache = SimplexCache::default();
            two_half_spaces(a, b_in_a)
        }
        (Shape::HalfSpace(h), _) => {
            *cache = SimplexCache::default();
            let pb = Proxy::placed(b, placement);
            half_space_vs_core(h.normal, &pb, b.radius())
        }
        (_, Shape::HalfSpace(h)) => {
            *cache = SimplexCache::default();
            let pa = Proxy::at_origin(a);
            core_vs_half_space(&pa, a.radius(), b_in_a.transform_vector(h.normal), b_in_a)
        }
        _ => {
            let pa = Proxy::at_origin(a);
            let pb = Proxy::placed(b, placement);
            let core = gjk_cores(&pa, &pb, cache, max_iterations);
            inflate(&core, a.radius(), b.radius())
        }
    };
    finite_or_fallback(out, Vec3::ZERO, b_in_a.position)
}

/// `core_distance − ra − rb`: the signed gap between the full shapes when the cores are
/// apart. One expression shared by GJK and EPA so both agree on "apart" to the bit.
#[inline]
pub(crate) fn radius_gap(core_distance: f32, ra: f32, rb: f32) -> f32 {
    core_distance - ra - rb
}

/// The full-shape answer from the core answer: subtract the radii, move the points.
pub(crate) fn inflate(core: &CoreDistance, ra: f32, rb: f32) -> DistanceOutput {
    let (distance, point_a, point_b) = match core.status {
        GjkStatus::Overlapping => (0.0, core.point_a, core.point_b),
        _ => (
            scalar::max(radius_gap(core.distance, ra, rb), 0.0),
            core.point_a + core.normal * ra,
            core.point_b - core.normal * rb,
        ),
    };
    DistanceOutput {
        distance,
        point_a,
        point_b,
        normal: core.normal,
        iterations: core.iterations,
        status: core.status,
    }
}

/// Never hand out a NaN or an infinity: inputs so large that f32 overflows give a
/// neutral answer, flagged [`GjkStatus::IterationLimit`]. An infinite distance (shapes
/// further apart than f32 can say) becomes `f32::MAX`, so "apart" stays apart; a NaN
/// becomes 0. Points that are not finite become `origin_a` and `origin_b` (or zero).
pub(crate) fn finite_or_fallback(
    out: DistanceOutput,
    origin_a: Vec3,
    origin_b: Vec3,
) -> DistanceOutput {
    // `0 x` is ±0 for a finite `x` and NaN for an infinity or a NaN, and a NaN carries
    // through the sum: one compare for all ten numbers.
    let zero = |p: Vec3| (p.x * 0.0 + p.y * 0.0) + p.z * 0.0;
    let all = out.distance * 0.0 + zero(out.point_a) + zero(out.point_b);
    if all + zero(out.normal) == 0.0 {
        return out;
    }
    let or_zero = |p: Vec3| if p.is_finite() { p } else { Vec3::ZERO };
    let points_ok = out.point_a.is_finite() && out.point_b.is_finite();
    DistanceOutput {
        distance: if out.distance.is_finite() {
            out.distance
        } else if out.distance > 0.0 {
            f32::MAX
        } else {
            0.0
        },
        point_a: if points_ok {
            out.point_a
        } else {
            or_zero(origin_a)
        },
        point_b: if points_ok {
            out.point_b
        } else {
            or_zero(origin_b)
        },
        normal: out.normal.normalize_or(Vec3::Y),
        iterations: out.iterations,
        status: GjkStatus::IterationLimit,
    }
}

// ---------------------------------------------------------------------------------------
// Half-spaces: closed forms.
// ---------------------------------------------------------------------------------------

/// A is the half-space `{p : n·p <= 0}` (A's frame); B's core at its pose. B's deepest core
/// point along `−n` is `p`; its height above the plane is `s = n·p`, so the distance is
/// `max(s − rb, 0)`, the normal `n`, B's point `p − n rb` and A's point its projection on
/// the plane. The cores overlap when `s <= 0`.
fn half_space_vs_core(n: Vec3, pb: &Proxy, rb: f32) -> DistanceOutput {
    let (p, _) = pb.support(-n);
    let s = n.dot(p);
    let point_b = p - n * rb;
    let point_a = point_b - n * n.dot(point_b);
    DistanceOutput {
        distance: scalar::max(radius_gap(s, 0.0, rb), 0.0),
        point_a,
        point_b,
        normal: n,
        iterations: 0,
        status: if s > 0.0 {
            GjkStatus::Separated
        } else {
            GjkStatus::Overlapping
        },
    }
}

/// B is the half-space `{p : n·(p − c) <= 0}` with `n` and `c` in A's frame. The mirror of
/// [`half_space_vs_core`]: A's deepest core point along `−n` at height `s = n·(p − c)`;
/// the normal from A towards B is `−n`.
fn core_vs_half_space(pa: &Proxy, ra: f32, n: Vec3, b_in_a: &Iso) -> DistanceOutput {
    let c = b_in_a.position;
    let (p, _) = pa.support(-n);
    let s = n.dot(p - c);
    let point_a = p - n * ra;
    let point_b = point_a - n * n.dot(point_a - c);
    DistanceOutput {
        distance: scalar::max(radius_gap(s, ra, 0.0), 0.0),
        point_a,
        point_b,
        normal: -n,
        iterations: 0,
        status: if s > 0.0 {
            GjkStatus::Separated
        } else {
            GjkStatus::Overlapping
        },
    }
}

/// Two half-spaces: reported as overlapping at distance 0 (they are static-only shapes and
/// never collide). The points are each plane's origin, the normal A's plane normal.
fn two_half_spaces(a: &Shape, b_in_a: &Iso) -> DistanceOutput {
    let normal = match a {
        Shape::HalfSpace(h) => h.normal,
        _ => Vec3::Y,
    };
    DistanceOutput {
        distance: 0.0,
        point_a: Vec3::ZERO,
        point_b: b_in_a.position,
        normal,
        iterations: 0,
        status: GjkStatus::Overlapping,
    }
}

// ---------------------------------------------------------------------------------------
// GJK on the cores.
// ---------------------------------------------------------------------------------------

/// One vertex of the simplex: the support points on each core (query frame), their
/// difference `w = b − a` (a point of `D`) and the core vertex indices that made them.
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct SimplexVertex {
    /// Point on A's core.
    pub a: Vec3,
    /// Point on B's core.
    pub b: Vec3,
    /// `b − a`.
    pub w: Vec3,
    /// Core vertex index on A.
    pub index_a: u32,
    /// Core vertex index on B.
    pub index_b: u32,
}

impl SimplexVertex {
    /// Same pair of core vertices.
    #[inline]
    pub fn same_as(&self, o: &SimplexVertex) -> bool {
        self.index_a == o.index_a && self.index_b == o.index_b
    }
}

/// The support point of `D = B − A` along `dir` (query frame): B's support along `dir`
/// minus A's support along `−dir`.
#[inline(always)]
pub(crate) fn support(pa: &Proxy, pb: &Proxy, dir: Vec3) -> SimplexVertex {
    let (b, index_b) = pb.support(dir);
    let (a, index_a) = pa.support(-dir);
    SimplexVertex {
        a,
        b,
        w: b - a,
        index_a,
        index_b,
    }
}

/// Up to four vertices with the barycentric coordinates of the point closest to the
/// origin (valid after [`Simplex::reduce_into`]).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub(crate) struct Simplex {
    /// The vertices; the first `count` are used.
    pub vertices: [SimplexVertex; 4],
    /// Barycentric coordinates of the closest point, one per used vertex.
    pub lambdas: [f32; 4],
    /// Number of vertices used, 0 to 4.
    pub count: usize,
    /// The point closest to the origin, `Σ λᵢ wᵢ` computed the accurate way (the origin's
    /// projection on the sub-simplex).
    pub point: Vec3,
}

impl Simplex {
    /// The simplex of one vertex.
    fn single(v: SimplexVertex) -> Simplex {
        let mut s = Simplex::default();
        s.push(v);
        s.lambdas = [1.0, 0.0, 0.0, 0.0];
        s.point = v.w;
        s
    }

    /// The vertices in use.
    pub fn used(&self) -> &[SimplexVertex] {
        let n = if self.count < 4 { self.count } else { 4 };
        self.vertices.get(..n).unwrap_or(&[])
    }

    /// Append a vertex; false (and nothing changes) when full.
    pub fn push(&mut self, v: SimplexVertex) -> bool {
        match self.vertices.get_mut(self.count) {
            Some(slot) => {
                *slot = v;
                self.count += 1;
                true
            }
            None => false,
        }
    }

    /// True when `v`'s vertex pair is already in the simplex.
    fn contains(&self, v: &SimplexVertex) -> bool {
        self.used().iter().any(|u| u.same_as(v))
    }

    /// The closest point `v` (valid after [`Simplex::reduce_into`]).
    pub fn closest(&self) -> Vec3 {
        self.point
    }

    /// The closest points on A's and B's cores: `Σ λᵢ aᵢ`, `Σ λᵢ bᵢ`.
    pub fn witnesses(&self) -> (Vec3, Vec3) {
        let mut pa = Vec3::ZERO;
        let mut pb = Vec3::ZERO;
        for (p, &l) in self.used().iter().zip(self.lambdas.iter()) {
            pa += p.a * l;
            pb += p.b * l;
        }
        (pa, pb)
    }

    /// The largest `|w|²` over the vertices: the scale of the overlap test.
    fn max_w_squared(&self) -> f32 {
        let mut m = 0.0;
        for p in self.used() {
            m = scalar::max(m, p.w.length_squared());
        }
        m
    }

    /// Remove the last vertex (pushed by [`Simplex::push`]), its slot cleared as an unused
    /// slot is; nothing happens to an empty simplex. Lambdas and the closest point are
    /// left as they were.
    fn pop(&mut self) {
        if let Some(count) = self.count.checked_sub(1) {
            if let Some(slot) = self.vertices.get_mut(count) {
                *slot = SimplexVertex::default();
            }
            self.count = count;
        }
    }

    /// Signed volumes: the smallest sub-simplex holding the point closest to the origin,
    /// with its barycentric coordinates, written into `out` (whatever it held before).
    /// Vertices keep their order.
    pub fn reduce_into(&self, out: &mut Simplex) {
        let [p0, p1, p2, p3] = self.vertices.map(|v| v.w);
        let (lambdas, point) = match self.count {
            0 => {
                *out = *self;
                return;
            }
            1 => ([1.0, 0.0, 0.0, 0.0], p0),
            2 => {
                let ([l0, l1], p) = s1d(p0, p1);
                ([l0, l1, 0.0, 0.0], p)
            }
            3 => {
                let ([l0, l1, l2], p) = s2d(p0, p1, p2);
                ([l0, l1, l2, 0.0], p)
            }
            _ => s3d(p0, p1, p2, p3),
        };
        // The vertices of positive coordinate, moved down in order; the slots past them
        // are left as they were (nothing reads a slot past `count`).
        // (Each coordinate is stored on its own: one load of four stored one by one
        // waits for them all to retire.)
        out.lambdas = [0.0; 4];
        let mut count = 0;
        for (v, &l) in self.used().iter().zip(lambdas.iter()) {
            if l > 0.0 {
                if let (Some(slot), Some(lambda)) =
                    (out.vertices.get_mut(count), out.lambdas.get_mut(count))
                {
                    *slot = *v;
                    *lambda = l;
                    count += 1;
                }
            }
        }
        if count == 0 {
            // Only reachable with NaN coordinates: keep the first vertex.
            *out = Simplex::single(self.vertices[0]);
            return;
        }
        out.count = count;
        out.point = point;
    }
}

/// True when `a` and `b` are both strictly positive or both strictly negative (the
/// paper's `compareSigns`; a zero matches nothing, which sends the search to the
/// boundary).
#[inline]
fn same_sign(a: f32, b: f32) -> bool {
    (a > 0.0 && b > 0.0) || (a < 0.0 && b < 0.0)
}

/// Index of the component of largest magnitude (ties: lowest index).
#[inline]
fn largest_axis(v: Vec3) -> usize {
    let a = v.abs();
    if a.x >= a.y && a.x >= a.z {
        0
    } else if a.y >= a.z {
        1
    } else {
        2
    }
}

/// Closest point of the segment `a b` to the origin: barycentric coordinates and the
/// point. The origin is projected on the line, `p0 = a − t (a·t / t·t)` with `t = b − a`
/// (written from `b` when `b` is nearer the origin); the coordinates are signed lengths
/// along the axis where the segment is longest (S1D). Inside the segment the point
/// returned is `p0` itself, which unlike `Σ λ w` does not inherit the coordinates'
/// rounding.
///
/// Departure from the paper: the projection starts from the nearer end. `p0` is a
/// difference that cancels down to `|p0|`, and its error is a few ulps of the end it
/// starts from; from the far end of a long edge of `D` (12 m) with the origin 0.3 mm off
/// it, that error (1e-6 m) tilts `p0` by 3e-3 rad, and the support point along `−p0` then
/// lands on the far end again: GJK stops on the wrong feature (fuzz regression
/// `sphere_near_sliver_hull_edge`). And one step of iterative refinement: with both ends
/// 8 m away and `p0` 1 mm from the origin, even the nearer end leaves an ulp of 8 m
/// (5e-7 m) in `p0`, which can zero the one component that tells two 15 m-apart support
/// vertices apart (fuzz regression `triangle_edge_through_triangle_corner`).
pub(crate) fn s1d(a: Vec3, b: Vec3) -> ([f32; 2], Vec3) {
    let t = b - a;
    let tt = t.length_squared();
    if !(tt > 0.0 && tt.is_finite()) {
        return ([1.0, 0.0], a);
    }
    let q = nearest_to_origin(a, b);
    let p0 = q - t * (q.dot(t) / tt);
    // One step of iterative refinement: p0 must be orthogonal to t, and the residual
    // p0·t is a product of the small p0, so it is accurate where p0 itself lost the
    // digits of q; removing it restores orthogonality to ulps of |p0|.
    let p0 = p0 - t * (p0.dot(t) / tt);
    let i = largest_axis(t);
    let mu = a[i] - b[i];
    let c_a = p0[i] - b[i]; // λa · mu
    let c_b = a[i] - p0[i]; // λb · mu
    if same_sign(mu, c_a) && same_sign(mu, c_b) {
        // Divided by their own sum (equal to mu up to rounding) so the coordinates sum
        // to 1 and the witnesses Σ λ a, Σ λ b are convex combinations, inside the cores.
        let sum = c_a + c_b;
        ([c_a / sum, c_b / sum], p0)
    } else if same_sign(mu, c_a) {
        ([1.0, 0.0], a)
    } else {
        ([0.0, 1.0], b)
    }
}

/// The one of `p`, `q` nearer the origin (`p` on ties).
#[inline]
fn nearest_to_origin(p: Vec3, q: Vec3) -> Vec3 {
    if q.length_squared() < p.length_squared() {
        q
    } else {
        p
    }
}

/// Twice the signed area of `p q r` projected on the coordinate plane `(j, k)`.
#[inline]
fn area2(p: Vec3, q: Vec3, r: Vec3, j: usize, k: usize) -> f32 {
    (q[j] - p[j]) * (r[k] - p[k]) - (q[k] - p[k]) * (r[j] - p[j])
}

/// Closest point of the triangle `a b c` to the origin: barycentric coordinates and the
/// point (S2D). The origin is projected on the plane, `p0 = n (q·n / n·n)` with `q` the
/// vertex nearest the origin; its
/// coordinates are signed areas in the coordinate plane where the triangle's projection
/// is largest (the one orthogonal to `n`'s largest component). If one is of the wrong
/// sign, the closest point lies on an edge opposite such a vertex: those edges are
/// searched with [`s1d`]. Inside, the point returned is `p0`: on a sliver triangle the
/// area ratios lose digits, the projection does not.
pub(crate) fn s2d(a: Vec3, b: Vec3, c: Vec3) -> ([f32; 3], Vec3) {
    let n = triangle_normal(a, b, c);
    let nn = n.length_squared();
    let mut search = [true; 3];
    if nn > 0.0 && nn.is_finite() {
        // The plane's offset read at the vertex nearest the origin: `q·n` rounds to a
        // few ulps of `|q| |n|`, so the nearest vertex gives the smallest error (see
        // [`s1d`]).
        let q = nearest_to_origin(nearest_to_origin(a, b), c);
        let p0 = n * (q.dot(n) / nn);
        let i = largest_axis(n);
        let (j, k) = match i {
            0 => (1, 2),
            1 => (2, 0),
            _ => (0, 1),
        };
        // With (i, j, k) cyclic, area2(a, b, c) over (j, k) is n[i].
        let mu = n[i];
        let c_a = area2(p0, b, c, j, k);
        let c_b = area2(a, p0, c, j, k);
        let c_c = area2(a, b, p0, j, k);
        let (s_a, s_b, s_c) = (same_sign(mu, c_a), same_sign(mu, c_b), same_sign(mu, c_c));
        if s_a && s_b && s_c {
            // Divided by their own sum, not mu: on a sliver the three areas lose digits
            // (a 15 m triangle 0.5 mm wide: their sum was 0.998 of mu), and coordinates
            // that do not sum to 1 put the witnesses Σ λ a, Σ λ b outside the cores.
            let sum = c_a + c_b + c_c;
            return ([c_a / sum, c_b / sum, c_c / sum], p0);
        }
        search = [!s_a, !s_b, !s_c];
    }
    let mut best = ([1.0, 0.0, 0.0], a);
    let mut best_d = f32::INFINITY;
    let mut consider = |l: [f32; 3], p: Vec3| {
        let d = p.length_squared();
        if d < best_d {
            best_d = d;
            best = (l, p);
        }
    };
    if search[0] {
        let ([lb, lc], p) = s1d(b, c);
        consider([0.0, lb, lc], p);
    }
    if search[1] {
        let ([la, lc], p) = s1d(a, c);
        consider([la, 0.0, lc], p);
    }
    if search[2] {
        let ([la, lb], p) = s1d(a, b);
        consider([la, lb, 0.0], p);
    }
    best
}

/// The triangle's normal scaled by twice its area, `(b − a) × (c − a)`, computed at the
/// corner opposite the longest edge (the same vector in exact arithmetic: the cross
/// product is invariant under cyclic relabelling).
///
/// Departure from the textbook `(b − a) × (c − a)`: the cross product's rounding is a few
/// ulps of the product of the two edge lengths it is built from, and excluding the
/// longest edge makes that product the smallest. For a sliver of `D` (a 6 m edge and a
/// 2 mm one, from a short capsule across a long one) the far corner's edges give a normal
/// off by 2e-4 rad, which puts the sliver's own third vertex 1 mm off its plane; the
/// corner opposite the long edge gives it to 1e-7 rad.
#[inline]
pub(crate) fn triangle_normal(a: Vec3, b: Vec3, c: Vec3) -> Vec3 {
    normal_and_longest_edge(a, b, c).0
}

/// [`triangle_normal`] and the triangle's longest edge squared (the largest of the three
/// squared lengths it compares; NaN when a comparison cannot tell).
#[inline]
fn normal_and_longest_edge(a: Vec3, b: Vec3, c: Vec3) -> (Vec3, f32) {
    let (ab, bc, ca) = (
        (b - a).length_squared(),
        (c - b).length_squared(),
        (a - c).length_squared(),
    );
    if bc >= ab && bc >= ca {
        ((b - a).cross(c - a), bc)
    } else if ca >= ab {
        ((c - b).cross(a - b), ca)
    } else {
        ((a - c).cross(b - c), ab)
    }
}

/// `a · (b × c)`.
#[inline]
fn det3(a: Vec3, b: Vec3, c: Vec3) -> f32 {
    a.dot(b.cross(c))
}

/// Closest point of the tetrahedron `a b c d` to the origin: barycentric coordinates
/// and the point (S3D). With `M` the 4×4 matrix of columns `(pᵢ, 1)`, Cramer's rule gives
/// `λᵢ = Cᵢ / det M` with `Cᵢ` the cofactors of the last row: `C₁ = −det(b, c, d)`,
/// `C₂ = det(a, c, d)`, `C₃ = −det(a, b, d)`, `C₄ = det(a, b, c)`. All of the sign of
/// `det M`: the origin is inside. Otherwise the faces opposite the vertices of the wrong
/// sign are searched with [`s2d`].
pub(crate) fn s3d(a: Vec3, b: Vec3, c: Vec3, d: Vec3) -> ([f32; 4], Vec3) {
    let c1 = -det3(b, c, d);
    let c2 = det3(a, c, d);
    let c3 = -det3(a, b, d);
    let c4 = det3(a, b, c);
    let det = c1 + c2 + c3 + c4;
    let signs = [
        same_sign(det, c1),
        same_sign(det, c2),
        same_sign(det, c3),
        same_sign(det, c4),
    ];
    if signs == [true; 4] {
        return ([c1 / det, c2 / det, c3 / det, c4 / det], Vec3::ZERO);
    }
    let mut best = ([1.0, 0.0, 0.0, 0.0], a);
    let mut best_d = f32::INFINITY;
    let mut consider = |l: [f32; 4], p: Vec3| {
        let dd = p.length_squared();
        if dd < best_d {
            best_d = dd;
            best = (l, p);
        }
    };
    if !signs[0] {
        let ([lb, lc, ld], p) = s2d(b, c, d);
        consider([0.0, lb, lc, ld], p);
    }
    if !signs[1] {
        let ([la, lc, ld], p) = s2d(a, c, d);
        consider([la, 0.0, lc, ld], p);
    }
    if !signs[2] {
        let ([la, lb, ld], p) = s2d(a, b, d);
        consider([la, lb, 0.0, ld], p);
    }
    if !signs[3] {
        let ([la, lb, lc], p) = s2d(a, b, c);
        consider([la, lb, lc, 0.0], p);
    }
    best
}

/// The cores' answer, before the radii.
#[derive(Clone, Copy, Debug)]
pub(crate) struct CoreDistance {
    /// Closest point on A's core (query frame).
    pub point_a: Vec3,
    /// Closest point on B's core (query frame).
    pub point_b: Vec3,
    /// Core distance `|v|` (0 when overlapping).
    pub distance: f32,
    /// Unit normal from A towards B: `v / |v|`, or the direction between the origins when
    /// the cores overlap.
    pub normal: Vec3,
    /// Support points taken.
    pub iterations: u32,
    /// How it ended.
    pub status: GjkStatus,
    /// The final simplex (EPA's seed when the cores overlap).
    pub simplex: Simplex,
    /// The cores are apart (not [`GjkStatus::Overlapping`]) but the closest point of `D`
    /// is a vertex or an edge so near the origin that `normal` is rounding noise (see
    /// [`GJK_DIRECTION_TOLERANCE`]); `distance` is still accurate. EPA gives the normal.
    pub ambiguous: bool,
}

/// Rebuild the cached simplex from its vertex indices, or `None` when the cache is empty,
/// repeats a vertex pair or is degenerate (coincident points, collinear triangle, flat
/// tetrahedron, each relative to its edge lengths).
fn warm_start(pa: &Proxy, pb: &Proxy, cache: &SimplexCache) -> Option<Simplex> {
    const THIN: f32 = 1.0e-5;
    let n = cache.count as usize;
    if n == 0 || n > 4 {
        return None;
    }
    let mut s = Simplex::default();
    for (&ia, &ib) in cache.index_a.iter().zip(cache.index_b.iter()).take(n) {
        let a = pa.vertex(ia);
        let b = pb.vertex(ib);
        let v = SimplexVertex {
            a,
            b,
            w: b - a,
            index_a: ia,
            index_b: ib,
        };
        if s.contains(&v) {
            return None;
        }
        s.push(v);
    }
    let [w0, w1, w2, w3] = s.vertices.map(|v| v.w);
    let (e1, e2, e3) = (w1 - w0, w2 - w0, w3 - w0);
    // Written so that a NaN counts as degenerate.
    let solid = match n {
        2 => e1.length_squared() > THIN * THIN * s.max_w_squared(),
        3 => e1.cross(e2).length() > THIN * e1.length() * e2.length(),
        4 => scalar::abs(det3(e1, e2, e3)) > THIN * e1.length() * e2.length() * e3.length(),
        _ => true,
    };
    solid.then_some(s)
}

/// The first vertex of a fresh start: the support of `D` towards the origin seen from B's
/// origin (B's origin minus A's), a guess at the closest region.
fn fresh_start(pa: &Proxy, pb: &Proxy) -> Simplex {
    let c = pb.pose.position - pa.pose.position;
    let dir = if c.length_squared() > 0.0 {
        -c
    } else {
        -Vec3::X
    };
    Simplex::single(support(pa, pb, dir))
}

/// True when the simplex's closest point `v` (on a simplex of `count` points) counts as
/// the origin: too short to give a normal at all (`|v|² <= 1e-20`, the floor of
/// [`Vec3::normalize_and_length`]: the answer "apart along a fallback normal" would be
/// wrong, "touching" lets EPA find the direction); or, on a vertex or an edge of `D`,
/// within [`GJK_OVERLAP_TOLERANCE`] of the size `size2` (the largest `|w|²` of every point
/// of `D` the run has taken, see [`gjk_cores`]). On a face of `D` there is no such test:
/// `v` is then along the face's normal, which is accurate at any distance, and its length
/// is the gap to within rounding, so the distance of nearly touching faces stays
/// monotonic in the gap down to rounding instead of dropping to 0 below a threshold.
/// False for NaN.
#[inline]
pub(super) fn touches_origin(v: Vec3, count: usize, size2: f32) -> bool {
    let tol2 = GJK_OVERLAP_TOLERANCE * GJK_OVERLAP_TOLERANCE;
    let vv = v.length_squared();
    vv <= GJK_NO_DIRECTION || (count < 3 && vv <= tol2 * size2)
}

/// True when the support point `w` of `D` along `−v` lies clearly past the origin: its
/// lower bound `v·w / |v|` on the distance is below `−GJK_OVERLAP_TOLERANCE · |w|`.
///
/// GJK ends on "apart" when `w` brings no progress. With the origin inside `D` but within
/// rounding of a triangle of the simplex (two concentric boxes, a segment through a box),
/// `v` is that tiny distance, the support along `−v` is deep on the other side, and the
/// signed volumes may still drop it (the origin reads as just outside the tetrahedron):
/// the run would stop with the cores "apart" by 1e-9 m while they overlap by the whole
/// depth. In exact arithmetic a stop has `v·w >= |v|² >= 0`, so a clearly negative
/// `v·w` is that rounding case: the origin is within `|v|` of a triangle of `D` and `D`
/// extends past it, so the cores overlap and EPA gives the depth. False for NaN.
#[inline]
fn beyond_origin(v: Vec3, w: Vec3) -> bool {
    // Squared, without the two square roots: `v·w < 0` and `(v·w)² > tol² |v|² |w|²`.
    let vw = v.dot(w);
    let tol2 = GJK_OVERLAP_TOLERANCE * GJK_OVERLAP_TOLERANCE;
    vw < 0.0 && vw * vw > tol2 * v.length_squared() * w.length_squared()
}

/// True when a closest point `v` on a simplex of `count` points has no trustworthy
/// direction (see [`GJK_DIRECTION_TOLERANCE`]): a vertex or an edge of `D` within the
/// tolerance of the origin. False for NaN.
#[inline]
fn direction_is_ambiguous(v: Vec3, count: usize, size2: f32) -> bool {
    let tol2 = GJK_DIRECTION_TOLERANCE * GJK_DIRECTION_TOLERANCE;
    count < 3 && v.length_squared() <= tol2 * size2
}

/// How a stop of the GJK loop ends (see `gjk_cores`).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
enum Stop {
    /// No support beyond the origin: the cores are apart.
    Separated,
    /// A support past the origin with `v` within rounding of it: they overlap.
    Overlapping,
    /// A support past the origin with `v` farther: f32 cannot tell (`gjk_f64::refine`).
    Undecided,
}

/// GJK between two cores with signed volumes, warm-started from `cache` and writing the
/// final simplex back to it.
pub(crate) fn gjk_cores(
    pa: &Proxy,
    pb: &Proxy,
    cache: &mut SimplexCache,
    max_iterations: u32,
) -> CoreDistance {
    let start = warm_start(pa, pb, cache).unwrap_or_else(|| fresh_start(pa, pb));
    // The overlap test's scale: the largest |w|² of every point of D taken so far, not
    // only of the current simplex. When the closest point is a vertex of D within
    // rounding of the origin (a sphere centred on a triangle's corner), the simplex
    // shrinks to that one vertex, |w| ≈ |v|, and a test relative to the simplex alone
    // would never fire: GJK would report the cores apart by 1e-21 m with a normal that is
    // rounding noise (or the fallback), not a direction of D's normal cone.
    let mut size2 = start.max_w_squared();
    // Two simplex buffers, swapped by reference: the grown simplex is built in place in
    // `simplex` and reduced into `next`; no simplex is copied in the loop.
    let mut buffers = (Simplex::default(), Simplex::default());
    start.reduce_into(&mut buffers.0);
    let (mut simplex, mut next) = (&mut buffers.0, &mut buffers.1);
    let mut v = simplex.closest();
    let mut status = GjkStatus::IterationLimit;
    let mut iterations = 0;
    let mut plateau = 0;
    let mut stop = None;
    while iterations < max_iterations {
        if simplex.count == 4 || touches_origin(v, simplex.count, size2) {
            status = GjkStatus::Overlapping;
            break;
        }
        iterations += 1;
        let w = support(pa, pb, -v);
        size2 = scalar::max(size2, w.w.length_squared());
        let vv = v.length_squared();
        // The stops below end on "apart" unless `w` shows `D` reaching clearly past the
        // origin along `−v` (see `beyond_origin`): then the origin lies within rounding of
        // the simplex with `D` on both sides of it, and the cores overlap.
        let v_now = v;
        // Only a `v` within the direction tolerance of the origin can be that rounding
        // case. A longer `v` with a negative `v·w` is a stop on a thin `D` where the
        // support's rounding tilts `w` (a 1.5 mm sphere 1.2 mm above an 8 m × 3 cm box
        // seen from a turned frame, fuzz finding `sphere-over-a-thin-box-a11fe352`):
        // apart, at the accurate `|v|`.
        let near_origin =
            v.length_squared() <= GJK_DIRECTION_TOLERANCE * GJK_DIRECTION_TOLERANCE * size2;
        // A support past the origin farther from it (`!near_origin`) leaves the stop
        // undecided: `gjk_f64::refine` continues from the simplex with exact closest
        // points (fuzz findings `plate-through-a-sphere-core-f50bc49a`: overlapping,
        // `sphere-over-a-thin-box-a11fe352`: apart).
        let apart = || {
            if !beyond_origin(v_now, w.w) {
                Stop::Separated
            } else if near_origin {
                Stop::Overlapping
            } else {
                Stop::Undecided
            }
        };
        // 1: the lower bound v·w/|v| is within the tolerance of the upper bound |v|.
        let gap = vv - v.dot(w.w);
        if gap <= GJK_RELATIVE_TOLERANCE * scalar::sqrt(vv) * w.w.length() {
            stop = Some(apart());
            break;
        }
        // 2: nothing new on the boundary.
        if simplex.contains(&w) {
            stop = Some(apart());
            break;
        }
        // The grown simplex, `simplex` with `w` pushed (popped again if it is not taken).
        let pushed = simplex.push(w);
        simplex.reduce_into(next);
        let v_next = next.closest();
        let vv_next = v_next.length_squared();
        if next.count < 4 {
            // 3: no progress: the sub-algorithm dropped `w` again, or the grown simplex
            // is farther by more than rounding. The previous simplex, the best, is kept.
            // Test 1 failed, so `w` lies below the plane through `v` by more than
            // rounding: the exact closest point of the grown simplex is closer. Near the
            // answer that gain is second order in the closest point's lateral error
            // and can be below f32 resolution of |v|², so a step that keeps |v|² equal
            // (within GJK_ROUNDING) is still taken: the point moves to the right feature.
            // A few such steps in a row mean f32 cannot tell the candidates apart: stop.
            let kept = next.used().iter().any(|u| u.same_as(&w));
            let rounding = GJK_ROUNDING * scalar::sqrt(vv * simplex.max_w_squared());
            let progress = kept && vv_next <= vv + rounding;
            if !progress {
                if pushed {
                    simplex.pop();
                }
                stop = Some(apart());
                break;
            }
            plateau = if vv_next < vv { 0 } else { plateau + 1 };
            if plateau > GJK_MAX_PLATEAU {
                core::mem::swap(&mut simplex, &mut next);
                v = v_next;
                stop = Some(apart());
                break;
            }
        }
        core::mem::swap(&mut simplex, &mut next);
        v = v_next;
    }
    // The final simplex is read where it is (no copy) unless f64 finishes the search: a
    // stop f32 cannot decide, or one apart on a sliver of `D` (coordinates f32 cannot
    // trust). At most `max_iterations` more supports.
    let in_f64 = match stop {
        Some(Stop::Undecided) => true,
        Some(Stop::Separated) => is_sliver(simplex),
        _ => false,
    };
    let refined;
    let simplex: &Simplex = if in_f64 {
        (refined, status) = gjk_f64::refine(pa, pb, simplex, size2, max_iterations);
        v = refined.closest();
        &refined
    } else {
        match stop {
            Some(Stop::Separated) => status = GjkStatus::Separated,
            Some(Stop::Overlapping) => status = GjkStatus::Overlapping,
            _ => {}
        }
        simplex
    };
    if status == GjkStatus::IterationLimit
        && (simplex.count == 4 || touches_origin(v, simplex.count, size2))
    {
        status = GjkStatus::Overlapping;
    }
    write_cache(simplex, cache);
    core_distance(pa, pb, simplex, status, iterations, size2)
}

/// Below this ratio of a triangle's `|n|` (twice its area) to its longest edge squared
/// (about the sine of its smallest angle), the triangle is a sliver: see [`is_sliver`].
const GJK_SLIVER: f32 = 1.0e-3;

/// True when the simplex is a triangle of `D` so thin that its barycentric coordinates
/// from projected areas ([`s2d`]) are unreliable: each area carries the rounding of the
/// longest edge squared, a few ulps of `L²`, against a total of `|n|`, so a coordinate is
/// off by about `10⁻⁷ L² / |n|` and a witness point slides that fraction of `L` along the
/// sliver. The closest point itself, the origin's projection on the plane, stays
/// accurate, and so does the distance. A sphere 2.3 cm from a hull whose two 8 m edges
/// meet at 3·10⁻⁵ rad got its point on the hull 6.6 mm along the edge, its witnesses
/// 0.9 mm further apart than the distance (fuzz finding `sphere-by-a-bent-sliver-hull-496c6ce0`).
/// False for NaN.
fn is_sliver(s: &Simplex) -> bool {
    if s.count != 3 {
        return false;
    }
    let [w0, w1, w2, _] = s.vertices.map(|v| v.w);
    let (n, longest) = normal_and_longest_edge(w0, w1, w2);
    n.length_squared() < GJK_SLIVER * GJK_SLIVER * longest * longest
}

/// GJK's answer from its final simplex and status (`size2`: the largest `|w|²` seen).
fn core_distance(
    pa: &Proxy,
    pb: &Proxy,
    simplex: &Simplex,
    status: GjkStatus,
    iterations: u32,
    size2: f32,
) -> CoreDistance {
    let v = simplex.closest();
    let (point_a, point_b) = simplex.witnesses();
    if status == GjkStatus::Overlapping {
        let c = pb.pose.position - pa.pose.position;
        CoreDistance {
            point_a,
            point_b,
            distance: 0.0,
            normal: c.normalize_or(Vec3::Y),
            iterations,
            status,
            simplex: *simplex,
            ambiguous: false,
        }
    } else {
        let (normal, distance) = v.normalize_and_length().unwrap_or((Vec3::Y, 0.0));
        CoreDistance {
            point_a,
            point_b,
            distance,
            normal,
            iterations,
            status,
            simplex: *simplex,
            ambiguous: direction_is_ambiguous(v, simplex.count, size2),
        }
    }
}

/// `core` (cores apart, from [`gjk_cores`]) with its search finished in f64
/// ([`gjk_f64::refine`]) when its closest point lies on a segment or a triangle of `D`
/// within [`GJK_REFINE_NEAR`] of `D`'s size; `None` otherwise. There f32 places the
/// closest point's direction and barycentric coordinates poorly: a sphere's centre 0.4 mm
/// from a hull's 15 m edge got its deepest point 19 mm along the edge and a depth 0.1 mm
/// off the other order's (fuzz finding `sphere-by-a-long-hull-edge-eaadbf85`). Used where
/// the witnesses and normal are the answer (the penetration of cores apart); distance
/// queries and time of impact keep the f32 answer, accurate in its length.
pub(crate) fn refined_near(pa: &Proxy, pb: &Proxy, core: &CoreDistance) -> Option<CoreDistance> {
    let size2 = core.simplex.max_w_squared();
    let v = core.simplex.closest();
    let near = v.length_squared() <= GJK_REFINE_NEAR * GJK_REFINE_NEAR * size2;
    if core.status != GjkStatus::Separated || core.simplex.count < 2 || !near {
        return None;
    }
    let (simplex, status) = gjk_f64::refine(pa, pb, &core.simplex, size2, MAX_GJK_ITERATIONS);
    Some(core_distance(
        pa,
        pb,
        &simplex,
        status,
        core.iterations,
        size2,
    ))
}

/// Store the simplex's vertex indices for the next call.
fn write_cache(s: &Simplex, cache: &mut SimplexCache) {
    *cache = SimplexCache::default();
    for (k, v) in s.used().iter().enumerate() {
        if let (Some(ia), Some(ib)) = (cache.index_a.get_mut(k), cache.index_b.get_mut(k)) {
            *ia = v.index_a;
            *ib = v.index_b;
            cache.count += 1;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::*;

    fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
        (a - b).length() <= tol
    }

    /// A simplex of the points `w` (no shapes behind them).
    fn simplex_of(ws: &[Vec3]) -> Simplex {
        let mut s = Simplex::default();
        for &w in ws {
            s.push(SimplexVertex {
                w,
                ..SimplexVertex::default()
            });
        }
        s
    }

    /// The fuzz finding's triangle (two 8 m edges at 3·10⁻⁵ rad) is a sliver, at any
    /// scale and turned; a right triangle, one at 0.1 rad, a segment and a triangle
    /// with a NaN are not.
    #[test]
    fn slivers_are_told_from_triangles_whose_areas_can_be_trusted() {
        let q = crate::math::Quat::from_xyzw(0.605, -0.0997, -0.631, 0.475).normalize();
        for scale in [1.0e-3, 1.0, 100.0] {
            let turned = |p: Vec3| q.rotate(p * scale);
            let sliver = [
                Vec3::new(0.0386, 0.0, 0.0),
                Vec3::new(0.0386, 0.0, 7.89),
                Vec3::new(0.0386, 0.000244, -7.8),
            ];
            assert!(is_sliver(&simplex_of(&sliver.map(turned))), "{scale}");
            let right = [Vec3::X, Vec3::Y, Vec3::ZERO];
            assert!(!is_sliver(&simplex_of(&right.map(turned))), "{scale}");
            let thin = [Vec3::ZERO, Vec3::X, Vec3::new(0.5, 0.05, 0.0)];
            assert!(!is_sliver(&simplex_of(&thin.map(turned))), "{scale}");
        }
        assert!(!is_sliver(&simplex_of(&[Vec3::ZERO, Vec3::X])));
        let nan = [Vec3::ZERO, Vec3::X, Vec3::new(f32::NAN, 0.0, 0.0)];
        assert!(!is_sliver(&simplex_of(&nan)));
    }

    fn combine(p: &[Vec3], l: &[f32]) -> Vec3 {
        let mut v = Vec3::ZERO;
        for (p, l) in p.iter().zip(l) {
            v += *p * *l;
        }
        v
    }

    #[test]
    fn s1d_projects_inside_and_clamps_outside() {
        let a = Vec3::new(-1.0, 2.0, 0.0);
        let b = Vec3::new(3.0, 2.0, 0.0);
        // Projection of the origin is (0, 2, 0): λ = (3/4, 1/4).
        let (l, p) = s1d(a, b);
        assert!((l[0] - 0.75).abs() < 1e-6 && (l[1] - 0.25).abs() < 1e-6);
        assert!(close(p, Vec3::new(0.0, 2.0, 0.0), 1e-6));
        // Segment entirely at x > 0: the closest point is the end at x = 1.
        assert_eq!(
            s1d(Vec3::new(1.0, 1.0, 0.0), Vec3::new(2.0, 1.0, 0.0)).0,
            [1.0, 0.0]
        );
        assert_eq!(
            s1d(Vec3::new(2.0, 1.0, 0.0), Vec3::new(1.0, 1.0, 0.0)).0,
            [0.0, 1.0]
        );
        // Coincident points keep the first.
        assert_eq!(s1d(Vec3::X, Vec3::X), ([1.0, 0.0], Vec3::X));
    }

    #[test]
    fn s2d_matches_brute_force_on_random_triangles() {
        // Oracle: minimum over a fine barycentric grid is too coarse; use the exact
        // answer: the min over the interior projection (if inside) and the three edges.
        let mut rng = crate::rng::SplitMix64::new(11);
        for _ in 0..2000 {
            let p = [
                Vec3::new(
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                ),
                Vec3::new(
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                ),
                Vec3::new(
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                    rng.range(-2.0, 2.0),
                ),
            ];
            let (l, v) = s2d(p[0], p[1], p[2]);
            // The point and the coordinates describe the same point (1e-5: ~40 ulps).
            assert!(close(v, combine(&p, &l), 1e-5));
            // Oracle in f64-free form: edges by s1d-independent clamped projection, and
            // the interior by solving the 2x2 normal equations.
            let mut best = f32::INFINITY;
            for (i, j) in [(0, 1), (1, 2), (2, 0)] {
                let (a, b) = (p[i], p[j]);
                let t = b - a;
                let s = (-a.dot(t) / t.dot(t)).clamp(0.0, 1.0);
                best = best.min((a + t * s).length());
            }
            let (e1, e2) = (p[1] - p[0], p[2] - p[0]);
            let (d11, d12, d22) = (e1.dot(e1), e1.dot(e2), e2.dot(e2));
            let (r1, r2) = (-p[0].dot(e1), -p[0].dot(e2));
            let den = d11 * d22 - d12 * d12;
            if den > 1e-6 {
                let u = (r1 * d22 - r2 * d12) / den;
                let w = (r2 * d11 - r1 * d12) / den;
                if u >= 0.0 && w >= 0.0 && u + w <= 1.0 {
                    best = best.min((p[0] + e1 * u + e2 * w).length());
                }
            }
            // Both are f32 computations on coordinates of size 2: 1e-5 is ~40 ulps.
            assert!(
                (v.length() - best).abs() < 1e-5,
                "{p:?} {l:?} {} {best}",
                v.length()
            );
            assert!(l.iter().all(|x| *x >= 0.0) && (l.iter().sum::<f32>() - 1.0).abs() < 1e-5);
        }
    }

    #[test]
    fn s3d_reports_inside_with_barycentric_coordinates() {
        // A regular tetrahedron around (0.1, 0.2, −0.1): the origin is inside.
        let shift = Vec3::new(0.1, 0.2, -0.1);
        let p = [
            Vec3::new(1.0, 1.0, 1.0) + shift,
            Vec3::new(1.0, -1.0, -1.0) + shift,
            Vec3::new(-1.0, 1.0, -1.0) + shift,
            Vec3::new(-1.0, -1.0, 1.0) + shift,
        ];
        let (l, v) = s3d(p[0], p[1], p[2], p[3]);
        assert_eq!(v, Vec3::ZERO);
        assert!(l.iter().all(|x| *x > 0.0), "{l:?}");
        assert!(close(combine(&p, &l), Vec3::ZERO, 1e-6));
        assert!((l.iter().sum::<f32>() - 1.0).abs() < 1e-6);
        // Moved 5 m along +x, the nearest feature is the edge p2 p3 on the plane x = 4.1;
        // the origin projects on it at (4.1, 0.05, 0.05) (parameter 4.6 / 8 from p2).
        let q = p.map(|x| x + Vec3::new(5.0, 0.0, 0.0));
        let (l, v) = s3d(q[0], q[1], q[2], q[3]);
        assert_eq!((l[0], l[1]), (0.0, 0.0), "{l:?}");
        assert!(close(v, Vec3::new(4.1, 0.05, 0.05), 1e-5));
        assert!(
            close(combine(&q, &l), Vec3::new(4.1, 0.05, 0.05), 1e-5),
            "{l:?}"
        );
    }

    #[test]
    fn s2d_point_is_orthogonal_to_a_sliver_triangle() {
        // A face of D from a 1.6 mm box edge against a 1.8 m triangle edge (found by the
        // fuzz-like stress run): the area ratios lose about four digits here, so the
        // point is the projection, orthogonal to the plane: v·wᵢ = |v|² for all three
        // vertices. Tolerance 1e-9: a few ulps of |v|² ≈ 1.1e-4.
        let w = [
            Vec3::new(-0.401_841_7, -0.798_890_1, -0.210_469_32),
            Vec3::new(0.349_758_4, 0.701_109_9, 0.164_530_8),
            Vec3::new(-0.400_241_67, -0.798_890_1, -0.210_469_32),
        ];
        let (l, v) = s2d(w[0], w[1], w[2]);
        assert!(l.iter().all(|x| *x > 0.0), "{l:?}");
        for p in w {
            assert!(
                (v.dot(p) - v.length_squared()).abs() < 1e-9,
                "{}",
                v.dot(p) - v.dot(v)
            );
        }
    }

    #[test]
    fn capped_gjk_returns_a_finite_upper_bound() {
        let a = Shape::cuboid(Vec3::new(1.0, 0.5, 0.7)).unwrap();
        let b = Shape::cuboid(Vec3::new(0.3, 0.8, 0.4)).unwrap();
        let mut rng = crate::rng::SplitMix64::new(5);
        for _ in 0..200 {
            let b_in_a = Iso::new(rng.unit_vector() * 3.0, rng.rotation());
            let full = distance_in_a(&a, &b, &b_in_a, &mut SimplexCache::default());
            let capped = distance_in_a_capped(&a, &b, &b_in_a, &mut SimplexCache::default(), 1);
            assert!(capped.iterations <= 1);
            assert!(capped.distance.is_finite() && capped.point_a.is_finite());
            assert!((capped.normal.length() - 1.0).abs() < 1e-5);
            // A partial simplex is a subset of D: its distance bounds the true one above
            // (1e-5: rounding of both answers at a 3 m scale).
            assert!(capped.distance >= full.distance - 1e-5);
            if capped.status != GjkStatus::IterationLimit {
                assert!((capped.distance - full.distance).abs() < 1e-4);
            }
        }
    }

    /// An answer whose ten numbers are finite comes back as it is, whatever their size;
    /// one infinity or NaN in any of them sends it down the fallback, which answers with
    /// finite numbers and [`GjkStatus::IterationLimit`].
    #[test]
    fn finite_answers_pass_and_any_non_finite_number_falls_back() {
        let good = DistanceOutput {
            distance: f32::MAX,
            point_a: Vec3::new(-f32::MAX, 1.0e-45, -0.0),
            point_b: Vec3::new(3.0, f32::MIN_POSITIVE, -7.5),
            normal: Vec3::Y,
            iterations: 4,
            status: GjkStatus::Separated,
        };
        assert_eq!(finite_or_fallback(good, Vec3::X, Vec3::Z), good);
        for field in 0..10 {
            for bad in [f32::INFINITY, f32::NEG_INFINITY, f32::NAN] {
                let mut out = good;
                let slot = match field {
                    0 => &mut out.distance,
                    1 => &mut out.point_a.x,
                    2 => &mut out.point_a.y,
                    3 => &mut out.point_a.z,
                    4 => &mut out.point_b.x,
                    5 => &mut out.point_b.y,
                    6 => &mut out.point_b.z,
                    7 => &mut out.normal.x,
                    8 => &mut out.normal.y,
                    _ => &mut out.normal.z,
                };
                *slot = bad;
                let fixed = finite_or_fallback(out, Vec3::X, Vec3::Z);
                assert_eq!(fixed.status, GjkStatus::IterationLimit, "{field} {bad}");
                assert!(fixed.distance.is_finite() && fixed.distance >= 0.0);
                assert!(fixed.point_a.is_finite() && fixed.point_b.is_finite());
                assert!((fixed.normal.length() - 1.0).abs() < 1e-6, "{field} {bad}");
            }
        }
    }
}
