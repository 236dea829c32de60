//! Broad phase, contact cache and events of the world, through the public API only.
//!
//! Oracles: an O(n²) loop over all body pairs with `collide::movement_bounds` and
//! `collide::contact` (the same stateless functions the step uses, so counts must match
//! exactly), and scenes whose events follow from simple kinematics.

use carom::collide::{contact, movement_bounds, Motion};
use carom::config::{reuse_slack, REUSE_SLACK};
use carom::rng::SplitMix64;
use carom::{
    BodyDesc, BodyHandle, BodyKind, ConvexHull, Event, Iso, Shape, StepTrace, Vec3, World,
    WorldConfig,
};

fn zero_gravity() -> WorldConfig {
    WorldConfig {
        gravity: Vec3::ZERO,
        ..WorldConfig::DEFAULT
    }
}

fn sphere(r: f32) -> Shape<'static> {
    Shape::sphere(r).unwrap()
}

/// A random convex shape: sphere, cuboid or capsule, 0.2 to 0.8 m.
fn random_shape(rng: &mut SplitMix64) -> Shape<'static> {
    match rng.next_u64() % 3 {
        0 => Shape::sphere(rng.range(0.2, 0.8)).unwrap(),
        1 => Shape::cuboid(Vec3::new(
            rng.range(0.2, 0.8),
            rng.range(0.2, 0.8),
            rng.range(0.2, 0.8),
        ))
        .unwrap(),
        _ => Shape::capsule(rng.range(0.1, 0.6), rng.range(0.2, 0.5)).unwrap(),
    }
}

/// What the broad phase and narrow phase must find for a world of bodies at rest, by
/// brute force: (pairs, contacts, points, touching pairs). A pair is two bodies that may
/// collide (one dynamic and awake) whose broad-phase boxes overlap: a moving body's box
/// is its movement bounds grown by the speculative margin and `aabb_margin`, a static
/// body's its exact box. A contact is a pair whose shapes are within `margin`.
fn brute_force<const B: usize, const C: usize, const E: usize>(
    world: &World<'_, B, C, E>,
    margin: impl Fn(&Shape<'_>, &Shape<'_>) -> f32,
) -> (usize, usize, usize, Vec<(BodyHandle, BodyHandle)>) {
    let cfg = *world.config();
    let handles: Vec<BodyHandle> = world.handles().collect();
    let bounds = |hd: BodyHandle| {
        let b = world.body(hd).unwrap();
        let moving = b.kind() != BodyKind::Static && b.is_awake();
        let motion = Motion {
            pose: b.pose(),
            // Velocity of the body origin: v + ω × (o − c).
            linear: b.linear_velocity()
                + b.angular_velocity()
                    .cross(b.position() - b.center_of_mass()),
            angular: b.angular_velocity(),
        };
        if moving {
            movement_bounds(&b.shape(), &motion, cfg.dt)
                .expanded(cfg.speculative_margin + cfg.aabb_margin)
        } else {
            b.shape().aabb(&b.pose())
        }
    };
    let (mut pairs, mut contacts, mut points) = (0, 0, 0);
    let mut touching = Vec::new();
    for (i, &hi) in handles.iter().enumerate() {
        for &hj in &handles[i + 1..] {
            let (a, b) = (world.body(hi).unwrap(), world.body(hj).unwrap());
            let some_dynamic = a.kind() == BodyKind::Dynamic || b.kind() == BodyKind::Dynamic;
            if !some_dynamic || !(a.is_awake() || b.is_awake()) || !bounds(hi).overlaps(&bounds(hj))
            {
                continue;
            }
            pairs += 1;
            let margin = margin(&a.shape(), &b.shape());
            let m = contact(&a.shape(), &a.pose(), &b.shape(), &b.pose(), margin).unwrap();
            if let Some(m) = m.filter(|m| !m.points().is_empty()) {
                contacts += 1;
                points += m.points().len();
                if m.min_separation() <= cfg.slop {
                    touching.push((hi, hj));
                }
            }
        }
    }
    (pairs, contacts, points, touching)
}

fn begins(events: &[Event]) -> Vec<(BodyHandle, BodyHandle)> {
    events
        .iter()
        .filter_map(|e| match *e {
            Event::ContactBegin { a, b } => Some((a, b)),
            _ => None,
        })
        .collect()
}

fn count(events: &[Event], pred: impl Fn(&Event) -> bool) -> usize {
    events.iter().filter(|e| pred(e)).count()
}

