//! Contact manifolds against analytic answers, feature-id stability, symmetry, margins, and
//! the manifold properties over random pairs of every shape kind.

use carom::collide::{contact, segment_closest_points, ContactId, Manifold};
use carom::math::{Iso, Quat, Vec3};
use carom::props::manifold_properties;
use carom::rng::SplitMix64;
use carom::shape::{ConvexHull, FeatureId, Shape};

/// Closed forms are exact up to `f32` rounding of a few transforms on coordinates of a few
/// metres: 1e-5 m.
const EXACT: f32 = 1.0e-5;

/// GJK/EPA answers (and anything derived from them) stop at their relative tolerance on
/// shapes of about 1 m: 1e-3 m.
const ITERATIVE: f32 = 1.0e-3;

fn contact_of(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso, margin: f32) -> Option<Manifold> {
    contact(a, pa, b, pb, margin).expect("valid input")
}

fn random_pose(rng: &mut SplitMix64, spread: f32) -> Iso {
    Iso::new(
        Vec3::new(
            rng.range(-spread, spread),
            rng.range(-spread, spread),
            rng.range(-spread, spread),
        ),
        rng.rotation(),
    )
}

fn close(a: Vec3, b: Vec3, tol: f32) -> bool {
    (a - b).length() <= tol
}

/// Sorted ids, to compare manifolds whatever their point order.
fn ids(m: &Manifold) -> Vec<ContactId> {
    let mut v: Vec<ContactId> = m.points().iter().map(|p| p.id).collect();
    v.sort();
    v
}

#[test]
fn sphere_sphere_matches_the_centre_line() {
    let mut rng = SplitMix64::new(1);
    let mut hits = 0;
    for _ in 0..2000 {
        let (ra, rb) = (rng.range(0.1, 1.0), rng.range(0.1, 1.0));
        let (a, b) = (Shape::sphere(ra).unwrap(), Shape::sphere(rb).unwrap());
        let pa = random_pose(&mut rng, 1.0);
        let pb = random_pose(&mut rng, 1.0);
        let margin = 0.05;
        let d = pb.position - pa.position;
        let expected = d.length() - ra - rb;
        match contact_of(&a, &pa, &b, &pb, margin) {
            None => assert!(expected > margin - EXACT, "missed {expected}"),
            Some(m) => {
                hits += 1;
                let n = d.normalize_or(Vec3::Y);
                assert_eq!(m.len, 1);
                assert!(close(m.normal, n, EXACT));
                let p = m.points[0];
                assert!((p.separation - expected).abs() < EXACT);
                assert!(close(p.point_a, pa.position + n * ra, EXACT));
                assert!(close(p.point_b, pb.position - n * rb, EXACT));
            }
        }
    }
    assert!(hits > 200, "too few contacts to mean anything: {hits}");
}

/// Concentric spheres have no contact direction of their own: the pair runs in its
/// canonical order (the smaller sphere first) and pushes along world +Y from there, so the
/// larger sphere is pushed up whichever order the caller gives, and `contact(b, a)` is
/// `contact(a, b)` reversed.
#[test]
fn concentric_spheres_push_the_larger_along_world_up() {
    let big = Shape::sphere(1.0).unwrap();
    let small = Shape::sphere(0.5).unwrap();
    let rot = Quat::from_axis_angle(Vec3::new(1.0, 2.0, 3.0), 0.7);
    let pose = Iso::new(Vec3::new(1.0, 2.0, 3.0), rot);
    let m = contact_of(&small, &pose, &big, &pose, 0.0).unwrap();
    assert!(close(m.normal, Vec3::Y, EXACT));
    assert!((m.points[0].separation + 1.5).abs() < EXACT);
    let w = contact_of(&big, &pose, &small, &pose, 0.0).unwrap();
    assert_eq!(w.normal, -m.normal);
    assert_eq!(w.points[0].separation, m.points[0].separation);
}

/// Closest point of the box `|x| <= h` to `p` (box frame).
fn closest_on_box(h: Vec3, p: Vec3) -> Vec3 {
    Vec3::new(
        p.x.clamp(-h.x, h.x),
        p.y.clamp(-h.y, h.y),
        p.z.clamp(-h.z, h.z),
    )
}

/// Signed distance of `p` to the box `|x| <= h` (box frame): negative inside.
fn box_signed_distance(h: Vec3, p: Vec3) -> f32 {
    let q = closest_on_box(h, p);
    if q == p {
        let inside = h - p.abs();
        -inside.min_elem()
    } else {
        (p - q).length()
    }
}

#[test]
fn sphere_box_matches_the_point_box_distance() {
    let mut rng = SplitMix64::new(2);
    let mut hits = 0;
    for _ in 0..2000 {
        let h = Vec3::new(
            rng.range(0.2, 1.0),
            rng.range(0.2, 1.0),
            rng.range(0.2, 1.0),
        );
        let r = rng.range(0.1, 0.8);
        let (cube, ball) = (Shape::cuboid(h).unwrap(), Shape::sphere(r).unwrap());
        let pose_box = random_pose(&mut rng, 0.5);
        let pose_ball = random_pose(&mut rng, 1.5);
        let margin = 0.05;
        let centre = pose_box.inverse_transform_point(pose_ball.position);
        let expected = box_signed_distance(h, centre) - r;
        let m = contact_of(&cube, &pose_box, &ball, &pose_ball, margin);
        let Some(m) = m else {
            assert!(expected > margin - ITERATIVE, "missed {expected}");
            continue;
        };
        hits += 1;
        assert_eq!(m.len, 1);
        assert!(
            (m.points[0].separation - expected).abs() < ITERATIVE,
            "{} vs {expected}",
            m.points[0].separation
        );
        // Separated: the point on the box is the closest point to the centre.
        if box_signed_distance(h, centre) > 0.01 {
            let on_box = pose_box.transform_point(closest_on_box(h, centre));
            assert!(close(m.points[0].point_a, on_box, ITERATIVE));
        }
        // The swapped order gives the mirrored manifold.
        let w = contact_of(&ball, &pose_ball, &cube, &pose_box, margin).unwrap();
        assert!(close(w.normal, -m.normal, EXACT));
        assert!((w.points[0].separation - m.points[0].separation).abs() < EXACT);
        assert_eq!(w.points[0].id.a, m.points[0].id.b);
    }
    assert!(hits > 200, "too few contacts: {hits}");
}

