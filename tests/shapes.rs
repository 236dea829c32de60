//! Shapes: convex hull building, mass properties and ray casts, checked against closed
//! forms, first-principles integrals and brute-force oracles computed in `f64`.

use carom::math::{Iso, Mat3, Quat, Vec3};
use carom::props::hull_properties;
use carom::rng::SplitMix64;
use carom::shape::{
    ConvexHull, MassProperties, Ray, RayHit, Shape, MAX_FACE_VERTICES, MAX_HULL_INPUT_POINTS,
    MAX_HULL_VERTICES,
};
use carom::{Error, HullError, Input};

// ----------------------------------------------------------------------------------------
// f64 helpers (the oracles never use carom's own math)
// ----------------------------------------------------------------------------------------

type D3 = [f64; 3];

fn d3(v: Vec3) -> D3 {
    [v.x as f64, v.y as f64, v.z as f64]
}
fn sub(a: D3, b: D3) -> D3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn add(a: D3, b: D3) -> D3 {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn mul(a: D3, s: f64) -> D3 {
    [a[0] * s, a[1] * s, a[2] * s]
}
fn dot(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}
fn cross(a: D3, b: D3) -> D3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}
fn norm(a: D3) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: D3) -> D3 {
    mul(a, 1.0 / norm(a))
}

/// Rotation matrix rows of a unit quaternion, in f64 (the textbook formula, not carom's).
fn rot_rows(q: Quat) -> [D3; 3] {
    let (x, y, z, w) = (q.x as f64, q.y as f64, q.z as f64, q.w as f64);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y - w * z),
            2.0 * (x * z + w * y),
        ],
        [
            2.0 * (x * y + w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z - w * x),
        ],
        [
            2.0 * (x * z - w * y),
            2.0 * (y * z + w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}
fn rot(r: &[D3; 3], v: D3) -> D3 {
    [dot(r[0], v), dot(r[1], v), dot(r[2], v)]
}
fn rot_t(r: &[D3; 3], v: D3) -> D3 {
    let mut o = [0.0; 3];
    for (i, row) in r.iter().enumerate() {
        for (k, ok) in o.iter_mut().enumerate() {
            *ok += row[k] * v[i];
        }
    }
    o
}
/// A world point into the local frame of `pose`, in f64.
fn to_local(pose: &Iso, p: D3) -> D3 {
    rot_t(&rot_rows(pose.rotation), sub(p, d3(pose.position)))
}
fn to_world(pose: &Iso, p: D3) -> D3 {
    add(rot(&rot_rows(pose.rotation), p), d3(pose.position))
}

fn v3(a: D3) -> Vec3 {
    Vec3::new(a[0] as f32, a[1] as f32, a[2] as f32)
}

fn random_pose(rng: &mut SplitMix64) -> Iso {
    Iso::new(
        Vec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        ),
        rng.rotation(),
    )
}

fn rel_close(a: f64, b: f64, rel: f64, what: &str) {
    assert!(
        (a - b).abs() <= rel * b.abs().max(1e-30),
        "{what}: {a} vs {b} (rel {})",
        ((a - b) / b).abs()
    );
}

/// Matrix entries compared relative to the largest entry of `b` (off-diagonal zeros
/// included).
fn mat_close(a: &Mat3, b: &[[f64; 3]; 3], rel: f64, what: &str) {
    let scale = b.iter().flatten().fold(0.0f64, |m, x| m.max(x.abs()));
    let cols = [a.x, a.y, a.z];
    for (j, col) in cols.iter().enumerate() {
        let c = d3(*col);
        for i in 0..3 {
            assert!(
                (c[i] - b[i][j]).abs() <= rel * scale,
                "{what}: entry ({i},{j}) {} vs {}",
                c[i],
                b[i][j]
            );
        }
    }
}

// ----------------------------------------------------------------------------------------
// Hull building: exact errors and exact structure
// ----------------------------------------------------------------------------------------

fn box_corners(h: Vec3) -> [Vec3; 8] {
    let mut c = [Vec3::ZERO; 8];
    for (i, p) in c.iter_mut().enumerate() {
        *p = Vec3::new(
            if i & 1 != 0 { h.x } else { -h.x },
            if i & 2 != 0 { h.y } else { -h.y },
            if i & 4 != 0 { h.z } else { -h.z },
        );
    }
    c
}

fn hull_err(points: &[Vec3]) -> Error {
    ConvexHull::new(points).expect_err("expected the hull to be refused")
}

#[test]
fn hull_bad_inputs_return_their_exact_errors() {
    let corners = box_corners(Vec3::new(1.0, 2.0, 3.0));
    // Non-finite coordinates, wherever they are.
    for bad in [f32::NAN, f32::INFINITY, f32::NEG_INFINITY] {
        let mut p = corners;
        p[5].y = bad;
        assert_eq!(hull_err(&p), Error::NonFinite(Input::Point));
    }
    // Beyond the coordinate range.
    let mut p = corners;
    p[2].z = 2.0 * ConvexHull::MAX_COORDINATE;
    assert_eq!(hull_err(&p), Error::OutOfRange(Input::Point));
    // Too few points.
    assert_eq!(hull_err(&[]), Error::Hull(HullError::TooFewPoints));
    assert_eq!(
        hull_err(&corners[..3]),
        Error::Hull(HullError::TooFewPoints)
    );
    // Too many points (checked before anything else).
    let many = [Vec3::new(f32::NAN, 0.0, 0.0); MAX_HULL_INPUT_POINTS + 1];
    assert_eq!(hull_err(&many), Error::Hull(HullError::TooManyPoints));
    // All the same point: duplicates do not count.
    let same = [Vec3::new(1.0, -2.0, 3.5); 10];
    assert_eq!(hull_err(&same), Error::Hull(HullError::Coincident));
    // Duplicates do not make points distinct: 4 points on 3 or 2 spots.
    let (a, b, c) = (
        Vec3::new(1.0, 2.0, 3.0),
        Vec3::new(2.0, 2.0, 3.0),
        Vec3::new(1.0, 3.0, 3.0),
    );
    assert_eq!(hull_err(&[a, b, a, c]), Error::Hull(HullError::Coplanar));
    assert_eq!(hull_err(&[a, b, b, a]), Error::Hull(HullError::Collinear));
    // Within tolerance of one point (1e-5 × 3.5 = 3.5e-5 m).
    let mut near = same;
    near[3].x += 1.0e-5;
    assert_eq!(hull_err(&near), Error::Hull(HullError::Coincident));
    // Collinear, with duplicates.
    let dir = Vec3::new(0.3, -0.5, 0.8);
    let line: Vec<Vec3> = (0..12)
        .map(|i| Vec3::new(1.0, 2.0, 3.0) + dir * ((i % 5) as f32))
        .collect();
    assert_eq!(hull_err(&line), Error::Hull(HullError::Collinear));
    // Coplanar: a 5 × 5 grid in a tilted plane.
    let (u, w) = (Vec3::new(1.0, 0.2, -0.3), Vec3::new(0.1, 1.0, 0.4));
    let plane: Vec<Vec3> = (0..25)
        .map(|i| Vec3::new(0.5, 0.5, 0.5) + u * ((i % 5) as f32) + w * ((i / 5) as f32))
        .collect();
    assert_eq!(hull_err(&plane), Error::Hull(HullError::Coplanar));
    // A box 1e-6 thick (tolerance 1e-5 × 3 = 3e-5 m) is coplanar; 1e-3 thick is a hull.
    let flat = box_corners(Vec3::new(3.0, 2.0, 0.5e-6));
    assert_eq!(hull_err(&flat), Error::Hull(HullError::Coplanar));
    assert!(ConvexHull::new(&box_corners(Vec3::new(3.0, 2.0, 0.5e-3))).is_ok());
}