/// Random crowded scenes, no gravity, at rest: after one step, pair, contact and point
/// counts and the begin events equal the brute-force answer exactly (bodies at rest: the
/// narrow phase's margin is the speculative margin plus the pair's reuse slack). After a
/// second step (the solver has pushed overlapping bodies apart, so they move and
/// manifolds may be reused) every pair within the speculative margin still has its
/// manifold.
#[test]
fn pairs_and_contacts_match_brute_force() {
    match_brute_force(&[]);
}

/// The same with convex hulls among the shapes: a pair with a hull keeps points up to the
/// longer `HULL_REUSE_SLACK` beyond the speculative margin, the others one slop
/// ([`REUSE_SLACK`]); a single margin for all pairs gives other counts.
#[test]
fn hull_pairs_keep_points_within_the_longer_reuse_slack() {
    let hulls: Vec<ConvexHull> = (0..4u64)
        .map(|k| {
            let mut rng = SplitMix64::new(100 + k);
            let points: Vec<Vec3> = (0..12)
                .map(|_| rng.unit_vector() * rng.range(0.2, 0.6))
                .collect();
            ConvexHull::new(&points).unwrap()
        })
        .collect();
    let shapes: Vec<Shape<'_>> = hulls.iter().map(Shape::Hull).collect();
    match_brute_force(&shapes);
}

