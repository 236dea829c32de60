//! World ray casts and overlap queries against analytic answers, through the public API.

use carom::dynamics::query::{QueryFilter, RayCastHit};
use carom::rng::SplitMix64;
use carom::shape::Ray;
use carom::{BodyDesc, BodyHandle, Error, Input, Iso, Quat, Shape, Vec3, World};

fn sphere(r: f32) -> Shape<'static> {
    Shape::sphere(r).unwrap()
}

fn ray(origin: Vec3, direction: Vec3) -> Ray {
    Ray::new(origin, direction).unwrap()
}

/// f32 ray casts on values up to ~10 m: a few ulps of 10 (1e-6 each) through a sqrt.
const T_TOL: f32 = 1.0e-4;

/// Spheres along +x: the closest one, its analytic `t = d − r`, point and normal; an
/// off-axis ray `t = d − √(r² − b²)`; a tie goes to the lower slot.
#[test]
fn cast_ray_finds_closest_sphere_analytically() {
    let mut world: World<8, 8> = World::new();
    let far = world
        .add(BodyDesc::fixed(sphere(0.5)).position(Vec3::new(7.0, 0.0, 0.0)))
        .unwrap();
    let near = world
        .add(BodyDesc::fixed(sphere(0.5)).position(Vec3::new(3.0, 0.0, 0.0)))
        .unwrap();
    world
        .add(BodyDesc::fixed(sphere(0.5)).position(Vec3::new(5.0, 0.0, 0.0)))
        .unwrap();
    // Behind the origin: never hit.
    world
        .add(BodyDesc::fixed(sphere(0.5)).position(Vec3::new(-2.0, 0.0, 0.0)))
        .unwrap();
    let hit = world
        .cast_ray(&ray(Vec3::ZERO, Vec3::X), 100.0, QueryFilter::default())
        .unwrap()
        .unwrap();
    assert_eq!(hit.body, near);
    assert!((hit.t - 2.5).abs() < T_TOL, "t = {}", hit.t);
    assert!((hit.point - Vec3::new(2.5, 0.0, 0.0)).length() < T_TOL);
    assert!((hit.normal - (-Vec3::X)).length() < T_TOL);

    // Off axis by b = 0.3: t = 3 − √(0.25 − 0.09) = 2.6.
    let hit = world
        .cast_ray(
            &ray(Vec3::new(0.0, 0.3, 0.0), Vec3::X),
            100.0,
            QueryFilter::default(),
        )
        .unwrap()
        .unwrap();
    assert_eq!(hit.body, near);
    assert!((hit.t - 2.6).abs() < T_TOL, "t = {}", hit.t);

    // Too short to reach anything; and passing just above every sphere.
    assert_eq!(
        world.cast_ray(&ray(Vec3::ZERO, Vec3::X), 2.4, QueryFilter::default()),
        Ok(None)
    );
    assert_eq!(
        world.cast_ray(
            &ray(Vec3::new(0.0, 0.51, 0.0), Vec3::X),
            100.0,
            QueryFilter::default()
        ),
        Ok(None)
    );

    // A twin of `far` in a higher slot: the tie keeps `far`.
    let twin = world
        .add(BodyDesc::fixed(sphere(0.5)).position(Vec3::new(7.0, 0.0, 0.0)))
        .unwrap();
    let from_right = ray(Vec3::new(10.0, 0.0, 0.0), -Vec3::X);
    let hit = world
        .cast_ray(&from_right, 100.0, QueryFilter::default())
        .unwrap()
        .unwrap();
    assert_eq!(hit.body, far);
    assert_ne!(hit.body, twin);
    assert!((hit.t - 2.5).abs() < T_TOL);
}