#[test]
fn box_hull_has_six_quads_and_drops_every_other_point() {
    let h = Vec3::new(0.5, 1.5, 2.5);
    let corners = box_corners(h);
    let mut rng = SplitMix64::new(11);
    let mut points = Vec::new();
    // Interior points first, then face centres, edge midpoints, a corner duplicate and
    // the corners interleaved with more interior points.
    for _ in 0..20 {
        points.push(Vec3::new(
            rng.range(-h.x, h.x) * 0.99,
            rng.range(-h.y, h.y) * 0.99,
            rng.range(-h.z, h.z) * 0.99,
        ));
    }
    for k in 0..3 {
        for s in [-1.0, 1.0] {
            let mut c = Vec3::ZERO;
            match k {
                0 => c.x = s * h.x,
                1 => c.y = s * h.y,
                _ => c.z = s * h.z,
            }
            points.push(c);
        }
    }
    for (i, a) in corners.iter().enumerate() {
        for b in &corners[i + 1..] {
            let d = *b - *a;
            let axes = (d.x != 0.0) as u8 + (d.y != 0.0) as u8 + (d.z != 0.0) as u8;
            if axes == 1 {
                points.push((*a + *b) * 0.5);
            }
        }
    }
    for c in &corners {
        points.push(*c);
        points.push(Vec3::new(rng.range(-0.4, 0.4), 0.0, rng.range(-2.0, 2.0)));
    }
    points.push(corners[3]);
    let hull = ConvexHull::new(&points).unwrap();
    // Exactly the 8 corners, in input order (the corners were pushed in index order).
    assert_eq!(hull.vertices(), &corners[..]);
    assert_eq!(hull.face_count(), 6);
    for f in 0..6 {
        let idx = hull.face_vertices(f);
        assert_eq!(idx.len(), 4, "face {f}");
        let (n, d) = hull.plane(f);
        // Axis-aligned normal, offset the half-extent along it (exact up to rounding).
        let a = n.abs();
        let axis = if a.x > 0.9 {
            0
        } else if a.y > 0.9 {
            1
        } else {
            2
        };
        assert!(
            (a.x + a.y + a.z - 1.0).abs() < 1e-6,
            "face {f} normal {n:?}"
        );
        assert!((d - h[axis]).abs() < 1e-6, "face {f} offset {d}");
        // Counter-clockwise about the normal, starting at the lowest index.
        let p: Vec<Vec3> = idx.iter().map(|&i| hull.vertices()[i as usize]).collect();
        let turn = (p[1] - p[0]).cross(p[2] - p[1]);
        assert!(turn.dot(n) > 0.0, "face {f} is clockwise");
        assert_eq!(idx[0], *idx.iter().min().unwrap());
    }
    assert!(!hull.is_reduced());
    assert_eq!(hull.centroid(), Vec3::ZERO);
    hull_properties(&points).unwrap();
}

#[test]
fn hull_is_deterministic_and_ordered_by_input() {
    let mut rng = SplitMix64::new(5);
    let points: Vec<Vec3> = (0..40)
        .map(|_| {
            Vec3::new(
                rng.range(-1.0, 1.0),
                rng.range(-2.0, 2.0),
                rng.range(-1.0, 3.0),
            )
        })
        .collect();
    let a = ConvexHull::new(&points).unwrap();
    let b = ConvexHull::new(&points).unwrap();
    assert_eq!(a, b);
    // Vertices appear in the order of their first occurrence in the input.
    let positions: Vec<usize> = a
        .vertices()
        .iter()
        .map(|v| points.iter().position(|p| p == v).unwrap())
        .collect();
    assert!(positions.windows(2).all(|w| w[0] < w[1]), "{positions:?}");
}

/// Brute-force hull vertices: the points on some plane through three points with every
/// point on one side (f64, O(n⁴)).
fn brute_force_hull_vertices(points: &[Vec3]) -> Vec<usize> {
    let p: Vec<D3> = points.iter().map(|v| d3(*v)).collect();
    let n = p.len();
    let mut on_hull = vec![false; n];
    for i in 0..n {
        for j in i + 1..n {
            for k in j + 1..n {
                let nrm = cross(sub(p[j], p[i]), sub(p[k], p[i]));
                if norm(nrm) < 1e-9 {
                    continue;
                }
                let nrm = unit(nrm);
                let h: Vec<f64> = p.iter().map(|q| dot(nrm, sub(*q, p[i]))).collect();
                let max = h.iter().cloned().fold(f64::MIN, f64::max);
                let min = h.iter().cloned().fold(f64::MAX, f64::min);
                if max <= 1e-9 || min >= -1e-9 {
                    for (m, hm) in h.iter().enumerate() {
                        if hm.abs() <= 1e-9 {
                            on_hull[m] = true;
                        }
                    }
                }
            }
        }
    }
    (0..n).filter(|&i| on_hull[i]).collect()
}

#[test]
fn random_16_point_hulls_match_brute_force_and_satisfy_properties() {
    let mut rng = SplitMix64::new(16);
    for round in 0..20 {
        let points: Vec<Vec3> = (0..16)
            .map(|_| {
                Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                )
            })
            .collect();
        hull_properties(&points).unwrap_or_else(|v| panic!("round {round}: {v:?}"));
        let hull = ConvexHull::new(&points).unwrap();
        let expected: Vec<Vec3> = brute_force_hull_vertices(&points)
            .into_iter()
            .map(|i| points[i])
            .collect();
        assert_eq!(hull.vertices(), &expected[..], "round {round}");
        // Random points in general position: every face is a triangle, F = 2V − 4.
        assert_eq!(hull.face_count(), 2 * hull.vertices().len() - 4);
    }
}

/// `n` points spread evenly on a sphere of radius `r` (Fibonacci lattice).
fn fibonacci_sphere(n: usize, r: f32) -> Vec<Vec3> {
    let golden = std::f64::consts::PI * (3.0 - 5.0f64.sqrt());
    (0..n)
        .map(|i| {
            let y = 1.0 - 2.0 * (i as f64 + 0.5) / n as f64;
            let rad = (1.0 - y * y).sqrt();
            let a = golden * i as f64;
            Vec3::new(
                (a.cos() * rad * r as f64) as f32,
                (y * r as f64) as f32,
                (a.sin() * rad * r as f64) as f32,
            )
        })
        .collect()
}

#[test]
fn large_coplanar_face_is_split_into_fans_of_at_most_16() {
    // A prism over a regular 20-gon: 40 vertices, 20 side quads, top and bottom 20-gons
    // split into pieces of 16 and 6 corners.
    let n = 20;
    let mut points = Vec::new();
    for y in [-1.0f32, 1.0] {
        for i in 0..n {
            let a = std::f64::consts::TAU * i as f64 / n as f64;
            points.push(Vec3::new(2.0 * a.cos() as f32, y, 2.0 * a.sin() as f32));
        }
    }
    hull_properties(&points).unwrap();
    let hull = ConvexHull::new(&points).unwrap();
    assert_eq!(hull.vertices().len(), 40);
    assert_eq!(hull.face_count(), 24);
    let mut lens: Vec<usize> = (0..24).map(|f| hull.face_vertices(f).len()).collect();
    lens.sort();
    let mut expected = vec![4; 20];
    expected.extend([6, 6, 16, 16]);
    expected.sort();
    assert_eq!(lens, expected);
    assert!(lens.iter().all(|&l| l <= MAX_FACE_VERTICES));
    // Volume: the 20-gon's area 1/2 n R² sin(2π/n) times height 2.
    let area = 0.5 * n as f64 * 4.0 * (std::f64::consts::TAU / n as f64).sin();
    rel_close(
        hull.mass_properties(1.0).mass as f64,
        area * 2.0,
        1e-5,
        "prism volume",
    );
}

#[test]
fn hull_of_more_than_64_vertices_is_reduced_greedily() {
    let points = fibonacci_sphere(500, 1.0);
    let hull = ConvexHull::new(&points).unwrap();
    assert!(hull.is_reduced());
    assert_eq!(hull.vertices().len(), MAX_HULL_VERTICES);
    assert_eq!(ConvexHull::new(&points).unwrap(), hull);
    hull_properties(&points).unwrap();
    // The greedy subset stays close to the sphere: no input point is more than 0.2 m
    // outside it (a 64-vertex hull of a unit sphere has edges ~0.5 m long).
    let mut worst = 0.0f32;
    for p in &points {
        for f in 0..hull.face_count() {
            let (n, d) = hull.plane(f);
            worst = worst.max(n.dot(*p) - d);
        }
    }
    assert!(worst < 0.2, "worst outside distance {worst}");
    // Exactly 64 points need no reduction.
    let points = fibonacci_sphere(MAX_HULL_VERTICES, 1.0);
    let hull = ConvexHull::new(&points).unwrap();
    assert!(!hull.is_reduced());
    assert_eq!(hull.vertices(), &points[..]);
}

