//! Velocity solver and projection scenarios with physical expectations: impulse formulas,
//! Newton's cradle, friction on an incline, resting contact, stacking, energy.
//!
//! Public API only. Each tolerance says why it is what it is.

use carom::rng::SplitMix64;
use carom::{BodyDesc, BodyHandle, Material, Quat, Shape, Vec3, World, WorldConfig};

/// Standard gravity of the default configuration (m/s²).
const G: f32 = 9.81;

fn no_gravity() -> WorldConfig {
    WorldConfig {
        gravity: Vec3::ZERO,
        ..WorldConfig::DEFAULT
    }
}

fn frictionless(restitution: f32) -> Material {
    Material {
        restitution,
        static_friction: 0.0,
        kinetic_friction: 0.0,
        rolling_resistance: 0.0,
        twist_friction: 0.0,
    }
}

fn close(a: f32, b: f32, tol: f32) -> bool {
    (a - b).abs() <= tol
}

/// Two spheres (1 kg and 3 kg) closing at 3 m/s along x, 5 mm apart: after one step their
/// velocities are `v_a − j/m_a`, `v_b + j/m_b` with `j = (1+e) v_close / (1/m_a + 1/m_b)`,
/// for e = 0, 0.5 and 1, and momentum is conserved. The head-on normal passes through
/// both centres, so no rotation.
#[test]
fn head_on_spheres_follow_the_impulse_formula() {
    for e in [0.0f32, 0.5, 1.0] {
        let mut w: World<8, 16> = World::with_config(no_gravity()).unwrap();
        let ball = Shape::sphere(0.5).unwrap();
        let (ma, mb, va, vb) = (1.0f32, 3.0f32, 2.0f32, -1.0f32);
        let a = w
            .add(
                BodyDesc::dynamic(ball)
                    .mass(ma)
                    .material(frictionless(e))
                    .position(Vec3::new(-0.505, 0.0, 0.0))
                    .velocity(Vec3::new(va, 0.0, 0.0)),
            )
            .unwrap();
        let b = w
            .add(
                BodyDesc::dynamic(ball)
                    .mass(mb)
                    .material(frictionless(e))
                    .position(Vec3::new(0.5, 0.0, 0.0))
                    .velocity(Vec3::new(vb, 0.0, 0.0)),
            )
            .unwrap();
        let j = (1.0 + e) * (va - vb) / (1.0 / ma + 1.0 / mb);
        let (va1, vb1) = (va - j / ma, vb + j / mb);
        // With e > 0 the bounce comes in step 1 (the gap closes within it). With e = 0 the
        // speculative contact first lets them close the 5 mm gap (step 1), and the
        // inelastic impact comes in step 2. Checked again long after: e = 0 keeps them
        // together, e > 0 separates them for good.
        let first = if e > 0.0 { 1 } else { 2 };
        let mut done = 0;
        for steps in [first, 30] {
            while done < steps {
                w.step();
                done += 1;
            }
            let (ra, rb) = (w.body(a).unwrap(), w.body(b).unwrap());
            let (ua, ub) = (ra.linear_velocity(), rb.linear_velocity());
            // 1e-4 m/s: a few dozen f32 roundings on speeds of order 1 m/s.
            assert!(
                close(ua.x, va1, 1e-4),
                "e={e} step {steps}: v_a {ua:?}, want {va1}"
            );
            assert!(
                close(ub.x, vb1, 1e-4),
                "e={e} step {steps}: v_b {ub:?}, want {vb1}"
            );
            assert!(ua.y.abs() + ua.z.abs() + ub.y.abs() + ub.z.abs() < 1e-6);
            assert!(ra.angular_velocity().length() + rb.angular_velocity().length() < 1e-6);
            let p = ma * ua.x + mb * ub.x;
            assert!(close(p, ma * va + mb * vb, 1e-4), "e={e}: momentum {p}");
            // Never overlapping by more than the slop (projection leaves at most that).
            let gap = rb.position().x - ra.position().x - 1.0;
            assert!(gap > -0.0051, "e={e}: gap {gap}");
        }
    }
}

