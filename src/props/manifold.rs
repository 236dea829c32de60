//! Properties of [`contact`] manifolds, checked against GJK distance, EPA depth, the
//! shapes' support functions and the swapped query.

use super::{accepted_pose, check, shape_size_in_range, Violation};
use crate::collide::{
    contact, contact_into, distance, penetration, EpaStatus, Manifold, PairCache, SimplexCache,
    EDGE_DEPTH_PREFERENCE, MAX_MANIFOLD_POINTS,
};
use crate::math::{scalar, Iso, Vec3};
use crate::shape::Shape;

/// Largest coordinate and shape size (m) for which the geometric properties are checked.
/// Outside it `f32` rounding in GJK/EPA grows past the slack below; only "no panic, at
/// most 4 finite points" is checked there.
pub const MANIFOLD_WORKING_RANGE: f32 = 1.0e3;

/// Smallest height of a triangle, as a fraction of its longest edge, for which the
/// geometric properties are checked (see `well_shaped`).
const MIN_TRIANGLE_ASPECT: f32 = 1.0e-3;

/// Position slack, relative to the scene's scale `1 + |positions| + sizes` (m): `f32`
/// rounding of world ↔ local transforms and of GJK/EPA's closest points (about 1e-6
/// relative each), with room for GJK's relative tolerance.
const POSITION_SLACK: f32 = 1.0e-4;

/// How far a reported normal may be from unit length (rounding of one normalisation and
/// one rotation).
const UNIT_SLACK: f32 = 1.0e-4;

/// Allowed gap (m) between the manifold's smallest separation and the GJK distance or
/// −EPA depth, as `AGREE_ABS · scale + AGREE_REL · |s|`: a clipped face manifold is kept
/// only within 1 mm + 0.2 % of the GJK/EPA answer (the manifold's guard), the closed forms
/// and GJK/EPA each stop within their own tolerance, and `scale >= 1`.
pub const AGREE_ABS: f32 = 1.5e-3;
/// See [`AGREE_ABS`].
pub const AGREE_REL: f32 = 0.005;

/// Properties of `contact(a, pose_a, b, pose_b, margin)`:
///
/// - it never panics; it refuses exactly the invalid inputs (poses refused by
///   [`accepted_pose`], negative or non-finite margin);
/// - [`contact_into`] gives the same answer (the same error, or the same manifold bit
///   for bit, `len` 0 when apart), over a manifold that held other numbers;
/// - a manifold has 1 to [`MAX_MANIFOLD_POINTS`] points, all finite, a unit normal, and
///   every separation `<= margin`;
///
/// and in the working range (coordinates, sizes and margin within [`MANIFOLD_WORKING_RANGE`],
/// shape sizes in range by [`shape_size_in_range`], no needle triangles):
///
/// - every separation equals `(point_b − point_a) · normal`;
/// - `local_a` maps to `point_a` by `pose_a`, `local_b` to `point_b` by `pose_b`;
/// - `point_a` is in or on A (within slack, by plane distances, not GJK) and not beyond
///   A's support plane along the normal; `point_b` likewise for B along the reversed
///   normal;
/// - the smallest separation agrees with the GJK distance (separated) or minus the EPA
///   depth (overlapping) within the slack of [`AGREE_ABS`], except that two overlapping
///   polytopes may report up to [`FACE_PREFERENCE_DEPTH`] of the depth deeper (a face
///   preferred to an edge pair), and that where EPA only bounds the depth (not
///   converged) the manifold is merely not deeper than that bound; `None` means GJK sees the shapes further apart than
///   `margin` (minus slack);
/// - symmetry: `contact(b, a)` has the same smallest separation and, unless both shapes
///   are polytopes (computed independently in each order), the negated normal.
pub fn manifold_properties(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
) -> Result<(), Violation> {
    let valid =
        accepted_pose(pose_a) && accepted_pose(pose_b) && margin.is_finite() && margin >= 0.0;
    let result = contact(a, pose_a, b, pose_b, margin);
    into_agrees(a, pose_a, b, pose_b, margin, &result)?;
    let Ok(found) = result else {
        return check(!valid, "manifold: valid input refused");
    };
    check(valid, "manifold: invalid input accepted")?;
    // The swapped query gets the poses exactly as given; every other statement below is
    // about the unit-rotation poses contact() works with.
    let (given_a, given_b) = (pose_a, pose_b);
    let pose_a = &unit(pose_a);
    let pose_b = &unit(pose_b);
    if let Some(m) = &found {
        basic_properties(m, margin)?;
    }
    if !in_working_range(a, pose_a, b, pose_b, margin) {
        return Ok(());
    }
    let scale = scene_scale(a, pose_a, b, pose_b);
    let slack = POSITION_SLACK * scale;
    let Some(m) = found else {
        return none_is_apart(a, pose_a, b, pose_b, margin, scale);
    };
    for p in m.points() {
        let sep = (p.point_b - p.point_a).dot(m.normal);
        check(
            scalar::abs(sep - p.separation) <= slack,
            "manifold: separation is not (point_b - point_a) . normal",
        )?;
        check(
            (pose_a.transform_point(p.local_a) - p.point_a).length() <= slack,
            "manifold: local_a does not map to point_a",
        )?;
        check(
            (pose_b.transform_point(p.local_b) - p.point_b).length() <= slack,
            "manifold: local_b does not map to point_b",
        )?;
        check(
            on_or_in(a, pose_a, p.point_a, m.normal, slack),
            "manifold: point_a not on A",
        )?;
        check(
            on_or_in(b, pose_b, p.point_b, -m.normal, slack),
            "manifold: point_b not on B",
        )?;
    }
    agrees_with_gjk_epa(a, pose_a, b, pose_b, &m, scale)?;
    symmetric(a, given_a, b, given_b, margin, &m, scale)
}

