//! Properties of the narrow phase: GJK [`distance`] and EPA [`penetration`], checked
//! against the shapes' support functions, the swapped query, translations along the
//! answer, and a brute-force distance oracle for polytope cores.

use super::{check, Violation};
use crate::collide::{
    distance, penetration, segment_closest_points, separation, EpaStatus, Penetration,
    SeparationStatus, SimplexCache, MAX_GJK_ITERATIONS,
};
use crate::error::MAX_COORDINATE;
use crate::math::{scalar, Iso, Vec3};
use crate::shape::{Shape, MAX_HULL_VERTICES, MAX_SIZE, MIN_SIZE};

/// Largest scene scale (m, see [`query_scale`]) for which the geometric properties are
/// checked. Beyond it f32 rounding of world coordinates grows past [`SLACK`]; only "no
/// panic, finite output, unit normal, non-negative distance" is checked there.
pub const WORKING_RANGE: f32 = 1.0e3;

/// True when every half-width of `shape` lies in [[`MIN_SIZE`], [`MAX_SIZE`]], the range
/// the constructors enforce for spheres, capsules and cuboids; the geometric properties
/// are checked only then. Below it a face is thinner than the f32 rounding of the
/// coordinates it sits at (the fuzzer's 1.1e-38 m box under a 3.6 m capsule) and its side
/// planes are noise. The half-widths: a sphere's or capsule's radius, a capsule's
/// half-height, a cuboid's half-extents; for a hull (not range-checked at construction)
/// half its thinnest width and its local box's half-extents; for a triangle half its
/// height over the longest edge and half that edge. A half-space has none. False for NaN.
pub fn shape_size_in_range(shape: &Shape) -> bool {
    let ok = |x: f32| (MIN_SIZE..=MAX_SIZE).contains(&x);
    match shape {
        Shape::HalfSpace(_) => true,
        Shape::Sphere(s) => ok(s.radius),
        Shape::Capsule(c) => ok(c.radius) && ok(c.half_height),
        Shape::Cuboid(c) => {
            let h = c.half_extents;
            ok(h.x) && ok(h.y) && ok(h.z)
        }
        Shape::Hull(_) => {
            let half = shape.local_aabb().half_extents();
            ok(0.5 * shape.min_extent()) && half.max_elem() <= MAX_SIZE
        }
        Shape::Triangle(t) => {
            let [v0, v1, v2] = t.vertices;
            let twice_area = (v1 - v0).cross(v2 - v0).length();
            let mut longest = 0.0;
            for e in [v1 - v0, v2 - v1, v0 - v2] {
                longest = scalar::max(longest, e.length());
            }
            // Height over the longest edge: twice the area over that edge.
            let height = if longest > 0.0 {
                twice_area / longest
            } else {
                0.0
            };
            ok(0.5 * height) && ok(0.5 * longest)
        }
        // Not single convex shapes: their parts are checked where they are built.
        Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => false,
    }
}

/// Geometric slack, relative to the scene scale: f32 carries about 6e-8 relative
/// precision; a world ↔ local transform, GJK's closest points (its relative stop
/// tolerance is 1e-6) and EPA's plane distances (relative tolerance 1e-5) each add a few
/// ulps to a few 1e-5, so 1e-4 of the scale separates a wrong answer from rounding.
pub const SLACK: f32 = 1.0e-4;

/// How far a reported normal may be from unit length (one normalisation, one rotation).
const UNIT_SLACK: f32 = 1.0e-4;

/// Translation probe of the penetration properties, relative to the scene scale: ten
/// times [`SLACK`], so a correct depth passes both probes with room for rounding.
pub const PROBE: f32 = 1.0e-3;

/// Most core vertices per shape for which the brute-force oracle runs in
/// [`distance_properties`]; the oracle costs `O(n⁴)` and hulls may have up to
/// [`MAX_HULL_VERTICES`].
pub const ORACLE_MAX_VERTICES: usize = 24;

/// Directions along which "the point is inside the shape" is probed: the six axes and
/// the eight diagonals.
const PROBES: [Vec3; 14] = {
    const D: f32 = 0.577_350_26; // 1/√3
    [
        Vec3::new(1.0, 0.0, 0.0),
        Vec3::new(-1.0, 0.0, 0.0),
        Vec3::new(0.0, 1.0, 0.0),
        Vec3::new(0.0, -1.0, 0.0),
        Vec3::new(0.0, 0.0, 1.0),
        Vec3::new(0.0, 0.0, -1.0),
        Vec3::new(D, D, D),
        Vec3::new(D, D, -D),
        Vec3::new(D, -D, D),
        Vec3::new(D, -D, -D),
        Vec3::new(-D, D, D),
        Vec3::new(-D, D, -D),
        Vec3::new(-D, -D, D),
        Vec3::new(-D, -D, -D),
    ]
};

