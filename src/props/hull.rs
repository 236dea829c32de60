//! Properties of [`ConvexHull::new`]: whatever the cloud, it returns a hull or an error and
//! never panics, a hull it returns is a closed, convex, counter-clockwise polytope built
//! from the input points that holds them all, and [`ConvexHull::rebuild`] agrees.

use super::{check, Violation};
use crate::error::{Error, HullError};
use crate::math::{scalar, Vec3};
use crate::shape::{ConvexHull, MAX_FACE_VERTICES, MAX_HULL_FACES, MAX_HULL_VERTICES};

/// How many build tolerances (`ConvexHull::tolerance`) a point may stick out of a face
/// plane, or a polygon corner bend the wrong way. The builder treats a point less than one
/// tolerance outside as on the hull, lets a new triangle leave an old vertex up to one
/// tolerance above it, leaves out a point it cannot add without folding the surface (a
/// few tolerances outside), and merges triangles whose corners lie within one tolerance
/// of a common plane. Measured over 10⁶ random clouds: at most 4.1 (input points), 1.0
/// (vertices), 1.4 (corners below their face's plane).
pub const HULL_SLACK_TOLERANCES: f32 = 8.0;

/// How far a face normal's squared length may be from 1 (a few `f32` rounding steps).
const UNIT_SLACK: f32 = 1.0e-5;

/// Most directed edges a valid hull has (its corner count).
const MAX_EDGES: usize = 2 * (3 * MAX_HULL_VERTICES - 6);

/// Properties of `ConvexHull::new(points)`:
///
/// - it never panics; fewer than 4 points is always refused (as too few, or for a
///   non-finite or out-of-range coordinate, which are checked first), any other refusal is fine
///   (the bad-input tests check the errors);
/// - a hull has 4 to [`MAX_HULL_VERTICES`] vertices, each bit-equal to an input point,
///   at least 4 and at most [`MAX_HULL_FACES`] faces of 3 to [`MAX_FACE_VERTICES`] corners;
/// - face normals have unit length; each face's corners lie on its plane and the polygon
///   is convex and counter-clockwise about the normal (within
///   [`HULL_SLACK_TOLERANCES`] build tolerances);
/// - the faces close up: each directed edge appears once and its reverse once, and
///   Euler's `V − E + F = 2` holds;
/// - every vertex, and (unless the hull is reduced) every input point, is inside or
///   within the slack of every face plane;
/// - for density 1 the mass is positive and finite, the inertia finite, and the centroid
///   strictly inside every face plane;
/// - [`ConvexHull::rebuild`] into a slot gives the same answer: the same hull, or the same
///   error with the slot left as [`ConvexHull::UNIT_TETRAHEDRON`].
pub fn hull_properties(points: &[Vec3]) -> Result<(), Violation> {
    let built = ConvexHull::new(points);
    rebuild_agrees(points, &built)?;
    let hull = match built {
        Ok(h) => h,
        Err(e) => {
            if points.len() < 4 {
                check(
                    matches!(
                        e,
                        Error::Hull(HullError::TooFewPoints)
                            | Error::NonFinite(_)
                            | Error::OutOfRange(_)
                    ),
                    "hull: fewer than 4 points not refused as such",
                )?;
            }
            return Ok(());
        }
    };
    check(points.len() >= 4, "hull: built from fewer than 4 points")?;
    let slack = HULL_SLACK_TOLERANCES * hull.tolerance();
    check(
        slack > 0.0 && slack.is_finite(),
        "hull: tolerance not positive",
    )?;
    counts_in_range(&hull)?;
    vertices_are_inputs(&hull, points)?;
    faces_are_flat_convex_ccw(&hull, slack)?;
    closed_with_euler_two(&hull)?;
    for v in hull.vertices() {
        inside_all_planes(&hull, *v, slack, "hull: a vertex is outside a face plane")?;
    }
    if !hull.is_reduced() {
        for p in points {
            inside_all_planes(&hull, *p, slack, "hull: an input point is outside")?;
        }
    }
    mass_is_sound(&hull)
}

/// `rebuild` of `points` into a slot (holding the unit tetrahedron) agrees with `built`,
/// `new`'s answer.
fn rebuild_agrees(points: &[Vec3], built: &Result<ConvexHull, Error>) -> Result<(), Violation> {
    let mut slot = ConvexHull::UNIT_TETRAHEDRON;
    let rebuilt = slot.rebuild(points);
    let agrees = match built {
        Ok(hull) => rebuilt.is_ok() && slot == *hull,
        Err(e) => rebuilt == Err(*e) && slot == ConvexHull::UNIT_TETRAHEDRON,
    };
    check(agrees, "hull: rebuild in place disagrees with new")
}