/// Fuzz finding `hull/input-point-outside-ef0690fd`: a cloud near a 5.8 m cube with a
/// 6.3 km spike (build tolerance 6.3 cm). The cube's corner `(5.84, 5.84, 5.83)` lies
/// within a centimetre of the spike's two long side faces, so the cone to it folded at
/// the scale of the tolerance and the builder left it out, 1.24 m (20 tolerances) outside
/// the hull. A finer build (`ConvexHull::new`) now tells those faces apart: the corner is
/// a vertex and every input point is inside.
#[test]
fn finding_a_corner_beside_long_nearly_coplanar_faces_is_not_left_out() {
    let points: Vec<Vec3> = [
        (5.835205, 0.003866032, 5.8125),
        (5.835205, 3.7019043, 5.838135),
        (3.7019043, 5.835205, 3.7019043),
        (5.835205, 3.9387207, 3.7019043),
        (5.8137207, 5.835205, 3.710205),
        (5.835205, 0.8352051, 5.835205),
        (5.8688965, 2.3215332, 0.009033203),
        (5.835205, 3.7019043, 5.835205),
        (3.7019043, 0.0, 5.835205),
        (0.0, 3.710205, 5.835205),
        (5.835205, 3.710205, 5.835205),
        (0.0, 5.8125, 3.7019043),
        (5.835205, 5.835205, 0.33520508),
        (0.8156738, 0.8156738, 6.065674),
        (0.00024414063, 0.0, 0.8156738),
        (5.835205, 1.3e-43, 2.3215332),
        (5.835205, 5.835205, 5.8269043),
        (-5.833252, 5.835205, -6328.721),
        (0.0031738281, 0.0, 0.8156738),
        (5.835205, 0.0, 2.3215332),
        (5.835205, 5.835205, 5.8269043),
        (5.835205, 5.585205, 0.8156738),
        (0.8156738, 0.8156738, 5.835205),
        (3.3492e-41, 2.3215332, -6328.721),
        (5.835205, 5.835205, -4.768799),
        (-8.368024e-8, 3.710205, 5.835205),
        (3.7019043, 5.835205, 3.7019043),
        (5.835205, -0.32885742, 5.835205),
        (5.835205, 3.710205, 5.835205),
        (3.7019043, 5.835205, 5.772705),
        (5.585205, 5.835205, 3.7019043),
        (0.33520508, 5.8269043, 0.8352051),
        (0.8156738, 0.8156738, 0.0),
        (-1.5397949, 0.001953125, 5.835205),
        (5.835205, 5.821289, 3.710205),
        (0.8156738, 5.897949, 0.08544922),
    ]
    .iter()
    .map(|&(x, y, z)| Vec3::new(x, y, z))
    .collect();
    let hull = ConvexHull::new(&points).unwrap();
    assert!(!hull.is_reduced());
    assert!((hull.tolerance() - 6.328721e-2).abs() < 1e-7);
    let corner = Vec3::new(5.835205, 5.835205, 5.8269043);
    assert!(hull.vertices().contains(&corner), "{:?}", hull.vertices());
    let outside = points
        .iter()
        .flat_map(|p| (0..hull.face_count()).map(|f| (hull.plane(f), *p)))
        .map(|((n, d), p)| n.dot(p) - d)
        .fold(f32::MIN, f32::max);
    assert!(outside <= hull.tolerance(), "a point {outside} m outside");
    hull_properties(&points).unwrap();
}

#[test]
fn hull_of_the_maximum_input_builds() {
    let mut rng = SplitMix64::new(1024);
    let points: Vec<Vec3> = (0..MAX_HULL_INPUT_POINTS)
        .map(|_| rng.unit_vector() * rng.range(0.5, 1.0))
        .collect();
    hull_properties(&points).unwrap();
}

// ----------------------------------------------------------------------------------------
// Hull properties over random clouds
// ----------------------------------------------------------------------------------------

/// A random cloud of one of seven kinds, at a log-uniform scale in [1e-3, 1e3] and offset
/// up to 3 scales from the origin: uniform in a box, on a sphere (up to 100 points, so
/// some need reduction), with many duplicates, near-coplanar (thickness 1e-7..1e-1
/// relative), on an integer lattice (much merging of coplanar triangles), a few points
/// near one line, and points on a cylinder (large flat caps).
fn random_cloud(rng: &mut SplitMix64) -> Vec<Vec3> {
    let scale = 10f32.powf(rng.range(-3.0, 3.0));
    let offset = Vec3::new(
        rng.range(-3.0, 3.0),
        rng.range(-3.0, 3.0),
        rng.range(-3.0, 3.0),
    );
    let kind = rng.next_u64() % 7;
    let n = 4 + (rng.next_u64() % 60) as usize;
    let rotation = rng.rotation();
    let mut pts: Vec<Vec3> = Vec::with_capacity(n);
    match kind {
        0 => {
            for _ in 0..n {
                pts.push(Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                ));
            }
        }
        1 => {
            let n = 4 + (rng.next_u64() % 97) as usize;
            for _ in 0..n {
                pts.push(rng.unit_vector());
            }
        }
        2 => {
            let distinct = 1 + (rng.next_u64() % 8) as usize;
            let base: Vec<Vec3> = (0..distinct).map(|_| rng.unit_vector()).collect();
            for _ in 0..n {
                pts.push(base[(rng.next_u64() % distinct as u64) as usize]);
            }
        }
        3 => {
            let thick = 10f32.powf(rng.range(-7.0, -1.0));
            for _ in 0..n {
                pts.push(Vec3::new(
                    rng.range(-1.0, 1.0),
                    rng.range(-1.0, 1.0),
                    rng.range(-thick, thick),
                ));
            }
        }
        4 => {
            let side = 2 + rng.next_u64() % 3;
            for _ in 0..n {
                let c = |r: &mut SplitMix64| (r.next_u64() % (side + 1)) as f32 / side as f32;
                pts.push(Vec3::new(c(rng), c(rng), c(rng)));
            }
        }
        5 => {
            let dir = rng.unit_vector();
            let wobble = 10f32.powf(rng.range(-7.0, -2.0));
            for _ in 0..n {
                pts.push(dir * rng.range(-1.0, 1.0) + rng.unit_vector() * wobble);
            }
        }
        _ => {
            let sides = 3 + rng.next_u64() % 30;
            for _ in 0..n {
                let a = (rng.next_u64() % sides) as f32 * std::f32::consts::TAU / sides as f32;
                let y = if rng.next_u64() & 1 == 0 { -1.0 } else { 1.0 };
                pts.push(Vec3::new(a.cos(), y, a.sin()));
            }
        }
    }
    pts.iter()
        .map(|p| (rotation.rotate(*p) + offset) * scale)
        .collect()
}

#[test]
fn random_clouds_satisfy_hull_properties() {
    let mut rng = SplitMix64::new(2000);
    let mut built = 0;
    let mut reduced = 0;
    let mut refused = std::collections::BTreeMap::new();
    for round in 0..2000 {
        let pts = random_cloud(&mut rng);
        hull_properties(&pts).unwrap_or_else(|v| panic!("cloud {round}: {v:?}\n{pts:?}"));
        match ConvexHull::new(&pts) {
            Ok(h) => {
                built += 1;
                reduced += h.is_reduced() as u32;
            }
            Err(e) => *refused.entry(format!("{e:?}")).or_insert(0) += 1,
        }
    }
    // The refusals are the degenerate kinds only, never a broken mesh.
    assert!(!refused.contains_key("Hull(TooComplex)"), "{refused:?}");
    assert!(built >= 1500, "built {built}, refused {refused:?}");
    assert!(reduced > 0, "no cloud exercised the reduction");
    println!("built {built} (reduced {reduced}), refused {refused:?}");
}

