//! Sleeping: islands fall asleep together, wake together when hit, moving kinematic
//! bodies keep what they touch awake, and the switch turns it all off.
//!
//! Public API only.

use carom::{BodyDesc, BodyHandle, Shape, Vec3, World, WorldConfig};

type W = World<'static, 16, 64>;

fn ground(w: &mut W) {
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )
    .unwrap();
}

/// A stack of `n` 1 m boxes at `x`, touching, on the ground.
fn stack(w: &mut W, x: f32, n: usize) -> Vec<BodyHandle> {
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    (0..n)
        .map(|i| {
            w.add(BodyDesc::dynamic(cube).position(Vec3::new(x, 0.5 + i as f32, 0.0)))
                .unwrap()
        })
        .collect()
}

fn awake(w: &W, hs: &[BodyHandle]) -> Vec<bool> {
    hs.iter().map(|&h| w.body(h).unwrap().is_awake()).collect()
}

/// Step until every body of `hs` sleeps; the step count, or `None` after `max` steps.
fn steps_until_asleep(w: &mut W, hs: &[BodyHandle], max: u32) -> Option<u32> {
    (1..=max).find(|_| {
        w.step();
        awake(w, hs).iter().all(|a| !a)
    })
}

/// A stack is one island: its boxes fall asleep in the same step, about `sleep_time`
/// after they come to rest, and then stay exactly where they are.
#[test]
fn a_stack_falls_asleep_as_one_island() {
    let mut w = W::with_config(WorldConfig::DEFAULT).unwrap();
    ground(&mut w);
    let boxes = stack(&mut w, 0.0, 3);
    let mut first_asleep = None;
    for i in 1..=120u32 {
        w.step();
        let a = awake(&w, &boxes);
        if a.iter().any(|x| !x) {
            assert!(a.iter().all(|x| !x), "step {i}: the island split: {a:?}");
            first_asleep.get_or_insert(i);
        }
    }
    let slept = first_asleep.expect("asleep within 2 s");
    eprintln!("stack of 3 asleep at step {slept}");
    // 0.5 s of slow motion (30 steps) plus the few steps a cold stack takes to settle.
    assert!((30..=60).contains(&slept), "slept at step {slept}");
    assert_eq!(w.last_report().awake_bodies, 0);
    let before: Vec<Vec3> = boxes
        .iter()
        .map(|&h| w.body(h).unwrap().position())
        .collect();
    for _ in 0..120 {
        w.step();
    }
    for (&h, p) in boxes.iter().zip(before) {
        assert_eq!(w.body(h).unwrap().position(), p, "a sleeping body moved");
        assert_eq!(w.body(h).unwrap().linear_velocity(), Vec3::ZERO);
    }
}

/// Two stacks far apart are two islands: holding one awake does not keep the other up.
#[test]
fn separate_islands_sleep_on_their_own() {
    let mut w = W::with_config(WorldConfig::DEFAULT).unwrap();
    ground(&mut w);
    let left = stack(&mut w, -4.0, 2);
    let right = stack(&mut w, 4.0, 2);
    for _ in 0..90 {
        // A tiny push every step keeps the left stack's top awake (a force wakes a body).
        w.apply_force(left[1], Vec3::new(0.0, 1.0, 0.0)).unwrap();
        w.step();
    }
    assert_eq!(
        awake(&w, &left),
        [true, true],
        "the held island must stay awake"
    );
    assert_eq!(
        awake(&w, &right),
        [false, false],
        "the free island must sleep"
    );
}

/// A ball thrown at the top of a sleeping stack wakes the whole stack (the hit box wakes
/// at once, the rest of its island at the end of that step), and the hit box moves.
#[test]
fn a_hit_wakes_a_sleeping_stack() {
    let mut w = W::with_config(WorldConfig::DEFAULT).unwrap();
    ground(&mut w);
    let boxes = stack(&mut w, 0.0, 3);
    steps_until_asleep(&mut w, &boxes, 120).expect("stack asleep");
    let top_before = w.body(boxes[2]).unwrap().position();
    let ball = w
        .add(
            BodyDesc::dynamic(Shape::sphere(0.25).unwrap())
                .position(Vec3::new(-1.5, 2.5, 0.0))
                .velocity(Vec3::new(8.0, 0.0, 0.0))
                .density(3000.0),
        )
        .unwrap();
    let mut woke_at = None;
    for i in 1..=20u32 {
        w.step();
        if awake(&w, &boxes).iter().all(|&a| a) {
            woke_at = Some(i);
            break;
        }
    }
    let woke = woke_at.expect("the stack woke");
    eprintln!("stack woke at step {woke}");
    // The ball covers the 1 m gap at 8 m/s in about 8 steps.
    assert!(woke <= 10, "woke at step {woke}");
    for _ in 0..10 {
        w.step();
    }
    let moved = w.body(boxes[2]).unwrap().position().x - top_before.x;
    assert!(moved > 0.01, "the top box did not move: {moved}");
    assert!(w.body(ball).unwrap().linear_velocity().x < 8.0);
}

