//! Continuous collision: time of impact and movement bounds, against closed forms,
//! brute-force sampling and the shared property function.

use carom::collide::{distance, movement_bounds, time_of_impact, Motion, SimplexCache, Toi};
use carom::math::{Iso, Quat, Vec3};
use carom::props::toi_properties;
use carom::rng::SplitMix64;
use carom::shape::{ConvexHull, Shape};
use carom::{Error, Input};

const DT: f32 = 1.0 / 60.0;

fn still(position: Vec3) -> Motion {
    Motion {
        pose: Iso::from_position(position),
        ..Motion::default()
    }
}

fn moving(position: Vec3, linear: Vec3) -> Motion {
    Motion {
        pose: Iso::from_position(position),
        linear,
        angular: Vec3::ZERO,
    }
}

fn gjk_gap(a: &Shape, ma: &Motion, b: &Shape, mb: &Motion, t: f32) -> f32 {
    let mut cache = SimplexCache::default();
    distance(a, &ma.pose_at(t), b, &mb.pose_at(t), &mut cache)
        .expect("valid poses")
        .distance
}

fn f64v(v: Vec3) -> [f64; 3] {
    [v.x as f64, v.y as f64, v.z as f64]
}

fn dot(a: [f64; 3], b: [f64; 3]) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn add_scaled(a: [f64; 3], b: [f64; 3], t: f64) -> [f64; 3] {
    [a[0] + b[0] * t, a[1] + b[1] * t, a[2] + b[2] * t]
}

/// Closed form for two spheres in linear motion, in f64: the gap
/// `g(t) = |Δp + Δv t| − R` and its first root `t*` of `|Δp + Δv t|² = R²`.
struct SpherePair {
    dp: [f64; 3],
    dv: [f64; 3],
    r: f64,
}

impl SpherePair {
    fn gap(&self, t: f64) -> f64 {
        let d = add_scaled(self.dp, self.dv, t);
        dot(d, d).sqrt() - self.r
    }

    /// First time the spheres touch, if they ever do after time 0.
    fn first_touch(&self) -> Option<f64> {
        let a = dot(self.dv, self.dv);
        let b = dot(self.dp, self.dv);
        let c = dot(self.dp, self.dp) - self.r * self.r;
        let disc = b * b - a * c;
        if a == 0.0 || b >= 0.0 || disc < 0.0 {
            return None;
        }
        Some((-b - disc.sqrt()) / a)
    }

    /// Smallest gap over `[0, t_max]` (g is convex: the minimum is at the clamped vertex).
    fn min_gap(&self, t_max: f64) -> f64 {
        let a = dot(self.dv, self.dv);
        let t = if a > 0.0 {
            (-dot(self.dp, self.dv) / a).clamp(0.0, t_max)
        } else {
            0.0
        };
        self.gap(t)
    }

    /// Speed at which the gap closes at time `t` (m/s).
    fn closing_speed(&self, t: f64) -> f64 {
        let d = add_scaled(self.dp, self.dv, t);
        -dot(d, self.dv) / dot(d, d).sqrt()
    }
}

