//! GJK distance and EPA penetration against closed forms and the brute-force oracle, with
//! the property functions of `carom::props` over random poses.
//!
//! Tolerances: coordinates here are at most a few metres, where one f32 ulp is about
//! 5e-7 m. A world ↔ local transform, GJK's barycentric reconstruction of the closest
//! points and the oracle's own arithmetic each cost a few ulps, and GJK stops within a
//! relative 1e-6 of the distance; together well under 1e-5 m. Distances are compared to
//! 1e-4 m: ten times that, while any wrong feature or missed iteration is off by
//! millimetres or more. Unit normals are compared to 1e-3 (a 1e-4 m error on a lever of
//! 0.1 m).

use carom::collide::{
    distance, intersects, penetration, segment_closest_points, separation, EpaStatus, GjkStatus,
    Separation, SeparationStatus, SimplexCache, MAX_GJK_ITERATIONS,
};
use carom::math::{Iso, Quat, Vec3};
use carom::props::{
    brute_force_distance, core_vertices, distance_properties, penetration_properties,
    separation_properties,
};
use carom::rng::SplitMix64;
use carom::shape::{ConvexHull, Shape};

/// Distance tolerance (m), see the file comment.
const TOL: f32 = 1.0e-4;
/// Normal tolerance (length of the difference of two unit vectors).
const NORMAL_TOL: f32 = 1.0e-3;
/// Separation-vector tolerance (m) against the oracle. GJK stops on a relative 1e-6 of
/// the distance, which leaves the direction free by up to √(2e-6) rad where the closest
/// features are nearly parallel: the worst of the 1000 hull pairs below is 1.4e-4 m with
/// libm and 3.2e-4 m with `micromath` (whose approximate trig gives `SplitMix64::rotation`
/// other random poses, one of them such a near-parallel pair), every other pair under 3e-6.
const GAP_TOL: f32 = if cfg!(feature = "micromath") {
    4.0 * TOL
} else {
    3.0 * TOL
};

fn random_pose(rng: &mut SplitMix64, reach: f32) -> Iso {
    Iso::new(rng.unit_vector() * rng.range(0.0, reach), rng.rotation())
}

fn hull_cloud(rng: &mut SplitMix64, scale: f32) -> [Vec3; 16] {
    let mut pts = [Vec3::ZERO; 16];
    for p in pts.iter_mut() {
        *p = rng.unit_vector() * scale;
    }
    pts
}

/// Random hulls of 16 unit-sphere points, or `None` when the hull builder refuses them.
fn random_hulls(seed: u64, n: usize, scale: f32) -> Option<Vec<ConvexHull>> {
    let mut rng = SplitMix64::new(seed);
    (0..n)
        .map(|_| ConvexHull::new(&hull_cloud(&mut rng, scale)).ok())
        .collect()
}

fn fresh_distance(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso) -> carom::collide::DistanceOutput {
    distance(a, pa, b, pb, &mut SimplexCache::default()).expect("valid poses")
}

/// Compare GJK with the oracle on the cores of two polytope-cored shapes; returns the
/// absolute distance error.
fn oracle_error(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso) -> f32 {
    let out = fresh_distance(a, pa, b, pb);
    let va = core_vertices(a, pa).expect("polytope core");
    let vb = core_vertices(b, pb).expect("polytope core");
    let o = brute_force_distance(va.points(), vb.points()).expect("non-empty");
    let expected = (o.distance - a.radius() - b.radius()).max(0.0);
    let err = (out.distance - expected).abs();
    if expected > TOL {
        // The separation vector of two convex sets is unique: compare it.
        let dir = (o.point_b - o.point_a).normalize_or(Vec3::Y);
        let gap = out.normal * out.distance - dir * expected;
        assert!(gap.length() < GAP_TOL, "{gap:?} {out:?} {o:?}");
        let v = out.point_b - out.point_a;
        assert!((v.length() - out.distance).abs() < TOL, "{out:?}");
    }
    err
}

#[test]
fn sphere_sphere_distance_and_points_are_analytic() {
    let mut rng = SplitMix64::new(1);
    for _ in 0..500 {
        let (ra, rb) = (rng.range(0.1, 1.0), rng.range(0.1, 1.0));
        let (a, b) = (Shape::sphere(ra).unwrap(), Shape::sphere(rb).unwrap());
        let (pa, pb) = (random_pose(&mut rng, 2.0), random_pose(&mut rng, 2.0));
        let out = fresh_distance(&a, &pa, &b, &pb);
        let c = pb.position - pa.position;
        let expected = (c.length() - ra - rb).max(0.0);
        assert!((out.distance - expected).abs() < TOL, "{out:?} {expected}");
        if c.length() > 1e-3 {
            let n = c.normalize_or(Vec3::Y);
            assert!((out.normal - n).length() < NORMAL_TOL);
            assert!((out.point_a - (pa.position + n * ra)).length() < TOL);
            assert!((out.point_b - (pb.position - n * rb)).length() < TOL);
        }
        assert_eq!(
            out.status == GjkStatus::Overlapping,
            c.length() <= 1e-5 * c.length().max(1.0)
        );
    }
}

#[test]
fn sphere_box_distance_matches_point_box_clamp() {
    let mut rng = SplitMix64::new(2);
    let half = Vec3::new(0.8, 0.3, 0.5);
    let cuboid = Shape::cuboid(half).unwrap();
    for _ in 0..1000 {
        let r = rng.range(0.05, 0.6);
        let ball = Shape::sphere(r).unwrap();
        let pose_box = random_pose(&mut rng, 1.0);
        let pose_ball = random_pose(&mut rng, 2.5);
        let out = fresh_distance(&cuboid, &pose_box, &ball, &pose_ball);
        // Closest point of the box to the centre: clamp in the box frame.
        let c = pose_box.inverse_transform_point(pose_ball.position);
        let q = Vec3::new(
            c.x.clamp(-half.x, half.x),
            c.y.clamp(-half.y, half.y),
            c.z.clamp(-half.z, half.z),
        );
        let outside = (c - q).length();
        if outside <= 1e-3 {
            continue; // centre inside or on the box: EPA's case
        }
        let expected = (outside - r).max(0.0);
        assert!((out.distance - expected).abs() < TOL, "{out:?} {expected}");
        let n = pose_box.transform_vector((c - q) * (1.0 / outside));
        assert!((out.normal - n).length() < NORMAL_TOL, "{out:?} {n:?}");
        assert!((out.point_a - pose_box.transform_point(q)).length() < TOL);
        assert!((out.point_b - (pose_ball.position - n * r)).length() < TOL);
    }
}