/// A 1 kg sphere at 3 m/s hits a free 2 kg box (half-extents 0.5, 0.25, 0.4) on its −x
/// face 0.15 m above the box's centre, e = 0.5, no friction, no gravity. The impulse is
/// `j = (1+e) v / (1/m_s + 1/m_b + (I⁻¹ (r×n))·(r×n))` with `r = (−0.5, 0.15, 0)`, and
/// the box leaves with `v = j/m_b` and `ω = I⁻¹ (r × j n)`, `I` the analytic box inertia.
#[test]
fn off_centre_hit_spins_the_box_as_the_formula_says() {
    let mut w: World<8, 16> = World::with_config(no_gravity()).unwrap();
    let (ms, mb, v, e) = (1.0f32, 2.0f32, 3.0f32, 0.5f32);
    let (hx, hy, hz) = (0.5f32, 0.25f32, 0.4f32);
    let (radius, y) = (0.2f32, 0.15f32);
    let s = w
        .add(
            BodyDesc::dynamic(Shape::sphere(radius).unwrap())
                .mass(ms)
                .material(frictionless(e))
                .position(Vec3::new(-hx - radius - 0.004, y, 0.0))
                .velocity(Vec3::new(v, 0.0, 0.0)),
        )
        .unwrap();
    let b = w
        .add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::new(hx, hy, hz)).unwrap())
                .mass(mb)
                .material(frictionless(e)),
        )
        .unwrap();
    w.step();
    // Analytic inverse inertia of a box about z: 3 / (m (hx² + hy²)).
    let inv_iz = 3.0 / (mb * (hx * hx + hy * hy));
    let rxn_z = -y; // (−hx, y, 0) × (1, 0, 0) = (0, 0, −y)
    let k = 1.0 / ms + 1.0 / mb + rxn_z * rxn_z * inv_iz;
    let j = (1.0 + e) * v / k;
    let box_ref = w.body(b).unwrap();
    let (vb, wb) = (box_ref.linear_velocity(), box_ref.angular_velocity());
    let vs = w.body(s).unwrap().linear_velocity();
    // 1e-4 (m/s, rad/s): f32 rounding on values of order 1.
    assert!(close(vb.x, j / mb, 1e-4), "box v {vb:?}, want {}", j / mb);
    assert!(
        close(wb.z, inv_iz * rxn_z * j, 1e-4),
        "box ω {wb:?}, want {}",
        inv_iz * rxn_z * j
    );
    assert!(
        vb.y.abs() + vb.z.abs() + wb.x.abs() + wb.y.abs() < 1e-5,
        "{vb:?} {wb:?}"
    );
    assert!(
        close(vs.x, v - j / ms, 1e-4),
        "sphere v {vs:?}, want {}",
        v - j / ms
    );
    assert!(w.body(s).unwrap().angular_velocity().length() < 1e-6);
    // The contact points separate at e times the closing speed.
    let p = Vec3::new(-hx, y, 0.0);
    let separating = box_ref.velocity_at(p).x - vs.x;
    assert!(close(separating, e * v, 1e-4), "separating at {separating}");
}