/// Linear spheres against the closed form. For a hit at `t_h` before the root `t*`:
/// the gap there is in `(0, tol]`, and since `g` is convex, `g(t_h) >= c (t* − t_h)` with
/// `c` the closing speed at `t*`, so `t* − t_h <= tol / c`. Misses whose smallest gap
/// exceeds the tolerance must be `Separated`.
#[test]
fn moving_spheres_match_the_closed_form() {
    let mut rng = SplitMix64::new(0x0701);
    // f32 GJK on point cores at coordinates up to ~30 m: rounding of ~1e-5 m.
    const EPS: f64 = 2.0e-5;
    let (mut hits, mut misses, mut overlaps) = (0, 0, 0);
    let mut worst_lag = 0.0f64; // (t* − t_h) c / tol, must be <= 1
    for _ in 0..4000 {
        let ra = rng.range(0.02, 1.0);
        let rb = rng.range(0.02, 1.0);
        let pa = Vec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        );
        let pb = Vec3::new(
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
            rng.range(-5.0, 5.0),
        );
        // Mostly aimed at each other, with a random miss distance.
        let aim = (pa - pb) * rng.range(0.0, 4.0) + rng.unit_vector() * rng.range(0.0, 6.0);
        let va = rng.unit_vector() * rng.range(0.0, 20.0);
        let vb = va + aim;
        let t_max = rng.range(0.01, 1.0);
        let tol = rng.range(1.0e-3, 1.0e-2);
        let (sa, sb) = (Shape::sphere(ra).unwrap(), Shape::sphere(rb).unwrap());
        let (ma, mb) = (moving(pa, va), moving(pb, vb));
        let pair = SpherePair {
            dp: f64v(pb - pa),
            dv: f64v(vb - va),
            r: ra as f64 + rb as f64,
        };
        let toi = time_of_impact(&sa, &ma, &sb, &mb, t_max, tol).unwrap();
        let gap0 = pair.gap(0.0);
        if gap0.abs() < EPS {
            continue; // touching within rounding: either answer is right
        }
        if gap0 < 0.0 {
            assert_eq!(toi, Toi::Overlapping);
            overlaps += 1;
            continue;
        }
        let touch = pair.first_touch().filter(|&t| t <= t_max as f64);
        match toi {
            Toi::Hit { time, normal, .. } => {
                hits += 1;
                let t_h = time as f64;
                let g = pair.gap(t_h);
                assert!(
                    g > 0.0 && g <= tol as f64 + EPS,
                    "gap {g} at the hit, tol {tol}"
                );
                if let Some(ts) = touch {
                    assert!(t_h <= ts, "hit {t_h} after the first touch {ts}");
                    let lag = (ts - t_h) * pair.closing_speed(ts) / tol as f64;
                    worst_lag = worst_lag.max(lag);
                    assert!(lag <= 1.0 + 1e-2, "hit {t_h} too early, touch {ts}");
                }
                // The normal joins the centres at the hit time.
                let centres = f64v(pb - pa);
                let d = add_scaled(centres, pair.dv, t_h);
                let len = dot(d, d).sqrt();
                let n = f64v(normal);
                assert!(dot(n, d) / len > 1.0 - 1e-4, "normal {normal:?}");
            }
            Toi::Separated => {
                misses += 1;
                assert!(touch.is_none(), "missed a touch at {touch:?}");
                // Coming within the tolerance without touching may go either way.
                let g = pair.min_gap(t_max as f64);
                assert!(g > 0.0, "separated but the closest gap is {g}");
            }
            Toi::Overlapping => panic!("overlapping reported with gap {gap0} at time 0"),
            // Translating spheres have an exact bound: advancement alone finishes.
            Toi::Unresolved { time } => panic!("unresolved at {time} for moving spheres"),
        }
    }
    assert!(
        hits > 500 && misses > 500 && overlaps > 10,
        "{hits} {misses} {overlaps}"
    );
    std::println!("spheres: {hits} hits, {misses} misses, worst lag {worst_lag:.3} of tol/c");
}

/// The bullet scene: a 5 cm sphere at 500 m/s against a 10 cm wall. It crosses 8.3 m per
/// step, 83 times the wall's thickness. The hit time must be the closed form
/// `(|x₀| − 0.05 − 0.05) / 500` less at most `tol / 500`.
#[test]
fn bullet_does_not_tunnel_through_a_thin_wall() {
    let bullet = Shape::sphere(0.05).unwrap();
    let wall = Shape::cuboid(Vec3::new(0.05, 5.0, 5.0)).unwrap();
    let wall_motion = still(Vec3::ZERO);
    let tol = 0.005;
    for i in 0..100 {
        // Start between 0.2 m and 8.4 m before the wall, at varied heights.
        let x0 = -0.2 - 8.2 * (i as f32 / 99.0);
        let start = Vec3::new(x0, -4.0 + 0.08 * i as f32, 1.5);
        let m = moving(start, Vec3::new(500.0, 0.0, 0.0));
        let toi = time_of_impact(&bullet, &m, &wall, &wall_motion, DT, tol).unwrap();
        let exact = (-x0 - 0.1) / 500.0;
        if exact > DT {
            assert_eq!(toi, Toi::Separated, "x0 = {x0}");
            continue;
        }
        let Toi::Hit {
            time,
            normal,
            point_a,
            point_b,
        } = toi
        else {
            panic!("x0 = {x0}: {toi:?}");
        };
        // 1e-7 s: f32 rounding of the positions (~1e-6 m at 8 m) divided by 500 m/s... doubled.
        assert!(
            time <= exact + 1e-7 && exact - time <= tol / 500.0 + 1e-7,
            "x0 {x0}: {time} vs {exact}"
        );
        assert!((normal - Vec3::X).length() < 1e-4, "{normal:?}");
        assert!(point_b.x - point_a.x > 0.0 && point_b.x - point_a.x <= tol + 1e-5);
        assert!((point_b.x - -0.05).abs() < 1e-5);
    }
}