#[test]
fn capsule_capsule_distance_matches_segment_closest_points() {
    let mut rng = SplitMix64::new(3);
    for _ in 0..1000 {
        let (ha, ra) = (rng.range(0.1, 1.0), rng.range(0.05, 0.4));
        let (hb, rb) = (rng.range(0.1, 1.0), rng.range(0.05, 0.4));
        let a = Shape::capsule(ha, ra).unwrap();
        let b = Shape::capsule(hb, rb).unwrap();
        let (pa, pb) = (random_pose(&mut rng, 1.0), random_pose(&mut rng, 2.5));
        let seg = |p: &Iso, h: f32| {
            (
                p.transform_point(Vec3::new(0.0, -h, 0.0)),
                p.transform_point(Vec3::new(0.0, h, 0.0)),
            )
        };
        let (p1, q1) = seg(&pa, ha);
        let (p2, q2) = seg(&pb, hb);
        let (s, t) = segment_closest_points(p1, q1, p2, q2);
        let (ca, cb) = (p1 + (q1 - p1) * s, p2 + (q2 - p2) * t);
        let core = (cb - ca).length();
        let out = fresh_distance(&a, &pa, &b, &pb);
        assert!(
            (out.distance - (core - ra - rb).max(0.0)).abs() < TOL,
            "{out:?} {core}"
        );
        if core > 1e-3 {
            // The closest points may not be unique (parallel segments); the separation
            // vector of the cores is.
            let n = (cb - ca) * (1.0 / core);
            assert!((out.normal - n).length() < NORMAL_TOL);
            let core_gap = (out.point_b + out.normal * rb) - (out.point_a - out.normal * ra);
            assert!((core_gap - (cb - ca)).length() < TOL * 2.0);
        }
    }
}

#[test]
fn box_box_distance_matches_brute_force_oracle() {
    let mut rng = SplitMix64::new(4);
    let mut max_err: f32 = 0.0;
    for _ in 0..1000 {
        let a = Shape::cuboid(Vec3::new(
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
        ))
        .unwrap();
        let b = Shape::cuboid(Vec3::new(
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
        ))
        .unwrap();
        let (pa, pb) = (random_pose(&mut rng, 1.0), random_pose(&mut rng, 3.0));
        max_err = max_err.max(oracle_error(&a, &pa, &b, &pb));
    }
    assert!(max_err < TOL, "max error {max_err}");
}

#[test]
fn hull_hull_and_hull_box_distances_match_brute_force_oracle() {
    let Some(hulls) = random_hulls(5, 16, 1.0) else {
        panic!("ConvexHull::new refused random unit-sphere clouds");
    };
    let cuboid = Shape::cuboid(Vec3::new(0.7, 0.4, 0.5)).unwrap();
    let mut rng = SplitMix64::new(6);
    let mut max_err: f32 = 0.0;
    for k in 0..1000 {
        let a = Shape::hull(&hulls[k % hulls.len()]);
        let b = if k % 4 == 0 {
            cuboid
        } else {
            Shape::hull(&hulls[(k * 7 + 3) % hulls.len()])
        };
        let (pa, pb) = (random_pose(&mut rng, 1.0), random_pose(&mut rng, 3.5));
        max_err = max_err.max(oracle_error(&a, &pa, &b, &pb));
    }
    assert!(max_err < TOL, "max error {max_err}");
}

#[test]
fn half_space_distance_and_depth_are_closed_form() {
    let mut rng = SplitMix64::new(7);
    let ground = Shape::half_space(Vec3::Y).unwrap();
    let half = Vec3::new(0.5, 0.25, 0.4);
    let cuboid = Shape::cuboid(half).unwrap();
    let ball = Shape::sphere(0.3).unwrap();
    for _ in 0..500 {
        let pose_ground = Iso::new(rng.unit_vector(), rng.rotation());
        let n = pose_ground.transform_vector(Vec3::Y);
        let pose_b = random_pose(&mut rng, 2.0);
        // The box's lowest point along n: centre minus the box's extent along n.
        let local_n = pose_b.inverse_transform_vector(n);
        let extent = half.x * local_n.x.abs() + half.y * local_n.y.abs() + half.z * local_n.z.abs();
        let height = n.dot(pose_b.position - pose_ground.position);
        for (shape, below) in [(cuboid, extent), (ball, 0.3)] {
            let s = height - below;
            let out = fresh_distance(&ground, &pose_ground, &shape, &pose_b);
            assert!((out.distance - s.max(0.0)).abs() < TOL);
            assert!((out.normal - n).length() < NORMAL_TOL);
            let swapped = fresh_distance(&shape, &pose_b, &ground, &pose_ground);
            assert!((swapped.distance - out.distance).abs() < TOL);
            assert!((swapped.normal + n).length() < NORMAL_TOL);
            match penetration(&ground, &pose_ground, &shape, &pose_b).unwrap() {
                Some(p) => {
                    assert!(s <= 0.0);
                    assert!((p.depth + s).abs() < TOL && (p.normal - n).length() < NORMAL_TOL);
                }
                None => assert!(s > 0.0),
            }
        }
    }
    // Two half-spaces: distance 0, overlapping, no finite depth.
    let out = fresh_distance(
        &ground,
        &Iso::IDENTITY,
        &ground,
        &Iso::from_position(Vec3::Y),
    );
    assert_eq!((out.distance, out.status), (0.0, GjkStatus::Overlapping));
    assert_eq!(
        penetration(&ground, &Iso::IDENTITY, &ground, &Iso::IDENTITY),
        Ok(None)
    );
}

#[test]
fn distance_is_symmetric_with_points_swapped() {
    let hulls = random_hulls(8, 4, 0.8).expect("hulls build");
    let shapes = [
        Shape::sphere(0.3).unwrap(),
        Shape::capsule(0.4, 0.2).unwrap(),
        Shape::cuboid(Vec3::new(0.5, 0.3, 0.2)).unwrap(),
        Shape::hull(&hulls[0]),
        Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::new(0.2, 0.0, 0.9)).unwrap(),
    ];
    let mut rng = SplitMix64::new(9);
    for _ in 0..300 {
        for a in &shapes {
            let (pa, pb) = (random_pose(&mut rng, 1.0), random_pose(&mut rng, 3.0));
            // Against a sphere the closest points are unique: they must swap exactly.
            let b = &shapes[0];
            let ab = fresh_distance(a, &pa, b, &pb);
            let ba = fresh_distance(b, &pb, a, &pa);
            assert!((ab.distance - ba.distance).abs() < TOL);
            if ab.distance > TOL {
                assert!((ab.normal + ba.normal).length() < NORMAL_TOL);
                assert!((ab.point_a - ba.point_b).length() < TOL);
                assert!((ab.point_b - ba.point_a).length() < TOL);
            }
            for b in &shapes {
                let ab = fresh_distance(a, &pa, b, &pb);
                let ba = fresh_distance(b, &pb, a, &pa);
                assert!((ab.distance - ba.distance).abs() < TOL, "{ab:?} {ba:?}");
                if ab.distance > TOL {
                    let v = ab.normal * ab.distance + ba.normal * ba.distance;
                    assert!(v.length() < 3.0 * TOL);
                }
            }
        }
    }
}