#[test]
fn hull_properties_never_panic_on_hostile_input() {
    let specials = [
        f32::NAN,
        f32::INFINITY,
        -f32::INFINITY,
        f32::MAX,
        f32::MIN_POSITIVE,
        1.0e-30,
        -0.0,
        0.0,
        1.0e30,
        ConvexHull::MAX_COORDINATE,
        1.0,
    ];
    let mut rng = SplitMix64::new(77);
    for _ in 0..500 {
        let n = (rng.next_u64() % 12) as usize;
        let pts: Vec<Vec3> = (0..n)
            .map(|_| {
                let mut c = || specials[(rng.next_u64() % specials.len() as u64) as usize];
                Vec3::new(c(), c(), c())
            })
            .collect();
        hull_properties(&pts).unwrap();
    }
    // Tiny and huge but valid hulls.
    for s in [1.0e-7f32, 1.0e-4, 1.0e4, ConvexHull::MAX_COORDINATE] {
        let pts: Vec<Vec3> = box_corners(Vec3::new(1.0, 0.5, 0.25))
            .iter()
            .map(|p| *p * s)
            .collect();
        hull_properties(&pts).unwrap();
        assert!(ConvexHull::new(&pts).is_ok(), "scale {s}");
    }
}

// ----------------------------------------------------------------------------------------
// Mass properties
// ----------------------------------------------------------------------------------------

/// Mass, inertia about the axis Y and about a transverse axis through the origin of a
/// solid of revolution about Y whose slice at height y is a disk of radius² `a(y)`,
/// integrated by Simpson's rule (2000 intervals) over each piece, in f64: a slice of
/// thickness dy has `dm = ρ π a dy`, `dI_axis = dm a / 2`, `dI_perp = dm (a / 4 + y²)`.
fn revolution(a: &dyn Fn(f64) -> f64, pieces: &[(f64, f64)], rho: f64) -> [f64; 3] {
    let mut total = [0.0; 3];
    let pi = std::f64::consts::PI;
    for &(y0, y1) in pieces {
        let n = 2000;
        let h = (y1 - y0) / n as f64;
        for k in 0..=n {
            let y = y0 + h * k as f64;
            let w = if k == 0 || k == n {
                1.0
            } else if k % 2 == 1 {
                4.0
            } else {
                2.0
            };
            let ay = a(y).max(0.0);
            let dm = rho * pi * ay * w * h / 3.0;
            total[0] += dm;
            total[1] += dm * ay / 2.0;
            total[2] += dm * (ay / 4.0 + y * y);
        }
    }
    total
}

fn assert_diagonal_inertia(m: &MassProperties, axis: f64, perp: f64, rel: f64, what: &str) {
    let expected = [[perp, 0.0, 0.0], [0.0, axis, 0.0], [0.0, 0.0, perp]];
    mat_close(&m.inertia, &expected, rel, what);
}

#[test]
fn sphere_mass_properties_match_the_revolution_integral() {
    // Tolerance 1e-5 relative: the f32 closed form rounds a handful of products (~1e-7
    // each); Simpson on a polynomial integrand is exact to ~1e-12.
    for (r, rho) in [(0.05f32, 7800.0f32), (0.5, 1000.0), (1.0, 1.0), (3.7, 0.25)] {
        let m = Shape::sphere(r).unwrap().mass_properties(rho).unwrap();
        let (r64, rho64) = (r as f64, rho as f64);
        let [mass, axis, perp] = revolution(&|y| r64 * r64 - y * y, &[(-r64, r64)], rho64);
        rel_close(m.mass as f64, mass, 1e-5, "sphere mass");
        assert_eq!(m.center, Vec3::ZERO);
        assert_diagonal_inertia(&m, axis, perp, 1e-5, "sphere inertia");
        // The integral itself against 2/5 m r² (a check on the oracle).
        rel_close(axis, 0.4 * mass * r64 * r64, 1e-9, "oracle");
    }
}

#[test]
fn capsule_mass_properties_match_the_revolution_integral() {
    let mut rng = SplitMix64::new(3);
    for _ in 0..20 {
        let (h, r, rho) = (
            rng.range(0.01, 3.0),
            rng.range(0.01, 2.0),
            rng.range(0.1, 5000.0),
        );
        let m = Shape::capsule(h, r).unwrap().mass_properties(rho).unwrap();
        let (h64, r64) = (h as f64, r as f64);
        let a = |y: f64| {
            let over = y.abs() - h64;
            if over > 0.0 {
                r64 * r64 - over * over
            } else {
                r64 * r64
            }
        };
        let pieces = [(-h64 - r64, -h64), (-h64, h64), (h64, h64 + r64)];
        let [mass, axis, perp] = revolution(&a, &pieces, rho as f64);
        rel_close(m.mass as f64, mass, 1e-5, "capsule mass");
        assert_eq!(m.center, Vec3::ZERO);
        assert_diagonal_inertia(&m, axis, perp, 1e-5, "capsule inertia");
    }
}

#[test]
fn cuboid_mass_properties_match_the_closed_form() {
    // m = 8 hx hy hz ρ, Ixx = m (hy² + hz²) / 3, ... (f64), 1e-5 relative.
    let mut rng = SplitMix64::new(4);
    for _ in 0..20 {
        let h = Vec3::new(
            rng.range(0.01, 3.0),
            rng.range(0.01, 3.0),
            rng.range(0.01, 3.0),
        );
        let rho = rng.range(0.1, 5000.0);
        let m = Shape::cuboid(h).unwrap().mass_properties(rho).unwrap();
        let [x, y, z] = d3(h);
        let mass = 8.0 * x * y * z * rho as f64;
        rel_close(m.mass as f64, mass, 1e-5, "cuboid mass");
        let expected = [
            [mass * (y * y + z * z) / 3.0, 0.0, 0.0],
            [0.0, mass * (x * x + z * z) / 3.0, 0.0],
            [0.0, 0.0, mass * (x * x + y * y) / 3.0],
        ];
        mat_close(&m.inertia, &expected, 1e-5, "cuboid inertia");
    }
}

#[test]
fn tetrahedron_hull_matches_the_closed_form() {
    // The corner tetrahedron (0, e_x, e_y, e_z): V = 1/6, centroid (1/4, 1/4, 1/4),
    // ∫x² dV = 1/60, ∫xy dV = 1/120; about the centroid C_xx = 1/60 − V/16 = 1/160,
    // C_xy = 1/120 − V/16 = −1/480, so I_xx = C_yy + C_zz = 1/80 and I_xy = −C_xy = 1/480.
    // Scaled by s: V ∝ s³, I ∝ s⁵. Tolerance 1e-5 relative (f32 output of f64 sums).
    for (s, rho) in [(1.0f32, 1.0f32), (0.01, 7800.0), (40.0, 2.0)] {
        let pts = [Vec3::ZERO, Vec3::X * s, Vec3::Y * s, Vec3::Z * s];
        let hull = ConvexHull::new(&pts).unwrap();
        let m = Shape::hull(&hull).mass_properties(rho).unwrap();
        let (s, rho) = (s as f64, rho as f64);
        rel_close(m.mass as f64, rho * s.powi(3) / 6.0, 1e-5, "tetra mass");
        for c in d3(m.center) {
            rel_close(c, s / 4.0, 1e-5, "tetra centroid");
        }
        let d = rho * s.powi(5) / 80.0;
        let o = rho * s.powi(5) / 480.0;
        mat_close(
            &m.inertia,
            &[[d, o, o], [o, d, o], [o, o, d]],
            1e-5,
            "tetra inertia",
        );
    }
}

#[test]
fn box_corner_hull_equals_the_cuboid() {
    // Two independent computations (closed form vs tetrahedron sum), 1e-4 relative.
    let mut rng = SplitMix64::new(8);
    for _ in 0..20 {
        let h = Vec3::new(
            rng.range(0.05, 4.0),
            rng.range(0.05, 4.0),
            rng.range(0.05, 4.0),
        );
        let rho = rng.range(0.5, 3000.0);
        let hull = ConvexHull::new(&box_corners(h)).unwrap();
        let a = Shape::hull(&hull).mass_properties(rho).unwrap();
        let b = Shape::cuboid(h).unwrap().mass_properties(rho).unwrap();
        rel_close(a.mass as f64, b.mass as f64, 1e-4, "mass");
        assert!(a.center.length() <= 1e-5 * h.length(), "{:?}", a.center);
        let cols = [b.inertia.x, b.inertia.y, b.inertia.z];
        let expected: [[f64; 3]; 3] =
            std::array::from_fn(|i| std::array::from_fn(|j| d3(cols[j])[i]));
        mat_close(&a.inertia, &expected, 1e-4, "inertia");
    }
}