/// Two 2 cm spheres, 10 m apart, closing at 300 m/s each: they meet at
/// `(10 − 0.04) / 600` s, inside one 1/60 s step, after crossing 250 diameters.
#[test]
fn fast_spheres_meet_head_on() {
    let s = Shape::sphere(0.02).unwrap();
    let ma = moving(Vec3::new(-5.0, 1.0, 2.0), Vec3::new(300.0, 0.0, 0.0));
    let mb = moving(Vec3::new(5.0, 1.0, 2.0), Vec3::new(-300.0, 0.0, 0.0));
    let tol = 1.0e-3;
    let Toi::Hit {
        time,
        normal,
        point_a,
        point_b,
    } = time_of_impact(&s, &ma, &s, &mb, DT, tol).unwrap()
    else {
        panic!("no hit");
    };
    let exact = 9.96 / 600.0;
    assert!(
        time <= exact && exact - time <= tol / 600.0 + 1e-7,
        "{time} vs {exact}"
    );
    assert!((normal - Vec3::X).length() < 1e-5);
    let gap = point_b.x - point_a.x;
    assert!(gap > 0.0 && gap <= tol + 1e-5, "gap {gap}");
    // Slightly off-axis they pass by: separated.
    let mb_off = moving(Vec3::new(5.0, 1.05, 2.0), Vec3::new(-300.0, 0.0, 0.0));
    assert_eq!(
        time_of_impact(&s, &ma, &s, &mb_off, DT, tol).unwrap(),
        Toi::Separated
    );
}

/// A rod (half-extents 1 × 0.05 × 0.05) spinning about Z at the origin meets a still
/// sphere of radius 0.1 at (x, y, 0) with its upper face. The integrator turns the rod by
/// `φ(t) = 2 atan(ω t / 2)`; the face touches the sphere when the centre is
/// `0.05 + 0.1` from the rod's axis: `y cos φ − x sin φ = 0.15`, i.e.
/// `φ* = acos(0.15 / √(x² + y²)) − atan2(x, y)`, when the centre's projection on the
/// axis, `x cos φ* + y sin φ*`, is inside the face (< 1). Then `t* = 2 tan(φ*/2) / ω`.
#[test]
fn spinning_rod_matches_the_rotating_face_formula() {
    let rod = Shape::cuboid(Vec3::new(1.0, 0.05, 0.05)).unwrap();
    let ball = Shape::sphere(0.1).unwrap();
    let mut rng = SplitMix64::new(0x5b1);
    let tol = 1.0e-3;
    let mut checked = 0;
    let mut worst_gap = 0.0f64;
    for _ in 0..300 {
        let (x, y) = (rng.range(0.2, 0.8) as f64, rng.range(0.25, 0.8) as f64);
        let omega = rng.range(5.0, 80.0);
        let phi = (0.15 / (x * x + y * y).sqrt()).acos() - x.atan2(y);
        if phi <= 0.0 || x * phi.cos() + y * phi.sin() >= 0.95 {
            continue; // the sphere would meet the rod's end, not its face
        }
        let t_star = 2.0 * (phi / 2.0).tan() / omega as f64;
        let rod_motion = Motion {
            pose: Iso::IDENTITY,
            linear: Vec3::ZERO,
            angular: Vec3::new(0.0, 0.0, omega),
        };
        let ball_motion = still(Vec3::new(x as f32, y as f32, 0.0));
        let t_max = 0.2;
        let toi = time_of_impact(&rod, &rod_motion, &ball, &ball_motion, t_max, tol).unwrap();
        if t_star > t_max as f64 {
            assert!(!matches!(toi, Toi::Overlapping));
            continue;
        }
        let Toi::Hit { time, .. } = toi else {
            panic!("({x}, {y}) ω {omega}: {toi:?}, expected a hit at {t_star}");
        };
        checked += 1;
        // The analytic gap at the reported time: distance to the axis minus 0.15.
        let phi_h = 2.0 * (omega as f64 * time as f64 / 2.0).atan();
        let gap = y * phi_h.cos() - x * phi_h.sin() - 0.15;
        worst_gap = worst_gap.max(gap);
        assert!(
            time as f64 <= t_star + 1e-6,
            "hit {time} after touch {t_star}"
        );
        // 1e-5: f32 rotation of a 1 m rod.
        assert!(
            gap > -1e-5 && gap <= tol as f64 + 1e-5,
            "gap {gap} at the hit"
        );
    }
    assert!(checked > 100, "{checked}");
    std::println!("spinning rod: {checked} face hits, largest gap {worst_gap:.2e}");
}

