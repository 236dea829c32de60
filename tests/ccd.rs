//! Continuous collision scenarios: bullets against thin walls, fast against fast, and
//! fast bodies that must not be stopped by what they only slide along.
//!
//! Public API only. Each tolerance says why it is what it is.

use carom::scenes::{self, Scene};
use carom::shape::HeightField;
use carom::{BodyDesc, Material, Shape, Vec3, World, WorldConfig};

const SLOP: f32 = carom::config::LINEAR_SLOP;

fn no_gravity() -> WorldConfig {
    WorldConfig {
        gravity: Vec3::ZERO,
        ..WorldConfig::DEFAULT
    }
}

/// SCENES.md "bullet": a 5 cm ball at 500 m/s (8.3 m per step) against a 10 cm wall. It
/// must never pass the wall: its centre stays in front of the near face less its radius,
/// up to the slop that contacts may rest at. The pair's speculative contact reaches as
/// far as the pair closes in a step, so the solver stops the ball at the face in the
/// step it arrives (time of impact has nothing left to do).
#[test]
fn bullet_never_passes_the_wall() {
    let mut w: World<8, 16> = World::with_config(Scene::Bullet.config()).unwrap();
    let bullet = Scene::Bullet.build(&mut w, &[]).unwrap();
    let limit = -0.05 - 0.05; // near face less the radius
    let mut max_x = f32::MIN;
    let mut hits = 0;
    for _ in 0..Scene::Bullet.steps() {
        let r = w.step();
        hits += r.ccd_hits;
        let x = w.body(bullet).unwrap().position().x;
        max_x = max_x.max(x);
        assert!(x < 0.0, "passed the wall's centre: x = {x}");
        // The slop: continuous collision stops it within the sweep tolerance (one slop),
        // and the contact after that may rest at most one slop deep.
        assert!(x <= limit + SLOP, "x = {x}, beyond {limit} + slop");
    }
    eprintln!("bullet: max x {max_x}, ccd hits {hits}");
    assert!(max_x > limit - 0.01, "stopped short of the wall: {max_x}");
    // The contact stopped it for good (no restitution): it rests at the wall.
    let v = w.body(bullet).unwrap().linear_velocity();
    assert!(v.length() < 1e-3, "still moving: {v:?}");
}

/// The same bullet with continuous collision switched off tunnels: the check above is
/// the sweep's doing, not the discrete contact's.
#[test]
fn bullet_without_ccd_tunnels() {
    let mut w: World<8, 16> = World::with_config(no_gravity()).unwrap();
    w.add(BodyDesc::fixed(
        Shape::cuboid(Vec3::new(0.05, 5.0, 5.0)).unwrap(),
    ))
    .unwrap();
    let b = w
        .add(
            BodyDesc::dynamic(Shape::sphere(0.05).unwrap())
                .position(Vec3::new(-5.0, 0.0, 0.0))
                .velocity(Vec3::new(500.0, 0.0, 0.0))
                .ccd(false),
        )
        .unwrap();
    let mut sweeps = 0;
    for _ in 0..3 {
        sweeps += w.step().ccd_sweeps;
    }
    assert_eq!(sweeps, 0);
    assert!(w.body(b).unwrap().position().x > 5.0, "expected to tunnel");
}

/// Two 5 cm balls closing at 300 m/s each (10 m per step together) collide: their order
/// along x never changes, and with no restitution and equal masses both stop.
#[test]
fn fast_balls_head_on_collide() {
    let mut w: World<8, 16> = World::with_config(no_gravity()).unwrap();
    let ball = Shape::sphere(0.05).unwrap();
    let m = Material {
        restitution: 0.0,
        static_friction: 0.0,
        kinetic_friction: 0.0,
        ..Material::DEFAULT
    };
    let a = w
        .add(
            BodyDesc::dynamic(ball)
                .position(Vec3::new(-2.0, 0.0, 0.0))
                .velocity(Vec3::new(300.0, 0.0, 0.0))
                .material(m),
        )
        .unwrap();
    let b = w
        .add(
            BodyDesc::dynamic(ball)
                .position(Vec3::new(2.03, 0.0, 0.0))
                .velocity(Vec3::new(-300.0, 0.0, 0.0))
                .material(m),
        )
        .unwrap();
    let mut hits = 0;
    let mut min_gap = f32::MAX;
    for _ in 0..30 {
        hits += w.step().ccd_hits;
        let gap = w.body(b).unwrap().position().x - w.body(a).unwrap().position().x - 0.1;
        min_gap = min_gap.min(gap);
        // Never crossed, never deeper than the slop the contact may rest at.
        assert!(gap > -SLOP, "gap {gap}");
    }
    eprintln!("fast balls: min gap {min_gap}, ccd hits {hits}");
    assert!(min_gap < 0.01, "never met: {min_gap}");
    for h in [a, b] {
        let v = w.body(h).unwrap().linear_velocity();
        // Equal masses, e = 0: the impact leaves both at rest, up to f32 rounding of
        // ±300 m/s (about 3e-5 m/s per rounding).
        assert!(v.length() < 1e-3, "{v:?}");
    }
}

