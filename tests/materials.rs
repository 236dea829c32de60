//! Material combine rules (`CombineRule`, `WorldConfig::friction_combine` and
//! `restitution_combine`): each rule's formula, the defaults that reproduce
//! `Material::combine`, what the rules do to a sliding box and a bouncing ball, and their
//! place in snapshots.
//!
//! Public API only. Each tolerance says why it is what it is.

use carom::{
    BodyDesc, BodyHandle, CombineRule, Error, Material, Shape, SnapshotError, Vec3, World,
    WorldConfig,
};

const G: f32 = 9.81;

const RULES: [CombineRule; 5] = CombineRule::ALL;

/// Coefficient pairs: zeros, equal values, the extremes a material accepts, and ordinary
/// friction and restitution values in both orders.
const PAIRS: [(f32, f32); 12] = [
    (0.0, 0.0),
    (0.0, 0.6),
    (0.6, 0.0),
    (0.4, 0.4),
    (1.0, 1.0),
    (0.3, 0.7),
    (0.7, 0.3),
    (0.05, 1.0),
    (0.8, 0.02),
    (100.0, 100.0),
    (0.0, 100.0),
    (2.5, 60.0),
];

/// The formula each variant documents, written out here independently.
fn formula(rule: CombineRule, a: f32, b: f32) -> f32 {
    match rule {
        CombineRule::GeometricMean => (a * b).sqrt(),
        CombineRule::Average => (a + b) / 2.0,
        CombineRule::Min => a.min(b),
        CombineRule::Max => a.max(b),
        CombineRule::Multiply => (a * b).min(100.0),
    }
}

#[test]
fn each_rule_follows_its_formula() {
    for rule in RULES {
        for (a, b) in PAIRS {
            let got = rule.apply(a, b);
            let want = formula(rule, a, b);
            // Bit-exact but for the square root: with `micromath` it is within 1 ulp.
            let tol = if rule == CombineRule::GeometricMean {
                2.0 * f32::EPSILON * want
            } else {
                0.0
            };
            assert!(
                (got - want).abs() <= tol,
                "{rule:?}({a}, {b}) = {got}, want {want}"
            );
            assert_eq!(
                got.to_bits(),
                rule.apply(b, a).to_bits(),
                "{rule:?} symmetric"
            );
        }
    }
}

/// Coefficients in `[0, 100]` combine into `[0, 100]`; restitutions in `[0, 1]` into
/// `[0, 1]`; every rule but `Multiply` stays between its two inputs.
#[test]
fn combined_coefficients_stay_in_range() {
    let values = [
        0.0f32, 1e-6, 0.02, 0.3, 0.5, 0.8, 1.0, 3.0, 42.0, 99.9, 100.0,
    ];
    for rule in RULES {
        for a in values {
            for b in values {
                let c = rule.apply(a, b);
                // The micromath square root may be 1 ulp above the larger input.
                let slack = if rule == CombineRule::GeometricMean {
                    f32::EPSILON * a.max(b)
                } else {
                    0.0
                };
                assert!(
                    c.is_finite() && (0.0..=100.0 + slack).contains(&c),
                    "{rule:?}"
                );
                if a <= 1.0 && b <= 1.0 {
                    assert!(c <= 1.0 + slack, "{rule:?}({a}, {b}) = {c}");
                }
                if rule != CombineRule::Multiply {
                    assert!(c >= a.min(b) && c <= a.max(b) + slack, "{rule:?}({a}, {b})");
                }
            }
        }
    }
}