/// [`pairs_and_contacts_match_brute_force`] on worlds whose every fourth body (when
/// `extra` is not empty) takes one of the `extra` shapes.
fn match_brute_force(extra: &[Shape<'_>]) {
    let (mut hull_pairs_between_slacks, mut points_total) = (0, 0);
    for seed in 1..=6u64 {
        let mut rng = SplitMix64::new(seed);
        let mut world: World<48, 256, 256> = World::with_config(zero_gravity()).unwrap();
        for k in 0..40 {
            let shape = if !extra.is_empty() && k % 4 == 0 {
                extra[(k / 4) % extra.len()]
            } else {
                random_shape(&mut rng)
            };
            let p = Vec3::new(
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
                rng.range(-3.0, 3.0),
            );
            let desc = if rng.next_u64().is_multiple_of(4) {
                BodyDesc::fixed(shape)
            } else {
                BodyDesc::dynamic(shape)
            };
            world
                .add(desc.position(p).rotation(rng.rotation()))
                .unwrap();
        }
        let cfg = *world.config();
        let (pairs, contacts, points, touching) =
            brute_force(&world, |a, b| cfg.speculative_margin + reuse_slack(a, b));
        // Hull pairs whose points lie between the short and the long slack: what the
        // per-pair slack decides (the test would pass with one slack for all otherwise).
        let (_, short, _, _) = brute_force(&world, |_, _| cfg.speculative_margin + REUSE_SLACK);
        hull_pairs_between_slacks += contacts
            .checked_sub(short)
            .expect("a longer margin cannot find fewer contacts");
        points_total += points;
        let report = world.step();
        assert!(contacts > 5, "seed {seed}: scene too sparse to test");
        assert_eq!(report.pairs as usize, pairs, "seed {seed}");
        assert_eq!(world.pair_count(), pairs, "seed {seed}");
        assert_eq!(report.contacts as usize, contacts, "seed {seed}");
        assert_eq!(world.contact_count(), contacts, "seed {seed}");
        assert_eq!(report.points as usize, points, "seed {seed}");
        assert!(!report.overflowed(), "seed {seed}: {report:?}");
        // Every touching pair is new: one begin each, in (lower slot, higher slot) order.
        assert_eq!(begins(world.events()), touching, "seed {seed}");
        let (_, near, _, _) = brute_force(&world, |_, _| cfg.speculative_margin);
        let report = world.step();
        assert!(
            report.contacts as usize >= near,
            "seed {seed}: {} manifolds, {near} pairs within the margin",
            report.contacts
        );
        assert!(!report.overflowed(), "seed {seed}: {report:?}");
    }
    assert!(points_total > 0);
    if extra.is_empty() {
        assert_eq!(hull_pairs_between_slacks, 0);
    } else {
        assert!(
            hull_pairs_between_slacks > 0,
            "no hull pair lies between the two slacks: the test does not tell them apart"
        );
    }
}

/// Group/mask filtering, static-static and sleeping-sleeping pairs: three overlapping
/// spheres where only A-B may collide, two overlapping static boxes, and two overlapping
/// sleeping spheres.
#[test]
fn filters_decide_which_pairs_are_tested() {
    let mut world: World<16, 32> = World::with_config(zero_gravity()).unwrap();
    let a = world
        .add(BodyDesc::dynamic(sphere(0.5)).filter(0b001, 0b010))
        .unwrap();
    let b = world
        .add(
            BodyDesc::dynamic(sphere(0.5))
                .position(Vec3::new(0.5, 0.0, 0.0))
                .filter(0b010, 0b001),
        )
        .unwrap();
    // C sees everybody, but neither A nor B sees group 0b100.
    world
        .add(
            BodyDesc::dynamic(sphere(0.5))
                .position(Vec3::new(0.25, 0.5, 0.0))
                .filter(0b100, u32::MAX),
        )
        .unwrap();
    let cube = Shape::cuboid(Vec3::splat(1.0)).unwrap();
    world
        .add(BodyDesc::fixed(cube).position(Vec3::new(10.0, 0.0, 0.0)))
        .unwrap();
    world
        .add(BodyDesc::fixed(cube).position(Vec3::new(10.5, 0.0, 0.0)))
        .unwrap();
    let s1 = world
        .add(BodyDesc::dynamic(sphere(0.5)).position(Vec3::new(-10.0, 0.0, 0.0)))
        .unwrap();
    let s2 = world
        .add(BodyDesc::dynamic(sphere(0.5)).position(Vec3::new(-10.5, 0.0, 0.0)))
        .unwrap();
    world.sleep(s1).unwrap();
    world.sleep(s2).unwrap();
    let report = world.step();
    assert_eq!(report.pairs, 1);
    assert_eq!(world.contact_count(), 1);
    assert_eq!(begins(world.events()), vec![(a, b)]);
    // Waking one of the sleepers makes its pair count again.
    world.wake(s1).unwrap();
    let report = world.step();
    assert_eq!(report.pairs, 2);
    assert_eq!(begins(world.events()), vec![(s1, s2)]);
}

/// A ball dropped 1 m onto a box: one begin, one hit at about `√(2 g h)`, no end while it
/// rests (and sleeps) for 4 s; teleported away, one end event.
#[test]
fn landing_ball_begins_once_and_ends_when_lifted() {
    let mut world: World<8, 16> = World::new();
    let ground = world
        .add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
    let ball = world
        .add(BodyDesc::dynamic(sphere(0.5)).position(Vec3::new(0.0, 1.5, 0.0)))
        .unwrap();
    let mut all = Vec::new();
    for _ in 0..240 {
        world.step();
        all.extend_from_slice(world.events());
    }
    assert_eq!(begins(&all), vec![(ground, ball)]);
    assert_eq!(count(&all, |e| matches!(e, Event::ContactEnd { .. })), 0);
    let hits: Vec<f32> = all
        .iter()
        .filter_map(|e| match *e {
            Event::Hit {
                a,
                b,
                speed,
                normal,
                ..
            } => {
                assert_eq!((a, b), (ground, ball));
                assert!((normal - Vec3::Y).length() < 1e-4, "normal {normal:?}");
                Some(speed)
            }
            _ => None,
        })
        .collect();
    // √(2 · 9.81 · 1) = 4.43 m/s. The hit is measured up to one step (2 cm margin and
    // 7 cm of fall) early or late: ±0.3 m/s covers a step of gravity and the margin.
    assert_eq!(hits.len(), 1, "{hits:?}");
    assert!((hits[0] - 4.43).abs() < 0.3, "hit speed {}", hits[0]);
    let y = world.body(ball).unwrap().position().y;
    assert!((y - 0.5).abs() < 0.02, "ball rests at y = {y}");

    world
        .set_pose(ball, Iso::from_position(Vec3::new(0.0, 5.0, 0.0)))
        .unwrap();
    world.step();
    assert_eq!(world.events(), &[Event::ContactEnd { a: ground, b: ball }]);
    assert_eq!(world.contact_count(), 0);
}

/// A ball of radius 0.5 at height `y`, falling at 3 m/s.
fn add_falling_ball(world: &mut World<4, 8>, y: f32) -> BodyHandle {
    world
        .add(
            BodyDesc::dynamic(sphere(0.5))
                .position(Vec3::new(0.0, y, 0.0))
                .velocity(Vec3::new(0.0, -3.0, 0.0)),
        )
        .unwrap()
}

/// Step `world` 60 times and return the steps of the one `Hit` and the one
/// `ContactBegin` between `a` and `b` (any other event, or a second one, fails), the hit
/// at a closing speed of 3 m/s (`(v_a − v_b)·n = (0 − (−3))·n`: exact up to the f32
/// velocity). `each` runs after every step with its index.
fn one_hit_then_one_begin(
    world: &mut World<4, 8>,
    (a0, b0): (BodyHandle, BodyHandle),
    mut each: impl FnMut(&World<4, 8>, usize),
) -> (Option<usize>, Option<usize>) {
    let (mut hit_step, mut begin_step) = (None, None);
    for k in 0..60 {
        world.step();
        each(world, k);
        for e in world.events() {
            match *e {
                Event::Hit { a, b, speed, .. } => {
                    assert_eq!((a, b, hit_step), (a0, b0, None), "step {k}");
                    assert!((speed - 3.0).abs() < 1e-5, "speed {speed}");
                    hit_step = Some(k);
                }
                Event::ContactBegin { a, b } => {
                    assert_eq!((a, b, begin_step), (a0, b0, None), "step {k}");
                    begin_step = Some(k);
                }
                other => panic!("step {k}: unexpected {other:?}"),
            }
        }
    }
    (hit_step, begin_step)
}

/// Two balls, one fixed, the other closing at 3 m/s (5 cm per step, no gravity): a sphere
/// pair is measured afresh every step with the step's margin and no reuse slack
/// (`reuse_slack` is 0 for it), so its point appears at the first step that starts
/// within the speculative margin plus what the pair closes in a step (1 + 5 cm) and not
/// one step earlier at 6.3 cm, which one slop of slack would reach. One hit then, at
/// the full closing speed, then one begin.
#[test]
fn a_sphere_pair_appears_within_the_step_margin_and_reports_one_hit() {
    let mut world: World<4, 8> = World::with_config(zero_gravity()).unwrap();
    let fixed = world.add(BodyDesc::fixed(sphere(0.5))).unwrap();
    // Gaps at the start of each step: 0.213, 0.163, 0.113, 0.063, 0.013.
    let ball = add_falling_ball(&mut world, 1.213);
    let cfg = *world.config();
    let margin = cfg.speculative_margin + 3.0 * cfg.dt;
    assert_eq!(reuse_slack(&sphere(0.5), &sphere(0.5)), 0.0);
    // The step a margin with one slop of slack would find it, and the one this finds it.
    let with_slack = (0..5).find(|k| 0.213 - 0.05 * *k as f32 <= margin + REUSE_SLACK);
    let first = (0..5).find(|k| 0.213 - 0.05 * *k as f32 <= margin);
    assert_eq!((with_slack, first), (Some(3), Some(4)));
    let (hit_step, begin_step) = one_hit_then_one_begin(&mut world, (fixed, ball), |w, k| {
        if k == 3 {
            assert_eq!(w.contact_count(), 0, "no point yet");
        }
    });
    assert_eq!(hit_step, first, "the fifth step starts 1.3 cm apart");
    assert!(begin_step.is_some_and(|b| b > 4), "begin at {begin_step:?}");
    // It came to rest against the fixed ball, touching within the slop.
    let y = world.body(ball).unwrap().position().y;
    assert!((y - 1.0).abs() <= cfg.slop, "ball rests at y = {y}");
}

/// A ball at 3 m/s (5 cm per step, no gravity) whose contact first appears as a
/// speculative one: the narrow phase keeps points within the speculative margin plus
/// what the pair closes in a step plus the reuse slack (1 + 5 + 0.5 cm), so the manifold
/// appears at the step that starts 6 cm above the ground. The hit is reported then,
/// at the full 3 m/s, because the solver stops the ball before it touches. One hit, then
/// one begin when it touches, nothing more while it rests.
#[test]
fn hit_is_reported_when_a_speculative_contact_appears() {
    let mut world: World<4, 8> = World::with_config(zero_gravity()).unwrap();
    let ground = world
        .add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
    // Gaps at the start of each step: 0.21, 0.16, 0.11, 0.06, 0.01 (speculative).
    let ball = add_falling_ball(&mut world, 0.71);
    let (hit_step, begin_step) = one_hit_then_one_begin(&mut world, (ground, ball), |_, _| {});
    let cfg = *world.config();
    let reach = cfg.speculative_margin + 3.0 * cfg.dt + REUSE_SLACK;
    let first = (0..5).find(|k| 0.21 - 0.05 * *k as f32 <= reach);
    assert_eq!(first, Some(3));
    assert_eq!(
        hit_step, first,
        "the fourth step starts 6 cm above the ground"
    );
    assert!(begin_step.is_some_and(|b| b > 3), "begin at {begin_step:?}");
}

/// A ball moving at 3 m/s straight through a static sensor box: enter once, exactly at
/// the step it comes within the slop; leave once, at the step it is more than the slop
/// below; no contact events, and its path is bit-identical to the same ball in a world
/// without the sensor.
#[test]
fn sensor_reports_enter_and_leave_without_pushing() {
    let cfg = zero_gravity();
    let mut world: World<4, 8> = World::with_config(cfg).unwrap();
    let mut twin: World<4, 8> = World::with_config(cfg).unwrap();
    let sensor = world
        .add(BodyDesc::fixed(Shape::cuboid(Vec3::splat(1.0)).unwrap()).sensor(true))
        .unwrap();
    let desc = BodyDesc::dynamic(sphere(0.25))
        .position(Vec3::new(0.0, 3.0, 0.0))
        .velocity(Vec3::new(0.0, -3.0, 0.0));
    let ball = world.add(desc).unwrap();
    let twin_ball = twin.add(desc).unwrap();
    let (mut entered, mut left) = (None, None);
    for k in 0..120 {
        let y = world.body(ball).unwrap().position().y;
        world.step();
        twin.step();
        let (p, q) = (
            world.body(ball).unwrap().pose(),
            twin.body(twin_ball).unwrap().pose(),
        );
        assert_eq!(p, q, "step {k}: the sensor pushed the ball");
        for e in world.events() {
            match *e {
                Event::SensorEnter { sensor: s, other } => {
                    assert_eq!((s, other, entered), (sensor, ball, None));
                    entered = Some(y);
                }
                Event::SensorLeave { sensor: s, other } => {
                    assert_eq!((s, other, left), (sensor, ball, None));
                    assert!(entered.is_some());
                    left = Some(y);
                }
                other => panic!("unexpected event {other:?}"),
            }
        }
        // Touching means a gap of at most the slop: above, `y − 0.25 − 1 <= slop`; below,
        // `−1 − (y + 0.25) <= slop`. Positions are 5 cm apart, so a step is never
        // borderline.
        let touching_now = y - 1.25 <= cfg.slop && -1.25 - y <= cfg.slop;
        assert_eq!(
            entered.is_some() && left.is_none(),
            touching_now,
            "step {k}, y = {y}"
        );
    }
    assert!(entered.is_some() && left.is_some());
}

/// Three events fit a queue of 2: the first two in pair order are kept, one is counted.
#[test]
fn event_overflow_is_counted_and_the_world_goes_on() {
    let mut world: World<8, 16, 2> = World::with_config(zero_gravity()).unwrap();
    let ground = world
        .add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
    let balls: Vec<BodyHandle> = (0..5)
        .map(|i| {
            let p = Vec3::new(2.0 * i as f32, 0.49, 0.0); // 1 cm deep
            world
                .add(BodyDesc::dynamic(sphere(0.5)).position(p))
                .unwrap()
        })
        .collect();
    let report = world.step();
    assert_eq!(report.contacts, 5);
    assert_eq!(report.dropped_events, 3);
    assert!(report.overflowed());
    assert_eq!(
        world.events(),
        &[
            Event::ContactBegin {
                a: ground,
                b: balls[0]
            },
            Event::ContactBegin {
                a: ground,
                b: balls[1]
            },
        ]
    );
    for _ in 0..60 {
        let r = world.step();
        assert_eq!(r.contacts, 5);
    }
}

/// Eight balls on a box with room for 4 pairs: the four with the smallest keys
/// `(ground, ball)` are kept and four are counted in the first step; from then on the
/// pool is full, and the four others are offered again every step and counted as
/// contacts that did not fit. No panic, and the same four contacts every step.
#[test]
fn pair_overflow_keeps_smallest_keys() {
    let mut world: World<16, 4, 16> = World::with_config(zero_gravity()).unwrap();
    let ground = world
        .add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(20.0, 0.5, 20.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
    // Added right to left, so slot order and order along x disagree.
    let balls: Vec<BodyHandle> = (0..8)
        .map(|i| {
            let p = Vec3::new(14.0 - 2.0 * i as f32, 0.49, 0.0);
            world
                .add(BodyDesc::dynamic(sphere(0.5)).position(p))
                .unwrap()
        })
        .collect();
    for step in 0..30 {
        let report = world.step();
        let dropped = if step == 0 { (4, 0) } else { (0, 4) };
        assert_eq!(report.pairs, 4, "step {step}");
        assert_eq!(
            (report.dropped_pairs, report.dropped_contacts),
            dropped,
            "step {step}"
        );
        assert_eq!(world.contact_count(), 4);
        if step == 0 {
            // The four lowest slots: the rightmost balls, added first.
            let expected: Vec<_> = balls[..4].iter().map(|&b| (ground, b)).collect();
            assert_eq!(begins(world.events()), expected);
        }
    }
}

/// Contacts kept for sleeping bodies plus new pairs overflow the contact pool: the
/// sleeping contacts stay, the new pair with the lower key gets the last place, the
/// other is counted; the pair that did not fit sends no begin event.
#[test]
fn contact_overflow_is_counted_and_sleeping_contacts_survive() {
    let mut world: World<16, 4, 16> = World::with_config(zero_gravity()).unwrap();
    let ground = world
        .add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(20.0, 0.5, 20.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
    let ball_at = |x: f32| BodyDesc::dynamic(sphere(0.5)).position(Vec3::new(x, 0.49, 0.0));
    let sleepers: Vec<BodyHandle> = (0..3)
        .map(|i| world.add(ball_at(2.0 * i as f32)).unwrap())
        .collect();
    world.step();
    assert_eq!(world.contact_count(), 3);
    for &s in &sleepers {
        world.sleep(s).unwrap();
    }
    let late = world.add(ball_at(10.0)).unwrap();
    world.add(ball_at(12.0)).unwrap();
    let report = world.step();
    assert_eq!(report.pairs, 1, "sleeping-static pairs are not tested");
    assert_eq!(report.contacts, 4);
    assert_eq!(report.dropped_contacts, 1);
    assert_eq!(
        world.events(),
        &[Event::ContactBegin { a: ground, b: late }]
    );
    for _ in 0..60 {
        world.step();
    }
    assert!(world.contact_count() <= 4);
}

/// The pairs a step finds do not depend on the shape of the broad-phase tree, overflow
/// included: a world whose tree grew with its history and a world restored from its
/// snapshot (whose tree is built again in slot order) find the same pairs, drop the same
/// ones when the pair buffer overflows, and stay bit-identical. The trace's broad-phase
/// digest covers the step's pair list.
#[test]
fn pairs_and_overflow_do_not_depend_on_the_tree() {
    type Small = World<'static, 64, 24, 64>;
    let mut a: Box<Small> = Box::new(World::new());
    a.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(20.0, 0.5, 20.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )
    .unwrap();
    let mut rng = SplitMix64::new(17);
    let mut balls = Vec::new();
    for i in 0..40 {
        let p = Vec3::new(
            (i % 4) as f32 * 0.9 + rng.range(-0.1, 0.1),
            0.5 + (i / 16) as f32 * 0.9,
            ((i / 4) % 4) as f32 * 0.9 + rng.range(-0.1, 0.1),
        );
        balls.push(
            a.add(BodyDesc::dynamic(random_shape(&mut rng)).position(p))
                .unwrap(),
        );
    }
    // A history for the tree: steps, a body removed, bodies teleported and added.
    for k in 0..20 {
        a.step();
        if k == 5 {
            a.remove(balls[7]).unwrap();
            let p = Iso::from_position(Vec3::new(0.5, 4.0, 0.5));
            a.set_pose(balls[20], p).unwrap();
        }
        if k == 9 {
            a.add(BodyDesc::dynamic(sphere(0.4)).position(Vec3::new(1.0, 5.0, 1.0)))
                .unwrap();
        }
    }
    let mut buf = vec![0u8; Small::max_snapshot_len()];
    let n = a.snapshot(&mut buf).unwrap();
    let mut b: Box<Small> = Box::new(World::new());
    b.restore(&buf[..n]).unwrap();
    assert_eq!(a.checksum(), b.checksum());
    let mut overflowing = 0;
    for step in 0..90 {
        let (mut ta, mut tb) = (StepTrace::default(), StepTrace::default());
        let ra = a.step_traced(Some(&mut ta));
        let rb = b.step_traced(Some(&mut tb));
        assert_eq!(ra, rb, "step {step}");
        assert_eq!(ta.first_difference(&tb), None, "step {step}");
        assert_eq!(a.events(), b.events(), "step {step}");
        assert_eq!(a.checksum(), b.checksum(), "step {step}");
        if ra.dropped_pairs > 0 {
            overflowing += 1;
        }
    }
    assert!(
        overflowing >= 3,
        "pair buffer overflowed in {overflowing} steps"
    );
}