/// Properties of [`distance`] for `a` at `pose_a` and `b` at `pose_b`:
///
/// - it never panics and refuses exactly the invalid poses (non-finite, non-unit
///   rotation, a coordinate beyond ±[`MAX_COORDINATE`]: see [`accepted_pose`]); the
///   rest is checked on the poses with their rotations normalised;
/// - the output is finite, `distance >= 0`, the normal unit length, the iteration count
///   at most [`MAX_GJK_ITERATIONS`];
/// - in the [`WORKING_RANGE`] with shape sizes in range ([`shape_size_in_range`]), with
///   slack `SLACK · scale`: each point lies in its shape
///   (by support functions: `u·p <= h(u)` along 14 probe directions); when separated,
///   `|point_b − point_a| = distance`, the normal is along `point_b − point_a`, and each
///   point is its shape's support point along the normal (`n·p_a = h_A(n)`,
///   `−n·p_b = h_B(−n)`);
/// - symmetry: `distance(b, a)` is the same distance with the negated separation vector
///   (within what a distance error of `tol` allows, see `vector_slack`);
/// - warm start: a second call with the cache of the first gives the same distance;
/// - for shapes other than half-spaces with at most [`ORACLE_MAX_VERTICES`] core
///   vertices: the distance equals `max(oracle − ra − rb, 0)` with the
///   [`brute_force_distance`] of the cores, and the separation vectors agree.
pub fn distance_properties(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
) -> Result<(), Violation> {
    let valid = accepted_pose(pose_a) && accepted_pose(pose_b);
    let result = distance(a, pose_a, b, pose_b, &mut SimplexCache::default());
    if result.is_err() {
        return check(!valid, "distance: valid pose refused");
    }
    check(valid, "distance: invalid pose accepted")?;
    let (pose_a, pose_b) = (&unit(pose_a), &unit(pose_b));
    let mut cache = SimplexCache::default();
    let out = distance(a, pose_a, b, pose_b, &mut cache)
        .map_err(|_| Violation("distance: normalised pose refused"))?;
    check(
        out.distance.is_finite()
            && out.point_a.is_finite()
            && out.point_b.is_finite()
            && out.normal.is_finite(),
        "distance: non-finite output",
    )?;
    check(out.distance >= 0.0, "distance: negative distance")?;
    check(is_unit(out.normal), "distance: normal not unit length")?;
    check(
        out.iterations <= MAX_GJK_ITERATIONS,
        "distance: too many iterations",
    )?;
    let scale = query_scale(a, pose_a, b, pose_b);
    if !in_working_range(a, b, scale) {
        return Ok(());
    }
    let tol = SLACK * scale;
    let (d, n) = (out.distance, out.normal);
    check(
        inside(a, pose_a, out.point_a, tol),
        "distance: point_a not in A",
    )?;
    check(
        inside(b, pose_b, out.point_b, tol),
        "distance: point_b not in B",
    )?;
    if d > tol {
        let v = out.point_b - out.point_a;
        check(
            scalar::abs(v.length() - d) <= tol,
            "distance: |point_b − point_a| differs from the distance",
        )?;
        check(
            (v - n * d).length() <= 2.0 * tol,
            "distance: normal not along point_b − point_a",
        )?;
        // The normal's direction is GJK's `v`, resolved to `GJK_NORMAL_ANGLE` (see there):
        // along a normal tilted by that much, a point of a face parallel to the other
        // shape's face falls short of the support by up to the tilt times the face's span.
        check(
            on_support(a, pose_a, out.point_a, n, tol + normal_tilt_slack(a)),
            "distance: point_a not A's support point along the normal",
        )?;
        check(
            on_support(b, pose_b, out.point_b, -n, tol + normal_tilt_slack(b)),
            "distance: point_b not B's support point against the normal",
        )?;
    }
    let swapped = distance(b, pose_b, a, pose_a, &mut SimplexCache::default())
        .map_err(|_| Violation("distance: swapped query refused"))?;
    check(
        scalar::abs(swapped.distance - d) <= tol,
        "distance: distance(b, a) differs from distance(a, b)",
    )?;
    if d > tol && swapped.distance > tol {
        check(
            (n * d + swapped.normal * swapped.distance).length() <= vector_slack(d, tol),
            "distance: swapped normal is not the negated normal",
        )?;
    }
    let warm = distance(a, pose_a, b, pose_b, &mut cache)
        .map_err(|_| Violation("distance: warm-started query refused"))?;
    check(
        scalar::abs(warm.distance - d) <= tol,
        "distance: warm start changes the distance",
    )?;
    if let (Some(va), Some(vb)) = (core_vertices(a, pose_a), core_vertices(b, pose_b)) {
        if va.len <= ORACLE_MAX_VERTICES && vb.len <= ORACLE_MAX_VERTICES {
            if let Some(o) = brute_force_distance(va.points(), vb.points()) {
                let gap = o.distance - a.radius() - b.radius();
                let expected = scalar::max(gap, 0.0);
                check(
                    scalar::abs(d - expected) <= tol,
                    "distance: disagrees with the brute-force oracle",
                )?;
                if d > tol && expected > tol {
                    let dir = (o.point_b - o.point_a).normalize_or(n);
                    check(
                        (n * d - dir * expected).length() <= vector_slack(d, tol),
                        "distance: separation vector disagrees with the oracle",
                    )?;
                }
            }
        }
    }
    Ok(())
}