#[test]
fn epa_sphere_inside_box_depth_is_radius_plus_face_distance() {
    let mut rng = SplitMix64::new(10);
    let half = Vec3::new(1.0, 0.7, 0.5);
    let cuboid = Shape::cuboid(half).unwrap();
    for _ in 0..1000 {
        let r = rng.range(0.05, 0.3);
        let ball = Shape::sphere(r).unwrap();
        let pose_box = random_pose(&mut rng, 1.0);
        let c = Vec3::new(
            rng.range(-0.95, 0.95) * half.x,
            rng.range(-0.95, 0.95) * half.y,
            rng.range(-0.95, 0.95) * half.z,
        );
        let pose_ball = Iso::new(pose_box.transform_point(c), rng.rotation());
        // Nearest face: the axis with the least room h − |c|.
        let room = [half.x - c.x.abs(), half.y - c.y.abs(), half.z - c.z.abs()];
        let k = (0..3).min_by(|&i, &j| room[i].total_cmp(&room[j])).unwrap();
        let mut axis = [Vec3::X, Vec3::Y, Vec3::Z][k];
        if [c.x, c.y, c.z][k] < 0.0 {
            axis = -axis;
        }
        let p = penetration(&cuboid, &pose_box, &ball, &pose_ball)
            .unwrap()
            .unwrap();
        assert_eq!(p.status, EpaStatus::Converged);
        assert!(
            (p.depth - (r + room[k])).abs() < TOL,
            "{p:?} {}",
            r + room[k]
        );
        let unique = (0..3).all(|i| i == k || room[i] > room[k] + 1e-3);
        if unique {
            assert!((p.normal - pose_box.transform_vector(axis)).length() < NORMAL_TOL);
        }
        let swapped = penetration(&ball, &pose_ball, &cuboid, &pose_box)
            .unwrap()
            .unwrap();
        assert!((swapped.depth - p.depth).abs() < TOL);
    }
}

#[test]
fn epa_box_box_face_overlap_depth_axis_aligned_and_rotated_about_the_normal() {
    let mut rng = SplitMix64::new(11);
    let a = Shape::cuboid(Vec3::new(1.0, 0.5, 0.8)).unwrap();
    let b = Shape::cuboid(Vec3::new(0.4, 0.3, 0.35)).unwrap();
    for k in 0..1000 {
        let pose_a = random_pose(&mut rng, 1.0);
        let depth = rng.range(0.01, 0.2);
        let angle = if k % 2 == 0 {
            0.0
        } else {
            rng.range(-3.1, 3.1)
        };
        // B sits on A's +Y face, sunk by `depth`, turned about A's Y (the contact normal).
        // Its footprint stays well inside the face, so every other axis overlaps by
        // more than 0.9 m and +Y is the unique minimum.
        let local = Vec3::new(
            rng.range(-0.3, 0.3),
            0.5 + 0.3 - depth,
            rng.range(-0.2, 0.2),
        );
        let pose_b = pose_a * Iso::new(local, Quat::from_axis_angle(Vec3::Y, angle));
        let n = pose_a.transform_vector(Vec3::Y);
        let p = penetration(&a, &pose_a, &b, &pose_b).unwrap().unwrap();
        assert_eq!(p.status, EpaStatus::Converged);
        assert!((p.depth - depth).abs() < TOL, "{p:?} {depth}");
        assert!((p.normal - n).length() < NORMAL_TOL, "{p:?}");
        let q = penetration(&b, &pose_b, &a, &pose_a).unwrap().unwrap();
        assert!((q.depth - depth).abs() < TOL && (q.normal + n).length() < NORMAL_TOL);
    }
}

#[test]
fn epa_capsule_box_depth_through_the_top_face() {
    let mut rng = SplitMix64::new(12);
    let cuboid = Shape::cuboid(Vec3::new(1.0, 0.5, 1.0)).unwrap();
    let capsule = Shape::capsule(0.5, 0.2).unwrap();
    let lying = Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_2);
    let mut cores_overlap = 0;
    for _ in 0..1000 {
        let pose_box = random_pose(&mut rng, 1.0);
        // A capsule lying along the box's x axis over its top face, sunk by `depth`:
        // shallower than the radius only the round skin overlaps (GJK's answer); deeper,
        // the core segment is inside the box (EPA's answer). The top face stays nearest.
        let depth = rng.range(0.02, 0.6);
        let local = Vec3::new(
            rng.range(-0.3, 0.3),
            0.5 + 0.2 - depth,
            rng.range(-0.3, 0.3),
        );
        let pose_capsule = pose_box * Iso::new(local, lying);
        let p = penetration(&cuboid, &pose_box, &capsule, &pose_capsule)
            .unwrap()
            .unwrap();
        assert_eq!(p.status, EpaStatus::Converged);
        assert!((p.depth - depth).abs() < TOL, "{p:?} {depth}");
        assert!((p.normal - pose_box.transform_vector(Vec3::Y)).length() < NORMAL_TOL);
        let q = penetration(&capsule, &pose_capsule, &cuboid, &pose_box)
            .unwrap()
            .unwrap();
        assert!((q.depth - p.depth).abs() < TOL && (q.normal + p.normal).length() < NORMAL_TOL);
        if depth > 0.2 + 1e-3 {
            cores_overlap += 1;
            let d = fresh_distance(&cuboid, &pose_box, &capsule, &pose_capsule);
            assert_eq!(d.status, GjkStatus::Overlapping);
        }
    }
    assert!(cores_overlap > 300, "both paths exercised");
}

#[test]
fn epa_is_symmetric_for_random_overlaps() {
    let hulls = random_hulls(13, 8, 0.9).expect("hulls build");
    let cuboid = Shape::cuboid(Vec3::new(0.6, 0.4, 0.5)).unwrap();
    let mut rng = SplitMix64::new(14);
    let mut checked = 0;
    for k in 0..1000 {
        let a = Shape::hull(&hulls[k % 8]);
        let b = if k % 2 == 0 {
            cuboid
        } else {
            Shape::hull(&hulls[(k / 2) % 8])
        };
        let (pa, pb) = (random_pose(&mut rng, 0.5), random_pose(&mut rng, 1.0));
        let Some(p) = penetration(&a, &pa, &b, &pb).unwrap() else {
            continue;
        };
        let q = penetration(&b, &pb, &a, &pa)
            .unwrap()
            .expect("symmetric overlap");
        assert_eq!(
            (p.status, q.status),
            (EpaStatus::Converged, EpaStatus::Converged)
        );
        assert!((p.depth - q.depth).abs() < TOL, "{p:?} {q:?}");
        checked += 1;
    }
    assert!(checked > 500);
}

#[test]
fn warm_start_gives_the_same_answer_in_no_more_iterations() {
    let hulls = random_hulls(15, 8, 1.0).expect("hulls build");
    let cuboid = Shape::cuboid(Vec3::new(0.6, 0.4, 0.5)).unwrap();
    let mut rng = SplitMix64::new(16);
    let (mut cold_total, mut warm_total) = (0u32, 0u32);
    for k in 0..1000 {
        let a = Shape::hull(&hulls[k % 8]);
        let b = if k % 3 == 0 {
            cuboid
        } else {
            Shape::hull(&hulls[(k + 5) % 8])
        };
        let (pa, pb) = (random_pose(&mut rng, 0.5), random_pose(&mut rng, 3.0));
        let mut cache = SimplexCache::default();
        let cold = distance(&a, &pa, &b, &pb, &mut cache).unwrap();
        assert!(cache.count >= 1 && cache.count <= 4);
        // Same pose with the cache: the same answer, never more iterations.
        let warm = distance(&a, &pa, &b, &pb, &mut cache).unwrap();
        assert!((warm.distance - cold.distance).abs() < TOL);
        assert!(warm.iterations <= cold.iterations, "{warm:?} {cold:?}");
        // 1 mm further on: the answer of a cold start, in fewer iterations on average.
        let moved = Iso::new(pb.position + rng.unit_vector() * 1e-3, pb.rotation);
        let warm = distance(&a, &pa, &b, &moved, &mut cache).unwrap();
        let cold = fresh_distance(&a, &pa, &b, &moved);
        assert!((warm.distance - cold.distance).abs() < TOL);
        cold_total += cold.iterations;
        warm_total += warm.iterations;
    }
    assert!(
        warm_total < cold_total,
        "warm {warm_total} cold {cold_total}"
    );
}