#[test]
fn capsule_capsule_matches_segment_distance() {
    let mut rng = SplitMix64::new(3);
    let mut hits = 0;
    for _ in 0..2000 {
        let (ha, ra) = (rng.range(0.1, 1.0), rng.range(0.1, 0.5));
        let (hb, rb) = (rng.range(0.1, 1.0), rng.range(0.1, 0.5));
        let a = Shape::capsule(ha, ra).unwrap();
        let b = Shape::capsule(hb, rb).unwrap();
        let pa = random_pose(&mut rng, 1.0);
        let pb = random_pose(&mut rng, 1.0);
        let seg = |p: &Iso, h: f32| {
            (
                p.transform_point(Vec3::new(0.0, -h, 0.0)),
                p.transform_point(Vec3::new(0.0, h, 0.0)),
            )
        };
        let (p1, q1) = seg(&pa, ha);
        let (p2, q2) = seg(&pb, hb);
        let (s, t) = segment_closest_points(p1, q1, p2, q2);
        let c1 = p1 + (q1 - p1) * s;
        let c2 = p2 + (q2 - p2) * t;
        let expected = (c2 - c1).length() - ra - rb;
        let margin = 0.05;
        let Some(m) = contact_of(&a, &pa, &b, &pb, margin) else {
            assert!(expected > margin - EXACT, "missed {expected}");
            continue;
        };
        hits += 1;
        assert!((m.min_separation() - expected).abs() < 1.0e-4);
        if expected > -ra - rb + 0.01 {
            assert!(close(m.normal, (c2 - c1).normalize_or(Vec3::Y), 1.0e-4));
        }
    }
    assert!(hits > 200, "too few contacts: {hits}");
}

#[test]
fn parallel_capsules_touch_along_their_overlap() {
    // Two horizontal capsules along X, B shifted by 0.5 along X and resting on A.
    let a = Shape::capsule(1.0, 0.25).unwrap();
    let b = Shape::capsule(1.0, 0.25).unwrap();
    let along_x = Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_2);
    let pa = Iso::new(Vec3::ZERO, along_x);
    let pb = Iso::new(Vec3::new(0.5, 0.49, 0.0), along_x);
    let m = contact_of(&a, &pa, &b, &pb, 0.02).unwrap();
    assert_eq!(m.len, 2);
    assert!(close(m.normal, Vec3::Y, EXACT));
    let mut xs: Vec<f32> = m.points().iter().map(|p| p.point_a.x).collect();
    xs.sort_by(f32::total_cmp);
    // Overlap of [-1, 1] and [-0.5, 1.5]: x from -0.5 to 1.
    assert!(
        (xs[0] + 0.5).abs() < EXACT && (xs[1] - 1.0).abs() < EXACT,
        "{xs:?}"
    );
    for p in m.points() {
        assert!((p.separation + 0.01).abs() < EXACT);
    }
}

#[test]
fn capsule_box_matches_sampled_segment_distance() {
    let mut rng = SplitMix64::new(4);
    let mut hits = 0;
    for _ in 0..1000 {
        let h = Vec3::new(
            rng.range(0.3, 1.0),
            rng.range(0.3, 1.0),
            rng.range(0.3, 1.0),
        );
        let (hh, r) = (rng.range(0.1, 0.8), rng.range(0.1, 0.4));
        let cube = Shape::cuboid(h).unwrap();
        let cap = Shape::capsule(hh, r).unwrap();
        let pose_box = random_pose(&mut rng, 0.3);
        let pose_cap = random_pose(&mut rng, 1.6);
        // Brute force over 2001 points of the segment, separated cases only (inside the
        // box the sampled distance is not the depth).
        let mut best = f32::INFINITY;
        for i in 0..=2000 {
            let y = -hh + 2.0 * hh * i as f32 / 2000.0;
            let p = pose_cap.transform_point(Vec3::new(0.0, y, 0.0));
            best = best.min(box_signed_distance(h, pose_box.inverse_transform_point(p)));
        }
        if best <= 0.0 {
            continue;
        }
        let expected = best - r;
        let margin = 0.05;
        let Some(m) = contact_of(&cap, &pose_cap, &cube, &pose_box, margin) else {
            assert!(expected > margin - ITERATIVE, "missed {expected}");
            continue;
        };
        hits += 1;
        // Sampling step 2 hh / 2000 <= 8e-4 m bounds the brute-force error.
        assert!(
            (m.min_separation() - expected).abs() < ITERATIVE + 1.0e-3,
            "{} vs {expected}",
            m.min_separation()
        );
    }
    assert!(hits > 100, "too few contacts: {hits}");
}

#[test]
fn capsule_lying_on_a_box_gives_two_points() {
    let cube = Shape::cuboid(Vec3::new(2.0, 0.5, 2.0)).unwrap();
    let cap = Shape::capsule(0.5, 0.2).unwrap();
    let pose_box = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
    for angle in [0.0f32, 0.3, 1.2] {
        // Lying along X, turned about Y, 1 cm deep.
        let lying = Quat::from_axis_angle(Vec3::Y, angle)
            * Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_2);
        let pose_cap = Iso::new(Vec3::new(0.1, 0.19, 0.2), lying);
        let m = contact_of(&cap, &pose_cap, &cube, &pose_box, 0.02).unwrap();
        assert_eq!(m.len, 2);
        assert!(close(m.normal, -Vec3::Y, EXACT));
        let ends = [
            pose_cap.transform_point(Vec3::new(0.0, -0.5, 0.0)),
            pose_cap.transform_point(Vec3::new(0.0, 0.5, 0.0)),
        ];
        for p in m.points() {
            assert!((p.separation + 0.01).abs() < 1.0e-4);
            assert!(p.point_b.y.abs() < 1.0e-4, "on the box top");
            let under = ends
                .iter()
                .any(|e| (e.x - p.point_b.x).abs() < 1e-4 && (e.z - p.point_b.z).abs() < 1e-4);
            assert!(under, "point under an end of the segment");
        }
    }
}