/// Properties of [`penetration`] for `a` at `pose_a` and `b` at `pose_b`:
///
/// - it never panics and refuses exactly the invalid poses;
/// - `None` exactly when GJK reports a distance `> 0` (or both are half-spaces);
/// - `Some`: finite, `depth >= 0`, unit normal;
/// - in the [`WORKING_RANGE`] with shape sizes in range ([`shape_size_in_range`]), with
///   slack `SLACK · scale` and probe `PROBE · scale`:
///   both points lie in their shapes; for converged answers
///   `point_b − point_a = −depth · normal`; moving B by `(depth + probe) · normal`
///   separates the shapes per GJK (every status, except GJK's own iteration cap on the
///   cores-apart path, whose depth is a lower bound); for converged answers deeper than
///   two probes, moving B by `(depth − probe) · normal` leaves them overlapping;
/// - symmetry: `penetration(b, a)` exists (unless the depth is within the slack of 0),
///   and when both converged has the same depth.
pub fn penetration_properties(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
) -> Result<(), Violation> {
    let valid = accepted_pose(pose_a) && accepted_pose(pose_b);
    if penetration(a, pose_a, b, pose_b).is_err() {
        return check(!valid, "penetration: valid pose refused");
    }
    check(valid, "penetration: invalid pose accepted")?;
    let (pose_a, pose_b) = (&unit(pose_a), &unit(pose_b));
    let found = penetration(a, pose_a, b, pose_b)
        .map_err(|_| Violation("penetration: normalised pose refused"))?;
    let gjk = distance(a, pose_a, b, pose_b, &mut SimplexCache::default())
        .map_err(|_| Violation("penetration: GJK refused the poses"))?;
    let two_planes = matches!((a, b), (Shape::HalfSpace(_), Shape::HalfSpace(_)));
    let Some(p) = found else {
        return check(
            two_planes || gjk.distance > 0.0,
            "penetration: None while GJK reports distance 0",
        );
    };
    check(!two_planes, "penetration: two half-spaces gave a depth")?;
    check(
        gjk.distance <= 0.0,
        "penetration: Some while GJK reports a distance",
    )?;
    check(
        p.depth.is_finite()
            && p.normal.is_finite()
            && p.point_a.is_finite()
            && p.point_b.is_finite(),
        "penetration: non-finite output",
    )?;
    check(p.depth >= 0.0, "penetration: negative depth")?;
    check(is_unit(p.normal), "penetration: normal not unit length")?;
    let scale = query_scale(a, pose_a, b, pose_b);
    if !in_working_range(a, b, scale) {
        return Ok(());
    }
    let tol = SLACK * scale;
    let probe = PROBE * scale;
    check(
        inside(a, pose_a, p.point_a, tol),
        "penetration: point_a not in A",
    )?;
    check(
        inside(b, pose_b, p.point_b, tol),
        "penetration: point_b not in B",
    )?;
    let converged = p.status == EpaStatus::Converged;
    if converged {
        // Along the normal the points are `depth` apart to the slack. Across it, GJK's
        // closest points (the deepest points of shapes whose cores are apart) are
        // barycentric combinations that may slide along a touching edge or face by
        // `GJK_NORMAL_ANGLE` of the span, as GJK's normal may lean (fuzz finding
        // `sphere-on-a-hull-edge-5c8d31d2`: a sphere's centre on a hull's edge, its deepest
        // point on B 3.4 mm along the 11 m edge); depth and normal stay exact.
        let gap = p.point_b - p.point_a + p.normal * p.depth;
        let along = p.normal.dot(gap);
        let across = (gap - p.normal * along).length();
        let slide = normal_tilt_slack(a) + normal_tilt_slack(b);
        check(
            scalar::abs(along) <= 2.0 * tol && across <= 2.0 * tol + slide,
            "penetration: point_b − point_a is not −depth · normal",
        )?;
    }
    let gjk_capped = p.status == EpaStatus::IterationLimit && p.iterations == 0;
    if !gjk_capped {
        check(
            !touching_after(a, pose_a, b, pose_b, &p, p.depth + probe)?,
            "penetration: moving B by depth + probe does not separate",
        )?;
    }
    if converged && p.depth > 2.0 * probe {
        check(
            touching_after(a, pose_a, b, pose_b, &p, p.depth - probe)?,
            "penetration: moving B by depth − probe already separates",
        )?;
    }
    let swapped = penetration(b, pose_b, a, pose_a)
        .map_err(|_| Violation("penetration: swapped query refused"))?;
    let Some(q) = swapped else {
        // Touching within rounding may read as apart the other way round.
        return check(
            p.depth <= tol,
            "penetration: swapped query finds no overlap",
        );
    };
    if converged && q.status == EpaStatus::Converged {
        check(
            scalar::abs(q.depth - p.depth) <= tol,
            "penetration: depth(b, a) differs from depth(a, b)",
        )?;
    }
    Ok(())
}

