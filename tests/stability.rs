//! The dynamics core's acceptance scenarios: stacks that stand, bounces that do not gain
//! energy, bounded push-out, rolling and twist resistance, and sleep that follows what a
//! body rests on. Public API only; each bound says where it comes from.

use carom::{BodyDesc, BodyHandle, Iso, Material, Shape, Vec3, World, WorldConfig};

const G: f32 = 9.81;

/// Timing-style configuration: sleeping off, so nothing hides behind a sleeping body.
fn awake() -> WorldConfig {
    WorldConfig {
        sleep_enabled: false,
        ..WorldConfig::DEFAULT
    }
}

/// Run `f` on a thread with a big stack (worlds are inline).
fn big_stack<T: Send + 'static>(f: impl FnOnce() -> T + Send + 'static) -> T {
    std::thread::Builder::new()
        .stack_size(256 << 20)
        .spawn(f)
        .unwrap()
        .join()
        .unwrap()
}

fn ground<const B: usize, const C: usize>(w: &mut World<'_, B, C>) -> BodyHandle {
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(50.0, 0.5, 50.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )
    .unwrap()
}

/// A wall pyramid of boxes of half-extent `h` (the SCENES.md layout scaled), base
/// `base`; the top box gets `top_density`. Returns the top box.
fn pyramid<const B: usize, const C: usize>(
    w: &mut World<'_, B, C>,
    base: u32,
    h: f32,
    top_density: f32,
) -> BodyHandle {
    ground(w);
    let cube = Shape::cuboid(Vec3::splat(h)).unwrap();
    let mut top = None;
    for i in 0..base {
        for j in i..base {
            let x = (i + 1) as f32 * h + 2.0 * (j - i) as f32 * h - h * base as f32;
            let y = (2 * i + 1) as f32 * h;
            let density = if i + 1 == base { top_density } else { 1000.0 };
            top = Some(
                w.add(
                    BodyDesc::dynamic(cube)
                        .position(Vec3::new(x, y, 0.0))
                        .density(density),
                )
                .unwrap(),
            );
        }
    }
    top.unwrap()
}

/// SCENES.md pyramid20, sleeping off, 500 steps: the top box moves at most 3 mm out of
/// its place sideways (x and z; the bound, rapier3d's figure) and sinks less
/// than 3 cm.
#[test]
fn pyramid20_top_stays_within_3_mm() {
    let (sideways, sink) = big_stack(|| {
        let mut w: Box<World<256, 1024>> = Box::new(World::with_config(awake()).unwrap());
        let top = carom::scenes::pyramid(&mut w, 20).unwrap();
        let start = w.body(top).unwrap().position();
        for _ in 0..500 {
            let r = w.step();
            assert!(r.dropped_pairs == 0 && r.dropped_contacts == 0, "{r:?}");
        }
        let d = w.body(top).unwrap().position() - start;
        (Vec3::new(d.x, 0.0, d.z).length(), -d.y)
    });
    eprintln!("pyramid20: sideways {sideways} m, sink {sink} m");
    assert!(sideways <= 0.003, "sideways {sideways}");
    assert!((0.0..0.03).contains(&sink), "sink {sink}");
}

/// A tower of `n` unit boxes on the ground, sleeping off, run `steps` steps: the
/// farthest its top box got from the tower's axis (m) and the top box's final height.
fn tower(n: usize, steps: u32) -> (f32, f32) {
    big_stack(move || {
        let mut w: Box<World<64, 256>> = Box::new(World::with_config(awake()).unwrap());
        ground(&mut w);
        let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
        let mut top = None;
        for i in 0..n {
            top = Some(
                w.add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, 0.5 + i as f32, 0.0)))
                    .unwrap(),
            );
        }
        let top = top.unwrap();
        let mut farthest = 0.0f32;
        for _ in 0..steps {
            w.step();
            let p = w.body(top).unwrap().position();
            farthest = farthest.max(Vec3::new(p.x, 0.0, p.z).length());
        }
        (farthest, w.body(top).unwrap().position().y)
    })
}

/// [`tower`] of `n` boxes for 20 s: its top never farther than `sway` (m) from the axis,
/// and finally above `height` (m).
fn tower_stands(n: usize, sway: f32, height: f32) {
    let (farthest, top) = tower(n, 1200);
    eprintln!("tower of {n}: farthest {farthest} m, top at {top} m");
    assert!(farthest < sway, "farthest {farthest}");
    assert!(top > height, "top at {top}");
}