#[test]
fn properties_hold_for_every_shape_pair_under_random_poses() {
    let hulls = random_hulls(17, 2, 0.7).expect("hulls build");
    let shapes = [
        Shape::sphere(0.4).unwrap(),
        Shape::capsule(0.5, 0.2).unwrap(),
        Shape::cuboid(Vec3::new(0.6, 0.3, 0.45)).unwrap(),
        Shape::hull(&hulls[0]),
        Shape::hull(&hulls[1]),
        Shape::triangle(
            Vec3::new(-0.5, 0.0, -0.4),
            Vec3::new(0.6, 0.1, 0.0),
            Vec3::new(0.0, -0.1, 0.7),
        )
        .unwrap(),
        Shape::half_space(Vec3::new(0.1, 1.0, 0.0)).unwrap(),
    ];
    let mut rng = SplitMix64::new(18);
    for round in 0..40 {
        for a in &shapes {
            for b in &shapes {
                let reach = if round % 2 == 0 { 0.8 } else { 2.0 };
                let (pa, pb) = (random_pose(&mut rng, reach), random_pose(&mut rng, reach));
                assert_eq!(
                    distance_properties(a, &pa, b, &pb),
                    Ok(()),
                    "{a:?} {pa:?} {b:?} {pb:?}"
                );
                assert_eq!(
                    penetration_properties(a, &pa, b, &pb),
                    Ok(()),
                    "{a:?} {pa:?} {b:?} {pb:?}"
                );
                assert_eq!(
                    separation_properties(a, &pa, b, &pb),
                    Ok(()),
                    "{a:?} {pa:?} {b:?} {pb:?}"
                );
            }
        }
    }
}

#[test]
fn touching_and_degenerate_contacts_keep_the_properties() {
    // Exactly touching faces, crossing capsule axes, concentric spheres, a sphere centred
    // on a triangle, coincident boxes: the cases where D is flat or the origin is on it.
    let cuboid = Shape::cuboid(Vec3::new(0.5, 0.5, 0.5)).unwrap();
    let capsule = Shape::capsule(0.5, 0.1).unwrap();
    let ball = Shape::sphere(0.25).unwrap();
    let tri = Shape::triangle(
        Vec3::new(-1.0, 0.0, -1.0),
        Vec3::new(1.0, 0.0, -1.0),
        Vec3::new(0.0, 0.0, 1.0),
    )
    .unwrap();
    let turned = Quat::from_axis_angle(Vec3::X, core::f32::consts::FRAC_PI_2);
    let cases = [
        (
            cuboid,
            Iso::IDENTITY,
            cuboid,
            Iso::from_position(Vec3::new(0.0, 1.0, 0.0)),
        ),
        (
            cuboid,
            Iso::IDENTITY,
            cuboid,
            Iso::from_position(Vec3::new(1.0, 1.0, 1.0)),
        ),
        (cuboid, Iso::IDENTITY, cuboid, Iso::IDENTITY),
        (
            capsule,
            Iso::IDENTITY,
            capsule,
            Iso::new(Vec3::ZERO, turned),
        ),
        (ball, Iso::IDENTITY, ball, Iso::IDENTITY),
        (tri, Iso::IDENTITY, ball, Iso::IDENTITY),
        (tri, Iso::IDENTITY, tri, Iso::IDENTITY),
        (ball, Iso::IDENTITY, capsule, Iso::IDENTITY),
    ];
    for (a, pa, b, pb) in cases {
        assert_eq!(
            distance_properties(&a, &pa, &b, &pb),
            Ok(()),
            "{a:?} {b:?} {pb:?}"
        );
        assert_eq!(
            penetration_properties(&a, &pa, &b, &pb),
            Ok(()),
            "{a:?} {b:?} {pb:?}"
        );
        assert!(intersects(&a, &pa, &b, &pb).unwrap());
    }
    // Coincident unit boxes: the depth is the full width, 1 m.
    let p = penetration(&cuboid, &Iso::IDENTITY, &cuboid, &Iso::IDENTITY)
        .unwrap()
        .unwrap();
    assert!((p.depth - 1.0).abs() < TOL, "{p:?}");
    // Concentric spheres: depth is the sum of the radii, along some unit normal.
    let p = penetration(&ball, &Iso::IDENTITY, &ball, &Iso::IDENTITY)
        .unwrap()
        .unwrap();
    assert!((p.depth - 0.5).abs() < TOL && (p.normal.length() - 1.0).abs() < 1e-6);
}

#[test]
fn invalid_poses_are_refused() {
    let s = Shape::sphere(1.0).unwrap();
    let bad = [
        Iso::from_position(Vec3::new(f32::NAN, 0.0, 0.0)),
        Iso::from_position(Vec3::new(0.0, f32::INFINITY, 0.0)),
        Iso::new(Vec3::ZERO, Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
        Iso::new(Vec3::ZERO, Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0)),
    ];
    for p in bad {
        assert!(distance(&s, &p, &s, &Iso::IDENTITY, &mut SimplexCache::default()).is_err());
        assert!(penetration(&s, &Iso::IDENTITY, &s, &p).is_err());
        assert!(intersects(&s, &p, &s, &Iso::IDENTITY).is_err());
        assert_eq!(distance_properties(&s, &p, &s, &Iso::IDENTITY), Ok(()));
        assert_eq!(penetration_properties(&s, &Iso::IDENTITY, &s, &p), Ok(()));
    }
}