fn counts_in_range(hull: &ConvexHull) -> Result<(), Violation> {
    let v = hull.vertices().len();
    check(
        (4..=MAX_HULL_VERTICES).contains(&v),
        "hull: vertex count out of range",
    )?;
    let f = hull.face_count();
    check(
        (4..=MAX_HULL_FACES).contains(&f),
        "hull: face count out of range",
    )?;
    for k in 0..f {
        let idx = hull.face_vertices(k);
        check(
            (3..=MAX_FACE_VERTICES).contains(&idx.len()),
            "hull: face corner count out of range",
        )?;
        check(
            idx.iter().all(|&i| (i as usize) < v),
            "hull: face corner index out of range",
        )?;
    }
    Ok(())
}

fn vertices_are_inputs(hull: &ConvexHull, points: &[Vec3]) -> Result<(), Violation> {
    for v in hull.vertices() {
        check(
            points.iter().any(|p| p == v),
            "hull: a vertex is not an input point",
        )?;
    }
    let vs = hull.vertices();
    for (k, v) in vs.iter().enumerate() {
        check(
            !vs.iter().skip(k + 1).any(|w| w == v),
            "hull: a vertex appears twice",
        )?;
    }
    Ok(())
}

/// Corners on the plane; every corner left of (or on) every edge, about the normal:
/// `((b − a) × (c − a)) · n ≥ −slack |b − a|` for each edge `a → b` and corner `c`.
fn faces_are_flat_convex_ccw(hull: &ConvexHull, slack: f32) -> Result<(), Violation> {
    let vs = hull.vertices();
    let at = |i: u8| vs.get(i as usize).copied().unwrap_or(Vec3::ZERO);
    for f in 0..hull.face_count() {
        let (n, d) = hull.plane(f);
        check(
            scalar::abs(n.length_squared() - 1.0) <= UNIT_SLACK,
            "hull: face normal not unit length",
        )?;
        let idx = hull.face_vertices(f);
        for &i in idx {
            check(
                scalar::abs(n.dot(at(i)) - d) <= slack,
                "hull: face corner off its plane",
            )?;
        }
        let next = idx.iter().skip(1).chain(idx.first());
        for (&i, &j) in idx.iter().zip(next) {
            let (a, b) = (at(i), at(j));
            let edge = b - a;
            for &k in idx {
                let side = edge.cross(at(k) - a).dot(n);
                check(
                    side >= -slack * edge.length(),
                    "hull: face not convex or not counter-clockwise",
                )?;
            }
        }
    }
    Ok(())
}

/// Every directed edge once, its reverse once; `V − E + F = 2`.
fn closed_with_euler_two(hull: &ConvexHull) -> Result<(), Violation> {
    let mut edges = [(0u8, 0u8); MAX_EDGES];
    let mut count = 0usize;
    for f in 0..hull.face_count() {
        let idx = hull.face_vertices(f);
        let next = idx.iter().skip(1).chain(idx.first());
        for (&i, &j) in idx.iter().zip(next) {
            let Some(slot) = edges.get_mut(count) else {
                return Err(Violation("hull: too many edges"));
            };
            *slot = (i, j);
            count += 1;
        }
    }
    let edges = edges.get(..count).unwrap_or(&[]);
    for (k, &(i, j)) in edges.iter().enumerate() {
        check(i != j, "hull: an edge from a vertex to itself")?;
        check(
            !edges.iter().skip(k + 1).any(|&e| e == (i, j)),
            "hull: a directed edge appears twice",
        )?;
        check(
            edges.iter().filter(|&&e| e == (j, i)).count() == 1,
            "hull: an edge without its reverse",
        )?;
    }
    let v = hull.vertices().len() as i64;
    let e = (count / 2) as i64;
    let f = hull.face_count() as i64;
    check(v - e + f == 2, "hull: Euler characteristic is not 2")
}

fn inside_all_planes(
    hull: &ConvexHull,
    p: Vec3,
    slack: f32,
    what: &'static str,
) -> Result<(), Violation> {
    for f in 0..hull.face_count() {
        let (n, d) = hull.plane(f);
        check(n.dot(p) - d <= slack, what)?;
    }
    Ok(())
}

fn mass_is_sound(hull: &ConvexHull) -> Result<(), Violation> {
    let m = hull.mass_properties(1.0);
    check(
        m.mass > 0.0 && m.mass.is_finite(),
        "hull: mass not positive and finite",
    )?;
    check(m.inertia.is_finite(), "hull: inertia not finite")?;
    check(m.center.is_finite(), "hull: centre of mass not finite")?;
    check(
        m.center == hull.centroid(),
        "hull: centre of mass differs from the centroid",
    )?;
    for f in 0..hull.face_count() {
        let (n, d) = hull.plane(f);
        check(
            n.dot(m.center) - d < 0.0,
            "hull: centroid not strictly inside",
        )?;
    }
    Ok(())
}
