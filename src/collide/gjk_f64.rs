//! GJK's sub-algorithm in f64, for the stops the f32 loop cannot decide.
//!
//! The f32 loop of [`super::gjk::gjk_cores`] can stop on "no progress" with the support
//! point `w` along `−v` clearly past the origin. That happens when the simplex is metres
//! long and its closest point `v` is a fraction of a millimetre from the origin: `v`
//! carries the rounding of the vertices' coordinates (an ulp of 8 m is 5e-7 m), so its
//! direction is off by that error over `|v|` (2e-3 rad at 0.24 mm), the support along the
//! tilted `−v` is a far vertex, and the sub-algorithm, rounding the same way, drops it
//! again. From f32 alone the stop cannot tell "the cores overlap" (a sphere's centre
//! 3.5 mm inside an 8 m × 8 mm plate, fuzz finding `plate-through-a-sphere-core-f50bc49a`;
//! two 3.3 m boxes 7.6 mm deep, `big-boxes-tilted-normal-5c2ee9ea`) from "apart" (a sphere
//! 1.2 mm over an 8 m × 3 cm box, `sphere-over-a-thin-box-a11fe352`).
//!
//! It is also how [`super::gjk::refined_near`] finishes a search that stopped with the
//! cores apart by less than 1e-3 of the simplex's size, where the answer's witnesses and
//! normal matter (a penetration through the radii).
//!
//! [`refine`] continues the search from that simplex with the closest point and the
//! barycentric coordinates computed in f64. The vertices stay the f32 support points of
//! the cores (`w = b − a` is exact in f64), so the search is exact for the polytopes the
//! f32 coordinates describe; only the search direction is rounded back to f32 (6e-8 rad),
//! which can cost a support vertex within an ulp of the best one, never the decision.
//! Both cases are rare (no golden line or scene checksum changed when they came), so
//! their cost does not show; the f64
//! operations are `+ − × ÷` and `sqrt`, correctly rounded on every target.

use super::gjk::{support, touches_origin, GjkStatus, Simplex, SimplexVertex};
use super::Proxy;
use crate::math::scalar;
use crate::math::vec64::{self, Vec64};

/// Test 1 of the f64 loop: stop when `|v|² − v·w <= F64_RELATIVE_TOLERANCE · |v| |w|`.
/// The f64 rounding of `|v|² − v·w` is about 1e-15 of `|v| |w|`; 1e-10 stops well above
/// it and bounds the distance's error by 1e-10 of the shapes' size.
const F64_RELATIVE_TOLERANCE: f64 = 1.0e-10;

/// `w = b − a` of a simplex vertex, exact in f64.
fn w64(v: &SimplexVertex) -> Vec64 {
    Vec64::of(v.b) - Vec64::of(v.a)
}

/// A simplex with its closest point in f64.
#[derive(Clone, Copy, Debug, Default)]
struct Simplex64 {
    /// The vertices; the first `count` are used.
    vertices: [SimplexVertex; 4],
    /// Barycentric coordinates of the closest point.
    lambdas: [f64; 4],
    /// Vertices in use, 1 to 4.
    count: usize,
    /// The point of the simplex closest to the origin.
    point: Vec64,
}

impl Simplex64 {
    fn used(&self) -> &[SimplexVertex] {
        self.vertices.get(..self.count.min(4)).unwrap_or(&[])
    }

    /// The smallest sub-simplex of `vertices` (1 to 4 of them) holding the point closest
    /// to the origin, with its coordinates; vertices keep their order. `None` for an empty
    /// slice or when no coordinate is positive (only NaN coordinates do that).
    fn reduced(vertices: &[SimplexVertex]) -> Option<Simplex64> {
        let w = |k: usize| vertices.get(k).map(w64).unwrap_or_default();
        let (lambdas, point) = match vertices.len() {
            1 => ([1.0, 0.0, 0.0, 0.0], w(0)),
            2 => {
                let ([l0, l1], p) = closest_on_segment(w(0), w(1));
                ([l0, l1, 0.0, 0.0], p)
            }
            3 => {
                let ([l0, l1, l2], p) = closest_on_triangle(w(0), w(1), w(2));
                ([l0, l1, l2, 0.0], p)
            }
            4 => closest_on_tetrahedron(w(0), w(1), w(2), w(3)),
            _ => return None,
        };
        let mut out = Simplex64 {
            point,
            ..Simplex64::default()
        };
        for (v, &l) in vertices.iter().zip(lambdas.iter()) {
            if l > 0.0 {
                if let (Some(sv), Some(sl)) = (
                    out.vertices.get_mut(out.count),
                    out.lambdas.get_mut(out.count),
                ) {
                    *sv = *v;
                    *sl = l;
                    out.count += 1;
                }
            }
        }
        (out.count > 0).then_some(out)
    }