/// A tower of 20 unit boxes, sleeping off, stands 20 s: its top never leaves its
/// column by 3 cm (2.1 cm here; rapier3d's sways 2.5 cm) and stays above 19.4 m (soft
/// contacts sag: 20 contacts at 45 Hz about 5 cm, `m g / (m_eff ω²)` each).
#[test]
fn tower_of_twenty_boxes_stands_twenty_seconds() {
    tower_stands(20, 0.03, 19.4);
}

/// A tower of 40 unit boxes stands 20 s: its top stays within 8 cm of its column (6.8
/// cm here, rapier3d's 5.2 cm) and sags less than 50 cm (19 cm here; rapier3d's sags 43
/// cm). With lever arms that turned with the boxes (`dynamics::contact`, "Lever arms
/// kept from the build") a tower of 22 leaned over and fell within 20 s.
#[test]
fn tower_of_forty_boxes_stands_twenty_seconds() {
    tower_stands(40, 0.08, 39.0);
}

/// A box `ratio` times as dense as five unit boxes stacked under it, run 600 steps with
/// `cfg`: the heavy box's final position and the lowest height it reached.
fn heavy_on_five_boxes(cfg: WorldConfig, ratio: f32) -> (Vec3, f32) {
    let mut w: World<16, 64> = World::with_config(cfg).unwrap();
    ground(&mut w);
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    for i in 0..5 {
        w.add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, 0.5 + i as f32, 0.0)))
            .unwrap();
    }
    let heavy = w
        .add(
            BodyDesc::dynamic(cube)
                .position(Vec3::new(0.0, 5.5, 0.0))
                .density(1000.0 * ratio),
        )
        .unwrap();
    let mut lowest = f32::INFINITY;
    for _ in 0..600 {
        w.step();
        lowest = lowest.min(w.body(heavy).unwrap().position().y);
    }
    (w.body(heavy).unwrap().position(), lowest)
}

/// Run [`heavy_on_five_boxes`] at density `ratio` with `cfg` and check that the heavy
/// box sank less than `sink` (m) at its deepest and ends within `aside` (m) of its
/// place sideways; returns how far it sank.
fn column_holds(cfg: WorldConfig, ratio: f32, sink: f32, aside: f32) -> f32 {
    let (p, lowest) = heavy_on_five_boxes(cfg, ratio);
    eprintln!("1:{ratio} on five boxes: heavy box at {p:?}, lowest {lowest}");
    assert!(5.5 - lowest < sink, "1:{ratio} sank to {lowest}");
    let slid = Vec3::new(p.x, 0.0, p.z).length();
    assert!(slid < aside, "1:{ratio} slid to {p:?}");
    5.5 - lowest
}

/// A box 1000 times as dense as the five unit boxes it stands on: the stack does not
/// collapse under it, and the heavy box sinks less than 5 cm below the rigid height.
///
/// The contact under the heavy box sees a mass ratio capped at 20 (`dynamics/support.rs`):
/// the column carries what a box 20 times as dense would put on it. Without that, an iterative
/// solve passes about `m_light · v_closing` of impulse down the column per visit, a
/// thousandth of what holding the heavy box takes: it fell at nearly g, pressed the
/// column together (0.5 m by step 25) and buckled it before step 50; stiffer contacts,
/// a higher push-out bound or unbounded warm starts did not help.
#[test]
fn heavy_box_on_five_boxes_sinks_under_5_cm() {
    column_holds(awake(), 1000.0, 0.05, 0.01);
}

/// Just under the capped ratio (`support::HEAVY_RATIO`, 20) the column holds as it is: a
/// box 19 times as dense as the five boxes under it sinks under 5 cm (about 3 cm: the
/// soft contacts' sag grows with the load) and stays within 5 mm of its place sideways.
/// (Uncapped, 1:30 sinks 4.5 cm, 1:50 8 cm, and 1:100 topples: the cap makes every
/// heavier box load the column like a 1:20 one.)
#[test]
fn heavy_box_just_under_the_capped_ratio_holds_uncapped() {
    column_holds(awake(), 19.0, 0.05, 0.005);
}