/// Random spheres and rays: `cast_ray` equals the closest analytic hit (computed in f64)
/// and `cast_ray_all` lists every analytic hit in order of `t`.
#[test]
fn random_rays_match_analytic_spheres() {
    let mut rng = SplitMix64::new(11);
    let mut world: World<32, 8> = World::new();
    let mut balls = Vec::new();
    for _ in 0..30 {
        let c = Vec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        );
        let r = rng.range(0.3, 1.5);
        let h = world.add(BodyDesc::dynamic(sphere(r)).position(c)).unwrap();
        balls.push((h, c, r));
    }
    let mut checked_hits = 0;
    for _ in 0..200 {
        let origin = Vec3::new(
            rng.range(-8.0, 8.0),
            rng.range(-8.0, 8.0),
            rng.range(-8.0, 8.0),
        );
        // Aim at a random ball's centre, jittered by up to 1 m, so most rays hit.
        let target = balls[(rng.next_u64() % balls.len() as u64) as usize].1;
        let jitter = rng.unit_vector() * rng.range(0.0, 1.0);
        let r = ray(origin, target + jitter - origin);
        // f64 oracle: smaller root of |o + t d − c|² = r², t clamped at 0 inside.
        // (t, body, tolerance). The f32 cast forms `b² − c` from terms of size `|m|²`:
        // a few ulps of that (ε = 2⁻²³) divided by `2√disc` from the square root, plus a
        // few ulps of `t` itself.
        let mut expected: Vec<(f64, BodyHandle, f64)> = Vec::new();
        let mut borderline = false;
        for &(h, c, rad) in &balls {
            let m = [
                (r.origin.x - c.x) as f64,
                (r.origin.y - c.y) as f64,
                (r.origin.z - c.z) as f64,
            ];
            let d = [
                r.direction.x as f64,
                r.direction.y as f64,
                r.direction.z as f64,
            ];
            let b = m[0] * d[0] + m[1] * d[1] + m[2] * d[2];
            let cc = m[0] * m[0] + m[1] * m[1] + m[2] * m[2] - (rad as f64) * (rad as f64);
            let disc = b * b - cc;
            if disc.abs() < 1e-3 || cc.abs() < 1e-3 {
                borderline = true; // grazing, or the origin on the surface
            }
            let eps = f32::EPSILON as f64;
            if cc <= 0.0 {
                expected.push((0.0, h, 1e-6));
            } else if b < 0.0 && disc >= 0.0 {
                let t = -b - disc.sqrt();
                let mm = m[0] * m[0] + m[1] * m[1] + m[2] * m[2];
                let tol = 8.0 * eps * (b * b + mm) / (2.0 * disc.sqrt()) + 8.0 * eps * t + 1e-6;
                expected.push((t, h, tol));
            }
        }
        if borderline {
            continue;
        }
        expected.sort_by(|x, y| x.0.total_cmp(&y.0).then(x.1.index.cmp(&y.1.index)));
        // Two hits closer in t than their tolerances may swap order: skip such rays.
        if expected
            .windows(2)
            .any(|w| w[1].0 - w[0].0 < w[0].2 + w[1].2)
        {
            continue;
        }
        let closest = world.cast_ray(&r, 100.0, QueryFilter::default()).unwrap();
        let mut out = [RayCastHit::default(); 32];
        let n = world
            .cast_ray_all(&r, 100.0, QueryFilter::default(), &mut out)
            .unwrap();
        assert_eq!(n, expected.len());
        for (got, want) in out[..n].iter().zip(&expected) {
            assert_eq!(got.body, want.1);
            assert!(
                (got.t as f64 - want.0).abs() < want.2,
                "{} vs {} ± {}",
                got.t,
                want.0,
                want.2
            );
        }
        assert!(out[..n].windows(2).all(|w| w[0].t <= w[1].t));
        match expected.first() {
            Some(&(t, h, tol)) => {
                let hit = closest.unwrap();
                assert_eq!(hit.body, h);
                assert!((hit.t as f64 - t).abs() < tol);
                checked_hits += 1;
            }
            None => assert_eq!(closest, None),
        }
    }
    assert!(checked_hits > 100, "only {checked_hits} rays hit something");
}

/// `cast_ray_all` with a short buffer keeps the nearest; `max_t` cuts the list.
#[test]
fn cast_ray_all_sorts_and_truncates_to_the_nearest() {
    let mut world: World<8, 8> = World::new();
    let xs = [7.0, 3.0, 5.0, 9.0];
    let h: Vec<BodyHandle> = xs
        .iter()
        .map(|&x| {
            world
                .add(BodyDesc::fixed(sphere(0.5)).position(Vec3::new(x, 0.0, 0.0)))
                .unwrap()
        })
        .collect();
    let r = ray(Vec3::ZERO, Vec3::X);
    let f = QueryFilter::default();
    let mut out = [RayCastHit::default(); 8];
    let n = world.cast_ray_all(&r, 100.0, f, &mut out).unwrap();
    let got: Vec<BodyHandle> = out[..n].iter().map(|x| x.body).collect();
    assert_eq!(got, vec![h[1], h[2], h[0], h[3]]);
    let ts: Vec<f32> = out[..n].iter().map(|x| x.t).collect();
    for (t, want) in ts.iter().zip([2.5, 4.5, 6.5, 8.5]) {
        assert!((t - want).abs() < T_TOL);
    }
    let mut two = [RayCastHit::default(); 2];
    assert_eq!(world.cast_ray_all(&r, 100.0, f, &mut two), Ok(2));
    assert_eq!([two[0].body, two[1].body], [h[1], h[2]]);
    let n = world.cast_ray_all(&r, 5.0, f, &mut out).unwrap();
    assert_eq!(n, 2);
    assert_eq!(world.cast_ray_all(&r, 100.0, f, &mut []), Ok(0));
}