/// The narrow-phase benchmark query sets (`shared/SCENES.md`; same seeds and draw order
/// as `benches/narrow_phase.rs`): every answer agrees with the oracle, EPA always
/// converges, and the iteration counts stay below their caps. Run with `--nocapture` to
/// see the figures.
#[test]
fn benchmark_query_sets_agree_with_the_oracle() {
    const PAIRS: usize = 4096;
    let mut rng = SplitMix64::new(0x4855_4c4c_5345_5421);
    let hulls: Vec<ConvexHull> = (0..64)
        .map(|_| ConvexHull::new(&hull_cloud(&mut rng, 1.0)).expect("hull builds"))
        .collect();
    let ball = Shape::sphere(0.5).unwrap();
    let cuboid = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let sets: [(&str, u64, (f32, f32)); 3] = [
        ("hull-hull", 1, (1.0, 2.2)),
        ("ball-box", 2, (0.6, 1.4)),
        ("box-box", 3, (0.8, 1.6)),
    ];
    for (name, seed, (d_min, d_max)) in sets {
        let mut rng = SplitMix64::new(seed);
        let count = if name == "hull-hull" { 64 } else { 1 };
        let (mut gjk_iters, mut epa_iters, mut epa_runs, mut epa_max) = (0u32, 0u32, 0u32, 0u32);
        let mut overlaps = 0;
        let mut max_err: f32 = 0.0;
        for _ in 0..PAIRS {
            let pa = Iso::new(Vec3::ZERO, rng.rotation());
            let dir = rng.unit_vector();
            let d = rng.range(d_min, d_max);
            let pb = Iso::new(dir * d, rng.rotation());
            let (ia, ib) = (
                (rng.next_u64() % count) as usize,
                (rng.next_u64() % count) as usize,
            );
            let (a, b) = match name {
                "hull-hull" => (Shape::hull(&hulls[ia]), Shape::hull(&hulls[ib])),
                "ball-box" => (ball, cuboid),
                _ => (cuboid, cuboid),
            };
            let out = fresh_distance(&a, &pa, &b, &pb);
            assert!(
                out.iterations <= MAX_GJK_ITERATIONS && out.status != GjkStatus::IterationLimit
            );
            gjk_iters += out.iterations;
            max_err = max_err.max(oracle_error(&a, &pa, &b, &pb));
            if let Some(p) = penetration(&a, &pa, &b, &pb).unwrap() {
                overlaps += 1;
                assert_eq!(p.status, EpaStatus::Converged, "{p:?}");
                if p.iterations > 0 {
                    epa_runs += 1;
                    epa_iters += p.iterations;
                    epa_max = epa_max.max(p.iterations);
                }
            }
        }
        eprintln!(
            "{name}: max |GJK − oracle| {max_err:.2e} m, mean GJK iterations {:.2}, \
             {overlaps} overlaps, EPA runs {epa_runs}, mean EPA iterations {:.2}, max {epa_max}",
            gjk_iters as f32 / PAIRS as f32,
            epa_iters as f32 / epa_runs.max(1) as f32,
        );
        assert!(max_err < TOL, "{name}: {max_err}");
        assert!(
            overlaps > PAIRS / 10,
            "{name}: the set has overlapping pairs"
        );
        assert!(epa_max < 48, "{name}: EPA needed {epa_max} iterations");
    }
}

/// A coordinate on a grid: `n · unit` with `n` uniform in `[−range, range]`.
fn grid(rng: &mut SplitMix64, range: u64, unit: f32) -> f32 {
    (rng.next_u64() % (2 * range + 1)) as f32 * unit - range as f32 * unit
}

/// The fuzz target's hard cases on stable: grid coordinates (faces line up, exact
/// touching, duplicate and nearly coplanar hull points), sizes from 0.1 mm to 1 m, axis
/// rotations, and one pair in ten 375 m from the origin. Every property holds.
#[test]
fn properties_hold_on_grid_aligned_and_degenerate_inputs() {
    let mut rng = SplitMix64::new(19);
    let mut checked = 0;
    for _ in 0..6000 {
        let mut hulls = [None, None];
        for h in hulls.iter_mut() {
            let flat = rng.next_u64().is_multiple_of(3);
            let n = 4 + (rng.next_u64() % 12) as usize;
            let pts: Vec<Vec3> = (0..n)
                .map(|_| {
                    let y = if flat {
                        grid(&mut rng, 1, 0.01)
                    } else {
                        grid(&mut rng, 8, 0.125)
                    };
                    Vec3::new(grid(&mut rng, 8, 0.125), y, grid(&mut rng, 8, 0.125))
                })
                .collect();
            *h = ConvexHull::new(&pts).ok();
        }
        let mut shapes = [None, None];
        for (k, s) in shapes.iter_mut().enumerate() {
            let unit = [1.0 / 8192.0, 1.0 / 16.0, 1.0e-4][(rng.next_u64() % 3) as usize];
            let mut size = || ((rng.next_u64() % 100) as f32 + 1.0) * unit;
            let (x, y, z) = (size(), size(), size());
            let mut corner = || {
                Vec3::new(
                    grid(&mut rng, 8, 0.125),
                    grid(&mut rng, 8, 0.125),
                    grid(&mut rng, 8, 0.125),
                )
            };
            let (c0, c1, c2) = (corner(), corner(), corner());
            *s = match rng.next_u64() % 6 {
                0 => Shape::sphere(x).ok(),
                1 => Shape::capsule(x, y).ok(),
                2 => Shape::cuboid(Vec3::new(x, y, z)).ok(),
                3 => hulls[k].as_ref().map(Shape::hull),
                4 => Shape::triangle(c0, c1, c2).ok(),
                _ => Shape::half_space(Vec3::new(
                    grid(&mut rng, 2, 1.0),
                    grid(&mut rng, 2, 1.0),
                    1.0,
                ))
                .ok(),
            };
        }
        let [Some(a), Some(b)] = shapes else {
            continue;
        };
        let mut pose = || {
            let rotation = match rng.next_u64() % 3 {
                0 => Quat::IDENTITY,
                1 => Quat::from_xyzw(
                    grid(&mut rng, 2, 1.0),
                    grid(&mut rng, 2, 1.0),
                    grid(&mut rng, 2, 1.0),
                    1.0,
                )
                .normalize(),
                _ => rng.rotation(),
            };
            let far = if rng.next_u64().is_multiple_of(10) {
                Vec3::new(300.0, -200.0, 100.0)
            } else {
                Vec3::ZERO
            };
            let unit = if rng.next_u64().is_multiple_of(4) {
                1.0 / 1024.0
            } else {
                1.0 / 16.0
            };
            let p = Vec3::new(
                grid(&mut rng, 16, unit),
                grid(&mut rng, 16, unit),
                grid(&mut rng, 16, unit),
            );
            Iso::new(far + p, rotation)
        };
        let (pa, pb) = (pose(), pose());
        assert_eq!(
            distance_properties(&a, &pa, &b, &pb),
            Ok(()),
            "{a:?} {pa:?} {b:?} {pb:?}"
        );
        assert_eq!(
            penetration_properties(&a, &pa, &b, &pb),
            Ok(()),
            "{a:?} {pa:?} {b:?} {pb:?}"
        );
        checked += 1;
    }
    assert!(checked > 4000, "{checked}");
}

// ---------------------------------------------------------------------------------------
// Concentric and nearly concentric polytopes (EPA regression).
//
// Shared centres put the origin of D = B − A deep inside it, on planes and lines of
// symmetry, so GJK's simplex often has a vertex on an edge of D and several EPA points
// share a face of D. The depth is checked against exact oracles evaluated in f64 on the
// f32 vertices: D is convex, so its penetration depth is min over unit u of
// h_D(u) = max_b u·b − min_a u·a, and every facet normal of D is a face normal of A or B
// or the cross product of an edge of A and an edge of B.
// ---------------------------------------------------------------------------------------

type V64 = [f64; 3];

fn v64(v: Vec3) -> V64 {
    [v.x as f64, v.y as f64, v.z as f64]
}

fn dot64(a: V64, b: V64) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn sub64(a: V64, b: V64) -> V64 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn unit_cross64(a: V64, b: V64) -> Option<V64> {
    let c = [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ];
    let l = dot64(c, c).sqrt();
    // Exactly parallel edges span no facet of D (their sum is an edge): skip them.
    (l > 1e-12).then(|| [c[0] / l, c[1] / l, c[2] / l])
}