/// The same column under a box 100 times as dense stands straight. (Before the capped
/// ratio it sank 11 cm and buckled sideways, every box tilting the same way a little
/// more each step, and fell near step 400; rapier3d 0.36.1 holds it with 26 cm sunk
/// and 2 cm sideways.)
#[test]
fn heavy_box_100_times_as_dense_on_five_boxes_stands() {
    column_holds(awake(), 100.0, 0.05, 0.01);
}

/// Without the capped ratio the same column holds with stiffer contacts and more
/// sub-steps (32 sub-steps of 1/1920 s, contacts at 480 Hz, which the
/// quarter-of-the-sub-step-rate cap allows): the soft sag falls with `1 / ω²`. The
/// configuration knobs still work where the shortcut is not wanted.
#[test]
fn heavy_box_on_five_boxes_holds_with_32_substeps_and_480_hz_contacts() {
    let cfg = WorldConfig {
        substeps: 32,
        contact_hertz: 480.0,
        ..awake()
    };
    column_holds(cfg, 1000.0, 0.025, 0.01);
}

/// A light ball thrown up from the ground into a box 1000 times as heavy resting on it
/// bounces off the box rather than lifting it: the ratio is capped only for a support at
/// rest (`RESTING_RISE`). Capped, the box would take 1/21 of the ball's 5 m/s (0.24
/// m/s); as it is, the ball's momentum moves it by `2 m v / M`, 4e-5 m/s; the bound
/// leaves room for the push-out of the box settling onto the ball (about 0.04 m/s).
#[test]
fn a_light_ball_thrown_up_into_a_heavy_box_does_not_lift_it() {
    let mut w: World<8, 32> = World::with_config(awake()).unwrap();
    ground(&mut w);
    w.add(
        BodyDesc::dynamic(Shape::sphere(0.1).unwrap())
            .position(Vec3::new(0.0, 0.1005, 0.0))
            .velocity(Vec3::new(0.0, 5.0, 0.0)),
    )
    .unwrap();
    let heavy = w
        .add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.5)).unwrap())
                .position(Vec3::new(0.0, 0.702, 0.0))
                .density(1.0e6),
        )
        .unwrap();
    let mut fastest = 0.0f32;
    for _ in 0..3 {
        w.step();
        fastest = fastest.max(w.body(heavy).unwrap().linear_velocity().y);
    }
    eprintln!("heavy box rose at up to {fastest} m/s");
    assert!(fastest < 0.1, "box rose at {fastest}");
}

/// A 10-level wall pyramid under a top box 300 times as dense (Box2D's high mass ratio
/// range) stands: the heavy top stays within 5 cm of its place sideways and sinks less
/// than 10 cm.
#[test]
fn pyramid10_under_a_300_times_heavier_box_stands() {
    let (sideways, sink) = big_stack(|| {
        let mut w: Box<World<64, 256>> = Box::new(World::with_config(awake()).unwrap());
        let top = pyramid(&mut w, 10, 0.5, 300_000.0);
        let start = w.body(top).unwrap().position();
        for _ in 0..600 {
            w.step();
        }
        let d = w.body(top).unwrap().position() - start;
        (Vec3::new(d.x, 0.0, d.z).length(), -d.y)
    });
    eprintln!("pyramid10 with 1:300 top: sideways {sideways} m, sink {sink} m");
    assert!(sideways < 0.05, "sideways {sideways}");
    assert!(sink < 0.10, "sink {sink}");
}

/// A wall pyramid of 5 cm boxes (inside the documented size range) stands: the top
/// moves less than a fifth of its box sideways in 10 s. (Soft contacts sag by an
/// absolute `load / (m ω²)`, the same for every box size, so smaller boxes are relatively
/// softer: 2.5 cm boxes drift by half a box.)
#[test]
fn small_box_pyramids_stand() {
    let h = 0.025f32;
    let sideways = big_stack(move || {
        let mut w: Box<World<64, 256>> = Box::new(World::with_config(awake()).unwrap());
        let top = pyramid(&mut w, 10, h, 1000.0);
        let start = w.body(top).unwrap().position();
        for _ in 0..600 {
            w.step();
        }
        let d = w.body(top).unwrap().position() - start;
        Vec3::new(d.x, 0.0, d.z).length()
    });
    eprintln!("pyramid10 of {} m boxes: sideways {sideways} m", 2.0 * h);
    assert!(sideways < 0.2 * 2.0 * h, "boxes of {h}: {sideways}");
}