#[test]
fn half_space_pairs_match_vertex_heights() {
    let mut rng = SplitMix64::new(5);
    let hull_points: Vec<Vec3> = (0..20).map(|_| rng.unit_vector() * 0.7).collect();
    let hull = ConvexHull::new(&hull_points).ok();
    let tri = Shape::triangle(
        Vec3::new(-0.5, 0.0, -0.3),
        Vec3::new(0.6, 0.1, -0.2),
        Vec3::new(0.0, -0.1, 0.7),
    )
    .unwrap();
    let mut shapes = vec![
        Shape::sphere(0.4).unwrap(),
        Shape::capsule(0.5, 0.2).unwrap(),
        Shape::cuboid(Vec3::new(0.3, 0.5, 0.7)).unwrap(),
        tri,
    ];
    if let Some(h) = &hull {
        shapes.push(Shape::hull(h));
    }
    let plane_normal = Vec3::new(0.3, 1.0, -0.2).normalize_or(Vec3::Y);
    let ground = Shape::half_space(plane_normal).unwrap();
    let mut hits = 0;
    for _ in 0..500 {
        let pose_ground = random_pose(&mut rng, 0.5);
        let n = pose_ground.transform_vector(plane_normal);
        for s in &shapes {
            let pose = Iso::new(
                pose_ground.position + n * rng.range(-0.5, 1.2) + n.any_perpendicular() * 0.3,
                rng.rotation(),
            );
            let margin = 0.05;
            // Heights of the core vertices, minus the radius.
            let heights: Vec<f32> = core_vertices(s)
                .iter()
                .map(|v| n.dot(pose.transform_point(*v) - pose_ground.position) - s.radius())
                .collect();
            let lowest = heights.iter().copied().fold(f32::INFINITY, f32::min);
            let within = heights.iter().filter(|h| **h <= margin).count();
            let m = contact_of(&ground, &pose_ground, s, &pose, margin);
            let Some(m) = m else {
                assert!(lowest > margin, "missed {lowest}");
                continue;
            };
            hits += 1;
            assert!(close(m.normal, n, EXACT));
            let count = m.len as usize;
            if within <= 4 || matches!(s, Shape::Cuboid(_)) {
                assert_eq!(count, within.min(4), "{heights:?} {m:?}");
            } else {
                // A hull's 4th point is dropped when it lies inside the other three's
                // triangle (it adds no area).
                assert!(count == 3 || count == 4, "{heights:?} {m:?}");
            }
            assert!((m.min_separation() - lowest).abs() < EXACT);
            for p in m.points() {
                assert!(
                    n.dot(p.point_a - pose_ground.position).abs() < EXACT,
                    "on plane"
                );
                let h = heights[p.id.b.index() as usize];
                assert!((p.separation - h).abs() < EXACT, "id names the vertex");
            }
            // Swapped: the mirrored manifold.
            let w = contact_of(s, &pose, &ground, &pose_ground, margin).unwrap();
            assert!(close(w.normal, -n, EXACT));
            assert_eq!(w.len, m.len, "{s:?} {m:?} {w:?}");
        }
    }
    assert!(hits > 500, "too few contacts: {hits}");
    let two = Shape::half_space(Vec3::Y).unwrap();
    assert!(contact_of(&ground, &Iso::IDENTITY, &two, &Iso::IDENTITY, 1.0).is_none());
}

/// Core vertices of a shape, indexed as its vertex feature ids.
fn core_vertices(s: &Shape) -> Vec<Vec3> {
    match s {
        Shape::Sphere(_) => vec![Vec3::ZERO],
        Shape::Capsule(c) => {
            let (a, b) = c.segment();
            vec![a, b]
        }
        Shape::Cuboid(_) => (0..8).map(|i| s.core_vertex(i)).collect(),
        Shape::Hull(h) => h.vertices().to_vec(),
        Shape::Triangle(t) => t.vertices.to_vec(),
        Shape::HalfSpace(_) | Shape::Mesh(_) | Shape::HeightField(_) | Shape::Compound(_) => {
            vec![]
        }
    }
}

/// A 1×1×1 box (half 0.5) resting `depth` deep on a ground box whose top is y = 0, turned
/// by `yaw` about Y.
fn box_on_ground(yaw: f32, depth: f32, shift: Vec3) -> (Shape<'static>, Iso, Shape<'static>, Iso) {
    let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap();
    let pose_ground = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let pose_box = Iso::new(
        Vec3::new(0.0, 0.5 - depth, 0.0) + shift,
        Quat::from_axis_angle(Vec3::Y, yaw),
    );
    (ground, pose_ground, cube, pose_box)
}

#[test]
fn box_resting_flat_gives_four_points_at_the_corners() {
    for yaw in [0.0f32, 0.4, 1.0, 2.5] {
        for depth in [0.01f32, 0.05] {
            let (ground, pg, cube, pb) = box_on_ground(yaw, depth, Vec3::new(0.3, 0.0, -0.2));
            let m = contact_of(&ground, &pg, &cube, &pb, 0.02).unwrap();
            assert_eq!(m.len, 4, "yaw {yaw}");
            assert!(close(m.normal, Vec3::Y, EXACT));
            let mut corners: Vec<Vec3> = (0..4)
                .map(|i| {
                    let x = if i & 1 == 0 { -0.5 } else { 0.5 };
                    let z = if i & 2 == 0 { -0.5 } else { 0.5 };
                    pb.transform_point(Vec3::new(x, -0.5, z))
                })
                .collect();
            for p in m.points() {
                assert!((p.separation + depth).abs() < ITERATIVE);
                assert!(p.point_a.y.abs() < EXACT, "point_a on the ground's top");
                let k = corners
                    .iter()
                    .position(|c| close(*c, p.point_b, ITERATIVE))
                    .expect("point_b at a bottom corner");
                corners.remove(k);
            }
        }
    }
}