/// A rod spinning fast about its own long axis (600 rad/s, 10 rad over the window) beside
/// a ball whose surface stands 0.2 mm inside the circle of the rod's edges: each edge
/// clips the ball for about 0.26 ms. The closing-speed bound takes the distance of the
/// rod's edges from the spin axis (7 cm: 42 m/s), not its 4 m reach (2400 m/s, 140 times
/// the edges' real speed, under which advancement crawled). Brute force (GJK every 0.5 µs)
/// sees the touch; the answer must be a hit before it, never `Separated`.
#[test]
fn a_rod_spinning_about_its_axis_clips_a_ball_and_is_not_missed() {
    let rod = Shape::cuboid(Vec3::new(4.0, 0.05, 0.05)).unwrap();
    let ball = Shape::sphere(0.02).unwrap();
    let (t_max, tol) = (1.0f32 / 60.0, 1.0e-3f32);
    let edge = 0.05f32 * core::f32::consts::SQRT_2;
    for (i, &(start, x)) in [(0.0f32, 3.0f32), (0.4, -2.0), (-0.3, 0.5)]
        .iter()
        .enumerate()
    {
        let rod_motion = Motion {
            pose: Iso::new(Vec3::ZERO, Quat::from_axis_angle(Vec3::X, start)),
            linear: Vec3::ZERO,
            angular: Vec3::new(600.0, 0.0, 0.0),
        };
        let ball_motion = still(Vec3::new(x, edge - 2.0e-4 + 0.02, 0.0));
        let toi = time_of_impact(&rod, &rod_motion, &ball, &ball_motion, t_max, tol).unwrap();
        let touch = brute_force_touch(&rod, &rod_motion, &ball, &ball_motion, t_max)
            .expect("an edge clips the ball");
        let Toi::Hit { time, .. } = toi else {
            panic!("case {i}: {toi:?}, brute force touches at {touch}");
        };
        assert!(time <= touch, "case {i}: {time} after the touch at {touch}");
        let gap = gjk_gap(&rod, &rod_motion, &ball, &ball_motion, time);
        assert!(
            gap > 0.0 && gap <= tol + 1e-5,
            "case {i}: gap {gap} at {time}"
        );
    }
}

/// The first time, in steps of 0.5 µs over `[0, t_max]`, at which GJK finds the shapes
/// touching.
fn brute_force_touch(a: &Shape, ma: &Motion, b: &Shape, mb: &Motion, t_max: f32) -> Option<f32> {
    let h = 5.0e-7;
    (0..=(t_max / h) as u32)
        .map(|k| k as f32 * h)
        .find(|&t| gjk_gap(a, ma, b, mb, t) <= 0.0)
}