/// A frictionless ball dropped from `height` (its lowest point) with restitution `e`:
/// the apexes of its first `bounces` bounces (lowest point above the ground).
fn bounce_apexes(e: f32, height: f32, bounces: usize) -> Vec<f32> {
    let mut w: World<4, 16> = World::with_config(awake()).unwrap();
    let m = Material {
        restitution: e,
        static_friction: 0.0,
        kinetic_friction: 0.0,
        rolling_resistance: 0.0,
        twist_friction: 0.0,
    };
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0))
            .material(m),
    )
    .unwrap();
    let r = 0.5;
    let ball = w
        .add(
            BodyDesc::dynamic(Shape::sphere(r).unwrap())
                .position(Vec3::new(0.0, height + r, 0.0))
                .material(m),
        )
        .unwrap();
    let mut apexes = Vec::new();
    let mut rising = false;
    let mut top = f32::MIN;
    for _ in 0..60 * 60 {
        w.step();
        let b = w.body(ball).unwrap();
        let (y, vy) = (b.position().y - r, b.linear_velocity().y);
        if vy > 0.0 {
            rising = true;
            top = top.max(y);
        } else if rising {
            rising = false;
            apexes.push(top.max(y));
            top = f32::MIN;
            if apexes.len() == bounces {
                break;
            }
        }
    }
    apexes
}

/// An elastic ball (e = 1) dropped from 10 m never rises above 10 m, over 20 bounces,
/// and keeps bouncing: each bounce loses less than 1 % (the integrator's own loss, about
/// `g h v` per reflection at a sub-step boundary: 0.6 % from 10 m).
#[test]
fn elastic_ball_never_rises_above_its_drop_height() {
    let apexes = bounce_apexes(1.0, 10.0, 20);
    eprintln!("e = 1 apexes: {apexes:?}");
    assert!(apexes.len() >= 10, "stopped bouncing: {apexes:?}");
    let mut previous = 10.0f32;
    for a in &apexes {
        assert!(*a <= previous, "rose to {a} after {previous}");
        assert!(*a > 0.99 * previous, "lost height: {a} after {previous}");
        previous = *a;
    }
}

/// With e = 0.9 each apex is 0.81 of the one before (energy ∝ height, speed ∝ e), within
/// 2 %, over the first bounces (before the speeds reach the restitution threshold).
#[test]
fn apex_ratio_is_e_squared() {
    let apexes = bounce_apexes(0.9, 10.0, 6);
    eprintln!("e = 0.9 apexes: {apexes:?}");
    assert!(apexes.len() == 6, "{apexes:?}");
    let mut previous = 10.0f32;
    for a in apexes {
        let ratio = a / previous;
        assert!((ratio - 0.81).abs() <= 0.02 * 0.81, "ratio {ratio}");
        previous = a;
    }
}

/// Two boxes created overlapping by half their size separate no faster than the
/// documented push-out bound (`max_push_speed`, 3 m/s; 5 % over for the one step in which
/// soft and rigid rows meet).
#[test]
fn overlap_recovery_is_bounded_by_the_push_out_speed() {
    let cfg = WorldConfig {
        gravity: Vec3::ZERO,
        ..awake()
    };
    let mut w: World<4, 16> = World::with_config(cfg).unwrap();
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let a = w
        .add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, 0.0, 0.0)))
        .unwrap();
    let b = w
        .add(BodyDesc::dynamic(cube).position(Vec3::new(0.5, 0.0, 0.0)))
        .unwrap();
    let mut fastest = 0.0f32;
    for _ in 0..120 {
        w.step();
        let dv = w.body(b).unwrap().linear_velocity() - w.body(a).unwrap().linear_velocity();
        fastest = fastest.max(dv.length());
    }
    let gap = w.body(b).unwrap().position().x - w.body(a).unwrap().position().x;
    eprintln!("overlap recovery: fastest relative speed {fastest} m/s, final distance {gap}");
    assert!(fastest <= 1.05 * cfg.max_push_speed, "{fastest} m/s");
    assert!(gap > 0.99, "still overlapping: {gap}");
}