/// Properties of [`separation`] for `a` at `pose_a` and `b` at `pose_b`:
///
/// - it never panics and refuses exactly the invalid poses ([`accepted_pose`]);
/// - the output is finite with a unit normal; two half-spaces give
///   [`SeparationStatus::HalfSpaces`] at 0;
/// - it is the other queries' answer to the bit: `distance` (with a fresh cache) and its
///   points when that is `> 0`, else minus the depth of `penetration` with its normal and
///   points (0 when `penetration` finds none);
/// - in the [`WORKING_RANGE`] with shape sizes in range, unless either order is
///   [`SeparationStatus::Bounded`]: `separation(b, a)` is the same separation within
///   `SLACK · scale`.
pub fn separation_properties(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
) -> Result<(), Violation> {
    let valid = accepted_pose(pose_a) && accepted_pose(pose_b);
    if separation(a, pose_a, b, pose_b).is_err() {
        return check(!valid, "separation: valid pose refused");
    }
    check(valid, "separation: invalid pose accepted")?;
    let (pose_a, pose_b) = (&unit(pose_a), &unit(pose_b));
    let s = separation(a, pose_a, b, pose_b)
        .map_err(|_| Violation("separation: normalised pose refused"))?;
    check(
        s.separation.is_finite()
            && s.normal.is_finite()
            && s.point_a.is_finite()
            && s.point_b.is_finite(),
        "separation: non-finite output",
    )?;
    check(is_unit(s.normal), "separation: normal not unit length")?;
    if matches!((a, b), (Shape::HalfSpace(_), Shape::HalfSpace(_))) {
        return check(
            s.status == SeparationStatus::HalfSpaces && s.separation == 0.0,
            "separation: two half-spaces not reported as such",
        );
    }
    let d = distance(a, pose_a, b, pose_b, &mut SimplexCache::default())
        .map_err(|_| Violation("separation: GJK refused the poses"))?;
    if d.distance > 0.0 {
        check(
            s.separation == d.distance && s.point_a == d.point_a && s.point_b == d.point_b,
            "separation: differs from distance",
        )?;
    } else {
        let p = penetration(a, pose_a, b, pose_b)
            .map_err(|_| Violation("separation: EPA refused the poses"))?;
        match p {
            Some(p) => check(
                s.separation == 0.0 - p.depth
                    && s.normal == p.normal
                    && s.point_a == p.point_a
                    && s.point_b == p.point_b,
                "separation: differs from minus the penetration depth",
            )?,
            None => check(s.separation == 0.0, "separation: touching but not 0")?,
        }
    }
    let scale = query_scale(a, pose_a, b, pose_b);
    if !in_working_range(a, b, scale) {
        return Ok(());
    }
    let w = separation(b, pose_b, a, pose_a)
        .map_err(|_| Violation("separation: swapped query refused"))?;
    // A bounded answer (EPA's polytope or iteration bound, or a Minkowski difference too
    // flat for it) is only a bound, as for `penetration` (fuzz finding
    // `bounded-capsule-hull-a73bb2b0`: 7.920 m bounded against 7.890 m converged).
    if s.status == SeparationStatus::Bounded || w.status == SeparationStatus::Bounded {
        return Ok(());
    }
    check(
        scalar::abs(w.separation - s.separation) <= SLACK * scale,
        "separation: separation(b, a) differs from separation(a, b)",
    )
}