/// The shared `bullets` scene: twelve 5 cm balls at 150 to 400 m/s in a closed room with
/// 10 cm walls, two of them head-on. None leaves the room.
#[test]
fn bullets_stay_in_the_room() {
    let mut w: World<32, 128> = World::with_config(Scene::Bullets.config()).unwrap();
    scenes::bullets(&mut w).unwrap();
    let balls: Vec<_> = w
        .handles()
        .filter(|&h| w.body(h).unwrap().mass().is_finite())
        .collect();
    assert_eq!(balls.len(), scenes::BULLETS);
    let mut hits = 0;
    let mut deepest = 0.0f32;
    for step in 0..120 {
        hits += w.step().ccd_hits;
        for &h in &balls {
            let p = w.body(h).unwrap().position();
            let room = [3.0 - p.x.abs(), 3.0 - p.z.abs(), p.y, 6.0 - p.y];
            deepest = room.iter().fold(deepest, |d, &gap| d.max(0.05 - gap));
            // Inner faces at |x|, |z| = 3 and y = 0, 6; the radius 0.05 less one slop of
            // resting penetration.
            let r = 0.05 - SLOP;
            assert!(
                p.x.abs() <= 3.0 - r && p.z.abs() <= 3.0 - r && p.y >= r && p.y <= 6.0 - r,
                "step {step}: ball at {p:?}"
            );
        }
    }
    eprintln!("bullets: ccd hits {hits}, deepest wall penetration {deepest} m");
    // Most impacts are stopped by speculative contacts; time of impact catches the balls
    // another ball knocked out of their predicted paths.
    assert!(hits >= 1, "time of impact never needed: {hits}");
}

/// A small box sliding fast along frictionless ground touches it all the time; that
/// contact must not make continuous collision stop it. It keeps its speed.
#[test]
fn fast_slider_is_not_stopped_by_the_ground() {
    let mut w: World<8, 16> = World::with_config(WorldConfig::DEFAULT).unwrap();
    let ice = Material {
        restitution: 0.0,
        static_friction: 0.0,
        kinetic_friction: 0.0,
        ..Material::DEFAULT
    };
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(50.0, 0.5, 5.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0))
            .material(ice),
    )
    .unwrap();
    // 10 cm box at 6 m/s: 0.1 m per step, four times the 2.5 cm that makes it fast.
    let b = w
        .add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.05)).unwrap())
                .position(Vec3::new(-40.0, 0.05, 0.0))
                .velocity(Vec3::new(6.0, 0.0, 0.0))
                .material(ice),
        )
        .unwrap();
    let mut sweeps = 0;
    for _ in 0..60 {
        sweeps += w.step().ccd_sweeps;
    }
    let r = w.body(b).unwrap();
    assert!(sweeps >= 50, "it was not swept: {sweeps}");
    // Frictionless: 6 m in 1 s. 1 mm: f32 rounding of 60 position updates near x = −40.
    assert!(
        (r.position().x - (-34.0)).abs() < 1e-3,
        "x = {}",
        r.position().x
    );
    assert!(
        (r.linear_velocity().x - 6.0).abs() < 1e-4,
        "v = {:?}",
        r.linear_velocity()
    );
}