/// Sixteen boxes created at the same pose on a 1 m thick ground: the pile sorts itself
/// out and none passes through the ground.
#[test]
fn coincident_spawns_never_pass_through_the_ground() {
    let mut w: World<32, 256> = World::with_config(awake()).unwrap();
    ground(&mut w);
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let boxes: Vec<_> = (0..16)
        .map(|_| {
            w.add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, 0.5, 0.0)))
                .unwrap()
        })
        .collect();
    let mut lowest = f32::MAX;
    for _ in 0..300 {
        w.step();
        for &b in &boxes {
            lowest = lowest.min(w.body(b).unwrap().position().y);
        }
    }
    eprintln!("coincident spawns: lowest centre {lowest} m");
    // The ground's top is y = 0; a box centre below −0.5 would be inside or under it.
    assert!(lowest > 0.0, "a box went into the ground: {lowest}");
}

/// A ball rolling on flat ground with rolling resistance `c_rr` decelerates at
/// `c_rr · g / (1 + I/(m r²))`: with I = 2/5 m r², `a = c_rr g / 1.4` (torque `c_rr N r`
/// about the contact). Within 15 %.
#[test]
fn rolling_resistance_decelerates_a_rolling_ball() {
    let mut w: World<4, 16> = World::with_config(awake()).unwrap();
    let m = Material {
        rolling_resistance: 0.05,
        ..Material::DEFAULT
    };
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(50.0, 0.5, 50.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0))
            .material(m),
    )
    .unwrap();
    let r = 0.5;
    let ball = w
        .add(
            BodyDesc::dynamic(Shape::sphere(r).unwrap())
                .position(Vec3::new(-20.0, r, 0.0))
                .velocity(Vec3::new(3.0, 0.0, 0.0))
                .angular_velocity(Vec3::new(0.0, 0.0, -3.0 / r))
                .material(m),
        )
        .unwrap();
    for _ in 0..30 {
        w.step();
    }
    let v0 = w.body(ball).unwrap().linear_velocity().x;
    for _ in 0..60 {
        w.step();
    }
    let v1 = w.body(ball).unwrap().linear_velocity().x;
    let decel = (v0 - v1) / 1.0;
    let want = 0.05 * G / 1.4;
    eprintln!("rolling: deceleration {decel} m/s², want {want}");
    assert!((decel - want).abs() < 0.15 * want, "{decel} vs {want}");
}

/// A ball spinning about the vertical on the ground stops (twist friction), where it
/// would spin for ever without: it comes to rest and sleeps.
#[test]
fn twist_friction_stops_a_spinning_ball_and_it_sleeps() {
    let mut w: World<4, 16> = World::new();
    ground(&mut w);
    let ball = w
        .add(
            BodyDesc::dynamic(Shape::sphere(0.5).unwrap())
                .position(Vec3::new(0.0, 0.5, 0.0))
                .angular_velocity(Vec3::new(0.0, 5.0, 0.0)),
        )
        .unwrap();
    for _ in 0..60 * 20 {
        w.step();
    }
    let b = w.body(ball).unwrap();
    eprintln!(
        "spinning ball: ω {:?}, awake {}",
        b.angular_velocity(),
        b.is_awake()
    );
    assert!(
        !b.is_awake(),
        "still spinning at {:?}",
        b.angular_velocity()
    );
}

/// A box asleep on another wakes and falls when the one below is removed, when it is
/// moved away, and when the static body under a box is moved away.
#[test]
fn sleepers_wake_when_their_support_goes() {
    for case in 0..3 {
        let mut w: World<8, 32> = World::new();
        let g = ground(&mut w);
        let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
        let lower = if case < 2 {
            Some(
                w.add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, 0.5, 0.0)))
                    .unwrap(),
            )
        } else {
            None
        };
        let top_y = if case < 2 { 1.5 } else { 0.5 };
        let top = w
            .add(BodyDesc::dynamic(cube).position(Vec3::new(0.0, top_y, 0.0)))
            .unwrap();
        for _ in 0..240 {
            w.step();
        }
        assert!(!w.body(top).unwrap().is_awake(), "case {case}: never slept");
        match (case, lower) {
            (0, Some(l)) => w.remove(l).unwrap(),
            (1, Some(l)) => w
                .set_pose(l, Iso::from_position(Vec3::new(10.0, 0.5, 0.0)))
                .unwrap(),
            _ => w
                .set_pose(g, Iso::from_position(Vec3::new(200.0, -0.5, 0.0)))
                .unwrap(),
        }
        let before = w.body(top).unwrap().position().y;
        for _ in 0..30 {
            w.step();
        }
        let after = w.body(top).unwrap().position().y;
        eprintln!("case {case}: top from {before} to {after}");
        assert!(after < before - 0.5, "case {case}: stayed at {after}");
    }
}