/// `h_D(u) = max_b u·b − min_a u·a` for `D = B − A` (f64).
fn h_d(u: V64, va: &[V64], vb: &[V64]) -> f64 {
    let max_b = vb.iter().map(|&b| dot64(u, b)).fold(f64::MIN, f64::max);
    let min_a = va.iter().map(|&a| dot64(u, a)).fold(f64::MAX, f64::min);
    max_b - min_a
}

/// Core penetration depth of two boxes: SAT over the 15 axes (3 face normals of each
/// box, 9 edge cross products), which are all the facet normals of D, both signs. Exact.
fn box_sat_depth(pose_a: &Iso, pose_b: &Iso, va: &[V64], vb: &[V64]) -> f64 {
    let axes = |p: &Iso| [Vec3::X, Vec3::Y, Vec3::Z].map(|e| v64(p.transform_vector(e)));
    let (ea, eb) = (axes(pose_a), axes(pose_b));
    let mut candidates: Vec<V64> = ea.iter().chain(eb.iter()).copied().collect();
    for &a in &ea {
        for &b in &eb {
            candidates.extend(unit_cross64(a, b));
        }
    }
    candidates
        .iter()
        .flat_map(|&u| [u, [-u[0], -u[1], -u[2]]])
        .map(|u| h_d(u, va, vb))
        .fold(f64::MAX, f64::min)
}

/// Core penetration depth of any two convex polytopes from their vertices alone: the
/// candidate directions are the normals of every vertex triple of A and of B (a superset
/// of their face normals) and the cross products of every vertex pair of A with every
/// vertex pair of B (a superset of their edges), both signs. Every unit `u` bounds the
/// depth from above and the facet normals of D are among the candidates, so the minimum
/// is exact.
fn polytope_depth_oracle(va: &[V64], vb: &[V64]) -> f64 {
    let pairs = |v: &[V64]| -> Vec<V64> {
        let mut out = Vec::new();
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                out.push(sub64(v[j], v[i]));
            }
        }
        out
    };
    let triples = |v: &[V64]| -> Vec<V64> {
        let mut out = Vec::new();
        for i in 0..v.len() {
            for j in i + 1..v.len() {
                for k in j + 1..v.len() {
                    out.extend(unit_cross64(sub64(v[j], v[i]), sub64(v[k], v[i])));
                }
            }
        }
        out
    };
    let mut candidates = triples(va);
    candidates.extend(triples(vb));
    let (pa, pb) = (pairs(va), pairs(vb));
    for &a in &pa {
        for &b in &pb {
            candidates.extend(unit_cross64(a, b));
        }
    }
    candidates
        .iter()
        .flat_map(|&u| [u, [-u[0], -u[1], -u[2]]])
        .map(|u| h_d(u, va, vb))
        .fold(f64::MAX, f64::min)
}

/// The world-frame core vertices of a polytope-cored shape, in f64.
fn core64(s: &Shape, pose: &Iso) -> Vec<V64> {
    core_vertices(s, pose)
        .expect("polytope core")
        .points()
        .iter()
        .map(|&p| v64(p))
        .collect()
}

/// Checks EPA on `a` at `pose_a` against `b` at `pose_b`, both orders: the depth equals
/// the oracle's, the normal realises it (`h_D(−normal) + radii` is that depth too) and
/// EPA converged. Returns the larger depth error of the two orders. Tolerance [`TOL`]:
/// EPA stops within 1e-5 of D's extent (about 2 m here, so 2e-5 m); the regression was
/// off by the whole depth, and a thin face trusted on a stall by 1.4e-4 m.
fn check_against_oracle(a: &Shape, pose_a: &Iso, b: &Shape, pose_b: &Iso) -> f64 {
    let both_boxes = matches!((a, b), (Shape::Cuboid(_), Shape::Cuboid(_)));
    let mut worst: f64 = 0.0;
    for (s, ps, t, pt) in [(a, pose_a, b, pose_b), (b, pose_b, a, pose_a)] {
        let (vs, vt) = (core64(s, ps), core64(t, pt));
        let radii = (s.radius() + t.radius()) as f64;
        let core = if both_boxes {
            box_sat_depth(ps, pt, &vs, &vt)
        } else {
            polytope_depth_oracle(&vs, &vt)
        };
        let expected = core + radii;
        let p = penetration(s, ps, t, pt)
            .expect("valid poses")
            .expect("concentric shapes overlap");
        let ctx = || format!("{s:?} {ps:?} {t:?} {pt:?} {p:?} expected {expected}");
        assert_eq!(p.status, EpaStatus::Converged, "{}", ctx());
        let err = (p.depth as f64 - expected).abs();
        assert!(err < TOL as f64, "{}", ctx());
        // The normal n (A to B) is −m for D's direction m: h_D(m) is the depth along it,
        // never below the true depth, and above it by EPA's tolerance at most.
        let m = v64(-p.normal);
        let along = h_d(m, &vs, &vt) + radii;
        assert!(along - expected < TOL as f64, "along {along}: {}", ctx());
        worst = worst.max(err);
    }
    worst
}

/// The rotations of the cube group (products of quarter turns about X, Y and Z, all 24
/// appear among these 64), renormalised as f32 quaternions.
fn quarter_turns() -> Vec<Quat> {
    let quarter = core::f32::consts::FRAC_PI_2;
    let mut out = Vec::new();
    for i in 0..4 {
        for j in 0..4 {
            for k in 0..4 {
                let q = Quat::from_axis_angle(Vec3::X, quarter * i as f32)
                    * Quat::from_axis_angle(Vec3::Y, quarter * j as f32)
                    * Quat::from_axis_angle(Vec3::Z, quarter * k as f32);
                out.push(q.normalize());
            }
        }
    }
    out
}

/// Regression: two unit cubes at one centre, A turned 90° about Z, B 0.01 rad about X,
/// rotations renormalised (what `collide::contact` does). EPA answered a depth of 7e-6
/// with status `Converged`. Root cause: B's tilt puts three polytope vertices on one
/// line of D's boundary (GJK's vertex on an edge of D); the new vertex lay on the plane
/// of a neighbour face, which rounding called "not seen", so the fan made a face of
/// three collinear points whose cross product was rounding noise, a plane through the
/// origin; its support point was already a vertex, which EPA took for convergence.
/// Both overlap by 1 m along X and Y: the SAT depth is 1 (the tilted cube's extent along
/// Y and Z is 0.5 (cos 0.01 + sin 0.01) ≈ 0.505).
#[test]
fn epa_depth_of_concentric_cubes_turned_90_degrees_and_tilted() {
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let pose_a = Iso::new(
        Vec3::ZERO,
        Quat::from_xyzw(0.0, 0.0, 0.707_106_77, 0.707_106_77).normalize(),
    );
    let pose_b = Iso::new(
        Vec3::ZERO,
        Quat::from_xyzw(0.004_999_979, 0.0, 0.0, 0.999_987_5).normalize(),
    );
    for (pa, pb) in [(&pose_a, &pose_b), (&pose_b, &pose_a)] {
        let p = penetration(&cube, pa, &cube, pb).unwrap().unwrap();
        assert_eq!(p.status, EpaStatus::Converged, "{p:?}");
        assert!((p.depth - 1.0).abs() < TOL, "{p:?}");
        let along_x = (p.normal.x.abs() - 1.0).abs() < NORMAL_TOL;
        let along_y = (p.normal.y.abs() - 1.0).abs() < NORMAL_TOL;
        assert!(along_x || along_y, "{p:?}");
    }
    let err = check_against_oracle(&cube, &pose_a, &cube, &pose_b);
    assert!(err < 1e-5, "{err}");
}