/// True when the geometric properties apply: the scene scale is at most
/// [`WORKING_RANGE`] and both shapes' sizes are in range ([`shape_size_in_range`]).
fn in_working_range(a: &Shape, b: &Shape, scale: f32) -> bool {
    scale <= WORKING_RANGE && shape_size_in_range(a) && shape_size_in_range(b)
}

/// True when GJK sees `a` and `b` touching after B moved by `t · p.normal`.
fn touching_after(
    a: &Shape,
    pose_a: &Iso,
    b: &Shape,
    pose_b: &Iso,
    p: &Penetration,
    t: f32,
) -> Result<bool, Violation> {
    let moved = Iso::new(pose_b.position + p.normal * t, pose_b.rotation);
    let d = distance(a, pose_a, b, &moved, &mut SimplexCache::default())
        .map_err(|_| Violation("penetration: moved pose refused"))?;
    Ok(d.distance <= 0.0)
}

/// How far two separation vectors `point_b − point_a` of the same pair may differ when
/// each distance is within `tol` of the true `d`. With `v` the closest point of the convex
/// set `D = B − A` and `x ∈ D`, `v·(x − v) >= 0`, so `|x − v|² <= |x|² − |v|² <=
/// (2d + tol) tol`: the vector is only as well determined as the square root of the
/// distance's error (far-apart shapes with faces facing each other). Plus `2 tol` for
/// rounding of the points themselves.
fn vector_slack(d: f32, tol: f32) -> f32 {
    scalar::sqrt((2.0 * d + tol) * tol) + 2.0 * tol
}

/// True for a pose the queries accept: finite, unit rotation, every coordinate within
/// ±[`MAX_COORDINATE`] (the API refuses farther positions with `OutOfRange`).
pub fn accepted_pose(pose: &Iso) -> bool {
    pose.is_valid() && pose.position.abs().max_elem() <= MAX_COORDINATE
}

/// The pose with its rotation normalised (the API accepts `|q|²` within 1e-3 of 1).
fn unit(pose: &Iso) -> Iso {
    Iso::new(pose.position, pose.rotation.normalize())
}

fn is_unit(n: Vec3) -> bool {
    scalar::abs(n.length() - 1.0) <= UNIT_SLACK
}