#[test]
fn rotated_offset_hull_has_the_right_centroid_and_inertia() {
    // The box corners moved by a random pose: centroid = pose position, inertia = R I Rᵀ
    // (computed in f64 from the cuboid's diagonal). Tolerances: centroid 1e-5 of the
    // largest coordinate (f32 input rounding), inertia 1e-4 of its largest entry.
    let mut rng = SplitMix64::new(9);
    for _ in 0..20 {
        let h = Vec3::new(
            rng.range(0.1, 2.0),
            rng.range(0.1, 2.0),
            rng.range(0.1, 2.0),
        );
        let pose = Iso::new(
            Vec3::new(
                rng.range(-20.0, 20.0),
                rng.range(-20.0, 20.0),
                rng.range(-20.0, 20.0),
            ),
            rng.rotation(),
        );
        let corners: Vec<Vec3> = box_corners(h)
            .iter()
            .map(|c| v3(to_world(&pose, d3(*c))))
            .collect();
        let hull = ConvexHull::new(&corners).unwrap();
        let m = hull.mass_properties(2.0);
        let scale = pose.position.abs().max_elem() + h.length();
        assert!(
            (m.center - pose.position).length() <= 1e-5 * scale,
            "centroid {:?} vs {:?}",
            m.center,
            pose.position
        );
        assert!((hull.centroid() - m.center).length() == 0.0);
        let [x, y, z] = d3(h);
        let mass = 16.0 * x * y * z;
        rel_close(m.mass as f64, mass, 1e-4, "mass");
        let diag = [
            mass * (y * y + z * z) / 3.0,
            mass * (x * x + z * z) / 3.0,
            mass * (x * x + y * y) / 3.0,
        ];
        let r = rot_rows(pose.rotation);
        let expected: [[f64; 3]; 3] = std::array::from_fn(|i| {
            std::array::from_fn(|j| (0..3).map(|k| r[i][k] * diag[k] * r[j][k]).sum())
        });
        mat_close(&m.inertia, &expected, 1e-4, "rotated inertia");
    }
}

#[test]
fn hull_of_points_on_a_sphere_approaches_the_sphere() {
    // Inscribed polytopes: mass and inertia below the sphere's, growing with the point
    // count. Lower bounds are the measured mass ratios of these Fibonacci sets (16: 0.666,
    // 32: 0.822, 64: 0.911) less a margin; 500 points reduced to 64 vertices reach 0.904.
    // From 32 points on, the inertia is isotropic within 1 % (measured 0.4 %).
    let r = 1.5f32;
    let sphere = Shape::sphere(r).unwrap().mass_properties(1.0).unwrap();
    let sphere_i = sphere.inertia.x.x;
    let (mut last_mass, mut last_inertia) = (0.0, 0.0);
    for (n, at_least) in [(16, 0.64), (32, 0.8), (64, 0.89), (500, 0.89)] {
        let hull = ConvexHull::new(&fibonacci_sphere(n, r)).unwrap();
        assert_eq!(hull.is_reduced(), n > MAX_HULL_VERTICES);
        let m = hull.mass_properties(1.0);
        let ratio = m.mass / sphere.mass;
        assert!(
            ratio < 1.0 && ratio > at_least,
            "{n} points: mass ratio {ratio}"
        );
        assert!(
            m.center.length() < 0.02 * r,
            "{n} points: centre {:?}",
            m.center
        );
        let diag = m.inertia.diagonal();
        assert!(diag.max_elem() < sphere_i, "{n} points: inertia {diag:?}");
        if n >= 32 {
            let spread = (diag.max_elem() - diag.min_elem()) / diag.max_elem();
            assert!(spread < 0.01, "{n} points: inertia {diag:?}");
        }
        if n <= 64 {
            assert!(
                m.mass > last_mass && diag.min_elem() > last_inertia,
                "{n} points"
            );
            (last_mass, last_inertia) = (m.mass, diag.max_elem());
        }
    }
}

#[test]
fn shapes_without_volume_and_bad_densities_are_refused_exactly() {
    let half = Shape::half_space(Vec3::Y).unwrap();
    let tri = Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::Z).unwrap();
    assert_eq!(half.mass_properties(1.0), Err(Error::NoVolume));
    assert_eq!(tri.mass_properties(1.0), Err(Error::NoVolume));
    let hull = ConvexHull::new(&box_corners(Vec3::ONE)).unwrap();
    let shapes = [
        Shape::sphere(1.0).unwrap(),
        Shape::capsule(1.0, 0.5).unwrap(),
        Shape::cuboid(Vec3::ONE).unwrap(),
        Shape::hull(&hull),
        half,
        tri,
    ];
    for s in &shapes {
        for (density, err) in [
            (0.0, Error::NotPositive(Input::Density)),
            (-0.0, Error::NotPositive(Input::Density)),
            (-2.0, Error::NotPositive(Input::Density)),
            (f32::NAN, Error::NonFinite(Input::Density)),
            (f32::INFINITY, Error::NonFinite(Input::Density)),
        ] {
            assert_eq!(s.mass_properties(density), Err(err), "{s:?} {density}");
        }
    }
}

// ----------------------------------------------------------------------------------------
// Ray casts
// ----------------------------------------------------------------------------------------

/// Distance along a ray to the first point where `sdf` reaches zero, by sphere tracing in
/// f64. `sdf` must never exceed the true distance to the surface (an exact signed
/// distance, or for a polytope the largest plane distance). Converges to 1e-10 m.
fn sphere_trace(sdf: &dyn Fn(D3) -> f64, origin: D3, dir: D3, max: f64) -> Option<f64> {
    let mut t = 0.0;
    for _ in 0..1_000_000 {
        let d = sdf(add(origin, mul(dir, t)));
        if d < 1e-10 {
            return Some(t);
        }
        t += d;
        if t > max {
            return None;
        }
    }
    panic!("sphere tracing did not converge");
}

/// Absolute tolerance (m) on ray distances and hit points in scenes within ~20 m of the
/// origin: ~100 f32 ulp at 20 m, covering the pose transforms (a few ulp each) and f32
/// root finding.
const RAY_TOL: f32 = 2.0e-4;

/// A shape with an f64 oracle: its signed distance (lower bound) in the local frame and a
/// way to draw interior points.
struct RayCase<'a> {
    shape: Shape<'a>,
    sdf: Box<dyn Fn(D3) -> f64 + 'a>,
    interior: Box<dyn Fn(&mut SplitMix64) -> Vec3 + 'a>,
}

