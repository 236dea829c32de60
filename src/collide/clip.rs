//! Polygon clipping for face contacts (Sutherland–Hodgman against the side planes of a
//! reference face) and reduction of the clipped points to at most 4.
//!
//! Everything here works in one frame (the caller's, A's frame in the narrow phase) and on
//! [`Face`](crate::shape::Face)s already moved into it.
//!
//! Feature ids follow each clipped point (Box2D `b2ClipPolygons`, Gregorius, "Robust
//! Contact Creation for Physics Simulations", GDC 2015): an incident vertex that survives
//! every side plane is (reference face, incident vertex); a point made where the incident
//! edge `e` crosses reference side plane `k` is (reference edge `k`, incident edge `e`); a
//! reference corner that lies inside the incident polygon is (reference vertex, incident
//! face). These pairs stay the same for as long as the same features touch.

use super::manifold::Candidate;
use crate::math::{scalar, Vec3};
use crate::shape::{FeatureId, Polygon, MAX_FACE_VERTICES};

/// Most points a clipped polygon can have: each of the at most `MAX_FACE_VERTICES` side
/// planes adds at most one vertex to an incident polygon of at most `MAX_FACE_VERTICES`.
pub(crate) const MAX_CLIP_POINTS: usize = 2 * MAX_FACE_VERTICES;

/// Relative tolerance of [`closest_feature`]: a fraction of the face's longest edge.
const FEATURE_TOLERANCE: f32 = 1.0e-4;

/// "No reference edge": the segment leaving a clip vertex lies inside the reference face.
const NO_EDGE: u8 = u8::MAX;

/// One vertex of a polygon being clipped, with the features it lies on.
#[derive(Clone, Copy, Debug, PartialEq)]
pub(crate) struct ClipVertex {
    /// The point (caller's frame, m), on the incident polygon.
    pub point: Vec3,
    /// The reference feature it lies on (face, side edge or corner).
    pub ref_id: FeatureId,
    /// The incident feature it lies on (vertex, edge or face).
    pub inc_id: FeatureId,
    /// Reference side plane the segment to the next vertex lies on, or [`NO_EDGE`].
    seg_ref_edge: u8,
    /// Incident feature the segment to the next vertex lies on.
    seg_inc: FeatureId,
}

/// A clipped polygon (or polyline): at most [`MAX_CLIP_POINTS`] vertices in order. The
/// storage is not initialised up front (a `heapless::Vec`), so an empty polygon costs
/// nothing to make.
#[derive(Clone, Debug)]
pub(crate) struct ClipPolygon {
    vertices: heapless::Vec<ClipVertex, MAX_CLIP_POINTS>,
}

impl ClipPolygon {
    /// An empty polygon.
    pub(crate) const fn new() -> ClipPolygon {
        ClipPolygon {
            vertices: heapless::Vec::new(),
        }
    }

    /// Append a vertex; ignored when full (cannot happen for faces within
    /// `MAX_FACE_VERTICES`, see [`MAX_CLIP_POINTS`]).
    fn push(&mut self, v: ClipVertex) {
        // A full polygon hands the vertex back: dropped, as documented.
        let _ = self.vertices.push(v);
    }

    /// The vertices in use.
    pub fn vertices(&self) -> &[ClipVertex] {
        &self.vertices
    }

    fn is_empty(&self) -> bool {
        self.vertices.is_empty()
    }
}

/// Outward normal of the side plane through reference edge `k` (from vertex `k` to
/// `k + 1`): `(v₁ − v₀) × n`, outward for a polygon counter-clockwise about `n`. Not
/// normalised: only its sign is used, and `d = s · (p − v₀)` scales with it.
#[inline]
fn side_plane(reference: &impl Polygon, k: usize) -> (Vec3, Vec3) {
    let verts = reference.points();
    let n = verts.len();
    let v0 = verts.get(k).copied().unwrap_or(Vec3::ZERO);
    let next = if k + 1 < n {
        verts.get(k + 1)
    } else {
        verts.first()
    };
    let v1 = next.copied().unwrap_or(v0);
    ((v1 - v0).cross(reference.normal()), v0)
}