    /// The f32 simplex: the same vertices, the coordinates rounded and the point rounded.
    #[allow(clippy::cast_possible_truncation)]
    fn rounded(&self) -> Simplex {
        let mut s = Simplex::default();
        for (v, &l) in self.used().iter().zip(self.lambdas.iter()) {
            if let Some(slot) = s.lambdas.get_mut(s.count) {
                *slot = l as f32;
            }
            s.push(*v);
        }
        s.point = self.point.rounded();
        s
    }
}

/// Closest point of the segment `a b` to the origin: coordinates and point.
fn closest_on_segment(a: Vec64, b: Vec64) -> ([f64; 2], Vec64) {
    let t = b - a;
    let tt = t.length_squared();
    if !(tt > 0.0 && tt.is_finite()) {
        return ([1.0, 0.0], a);
    }
    let s = -a.dot(t) / tt;
    if s >= 1.0 {
        ([0.0, 1.0], b)
    } else if s > 0.0 {
        ([1.0 - s, s], a + t * s)
    } else {
        ([1.0, 0.0], a)
    }
}

/// Closest point of the triangle `a b c` to the origin: coordinates and point. The
/// origin's projection on the plane has coordinates `n·(b × c)`, `n·(c × a)`, `n·(a × b)`
/// over `n·n` (`n = (b − a) × (c − a)`); if one is not positive the closest point lies
/// on an edge opposite such a vertex.
fn closest_on_triangle(a: Vec64, b: Vec64, c: Vec64) -> ([f64; 3], Vec64) {
    let n = (b - a).cross(c - a);
    let nn = n.length_squared();
    let mut search = [true; 3];
    if nn > 0.0 && nn.is_finite() {
        let l = [n.dot(b.cross(c)), n.dot(c.cross(a)), n.dot(a.cross(b))];
        if l.iter().all(|&x| x > 0.0) {
            let sum = l[0] + l[1] + l[2];
            return ([l[0] / sum, l[1] / sum, l[2] / sum], n * (a.dot(n) / nn));
        }
        search = l.map(|x| x <= 0.0 || x.is_nan());
    }
    let mut nearest = Nearest::new([1.0, 0.0, 0.0], a);
    if search[0] {
        let ([lb, lc], p) = closest_on_segment(b, c);
        nearest.consider([0.0, lb, lc], p);
    }
    if search[1] {
        let ([la, lc], p) = closest_on_segment(a, c);
        nearest.consider([la, 0.0, lc], p);
    }
    if search[2] {
        let ([la, lb], p) = closest_on_segment(a, b);
        nearest.consider([la, lb, 0.0], p);
    }
    nearest.best
}

/// The candidate (coordinates, point) nearest the origin among those considered; the
/// first of equals.
struct Nearest<const K: usize> {
    best: ([f64; K], Vec64),
    distance2: f64,
}

impl<const K: usize> Nearest<K> {
    /// A search whose answer, if nothing is considered, is `fallback` at `point`.
    fn new(fallback: [f64; K], point: Vec64) -> Self {
        Nearest {
            best: (fallback, point),
            distance2: f64::INFINITY,
        }
    }

    fn consider(&mut self, l: [f64; K], p: Vec64) {
        let d = p.length_squared();
        if d < self.distance2 {
            self.distance2 = d;
            self.best = (l, p);
        }
    }
}

/// `a · (b × c)`.
fn det3(a: Vec64, b: Vec64, c: Vec64) -> f64 {
    a.dot(b.cross(c))
}

/// Closest point of the tetrahedron `a b c d` to the origin: coordinates (the cofactors
/// of Cramer's rule over `det M`, as in the f32 `s3d`) and point; the faces opposite the
/// vertices of the wrong sign are searched when the origin is outside.
fn closest_on_tetrahedron(a: Vec64, b: Vec64, c: Vec64, d: Vec64) -> ([f64; 4], Vec64) {
    let cof = [-det3(b, c, d), det3(a, c, d), -det3(a, b, d), det3(a, b, c)];
    let det = cof[0] + cof[1] + cof[2] + cof[3];
    let inside = cof.map(|x| (det > 0.0 && x > 0.0) || (det < 0.0 && x < 0.0));
    if inside == [true; 4] {
        return (cof.map(|x| x / det), Vec64::default());
    }
    let mut nearest = Nearest::new([1.0, 0.0, 0.0, 0.0], a);
    if !inside[0] {
        let ([lb, lc, ld], p) = closest_on_triangle(b, c, d);
        nearest.consider([0.0, lb, lc, ld], p);
    }
    if !inside[1] {
        let ([la, lc, ld], p) = closest_on_triangle(a, c, d);
        nearest.consider([la, 0.0, lc, ld], p);
    }
    if !inside[2] {
        let ([la, lb, ld], p) = closest_on_triangle(a, b, d);
        nearest.consider([la, lb, 0.0, ld], p);
    }
    if !inside[3] {
        let ([la, lb, lc], p) = closest_on_triangle(a, b, c);
        nearest.consider([la, lb, lc, 0.0], p);
    }
    nearest.best
}