#[test]
fn lib_doctest_scene_gives_four_points_both_ways() {
    let (ground, pg, cube, pb) = box_on_ground(0.0, 0.01, Vec3::ZERO);
    let m = contact_of(&ground, &pg, &cube, &pb, 0.02).unwrap();
    let w = contact_of(&cube, &pb, &ground, &pg, 0.02).unwrap();
    assert_eq!(m.len, 4);
    assert_eq!(w.len, 4);
    assert!(close(w.normal, -m.normal, EXACT));
    for p in w.points() {
        assert!((p.separation + 0.01).abs() < ITERATIVE);
    }
}

#[test]
fn box_edge_on_a_face_gives_two_points() {
    // Turned 30° about Z: the bottom edge along Z touches, 1 cm deep.
    let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap();
    let pg = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let rot = Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_6);
    let lowest = (0..8)
        .map(|i| rot.rotate(cube.core_vertex(i)).y)
        .fold(f32::INFINITY, f32::min);
    let pb = Iso::new(Vec3::new(0.0, -lowest - 0.01, 0.0), rot);
    for (a, pa, b, pbb) in [(&ground, &pg, &cube, &pb), (&cube, &pb, &ground, &pg)] {
        let m = contact_of(a, pa, b, pbb, 0.02).unwrap();
        assert_eq!(m.len, 2);
        for p in m.points() {
            assert!((p.separation + 0.01).abs() < ITERATIVE);
        }
        let d = m.points[0].point_a - m.points[1].point_a;
        assert!((d.length() - 1.0).abs() < ITERATIVE, "the whole edge");
    }
}

#[test]
fn box_vertex_on_a_face_gives_one_point() {
    let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap();
    let pg = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    // Tip the box so the diagonal (-1,-1,-1) points down.
    let rot = Quat::from_axis_angle(Vec3::new(1.0, 0.0, -1.0), 0.9553);
    let lowest = (0..8)
        .map(|i| rot.rotate(cube.core_vertex(i)).y)
        .fold(f32::INFINITY, f32::min);
    let pb = Iso::new(Vec3::new(0.2, -lowest - 0.01, 0.1), rot);
    let m = contact_of(&ground, &pg, &cube, &pb, 0.02).unwrap();
    assert_eq!(m.len, 1);
    assert!(close(m.normal, Vec3::Y, EXACT));
    assert!((m.points[0].separation + 0.01).abs() < ITERATIVE);
    let lowest_vertex = (0..8u32)
        .min_by(|i, j| {
            rot.rotate(cube.core_vertex(*i))
                .y
                .total_cmp(&rot.rotate(cube.core_vertex(*j)).y)
        })
        .unwrap();
    assert_eq!(m.points[0].id.b, FeatureId::vertex(lowest_vertex));
}

#[test]
fn feature_ids_survive_a_millimetre_of_motion() {
    let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap();
    let pg = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let poses = [
        // Flat, turned about Y.
        Iso::new(
            Vec3::new(0.0, 0.49, 0.0),
            Quat::from_axis_angle(Vec3::Y, 0.3),
        ),
        // On an edge.
        Iso::new(
            Vec3::new(0.0, 0.5 * 2f32.sqrt() - 0.01, 0.0),
            Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_4),
        ),
        // Overhanging the ground's edge: clipped points.
        Iso::new(
            Vec3::new(4.8, 0.49, 1.0),
            Quat::from_axis_angle(Vec3::Y, 0.2),
        ),
    ];
    for pose in poses {
        let m0 = contact_of(&ground, &pg, &cube, &pose, 0.02).unwrap();
        let w0 = contact_of(&cube, &pose, &ground, &pg, 0.02).unwrap();
        for shift in [Vec3::X, Vec3::Z, -Vec3::X, Vec3::Y * 0.5] {
            let moved = Iso::new(pose.position + shift * 0.001, pose.rotation);
            let m1 = contact_of(&ground, &pg, &cube, &moved, 0.02).unwrap();
            assert_eq!(ids(&m0), ids(&m1), "pose {pose:?} shift {shift:?}");
            let w1 = contact_of(&cube, &moved, &ground, &pg, 0.02).unwrap();
            assert_eq!(ids(&w0), ids(&w1), "swapped, pose {pose:?} shift {shift:?}");
        }
    }
}

#[test]
fn speculative_margin_keeps_near_points_and_drops_far_ones() {
    let (ground, pg, cube, pb) = box_on_ground(0.2, -0.01, Vec3::ZERO);
    let m = contact_of(&ground, &pg, &cube, &pb, 0.02).unwrap();
    assert_eq!(m.len, 4);
    for p in m.points() {
        // GJK distance of a 1 cm gap, to its tolerance.
        assert!((p.separation - 0.01).abs() < ITERATIVE);
    }
    assert!(contact_of(&ground, &pg, &cube, &pb, 0.005).is_none());
}

#[test]
fn swapped_pairs_mirror_each_other() {
    let mut rng = SplitMix64::new(6);
    let shapes = [
        Shape::sphere(0.5).unwrap(),
        Shape::capsule(0.4, 0.3).unwrap(),
        Shape::cuboid(Vec3::new(0.4, 0.6, 0.5)).unwrap(),
    ];
    let mut compared = 0;
    for _ in 0..300 {
        for a in &shapes {
            for b in &shapes {
                let pa = random_pose(&mut rng, 0.6);
                let pb = random_pose(&mut rng, 0.6);
                let m = contact_of(a, &pa, b, &pb, 0.02);
                let w = contact_of(b, &pb, a, &pa, 0.02);
                let (Some(m), Some(w)) = (m, w) else { continue };
                compared += 1;
                assert!(
                    (m.min_separation() - w.min_separation()).abs() < ITERATIVE,
                    "{a:?} {b:?}"
                );
                assert!(m.normal.dot(w.normal) < -0.6);
            }
        }
    }
    assert!(compared > 500, "too few contacts: {compared}");
}