/// `Material::combine` is the default rules' shorthand, and the defaults are today's:
/// restitution by the larger, friction by the geometric mean. Rolling resistance and
/// twist friction take the larger whatever the rules.
#[test]
fn defaults_reproduce_material_combine() {
    assert_eq!(
        WorldConfig::DEFAULT.friction_combine,
        CombineRule::GeometricMean
    );
    assert_eq!(WorldConfig::DEFAULT.restitution_combine, CombineRule::Max);
    let a = Material {
        restitution: 0.8,
        static_friction: 1.0,
        kinetic_friction: 0.8,
        rolling_resistance: 0.02,
        twist_friction: 0.001,
    };
    let b = Material {
        restitution: 0.1,
        static_friction: 0.05,
        kinetic_friction: 0.02,
        rolling_resistance: 0.005,
        twist_friction: 0.3,
    };
    let by_default = Material::combine_with(
        &a,
        &b,
        WorldConfig::DEFAULT.friction_combine,
        WorldConfig::DEFAULT.restitution_combine,
    );
    assert_eq!(Material::combine(&a, &b), by_default);
    assert_eq!(by_default.restitution, 0.8);
    assert_eq!(
        by_default.kinetic_friction.to_bits(),
        CombineRule::GeometricMean.apply(0.8, 0.02).to_bits()
    );
    for f in RULES {
        for e in RULES {
            let m = Material::combine_with(&a, &b, f, e);
            assert_eq!(m.restitution, e.apply(a.restitution, b.restitution));
            assert_eq!(
                m.static_friction,
                f.apply(a.static_friction, b.static_friction)
            );
            assert_eq!(
                m.kinetic_friction,
                f.apply(a.kinetic_friction, b.kinetic_friction)
            );
            assert_eq!(m.rolling_resistance, 0.02);
            assert_eq!(m.twist_friction, 0.3);
            assert!(m.validate().is_ok());
            assert_eq!(m, Material::combine_with(&b, &a, f, e), "symmetric");
        }
    }
}

fn config(friction: CombineRule, restitution: CombineRule) -> WorldConfig {
    WorldConfig {
        friction_combine: friction,
        restitution_combine: restitution,
        sleep_enabled: false,
        ..WorldConfig::DEFAULT
    }
}

const SLIDE_SPEED: f32 = 5.0;
const BOX_MU: f32 = 0.5;

/// A frictionless ground and a 0.5 m box of friction [`BOX_MU`] (static and kinetic)
/// resting on it, moving at [`SLIDE_SPEED`] along x.
fn sliding_box(cfg: WorldConfig) -> (World<'static, 4, 8>, BodyHandle) {
    let mut w = World::with_config(cfg).unwrap();
    let ice = Material {
        static_friction: 0.0,
        kinetic_friction: 0.0,
        ..Material::DEFAULT
    };
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(50.0, 0.5, 50.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0))
            .material(ice),
    )
    .unwrap();
    let rough = Material {
        static_friction: BOX_MU,
        kinetic_friction: BOX_MU,
        ..Material::DEFAULT
    };
    let b = w
        .add(
            BodyDesc::dynamic(Shape::cuboid(Vec3::splat(0.25)).unwrap())
                .position(Vec3::new(-20.0, 0.25, 0.0))
                .velocity(Vec3::new(SLIDE_SPEED, 0.0, 0.0))
                .material(rough),
        )
        .unwrap();
    (w, b)
}

fn speed_x(w: &World<'static, 4, 8>, b: BodyHandle) -> f32 {
    w.body(b).unwrap().linear_velocity().x
}

/// With `Min` (and the default geometric mean) the frictionless ground makes the contact
/// frictionless: the box keeps its speed over 60 steps (1e-3 m/s: nothing else slows
/// it).
#[test]
fn min_rule_on_a_frictionless_ground_keeps_the_box_sliding() {
    for rule in [CombineRule::Min, CombineRule::GeometricMean] {
        let (mut w, b) = sliding_box(config(rule, CombineRule::Max));
        for _ in 0..60 {
            w.step();
        }
        let v = speed_x(&w, b);
        eprintln!("{rule:?}: speed after 60 steps {v} m/s");
        assert!((v - SLIDE_SPEED).abs() < 1e-3, "{rule:?}: {v}");
    }
}