/// Five touching 1 kg balls, e = 1, no friction, no gravity; the first arrives at 2 m/s.
/// The collision pass measures each contact's approach when it visits it, so the impulse
/// travels down the row: the last ball leaves at 2 m/s and the others stay. Added in both
/// slot orders: chain order settles in one sweep, the reverse order in four.
#[test]
fn newtons_cradle_passes_the_speed_down_the_row() {
    for reversed in [false, true] {
        let mut w: World<8, 16> = World::with_config(no_gravity()).unwrap();
        let ball = Shape::sphere(0.5).unwrap();
        let mut h: [Option<BodyHandle>; 5] = [None; 5];
        let order: [usize; 5] = if reversed {
            [4, 3, 2, 1, 0]
        } else {
            [0, 1, 2, 3, 4]
        };
        for i in order {
            let x = if i == 0 { -0.01 } else { i as f32 };
            let vel = if i == 0 { 2.0 } else { 0.0 };
            h[i] = Some(
                w.add(
                    BodyDesc::dynamic(ball)
                        .mass(1.0)
                        .material(frictionless(1.0))
                        .position(Vec3::new(x, 0.0, 0.0))
                        .velocity(Vec3::new(vel, 0.0, 0.0)),
                )
                .unwrap(),
            );
        }
        let speeds = |w: &World<8, 16>| h.map(|b| w.body(b.unwrap()).unwrap().linear_velocity().x);
        w.step();
        let after_impact = speeds(&w);
        for _ in 0..59 {
            w.step();
        }
        let after_1s = speeds(&w);
        eprintln!(
            "cradle reversed={reversed}: after impact {after_impact:?}, after 1 s {after_1s:?}"
        );
        for v in [after_impact, after_1s] {
            // One-point contacts between equal masses: every bounce hands over the whole
            // speed up to f32 rounding, so 1e-4 m/s (5e-5 of the speed) holds for all.
            assert!(close(v[4], 2.0, 1e-4), "reversed={reversed}: {v:?}");
            for u in &v[..4] {
                assert!(u.abs() < 1e-4, "reversed={reversed}: {v:?}");
            }
        }
    }
}

/// A 0.5 m box on a 30° incline (a rotated static box), both of `material`; `push` is the
/// initial speed down the slope. Returns the distance slid down the slope at 0.5 s, 1.0 s,
/// 1.5 s and 2.0 s.
fn incline_run(material: Material, push: f32) -> [f32; 4] {
    let (q, up_slope, normal) = incline();
    let mut w: World<8, 16> = World::with_config(WorldConfig::DEFAULT).unwrap();
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(12.0, 0.5, 3.0)).unwrap())
            .rotation(q)
            .material(material),
    )
    .unwrap();
    let start = up_slope * 7.0 + normal * 0.75;
    let b = w
        .add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.25)).unwrap())
                .rotation(q)
                .position(start)
                .material(material)
                .velocity(-up_slope * push),
        )
        .unwrap();
    let mut out = [0.0; 4];
    for (k, slot) in out.iter_mut().enumerate() {
        for _ in 0..30 {
            w.step();
        }
        let p = w.body(b).unwrap().position();
        *slot = -(p - start).dot(up_slope);
        // The box stays on the surface: no sinking, no hopping (2 slops).
        let height = (p - start).dot(normal);
        assert!(
            height.abs() < 0.01,
            "step {}: height {height}",
            30 * (k + 1)
        );
    }
    out
}

/// Second difference of positions sampled every 0.5 s: the acceleration (m/s²). Exact for
/// the integrator under a constant acceleration.
fn acceleration(s: [f32; 4]) -> f32 {
    (s[2] - 2.0 * s[1] + s[0]) / 0.25
}

/// The incline's rotation (30° about Z), the unit vector up its slope and its normal, both
/// taken from the rotation itself: with `micromath` the rotation's angle is off by up to
/// 2.2e-3 rad (approximate trig), which over the 7 m of the run would read as a 1.5 cm
/// height if the axes came from the exact angle.
fn incline() -> (Quat, Vec3, Vec3) {
    let q = Quat::from_axis_angle(Vec3::Z, 30.0f32.to_radians());
    (q, q.rotate(Vec3::X), q.rotate(Vec3::Y))
}

/// `g (sin θ − μk cos θ)` at the incline's angle θ (30°).
fn kinetic_rate(mu_k: f32) -> f32 {
    let (_, up_slope, _) = incline();
    G * (up_slope.y - mu_k * up_slope.x)
}

#[test]
fn box_slides_down_an_incline_at_the_kinetic_rate() {
    let m = Material {
        restitution: 0.0,
        static_friction: 0.2,
        kinetic_friction: 0.2,
        ..Material::DEFAULT
    };
    let s = incline_run(m, 0.0);
    let a = acceleration(s);
    eprintln!("incline μ 0.2: a = {a} m/s², want {}", kinetic_rate(0.2));
    // 3 %: the brief's bound. Measured between 0.5 s and 1.5 s.
    assert!(
        (a - kinetic_rate(0.2)).abs() < 0.03 * kinetic_rate(0.2),
        "a = {a}, want {}",
        kinetic_rate(0.2)
    );
}