/// Random rays aimed at interior points from outside the bounding sphere, random misses,
/// origins inside and the max_t cut-off, all under random poses.
fn check_ray_casts(case: &RayCase, seed: u64) {
    let mut rng = SplitMix64::new(seed);
    let radius = case.shape.bounding_radius();
    for _ in 0..200 {
        let pose = random_pose(&mut rng);
        let rows = rot_rows(pose.rotation);
        // A hit: aimed at an interior point.
        let target = to_world(&pose, d3((case.interior)(&mut rng)));
        let dir = rng.unit_vector();
        let dist = 2.0 * radius + 1.0 + rng.range(0.0, 3.0);
        let origin = v3(sub(target, mul(d3(dir), dist as f64)));
        let ray = Ray::new(origin, dir).unwrap();
        let local_o = to_local(&pose, d3(ray.origin));
        let local_d = rot_t(&rows, d3(ray.direction));
        let t = sphere_trace(&*case.sdf, local_o, local_d, 100.0).expect("oracle missed");
        let hit: RayHit = case
            .shape
            .cast_ray(&pose, &ray, 100.0)
            .unwrap()
            .unwrap_or_else(|| panic!("missed; oracle t = {t}"));
        assert!(
            (hit.t as f64 - t).abs() <= RAY_TOL as f64,
            "t {} vs {t}",
            hit.t
        );
        assert!((hit.point - ray.at(hit.t)).length() <= RAY_TOL);
        // The normal: unit, against the ray, and a supporting normal at the hit point
        // (the hit point is extreme along it), which pins it on smooth surfaces and
        // allows any valid one on edges.
        assert!((hit.normal.length() - 1.0).abs() < 1e-4);
        assert!(
            hit.normal.dot(ray.direction) <= 1e-4,
            "normal along the ray"
        );
        let n_local = pose.rotation.inverse_rotate(hit.normal);
        let p_local = pose.inverse_transform_point(hit.point);
        let support = case.shape.support(n_local).dot(n_local);
        assert!(
            (support - p_local.dot(n_local)).abs() <= RAY_TOL,
            "normal {:?} does not support the hit point",
            hit.normal
        );
        // max_t just short of the hit: no hit; just past it: the same hit.
        assert_eq!(
            case.shape.cast_ray(&pose, &ray, hit.t - 1e-3).unwrap(),
            None
        );
        assert_eq!(
            case.shape.cast_ray(&pose, &ray, hit.t + 1e-3).unwrap(),
            Some(hit)
        );

        // A miss: a line passing farther than the bounding radius from the centre.
        let dir = rng.unit_vector();
        let side = dir.any_perpendicular();
        let offset = side * (radius + 0.05 + rng.range(0.0, 2.0));
        let origin = pose.position + offset - dir * (radius + rng.range(0.0, 5.0));
        let ray = Ray::new(origin, dir).unwrap();
        assert_eq!(case.shape.cast_ray(&pose, &ray, 1.0e3).unwrap(), None);

        // Inside: t = 0, the origin, the reversed direction.
        let origin = v3(to_world(&pose, d3((case.interior)(&mut rng))));
        let ray = Ray::new(origin, rng.unit_vector()).unwrap();
        let hit = case.shape.cast_ray(&pose, &ray, 1.0).unwrap().unwrap();
        assert_eq!(hit.t, 0.0);
        assert!((hit.point - origin).length() <= 1e-5);
        assert!((hit.normal + ray.direction).length() <= 1e-5);
    }
}

fn random_in_ball(rng: &mut SplitMix64, r: f32) -> Vec3 {
    rng.unit_vector() * (r * rng.next_f32().cbrt())
}

#[test]
fn sphere_ray_casts_match_the_oracle() {
    for (k, r) in [0.1f32, 1.0, 2.5].into_iter().enumerate() {
        let case = RayCase {
            shape: Shape::sphere(r).unwrap(),
            sdf: Box::new(move |p| norm(p) - r as f64),
            interior: Box::new(move |rng| random_in_ball(rng, 0.95 * r)),
        };
        check_ray_casts(&case, 100 + k as u64);
    }
}

#[test]
fn capsule_ray_casts_match_the_oracle() {
    for (k, (h, r)) in [(1.0f32, 0.3f32), (0.05, 1.0), (2.0, 0.05)]
        .into_iter()
        .enumerate()
    {
        let case = RayCase {
            shape: Shape::capsule(h, r).unwrap(),
            sdf: Box::new(move |p| {
                let y = p[1].clamp(-h as f64, h as f64);
                norm(sub(p, [0.0, y, 0.0])) - r as f64
            }),
            interior: Box::new(move |rng| {
                Vec3::new(0.0, rng.range(-h, h), 0.0) + random_in_ball(rng, 0.95 * r)
            }),
        };
        check_ray_casts(&case, 200 + k as u64);
    }
}

/// Exact signed distance to a box of half-extents `h`.
fn box_sdf(p: D3, h: D3) -> f64 {
    let q = [p[0].abs() - h[0], p[1].abs() - h[1], p[2].abs() - h[2]];
    let outside = norm([q[0].max(0.0), q[1].max(0.0), q[2].max(0.0)]);
    outside + q[0].max(q[1]).max(q[2]).min(0.0)
}

fn random_in_box(rng: &mut SplitMix64, h: Vec3) -> Vec3 {
    Vec3::new(
        rng.range(-h.x, h.x),
        rng.range(-h.y, h.y),
        rng.range(-h.z, h.z),
    ) * 0.95
}

#[test]
fn cuboid_ray_casts_match_the_oracle() {
    for (k, h) in [
        Vec3::new(1.0, 2.0, 0.5),
        Vec3::splat(0.1),
        Vec3::new(3.0, 0.05, 1.0),
    ]
    .into_iter()
    .enumerate()
    {
        let case = RayCase {
            shape: Shape::cuboid(h).unwrap(),
            sdf: Box::new(move |p| box_sdf(p, d3(h))),
            interior: Box::new(move |rng| random_in_box(rng, h)),
        };
        check_ray_casts(&case, 300 + k as u64);
    }
}

/// Brute-force facet planes `(n, d)` of the hull of `points` (f64, O(n⁴)): planes through
/// three points with every point on or below them.
fn brute_force_planes(points: &[Vec3]) -> Vec<(D3, f64)> {
    let p: Vec<D3> = points.iter().map(|v| d3(*v)).collect();
    let mut planes = Vec::new();
    for i in 0..p.len() {
        for j in i + 1..p.len() {
            for k in j + 1..p.len() {
                let c = cross(sub(p[j], p[i]), sub(p[k], p[i]));
                if norm(c) < 1e-9 {
                    continue;
                }
                for n in [unit(c), mul(unit(c), -1.0)] {
                    let d = dot(n, p[i]);
                    if p.iter().all(|q| dot(n, *q) - d <= 1e-9) {
                        planes.push((n, d));
                    }
                }
            }
        }
    }
    planes
}

#[test]
fn hull_ray_casts_match_the_oracle() {
    // A box hull against the exact box distance (independent of the hull's planes).
    let h = Vec3::new(0.7, 1.3, 0.4);
    let box_hull = ConvexHull::new(&box_corners(h)).unwrap();
    let case = RayCase {
        shape: Shape::hull(&box_hull),
        sdf: Box::new(move |p| box_sdf(p, d3(h))),
        interior: Box::new(move |rng| random_in_box(rng, h)),
    };
    check_ray_casts(&case, 400);
    // Random 16-point hulls against their brute-force facet planes (the largest plane
    // distance is a lower bound of the distance, so sphere tracing converges to the hit).
    let mut rng = SplitMix64::new(401);
    for k in 0..5 {
        let points: Vec<Vec3> = (0..16)
            .map(|_| rng.unit_vector() * rng.range(0.5, 2.0))
            .collect();
        let hull = ConvexHull::new(&points).unwrap();
        let planes = brute_force_planes(&points);
        let vertices: Vec<Vec3> = hull.vertices().to_vec();
        let case = RayCase {
            shape: Shape::hull(&hull),
            sdf: Box::new(move |p| {
                planes
                    .iter()
                    .map(|(n, d)| dot(*n, p) - d)
                    .fold(f64::MIN, f64::max)
            }),
            // A random convex combination of the vertices, pulled 5 % towards the centroid.
            interior: Box::new(move |rng| {
                let w: Vec<f32> = vertices.iter().map(|_| rng.next_f32() + 1e-3).collect();
                let total: f32 = w.iter().sum();
                let mut p = Vec3::ZERO;
                for (v, wi) in vertices.iter().zip(&w) {
                    p += *v * (wi / total);
                }
                p * 0.95
            }),
        };
        check_ray_casts(&case, 410 + k);
    }
}

#[test]
fn half_space_ray_casts_match_the_closed_form() {
    // The plane through the pose's position with normal R n; from height s above it along
    // a direction with n · d < 0 the ray meets it at t = s / (−n · d).
    let mut rng = SplitMix64::new(500);
    for _ in 0..200 {
        let normal = rng.unit_vector();
        let shape = Shape::half_space(normal).unwrap();
        let pose = random_pose(&mut rng);
        let n = v3(rot(&rot_rows(pose.rotation), d3(normal)));
        let s = rng.range(0.1, 5.0);
        let origin = pose.position + n * s + n.any_perpendicular() * rng.range(-3.0, 3.0);
        let mut dir = rng.unit_vector();
        if dir.dot(n) > -0.1 {
            dir = (dir - n * (dir.dot(n) + 0.5)).normalize_or(-n);
        }
        let ray = Ray::new(origin, dir).unwrap();
        let t = s as f64 / -(n.dot(ray.direction) as f64);
        let hit = shape.cast_ray(&pose, &ray, 100.0).unwrap().unwrap();
        assert!(
            (hit.t as f64 - t).abs() <= RAY_TOL as f64 * (1.0 + t),
            "{} vs {t}",
            hit.t
        );
        assert!((hit.normal - n).length() <= 1e-5);
        assert_eq!(shape.cast_ray(&pose, &ray, hit.t * 0.999).unwrap(), None);
        // Moving away: a miss.
        let away = Ray::new(
            origin,
            (n + n.any_perpendicular() * rng.range(-2.0, 2.0)).normalize_or(n),
        )
        .unwrap();
        assert_eq!(shape.cast_ray(&pose, &away, 1.0e3).unwrap(), None);
        // Below the plane: inside.
        let below = Ray::new(pose.position - n * s, dir).unwrap();
        let hit = shape.cast_ray(&pose, &below, 1.0).unwrap().unwrap();
        assert_eq!(hit.t, 0.0);
        assert!((hit.normal + below.direction).length() <= 1e-6);
    }
}