/// The scene scale (m): `1 + |positions| + bounding radii` (a half-space counts 0).
/// Tolerances are relative to it.
pub fn query_scale(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> f32 {
    let size = |s: &Shape| match s {
        Shape::HalfSpace(_) => 0.0,
        _ => s.bounding_radius(),
    };
    1.0 + pose_a.position.length() + pose_b.position.length() + size(a) + size(b)
}

/// `max_{x ∈ shape} u·x` (world frame), `None` for a half-space (unbounded).
fn support_height(shape: &Shape, pose: &Iso, u: Vec3) -> Option<f32> {
    match shape {
        Shape::HalfSpace(_) => None,
        _ => {
            let local = shape.support(pose.inverse_transform_vector(u));
            Some(u.dot(pose.transform_point(local)))
        }
    }
}

/// `p` is in the shape within `tol`, probed along [`PROBES`] (and, for a half-space, its
/// normal).
fn inside(shape: &Shape, pose: &Iso, p: Vec3, tol: f32) -> bool {
    if let Shape::HalfSpace(h) = shape {
        let n = pose.transform_vector(h.normal);
        return n.dot(p - pose.position) <= tol;
    }
    PROBES
        .iter()
        .all(|u| support_height(shape, pose, *u).is_some_and(|h| u.dot(p) <= h + tol))
}

/// `p` is the shape's support point along unit `u` within `tol`: `u·p >= h(u) − tol`.
/// A half-space supports only along its normal: there `p` must be on the plane.
/// How far GJK's normal of separated shapes may be tilted (rad). GJK measures its closest
/// point `v` by `|v|²` in `f32`, which cannot tell two points of a face parallel to the
/// other shape's face apart when their lateral offsets differ by less than
/// `|v| · √(2⁻²³) ≈ 3.5e-4 |v|`: where two faces are parallel, `v` (and with it the
/// normal) may lean by about 3.5e-4 rad while the distance stays exact (fuzz finding
/// `parallel-faces-47774539`: two boxes 2.97 m apart face to face, a tilt of 3.8e-4 rad).
/// Three times that, for the rounding of the supports themselves.
pub const GJK_NORMAL_ANGLE: f32 = 1.0e-3;

/// The shortfall from the support that a normal tilted by [`GJK_NORMAL_ANGLE`] allows a
/// point of `shape`: the tilt times the core's span (twice its bounding radius). A
/// half-space's face is checked by its own normal ([`on_support`]), so 0.
fn normal_tilt_slack(shape: &Shape) -> f32 {
    if matches!(shape, Shape::HalfSpace(_)) {
        0.0
    } else {
        GJK_NORMAL_ANGLE * 2.0 * shape.bounding_radius()
    }
}

fn on_support(shape: &Shape, pose: &Iso, p: Vec3, u: Vec3, tol: f32) -> bool {
    if let Shape::HalfSpace(h) = shape {
        let n = pose.transform_vector(h.normal);
        if n.dot(u) >= 1.0 - UNIT_SLACK {
            return scalar::abs(n.dot(p - pose.position)) <= tol;
        }
        return true;
    }
    support_height(shape, pose, u).is_some_and(|h| u.dot(p) >= h - tol)
}

/// The vertices of a shape's core in the world frame.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct CoreVertices {
    /// The vertices; the first `len` are used.
    pub vertices: [Vec3; MAX_HULL_VERTICES],
    /// Number used.
    pub len: usize,
}

impl CoreVertices {
    /// The vertices in use.
    pub fn points(&self) -> &[Vec3] {
        self.vertices.get(..self.len).unwrap_or(&[])
    }

    fn push(&mut self, p: Vec3) {
        if let Some(slot) = self.vertices.get_mut(self.len) {
            *slot = p;
            self.len += 1;
        }
    }
}

/// The core's vertices under `pose` (world frame): a sphere's centre, a capsule's two
/// segment ends, a box's 8 corners, a hull's or triangle's vertices. `None` for a
/// half-space, which has none.
pub fn core_vertices(shape: &Shape, pose: &Iso) -> Option<CoreVertices> {
    let mut out = CoreVertices {
        vertices: [Vec3::ZERO; MAX_HULL_VERTICES],
        len: 0,
    };
    let count = shape.core_vertex_count()? as usize;
    for i in 0..count.min(MAX_HULL_VERTICES) {
        out.push(pose.transform_point(shape.core_vertex(i as u32)));
    }
    Some(out)
}

/// The answer of [`brute_force_distance`].
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct OracleDistance {
    /// Distance between the two convex hulls (m); 0 when they overlap.
    pub distance: f32,
    /// Closest point on the hull of `a`.
    pub point_a: Vec3,
    /// Closest point on the hull of `b`.
    pub point_b: Vec3,
}

/// Exhaustive distance between the convex hulls of two vertex sets, for tests.
///
/// Every convex polytope is the union of the triangles over its vertex triples, so the
/// closest pair of points lies on some pair of sub-simplices; enumerating every vertex
/// against every vertex, edge (vertex pair) and triangle interior (vertex triple) of the
/// other set, both ways, and every edge against every edge finds it. `O(n_a n_b³ +
/// n_a³ n_b + n_a² n_b²)`. That minimum is the distance only if the hulls are apart,
/// which a positive gap along a separating axis certifies: the closest pair's vector,
/// or else (`O((n_a³ + n_b³ + n_a² n_b²)(n_a + n_b))`) every face-normal and edge-cross
/// candidate. Without one the hulls overlap and the distance is 0. `None` when a set is
/// empty.
pub fn brute_force_distance(a: &[Vec3], b: &[Vec3]) -> Option<OracleDistance> {
    let (&a0, &b0) = (a.first()?, b.first()?);
    let mut best = OracleDistance {
        distance: f32::INFINITY,
        point_a: a0,
        point_b: b0,
    };
    let mut keep = |pa: Vec3, pb: Vec3| {
        let d = (pb - pa).length();
        if d < best.distance {
            best = OracleDistance {
                distance: d,
                point_a: pa,
                point_b: pb,
            };
        }
    };
    for &p in a {
        for q in closest_points_of_simplices(p, b) {
            keep(p, q);
        }
    }
    for &q in b {
        for p in closest_points_of_simplices(q, a) {
            keep(p, q);
        }
    }
    for (i, &p1) in a.iter().enumerate() {
        for &q1 in a.iter().skip(i + 1) {
            for (j, &p2) in b.iter().enumerate() {
                for &q2 in b.iter().skip(j + 1) {
                    let (s, t) = segment_closest_points(p1, q1, p2, q2);
                    keep(p1 + (q1 - p1) * s, p2 + (q2 - p2) * t);
                }
            }
        }
    }
    // Separation certificate: the closest pair's vector (or, failing that, any of the
    // separating-axis candidates: a normal of a vertex triple of either set, or the cross
    // product of an edge of each) must show a positive gap between the sets.
    let v = best.point_b - best.point_a;
    if !(best.distance > 0.0 && (gap_along(v, a, b) > 0.0 || separating_axis_exists(a, b))) {
        best.distance = 0.0;
    }
    Some(best)
}