/// [`contact_into`] answers as [`contact`] did (`result`), written over a manifold of
/// other numbers.
fn into_agrees(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    result: &Result<Option<Manifold>, crate::Error>,
) -> Result<(), Violation> {
    let mut out = Manifold {
        normal: Vec3::splat(7.0),
        len: 3,
        ..Manifold::default()
    };
    let got = contact_into(
        a,
        pose_a,
        b,
        pose_b,
        margin,
        &mut PairCache::default(),
        &mut out,
    );
    let agrees = match (result, got) {
        (Err(want), Err(got)) => *want == got,
        (Ok(None), Ok(false)) => out.len == 0,
        (Ok(Some(m)), Ok(true)) => same_bits(m, &out),
        _ => false,
    };
    check(agrees, "manifold: contact_into differs from contact")
}

/// The two manifolds' used parts are equal to the bit.
fn same_bits(m: &Manifold, n: &Manifold) -> bool {
    let v = |x: Vec3| [x.x.to_bits(), x.y.to_bits(), x.z.to_bits()];
    let point = |p: &crate::collide::ManifoldPoint| {
        let [a, b, c, d] = [p.point_a, p.point_b, p.local_a, p.local_b].map(v);
        (a, b, c, d, p.separation.to_bits(), p.id)
    };
    m.len == n.len
        && m.depth_bound == n.depth_bound
        && v(m.normal) == v(n.normal)
        && m.points()
            .iter()
            .map(point)
            .eq(n.points().iter().map(point))
}

/// Point count, finiteness, unit normal, separations within the margin.
fn basic_properties(m: &Manifold, margin: f32) -> Result<(), Violation> {
    let n = m.points().len();
    check(
        (1..=MAX_MANIFOLD_POINTS).contains(&n) && m.len as usize == n,
        "manifold: point count not in 1..=4",
    )?;
    check(m.normal.is_finite(), "manifold: normal not finite")?;
    check(
        scalar::abs(m.normal.length() - 1.0) <= UNIT_SLACK,
        "manifold: normal not unit",
    )?;
    for p in m.points() {
        let finite = p.point_a.is_finite()
            && p.point_b.is_finite()
            && p.local_a.is_finite()
            && p.local_b.is_finite()
            && p.separation.is_finite();
        check(finite, "manifold: point not finite")?;
        check(p.separation <= margin, "manifold: separation beyond margin")?;
    }
    Ok(())
}

/// `pose` with its rotation renormalised, as `contact` uses it.
fn unit(pose: &Iso) -> Iso {
    Iso::new(pose.position, pose.rotation.normalize())
}

/// Size of a shape for the working range and slack: its bounding radius, or 0 for a
/// half-space (its extent is infinite but its geometry is one plane).
fn size(s: &Shape) -> f32 {
    match s {
        Shape::HalfSpace(_) => 0.0,
        _ => s.bounding_radius(),
    }
}