/// A random shape of kind `k` (0 sphere, 1 capsule, 2 box, 3 hull, 4 half-space,
/// 5 triangle); `hull` is used for kind 3 when it could be built.
fn random_shape<'h>(rng: &mut SplitMix64, k: u32, hull: Option<&'h ConvexHull>) -> Shape<'h> {
    let s = |rng: &mut SplitMix64| rng.range(0.05, 1.0);
    match k {
        0 => Shape::sphere(s(rng)).unwrap(),
        1 => Shape::capsule(s(rng), s(rng) * 0.5).unwrap(),
        3 if hull.is_some() => Shape::hull(hull.unwrap()),
        4 => Shape::half_space(rng.unit_vector()).unwrap(),
        5 => Shape::triangle(
            rng.unit_vector() * s(rng),
            rng.unit_vector() * s(rng),
            rng.unit_vector() * s(rng),
        )
        .unwrap_or(Shape::cuboid(Vec3::splat(0.3)).unwrap()),
        _ => Shape::cuboid(Vec3::new(s(rng), s(rng), s(rng))).unwrap(),
    }
}

#[test]
fn properties_hold_for_random_pairs_of_every_kind() {
    let mut rng = SplitMix64::new(7);
    let hulls: Vec<ConvexHull> = (0..8)
        .filter_map(|_| {
            let n = 4 + (rng.next_u64() % 30) as usize;
            let scale = rng.range(0.1, 1.0);
            let pts: Vec<Vec3> = (0..n).map(|_| rng.unit_vector() * scale).collect();
            ConvexHull::new(&pts).ok()
        })
        .collect();
    let mut failures = Vec::new();
    let mut found = 0;
    for i in 0..3000u32 {
        let hull = hulls.get(i as usize % hulls.len().max(1));
        let a = random_shape(&mut rng, i % 6, hull);
        let b = random_shape(&mut rng, (i / 6) % 6, hull);
        let pa = random_pose(&mut rng, 0.8);
        let pb = random_pose(&mut rng, 0.8);
        let margin = rng.range(0.0, 0.05);
        if let Ok(Some(_)) = contact(&a, &pa, &b, &pb, margin) {
            found += 1;
        }
        if let Err(v) = manifold_properties(&a, &pa, &b, &pb, margin) {
            failures.push((i, v, a, pa, b, pb, margin));
        }
    }
    assert!(
        failures.is_empty(),
        "{} failures, first: {:?}",
        failures.len(),
        failures.first()
    );
    assert!(found > 1000, "too few contacts: {found}");
    if hulls.is_empty() {
        eprintln!("note: ConvexHull::new failed; hull pairs ran as boxes");
    }
}

#[test]
fn degenerate_inputs_give_no_nan() {
    // Sizes outside the documented range are refused; the extremes of the range work.
    use carom::shape::{MAX_SIZE, MIN_SIZE};
    use carom::{Error, Input};
    assert_eq!(
        Shape::cuboid(Vec3::splat(1.0e-6)),
        Err(Error::OutOfRange(Input::HalfExtents))
    );
    assert_eq!(Shape::sphere(1.0e6), Err(Error::OutOfRange(Input::Radius)));
    assert_eq!(
        Shape::capsule(MIN_SIZE * 0.5, 1.0),
        Err(Error::OutOfRange(Input::HalfHeight))
    );
    let tiny = Shape::cuboid(Vec3::splat(MIN_SIZE)).unwrap();
    let huge = Shape::cuboid(Vec3::splat(MAX_SIZE)).unwrap();
    let ball = Shape::sphere(1.0).unwrap();
    let cap = Shape::capsule(1.0, 0.5).unwrap();
    let flat = Shape::triangle(Vec3::ZERO, Vec3::X, Vec3::new(0.0, 0.0, 1.0e-5)).unwrap();
    let shapes = [tiny, huge, ball, cap, flat];
    let poses = [
        Iso::IDENTITY,
        Iso::from_position(Vec3::new(0.0, 1.0e-7, 0.0)),
        Iso::new(
            Vec3::new(1.0e4, 0.0, 0.0),
            Quat::from_axis_angle(Vec3::X, 1.0),
        ),
    ];
    for a in &shapes {
        for b in &shapes {
            for pa in &poses {
                for pb in &poses {
                    if let Some(m) = contact_of(a, pa, b, pb, 0.01) {
                        assert!(m.normal.is_finite());
                        assert!((m.normal.length() - 1.0).abs() < 1e-4);
                        assert!(m.len >= 1 && m.len <= 4);
                        for p in m.points() {
                            assert!(p.point_a.is_finite() && p.point_b.is_finite());
                            assert!(p.separation.is_finite() && p.separation <= 0.01);
                        }
                    }
                }
            }
        }
    }
}

#[test]
fn bad_input_is_refused() {
    let ball = Shape::sphere(1.0).unwrap();
    let bad = Iso::from_position(Vec3::new(f32::NAN, 0.0, 0.0));
    assert!(contact(&ball, &bad, &ball, &Iso::IDENTITY, 0.0).is_err());
    assert!(contact(&ball, &Iso::IDENTITY, &ball, &Iso::IDENTITY, -1.0).is_err());
    assert!(contact(&ball, &Iso::IDENTITY, &ball, &Iso::IDENTITY, f32::INFINITY).is_err());
}