/// A 32-sided polygonal wheel (a hull of 64 points, radius 1 m, axle along y). Spinning
/// at 300 rad/s about its axle beside a wall, its gap changes by 5 mm at most while the
/// closing-speed bound counts its 300 m/s rim: advancement crawls and the certified
/// search runs.
fn wheel() -> ConvexHull {
    let mut points = Vec::new();
    for k in 0..32 {
        let a = k as f32 * core::f32::consts::TAU / 32.0;
        for y in [-0.5f32, 0.5] {
            points.push(Vec3::new(a.cos(), y, a.sin()));
        }
    }
    ConvexHull::new(&points).unwrap()
}

/// The wheel of [`wheel`] with a wall 0.3 mm inside the circle of its rim corners: each
/// corner clips the wall for 0.16 ms after the wheel has crawled a quarter of a
/// millisecond at a few millimetres. The search finds the first clip (brute force, GJK
/// every 0.5 µs, agrees); the old fallback, 32 equal steps of 0.5 ms, could step over it.
#[test]
fn a_spinning_polygonal_wheel_clipping_a_wall_is_found_by_the_search() {
    let hull = wheel();
    let wheel = Shape::hull(&hull);
    let wall = Shape::cuboid(Vec3::new(0.5, 2.0, 2.0)).unwrap();
    let (t_max, tol) = (1.0f32 / 60.0, 1.0e-4f32);
    for (i, &start) in [0.0f32, 0.05, -0.06].iter().enumerate() {
        let spin = Motion {
            // A face, not a corner, faces the wall at the start (half a sector turned).
            pose: Iso::new(
                Vec3::ZERO,
                Quat::from_axis_angle(Vec3::Y, core::f32::consts::PI / 32.0 + start),
            ),
            linear: Vec3::ZERO,
            angular: Vec3::new(0.0, 300.0, 0.0),
        };
        let wall_motion = still(Vec3::new(0.9997 + 0.5, 0.0, 0.0));
        let toi = time_of_impact(&wheel, &spin, &wall, &wall_motion, t_max, tol).unwrap();
        let touch = brute_force_touch(&wheel, &spin, &wall, &wall_motion, t_max)
            .expect("a corner clips the wall");
        let Toi::Hit { time, .. } = toi else {
            panic!("case {i}: {toi:?}, brute force touches at {touch}");
        };
        assert!(time <= touch, "case {i}: {time} after the touch at {touch}");
        let gap = gjk_gap(&wheel, &spin, &wall, &wall_motion, time);
        assert!(
            gap > 0.0 && gap <= tol + 1e-5,
            "case {i}: gap {gap} at {time}"
        );
    }
}

/// The same wheel 2 mm clear of the wall for the whole window: nothing touches, but the
/// bound cannot certify 1/60 s at a few millimetres under 300 m/s within the budget. It
/// ends in `Unresolved`, with a time up to which the shapes are certainly apart, never a
/// claimed hit or a guess.
#[test]
fn a_budget_that_runs_out_is_unresolved_not_a_guess() {
    let hull = wheel();
    let wheel = Shape::hull(&hull);
    let wall = Shape::cuboid(Vec3::new(0.5, 2.0, 2.0)).unwrap();
    let spin = Motion {
        pose: Iso::IDENTITY,
        linear: Vec3::ZERO,
        angular: Vec3::new(0.0, 300.0, 0.0),
    };
    let wall_motion = still(Vec3::new(1.0 + 0.002 + 0.5, 0.0, 0.0));
    let (t_max, tol) = (1.0f32 / 60.0, 1.0e-3f32);
    let toi = time_of_impact(&wheel, &spin, &wall, &wall_motion, t_max, tol).unwrap();
    let Toi::Unresolved { time } = toi else {
        panic!("expected the budget to run out: {toi:?}");
    };
    assert!((0.0..t_max).contains(&time), "{time}");
    assert!(brute_force_touch(&wheel, &spin, &wall, &wall_motion, t_max).is_none());
    let gap = gjk_gap(&wheel, &spin, &wall, &wall_motion, time);
    assert!(gap >= 0.002 - 1e-5, "gap {gap} at {time}");
}