/// Concentric and nearly concentric pairs (centre offsets 0 to 0.1 mm) of boxes, hulls
/// and capsule/box under random rotations, exact quarter turns, and quarter turns tilted
/// by 1e-5 to 1e-2 rad: EPA converges to the oracle's depth along a normal that realises
/// it, in both orders.
#[test]
fn epa_depth_of_concentric_and_nearly_concentric_pairs_matches_the_oracle() {
    let mut rng = SplitMix64::new(41);
    let cloud_hulls = random_hulls(42, 3, 0.6).expect("hulls build");
    let corners: Vec<Vec3> = (0..8)
        .map(|i| Shape::cuboid(Vec3::splat(0.5)).unwrap().core_vertex(i))
        .collect();
    let cube_hull = ConvexHull::new(&corners).expect("cube hull");
    let slab_corners: Vec<Vec3> = (0..8)
        .map(|i| {
            Shape::cuboid(Vec3::new(0.7, 0.3, 0.5))
                .unwrap()
                .core_vertex(i)
        })
        .collect();
    let slab_hull = ConvexHull::new(&slab_corners).expect("slab hull");
    let hulls = [
        Shape::hull(&cloud_hulls[0]),
        Shape::hull(&cloud_hulls[1]),
        Shape::hull(&cloud_hulls[2]),
        Shape::hull(&cube_hull),
        Shape::hull(&slab_hull),
    ];
    let boxes = [
        Shape::cuboid(Vec3::splat(0.5)).unwrap(),
        Shape::cuboid(Vec3::new(1.0, 0.6, 0.8)).unwrap(),
        Shape::cuboid(Vec3::new(0.5, 0.9, 0.4)).unwrap(),
        Shape::cuboid(Vec3::new(0.5, 0.5, 0.25)).unwrap(),
    ];
    let capsules = [
        Shape::capsule(0.5, 0.2).unwrap(),
        Shape::capsule(0.3, 0.05).unwrap(),
    ];
    let turns = quarter_turns();
    let axes = [Vec3::X, Vec3::Y, Vec3::Z];
    let tilts = [1e-5f32, 1e-4, 1e-3, 1e-2];
    let mut worst = [0.0f64; 4];
    for k in 0..4000usize {
        let kind = k % 4;
        let (a, b) = match kind {
            0 => (boxes[(k / 4) % 4], boxes[(k / 16) % 4]),
            1 => (hulls[(k / 4) % 5], hulls[(k / 20) % 5]),
            2 => (boxes[(k / 4) % 4], hulls[(k / 16) % 5]),
            _ => (capsules[(k / 4) % 2], boxes[(k / 8) % 4]),
        };
        let rotation = |rng: &mut SplitMix64| -> Quat {
            let pick = |rng: &mut SplitMix64, n: usize| (rng.next_u64() % n as u64) as usize;
            match pick(rng, 3) {
                0 => rng.rotation(),
                1 => turns[pick(rng, turns.len())],
                _ => {
                    let tilt = Quat::from_axis_angle(axes[pick(rng, 3)], tilts[pick(rng, 4)]);
                    (turns[pick(rng, turns.len())] * tilt).normalize()
                }
            }
        };
        let (qa, qb) = (rotation(&mut rng), rotation(&mut rng));
        let centre = if k % 2 == 0 {
            Vec3::ZERO
        } else {
            rng.unit_vector() * rng.range(0.0, 1.0)
        };
        let offset = match (k / 2) % 3 {
            0 => Vec3::ZERO,
            1 => rng.unit_vector() * rng.range(0.0, 1e-4),
            // Along a coordinate axis: keeps the symmetry planes of aligned shapes.
            _ => axes[(k / 6) % 3] * rng.range(0.0, 1e-4),
        };
        let pose_a = Iso::new(centre, qa);
        let pose_b = Iso::new(centre + offset, qb);
        let err = check_against_oracle(&a, &pose_a, &b, &pose_b);
        worst[kind] = worst[kind].max(err);
    }
    eprintln!(
        "max |EPA depth − oracle| (m): box/box {:.1e}, hull/hull {:.1e}, box/hull {:.1e}, \
         capsule/box {:.1e}",
        worst[0], worst[1], worst[2], worst[3]
    );
}

// ---------------------------------------------------------------------------------------
// The one-shot query: `separation`.
// ---------------------------------------------------------------------------------------

fn fresh_separation(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso) -> Separation {
    separation(a, pa, b, pb).expect("valid poses")
}

/// Every pair kind under random poses, apart and overlapping: `separation` gives the
/// numbers of `distance` (apart) and `penetration` (overlapping) to the bit, a unit normal,
/// and witnesses with `point_b − point_a = separation · normal`; swapping A and B gives the
/// same separation, the negated normal and swapped witnesses.
#[test]
fn separation_is_distance_or_minus_depth_and_swaps_with_a_negated_normal() {
    let hulls = random_hulls(23, 2, 0.7).expect("hulls build");
    let shapes = [
        Shape::sphere(0.4).unwrap(),
        Shape::capsule(0.5, 0.2).unwrap(),
        Shape::cuboid(Vec3::new(0.6, 0.3, 0.45)).unwrap(),
        Shape::hull(&hulls[0]),
        Shape::hull(&hulls[1]),
        Shape::triangle(
            Vec3::new(-0.5, 0.0, -0.4),
            Vec3::new(0.6, 0.1, 0.0),
            Vec3::new(0.0, -0.1, 0.7),
        )
        .unwrap(),
        Shape::half_space(Vec3::new(0.1, 1.0, 0.0)).unwrap(),
    ];
    let mut rng = SplitMix64::new(24);
    let (mut apart, mut overlapping, mut worst_swap) = (0, 0, 0.0f32);
    for round in 0..60 {
        for (i, a) in shapes.iter().enumerate() {
            for (j, b) in shapes.iter().enumerate() {
                let reach = if round % 2 == 0 { 0.8 } else { 2.0 };
                let (pa, pb) = (random_pose(&mut rng, reach), random_pose(&mut rng, reach));
                let s = fresh_separation(a, &pa, b, &pb);
                let ctx = || format!("{a:?} {pa:?} {b:?} {pb:?} {s:?}");
                assert!((s.normal.length() - 1.0).abs() < 1e-5, "{}", ctx());
                let both_planes = i == 6 && j == 6;
                if both_planes {
                    assert_eq!(s.status, SeparationStatus::HalfSpaces);
                    assert_eq!(s.separation, 0.0);
                    continue;
                }
                let d = fresh_distance(a, &pa, b, &pb);
                if d.distance > 0.0 {
                    apart += 1;
                    assert_eq!(s.separation, d.distance, "{}", ctx());
                    assert_eq!((s.point_a, s.point_b), (d.point_a, d.point_b), "{}", ctx());
                    if s.separation > TOL {
                        assert_eq!(s.normal, d.normal, "{}", ctx());
                    }
                } else {
                    let p = penetration(a, &pa, b, &pb)
                        .unwrap()
                        .expect("GJK says touching");
                    overlapping += 1;
                    assert_eq!(s.separation, 0.0 - p.depth, "{}", ctx());
                    assert_eq!(s.normal, p.normal, "{}", ctx());
                    assert_eq!((s.point_a, s.point_b), (p.point_a, p.point_b), "{}", ctx());
                }
                if s.status == SeparationStatus::Converged {
                    let along = s.point_b - s.point_a - s.normal * s.separation;
                    assert!(along.length() < 2.0 * TOL, "{}", ctx());
                }
                let w = fresh_separation(b, &pb, a, &pa);
                assert!((w.separation - s.separation).abs() < TOL, "{} {w:?}", ctx());
                // A well-defined normal (not touching cores, where it is a fallback) is
                // negated by the swap.
                let round_core_touch = (s.separation + a.radius() + b.radius()).abs() < TOL;
                if !round_core_touch && s.separation.abs() > TOL {
                    let off = (w.normal + s.normal).length();
                    worst_swap = worst_swap.max(off);
                    assert!(off < NORMAL_TOL, "{} {w:?}", ctx());
                    assert!(
                        (w.point_a - s.point_b).length() < 10.0 * TOL,
                        "{} {w:?}",
                        ctx()
                    );
                    assert!(
                        (w.point_b - s.point_a).length() < 10.0 * TOL,
                        "{} {w:?}",
                        ctx()
                    );
                }
            }
        }
    }
    eprintln!("{apart} apart, {overlapping} overlapping, worst swapped normal {worst_swap:e}");
    assert!(apart > 500 && overlapping > 500, "{apart} {overlapping}");
}