/// With `Max` the box's friction rules: it decelerates at `μk g` (2 %), measured over
/// steps 5 to 45 (the box stops near step 61).
#[test]
fn max_rule_on_a_frictionless_ground_decelerates_at_mu_g() {
    let (mut w, b) = sliding_box(config(CombineRule::Max, CombineRule::Max));
    let mut v = [0.0f32; 61];
    for slot in v.iter_mut().skip(1) {
        w.step();
        *slot = speed_x(&w, b);
    }
    let decel = (v[5] - v[45]) / (40.0 * WorldConfig::DEFAULT.dt);
    let want = BOX_MU * G;
    eprintln!("Max: deceleration {decel} m/s², want {want}");
    assert!((decel - want).abs() < 0.02 * want, "{decel} vs {want}");
}

/// Changing the rules with `set_config` applies to the contacts already there: a box
/// braking under `Max` slides freely once the rule becomes `Min`.
#[test]
fn set_config_recombines_existing_contacts() {
    let (mut w, b) = sliding_box(config(CombineRule::Max, CombineRule::Max));
    for _ in 0..10 {
        w.step();
    }
    let braked = speed_x(&w, b);
    assert!(braked < SLIDE_SPEED - 0.5, "braking: {braked}");
    w.set_config(config(CombineRule::Min, CombineRule::Max))
        .unwrap();
    for _ in 0..20 {
        w.step();
    }
    let v = speed_x(&w, b);
    assert!((v - braked).abs() < 1e-3, "{v} after {braked}");
}

const DROP: f32 = 2.0;

/// A frictionless ball of restitution 0.8 dropped from [`DROP`] (its lowest point) on a
/// ground of restitution 0: the highest its lowest point rises after the first impact.
fn rebound_apex(restitution: CombineRule) -> f32 {
    let mut w: World<'static, 4, 8> =
        World::with_config(config(CombineRule::GeometricMean, restitution)).unwrap();
    let smooth = |e| Material {
        restitution: e,
        static_friction: 0.0,
        kinetic_friction: 0.0,
        rolling_resistance: 0.0,
        twist_friction: 0.0,
    };
    w.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(10.0, 0.5, 10.0)).unwrap())
            .position(Vec3::new(0.0, -0.5, 0.0))
            .material(smooth(0.0)),
    )
    .unwrap();
    let r = 0.25;
    let ball = w
        .add(
            BodyDesc::dynamic(Shape::sphere(r).unwrap())
                .position(Vec3::new(0.0, DROP + r, 0.0))
                .material(smooth(0.8)),
        )
        .unwrap();
    let mut falling = false;
    let mut apex: Option<f32> = None;
    for _ in 0..240 {
        w.step();
        let body = w.body(ball).unwrap();
        let (y, vy) = (body.position().y - r, body.linear_velocity().y);
        if let Some(top) = apex.as_mut() {
            *top = top.max(y);
        } else if vy < -3.0 {
            falling = true;
        } else if falling && vy > -1.0 {
            // The impact cut the fall (6.3 m/s): from here on, track the height.
            apex = Some(y);
        }
    }
    apex.unwrap_or_else(|| panic!("{restitution:?}: the ball never landed"))
}

/// `Max`: the ball's 0.8 wins and it bounces to `0.8² · h` (5 %).
#[test]
fn max_restitution_bounces_to_e_squared_of_the_height() {
    let apex = rebound_apex(CombineRule::Max);
    let want = 0.64 * DROP;
    eprintln!("Max: apex {apex} m, want {want}");
    assert!((apex - want).abs() < 0.05 * want, "{apex} vs {want}");
}

/// `Min`: the ground's 0 wins and the ball does not bounce (apex below 1 % of the drop).
#[test]
fn min_restitution_does_not_bounce() {
    let apex = rebound_apex(CombineRule::Min);
    eprintln!("Min: apex {apex} m");
    assert!(apex < 0.01 * DROP, "{apex}");
}

type Snap = World<'static, 4, 8>;