/// The rod's end sweeping past a sphere near its tip, against brute force: GJK sampled
/// every 2 µs finds the first touching sample; the reported hit must come before it and
/// after the last sample that is more than the tolerance apart.
#[test]
fn spinning_rod_tip_matches_brute_force() {
    let rod = Shape::cuboid(Vec3::new(1.0, 0.05, 0.05)).unwrap();
    let ball = Shape::sphere(0.1).unwrap();
    let rod_motion = Motion {
        pose: Iso::new(Vec3::ZERO, Quat::from_axis_angle(Vec3::Z, -0.3)),
        linear: Vec3::ZERO,
        angular: Vec3::new(0.0, 0.0, 40.0),
    };
    for (i, &(x, y, z)) in [
        (1.05f32, 0.2f32, 0.0f32),
        (1.03, 0.3, 0.06),
        (0.95, 0.4, -0.1),
    ]
    .iter()
    .enumerate()
    {
        let ball_motion = still(Vec3::new(x, y, z));
        let (t_max, tol) = (0.05f32, 1.0e-3f32);
        let toi = time_of_impact(&rod, &rod_motion, &ball, &ball_motion, t_max, tol).unwrap();
        let h = 2.0e-6;
        let steps = (t_max / h) as u32;
        let first = |pred: &dyn Fn(f32) -> bool| {
            (0..=steps)
                .map(|k| k as f32 * h)
                .find(|&t| pred(gjk_gap(&rod, &rod_motion, &ball, &ball_motion, t)))
        };
        let touch = first(&|g| g <= 0.0).expect("the tip reaches the ball");
        let near = first(&|g| g <= tol).expect("the tip comes near");
        let Toi::Hit { time, .. } = toi else {
            panic!("case {i}: {toi:?}")
        };
        // One sample of slack each way: the brute force only sees multiples of h.
        assert!(
            time <= touch && time >= near - h,
            "case {i}: {time} not in [{near}, {touch}]"
        );
        let gap = gjk_gap(&rod, &rod_motion, &ball, &ball_motion, time);
        assert!(gap > 0.0 && gap <= tol + 1e-5, "case {i}: gap {gap}");
    }
}

#[test]
fn overlapping_at_start_is_reported() {
    let s = Shape::sphere(0.5).unwrap();
    let b = Shape::cuboid(Vec3::splat(0.5)).unwrap();
    let ma = moving(Vec3::ZERO, Vec3::new(-10.0, 0.0, 0.0));
    let mb = moving(Vec3::new(0.9, 0.0, 0.0), Vec3::new(10.0, 0.0, 0.0));
    // Moving apart, but overlapping by 0.1 m at time 0.
    assert_eq!(
        time_of_impact(&s, &ma, &b, &mb, DT, 1e-3).unwrap(),
        Toi::Overlapping
    );
    // Within the tolerance but apart at time 0: a hit at time 0.
    let mb_close = still(Vec3::new(1.0005, 0.0, 0.0));
    let toi = time_of_impact(&s, &still(Vec3::ZERO), &b, &mb_close, DT, 1e-3).unwrap();
    assert!(
        matches!(toi, Toi::Hit { time, .. } if time == 0.0),
        "{toi:?}"
    );
}

#[test]
fn moving_apart_is_separated() {
    let s = Shape::sphere(0.5).unwrap();
    let b = Shape::cuboid(Vec3::new(0.3, 0.2, 0.4)).unwrap();
    let ma = Motion {
        pose: Iso::IDENTITY,
        linear: Vec3::new(-100.0, 0.0, 0.0),
        angular: Vec3::new(3.0, 50.0, -7.0), // a spinning sphere is still a sphere
    };
    let mb = moving(Vec3::new(1.0, 0.0, 0.0), Vec3::new(100.0, 5.0, 0.0));
    assert_eq!(
        time_of_impact(&s, &ma, &b, &mb, 1.0, 1e-3).unwrap(),
        Toi::Separated
    );
    // Parallel motion at the same velocity keeps a 0.2 m gap.
    let v = Vec3::new(30.0, -40.0, 2.0);
    let mb_same = moving(Vec3::new(1.0, 0.0, 0.0), v);
    let ma_same = moving(Vec3::ZERO, v);
    assert_eq!(
        time_of_impact(&s, &ma_same, &b, &mb_same, 1.0, 1e-3).unwrap(),
        Toi::Separated
    );
}