/// Group/mask and sensors exclude bodies from ray casts and overlaps.
#[test]
fn filters_exclude_bodies() {
    let mut world: World<8, 8> = World::new();
    let grouped = world
        .add(
            BodyDesc::fixed(sphere(0.5))
                .position(Vec3::new(2.0, 0.0, 0.0))
                .filter(0b10, u32::MAX),
        )
        .unwrap();
    let picky = world
        .add(
            BodyDesc::fixed(sphere(0.5))
                .position(Vec3::new(4.0, 0.0, 0.0))
                .filter(0b01, 0b01),
        )
        .unwrap();
    let sensor = world
        .add(
            BodyDesc::fixed(sphere(0.5))
                .position(Vec3::new(6.0, 0.0, 0.0))
                .sensor(true),
        )
        .unwrap();
    let plain = world
        .add(BodyDesc::fixed(sphere(0.5)).position(Vec3::new(8.0, 0.0, 0.0)))
        .unwrap();
    let r = ray(Vec3::ZERO, Vec3::X);
    let first = |f: QueryFilter| world.cast_ray(&r, 100.0, f).unwrap().map(|h| h.body);
    assert_eq!(first(QueryFilter::default()), Some(grouped));
    // Mask 0b01 does not see group 0b10.
    let f = QueryFilter {
        group: u32::MAX,
        mask: 0b01,
        include_sensors: true,
    };
    assert_eq!(first(f), Some(picky));
    // A query in group 0b10 is not seen by `picky` (mask 0b01), nor sees `grouped`.
    let f = QueryFilter {
        group: 0b10,
        mask: 0b01,
        include_sensors: true,
    };
    assert_eq!(first(f), Some(sensor));
    let f = QueryFilter {
        group: 0b10,
        mask: 0b01,
        include_sensors: false,
    };
    assert_eq!(first(f), Some(plain));

    // A big ball over all four: the same filters on overlap.
    let big = sphere(10.0);
    let mut out = [BodyHandle {
        index: 0,
        generation: 0,
    }; 8];
    let mut overlap = |f: QueryFilter| {
        let n = world.overlap(&big, &Iso::IDENTITY, f, &mut out).unwrap();
        out[..n].to_vec()
    };
    assert_eq!(
        overlap(QueryFilter::default()),
        vec![grouped, picky, sensor, plain]
    );
    let f = QueryFilter {
        group: 0b10,
        mask: 0b01,
        include_sensors: false,
    };
    assert_eq!(overlap(f), vec![plain]);
}

/// Random spheres and boxes (rotated) against random ball and half-space queries:
/// `overlap` returns, in slot order, exactly the bodies an analytic test finds, apart
/// from cases within 1e-3 m of touching (where f32 GJK may go either way).
#[test]
fn overlap_matches_analytic_tests() {
    let mut rng = SplitMix64::new(5);
    let mut world: World<40, 8> = World::new();
    // (handle, centre, rotation matrix, Some(radius) for a ball / None for the box, half)
    let mut bodies = Vec::new();
    for i in 0..36 {
        let c = Vec3::new(
            rng.range(-6.0, 6.0),
            rng.range(-6.0, 6.0),
            rng.range(-6.0, 6.0),
        );
        let q = rng.rotation();
        let (shape, radius, half) = if i % 2 == 0 {
            let r = rng.range(0.2, 1.2);
            (sphere(r), Some(r), Vec3::ZERO)
        } else {
            let half = Vec3::new(
                rng.range(0.2, 1.2),
                rng.range(0.2, 1.2),
                rng.range(0.2, 1.2),
            );
            (Shape::cuboid(half).unwrap(), None, half)
        };
        let h = world
            .add(BodyDesc::fixed(shape).position(c).rotation(q))
            .unwrap();
        let pose = world.body(h).unwrap().pose();
        bodies.push((h, pose, radius, half));
    }
    let mut found_total = 0;
    for round in 0..60 {
        let centre = Vec3::new(
            rng.range(-6.0, 6.0),
            rng.range(-6.0, 6.0),
            rng.range(-6.0, 6.0),
        );
        let half_space_query = round % 4 == 3;
        let r = rng.range(0.5, 3.0);
        let (shape, pose) = if half_space_query {
            let n = rng.unit_vector();
            (Shape::half_space(n).unwrap(), Iso::from_position(centre))
        } else {
            (sphere(r), Iso::new(centre, rng.rotation()))
        };
        let n_world = match shape {
            Shape::HalfSpace(h) => h.normal,
            _ => Vec3::ZERO,
        };
        let mut sure = Vec::new();
        let mut maybe = Vec::new();
        for &(h, body_pose, radius, half) in &bodies {
            // Signed gap (m): negative or zero means they meet.
            let gap = if half_space_query {
                // Lowest point along n: centre − r for a ball, centre − Σ|R·n| h for a box.
                let reach = match radius {
                    Some(rad) => rad,
                    None => {
                        let local_n = body_pose.inverse_transform_vector(n_world);
                        local_n.abs().dot(half)
                    }
                };
                n_world.dot(body_pose.position - centre) - reach
            } else {
                match radius {
                    Some(rad) => (body_pose.position - centre).length() - rad - r,
                    None => {
                        // Distance from the ball's centre to the box: clamp in the box frame.
                        let local = body_pose.inverse_transform_point(centre);
                        let clamped = local.max(-half).min(half);
                        (local - clamped).length() - r
                    }
                }
            };
            if gap.abs() < 1e-3 {
                maybe.push(h);
            } else if gap < 0.0 {
                sure.push(h);
            }
        }
        let mut out = [BodyHandle {
            index: 0,
            generation: 0,
        }; 40];
        let n = world
            .overlap(&shape, &pose, QueryFilter::default(), &mut out)
            .unwrap();
        let got = &out[..n];
        assert!(
            got.windows(2).all(|w| w[0].index < w[1].index),
            "round {round}: not in slot order"
        );
        let without_maybe: Vec<BodyHandle> =
            got.iter().copied().filter(|h| !maybe.contains(h)).collect();
        assert_eq!(without_maybe, sure, "round {round}");
        found_total += sure.len();
    }
    assert!(
        found_total > 100,
        "only {found_total} overlaps: the test is too sparse"
    );
    // A short buffer keeps the lowest slots.
    let mut two = [BodyHandle {
        index: 0,
        generation: 0,
    }; 2];
    let everything = sphere(100.0);
    assert_eq!(
        world.overlap(
            &everything,
            &Iso::IDENTITY,
            QueryFilter::default(),
            &mut two
        ),
        Ok(2)
    );
    assert_eq!(two, [bodies[0].0, bodies[1].0]);
}