#[test]
fn properties_hold_for_aligned_and_resting_pairs() {
    // Exactly aligned faces, exact touching (dy = 1), coplanar sides, near-parallel tilts
    // (0.01 rad) and shared centres: the degenerate cases random poses never hit.
    let mut rng = SplitMix64::new(8);
    let pts: Vec<Vec3> = (0..24).map(|_| rng.unit_vector() * 0.6).collect();
    let corners: Vec<Vec3> = (0..8)
        .map(|i| Shape::cuboid(Vec3::splat(0.5)).unwrap().core_vertex(i))
        .collect();
    let hulls: Vec<ConvexHull> = [pts, corners]
        .iter()
        .filter_map(|p| ConvexHull::new(p).ok())
        .collect();
    let mut shapes = vec![
        Shape::sphere(0.5).unwrap(),
        Shape::capsule(0.5, 0.25).unwrap(),
        Shape::cuboid(Vec3::splat(0.5)).unwrap(),
        Shape::cuboid(Vec3::new(2.0, 0.5, 2.0)).unwrap(),
        Shape::half_space(Vec3::Y).unwrap(),
        Shape::triangle(
            Vec3::new(-1.0, 0.5, -1.0),
            Vec3::new(1.0, 0.5, -1.0),
            Vec3::new(0.0, 0.5, 1.0),
        )
        .unwrap(),
    ];
    shapes.extend(hulls.iter().map(Shape::hull));
    let turns = [
        Quat::IDENTITY,
        Quat::from_axis_angle(Vec3::X, core::f32::consts::FRAC_PI_2),
        Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_2),
        Quat::from_axis_angle(Vec3::Y, 0.3),
        Quat::from_axis_angle(Vec3::X, 0.01),
    ];
    let mut failures = Vec::new();
    let mut checked = 0;
    for a in &shapes {
        for b in &shapes {
            for qa in &turns {
                for qb in &turns {
                    for dy in [0.0f32, 0.25, 0.5, 0.75, 0.99, 1.0, 1.01] {
                        for dx in [0.0f32, 0.5, 1.0, 2.5] {
                            let pa = Iso::new(Vec3::ZERO, *qa);
                            let pb = Iso::new(Vec3::new(dx, dy, 0.0), *qb);
                            checked += 1;
                            if let Err(v) = manifold_properties(a, &pa, b, &pb, 0.02) {
                                failures.push((v, *a, pa, *b, pb));
                            }
                        }
                    }
                }
            }
        }
    }
    assert!(
        failures.is_empty(),
        "{} of {checked} failed, first: {:?}",
        failures.len(),
        failures.first()
    );
}

/// Regression found by `properties_hold_for_aligned_and_resting_pairs`: two unit cubes at
/// one centre, one turned 90° about Z, the other 0.01 rad about X, overlap by 1 m along
/// X, but EPA (in B's order, with renormalised rotations) reports a depth of 7e-6 with
/// status `Converged`, so the manifold says "touching".
#[test]
fn epa_depth_of_concentric_cubes() {
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let pa = Iso::new(
        Vec3::ZERO,
        Quat::from_xyzw(0.0, 0.0, 0.707_106_77, 0.707_106_77),
    );
    let pb = Iso::new(
        Vec3::ZERO,
        Quat::from_xyzw(0.004_999_979, 0.0, 0.0, 0.999_987_5),
    );
    for (p, q) in [(&pa, &pb), (&pb, &pa)] {
        let m = contact_of(&cube, p, &cube, q, 0.02).unwrap();
        // Depth 1 m along X or Y (both are 1 m deep to within 0.5·(1 − cos 0.01)).
        assert!((m.min_separation() + 1.0).abs() < ITERATIVE, "{m:?}");
    }
}

// ---------------------------------------------------------------------------------------
// Honest, symmetric manifolds on the benchmark query sets.
// ---------------------------------------------------------------------------------------

mod honest {
    use carom::collide::{contact, contact_gjk_epa, penetration, Manifold};
    use carom::props::FACE_PREFERENCE_DEPTH;

    fn is_polytope(s: &Shape) -> bool {
        matches!(s, Shape::Cuboid(_) | Shape::Hull(_) | Shape::Triangle(_))
    }
    use carom::Error;

    type Query = fn(&Shape, &Iso, &Shape, &Iso, f32) -> Result<Option<Manifold>, Error>;
    use carom::math::{Iso, Quat, Vec3};
    use carom::scenes::queries::{
        self, PoseQuery, QuerySet, CONTACT_MARGIN, HULLS, HULL_POINTS, PAIRS,
    };
    use carom::shape::{ConvexHull, Shape};

    /// The deepest point's separation against the minimal penetration depth (m).
    pub const DEPTH: f64 = 1.0e-4;
    /// `|normal(B, A) + normal(A, B)|` and the depth difference of the two orders.
    pub const SYMMETRY: f32 = 1.0e-4;