/// The reference feature of a point made on side plane `k` from a segment that lay on
/// `seg_ref_edge`: edge `k` when the segment was inside the face, else the corner shared
/// by the two side edges (edge `j` ends where edge `j + 1` starts).
fn reference_feature(reference: &impl Polygon, seg_ref_edge: u8, k: usize) -> FeatureId {
    let n = reference.points().len();
    let edge_k = reference
        .edge_ids()
        .get(k)
        .copied()
        .unwrap_or(reference.id());
    if seg_ref_edge == NO_EDGE || n == 0 {
        return edge_k;
    }
    let j = seg_ref_edge as usize;
    // (i + 1) mod n for i < n, without a division.
    let succ = |i: usize| if i + 1 >= n { 0 } else { i + 1 };
    let corner = if succ(j) == k {
        reference.vertex_ids().get(k)
    } else if succ(k) == j {
        reference.vertex_ids().get(j)
    } else {
        None
    };
    corner.copied().unwrap_or(edge_k)
}

/// The point where segment `p → q` crosses the plane, from the signed plane distances
/// `dp` and `dq` of opposite strict signs: `p + (q − p) dp / (dp − dq)`. The division is
/// safe: `dp − dq` is non-zero when the signs differ strictly.
#[inline]
fn crossing(p: Vec3, q: Vec3, dp: f32, dq: f32) -> Vec3 {
    let t = scalar::clamp(dp / (dp - dq), 0.0, 1.0);
    p + (q - p) * t
}

/// Clip `input` against reference side plane `k` into `out` (emptied first), keeping the
/// part with `d <= 0` (Sutherland–Hodgman, 1974). A point is made only where a segment
/// crosses the plane strictly, so a vertex lying on the plane is not doubled. `closed`
/// says whether the last vertex joins the first (a polygon) or not (a segment).
///
/// False, with `out` untouched, when every vertex has `d <= 0`: the clip would copy the
/// input as it is (nothing is dropped, no segment crosses), so the input stands.
fn clip_by_side_plane(
    input: &ClipPolygon,
    out: &mut ClipPolygon,
    reference: &impl Polygon,
    k: usize,
    incident_face: FeatureId,
    closed: bool,
) -> bool {
    let (s, v0) = side_plane(reference, k);
    let verts = input.vertices();
    let n = verts.len();
    // Every vertex's signed distance, once. A NaN distance drops its vertex below, so it
    // counts as outside here.
    let mut d = [0.0f32; MAX_CLIP_POINTS];
    let mut outside = false;
    for (di, v) in d.iter_mut().zip(verts) {
        *di = s.dot(v.point - v0);
        outside |= *di > 0.0 || di.is_nan();
    }
    if !outside {
        return false;
    }
    out.vertices.clear();
    // Segments i → i + 1; the closing one only for a polygon.
    let segments = if closed && n > 2 {
        n
    } else {
        n.saturating_sub(1)
    };
    for (i, p) in verts.iter().enumerate() {
        let dp = d.get(i).copied().unwrap_or(0.0);
        if dp <= 0.0 {
            out.push(*p);
        }
        if i >= segments {
            continue;
        }
        let j = if i + 1 < n { i + 1 } else { 0 };
        let dq = d.get(j).copied().unwrap_or(0.0);
        let exits = dp < 0.0 && dq > 0.0;
        let enters = dp > 0.0 && dq < 0.0;
        if !(exits || enters) {
            continue;
        }
        let Some(q) = verts.get(j) else { continue };
        let ref_id = reference_feature(reference, p.seg_ref_edge, k);
        let (seg_ref_edge, seg_inc) = if exits {
            // From here the clipped boundary runs along side plane k, inside the
            // incident polygon, until it re-enters.
            (k as u8, incident_face)
        } else {
            (p.seg_ref_edge, p.seg_inc)
        };
        out.push(ClipVertex {
            point: crossing(p.point, q.point, dp, dq),
            ref_id,
            inc_id: p.seg_inc,
            seg_ref_edge,
            seg_inc,
        });
    }
    true
}

/// Two clipping buffers the side planes alternate between, borrowed from two polygons
/// the caller keeps as separate locals: their storage is not initialised, so making
/// them costs two length fields. (One struct holding both polygons by value cost a
/// 912-byte `memset` per clip: the compiler folds its making into one constant and
/// zeroes it up to the second polygon's length.) The result is borrowed from them,
/// never copied.
#[derive(Debug)]
pub(crate) struct ClipBuffers<'b> {
    front: &'b mut ClipPolygon,
    back: &'b mut ClipPolygon,
}