#[test]
fn bad_input_gives_exact_errors() {
    let s = Shape::sphere(0.5).unwrap();
    let ok = still(Vec3::ZERO);
    let other = still(Vec3::new(3.0, 0.0, 0.0));
    let toi =
        |ma: &Motion, mb: &Motion, t_max: f32, tol: f32| time_of_impact(&s, ma, &s, mb, t_max, tol);
    let nan_v = moving(Vec3::ZERO, Vec3::new(f32::NAN, 0.0, 0.0));
    assert_eq!(
        toi(&nan_v, &other, DT, 1e-3),
        Err(Error::NonFinite(Input::LinearVelocity))
    );
    let inf_w = Motion {
        angular: Vec3::new(0.0, f32::INFINITY, 0.0),
        ..ok
    };
    assert_eq!(
        toi(&ok, &inf_w, DT, 1e-3),
        Err(Error::NonFinite(Input::AngularVelocity))
    );
    assert_eq!(
        toi(&ok, &other, 0.0, 1e-3),
        Err(Error::NotPositive(Input::Time))
    );
    assert_eq!(
        toi(&ok, &other, -1.0, 1e-3),
        Err(Error::NotPositive(Input::Time))
    );
    assert_eq!(
        toi(&ok, &other, f32::NAN, 1e-3),
        Err(Error::NonFinite(Input::Time))
    );
    assert_eq!(
        toi(&ok, &other, DT, 0.0),
        Err(Error::NotPositive(Input::Distance))
    );
    let stretched = Motion {
        pose: Iso::new(Vec3::ZERO, Quat::from_xyzw(0.0, 0.0, 0.0, 2.0)),
        ..ok
    };
    assert_eq!(
        toi(&stretched, &other, DT, 1e-3),
        Err(Error::NotUnit(Input::Rotation))
    );
    let lost = still(Vec3::new(f32::NAN, 0.0, 0.0));
    assert_eq!(
        toi(&ok, &lost, DT, 1e-3),
        Err(Error::NonFinite(Input::Position))
    );
}

/// Hulls of 16 random points in a ball of radius 0.2 to 1 m, centred off the local origin
/// so that the rotation about the origin swings them.
fn random_hulls(rng: &mut SplitMix64) -> Vec<ConvexHull> {
    (0..6)
        .map(|_| {
            let size = rng.range(0.2, 1.0);
            let offset = rng.unit_vector() * rng.range(0.0, 0.5);
            let points: Vec<Vec3> = (0..16)
                .map(|_| offset + rng.unit_vector() * (size * rng.range(0.3, 1.0)))
                .collect();
            ConvexHull::new(&points).expect("16 random points span a volume")
        })
        .collect()
}

/// A sphere, capsule, box, hull (from `hulls`) or triangle of random size.
fn random_shape<'h>(rng: &mut SplitMix64, hulls: &'h [ConvexHull]) -> Shape<'h> {
    match (rng.next_u64() % 5) as u32 {
        0 => Shape::sphere(rng.range(0.05, 1.0)).unwrap(),
        1 => Shape::capsule(rng.range(0.05, 1.0), rng.range(0.05, 0.5)).unwrap(),
        2 => Shape::cuboid(Vec3::new(
            rng.range(0.02, 1.0),
            rng.range(0.02, 1.0),
            rng.range(0.02, 2.0),
        ))
        .unwrap(),
        3 => Shape::hull(&hulls[(rng.next_u64() % hulls.len() as u64) as usize]),
        _ => {
            let size = rng.range(0.1, 1.5);
            let mut corner = || rng.unit_vector() * size;
            let (p, q, r) = (corner(), corner(), corner());
            Shape::triangle(p, q, r).unwrap_or(Shape::sphere(size).unwrap())
        }
    }
}