fn scene_scale(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> f32 {
    1.0 + pose_a.position.abs().max_elem() + pose_b.position.abs().max_elem() + size(a) + size(b)
}

fn in_working_range(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso, margin: f32) -> bool {
    let r = MANIFOLD_WORKING_RANGE;
    pose_a.position.abs().max_elem() <= r
        && pose_b.position.abs().max_elem() <= r
        && size(a) <= r
        && size(b) <= r
        && margin <= r
        && well_shaped(a)
        && well_shaped(b)
        && shape_size_in_range(a)
        && shape_size_in_range(b)
}

/// False for a needle triangle, thinner than [`MIN_TRIANGLE_ASPECT`] of its longest
/// edge: its normal is then only known to about `f32` epsilon over that ratio, and plane
/// distances of its far vertices are noise.
fn well_shaped(s: &Shape) -> bool {
    let Shape::Triangle(t) = s else {
        return true;
    };
    let [v0, v1, v2] = t.vertices;
    let twice_area = (v1 - v0).cross(v2 - v0).length();
    let mut longest = 0.0;
    for e in [v1 - v0, v2 - v1, v0 - v2] {
        longest = scalar::max(longest, e.length_squared());
    }
    twice_area >= MIN_TRIANGLE_ASPECT * longest
}

/// True when `p` (world) lies in or on `shape` within `slack` (by [`outside_by`]), and not
/// beyond the shape's support plane along the unit `dir`.
fn on_or_in(shape: &Shape, pose: &Iso, p: Vec3, dir: Vec3, slack: f32) -> bool {
    let local = pose.inverse_transform_point(p);
    let inside = outside_by(shape, local) <= slack; // false for NaN too
    if !inside {
        return false;
    }
    if let Shape::HalfSpace(_) = shape {
        return true; // its support plane along any direction but −n is at infinity
    }
    let support = pose.transform_point(shape.support(pose.inverse_transform_vector(dir)));
    dir.dot(p - support) <= slack
}

/// How far the local point `p` is outside `shape` (m), `<= 0` inside; a lower bound of the
/// distance that is exact over faces: the largest signed distance to a bounding plane
/// (cuboid, hull, half-space), to the plane and edges (triangle), or to the core minus the
/// radius (sphere, capsule). An oracle independent of GJK.
fn outside_by(shape: &Shape, p: Vec3) -> f32 {
    match shape {
        Shape::Sphere(s) => p.length() - s.radius,
        Shape::Capsule(c) => {
            let y = scalar::clamp(p.y, -c.half_height, c.half_height);
            (p - Vec3::new(0.0, y, 0.0)).length() - c.radius
        }
        Shape::Cuboid(c) => (p.abs() - c.half_extents).max_elem(),
        Shape::Hull(h) => {
            let mut out = f32::NEG_INFINITY;
            for f in 0..h.face_count() {
                let (n, d) = h.plane(f);
                out = scalar::max(out, n.dot(p) - d);
            }
            out
        }
        Shape::HalfSpace(h) => h.normal.dot(p),
        Shape::Triangle(t) => {
            let n = t.normal();
            let [v0, v1, v2] = t.vertices;
            let mut out = scalar::abs(n.dot(p - v0));
            for (u, v) in [(v0, v1), (v1, v2), (v2, v0)] {
                let outward = (v - u).cross(n).normalize_or(Vec3::ZERO);
                out = scalar::max(out, outward.dot(p - u));
            }
            out
        }
        // Not convex: the narrow phase never sees them; the least over their parts
        // would be the answer, and no property asks for it.
        Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => f32::NAN,
    }
}

/// The GJK distance (separated) or minus the EPA depth (overlapping) of two shapes, or
/// `None` when GJK and EPA disagree about overlap.
fn true_separation(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> Option<f32> {
    let mut cache = SimplexCache::default();
    let d = distance(a, pose_a, b, pose_b, &mut cache).ok()?;
    if d.distance > 0.0 {
        return Some(d.distance);
    }
    match penetration(a, pose_a, b, pose_b).ok()? {
        Some(p) => Some(-p.depth),
        None => Some(0.0),
    }
}

/// EPA's depth bound (m) when it stopped at a bound on an overlapping pair in either
/// order (the deeper of the two when both did), `None` when both orders converged. The
/// manifold runs in one canonical order whatever the argument order, so a bound in the
/// other order is the one it may have met (fuzz finding
/// `capsule-core-touching-a-hull-549aad0e`: the capsule first converges to 7.890 m, the
/// hull first, the manifold's order, only bounds it at 8.163 m).
fn epa_bound(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> Option<f32> {
    let bound = |x: &Shape, px: &Iso, y: &Shape, py: &Iso| match penetration(x, px, y, py) {
        Ok(Some(p)) if p.status != EpaStatus::Converged => Some(p.depth),
        _ => None,
    };
    match (bound(a, pose_a, b, pose_b), bound(b, pose_b, a, pose_a)) {
        (Some(x), Some(y)) => Some(scalar::max(x, y)),
        (x, None) => x,
        (None, y) => y,
    }
}

fn agree_slack(scale: f32, s: f32) -> f32 {
    AGREE_ABS * scale + AGREE_REL * scalar::abs(s)
}

/// `None` must mean the shapes are apart by more than the margin (minus slack).
fn none_is_apart(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    scale: f32,
) -> Result<(), Violation> {
    if matches!((a, b), (Shape::HalfSpace(_), Shape::HalfSpace(_))) {
        return Ok(());
    }
    let Some(s) = true_separation(a, pose_a, b, pose_b) else {
        return Ok(());
    };
    check(
        s > margin - agree_slack(scale, s),
        "manifold: None for shapes within the margin",
    )
}

/// How much deeper than the minimal penetration (EPA) an overlapping polytope pair's
/// manifold may be, as a fraction of that depth: its face was preferred to an edge pair
/// shallower by up to [`EDGE_DEPTH_PREFERENCE`] of the face's depth, so the face is at
/// most `p / (1 − p)` deeper.
pub const FACE_PREFERENCE_DEPTH: f32 = EDGE_DEPTH_PREFERENCE / (1.0 - EDGE_DEPTH_PREFERENCE);

fn agrees_with_gjk_epa(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    m: &Manifold,
    scale: f32,
) -> Result<(), Violation> {
    if matches!((a, b), (Shape::HalfSpace(_), Shape::HalfSpace(_))) {
        return check(false, "manifold: two half-spaces touched");
    }
    let Some(s) = true_separation(a, pose_a, b, pose_b) else {
        return Ok(());
    };
    let slack = agree_slack(scale, s);
    let bound = if s < 0.0 {
        epa_bound(a, pose_a, b, pose_b)
    } else {
        None
    };
    if let Some(bound) = bound {
        // EPA stopped at a bound in one order (a Minkowski difference too thin to expand,
        // or its caps): that depth is only an upper bound, and the manifold may stand on
        // it, never deeper (fuzz findings `bounded-capsule-hull-02612b2b`, a capsule whose
        // core just touches a hull, 7.890 m deep by the manifold, bounded at 8.175 m by
        // EPA; and `capsule-core-touching-a-hull-549aad0e`, the bound in the other order).
        return check(
            m.min_separation() >= scalar::min(s, -bound) - slack,
            "manifold: deeper than EPA's bound",
        );
    }
    if m.depth_bound {
        // The manifold's own EPA (in the f32 relative pose of the pair's canonical order)
        // stopped at a bound where the public queries (f64 relative pose) converged:
        // an upper bound on the depth, never shallower than the exact one (fuzz finding
        // `capsule-core-touching-a-hull-7d7caaf2`).
        return check(
            m.min_separation() <= s + slack,
            "manifold: a bounded depth shallower than the exact one",
        );
    }
    // Two overlapping polytopes: a face may stand in for a slightly shallower edge pair.
    let deeper = if is_polytope(a) && is_polytope(b) && s < 0.0 {
        FACE_PREFERENCE_DEPTH * -s
    } else {
        0.0
    };
    let d = m.min_separation();
    check(
        d <= s + slack && d >= s - deeper - slack,
        "manifold: smallest separation disagrees with GJK/EPA",
    )
}

/// `contact(b, a)` against `m = contact(a, b)`.
fn symmetric(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    margin: f32,
    m: &Manifold,
    scale: f32,
) -> Result<(), Violation> {
    let s = m.min_separation();
    let slack = agree_slack(scale, s);
    let Ok(swapped) = contact(b, pose_b, a, pose_a, margin) else {
        return check(false, "manifold: swapped query refused");
    };
    let Some(w) = swapped else {
        // Only a pair right at the margin may be found one way and not the other.
        return check(s > margin - slack, "manifold: swapped query found nothing");
    };
    check(
        scalar::abs(w.min_separation() - s) <= slack,
        "manifold: swapped query has another smallest separation",
    )?;
    // When the cores touch (separation = −(radius A + radius B)) the normal is a fixed
    // fallback (world +Y) both ways, so only the separations are compared.
    if scalar::abs(s + a.radius() + b.radius()) <= POSITION_SLACK * scale {
        return Ok(());
    }
    // Two polytopes are computed independently in each order: deep inside each other
    // EPA may find another axis of the same depth (two cubes at one centre have six), and
    // each order may pick another reference face, so only the separations are compared.
    // Every other pair is computed once and flipped, or by a closed form that is
    // symmetric by construction: reversed normals up to rounding.
    if is_polytope(a) && is_polytope(b) {
        return Ok(());
    }
    check(
        w.normal.dot(m.normal) <= -1.0 + 1.0e-6,
        "manifold: swapped query's normal is not reversed",
    )
}

fn is_polytope(s: &Shape) -> bool {
    matches!(s, Shape::Cuboid(_) | Shape::Hull(_) | Shape::Triangle(_))
}