impl<'b> ClipBuffers<'b> {
    /// The buffers `front` and `back` (emptied as they are used).
    pub(crate) fn new(front: &'b mut ClipPolygon, back: &'b mut ClipPolygon) -> ClipBuffers<'b> {
        ClipBuffers { front, back }
    }

    /// Clip the incident polygon against the side planes of the reference face (both in
    /// the same frame). The result lies on the incident polygon, inside the reference
    /// face's prism; points are not yet filtered by depth. A 1-vertex incident face gives
    /// that vertex when it is inside; a 2-vertex one is clipped as a segment.
    pub(crate) fn polygon(
        &mut self,
        reference: &impl Polygon,
        incident: &impl Polygon,
    ) -> &ClipPolygon {
        self.front.vertices.clear();
        let points = incident.points();
        let (vertex_ids, edge_ids) = (incident.vertex_ids(), incident.edge_ids());
        for (k, &point) in points.iter().enumerate() {
            self.front.push(ClipVertex {
                point,
                ref_id: reference.id(),
                inc_id: vertex_ids.get(k).copied().unwrap_or(incident.id()),
                seg_ref_edge: NO_EDGE,
                seg_inc: edge_ids.get(k).copied().unwrap_or(incident.id()),
            });
        }
        self.run(reference, incident.id(), points.len() > 2)
    }

    /// Clip the segment `p0 → p1` (ids `vertex_ids`, edge id `edge_id`) against the side
    /// planes of the reference face: at most 2 points.
    pub(crate) fn segment(
        &mut self,
        reference: &impl Polygon,
        p0: Vec3,
        p1: Vec3,
        vertex_ids: [FeatureId; 2],
        edge_id: FeatureId,
    ) -> &ClipPolygon {
        self.front.vertices.clear();
        for (p, id) in [(p0, vertex_ids[0]), (p1, vertex_ids[1])] {
            self.front.push(ClipVertex {
                point: p,
                ref_id: reference.id(),
                inc_id: id,
                seg_ref_edge: NO_EDGE,
                seg_inc: edge_id,
            });
        }
        self.run(reference, edge_id, false)
    }

    /// Run every side plane of `reference` over the front buffer in edge order, back and
    /// forth between the two buffers; then drop the points that lie outside the reference
    /// face's box (see [`FaceBox`]), unless the face is right-angled (a box's face): its
    /// side planes keep no point the box test would drop (tested), so the test is left
    /// out (a few per cent of a box–box query).
    fn run<R: Polygon>(
        &mut self,
        reference: &R,
        incident_face: FeatureId,
        closed: bool,
    ) -> &ClipPolygon {
        let out = self.side_planes(reference, incident_face, closed);
        if R::RIGHT_ANGLED {
            return out;
        }
        if let Some(face_box) = FaceBox::of(reference) {
            out.vertices.retain(|v| face_box.holds(v.point));
        }
        out
    }

    /// Run every side plane of `reference` over the front buffer in edge order, back and
    /// forth between the two buffers (a plane that cuts nothing leaves the polygon where
    /// it is).
    fn side_planes(
        &mut self,
        reference: &impl Polygon,
        incident_face: FeatureId,
        closed: bool,
    ) -> &mut ClipPolygon {
        let planes = reference.points().len();
        if planes < 3 {
            return self.front;
        }
        let mut in_front = true;
        for k in 0..planes {
            let (from, to) = if in_front {
                (&*self.front, &mut *self.back)
            } else {
                (&*self.back, &mut *self.front)
            };
            if clip_by_side_plane(from, to, reference, k, incident_face, closed) {
                in_front = !in_front;
                if to.is_empty() {
                    break;
                }
            }
        }
        if in_front {
            self.front
        } else {
            self.back
        }
    }
}

/// Relative slack of [`FaceBox`]: ten times the rounding of a side-plane test, far below
/// any real overshoot it exists to catch.
const FACE_BOX_SLACK: f32 = 1.0e-5;

/// The box of a reference face's vertices grown by [`FACE_BOX_SLACK`] of their largest
/// coordinate: a clipped point is kept when, moved along the face normal onto the face's
/// plane, it lies in the box ([`FaceBox::holds`]).
///
/// Why: the side planes of a sliver face (two of its edges nearly parallel, such as a
/// triangle with a 0.2 mm edge and 10 m sides) meet at a point that `f32` cannot place:
/// a clipped point 2 cm past the sliver's tip lies within rounding of both long side
/// planes and passes them (narrow_phase fuzz finding `sliver-reference-face-7d4378d2`).
/// The box test has no such conditioning: it drops that point. A clip of a well-shaped
/// face never comes near the box's sides but by rounding, so it keeps every point.
///
/// Formed once per clip, not once per point: the same numbers, a fifth of a box–box
/// manifold's work less. A box's face skips it ([`Polygon::RIGHT_ANGLED`]): it has no tip,
/// and its slack, relative to the reference face alone, dropped a small face's corners
/// cut from a much larger incident face (off by the rounding of the long incident edge).
struct FaceBox {
    /// The face's first vertex and its normal: the plane points are moved onto.
    v0: Vec3,
    normal: Vec3,
    lo: Vec3,
    hi: Vec3,
}

