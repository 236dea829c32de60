//! Closed forms: sphere, capsule and half-space pairs, sphere against box and against a
//! triangle. They also serve
//! as test oracles.

use super::manifold::{
    Candidate, ContactId, LocalManifold, Manifold, ManifoldPoint, MAX_MANIFOLD_POINTS,
};
use crate::math::{scalar, Iso, Vec3};
use crate::shape::{
    Capsule, Cuboid, FeatureId, HalfSpace, Shape, Sphere, Triangle, MAX_HULL_VERTICES,
};

/// Closest points between segments `p1–q1` and `p2–q2`: returns `(s, t)` with the points
/// `p1 + s (q1 − p1)` and `p2 + t (q2 − p2)`, `s, t ∈ [0, 1]`. Degenerate segments
/// (points) are handled. (Ericson, Real-Time Collision Detection, 5.1.9.)
///
/// Departure from Ericson: for segments that meet at a small angle θ his parameters carry
/// about `ε / sin²θ` of rounding (at θ = 1e-4 rad in f32, more than the whole range), so
/// his clamped answer can be the far end of two nearly parallel segments; the true closest
/// pair is then one of the end pairs. Within about 5.7° of parallel (`sin²θ ≤ 0.01`)
/// his answer is compared with the four end-to-segment pairs (each a well-conditioned
/// projection) and the closest of the five is returned (his on ties). Beyond that his
/// answer stands alone: exact in exact arithmetic, its rounding is then below `100 ε` of
/// the segments' lengths and distance, and an end pair could beat it by rounding only.
pub fn segment_closest_points(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> (f32, f32) {
    let (best, well_conditioned) = ericson_closest_points(p1, q1, p2, q2);
    if well_conditioned {
        return best;
    }
    let (d1, d2) = (q1 - p1, q2 - p2);
    let gap2 = |(s, t): (f32, f32)| (p2 + d2 * t - p1 - d1 * s).length_squared();
    // The parameter of the point of segment `p + u d` closest to `x`, clamped.
    let project = |x: Vec3, p: Vec3, d: Vec3| {
        let dd = d.length_squared();
        if dd > 0.0 {
            scalar::clamp((x - p).dot(d) / dd, 0.0, 1.0)
        } else {
            0.0
        }
    };
    let mut best = best;
    let mut best_gap2 = gap2(best);
    let ends = [
        (0.0, project(p1, p2, d2)),
        (1.0, project(q1, p2, d2)),
        (project(p2, p1, d1), 0.0),
        (project(q2, p1, d1), 1.0),
    ];
    for pair in ends {
        let g = gap2(pair);
        if g < best_gap2 {
            best = pair;
            best_gap2 = g;
        }
    }
    best
}

/// `sin²θ` of the angle between two segments above which Ericson's closest points are
/// taken as they are in [`segment_closest_points`] (θ above about 5.7°): their rounding,
/// about `ε / sin²θ` of the segments' lengths and distance, is then below 1e-5 of them.
const WELL_CONDITIONED_SIN2: f32 = 1.0e-2;

/// Ericson's closest points of two segments (5.1.9), see [`segment_closest_points`], and
/// whether they are well conditioned (neither segment a point, `sin²θ` above
/// [`WELL_CONDITIONED_SIN2`]).
fn ericson_closest_points(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> ((f32, f32), bool) {
    const EPS: f32 = 1.0e-12;
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let r = p1 - p2;
    let a = d1.length_squared();
    let e = d2.length_squared();
    let f = d2.dot(r);
    if a <= EPS && e <= EPS {
        return ((0.0, 0.0), false);
    }
    if a <= EPS {
        return ((0.0, scalar::clamp(f / e, 0.0, 1.0)), false);
    }
    let c = d1.dot(r);
    if e <= EPS {
        return ((scalar::clamp(-c / a, 0.0, 1.0), 0.0), false);
    }
    let b = d1.dot(d2);
    // `a e sin²θ`.
    let denom = a * e - b * b;
    let mut s = if denom > EPS * a * e {
        scalar::clamp((b * f - c * e) / denom, 0.0, 1.0)
    } else {
        0.0
    };
    let mut t = (b * s + f) / e;
    if t < 0.0 {
        t = 0.0;
        s = scalar::clamp(-c / a, 0.0, 1.0);
    } else if t > 1.0 {
        t = 1.0;
        s = scalar::clamp((b - c) / a, 0.0, 1.0);
    }
    // False for NaN too: the end pairs then have their say.
    let well_conditioned = denom > WELL_CONDITIONED_SIN2 * a * e;
    ((s, t), well_conditioned)
}

/// Below this `sin` of the angle between two capsule segments (about 2.9°), the segments
/// count as parallel and their overlap gives two points (stacked logs rest on a line, not
/// a point).
const PARALLEL_SIN: f32 = 0.05;

/// Relative tolerance (fraction of the segment length) under which a point on a capsule's
/// segment is named by the nearer end vertex instead of the segment.
const END_TOLERANCE: f32 = 1.0e-4;

/// Below this fraction of the coordinates' size, a gap between core points is rounding
/// noise (`f32` keeps about 6e-8 relative; each point takes a few operations): the cores
/// touch and the normal comes from the fallback rules.
const TOUCH_TOLERANCE: f32 = 1.0e-6;

/// The feature of capsule `c`'s core nearest to the core point `p` (local frame): vertex 0
/// (bottom end), vertex 1 (top end) or the segment, edge (0, 1).
pub(crate) fn segment_feature(c: &Capsule, p: Vec3) -> FeatureId {
    let h = c.half_height;
    if p.y <= -h + END_TOLERANCE * 2.0 * h {
        FeatureId::vertex(0)
    } else if p.y >= h - END_TOLERANCE * 2.0 * h {
        FeatureId::vertex(1)
    } else {
        FeatureId::edge(0, 1)
    }
}

/// The feature of a segment at parameter `t ∈ [0, 1]`.
pub(crate) fn feature_at(t: f32) -> FeatureId {
    if t <= END_TOLERANCE {
        FeatureId::vertex(0)
    } else if t >= 1.0 - END_TOLERANCE {
        FeatureId::vertex(1)
    } else {
        FeatureId::edge(0, 1)
    }
}

/// The unit vector along `v`, or the part of `fallback` perpendicular to `axis` when `v`
/// is (nearly) zero, or any perpendicular of `axis` when that is zero too.
fn direction_or_perpendicular(v: Vec3, axis: Vec3, fallback: Vec3) -> Vec3 {
    if let Some((n, _)) = v.normalize_and_length() {
        return n;
    }
    let aa = axis.length_squared();
    if aa > 0.0 {
        let perp = fallback - axis * (fallback.dot(axis) / aa);
        perp.normalize_or(axis.normalize_or(Vec3::Y).any_perpendicular())
    } else {
        fallback
    }
}

/// Sphere `a` at A's origin, sphere `b` centred at `b_in_a.position`. Normal along the
/// centre line; `fallback` (unit) when the centres coincide.
pub(crate) fn sphere_sphere(
    a: &Sphere,
    b: &Sphere,
    b_in_a: &Iso,
    fallback: Vec3,
    margin: f32,
) -> Option<LocalManifold> {
    let c = b_in_a.position;
    let normal = c.normalize_or(fallback);
    let id = ContactId {
        a: FeatureId::vertex(0),
        b: FeatureId::vertex(0),
    };
    let mut m = LocalManifold::new(normal);
    m.push_within(
        Candidate::new(normal * a.radius, c - normal * b.radius, normal, id),
        margin,
    );
    m.non_empty()
}

/// Sphere `a` at `pose_a` against sphere `b` at `pose_b` (world frame, unit rotations), in
/// closed form in the world frame: with `d = c_b − c_a`, the normal is `d / |d|` (`fallback`,
/// unit, when the centres coincide), the separation `|d| − r_a − r_b`, and the points
/// `c_a + r_a n`, `c_b − r_b n`. The answer is symmetric to the bit: swapping the spheres
/// negates `d` exactly, so the normal flips and the points swap (the fallback is the
/// caller's to keep symmetric). The normal and the one point; `None` when apart by more
/// than `margin` (the numbers are not checked for finiteness: [`write_one_point`] does).
#[inline]
pub(crate) fn sphere_sphere_point(
    a: &Sphere,
    pose_a: &Iso,
    b: &Sphere,
    pose_b: &Iso,
    fallback: impl Fn() -> Vec3,
    margin: f32,
) -> Option<(Vec3, ManifoldPoint)> {
    let d = pose_b.position - pose_a.position;
    let (normal, distance) = d
        .normalize_and_length()
        .unwrap_or_else(|| (fallback(), 0.0));
    let separation = distance - (a.radius + b.radius);
    let within = separation <= margin; // false for NaN too
    if !within {
        return None;
    }
    let (on_a, on_b) = (normal * a.radius, normal * -b.radius);
    let point = ManifoldPoint {
        point_a: pose_a.position + on_a,
        point_b: pose_b.position + on_b,
        local_a: pose_a.inverse_transform_vector(on_a),
        local_b: pose_b.inverse_transform_vector(on_b),
        separation,
        id: ContactId {
            a: FeatureId::vertex(0),
            b: FeatureId::vertex(0),
        },
    };
    Some((normal, point))
}

/// Sphere `a` at `pose_a` against box `b` at `pose_b` (world frame, unit rotations), in
/// closed form in the box's frame, where the box is `|x| <= h`: the sphere's centre is moved
/// into that frame once and the answer out of it once (this pair skips the A-frame round
/// trip of the other pairs). The centre `p` is clamped to the box, `q = clamp(p, −h, h)`:
///
/// - centre outside (`p ≠ q`): the closest point of the box is `q`, the normal from the
///   sphere towards the box `(q − p) / |q − p|`, the separation `|p − q| − r`; the box's
///   feature is the face, edge or vertex on which `q` lies (one, two or three coordinates
///   clamped);
/// - centre inside or on the surface: the face of least penetration, the smallest of the
///   six distances `h_k ∓ p_k` (first in face order on ties), with the normal into that
///   face, the separation `−(h_k ∓ p_k) − r`, and the centre's projection on that face.
///
/// One point, written to `out`: the sphere's surface point along the normal and the box
/// point. False (and `out` unspecified) when apart by more than `margin` or when a number
/// is not finite.
pub(crate) fn sphere_cuboid(
    a: &Sphere,
    pose_a: &Iso,
    b: &Cuboid,
    pose_b: &Iso,
    margin: f32,
    out: &mut Manifold,
) -> bool {
    let p = pose_b.inverse_transform_point(pose_a.position);
    let h = b.half_extents;
    let q = Vec3::new(
        scalar::clamp(p.x, -h.x, h.x),
        scalar::clamp(p.y, -h.y, h.y),
        scalar::clamp(p.z, -h.z, h.z),
    );
    let r = a.radius;
    // Box frame: `outward` from the box towards the centre, `on_box` the box point.
    let (outward, on_box, separation, feature) = match (p - q).normalize_and_length() {
        Some((outward, gap)) => {
            let sep = gap - r;
            let within = sep <= margin; // false for NaN too
            if !within {
                return false;
            }
            (outward, q, sep, clamped_feature(p, h))
        }
        None => {
            // Inside: faces in order −X, +X, −Y, +Y, −Z, +Z; distance to each.
            let mut best = (0usize, h.x + p.x);
            for f in 1..6 {
                let k = f / 2;
                let d = if f % 2 == 1 { h[k] - p[k] } else { h[k] + p[k] };
                if d < best.1 {
                    best = (f, d);
                }
            }
            let (f, depth) = best;
            let s = if f % 2 == 1 { 1.0 } else { -1.0 };
            let mut outward = Vec3::ZERO;
            let mut on_box = p;
            match f / 2 {
                0 => {
                    outward.x = s;
                    on_box.x = s * h.x;
                }
                1 => {
                    outward.y = s;
                    on_box.y = s * h.y;
                }
                _ => {
                    outward.z = s;
                    on_box.z = s * h.z;
                }
            }
            (outward, on_box, -depth - r, FeatureId::face(f as u32))
        }
    };
    let on = SphereOn {
        outward,
        point: on_box,
        separation,
        feature,
    };
    one_sphere_point(pose_a, r, pose_b, &on, out)
}

/// The one point of a sphere against a shape B, found in B's frame: `outward` from B
/// towards the centre (unit), `point` on B, `separation` (m), B's `feature`.
struct SphereOn {
    outward: Vec3,
    point: Vec3,
    separation: f32,
    feature: FeatureId,
}

/// Write the one point of `on` into `out`, world frame, the normal from the sphere (radius
/// `r` at `pose_a`) towards B (at `pose_b`): the sphere's surface point along the normal
/// and B's point. False when a number is not finite.
fn one_sphere_point(pose_a: &Iso, r: f32, pose_b: &Iso, on: &SphereOn, out: &mut Manifold) -> bool {
    let normal = pose_b.transform_vector(-on.outward);
    let on_sphere = normal * r;
    let point = ManifoldPoint {
        point_a: pose_a.position + on_sphere,
        point_b: pose_b.transform_point(on.point),
        local_a: pose_a.inverse_transform_vector(on_sphere),
        local_b: on.point,
        separation: on.separation,
        id: ContactId {
            a: FeatureId::vertex(0),
            b: on.feature,
        },
    };
    write_one_point(normal, point, out)
}

/// Write the one-point manifold `(normal, point)` into `out`; false (and `out` as it
/// was) when a number of it is not finite.
pub(crate) fn write_one_point(normal: Vec3, point: ManifoldPoint, out: &mut Manifold) -> bool {
    // `&`, not `&&`: the usual answer is true, so every check runs anyway.
    let finite = normal.is_finite()
        & point.point_a.is_finite()
        & point.point_b.is_finite()
        & point.local_a.is_finite()
        & point.local_b.is_finite()
        & point.separation.is_finite();
    if !finite {
        return false;
    }
    out.normal = normal;
    out.points[0] = point;
    out.len = 1;
    true
}

/// Sphere `a` against triangle `b` (a mesh or height-field part), world frame in and out,
/// the normal from the sphere towards the triangle. In the triangle's frame the centre
/// `p` has a closest point `q` on the triangle, found by the Voronoi regions of its
/// vertices, edges and face (Ericson, *Real-Time Collision Detection*, 5.1.5):
///
/// - over the face: `q` is `p` projected on the plane, the normal is the face normal
///   (front `n` or back `−n`, whichever side `p` is on; front when on the plane), the
///   separation `|n·(p − v₀)| − r`, the feature the face (0 front, 1 back, as the
///   triangle's supporting face numbers them);
/// - beyond an edge or a vertex: the normal is `(q − p) / |q − p|`, the separation
///   `|q − p| − r`, the feature that edge (`v_i → v_{i+1}`) or vertex. A centre exactly on
///   the edge or vertex takes the face normal of its side.
///
/// One point: the sphere's surface point along the normal and `q`. False when apart by
/// more than `margin` or when a number is not finite.
pub(crate) fn sphere_triangle(
    a: &Sphere,
    pose_a: &Iso,
    b: &Triangle,
    pose_b: &Iso,
    margin: f32,
    out: &mut Manifold,
) -> bool {
    let p = pose_b.inverse_transform_point(pose_a.position);
    let n = b.normal();
    let (q, feature) = closest_on_triangle(b, p);
    let height = n.dot(p - b.vertices[0]);
    let face_side = if height >= 0.0 {
        (n, FeatureId::face(0))
    } else {
        (-n, FeatureId::face(1))
    };
    // Triangle frame: `outward` from the triangle towards the centre.
    let (outward, gap, feature) = match feature {
        None => (face_side.0, scalar::abs(height), face_side.1),
        Some(f) => match (p - q).normalize_and_length() {
            Some((outward, gap)) => (outward, gap, f),
            None => (face_side.0, 0.0, f),
        },
    };
    let separation = gap - a.radius;
    let within = separation <= margin; // false for NaN too
    if !within {
        return false;
    }
    let on_triangle = match feature.kind() {
        crate::shape::FeatureKind::Face => p - n * height,
        _ => q,
    };
    let on = SphereOn {
        outward,
        point: on_triangle,
        separation,
        feature,
    };
    one_sphere_point(pose_a, a.radius, pose_b, &on, out)
}

/// The point of triangle `t` closest to `p` and, when it lies on an edge or a vertex,
/// that feature (`None`: inside the face). Ericson's region tests, in his order; `q` on
/// the face is left to the caller (the plane projection is more exact).
pub(crate) fn closest_on_triangle(t: &Triangle, p: Vec3) -> (Vec3, Option<FeatureId>) {
    let [a, b, c] = t.vertices;
    let (ab, ac, ap) = (b - a, c - a, p - a);
    let (d1, d2) = (ab.dot(ap), ac.dot(ap));
    if d1 <= 0.0 && d2 <= 0.0 {
        return (a, Some(FeatureId::vertex(0)));
    }
    let bp = p - b;
    let (d3, d4) = (ab.dot(bp), ac.dot(bp));
    if d3 >= 0.0 && d4 <= d3 {
        return (b, Some(FeatureId::vertex(1)));
    }
    let vc = d1 * d4 - d3 * d2;
    if vc <= 0.0 && d1 >= 0.0 && d3 <= 0.0 {
        return (a + ab * fraction(d1, d1 - d3), Some(FeatureId::edge(0, 1)));
    }
    let cp = p - c;
    let (d5, d6) = (ab.dot(cp), ac.dot(cp));
    if d6 >= 0.0 && d5 <= d6 {
        return (c, Some(FeatureId::vertex(2)));
    }
    let vb = d5 * d2 - d1 * d6;
    if vb <= 0.0 && d2 >= 0.0 && d6 <= 0.0 {
        return (a + ac * fraction(d2, d2 - d6), Some(FeatureId::edge(2, 0)));
    }
    let va = d3 * d6 - d5 * d4;
    let (e, f) = (d4 - d3, d5 - d6);
    if va <= 0.0 && e >= 0.0 && f >= 0.0 {
        return (
            b + (c - b) * fraction(e, e + f),
            Some(FeatureId::edge(1, 2)),
        );
    }
    (p, None)
}

/// `num / den` clamped to `[0, 1]`, 0 when `den` is not positive (a degenerate region).
#[inline]
fn fraction(num: f32, den: f32) -> f32 {
    if den > 0.0 {
        scalar::clamp(num / den, 0.0, 1.0)
    } else {
        0.0
    }
}

/// The box feature under a point `p` outside the box `|x| <= h` (box frame): the face,
/// edge or vertex where `p`'s clamped coordinates put its closest point. Computed from
/// bit masks without branching on the (random) pattern of clamped coordinates.
pub(crate) fn clamped_feature(p: Vec3, h: Vec3) -> FeatureId {
    // Bit k: coordinate k beyond +h_k (`above`) or clamped at all (`clamped`).
    let above = (p.x > h.x) as u32 | ((p.y > h.y) as u32) << 1 | ((p.z > h.z) as u32) << 2;
    let below = (p.x < -h.x) as u32 | ((p.y < -h.y) as u32) << 1 | ((p.z < -h.z) as u32) << 2;
    let clamped = above | below;
    // Three clamped: the vertex `above`. Two: the edge along the free axis, from the vertex
    // with that bit clear. One: the face on the clamped axis (`2k` below, `2k + 1` above).
    let free = !clamped & 7;
    let face_axis = clamped.trailing_zeros() & 3;
    let vertex = FeatureId::vertex(above);
    let edge = FeatureId::edge(above, above | free);
    let face = FeatureId::face(2 * face_axis + ((above >> face_axis) & 1));
    match clamped.count_ones() {
        3 => vertex,
        2 => edge,
        _ => face,
    }
}

/// Sphere `a` at A's origin, capsule `b` at `b_in_a`: the sphere against the closest point
/// of B's segment. When the centre lies on the segment the normal is `fallback` made
/// perpendicular to the segment.
pub(crate) fn sphere_capsule(
    a: &Sphere,
    b: &Capsule,
    b_in_a: &Iso,
    fallback: Vec3,
    margin: f32,
) -> Option<LocalManifold> {
    let (b0, b1) = b.segment();
    let p = b_in_a.transform_point(b0);
    let d = b_in_a.transform_point(b1) - p;
    let dd = d.length_squared();
    // Closest point on p + t d to the origin: t = −p·d / d·d, clamped.
    let t = if dd > 0.0 {
        scalar::clamp(-p.dot(d) / dd, 0.0, 1.0)
    } else {
        0.0
    };
    let q = p + d * t;
    // Below rounding noise of the coordinates, q has no direction: the centre is on the
    // segment.
    let touching = q.length() <= TOUCH_TOLERANCE * (p.length() + d.length());
    let normal = if touching {
        direction_or_perpendicular(Vec3::ZERO, d, fallback)
    } else {
        direction_or_perpendicular(q, d, fallback)
    };
    let id = ContactId {
        a: FeatureId::vertex(0),
        b: feature_at(t),
    };
    let mut m = LocalManifold::new(normal);
    m.push_within(
        Candidate::new(normal * a.radius, q - normal * b.radius, normal, id),
        margin,
    );
    m.non_empty()
}

/// Capsule `a` (A's frame) against capsule `b` at `b_in_a`: the segments' closest points
/// (Ericson 5.1.9), the normal along the lines' common perpendicular when both points are
/// inside their segments ([`line_gap`]); when the segments are parallel within
/// [`PARALLEL_SIN`] and overlap along A's axis, two points at the ends of the overlap.
/// When the segments cross, the
/// normal is `d₁ × d₂` turned towards B's centre; when they are collinear, `fallback` made
/// perpendicular to A's segment.
pub(crate) fn capsule_capsule(
    a: &Capsule,
    b: &Capsule,
    b_in_a: &Iso,
    fallback: Vec3,
    margin: f32,
) -> Option<LocalManifold> {
    let (p1, q1) = a.segment();
    let (b0, b1) = b.segment();
    let p2 = b_in_a.transform_point(b0);
    let q2 = b_in_a.transform_point(b1);
    let d1 = q1 - p1;
    let d2 = q2 - p2;
    let (s, t) = segment_closest_points(p1, q1, p2, q2);
    let c1 = p1 + d1 * s;
    let c2 = p2 + d2 * t;
    // Closer than rounding noise of the coordinates, the segments meet and c₂ − c₁ has no
    // direction.
    let scale = p1.length() + q1.length() + p2.length() + q2.length();
    let touch = TOUCH_TOLERANCE * scale;
    let interior = line_gap(p1, d1, p2, d2, s, t);
    let normal = match interior {
        // Both closest points inside their segments: the gap is along d₁ × d₂.
        Some((n, gap)) if scalar::abs(gap) > touch => n * scalar::sign(gap),
        Some(_) => crossing_normal(d1, d2, b_in_a.position, fallback),
        None => match (c2 - c1).normalize_and_length() {
            Some((n, gap)) if gap > touch => n,
            _ => crossing_normal(d1, d2, b_in_a.position, fallback),
        },
    };
    let (ra, rb) = (a.radius, b.radius);
    let mut m = LocalManifold::new(normal);
    parallel_overlap(&mut m, [p1, d1], [p2, d2], [ra, rb], margin);
    if m.len == 0 {
        let id = ContactId {
            a: feature_at(s),
            b: feature_at(t),
        };
        m.push_within(
            Candidate::new(c1 + normal * ra, c2 - normal * rb, normal, id),
            margin,
        );
    }
    m.non_empty()
}

/// When the closest points of two segments lie strictly inside both (`0 < s, t < 1`) and
/// the segments are not parallel: the unit common normal `n = d₁ × d₂ / |d₁ × d₂|` of the
/// two lines and the signed gap `n · (p₂ − p₁)` along it (m); `None` otherwise.
///
/// For lines that meet at an angle θ the closest points are ill-conditioned (their
/// parameters carry about `ε / sin²θ` of rounding), and `c₂ − c₁` slides along the lines
/// with them: for capsules crossing at 0.3° its direction is noise of 0.02 rad, and the
/// two query orders disagree. The cross product's direction is off by only `ε / sin θ`,
/// and the gap along it does not depend on where the points slid to.
fn line_gap(p1: Vec3, d1: Vec3, p2: Vec3, d2: Vec3, s: f32, t: f32) -> Option<(Vec3, f32)> {
    let inside = s > 0.0 && s < 1.0 && t > 0.0 && t < 1.0;
    let n = d1.cross(d2);
    // The segments are not parallel: |d₁ × d₂| above rounding of |d₁| |d₂|.
    let crossing = n.length_squared() > PARALLEL_NOISE * d1.length_squared() * d2.length_squared();
    if !(inside && crossing) {
        return None;
    }
    let (n, _) = n.normalize_and_length()?;
    Some((n, n.dot(p2 - p1)))
}

/// `sin²` of the angle between two segments below which their cross product is rounding
/// noise (`sin θ` of about 3e-6, some 50 ulps): treated as parallel by [`line_gap`].
const PARALLEL_NOISE: f32 = 1.0e-11;

/// Normal of two segments that meet: `d₁ × d₂` pointing towards B's centre (or along
/// `fallback` when B's centre is in the plane of the two); for collinear segments,
/// `fallback` made perpendicular to `d₁`.
fn crossing_normal(d1: Vec3, d2: Vec3, center_b: Vec3, fallback: Vec3) -> Vec3 {
    let n = direction_or_perpendicular(d1.cross(d2), d1, fallback);
    let side = n.dot(center_b);
    let flip = if side != 0.0 {
        side < 0.0
    } else {
        n.dot(fallback) < 0.0
    };
    if flip {
        -n
    } else {
        n
    }
}

/// Two points for nearly parallel, overlapping segments `p₁ + u d₁` and `p₂ + t d₂`: B's
/// segment is clipped to A's parameter range `u ∈ [0, 1]`, and each end of the overlap
/// pairs a point of B's segment with its projection on A's. Ids: an end of B inside A's
/// range is (A's segment, B's vertex); an end cut by A's end vertex is (A's vertex, B's
/// segment). Adds nothing when the segments are not parallel or do not overlap.
fn parallel_overlap(
    m: &mut LocalManifold,
    [p1, d1]: [Vec3; 2],
    [p2, d2]: [Vec3; 2],
    [ra, rb]: [f32; 2],
    margin: f32,
) {
    let dd1 = d1.length_squared();
    let dd2 = d2.length_squared();
    let parallel = d1.cross(d2).length_squared() <= PARALLEL_SIN * PARALLEL_SIN * dd1 * dd2;
    if !(parallel && dd1 > 0.0 && dd2 > 0.0) {
        return;
    }
    // B's end points as parameters along A's segment.
    let u0 = (p2 - p1).dot(d1) / dd1;
    let u1 = (p2 + d2 - p1).dot(d1) / dd1;
    let du = u1 - u0;
    let spans = scalar::abs(du) > END_TOLERANCE; // false for NaN too
    if !spans {
        return;
    }
    // (parameter, B's vertex there) at the low and high ends.
    let (low, high) = if u0 <= u1 {
        ((u0, 0), (u1, 1))
    } else {
        ((u1, 1), (u0, 0))
    };
    let lo = scalar::max(low.0, 0.0);
    let hi = scalar::min(high.0, 1.0);
    let overlaps = hi - lo > END_TOLERANCE;
    if !overlaps {
        return;
    }
    let normal = m.normal;
    let ends = [
        (lo, low.0 < 0.0, 0u32, low.1),
        (hi, high.0 > 1.0, 1u32, high.1),
    ];
    for (u, cut_by_a, a_vertex, b_vertex) in ends {
        let t = scalar::clamp((u - u0) / du, 0.0, 1.0);
        let on_a = p1 + d1 * u;
        let on_b = p2 + d2 * t;
        let id = if cut_by_a {
            ContactId {
                a: FeatureId::vertex(a_vertex),
                b: FeatureId::edge(0, 1),
            }
        } else {
            ContactId {
                a: FeatureId::edge(0, 1),
                b: FeatureId::vertex(b_vertex),
            }
        };
        m.push_within(
            Candidate::new(on_a + normal * ra, on_b - normal * rb, normal, id),
            margin,
        );
    }
}

/// Half-space `plane` (A, `{p : n · p <= 0}` in A's frame) against any shape `b` at
/// `b_in_a`: each core vertex of B, pushed down by B's radius, whose height above the
/// plane is within `margin`; the point on A is its projection on the plane. A cuboid keeps
/// its deepest 4 vertices (ties by index), a hull its 4 chosen by
/// [`super::clip::reduce_to_four`]. Two half-spaces never touch.
pub(crate) fn half_space_contact(
    plane: &HalfSpace,
    b: &Shape,
    b_in_a: &Iso,
    margin: f32,
) -> Option<LocalManifold> {
    let n = plane.normal;
    let radius = b.radius();
    let mut candidates = [Candidate::default(); MAX_HULL_VERTICES];
    let mut count = 0usize;
    let mut add = |local: Vec3, index: u32| {
        let point_b = b_in_a.transform_point(local) - n * radius;
        let point_a = point_b - n * n.dot(point_b);
        let id = ContactId {
            a: FeatureId::face(0),
            b: FeatureId::vertex(index),
        };
        let c = Candidate::new(point_a, point_b, n, id);
        if c.separation <= margin {
            if let Some(slot) = candidates.get_mut(count) {
                *slot = c;
                count += 1;
            }
        }
    };
    match b {
        // Half-spaces never touch; meshes and compounds never reach the narrow phase.
        Shape::HalfSpace(_) | Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => {
            return None
        }
        Shape::Sphere(_) => add(Vec3::ZERO, 0),
        Shape::Capsule(c) => {
            let (s0, s1) = c.segment();
            add(s0, 0);
            add(s1, 1);
        }
        Shape::Cuboid(c) => {
            for i in 0..8 {
                add(c.core_vertex(i), i);
            }
        }
        Shape::Hull(h) => {
            for (i, v) in h.vertices().iter().enumerate() {
                add(*v, i as u32);
            }
        }
        Shape::Triangle(t) => {
            for (i, v) in t.vertices.iter().enumerate() {
                add(*v, i as u32);
            }
        }
    }
    let found = candidates.get(..count).unwrap_or(&[]);
    if matches!(b, Shape::Cuboid(_)) {
        deepest_four(n, found)
    } else {
        LocalManifold::from_candidates(n, found)
    }
}

/// The (at most) 4 deepest candidates, deepest first; ties go to the lower index.
fn deepest_four(normal: Vec3, candidates: &[Candidate]) -> Option<LocalManifold> {
    let mut m = LocalManifold::new(normal);
    let mut taken = [false; 8];
    for _ in 0..MAX_MANIFOLD_POINTS {
        let mut best: Option<usize> = None;
        let mut best_s = f32::INFINITY;
        for (i, c) in candidates.iter().enumerate().take(taken.len()) {
            let free = !taken.get(i).copied().unwrap_or(true);
            if free && (best.is_none() || c.separation < best_s) {
                best = Some(i);
                best_s = c.separation;
            }
        }
        let Some(i) = best else { break };
        if let (Some(t), Some(c)) = (taken.get_mut(i), candidates.get(i)) {
            *t = true;
            m.push_within(*c, f32::INFINITY);
        }
    }
    m.non_empty()
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::math::vec64::Vec64;
    use crate::rng::SplitMix64;

    /// The box feature by cases: vertex, edge or face from the clamped coordinates.
    fn feature_by_cases(p: Vec3, h: Vec3) -> FeatureId {
        let side = |x: f32, hk: f32| {
            if x > hk {
                2u32
            } else if x < -hk {
                1
            } else {
                0
            }
        };
        let sides = [side(p.x, h.x), side(p.y, h.y), side(p.z, h.z)];
        let bits = (0..3)
            .filter(|&k| sides[k] == 2)
            .map(|k| 1u32 << k)
            .sum::<u32>();
        match sides.iter().filter(|&&s| s != 0).count() {
            3 => FeatureId::vertex(bits),
            2 => {
                let free = (0..3).find(|&k| sides[k] == 0).unwrap();
                FeatureId::edge(bits, bits | (1 << free))
            }
            _ => {
                let k = (0..3).find(|&k| sides[k] != 0).unwrap();
                FeatureId::face(2 * k as u32 + (sides[k] == 2) as u32)
            }
        }
    }

    #[test]
    fn clamped_feature_names_the_face_edge_or_vertex() {
        let mut rng = SplitMix64::new(41);
        let h = Vec3::new(0.5, 0.7, 0.3);
        for _ in 0..20000 {
            let p = Vec3::new(
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
                rng.range(-1.5, 1.5),
            );
            if (p.abs() - h).max_elem() <= 0.0 {
                continue; // inside: not this function's case
            }
            assert_eq!(clamped_feature(p, h), feature_by_cases(p, h), "{p:?}");
        }
    }

    /// The squared gap of the closest points of segments `p1 + s d1` and `p2 + t d2`, in
    /// f64: the gap squared is convex in `s` once `t` is the clamped projection, so a
    /// ternary search on `s` (200 rounds) finds its minimum.
    fn closest_gap_oracle(p1: Vec3, q1: Vec3, p2: Vec3, q2: Vec3) -> f64 {
        let (p1, p2) = (Vec64::of(p1), Vec64::of(p2));
        let (d1, d2) = (Vec64::of(q1) - p1, Vec64::of(q2) - p2);
        let e = d2.length_squared();
        let gap2 = |s: f64| {
            let x = p1 + d1 * s;
            let t = if e > 0.0 {
                ((x - p2).dot(d2) / e).clamp(0.0, 1.0)
            } else {
                0.0
            };
            (p2 + d2 * t - x).length_squared()
        };
        let (mut lo, mut hi) = (0.0f64, 1.0f64);
        for _ in 0..200 {
            let (m1, m2) = (lo + (hi - lo) / 3.0, hi - (hi - lo) / 3.0);
            if gap2(m1) <= gap2(m2) {
                hi = m2;
            } else {
                lo = m1;
            }
        }
        gap2(0.5 * (lo + hi)).min(gap2(0.0)).min(gap2(1.0))
    }

    /// Against the f64 oracle, for segment pairs at every angle θ from parallel within
    /// 1e-5 rad through the threshold [`WELL_CONDITIONED_SIN2`] to crossing, at a 1 m
    /// scale: above the threshold (Ericson's answer alone) the returned pair's gap is the
    /// closest within 5e-7 m (f32 rounding of the points: 9e-8 m seen); below it within
    /// 5e-7 m + 5e-8 m / sin θ (the end pairs fix a clamped answer, but a nearly parallel
    /// overlap's parameters still carry `ε / sin²θ`, worth `ε / sin θ` of gap: 1.1e-8 m
    /// seen).
    #[test]
    fn segment_closest_points_match_an_f64_oracle_at_every_angle() {
        let mut rng = SplitMix64::new(97);
        let mut cases = [0u32; 2];
        for i in 0..20000 {
            let p1 = Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
                rng.range(-1.0, 1.0),
            );
            let d1 = rng.unit_vector() * rng.range(0.05, 1.5);
            // The second segment's direction: d1 turned by an angle spread over decades.
            let angle = libm::powf(10.0, rng.range(-5.0, 0.2));
            let side = rng.unit_vector().cross(d1).normalize_or(Vec3::X);
            let along = d1.normalize_or(Vec3::X);
            let dir = along * libm::cosf(angle) + side * libm::sinf(angle);
            let p2 = p1 + rng.unit_vector() * rng.range(0.0, 0.6);
            let d2 = dir * rng.range(0.05, 1.5) * if i % 2 == 0 { 1.0 } else { -1.0 };
            let (q1, q2) = (p1 + d1, p2 + d2);
            let (s, t) = segment_closest_points(p1, q1, p2, q2);
            assert!((0.0..=1.0).contains(&s) && (0.0..=1.0).contains(&t));
            let gap = (p2 + d2 * t - p1 - d1 * s).length();
            let oracle = libm::sqrt(closest_gap_oracle(p1, q1, p2, q2)) as f32;
            let cos = d1.dot(d2) / libm::sqrtf(d1.length_squared() * d2.length_squared());
            let sin2 = 1.0 - cos * cos;
            let well = sin2 > WELL_CONDITIONED_SIN2;
            let bound = if well {
                5.0e-7
            } else {
                5.0e-7 + 5.0e-8 / libm::sqrtf(sin2.max(1.0e-12))
            };
            assert!(
                gap - oracle <= bound,
                "case {i}: {gap} against {oracle}, sin²θ {sin2}"
            );
            cases[usize::from(well)] += 1;
        }
        // Both regimes are exercised, each many times.
        assert!(cases[0] > 4000 && cases[1] > 4000, "{cases:?}");
    }
}