/// A kinematic platform creeping at 2 cm/s (below the sleep speed) carries a box; the
/// moving platform keeps the box awake, so the box keeps riding along.
#[test]
fn a_moving_kinematic_keeps_its_load_awake() {
    let mut w = W::with_config(WorldConfig::DEFAULT).unwrap();
    let speed = 0.02;
    w.add(
        BodyDesc::kinematic(Shape::cuboid(Vec3::new(3.0, 0.25, 3.0)).unwrap())
            .position(Vec3::new(0.0, -0.25, 0.0))
            .velocity(Vec3::new(speed, 0.0, 0.0)),
    )
    .unwrap();
    let b = w
        .add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.5)).unwrap())
                .position(Vec3::new(0.0, 0.5, 0.0)),
        )
        .unwrap();
    for _ in 0..180 {
        w.step();
    }
    let r = w.body(b).unwrap();
    eprintln!("carried box at x = {}", r.position().x);
    assert!(r.is_awake(), "the carried box fell asleep");
    // Static friction carries it: 6 cm in 3 s. 5 mm allows the first steps' slip while
    // friction builds up.
    assert!(
        (r.position().x - 3.0 * speed).abs() < 5e-3,
        "x = {}",
        r.position().x
    );
}

/// A kinematic body at rest does not keep anything awake.
#[test]
fn a_resting_kinematic_lets_its_load_sleep() {
    let mut w = W::with_config(WorldConfig::DEFAULT).unwrap();
    w.add(
        BodyDesc::kinematic(Shape::cuboid(Vec3::new(3.0, 0.25, 3.0)).unwrap())
            .position(Vec3::new(0.0, -0.25, 0.0)),
    )
    .unwrap();
    let b = stack(&mut w, 0.0, 1);
    assert!(steps_until_asleep(&mut w, &b, 120).is_some());
}

/// With sleeping switched off nothing sleeps, and the report counts every dynamic body.
#[test]
fn sleep_can_be_switched_off() {
    let cfg = WorldConfig {
        sleep_enabled: false,
        ..WorldConfig::DEFAULT
    };
    let mut w = W::with_config(cfg).unwrap();
    ground(&mut w);
    let boxes = stack(&mut w, 0.0, 2);
    for _ in 0..180 {
        w.step();
    }
    assert_eq!(awake(&w, &boxes), [true, true]);
    assert_eq!(w.last_report().awake_bodies, 2);
    // Resting, not drifting: the solver alone keeps them still (1 mm/s).
    for &h in &boxes {
        assert!(w.body(h).unwrap().linear_velocity().length() < 1e-3);
    }
    // A body put to sleep by hand wakes again at the next step.
    w.sleep(boxes[1]).unwrap();
    w.step();
    assert!(w.body(boxes[1]).unwrap().is_awake());
}

/// A world where everything sleeps steps in constant time (only its step count moves),
/// and that shortcut gives exactly what the full pipeline gives: a clone forced through
/// the full step (a no-op `set_config` clears the shortcut) has the same checksum,
/// snapshot, report and stage trace after every step.
#[test]
fn an_all_asleep_world_steps_like_the_full_pipeline() {
    let mut w: World<32, 128> = World::new();
    carom::scenes::tower(&mut w, 10).unwrap();
    let mut slept = false;
    for _ in 0..1000 {
        if w.step().awake_bodies == 0 {
            slept = true;
            break;
        }
    }
    assert!(slept, "the tower never slept");
    w.step();
    let cfg = *w.config();
    for k in 0..10 {
        let mut full = w.clone();
        full.set_config(cfg).unwrap();
        let (mut ta, mut tb) = (carom::StepTrace::default(), carom::StepTrace::default());
        let ra = w.step_traced(Some(&mut ta));
        let rb = full.step_traced(Some(&mut tb));
        assert_eq!(ra, rb, "step {k}: reports differ");
        assert_eq!(ta, tb, "step {k}: traces differ");
        assert_eq!(w.checksum(), full.checksum(), "step {k}");
        let (mut a, mut b) = (vec![0u8; 65536], vec![0u8; 65536]);
        let (na, nb) = (w.snapshot(&mut a).unwrap(), full.snapshot(&mut b).unwrap());
        if a[..na] != b[..nb] {
            let first: Vec<usize> = (0..na.min(nb)).filter(|&i| a[i] != b[i]).take(20).collect();
            panic!("step {k}: snapshots differ: len {na} {nb}, first byte {first:?}");
        }
    }
}

/// A world at rest takes a shortcut through the step (nothing can move), and still
/// names every stage, in order, to `step_observed`, steps as `step` does, and keeps
/// every body where it is.
#[test]
fn a_world_at_rest_still_names_every_stage() {
    let mut w = W::with_config(WorldConfig::DEFAULT).unwrap();
    ground(&mut w);
    let boxes = stack(&mut w, 0.0, 3);
    steps_until_asleep(&mut w, &boxes, 240).expect("asleep within 4 s");
    let positions = |w: &W| -> Vec<Vec3> {
        boxes
            .iter()
            .map(|&h| w.body(h).unwrap().position())
            .collect()
    };
    let at_rest = positions(&w);
    let mut plain = w.clone();
    for step in 0..5 {
        let mut heard = Vec::new();
        let report = w.step_observed(&mut |stage| heard.push(stage));
        assert_eq!(heard, carom::Stage::ALL, "step {step} at rest");
        assert_eq!(report, plain.step(), "step {step} at rest");
        assert_eq!(w.checksum(), plain.checksum(), "step {step} at rest");
        assert_eq!(report.awake_bodies, 0);
    }
    assert_eq!(positions(&w), at_rest);
}