/// Spheres: the separation is `|c_b − c_a| − r_a − r_b` along the line of centres, apart
/// and overlapping; axis-aligned boxes (and boxes sharing one rotation): the exact f64
/// separation of two boxes, `−min_i (h_i − |Δ_i|)` along that axis when they overlap and
/// `|max(|Δ| − h, 0)|` when apart.
#[test]
fn separation_of_spheres_and_boxes_is_analytic() {
    let mut rng = SplitMix64::new(31);
    for _ in 0..2000 {
        let (ra, rb) = (rng.range(0.1, 1.0), rng.range(0.1, 1.0));
        let ca = rng.unit_vector() * rng.range(0.0, 3.0);
        let cb = ca + rng.unit_vector() * rng.range(0.05, 2.5);
        let (pa, pb) = (Iso::new(ca, rng.rotation()), Iso::new(cb, rng.rotation()));
        let s = fresh_separation(
            &Shape::sphere(ra).unwrap(),
            &pa,
            &Shape::sphere(rb).unwrap(),
            &pb,
        );
        let d = v64(cb)
            .iter()
            .zip(v64(ca).iter())
            .map(|(x, y)| (x - y) * (x - y))
            .sum::<f64>()
            .sqrt();
        let expected = d - ra as f64 - rb as f64;
        assert!(
            (s.separation as f64 - expected).abs() < 1e-5,
            "{s:?} {expected}"
        );
        let n = (cb - ca).normalize_or(Vec3::Y);
        assert!((s.normal - n).length() < 1e-5, "{s:?} {n:?}");
        assert!((s.point_a - (ca + n * ra)).length() < 1e-5, "{s:?}");
        assert!((s.point_b - (cb - n * rb)).length() < 1e-5, "{s:?}");
    }
    let (mut apart, mut overlapping) = (0, 0);
    for k in 0..2000 {
        let ha = Vec3::new(
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
        );
        let hb = Vec3::new(
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
        );
        let shared = if k % 2 == 0 {
            Quat::IDENTITY
        } else {
            rng.rotation()
        };
        let ca = rng.unit_vector() * rng.range(0.0, 2.0);
        let delta_local = Vec3::new(
            rng.range(-1.6, 1.6),
            rng.range(-1.6, 1.6),
            rng.range(-1.6, 1.6),
        );
        let pa = Iso::new(ca, shared);
        let pb = Iso::new(ca + shared.rotate(delta_local), shared);
        let s = fresh_separation(
            &Shape::cuboid(ha).unwrap(),
            &pa,
            &Shape::cuboid(hb).unwrap(),
            &pb,
        );
        // The exact answer in the shared frame, from the f32 poses (f64).
        let dl = pa.inverse_transform_point(pb.position);
        let dl = v64(dl);
        let h = [0usize, 1, 2].map(|i| v64(ha)[i] + v64(hb)[i]);
        let gaps = [0usize, 1, 2].map(|i| dl[i].abs() - h[i]);
        let (expected, axis) = if gaps.iter().all(|g| *g < 0.0) {
            overlapping += 1;
            let (i, g) = gaps
                .iter()
                .enumerate()
                .max_by(|x, y| x.1.total_cmp(y.1))
                .unwrap();
            (*g, Some(i))
        } else {
            apart += 1;
            (
                gaps.iter().map(|g| g.max(0.0).powi(2)).sum::<f64>().sqrt(),
                None,
            )
        };
        let ctx = || format!("{ha:?} {hb:?} {pa:?} {pb:?} {s:?} expected {expected}");
        // 1e-5 of a few metres: EPA's tolerance (overlap), GJK's rounding (apart).
        assert!((s.separation as f64 - expected).abs() < 3e-5, "{}", ctx());
        if let Some(i) = axis {
            // The second-deepest axis must be clearly worse for the normal to be unique.
            let mut sorted = gaps;
            sorted.sort_by(|x, y| y.total_cmp(x));
            if sorted[0] - sorted[1] > 1e-3 {
                let mut n = [0.0f32; 3];
                n[i] = dl[i].signum() as f32;
                let n = shared.rotate(Vec3::new(n[0], n[1], n[2]));
                assert!((s.normal - n).length() < NORMAL_TOL, "{}", ctx());
            }
        }
    }
    assert!(apart > 300 && overlapping > 300, "{apart} {overlapping}");
}

#[test]
fn separation_refuses_exactly_what_the_other_queries_refuse() {
    let s = Shape::sphere(1.0).unwrap();
    let bad = [
        (
            Iso::from_position(Vec3::new(f32::NAN, 0.0, 0.0)),
            carom::Error::NonFinite(carom::Input::Position),
        ),
        (
            Iso::from_position(Vec3::new(0.0, f32::INFINITY, 0.0)),
            carom::Error::NonFinite(carom::Input::Position),
        ),
        (
            Iso::from_position(Vec3::new(0.0, 0.0, 2.0 * carom::MAX_COORDINATE)),
            carom::Error::OutOfRange(carom::Input::Position),
        ),
        (
            Iso::new(Vec3::ZERO, Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
            carom::Error::NotUnit(carom::Input::Rotation),
        ),
        (
            Iso::new(Vec3::ZERO, Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0)),
            carom::Error::NonFinite(carom::Input::Rotation),
        ),
    ];
    for (p, e) in bad {
        assert_eq!(separation(&s, &p, &s, &Iso::IDENTITY), Err(e), "{p:?}");
        assert_eq!(separation(&s, &Iso::IDENTITY, &s, &p), Err(e), "{p:?}");
        let d = distance(&s, &p, &s, &Iso::IDENTITY, &mut SimplexCache::default());
        assert_eq!(d.map(|_| ()), Err(e), "{p:?}");
    }
}