/// A block of boxes dropped as a grid (the `boxes` scene, 5×5×6 instead of 10×10×10),
/// box `i` of density `density(i)`: the energy gained after the low, what pushing out the
/// crash's overlaps may give (`m g` times 6 cm per box), the highest any box rose and the
/// block's top at the drop.
fn crash_block(density: fn(usize) -> f32) -> (f64, f64, f32, f32) {
    big_stack(move || {
        let mut w: Box<World<'static, 256, 2048>> = Box::new(World::new());
        w.set_config(awake()).unwrap();
        ground(&mut w);
        let mut rng = carom::rng::SplitMix64::new(11);
        let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
        let mut boxes = Vec::new();
        for y in 0..6 {
            for z in 0..5 {
                for x in 0..5 {
                    let p = Vec3::new(
                        (x as f32 - 2.0) * 1.2 + rng.range(-0.1, 0.1),
                        2.0 + y as f32 * 1.2,
                        (z as f32 - 2.0) * 1.2 + rng.range(-0.1, 0.1),
                    );
                    let d = density(boxes.len());
                    let b = BodyDesc::dynamic(cube).position(p).density(d);
                    boxes.push(w.add(b).unwrap());
                }
            }
        }
        let top0 = 2.0 + 5.0 * 1.2;
        let energy = |w: &World<'static, 256, 2048>| -> f64 {
            boxes
                .iter()
                .map(|&h| {
                    let b = w.body(h).unwrap();
                    f64::from(b.kinetic_energy()) + f64::from(b.mass() * G * b.position().y)
                })
                .sum()
        };
        let (mut lowest, mut highest) = (f64::MAX, 0.0f32);
        let mut worst_gain = 0.0f64;
        for _ in 0..300 {
            w.step();
            let e = energy(&w);
            lowest = lowest.min(e);
            worst_gain = worst_gain.max(e - lowest);
            for &h in &boxes {
                highest = highest.max(w.body(h).unwrap().position().y);
            }
        }
        // Pushing the crash's overlaps out may lift each box by a few centimetres: 6 cm
        // each (4.5 cm measured; 9.6 cm with the 3 m/s push-out and 5 cm projections).
        let allowed: f64 = boxes
            .iter()
            .map(|&h| f64::from(w.body(h).unwrap().mass() * G) * 0.06)
            .sum();
        (worst_gain, allowed, highest, top0)
    })
}

/// The block of equal boxes crashes into a pile: without restitution nothing may come
/// out of the crash faster than it went in. The total energy (kinetic plus `m g y`)
/// after the block landed may rise only by the potential energy of pushing the
/// remaining overlaps out, and no box may rise more than 0.5 m above the highest point
/// of the block's drop. With a 3 m/s push-out and 5 cm projections, the full 10×10×10
/// pile gained 4.4 MJ (9 % of its energy) and launched a box 7 m up.
#[test]
fn a_crashing_block_of_boxes_gains_no_energy() {
    crash_gains_no_energy(|_| 1000.0);
}

/// [`crash_block`] with `density`, checked: the energy rose less than the push-out
/// allowance after its low, and no box rose 0.5 m above the block's top at the drop.
fn crash_gains_no_energy(density: fn(usize) -> f32) {
    let (gain, allowed, highest, top0) = crash_block(density);
    eprintln!("crash: energy rose {gain:.0} J, allowed {allowed:.0} J, top {highest}");
    assert!(
        gain < allowed,
        "energy rose {gain:.0} J (allowed {allowed:.0} J)"
    );
    assert!(
        highest < top0 + 0.5,
        "a box reached y = {highest} (from {top0})"
    );
}