#[test]
fn static_friction_holds_a_box_on_an_incline() {
    let m = Material {
        restitution: 0.0,
        static_friction: 0.7,
        kinetic_friction: 0.2,
        ..Material::DEFAULT
    };
    let s = incline_run(m, 0.0);
    eprintln!("incline μs 0.7 at rest: slid {s:?} m");
    // tan 30° = 0.577 < 0.7: it must not move. 1 mm in 2 s: the brief's bound.
    assert!(s[3].abs() < 1e-3, "slid {s:?}");
}

#[test]
fn a_pushed_box_keeps_sliding_at_the_kinetic_rate() {
    let m = Material {
        restitution: 0.0,
        static_friction: 0.7,
        kinetic_friction: 0.2,
        ..Material::DEFAULT
    };
    let s = incline_run(m, 2.0);
    let a = acceleration(s);
    eprintln!("incline pushed: a = {a} m/s², want {}", kinetic_rate(0.2));
    // Once sliding, static friction (0.7, enough to hold it at rest) must not come back.
    assert!(
        (a - kinetic_rate(0.2)).abs() < 0.03 * kinetic_rate(0.2),
        "a = {a}, want {}",
        kinetic_rate(0.2)
    );
    assert!(s[3] > 2.0 * 2.0, "slid only {s:?}");
}

/// A box set down on the ground comes to rest without jitter, then sleeps.
#[test]
fn box_rests_on_the_ground_without_jitter() {
    let mut w: World<8, 16> = World::with_config(WorldConfig::DEFAULT).unwrap();
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )
    .unwrap();
    let b = w
        .add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::new(0.5, 0.3, 0.4)).unwrap())
                .position(Vec3::new(0.0, 0.3, 0.0)),
        )
        .unwrap();
    for _ in 0..60 {
        w.step();
    }
    let r = w.body(b).unwrap();
    // 1e-3 m/s and 1e-3 rad/s after 1 s: the brief's bound for "no jitter".
    assert!(
        r.linear_velocity().length() < 1e-3,
        "v = {:?}",
        r.linear_velocity()
    );
    assert!(
        r.angular_velocity().length() < 1e-3,
        "ω = {:?}",
        r.angular_velocity()
    );
    // Resting at most one slop deep, not tilted.
    assert!(
        (r.position().y - 0.3).abs() <= 0.0051,
        "y = {}",
        r.position().y
    );
    assert!(r.rotation().w.abs() > 0.99999, "tilted: {:?}", r.rotation());
    let mut slept_at = None;
    for i in 60..120 {
        w.step();
        if slept_at.is_none() && !w.body(b).unwrap().is_awake() {
            slept_at = Some(i + 1);
        }
    }
    let slept = slept_at.expect("asleep within 2 s");
    assert!(
        !w.body(b).unwrap().is_awake(),
        "woke again after step {slept}"
    );
}

/// The shared `tower` scene (10 boxes of 1 m, dropped 1 cm apart) settles and stands for
/// 10 s.
#[test]
fn tower_of_ten_boxes_stands() {
    let mut w: World<16, 64> = World::with_config(WorldConfig::DEFAULT).unwrap();
    let top = carom::scenes::tower(&mut w, 10).unwrap();
    let start = w.body(top).unwrap().position();
    for _ in 0..600 {
        w.step();
    }
    let end = w.body(top).unwrap().position();
    let sideways = Vec3::new(end.x - start.x, 0.0, end.z - start.z).length();
    // Once the gaps close the top box's centre is at 9.5 m; ten contacts may each rest up
    // to one slop deep.
    let sink = 9.5 - end.y;
    eprintln!("tower of 10: sideways {sideways} m, below 9.5 m by {sink} m");
    // 5 cm: the brief's bound, on the sideways drift and on the height.
    assert!(sideways < 0.05, "top drifted sideways to {end:?}");
    assert!((-0.001..0.05).contains(&sink), "top at {end:?}");
}