    type V = [f64; 3];
    fn v64(v: Vec3) -> V {
        [v.x as f64, v.y as f64, v.z as f64]
    }
    fn sub(a: V, b: V) -> V {
        [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
    }
    fn dot(a: V, b: V) -> f64 {
        a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
    }
    fn cross(a: V, b: V) -> V {
        [
            a[1] * b[2] - a[2] * b[1],
            a[2] * b[0] - a[0] * b[2],
            a[0] * b[1] - a[1] * b[0],
        ]
    }
    fn unit(a: V) -> Option<V> {
        let l = dot(a, a).sqrt();
        (l > 1e-9).then(|| [a[0] / l, a[1] / l, a[2] / l])
    }
    /// `q` (normalised in f64) applied to `v`, plus `p`.
    fn place(pose: &Iso, v: V) -> V {
        let q = pose.rotation;
        let n = ((q.x as f64).powi(2)
            + (q.y as f64).powi(2)
            + (q.z as f64).powi(2)
            + (q.w as f64).powi(2))
        .sqrt();
        let u = [q.x as f64 / n, q.y as f64 / n, q.z as f64 / n];
        let w = q.w as f64 / n;
        let t = cross(u, v).map(|x| 2.0 * x);
        let ut = cross(u, t);
        let p = v64(pose.position);
        [
            v[0] + w * t[0] + ut[0] + p[0],
            v[1] + w * t[1] + ut[1] + p[1],
            v[2] + w * t[2] + ut[2] + p[2],
        ]
    }

    /// Local vertices, faces (vertex loops) and edges (vertex pairs).
    type Outline = (Vec<V>, Vec<Vec<usize>>, Vec<(usize, usize)>);

    /// A polytope in the world frame (f64): vertices, face normals, edge directions.
    struct Poly {
        vertices: Vec<V>,
        faces: Vec<V>,
        edges: Vec<V>,
    }

    /// The world-frame polytope of a cuboid, hull or triangle; `None` for round shapes.
    fn poly(s: &Shape, pose: &Iso) -> Option<Poly> {
        let (local, faces, edges): Outline = match s {
            Shape::Cuboid(c) => {
                let h = v64(c.half_extents);
                let vs: Vec<V> = (0..8)
                    .map(|i| {
                        let sg = |bit: usize, x: f64| if i & bit != 0 { x } else { -x };
                        [sg(1, h[0]), sg(2, h[1]), sg(4, h[2])]
                    })
                    .collect();
                // Faces by one corner triple each; edges along the axes.
                let faces = vec![
                    vec![0, 2, 4],
                    vec![1, 3, 5],
                    vec![0, 1, 4],
                    vec![2, 3, 6],
                    vec![0, 1, 2],
                    vec![4, 5, 6],
                ];
                (vs, faces, vec![(0, 1), (0, 2), (0, 4)])
            }
            Shape::Hull(h) => {
                let vs: Vec<V> = h.vertices().iter().map(|&p| v64(p)).collect();
                let mut faces = Vec::new();
                let mut edges = Vec::new();
                for f in 0..h.face_count() {
                    let idx: Vec<usize> = h.face_vertices(f).iter().map(|&i| i as usize).collect();
                    for k in 0..idx.len() {
                        edges.push((idx[k], idx[(k + 1) % idx.len()]));
                    }
                    faces.push(idx);
                }
                (vs, faces, edges)
            }
            Shape::Triangle(t) => {
                let vs: Vec<V> = t.vertices.iter().map(|&p| v64(p)).collect();
                (vs, vec![vec![0, 1, 2]], vec![(0, 1), (1, 2), (2, 0)])
            }
            _ => return None,
        };
        let vertices: Vec<V> = local.iter().map(|&v| place(pose, v)).collect();
        let faces = faces
            .iter()
            .filter_map(|f| {
                // Newell's normal of the face polygon.
                let mut n = [0.0; 3];
                for k in 0..f.len() {
                    let (p, q) = (vertices[f[k]], vertices[f[(k + 1) % f.len()]]);
                    n[0] += (p[1] - q[1]) * (p[2] + q[2]);
                    n[1] += (p[2] - q[2]) * (p[0] + q[0]);
                    n[2] += (p[0] - q[0]) * (p[1] + q[1]);
                }
                unit(n)
            })
            .collect();
        let edges = edges
            .iter()
            .filter_map(|&(i, j)| unit(sub(vertices[j], vertices[i])))
            .collect();
        Some(Poly {
            vertices,
            faces,
            edges,
        })
    }

    /// The minimal penetration depth of two convex polytopes (f64 SAT over every face
    /// normal of both and every edge pair), or `None` when a separating axis exists.
    fn sat_depth(a: &Poly, b: &Poly) -> Option<f64> {
        let span = |p: &Poly, u: V| {
            p.vertices
                .iter()
                .map(|v| dot(*v, u))
                .fold((f64::INFINITY, f64::NEG_INFINITY), |(lo, hi), x| {
                    (lo.min(x), hi.max(x))
                })
        };
        let mut axes: Vec<V> = a.faces.iter().chain(b.faces.iter()).copied().collect();
        for ea in &a.edges {
            for eb in &b.edges {
                if let Some(u) = unit(cross(*ea, *eb)) {
                    axes.push(u);
                }
            }
        }
        let mut depth = f64::INFINITY;
        for u in axes {
            let (la, ha) = span(a, u);
            let (lb, hb) = span(b, u);
            let overlap = (ha - lb).min(hb - la);
            if overlap < 0.0 {
                return None;
            }
            depth = depth.min(overlap);
        }
        Some(depth)
    }

    /// The minimal penetration depth of `a` and `b` (f64 SAT for two polytopes, EPA
    /// otherwise), or `None` when they are apart.
    fn true_depth(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso) -> Option<f64> {
        match (poly(a, pa), poly(b, pb)) {
            (Some(x), Some(y)) => sat_depth(&x, &y),
            _ => penetration(a, pa, b, pb)
                .unwrap()
                .map(|p| p.depth as f64)
                .filter(|d| *d > 0.0),
        }
    }

    /// Statistics of one pair kind.
    #[derive(Default, Debug)]
    pub struct Stats {
        pub overlapping: usize,
        pub depth_off: usize,
        /// Manifolds deeper than the minimum by more than [`DEPTH`] (within the face
        /// preference allowed for two polytopes).
        pub preferred: usize,
        pub worst_depth: f64,
        pub asymmetric: usize,
        pub worst_normal: f32,
        pub worst_depth_swap: f32,
        pub worst: String,
    }

    fn hulls() -> Vec<ConvexHull> {
        let mut clouds = vec![[Vec3::ZERO; HULL_POINTS]; HULLS];
        queries::hull_clouds(&mut clouds);
        clouds.iter().map(|c| ConvexHull::new(c).unwrap()).collect()
    }

    fn poses(set: QuerySet) -> Vec<PoseQuery> {
        let mut qs = vec![PoseQuery::default(); PAIRS];
        set.fill(&mut qs);
        qs
    }

    fn measure(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso, s: &mut Stats) {
        measure_with(contact, a, pa, b, pb, s);
    }

    fn measure_with(query: Query, a: &Shape, pa: &Iso, b: &Shape, pb: &Iso, s: &mut Stats) {
        let Some(depth) = true_depth(a, pa, b, pb) else {
            return;
        };
        s.overlapping += 1;
        let m: Option<Manifold> = query(a, pa, b, pb, CONTACT_MARGIN).unwrap();
        let w: Option<Manifold> = query(b, pb, a, pa, CONTACT_MARGIN).unwrap();
        let (Some(m), Some(w)) = (m, w) else {
            s.depth_off += 1;
            s.worst = format!("no manifold at depth {depth}: {a:?} {pa:?} {b:?} {pb:?}");
            return;
        };
        // Deeper by up to the face preference is allowed for two polytopes (a face chosen
        // over a slightly shallower edge pair); shallower never.
        let polytopes = is_polytope(a) && is_polytope(b);
        let allowed = if polytopes {
            f64::from(FACE_PREFERENCE_DEPTH) * depth
        } else {
            0.0
        };
        let signed = -(m.min_separation() as f64) - depth; // > 0: deeper than the minimum
        let err = if signed > 0.0 {
            (signed - allowed).max(0.0)
        } else {
            -signed
        };
        if signed > DEPTH {
            s.preferred += 1;
        }
        if err > DEPTH {
            s.depth_off += 1;
        }
        if err > s.worst_depth {
            s.worst_depth = err;
            s.worst = format!(
                "depth {} vs {depth}: {a:?} {pa:?} {b:?} {pb:?}",
                -m.min_separation()
            );
        }
        let off = (m.normal + w.normal).length();
        let swap = (m.min_separation() - w.min_separation()).abs();
        if off > SYMMETRY || swap > SYMMETRY {
            s.asymmetric += 1;
        }
        s.worst_normal = s.worst_normal.max(off);
        s.worst_depth_swap = s.worst_depth_swap.max(swap);
    }

    /// Every pair kind on the benchmark poses: (name, stats).
    pub fn run() -> Vec<(&'static str, Stats)> {
        let hulls = hulls();
        let hull = |i: u8| Shape::hull(&hulls[usize::from(i) % hulls.len()]);
        let cube = Shape::cuboid(Vec3::splat(queries::BOX_HALF)).unwrap();
        let ball = Shape::sphere(queries::BALL_RADIUS).unwrap();
        let capsule = Shape::capsule(0.4, 0.3).unwrap();
        let triangle = Shape::triangle(
            Vec3::new(-0.9, 0.0, -0.6),
            Vec3::new(0.9, 0.1, -0.5),
            Vec3::new(0.1, -0.1, 0.9),
        )
        .unwrap();
        let hull_poses = poses(QuerySet::HullHull);
        let box_poses = poses(QuerySet::BoxBox);
        let ball_poses = poses(QuerySet::BallBox);
        let mut out = Vec::new();
        let mut kind = |name: &'static str, f: &mut dyn FnMut(&mut Stats)| {
            let mut s = Stats::default();
            f(&mut s);
            out.push((name, s));
        };
        kind("hull-hull", &mut |s| {
            for q in &hull_poses {
                measure(&hull(q.hull_a), &q.pose_a, &hull(q.hull_b), &q.pose_b, s);
            }
        });
        kind("box-box", &mut |s| {
            for q in &box_poses {
                measure(&cube, &q.pose_a, &cube, &q.pose_b, s);
            }
        });
        kind("box-hull", &mut |s| {
            for q in &hull_poses {
                measure(&cube, &q.pose_a, &hull(q.hull_b), &q.pose_b, s);
            }
        });
        kind("hull-hull, general path", &mut |s| {
            for q in &hull_poses {
                let (a, b) = (hull(q.hull_a), hull(q.hull_b));
                measure_with(contact_gjk_epa, &a, &q.pose_a, &b, &q.pose_b, s);
            }
        });
        kind("box-box, general path", &mut |s| {
            for q in &box_poses {
                measure_with(contact_gjk_epa, &cube, &q.pose_a, &cube, &q.pose_b, s);
            }
        });
        kind("box-hull, general path", &mut |s| {
            for q in &hull_poses {
                let b = hull(q.hull_b);
                measure_with(contact_gjk_epa, &cube, &q.pose_a, &b, &q.pose_b, s);
            }
        });
        kind("sphere-hull", &mut |s| {
            for q in &ball_poses {
                measure(&ball, &q.pose_a, &hull(q.hull_b), &q.pose_b, s);
            }
        });
        kind("capsule-hull", &mut |s| {
            for q in &hull_poses {
                measure(&capsule, &q.pose_a, &hull(q.hull_b), &q.pose_b, s);
            }
        });
        kind("capsule-capsule", &mut |s| {
            for q in &box_poses {
                measure(&capsule, &q.pose_a, &capsule, &q.pose_b, s);
            }
        });
        kind("triangle-hull", &mut |s| {
            for q in &hull_poses {
                measure(&triangle, &q.pose_a, &hull(q.hull_b), &q.pose_b, s);
            }
        });
        kind("triangle-box", &mut |s| {
            for q in &box_poses {
                measure(&triangle, &q.pose_a, &cube, &q.pose_b, s);
            }
        });
        kind("triangle-triangle", &mut |s| {
            for q in &box_poses {
                let turned = Iso::new(q.pose_b.position * 0.6, q.pose_b.rotation);
                measure(&triangle, &q.pose_a, &triangle, &turned, s);
            }
        });
        kind("sphere-triangle", &mut |s| {
            for q in &ball_poses {
                let near = Iso::new(q.pose_b.position * 0.5, Quat::IDENTITY);
                measure(&triangle, &q.pose_a, &ball, &near, s);
            }
        });
        kind("capsule-triangle", &mut |s| {
            for q in &box_poses {
                let near = Iso::new(q.pose_b.position * 0.5, q.pose_b.rotation);
                measure(&triangle, &q.pose_a, &capsule, &near, s);
            }
        });
        out
    }
}