fn snapshot(w: &Snap) -> Vec<u8> {
    let mut buf = vec![0u8; Snap::max_snapshot_len()];
    let n = w.snapshot(&mut buf).unwrap();
    buf.truncate(n);
    buf
}

/// A restored world has the snapshot's rules, and continues bit-identically.
#[test]
fn snapshot_round_trip_keeps_the_rules() {
    let cfg = config(CombineRule::Min, CombineRule::Average);
    let (mut w, _) = sliding_box(cfg);
    for _ in 0..10 {
        w.step();
    }
    let bytes = snapshot(&w);
    let (mut other, _) = sliding_box(WorldConfig::DEFAULT);
    other.restore(&bytes).unwrap();
    assert_eq!(*other.config(), cfg);
    for _ in 0..20 {
        w.step();
        other.step();
        assert_eq!(w.checksum(), other.checksum());
    }
}

/// FNV-1a 64, the snapshot's payload hash, written out here.
fn fnv1a(bytes: &[u8]) -> u64 {
    let mut h: u64 = 0xcbf2_9ce4_8422_2325;
    for b in bytes {
        h = (h ^ u64::from(*b)).wrapping_mul(0x0000_0100_0000_01b3);
    }
    h
}

/// Rewrite the snapshot header's payload hash (bytes 28..36, over the payload from 36).
fn reseal(buf: &mut [u8]) {
    let sum = fnv1a(&buf[36..]);
    buf[28..36].copy_from_slice(&sum.to_le_bytes());
}

/// Where two snapshots' payloads differ.
fn payload_diff(a: &[u8], b: &[u8]) -> Vec<usize> {
    assert_eq!(a.len(), b.len());
    (36..a.len()).filter(|&i| a[i] != b[i]).collect()
}

/// A snapshot whose rule code is not a rule is refused as corrupt, with the world
/// unchanged. The codes are found by snapshotting a world without contacts under two
/// rules (the only payload bytes that differ).
#[test]
fn unknown_rule_codes_are_refused() {
    let (mut w, _) = sliding_box(config(CombineRule::Min, CombineRule::Min));
    let min_min = snapshot(&w);
    w.set_config(config(CombineRule::Max, CombineRule::Min))
        .unwrap();
    let max_min = snapshot(&w);
    w.set_config(config(CombineRule::Min, CombineRule::Max))
        .unwrap();
    let min_max = snapshot(&w);
    let friction_at = payload_diff(&min_min, &max_min);
    let restitution_at = payload_diff(&min_min, &min_max);
    assert_eq!(friction_at.len(), 1, "layout: {friction_at:?}");
    assert_eq!(restitution_at, [friction_at[0] + 4], "layout");

    // A world elsewhere: stepped, with other rules.
    let cfg = config(CombineRule::Average, CombineRule::Multiply);
    let (mut target, _) = sliding_box(cfg);
    for _ in 0..5 {
        target.step();
    }
    let before = target.checksum();
    for at in [friction_at[0], restitution_at[0]] {
        for code in [5u32, 99, u32::MAX] {
            let mut bad = min_min.clone();
            bad[at..at + 4].copy_from_slice(&code.to_le_bytes());
            reseal(&mut bad);
            assert_eq!(
                target.restore(&bad),
                Err(Error::Snapshot(SnapshotError::Corrupt)),
                "code {code} at {at}"
            );
            assert_eq!(target.checksum(), before);
            assert_eq!(*target.config(), cfg);
        }
        // Every known code is accepted.
        for (code, rule) in RULES.iter().enumerate() {
            let mut good = min_min.clone();
            good[at..at + 4].copy_from_slice(&(code as u32).to_le_bytes());
            reseal(&mut good);
            let mut w2 = sliding_box(WorldConfig::DEFAULT).0;
            w2.restore(&good).unwrap();
            let got = if at == friction_at[0] {
                w2.config().friction_combine
            } else {
                w2.config().restitution_combine
            };
            assert_eq!(got, *rule, "code {code}");
        }
    }
}