impl FaceBox {
    /// The box of `reference`; `None` for a face without vertices (every point kept).
    fn of(reference: &impl Polygon) -> Option<FaceBox> {
        let verts = reference.points();
        let &v0 = verts.first()?;
        let (mut lo, mut hi) = (v0, v0);
        let mut size = 0.0f32;
        for v in verts {
            lo = lo.min(*v);
            hi = hi.max(*v);
            size = scalar::max(size, v.abs().max_elem());
        }
        let slack = Vec3::splat(FACE_BOX_SLACK * size);
        Some(FaceBox {
            v0,
            normal: reference.normal(),
            lo: lo - slack,
            hi: hi + slack,
        })
    }

    /// True when `p`, moved along the normal onto the face's plane, lies in the box.
    fn holds(&self, p: Vec3) -> bool {
        let n = self.normal;
        let q = p - n * n.dot(p - self.v0);
        let (lo, hi) = (self.lo, self.hi);
        // NaN fails every compare: such a point is dropped.
        q.x >= lo.x && q.y >= lo.y && q.z >= lo.z && q.x <= hi.x && q.y <= hi.y && q.z <= hi.z
    }
}

/// The index after `k` in a cycle of `n` (0 after the last): `(k + 1) % n` without the
/// division, which has a panic path for `n = 0`.
#[inline]
fn next_index(k: usize, n: usize) -> usize {
    if k + 1 < n {
        k + 1
    } else {
        0
    }
}

/// The feature of `face` (a polygon, segment or point in the caller's frame) nearest to
/// `p`: the face itself when `p` projects inside it by more than a tolerance, else the
/// nearest boundary edge, or a vertex when the nearest boundary point is within the
/// tolerance of one. The tolerance is [`FEATURE_TOLERANCE`] times the longest edge, so a
/// point resting exactly on an edge or corner is named by it despite rounding.
pub(crate) fn closest_feature(face: &impl Polygon, p: Vec3) -> FeatureId {
    let verts = face.points();
    let n = verts.len();
    let mut longest = 0.0;
    for k in 0..n {
        let v0 = verts.get(k).copied().unwrap_or(Vec3::ZERO);
        let v1 = verts.get(next_index(k, n)).copied().unwrap_or(v0);
        longest = scalar::max(longest, (v1 - v0).length());
    }
    let tolerance = FEATURE_TOLERANCE * longest;
    if n == 0 {
        return face.id();
    }
    if n == 1 {
        return face.vertex_ids().first().copied().unwrap_or(face.id());
    }
    if n >= 3 {
        let mut inside = true;
        for k in 0..n {
            let (s, v0) = side_plane(face, k);
            let len = s.length();
            // Signed distance (m) of p outside side plane k.
            if s.dot(p - v0) > -tolerance * len {
                inside = false;
                break;
            }
        }
        if inside {
            return face.id();
        }
    }
    // Nearest point on the boundary; a segment (n == 2) has one edge.
    let edges = if n == 2 { 1 } else { n };
    let mut best = face.id();
    let mut best_d2 = f32::INFINITY;
    for k in 0..edges {
        let v0 = verts.get(k).copied().unwrap_or(Vec3::ZERO);
        let v1 = verts.get(next_index(k, n)).copied().unwrap_or(v0);
        let e = v1 - v0;
        let e2 = e.length_squared();
        let t = if e2 > 0.0 {
            scalar::clamp((p - v0).dot(e) / e2, 0.0, 1.0)
        } else {
            0.0
        };
        let d2 = (v0 + e * t - p).length_squared();
        if d2 < best_d2 {
            best_d2 = d2;
            let along = t * scalar::sqrt(e2);
            let back = (1.0 - t) * scalar::sqrt(e2);
            best = if along <= tolerance {
                face.vertex_ids().get(k).copied().unwrap_or(face.id())
            } else if back <= tolerance {
                face.vertex_ids()
                    .get(next_index(k, n))
                    .copied()
                    .unwrap_or(face.id())
            } else {
                face.edge_ids().get(k).copied().unwrap_or(face.id())
            };
        }
    }
    best
}