/// Each bad input gives its exact error.
#[test]
fn bad_inputs_give_exact_errors() {
    let mut world: World<4, 4> = World::new();
    world.add(BodyDesc::fixed(sphere(1.0))).unwrap();
    let f = QueryFilter::default();
    let good = ray(Vec3::new(0.0, 0.0, -5.0), Vec3::Z);
    let raw = |origin: Vec3, direction: Vec3| Ray { origin, direction };
    let cases = [
        (good, f32::NAN, Error::NonFinite(Input::Distance)),
        (good, f32::INFINITY, Error::NonFinite(Input::Distance)),
        (good, -1.0, Error::Negative(Input::Distance)),
        (
            raw(Vec3::new(f32::NAN, 0.0, 0.0), Vec3::Z),
            1.0,
            Error::NonFinite(Input::Position),
        ),
        (
            raw(Vec3::ZERO, Vec3::new(0.0, f32::INFINITY, 0.0)),
            1.0,
            Error::NonFinite(Input::Direction),
        ),
        (
            raw(Vec3::ZERO, Vec3::ZERO),
            1.0,
            Error::NotPositive(Input::Direction),
        ),
        (
            raw(Vec3::ZERO, Vec3::new(0.0, 0.0, 2.0)),
            1.0,
            Error::OutOfRange(Input::Direction),
        ),
    ];
    let mut out = [RayCastHit::default(); 4];
    for (r, max_t, err) in cases {
        assert_eq!(world.cast_ray(&r, max_t, f), Err(err), "{r:?} {max_t}");
        assert_eq!(
            world.cast_ray_all(&r, max_t, f, &mut out),
            Err(err),
            "{r:?} {max_t}"
        );
    }
    // Zero length is allowed: the ray starts inside the ball.
    let inside = world
        .cast_ray(&ray(Vec3::ZERO, Vec3::Z), 0.0, f)
        .unwrap()
        .unwrap();
    assert_eq!(inside.t, 0.0);

    let mut handles = [BodyHandle {
        index: 0,
        generation: 0,
    }; 4];
    let s = sphere(1.0);
    let poses = [
        (
            Iso::from_position(Vec3::new(0.0, f32::NAN, 0.0)),
            Error::NonFinite(Input::Position),
        ),
        (
            Iso::new(Vec3::ZERO, Quat::from_xyzw(f32::NAN, 0.0, 0.0, 1.0)),
            Error::NonFinite(Input::Rotation),
        ),
        (
            Iso::new(Vec3::ZERO, Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
            Error::NotUnit(Input::Rotation),
        ),
    ];
    for (pose, err) in poses {
        assert_eq!(world.overlap(&s, &pose, f, &mut handles), Err(err));
    }
}