/// `min_{y∈b} u·y − max_{x∈a} u·x`: positive when the plane orthogonal to `u` separates
/// the sets.
fn gap_along(u: Vec3, a: &[Vec3], b: &[Vec3]) -> f32 {
    let max_a = a
        .iter()
        .fold(f32::NEG_INFINITY, |m, x| scalar::max(m, u.dot(*x)));
    let min_b = b
        .iter()
        .fold(f32::INFINITY, |m, y| scalar::min(m, u.dot(*y)));
    min_b - max_a
}

/// Brute-force separating-axis test for two vertex sets: the normals of every vertex
/// triple of each set (a superset of the face normals) and the cross products of every
/// vertex pair of one with every vertex pair of the other (a superset of the edge
/// pairs), both signs; and, when a set has at most 3 points, the in-plane side normals of
/// a flat Minkowski difference.
fn separating_axis_exists(a: &[Vec3], b: &[Vec3]) -> bool {
    let separates = |u: Vec3| gap_along(u, a, b) > 0.0 || gap_along(-u, a, b) > 0.0;
    for set in [a, b] {
        for (i, &p) in set.iter().enumerate() {
            for (j, &q) in set.iter().enumerate().skip(i + 1) {
                for &r in set.iter().skip(j + 1) {
                    if separates((q - p).cross(r - p)) {
                        return true;
                    }
                }
            }
        }
    }
    for (i, &p1) in a.iter().enumerate() {
        for &q1 in a.iter().skip(i + 1) {
            for (j, &p2) in b.iter().enumerate() {
                for &q2 in b.iter().skip(j + 1) {
                    if separates((q1 - p1).cross(q2 - p2)) {
                        return true;
                    }
                }
            }
        }
    }
    // A set of at most 3 points (a sphere's centre, a capsule's segment, a triangle) can
    // make the Minkowski difference flat, and a flat difference has faces the candidates
    // above miss: its sides, normal to its edges within its plane. Those are the small
    // set's plane normal crossed with its own edges, and an edge-pair normal crossed with
    // either edge. (Found by the narrow_phase fuzzer: a sphere centred level with a
    // triangle's far corner, 3 cm past another corner, read as overlapping.)
    let edges = |set: &[Vec3]| {
        let mut out = [Vec3::ZERO; 3];
        let mut n = 0;
        for (i, &p) in set.iter().enumerate().take(3) {
            for &q in set.iter().take(3).skip(i + 1) {
                if let Some(slot) = out.get_mut(n) {
                    *slot = q - p;
                    n += 1;
                }
            }
        }
        (out, n)
    };
    for (small, other) in [(a, b), (b, a)] {
        if small.len() > 3 {
            continue;
        }
        let (own, count) = edges(small);
        let own = own.get(..count).unwrap_or(&[]);
        if let [e1, e2, ..] = own {
            let m = e1.cross(*e2);
            if own.iter().any(|e| separates(m.cross(*e))) {
                return true;
            }
        }
        for e in own {
            for (j, &p) in other.iter().enumerate() {
                for &q in other.iter().skip(j + 1) {
                    let u = e.cross(q - p);
                    if separates(u.cross(*e)) || separates(u.cross(q - p)) {
                        return true;
                    }
                }
            }
        }
    }
    false
}