/// The indices (into `points`) of at most 4 points that keep the manifold's support
/// polygon large (Gregorius, GDC 2015): the deepest point; the one farthest from it; the
/// one making the largest triangle with those two; the one adding the most area outside
/// that triangle. Areas are signed about `normal`. Ties go to the lowest
/// index. A point that adds no area (`<= 1e-6` of the squared spread) is not taken, so
/// collinear sets give 2 points and coincident sets 1.
pub(crate) fn reduce_to_four(points: &[Candidate], normal: Vec3) -> ([usize; 4], usize) {
    let mut chosen = [0usize; 4];
    let Some(first) = points.first() else {
        return (chosen, 0);
    };
    // 1. Deepest.
    let mut i0 = 0;
    let mut s0 = first.separation;
    for (i, c) in points.iter().enumerate() {
        if c.separation < s0 {
            s0 = c.separation;
            i0 = i;
        }
    }
    let p0 = points.get(i0).map_or(Vec3::ZERO, |c| c.point_a);
    chosen[0] = i0;
    // 2. Farthest from the deepest.
    let mut i1 = i0;
    let mut d1 = 0.0;
    for (i, c) in points.iter().enumerate() {
        let d = (c.point_a - p0).length_squared();
        if d > d1 {
            d1 = d;
            i1 = i;
        }
    }
    if i1 == i0 {
        return (chosen, 1);
    }
    chosen[1] = i1;
    let p1 = points.get(i1).map_or(p0, |c| c.point_a);
    let e01 = p1 - p0;
    // Twice the signed area of (p0, p1, q) about the normal.
    let area = |q: Vec3| e01.cross(q - p0).dot(normal);
    let min_area = 1.0e-6 * d1;
    // 3. Largest triangle.
    let mut i2 = i0;
    let mut a2 = min_area;
    let mut side = 1.0;
    for (i, c) in points.iter().enumerate() {
        let a = area(c.point_a);
        if scalar::abs(a) > a2 {
            a2 = scalar::abs(a);
            i2 = i;
            side = scalar::sign(a);
        }
    }
    if i2 == i0 {
        return (chosen, 2);
    }
    chosen[2] = i2;
    // 4. Most area added to the triangle: the largest area of the triangle q makes with
    //    an edge of (p0, p1, p2) that q lies outside of. Gregorius takes the other side of
    //    p0–p1 only; when p0–p1 is itself a boundary edge there is nothing there, and
    //    the two other edges still give a fourth point.
    let p2 = points.get(i2).map_or(p0, |c| c.point_a);
    let oriented = normal * side;
    let edge_area = |u: Vec3, v: Vec3, q: Vec3| (v - u).cross(q - u).dot(oriented);
    let mut i3 = i0;
    let mut a3 = min_area;
    for (i, c) in points.iter().enumerate() {
        let q = c.point_a;
        let outside = scalar::max(
            -edge_area(p0, p1, q),
            scalar::max(-edge_area(p1, p2, q), -edge_area(p2, p0, q)),
        );
        if outside > a3 {
            a3 = outside;
            i3 = i;
        }
    }
    if i3 == i0 {
        return (chosen, 3);
    }
    chosen[3] = i3;
    (chosen, 4)
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::collide::manifold::ContactId;
    use crate::shape::{Cuboid, Face};
    use std::vec::Vec;

    /// The +Y face of a box of half-extents `h`, moved by `offset`, turned over when `flip`.
    fn top_face(h: Vec3, offset: Vec3, flip: bool) -> Face<4> {
        let c = Cuboid::new(h).unwrap();
        let f = c.quad(1, !flip);
        let mut f = f.transformed(&crate::math::Iso::from_position(offset));
        if flip {
            // The −Y face of a box above: same plane orientation as an incident face.
            f.normal = -Vec3::Y;
        }
        f
    }

    #[test]
    fn square_clipped_by_square_keeps_inside_corners_and_makes_crossings() {
        // Reference: top of a 2×2 square at y = 0. Incident: bottom of a 2×2 square
        // shifted by (1, 0, 1): one incident corner inside, one reference corner inside,
        // two edge crossings on each side.
        let reference = top_face(Vec3::new(1.0, 1.0, 1.0), Vec3::new(0.0, -1.0, 0.0), false);
        let incident = top_face(Vec3::new(1.0, 1.0, 1.0), Vec3::new(1.0, 1.0, 1.0), true);
        let (mut front, mut back) = (ClipPolygon::new(), ClipPolygon::new());
        let mut bufs = ClipBuffers::new(&mut front, &mut back);
        let out = bufs.polygon(&reference, &incident);
        let pts: Vec<Vec3> = out.vertices().iter().map(|v| v.point).collect();
        assert_eq!(pts.len(), 4, "{pts:?}");
        // The overlap of [-1,1]² and [0,2]² is [0,1]²: corners (0,0), (1,0), (1,1), (0,1).
        for want in [(0.0, 0.0), (1.0, 0.0), (1.0, 1.0), (0.0, 1.0)] {
            assert!(
                pts.iter()
                    .any(|p| (p.x - want.0).abs() < 1e-6 && (p.z - want.1).abs() < 1e-6),
                "{want:?} in {pts:?}"
            );
        }
        // Exactly one survivor of each kind: incident vertex (ref face), reference corner
        // (incident face), and two crossings (ref edge, incident edge).
        let kinds: Vec<(u32, u32)> = out
            .vertices()
            .iter()
            .map(|v| (v.ref_id.0 >> 30, v.inc_id.0 >> 30))
            .collect();
        assert_eq!(
            kinds.iter().filter(|k| **k == (2, 0)).count(),
            1,
            "{kinds:?}"
        );
        assert_eq!(
            kinds.iter().filter(|k| **k == (0, 2)).count(),
            1,
            "{kinds:?}"
        );
        assert_eq!(
            kinds.iter().filter(|k| **k == (1, 1)).count(),
            2,
            "{kinds:?}"
        );
    }

    /// Sutherland–Hodgman as written first: every plane copies the polygon into the
    /// other buffer, whether it cuts anything or not (the oracle of the clip that lets a
    /// plane cutting nothing leave the polygon where it is).
    fn clip_every_plane(reference: &Face<4>, incident: &Face<4>) -> Vec<ClipVertex> {
        let mut poly: Vec<ClipVertex> = (0..4)
            .map(|k| ClipVertex {
                point: incident.vertices[k],
                ref_id: reference.id,
                inc_id: incident.vertex_ids[k],
                seg_ref_edge: NO_EDGE,
                seg_inc: incident.edge_ids[k],
            })
            .collect();
        for k in 0..4 {
            let (s, v0) = side_plane(reference, k);
            let d: Vec<f32> = poly.iter().map(|v| s.dot(v.point - v0)).collect();
            let n = poly.len();
            let mut out = Vec::new();
            for i in 0..n {
                let (p, dp) = (poly[i], d[i]);
                if dp <= 0.0 {
                    out.push(p);
                }
                let j = (i + 1) % n;
                let (q, dq) = (poly[j], d[j]);
                let (exits, enters) = (dp < 0.0 && dq > 0.0, dp > 0.0 && dq < 0.0);
                if (n > 2 || i + 1 < n) && (exits || enters) {
                    let (seg_ref_edge, seg_inc) = if exits {
                        (k as u8, incident.id)
                    } else {
                        (p.seg_ref_edge, p.seg_inc)
                    };
                    out.push(ClipVertex {
                        point: crossing(p.point, q.point, dp, dq),
                        ref_id: reference_feature(reference, p.seg_ref_edge, k),
                        inc_id: p.seg_inc,
                        seg_ref_edge,
                        seg_inc,
                    });
                }
            }
            poly = out;
            if poly.is_empty() {
                break;
            }
        }
        let face_box = FaceBox::of(reference).unwrap();
        poly.retain(|v| face_box.holds(v.point));
        poly
    }

    /// The clip gives what clipping by every plane gives, bit for bit, for box faces
    /// turned and moved at random (many planes cut nothing, many cut).
    #[test]
    fn planes_that_cut_nothing_leave_the_clip_unchanged() {
        use crate::math::Iso;
        let mut rng = crate::rng::SplitMix64::new(21);
        let (a, b) = (
            Cuboid::new(Vec3::new(0.5, 0.3, 0.8)).unwrap(),
            Cuboid::new(Vec3::new(0.3, 0.6, 0.2)).unwrap(),
        );
        let (mut untouched, mut cut) = (0, 0);
        for _ in 0..2000 {
            let reference = a.quad(1, true);
            let pose = Iso::new(
                Vec3::new(rng.range(-0.8, 0.8), 0.3, rng.range(-1.0, 1.0)),
                if rng.range(0.0, 1.0) < 0.5 {
                    crate::math::Quat::IDENTITY
                } else {
                    rng.rotation()
                },
            );
            let incident = b.quad(1, false).transformed(&pose);
            let (mut front, mut back) = (ClipPolygon::new(), ClipPolygon::new());
            let mut bufs = ClipBuffers::new(&mut front, &mut back);
            let got = bufs.polygon(&reference, &incident).vertices().to_vec();
            let want = clip_every_plane(&reference, &incident);
            assert_eq!(std::format!("{got:?}"), std::format!("{want:?}"));
            if got.len() == 4
                && got
                    .iter()
                    .zip(incident.points())
                    .all(|(v, p)| v.point == *p)
            {
                untouched += 1;
            } else {
                cut += 1;
            }
        }
        assert!(untouched > 100 && cut > 100, "{untouched} {cut}");
    }

    /// A box's face skips the face box test (`ClipBuffers::run`): no tip, so every point
    /// its side planes keep lies in the face up to the rounding of the clip, which is
    /// relative to the largest coordinate of either face (a crossing point moves along
    /// an incident edge). Checked on box faces of sizes from `MIN_SIZE` to `MAX_SIZE`
    /// (each axis on its own: faces as thin as 1:10⁶, incident faces 10⁶ times the
    /// reference), turned at random, as a reference face of A (axis-aligned) or of B
    /// (turned and moved into A's frame), against incident box faces laid across them.
    /// (The face box, whose slack is relative to the reference face alone, drops some of
    /// these points: a small face's corners cut from a large incident face.)
    #[test]
    fn box_faces_keep_only_points_in_the_face() {
        use crate::math::{Iso, Quat};
        use crate::shape::{MAX_SIZE, MIN_SIZE};
        let mut rng = crate::rng::SplitMix64::new(77);
        // Log-uniform in [MIN_SIZE, MAX_SIZE].
        let size = |rng: &mut crate::rng::SplitMix64| {
            let t = rng.range(0.0, 1.0);
            MIN_SIZE * libm::powf(MAX_SIZE / MIN_SIZE, t)
        };
        let largest = |f: &Face<4>| {
            f.points()
                .iter()
                .fold(0.0f32, |m, p| m.max(p.abs().max_elem()))
        };
        let (mut kept, mut cut) = (0usize, 0usize);
        for i in 0..20_000 {
            let h = |rng: &mut crate::rng::SplitMix64| Vec3::new(size(rng), size(rng), size(rng));
            let (a, b) = (
                Cuboid::new(h(&mut rng)).unwrap(),
                Cuboid::new(h(&mut rng)).unwrap(),
            );
            let axis = (rng.next_u64() % 3) as usize;
            let turned = |rng: &mut crate::rng::SplitMix64| {
                if rng.range(0.0, 1.0) < 0.3 {
                    Quat::IDENTITY
                } else {
                    rng.rotation()
                }
            };
            // The reference: A's face as it is, or B's face moved into A's frame.
            let mut reference = a.quad(axis, rng.range(0.0, 1.0) < 0.5);
            if i % 2 == 1 {
                let far = Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ) * 2.0e3;
                reference.transform_by(&sat_matrix(turned(&mut rng)), far);
            }
            let [c0, c1, c2, c3] = reference.vertices;
            // The incident face: a face of the other box, turned, its centre near the
            // reference face's plane near a random point of the face.
            let on_face = c0 + (c1 - c0) * rng.range(-0.5, 1.5) + (c2 - c1) * rng.range(-0.5, 1.5);
            let extent = (c2 - c0).length();
            let lift = reference.normal * (rng.range(-0.5, 0.5) * extent);
            let incident_axis = (rng.next_u64() % 3) as usize;
            let incident = b
                .quad(incident_axis, false)
                .transformed(&Iso::new(on_face + lift, turned(&mut rng)));
            let (mut front, mut back) = (ClipPolygon::new(), ClipPolygon::new());
            let mut bufs = ClipBuffers::new(&mut front, &mut back);
            let got = bufs.polygon(&reference, &incident).vertices().to_vec();
            // In the face: on the inner side of each edge, measured along the edge's
            // in-plane unit normal, up to the tolerance.
            let tol = 1.0e-5 * largest(&reference).max(largest(&incident));
            let n = reference.normal;
            for v in &got {
                for (p, q) in [(c0, c1), (c1, c2), (c2, c3), (c3, c0)] {
                    let outward = (q - p).cross(n).normalize_or(Vec3::ZERO);
                    let beyond = (v.point - p).dot(outward);
                    assert!(
                        beyond <= tol,
                        "case {i}: {:?} {beyond} past an edge of {reference:?} (incident {incident:?})",
                        v.point
                    );
                }
            }
            kept += got.len();
            cut += usize::from(got.len() != 4);
        }
        // Both kinds of clip were seen many times.
        assert!(kept > 20_000 && cut > 5_000, "{kept} {cut}");
    }

    /// The narrow phase's rotation matrix of `q`.
    fn sat_matrix(q: crate::math::Quat) -> crate::math::Mat3 {
        crate::collide::sat::rotation_matrix(q)
    }

    #[test]
    fn vertex_on_a_side_plane_is_not_doubled() {
        let reference = top_face(Vec3::ONE, Vec3::new(0.0, -1.0, 0.0), false);
        // Same size, exactly on top: every incident vertex lies on two side planes.
        let incident = top_face(Vec3::ONE, Vec3::new(0.0, 1.0, 0.0), true);
        let (mut front, mut back) = (ClipPolygon::new(), ClipPolygon::new());
        let mut bufs = ClipBuffers::new(&mut front, &mut back);
        let out = bufs.polygon(&reference, &incident);
        assert_eq!(out.vertices().len(), 4);
    }

    #[test]
    fn segment_clip_cuts_at_the_face_edge() {
        let reference = top_face(Vec3::ONE, Vec3::new(0.0, -1.0, 0.0), false);
        let (mut front, mut back) = (ClipPolygon::new(), ClipPolygon::new());
        let mut bufs = ClipBuffers::new(&mut front, &mut back);
        let out = bufs.segment(
            &reference,
            Vec3::new(0.0, 0.1, 0.0),
            Vec3::new(3.0, 0.1, 0.0),
            [FeatureId::vertex(0), FeatureId::vertex(1)],
            FeatureId::edge(0, 1),
        );
        let v = out.vertices();
        assert_eq!(v.len(), 2);
        assert_eq!(v[0].inc_id, FeatureId::vertex(0));
        assert!((v[1].point.x - 1.0).abs() < 1e-6);
        assert_eq!(v[1].inc_id, FeatureId::edge(0, 1));
        assert_eq!(v[1].ref_id.0 >> 30, 1, "a reference edge");
    }

    fn candidate(x: f32, z: f32, separation: f32) -> Candidate {
        let p = Vec3::new(x, 0.0, z);
        Candidate {
            point_a: p,
            point_b: p,
            separation,
            id: ContactId::default(),
        }
    }

    #[test]
    fn reduction_keeps_the_deepest_and_the_outer_corners() {
        // A 5×5 grid with the deepest point in the middle of one side.
        let mut pts = Vec::new();
        for i in 0..5 {
            for j in 0..5 {
                let deep = i == 0 && j == 2;
                pts.push(candidate(
                    i as f32,
                    j as f32,
                    if deep { -0.5 } else { -0.1 },
                ));
            }
        }
        let (chosen, n) = reduce_to_four(&pts, Vec3::Y);
        assert_eq!(n, 4);
        assert_eq!(chosen[0], 2, "deepest first");
        let mut corners: Vec<(f32, f32)> = chosen[1..]
            .iter()
            .map(|&i| (pts[i].point_a.x, pts[i].point_a.z))
            .collect();
        // The crate's panic-free heapsort; the coordinates are finite, `total_cmp` orders
        // them as `<` does (and would put a NaN last instead of panicking).
        crate::sort::sort_unstable_by(&mut corners, |a, b| {
            a.0.total_cmp(&b.0).then(a.1.total_cmp(&b.1)).is_lt()
        });
        // Farthest from (0, 2): (4, 0) and (4, 4) tie, the lower index (4, 0) wins; the
        // largest triangle adds (4, 4) (twice-area 16); outside that triangle (0, 0) and
        // (0, 4) both add twice-area 8, the lower index (0, 0) wins.
        assert_eq!(corners, [(0.0, 0.0), (4.0, 0.0), (4.0, 4.0)]);
    }

    #[test]
    fn reduction_of_collinear_points_gives_two() {
        let pts: Vec<Candidate> = (0..6).map(|i| candidate(i as f32, 0.0, -0.1)).collect();
        let (chosen, n) = reduce_to_four(&pts, Vec3::Y);
        assert_eq!(n, 2);
        assert_eq!(&chosen[..2], &[0, 5]);
    }

    #[test]
    fn closest_feature_names_face_edge_and_vertex() {
        let f = top_face(Vec3::ONE, Vec3::new(0.0, -1.0, 0.0), false);
        assert_eq!(closest_feature(&f, Vec3::new(0.2, 0.0, 0.3)), f.id);
        assert_eq!(closest_feature(&f, Vec3::new(1.0, 0.0, 0.3)).0 >> 30, 1);
        assert_eq!(closest_feature(&f, Vec3::new(1.0, 0.0, 1.0)).0 >> 30, 0);
        assert_eq!(closest_feature(&f, Vec3::new(1.5, 0.0, 2.0)).0 >> 30, 0);
    }
}