#[test]
fn triangle_ray_casts_match_the_closed_form() {
    // Aimed at a point with barycentric coordinates ≥ 0.05 from `dist` away: t = dist,
    // normal ± the triangle normal, facing the ray, from either side. Aimed at a point
    // with a barycentric coordinate ≤ −0.05 in its plane: a miss.
    let mut rng = SplitMix64::new(600);
    let mut tested = 0;
    while tested < 200 {
        let [a, b, c] = [0, 1, 2].map(|_| rng.unit_vector() * rng.range(0.2, 2.0));
        let raw = (b - a).cross(c - a);
        if raw.length() < 0.2 {
            continue;
        }
        tested += 1;
        let shape = Shape::triangle(a, b, c).unwrap();
        let pose = random_pose(&mut rng);
        let world = |p: Vec3| v3(to_world(&pose, d3(p)));
        let n = v3(rot(&rot_rows(pose.rotation), unit(d3(raw))));
        let mut bary = [
            rng.range(0.05, 1.0),
            rng.range(0.05, 1.0),
            rng.range(0.05, 1.0),
        ];
        let total: f32 = bary.iter().sum();
        bary = bary.map(|x| x / total);
        if bary.iter().any(|&x| x < 0.05) {
            continue;
        }
        let target = world(a * bary[0] + b * bary[1] + c * bary[2]);
        let mut dir = rng.unit_vector();
        if dir.dot(n).abs() < 0.2 {
            dir = (dir + n).normalize_or(n);
        }
        let dist = rng.range(0.5, 5.0);
        let ray = Ray::new(target - dir * dist, dir).unwrap();
        let hit = shape.cast_ray(&pose, &ray, 100.0).unwrap().unwrap();
        assert!((hit.t - dist).abs() <= RAY_TOL, "{} vs {dist}", hit.t);
        let facing = if n.dot(ray.direction) < 0.0 { n } else { -n };
        assert!((hit.normal - facing).length() <= 1e-4);
        assert_eq!(shape.cast_ray(&pose, &ray, dist - 1e-3).unwrap(), None);
        // Outside one edge, in the triangle's plane: a miss.
        let out = world(a * -0.1 + b * 0.6 + c * 0.5);
        let ray = Ray::new(out - dir * dist, dir).unwrap();
        assert_eq!(shape.cast_ray(&pose, &ray, 100.0).unwrap(), None);
    }
}

#[test]
fn cast_ray_refuses_bad_input_exactly() {
    let shape = Shape::sphere(1.0).unwrap();
    let pose = Iso::IDENTITY;
    let good = Ray::new(Vec3::new(0.0, 0.0, -5.0), Vec3::Z).unwrap();
    let nan = Vec3::new(f32::NAN, 0.0, 0.0);
    let bad_origin = Ray {
        origin: nan,
        ..good
    };
    let bad_dir = Ray {
        direction: nan,
        ..good
    };
    assert_eq!(
        shape.cast_ray(&pose, &bad_origin, 1.0),
        Err(Error::NonFinite(Input::Position))
    );
    assert_eq!(
        shape.cast_ray(&pose, &bad_dir, 1.0),
        Err(Error::NonFinite(Input::Direction))
    );
    assert_eq!(
        shape.cast_ray(&pose, &good, -1.0),
        Err(Error::Negative(Input::Distance))
    );
    assert_eq!(
        shape.cast_ray(&pose, &good, f32::NAN),
        Err(Error::NonFinite(Input::Distance))
    );
    assert_eq!(
        shape.cast_ray(&pose, &good, f32::INFINITY),
        Err(Error::NonFinite(Input::Distance))
    );
    let bad_pose = Iso::from_position(nan);
    assert_eq!(
        shape.cast_ray(&bad_pose, &good, 1.0),
        Err(Error::NonFinite(Input::Position))
    );
    assert_eq!(
        Ray::new(Vec3::ZERO, Vec3::ZERO),
        Err(Error::NotPositive(Input::Direction))
    );
    assert_eq!(
        Ray::new(nan, Vec3::X),
        Err(Error::NonFinite(Input::Position))
    );
    // max_t = 0 is allowed: only an origin inside hits.
    assert_eq!(shape.cast_ray(&pose, &good, 0.0), Ok(None));
}

// ----------------------------------------------------------------------------------------
// Regression tests for the primitive ray casts fixed with this file
// ----------------------------------------------------------------------------------------

#[test]
fn sphere_ray_keeps_its_precision_far_away() {
    // A 1 cm ball seen from 10 km. The textbook root b² − (|m|² − r²) cancels to nothing
    // in f32 here (both terms ~1e8, ulp 8): it reported the 1.01 cm miss as a hit and the
    // 5 mm offset hit with a wrong normal.
    let ball = Shape::sphere(0.01).unwrap();
    let pose = Iso::IDENTITY;
    let hit = ball
        .cast_ray(
            &pose,
            &Ray::new(Vec3::new(1.0e4, 0.005, 0.0), -Vec3::X).unwrap(),
            2.0e4,
        )
        .unwrap()
        .unwrap();
    // Normal (√0.75, 0.5, 0): the hit is 5 mm off the axis on a 1 cm ball. Tolerance
    // 1e-2: the hit point's x is rounded to the f32 ulp at 1e4 (1 mm of its 8.7 mm); the
    // old code answered (0, 1, 0).
    assert!(
        (hit.normal - Vec3::new(0.75f32.sqrt(), 0.5, 0.0)).length() < 1e-2,
        "{hit:?}"
    );
    assert!(
        (hit.t as f64 - (1.0e4 - 0.75f64.sqrt() * 0.01)).abs() < 2e-3,
        "{hit:?}"
    );
    let miss = Ray::new(Vec3::new(1.0e4, 0.0101, 0.0), -Vec3::X).unwrap();
    assert_eq!(ball.cast_ray(&pose, &miss, 2.0e4).unwrap(), None);
    // 1e20 m away |m|² would overflow; such rays are now refused at the door.
    assert_eq!(
        Ray::new(Vec3::new(1.0e20, 0.5, 0.0), Vec3::X),
        Err(carom::Error::OutOfRange(carom::Input::Position))
    );
}

#[test]
fn capsule_ray_keeps_its_precision_far_away() {
    // A 1 cm thick capsule seen from 1 km across its cylinder: a miss 0.1 mm outside the
    // radius and a hit 1 mm inside it.
    let capsule = Shape::capsule(1.0, 0.01).unwrap();
    let pose = Iso::IDENTITY;
    let miss = Ray::new(Vec3::new(1.0e3, 0.0, 0.0101), -Vec3::X).unwrap();
    assert_eq!(capsule.cast_ray(&pose, &miss, 2.0e3).unwrap(), None);
    let ray = Ray::new(Vec3::new(1.0e3, 0.0, 0.009), -Vec3::X).unwrap();
    let hit = capsule.cast_ray(&pose, &ray, 2.0e3).unwrap().unwrap();
    let expected_t = 1.0e3 - (0.01f64 * 0.01 - 0.009 * 0.009).sqrt();
    assert!((hit.t as f64 - expected_t).abs() < 1e-3, "{hit:?}");
    assert!((hit.normal - Vec3::new((1.0f32 - 0.81).sqrt(), 0.0, 0.9)).length() < 1e-2);
}