/// Candidate closest points of `set`'s sub-simplices to `p`: each vertex, the clamped
/// projection on each edge, and the projection on each triangle's plane when it falls
/// inside the triangle (boundary cases are the edges and vertices already listed).
fn closest_points_of_simplices(p: Vec3, set: &[Vec3]) -> impl Iterator<Item = Vec3> + '_ {
    let vertices = set.iter().copied();
    let edges = set.iter().enumerate().flat_map(move |(i, &a)| {
        set.iter().skip(i + 1).map(move |&b| {
            let t = b - a;
            let tt = t.length_squared();
            if tt > 0.0 {
                a + t * scalar::clamp((p - a).dot(t) / tt, 0.0, 1.0)
            } else {
                a
            }
        })
    });
    let triangles = set.iter().enumerate().flat_map(move |(i, &a)| {
        set.iter().enumerate().skip(i + 1).flat_map(move |(j, &b)| {
            set.iter()
                .skip(j + 1)
                .filter_map(move |&c| projection_inside_triangle(p, a, b, c))
        })
    });
    vertices.chain(edges).chain(triangles)
}

/// The projection of `p` on the plane of `a b c` when it lies inside the triangle.
///
/// A sliver (the sine of its angle at `a` below 1e-5) is skipped: its normal is mostly
/// rounding, so the projection can land far off the triangle and still pass the inside
/// test by rounding, and its points lie within 1e-5 of its size from its edges, which are
/// candidates of their own. (Found by the narrow_phase fuzzer: a hull with vertex
/// coordinates of 1e-23 gave a closest "point" 0.12 m outside the hull.)
fn projection_inside_triangle(p: Vec3, a: Vec3, b: Vec3, c: Vec3) -> Option<Vec3> {
    let (ab, ac) = (b - a, c - a);
    let n = ab.cross(ac);
    let nn = n.length_squared();
    // |ab × ac|² = |ab|² |ac|² sin², compared with sin² = 1e-10.
    let usable = nn > 1.0e-10 * (ab.length_squared() * ac.length_squared());
    if !usable {
        return None;
    }
    let q = p - n * (n.dot(p - a) / nn);
    // Barycentric coordinates from the signed areas of the sub-triangles, over n·n.
    let la = n.dot((b - q).cross(c - q));
    let lb = n.dot((c - q).cross(a - q));
    let lc = n.dot((a - q).cross(b - q));
    (la >= 0.0 && lb >= 0.0 && lc >= 0.0).then_some(q)
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn oracle_matches_unit_cubes_apart_and_overlapping() {
        let cube = |c: Vec3| {
            let mut v = [Vec3::ZERO; 8];
            for (i, p) in v.iter_mut().enumerate() {
                let s = |bit: usize| if i & bit != 0 { 0.5 } else { -0.5 };
                *p = c + Vec3::new(s(1), s(2), s(4));
            }
            v
        };
        let a = cube(Vec3::ZERO);
        // Face to face 1 m apart along x: distance 1 - 0.5 - 0.5 + 1 = 1.
        let o = brute_force_distance(&a, &cube(Vec3::new(2.0, 0.3, -0.2))).unwrap();
        assert!((o.distance - 1.0).abs() < 1e-6);
        // Corner to corner along the diagonal: √3 · (2 − 1) = √3.
        let o = brute_force_distance(&a, &cube(Vec3::new(2.0, 2.0, 2.0))).unwrap();
        assert!((o.distance - 3f32.sqrt()).abs() < 1e-6);
        // An edge of a cube turned 45° about z, 0.1 m past the face x = 0.5: overlap.
        let turned: [Vec3; 8] = cube(Vec3::ZERO).map(|p| {
            let r = crate::math::Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_4);
            r.rotate(p) + Vec3::new(0.5 + core::f32::consts::FRAC_1_SQRT_2 - 0.1, 0.0, 0.0)
        });
        assert_eq!(brute_force_distance(&a, &turned).unwrap().distance, 0.0);
        // A small cube entirely inside: overlap with no crossing features.
        let small = a.map(|p| p * 0.2);
        assert_eq!(brute_force_distance(&a, &small).unwrap().distance, 0.0);
        assert!(brute_force_distance(&a, &[]).is_none());
    }

    #[test]
    fn invalid_poses_are_refused_and_pass() {
        let s = Shape::sphere(1.0).unwrap();
        let nan = Iso::from_position(Vec3::new(f32::NAN, 0.0, 0.0));
        assert_eq!(distance_properties(&s, &nan, &s, &Iso::IDENTITY), Ok(()));
        assert_eq!(penetration_properties(&s, &Iso::IDENTITY, &s, &nan), Ok(()));
    }
}