/// A slow body is not swept at all.
#[test]
fn slow_bodies_are_not_swept() {
    let mut w: World<8, 16> = World::with_config(WorldConfig::DEFAULT).unwrap();
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )
    .unwrap();
    // A 1 m box dropped from 0.5 m reaches 3.1 m/s: 5 cm per step, under a quarter of 1 m.
    w.add(
        BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.5)).unwrap())
            .position(Vec3::new(0.0, 1.0, 0.0)),
    )
    .unwrap();
    for _ in 0..60 {
        assert_eq!(w.step().ccd_sweeps, 0);
    }
}

/// Spin alone makes a body fast only by what its core sweeps: a ball spinning in place at
/// the speed limit, 100 rad/s (its surface at 10 m/s, 17 cm per step, most of its
/// diameter), moves no point of its core and is never swept, while a capsule of the same
/// radius spinning as fast about its middle sweeps its segment's ends 0.8 m per step and is
/// swept every step.
#[test]
fn a_spinning_ball_is_not_swept_and_a_spinning_capsule_is() {
    for (shape, swept) in [
        (Shape::sphere(0.1).unwrap(), false),
        (Shape::capsule(0.5, 0.1).unwrap(), true),
    ] {
        let mut w: World<8, 16> = World::with_config(no_gravity()).unwrap();
        // A neighbour a metre away, so the spinning body has a partner to be swept against.
        w.add(BodyDesc::fixed(Shape::sphere(0.1).unwrap()).position(Vec3::new(0.0, 0.0, 1.0)))
            .unwrap();
        let h = w
            .add(BodyDesc::dynamic(shape).angular_velocity(Vec3::new(0.0, 100.0, 0.0)))
            .unwrap();
        for step in 0..30 {
            let sweeps = w.step().ccd_sweeps;
            assert_eq!(sweeps > 0, swept, "{shape:?} step {step}: {sweeps} sweeps");
        }
        assert!(w.body(h).unwrap().angular_velocity().y > 99.0);
    }
}

/// A fast box falling onto a height field is swept once against each triangle near its
/// path per step: the step's time-of-impact queries are exactly the triangles that the
/// field's own box query finds around the path (a brute-force count over the public
/// query), not that count again for each of the pair's part contacts. Checked in the
/// steps where the box is fast, has the field as a contact partner and is not moved back
/// (its pose after the step is then the end of the path that was swept).
#[test]
fn a_fast_body_is_swept_once_against_each_triangle_near_its_path() {
    // A ramp rising along x at 1 in 2 (8 × 8 cells of 0.5 m, 128 triangles): a cell's
    // box reaches 0.25 m above its lower edge, so the path of a box falling beside the
    // slope meets triangle boxes before the box touches the surface.
    let n = 9u32;
    let heights: Vec<f32> = (0..n * n).map(|k| 0.25 * (k % n) as f32).collect();
    let field = HeightField::new(&heights, n, n, 0.5).unwrap();
    let mut w: World<8, 512> = World::new();
    let ground = w.add(BodyDesc::fixed(Shape::HeightField(&field))).unwrap();
    let cube = Shape::cuboid(Vec3::splat(0.3)).unwrap();
    // 12 m/s: 0.2 m a step, past a quarter of the box's 0.6 m (fast).
    let b = w
        .add(
            BodyDesc::dynamic(cube)
                .position(Vec3::new(2.0, 3.5, 2.0))
                .velocity(Vec3::new(0.0, -12.0, 0.0)),
        )
        .unwrap();
    let field_pose_inverse = w.body(ground).unwrap().pose().inverse();
    let (mut checked, mut queries) = (0, 0);
    for _ in 0..30 {
        let before = w.body(b).unwrap().pose();
        let r = w.step();
        let after = w.body(b).unwrap().pose();
        queries += r.ccd_queries;
        if r.ccd_sweeps == 0 || r.ccd_hits > 0 || r.ccd_queries == 0 {
            continue;
        }
        let path = cube.aabb(&before).union(&cube.aabb(&after));
        let mut near = 0u32;
        field.query_aabb(&path.transformed(&field_pose_inverse), |_| near += 1);
        assert_eq!(r.ccd_queries, near, "step {}", w.step_count());
        checked += 1;
    }
    eprintln!("swept-once check: {checked} steps, {queries} queries");
    assert!(checked >= 1, "no step swept the box against the field");
    // It landed on the field and stays above its lowest point.
    let p = w.body(b).unwrap().position();
    assert!(p.y > 0.3 - SLOP, "box at {p:?}");
}