/// The pyramid20 scene (SCENES.md) stands for 10 s.
#[test]
fn pyramid20_stands() {
    let run = || {
        let mut w: Box<World<256, 1024>> =
            Box::new(World::with_config(WorldConfig::DEFAULT).unwrap());
        let top = carom::scenes::pyramid(&mut w, 20).unwrap();
        let start = w.body(top).unwrap().position();
        for _ in 0..600 {
            w.step();
            let r = w.last_report();
            assert!(r.dropped_pairs == 0 && r.dropped_contacts == 0, "{r:?}");
        }
        w.body(top).unwrap().position() - start
    };
    let drift = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(run)
        .unwrap()
        .join()
        .unwrap();
    eprintln!("pyramid20: top drift {drift:?}");
    // 5 cm: the brief's bound (20 contacts resting at the slop sink the top by up to
    // 20 × 5 mm in theory; in practice far less).
    assert!(drift.length() < 0.05, "top drifted {drift:?}");
}

/// Spheres and boxes with e = 1 and no friction bounce around a closed box without gravity:
/// the total kinetic energy never rises more than 1 % above its start.
#[test]
fn elastic_bodies_in_a_closed_box_do_not_gain_energy() {
    let mut w: World<64, 256> = World::with_config(no_gravity()).unwrap();
    let elastic = frictionless(1.0);
    // Walls 1 m thick, inner faces at ±3.
    for axis in 0..3 {
        for side in [-1.0f32, 1.0] {
            let mut half = Vec3::splat(4.0);
            let mut pos = Vec3::ZERO;
            match axis {
                0 => {
                    half.x = 0.5;
                    pos.x = side * 3.5;
                }
                1 => {
                    half.y = 0.5;
                    pos.y = side * 3.5;
                }
                _ => {
                    half.z = 0.5;
                    pos.z = side * 3.5;
                }
            }
            w.add(
                BodyDesc::fixed(Shape::cuboid(half).unwrap())
                    .position(pos)
                    .material(elastic),
            )
            .unwrap();
        }
    }
    let mut rng = SplitMix64::new(0xE1A5_71C0);
    let mut bodies = Vec::new();
    for i in 0..3 {
        for j in 0..3 {
            for k in 0..3 {
                let p = Vec3::new(i as f32 - 1.0, j as f32 - 1.0, k as f32 - 1.0) * 1.8;
                let shape = if (i + j + k) % 2 == 0 {
                    Shape::sphere(0.35).unwrap()
                } else {
                    Shape::cuboid(Vec3::new(0.3, 0.25, 0.2)).unwrap()
                };
                let v = rng.unit_vector() * rng.range(2.0, 6.0);
                let h = w
                    .add(
                        BodyDesc::dynamic(shape)
                            .position(p)
                            .rotation(rng.rotation())
                            .velocity(v)
                            .angular_velocity(rng.unit_vector() * rng.range(0.0, 3.0))
                            .material(elastic),
                    )
                    .unwrap();
                bodies.push(h);
            }
        }
    }
    let energy = |w: &World<64, 256>| {
        bodies
            .iter()
            .map(|&b| w.body(b).unwrap().kinetic_energy())
            .sum::<f32>()
    };
    let e0 = energy(&w);
    let mut peak = e0;
    let mut hits = 0;
    for _ in 0..600 {
        let r = w.step();
        hits += r.contacts;
        peak = peak.max(energy(&w));
        for &b in &bodies {
            let p = w.body(b).unwrap().position();
            assert!(
                p.x.abs() < 3.0 && p.y.abs() < 3.0 && p.z.abs() < 3.0,
                "escaped: {p:?}"
            );
        }
    }
    assert!(hits > 100, "too few contacts to test anything: {hits}");
    eprintln!(
        "elastic box: energy {e0} J, peak {peak} J, final {}",
        energy(&w)
    );
    // 1 %: the brief's bound.
    assert!(peak <= 1.01 * e0, "energy rose from {e0} to {peak}");
}