#[test]
fn small_triangle_is_hit_at_a_grazing_angle() {
    // A triangle of 2 µm legs (area 2e-12 m²) hit at 80° from its normal: the old absolute
    // parallel test |det| < 1e-12 (det = 4e-12 · cos 80° = 7e-13) called it parallel.
    let tri = Shape::triangle(
        Vec3::ZERO,
        Vec3::new(2.0e-6, 0.0, 0.0),
        Vec3::new(0.0, 0.0, 2.0e-6),
    )
    .unwrap();
    let angle = 80.0f32.to_radians();
    let dir = Vec3::new(angle.sin(), -angle.cos(), 0.0);
    let target = Vec3::new(0.5e-6, 0.0, 0.5e-6);
    let ray = Ray::new(target - dir * 1.0e-3, dir).unwrap();
    let hit = tri.cast_ray(&Iso::IDENTITY, &ray, 1.0).unwrap().unwrap();
    assert!((hit.t - 1.0e-3).abs() < 1e-8, "{hit:?}");
    assert_eq!(hit.normal, Vec3::Y);
}

#[test]
fn hull_size_is_documented() {
    // "about 4.9 KiB" in the ConvexHull docs.
    let size = std::mem::size_of::<ConvexHull>();
    assert!((4864..5120).contains(&size), "{size}");
}

#[test]
fn sizes_out_of_range_and_non_unit_rays_are_refused_exactly() {
    use carom::shape::{Ray, MAX_SIZE, MIN_SIZE};
    assert_eq!(
        Shape::sphere(MIN_SIZE * 0.99),
        Err(Error::OutOfRange(Input::Radius))
    );
    assert_eq!(
        Shape::sphere(MAX_SIZE * 1.01),
        Err(Error::OutOfRange(Input::Radius))
    );
    assert!(Shape::sphere(MIN_SIZE).is_ok() && Shape::sphere(MAX_SIZE).is_ok());
    assert_eq!(
        Shape::capsule(1.0, 2.0e3),
        Err(Error::OutOfRange(Input::Radius))
    );
    assert_eq!(
        Shape::cuboid(Vec3::new(1.0, 1.0e-4, 1.0)),
        Err(Error::OutOfRange(Input::HalfExtents))
    );
    assert_eq!(Shape::sphere(-1.0), Err(Error::NotPositive(Input::Radius)));
    // A ray built by hand with a non-unit direction is refused by cast_ray.
    let ball = Shape::sphere(1.0).unwrap();
    let ray = Ray {
        origin: Vec3::new(-5.0, 0.0, 0.0),
        direction: Vec3::new(2.0, 0.0, 0.0),
    };
    assert_eq!(
        ball.cast_ray(&Iso::IDENTITY, &ray, 10.0),
        Err(Error::NotUnit(Input::Direction))
    );
    // A density that overflows the mass is refused.
    let big = Shape::cuboid(Vec3::splat(MAX_SIZE)).unwrap();
    assert_eq!(
        big.mass_properties(1.0e36),
        Err(Error::OutOfRange(Input::Density))
    );
}

/// `Face::len` is a public field: a value beyond the vertex array reads as a full face
/// instead of panicking, in `points` and in `transformed`.
#[test]
fn a_face_length_beyond_its_array_reads_as_full() {
    use carom::shape::MAX_FACE_VERTICES;
    let mut f = Shape::cuboid(Vec3::splat(0.5))
        .unwrap()
        .supporting_face(Vec3::Y);
    assert_eq!(f.points().len(), 4);
    f.len = 200;
    assert_eq!(f.points().len(), MAX_FACE_VERTICES);
    let moved = f.transformed(&Iso::new(Vec3::new(1.0, 2.0, 3.0), Quat::IDENTITY));
    assert_eq!(moved.points().len(), MAX_FACE_VERTICES);
    assert_eq!(moved.points()[0], f.points()[0] + Vec3::new(1.0, 2.0, 3.0));
}

// ----------------------------------------------------------------------------------------
// The builder's answers, bit for bit
// ----------------------------------------------------------------------------------------

/// FNV-1a 64 over `bytes`, continuing from `h`.
fn fnv(mut h: u64, bytes: &[u8]) -> u64 {
    for &b in bytes {
        h = (h ^ u64::from(b)).wrapping_mul(0x0100_0000_01b3);
    }
    h
}

/// Every hull the builder made for the standard scenes (`make_hulls` with the scenes'
/// seed), a reduced sphere, the largest input and 600 random clouds of every kind (the
/// refusals too), all of each answer's fields (its `Debug` text: `f32`s print as the
/// shortest text that reads back to the same bits), against a golden hash per math
/// backend. A change to
/// the builder that moves one bit anywhere (a vertex, a plane, a face's corner order,
/// an edge, the derived radii) fails here by name, before the scene checksums move.
#[test]
fn hull_builds_match_their_golden_hash() {
    let mut h = 0xcbf2_9ce4_8422_2325u64;
    let mut hash = |r: Result<ConvexHull, Error>| h = fnv(h, format!("{r:?}").as_bytes());
    let tetra = [Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z];
    let mut scene = vec![ConvexHull::new(&tetra).unwrap(); 64];
    carom::scenes::make_hulls(&mut scene, carom::scenes::SEED).unwrap();
    for hull in scene {
        hash(Ok(hull));
    }
    hash(ConvexHull::new(&fibonacci_sphere(500, 1.0)));
    let mut rng = SplitMix64::new(1024);
    let most: Vec<Vec3> = (0..MAX_HULL_INPUT_POINTS)
        .map(|_| rng.unit_vector() * rng.range(0.5, 1.0))
        .collect();
    hash(ConvexHull::new(&most));
    let mut rng = SplitMix64::new(2000);
    for _ in 0..600 {
        hash(ConvexHull::new(&random_cloud(&mut rng)));
    }
    // Each math backend has its own value: `micromath`'s square roots are approximations,
    // so its hulls differ in the last bits (both values taken before the change).
    let golden = if cfg!(feature = "micromath") {
        0x8daa_ccfd_339f_6620
    } else {
        0xa8ee_cb46_5c10_9300
    };
    assert_eq!(h, golden, "hash {h:#018x}");
}

/// `ConvexHull::UNIT_TETRAHEDRON` is what the builder makes of the four corners, every
/// field to the bit (the `Debug` text tells `-0.0` from `0.0`, which `==` does not).
#[test]
fn unit_tetrahedron_is_the_builders_hull_to_the_bit() {
    let built = ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
    assert_eq!(
        format!("{:?}", ConvexHull::UNIT_TETRAHEDRON),
        format!("{built:?}")
    );
}

/// `rebuild` in place gives `new`'s answer to the bit, whatever the slot held before (the
/// last cloud's hull, larger or smaller), and leaves the unit tetrahedron after a refusal:
/// the scenes' clouds, a reduced sphere and 600 random clouds of every kind, one slot.
#[test]
fn rebuild_in_place_matches_new_to_the_bit() {
    let mut rng = SplitMix64::new(2000);
    let mut clouds: Vec<Vec<Vec3>> = (0..600).map(|_| random_cloud(&mut rng)).collect();
    clouds.push(fibonacci_sphere(500, 1.0));
    let mut rng = SplitMix64::new(carom::scenes::SEED);
    for _ in 0..8 {
        clouds.push((0..16).map(|_| rng.unit_vector()).collect());
    }
    let mut slot = ConvexHull::UNIT_TETRAHEDRON;
    let (mut built, mut refused) = (0, 0);
    for cloud in &clouds {
        let fresh = ConvexHull::new(cloud);
        let in_place = slot.rebuild(cloud);
        match fresh {
            Ok(hull) => {
                assert_eq!(in_place, Ok(()));
                assert_eq!(format!("{slot:?}"), format!("{hull:?}"));
                built += 1;
            }
            Err(e) => {
                assert_eq!(in_place, Err(e));
                assert_eq!(
                    format!("{slot:?}"),
                    format!("{:?}", ConvexHull::UNIT_TETRAHEDRON)
                );
                refused += 1;
            }
        }
    }
    // Both outcomes were exercised.
    assert!(
        built > 100 && refused > 10,
        "built {built}, refused {refused}"
    );
}