/// On the benchmark poses, for every overlapping pair of every kind that goes through
/// the separating axis test or the general GJK/EPA path: the manifold's deepest point
/// agrees with the minimal penetration depth (f64 SAT for polytope pairs, EPA otherwise)
/// within [`honest::DEPTH`] (two polytopes may be deeper by up to
/// `carom::props::FACE_PREFERENCE_DEPTH` of the depth: a face preferred to a slightly
/// shallower edge pair, `carom::collide::EDGE_DEPTH_PREFERENCE`), and `contact(B, A)` has the negated normal and the same
/// depth within [`honest::SYMMETRY`].
#[test]
fn manifolds_are_honest_and_symmetric_on_the_query_sets() {
    let mut failures = Vec::new();
    for (name, s) in honest::run() {
        eprintln!(
            "{name}: {} overlapping, depth off > 1e-4: {} (worst {:.2e} m), face preferred: {}, asymmetric: {} (normal {:.2e}, depth {:.2e})",
            s.overlapping, s.depth_off, s.worst_depth, s.preferred, s.asymmetric, s.worst_normal, s.worst_depth_swap
        );
        if s.depth_off > 0 || s.asymmetric > 0 {
            failures.push(format!("{name}: {s:?}"));
        }
    }
    assert!(failures.is_empty(), "{failures:#?}");
}