/// GJK from `start` (the simplex an undecided f32 stop ended on) with the sub-algorithm
/// in f64, at most `max_iterations` supports; `size2` is the largest `|w|²` seen so far.
/// Returns the final simplex (coordinates and point rounded to f32) and
/// [`GjkStatus::Overlapping`] or [`GjkStatus::Separated`] (or
/// [`GjkStatus::IterationLimit`] at the cap with the origin still outside).
pub(crate) fn refine(
    pa: &Proxy,
    pb: &Proxy,
    start: &Simplex,
    mut size2: f32,
    max_iterations: u32,
) -> (Simplex, GjkStatus) {
    let Some(mut s) = Simplex64::reduced(start.used()) else {
        return (*start, GjkStatus::Separated);
    };
    let overlapping = |s: &Simplex64, size2: f32| {
        s.count == 4 || touches_origin(s.point.rounded(), s.count, size2)
    };
    let mut status = GjkStatus::IterationLimit;
    for _ in 0..max_iterations {
        if overlapping(&s, size2) {
            status = GjkStatus::Overlapping;
            break;
        }
        let w = support(pa, pb, (-s.point).rounded());
        size2 = scalar::max(size2, w.w.length_squared());
        let vv = s.point.length_squared();
        let ww = w64(&w);
        // 1: the lower bound v·w/|v| meets the upper bound |v| (within f64 rounding).
        let gap = vv - s.point.dot(ww);
        let bound = F64_RELATIVE_TOLERANCE * vec64::sqrt(vv * ww.length_squared());
        if gap <= bound || s.used().iter().any(|u| u.same_as(&w)) {
            status = GjkStatus::Separated;
            break;
        }
        // 2: the grown simplex is no closer: nothing left to gain (exact arithmetic
        // always gains when test 1 fails; f64 rounding leaves a margin of 1e-15).
        let mut grown = [w; 4];
        for (slot, v) in grown.iter_mut().zip(s.used()) {
            *slot = *v;
        }
        let Some(next) = grown.get(..s.count + 1).and_then(Simplex64::reduced) else {
            status = GjkStatus::Separated;
            break;
        };
        if next.count < 4 && next.point.length_squared() >= vv {
            status = GjkStatus::Separated;
            break;
        }
        s = next;
    }
    if status == GjkStatus::IterationLimit && overlapping(&s, size2) {
        status = GjkStatus::Overlapping;
    }
    (s.rounded(), status)
}

#[cfg(test)]
mod tests {
    use super::*;

    fn v(x: f64, y: f64, z: f64) -> Vec64 {
        Vec64 { x, y, z }
    }

    #[test]
    fn segment_projects_inside_and_clamps_outside() {
        let (l, p) = closest_on_segment(v(-1.0, 2.0, 0.0), v(3.0, 2.0, 0.0));
        assert_eq!(l, [0.75, 0.25]);
        assert_eq!(p, v(0.0, 2.0, 0.0));
        let (l, p) = closest_on_segment(v(1.0, 2.0, 0.0), v(3.0, 2.0, 0.0));
        assert_eq!((l, p), ([1.0, 0.0], v(1.0, 2.0, 0.0)));
        let (l, p) = closest_on_segment(v(3.0, 2.0, 0.0), v(1.0, 2.0, 0.0));
        assert_eq!((l, p), ([0.0, 1.0], v(1.0, 2.0, 0.0)));
    }

    #[test]
    fn triangle_projects_inside_and_searches_the_edges_outside() {
        // The plane z = 2 over the origin's projection (0, 0, 2) inside.
        let (a, b, c) = (v(-1.0, -1.0, 2.0), v(3.0, -1.0, 2.0), v(-1.0, 3.0, 2.0));
        let (l, p) = closest_on_triangle(a, b, c);
        assert_eq!(p, v(0.0, 0.0, 2.0));
        assert_eq!(l, [0.5, 0.25, 0.25]);
        // Shifted right: the closest point is on edge a c at x = 1.
        let s = v(2.0, 0.0, 0.0);
        let (l, p) = closest_on_triangle(a + s, b + s, c + s);
        assert_eq!(p, v(1.0, 0.0, 2.0));
        assert_eq!(l, [0.75, 0.0, 0.25]);
    }

    #[test]
    fn tetrahedron_reports_the_origin_inside_and_the_nearest_face_outside() {
        let (a, b, c, d) = (
            v(-1.0, -1.0, -1.0),
            v(3.0, -1.0, -1.0),
            v(-1.0, 3.0, -1.0),
            v(-1.0, -1.0, 3.0),
        );
        let (l, p) = closest_on_tetrahedron(a, b, c, d);
        assert_eq!(p, Vec64::default());
        assert_eq!(l, [0.25; 4]);
        let s = v(0.0, 0.0, 2.0);
        let (l, p) = closest_on_tetrahedron(a + s, b + s, c + s, d + s);
        assert_eq!(p, v(0.0, 0.0, 1.0));
        assert_eq!(l, [0.5, 0.25, 0.25, 0.0]);
    }
}