/// The same crash with every third box 50 times as dense, so heavy boxes land on light
/// ones and rest on them through capped contacts (`dynamics/support.rs`): the cap must
/// not feed energy into the pile either. (With an infinite mass for the support, a
/// one-way contact, a heavy box took the speed of a light one squeezed up under it and
/// flew 1.8 m above the drop; capped, the pile gains 0.13 MJ after its low, uncapped 2.6
/// MJ, as heavy boxes push the light ones they land on out of the way.)
#[test]
fn a_crashing_block_of_heavy_and_light_boxes_gains_no_energy() {
    crash_gains_no_energy(|i| if i % 3 == 0 { 50_000.0 } else { 1000.0 });
}

/// A column of ten unit boxes dropped as in the `boxes` scene (1.2 m apart, lowest at
/// y = 2, jitter ±0.1 m in x and z): the boxes land on each other one by one at 5–8 m/s
/// and the column stands. Before the separating axis test preferred faces to slightly
/// shallower edge pairs (`carom::collide::EDGE_DEPTH_PREFERENCE`), half the contacts of
/// two slightly tilted, offset boxes had one point: the second box pivoted on it, sank
/// 0.59 m into the first, and the column toppled (the `boxes` scene never slept).
#[test]
fn a_dropped_column_of_offset_boxes_lands_and_stands() {
    let mut w: World<16, 64> = World::with_config(awake()).unwrap();
    ground(&mut w);
    let cube = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let mut rng = carom::rng::SplitMix64::new(1);
    let boxes: Vec<BodyHandle> = (0..10)
        .map(|i| {
            let p = Vec3::new(
                rng.range(-0.1, 0.1),
                2.0 + 1.2 * i as f32,
                rng.range(-0.1, 0.1),
            );
            w.add(BodyDesc::dynamic(cube).position(p)).unwrap()
        })
        .collect();
    let start: Vec<Vec3> = boxes
        .iter()
        .map(|h| w.body(*h).unwrap().position())
        .collect();
    let mut deepest = 0.0f32;
    for _ in 0..300 {
        w.step();
        let ys: Vec<f32> = boxes
            .iter()
            .map(|h| w.body(*h).unwrap().position().y)
            .collect();
        for pair in ys.windows(2) {
            deepest = deepest.min(pair[1] - pair[0] - 1.0);
        }
    }
    eprintln!("dropped column: deepest overlap between neighbours {deepest} m");
    // Landing at up to 8 m/s the soft contacts give way for a moment, but not by more
    // than a tenth of a box (it was 0.59 m).
    assert!(deepest > -0.1, "neighbours overlapped by {deepest} m");
    for (h, p0) in boxes.iter().zip(&start) {
        let p = w.body(*h).unwrap().position();
        let sideways = Vec3::new(p.x - p0.x, 0.0, p.z - p0.z).length();
        assert!(sideways < 0.5, "a box moved {sideways} m sideways: {p:?}");
    }
    let top = w.body(boxes[9]).unwrap().position();
    assert!((top.y - 9.5).abs() < 0.03, "top at {top:?}, rests at 9.5");
}

/// The `boxes` scene (SCENES.md: 1000 unit boxes dropped in jittered columns of ten) with
/// its own configuration, sleep on: within 15 s every column stands (no box above the
/// 9.5 m of a column's top, none below the ground) and every box sleeps (measured: 750
/// awake at 5 s, 20 at 8.3 s, none from 13.3 s; it was 874 awake at 13.3 s, the columns
/// toppling one after another).
#[test]
fn the_boxes_scene_comes_to_rest_and_sleeps() {
    big_stack(|| {
        let mut w: Box<World<'static, 1024, 8192, 64>> = Box::new(World::new());
        let scene = carom::scenes::Scene::Boxes;
        w.set_config(scene.config()).unwrap();
        scene.build(&mut w, &[]).unwrap();
        for _ in 0..900 {
            w.step();
        }
        let report = w.last_report();
        assert_eq!(report.awake_bodies, 0, "{report:?}");
        let (mut low, mut high) = (f32::INFINITY, f32::NEG_INFINITY);
        for h in w.handles().skip(1) {
            let y = w.body(h).unwrap().position().y;
            low = low.min(y);
            high = high.max(y);
        }
        assert!(
            low > 0.4 && high < 9.55,
            "boxes between y = {low} and {high}"
        );
    });
}