fn random_motion(rng: &mut SplitMix64, spread: f32, speed: f32, spin: f32) -> Motion {
    Motion {
        pose: Iso::new(rng.unit_vector() * rng.range(0.0, spread), rng.rotation()),
        linear: rng.unit_vector() * rng.range(0.0, speed),
        angular: rng.unit_vector() * rng.range(0.0, spin),
    }
}

/// The box at 100 evenly spaced times lies inside the movement bounds, for slow and fast
/// spins (up to 3000 rad/s over 1/60 s, 50 radians); pure translation gives exactly the
/// union of the end boxes (plus the rounding slack).
#[test]
fn movement_bounds_contain_the_swept_shape() {
    let mut rng = SplitMix64::new(0xb0);
    let hulls = random_hulls(&mut rng);
    for i in 0..2000 {
        let shape = random_shape(&mut rng, &hulls);
        let spin = [0.0, 1.0, 30.0, 3000.0][i % 4];
        let m = random_motion(&mut rng, 10.0, 200.0, spin);
        let dt = rng.range(0.001, 0.1);
        let bounds = movement_bounds(&shape, &m, dt);
        for k in 0..100 {
            let t = dt * k as f32 / 99.0;
            let b = shape.aabb(&m.pose_at(t));
            assert!(
                bounds.contains(&b),
                "case {i} t {t}: {b:?} not in {bounds:?}"
            );
        }
        if spin == 0.0 {
            let ends = shape
                .aabb(&m.pose_at(0.0))
                .union(&shape.aabb(&m.pose_at(dt)));
            let excess = (ends.min - bounds.min)
                .max_elem()
                .max((bounds.max - ends.max).max_elem());
            // 1e-6 relative slack at coordinates up to ~30 m.
            assert!(
                excess <= 5e-5,
                "case {i}: translation bounds grew by {excess}"
            );
        }
    }
}

/// The shared properties (no panic, time in range, gap at the hit, no tunnelling before
/// it, separated means apart at 256 times, movement bounds hold) over random pairs of
/// spheres, capsules, boxes, hulls, triangles and a floor, close together and moving fast
/// and spinning (up to 30 rad/s each, so at most 6 rad in all over the longest window,
/// inside the one-turn range where no miss is allowed). All three outcomes must occur often.
#[test]
fn toi_properties_hold_on_random_pairs() {
    let mut rng = SplitMix64::new(0x7013);
    let hulls = random_hulls(&mut rng);
    let floor = Shape::half_space(Vec3::Y).unwrap();
    let mut outcomes = [0u32; 3];
    for i in 0..3000 {
        let a = random_shape(&mut rng, &hulls);
        let b = if i % 10 == 0 {
            floor
        } else {
            random_shape(&mut rng, &hulls)
        };
        let ma = random_motion(&mut rng, 3.0, 100.0, 30.0);
        let mut mb = random_motion(&mut rng, 3.0, 100.0, 30.0);
        if i % 10 == 0 {
            mb = still(Vec3::new(0.0, -3.0, 0.0));
        }
        let t_max = [DT, 0.05, 0.1][i % 3];
        if i % 2 == 1 {
            // Aim B at A so that they cross within the window.
            let gap = ma.pose.position - mb.pose.position;
            mb.linear = ma.linear + gap * (rng.range(0.0, 2.0) / t_max) + rng.unit_vector() * 5.0;
        }
        let tol = rng.range(1e-3, 1e-2);
        if let Err(v) = toi_properties(&a, &ma, &b, &mb, t_max, tol) {
            panic!("case {i}: {v:?}\n {ma:?}\n {mb:?}\n t_max {t_max} tol {tol}");
        }
        outcomes[match time_of_impact(&a, &ma, &b, &mb, t_max, tol).unwrap() {
            Toi::Hit { .. } => 0,
            Toi::Separated => 1,
            Toi::Overlapping => 2,
            Toi::Unresolved { .. } => 3,
        }] += 1;
    }
    assert!(
        outcomes.iter().all(|&n| n >= 300),
        "hit, separated, overlapping: {outcomes:?}"
    );
}
