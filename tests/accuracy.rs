//! Accuracy of the math backend: the narrow phase against exact answers computed in f64,
//! and resting heights of the standard scenes, with the bounds the README states for
//! libm and for `micromath`. The inputs are drawn without trigonometry (rotations are
//! normalised random quaternions), so both backends see the same poses to within one ulp
//! of a square root.
//!
//! The measured figures are printed: `cargo test --test accuracy -- --nocapture` (add
//! `--features micromath` for the other backend) gives the numbers of the README's
//! `micromath` row.

use carom::collide::{distance, penetration, SimplexCache};
use carom::props::{brute_force_distance, core_vertices};
use carom::rng::SplitMix64;
use carom::scenes::{self, ReferenceWorld, Scene};
use carom::{BodyDesc, ConvexHull, Iso, Quat, Shape, Vec3, World};

/// The bounds the README states (m), the same for both backends: with its refined square
/// root (within 1 ulp) `micromath` answers these queries as accurately as libm; only
/// `Quat::from_axis_angle` (not used here) keeps micromath's approximate trigonometry.
/// Measured at the commit that added this file, libm / micromath: distance 9.5e-7 /
/// 9.5e-7, depth 2.0e-7 / 1.9e-7, ball and box resting heights 4.1e-5 / 4.1e-5 (soft
/// contact sag), tower top 1.13e-2 / 1.13e-2 (ten soft contacts, each sagging ~1 mm).
const DISTANCE_BOUND: f64 = 2.0e-6;
/// See [`DISTANCE_BOUND`].
const DEPTH_BOUND: f64 = 1.0e-6;
/// See [`DISTANCE_BOUND`].
const REST_BOUND: f64 = 1.0e-4;
/// See [`DISTANCE_BOUND`].
const TOWER_BOUND: f64 = 2.0e-2;

fn rotation(rng: &mut SplitMix64) -> Quat {
    loop {
        let q = Quat::from_xyzw(
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
            rng.range(-1.0, 1.0),
        );
        let l2 = q.length_squared();
        if l2 > 0.1 && l2 <= 1.0 {
            return q.normalize();
        }
    }
}

fn point(rng: &mut SplitMix64, reach: f32) -> Vec3 {
    Vec3::new(
        rng.range(-reach, reach),
        rng.range(-reach, reach),
        rng.range(-reach, reach),
    )
}

fn pose(rng: &mut SplitMix64, reach: f32) -> Iso {
    Iso::new(point(rng, reach), rotation(rng))
}

type D3 = [f64; 3];

fn d3(v: Vec3) -> D3 {
    [f64::from(v.x), f64::from(v.y), f64::from(v.z)]
}

fn sub(a: D3, b: D3) -> D3 {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}

fn dot(a: D3, b: D3) -> f64 {
    a[0] * b[0] + a[1] * b[1] + a[2] * b[2]
}

fn cross(a: D3, b: D3) -> D3 {
    [
        a[1] * b[2] - a[2] * b[1],
        a[2] * b[0] - a[0] * b[2],
        a[0] * b[1] - a[1] * b[0],
    ]
}

/// The columns of the rotation matrix of `q` (its local axes in the world), in f64.
fn axes(q: Quat) -> [D3; 3] {
    let (x, y, z, w) = (
        f64::from(q.x),
        f64::from(q.y),
        f64::from(q.z),
        f64::from(q.w),
    );
    let n = (x * x + y * y + z * z + w * w).sqrt();
    let (x, y, z, w) = (x / n, y / n, z / n, w / n);
    [
        [
            1.0 - 2.0 * (y * y + z * z),
            2.0 * (x * y + w * z),
            2.0 * (x * z - w * y),
        ],
        [
            2.0 * (x * y - w * z),
            1.0 - 2.0 * (x * x + z * z),
            2.0 * (y * z + w * x),
        ],
        [
            2.0 * (x * z + w * y),
            2.0 * (y * z - w * x),
            1.0 - 2.0 * (x * x + y * y),
        ],
    ]
}

/// Signed distance from `p` to the box (`half`, `pose`) in f64: positive outside,
/// negative inside (minus the depth to the nearest face).
fn box_signed_distance(p: D3, half: Vec3, pose: &Iso) -> f64 {
    let ax = axes(pose.rotation);
    let c = sub(p, d3(pose.position));
    let h = d3(half);
    let local = [dot(c, ax[0]), dot(c, ax[1]), dot(c, ax[2])];
    let mut outside = 0.0;
    let mut inside = f64::NEG_INFINITY;
    for i in 0..3 {
        let e = local[i].abs() - h[i];
        if e > 0.0 {
            outside += e * e;
        }
        inside = inside.max(e);
    }
    if outside > 0.0 {
        outside.sqrt()
    } else {
        inside
    }
}

/// Minimal penetration depth of two overlapping boxes in f64: the smallest overlap over
/// the 15 axes of the separating axis test (exact for boxes).
fn box_box_depth(ha: Vec3, pa: &Iso, hb: Vec3, pb: &Iso) -> f64 {
    let (aa, ab) = (axes(pa.rotation), axes(pb.rotation));
    let (ha, hb) = (d3(ha), d3(hb));
    let t = sub(d3(pb.position), d3(pa.position));
    let mut candidates: Vec<D3> = aa.iter().chain(ab.iter()).copied().collect();
    for u in aa {
        for v in ab {
            let c = cross(u, v);
            let l = dot(c, c).sqrt();
            if l > 1e-6 {
                candidates.push([c[0] / l, c[1] / l, c[2] / l]);
            }
        }
    }
    let radius = |ax: &[D3; 3], h: D3, n: D3| -> f64 {
        (0..3).map(|i| h[i] * dot(ax[i], n).abs()).sum::<f64>()
    };
    candidates
        .iter()
        .map(|n| radius(&aa, ha, *n) + radius(&ab, hb, *n) - dot(t, *n).abs())
        .fold(f64::INFINITY, f64::min)
}

fn dist(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso) -> f64 {
    f64::from(
        distance(a, pa, b, pb, &mut SimplexCache::default())
            .unwrap()
            .distance,
    )
}

fn depth(a: &Shape, pa: &Iso, b: &Shape, pb: &Iso) -> Option<f64> {
    penetration(a, pa, b, pb)
        .unwrap()
        .map(|p| f64::from(p.depth))
}

/// Largest distance and depth errors (m) over the standard query sets.
fn narrow_phase_errors() -> (f64, f64) {
    let mut rng = SplitMix64::new(11);
    let (mut d_err, mut p_err) = (0.0f64, 0.0f64);
    // Sphere pairs, separated and overlapping.
    for _ in 0..2000 {
        let (ra, rb) = (rng.range(0.05, 1.0), rng.range(0.05, 1.0));
        let (a, b) = (Shape::sphere(ra).unwrap(), Shape::sphere(rb).unwrap());
        let (pa, pb) = (pose(&mut rng, 1.5), pose(&mut rng, 1.5));
        let c = sub(d3(pb.position), d3(pa.position));
        let gap = dot(c, c).sqrt() - f64::from(ra) - f64::from(rb);
        if gap > 1e-3 {
            d_err = d_err.max((dist(&a, &pa, &b, &pb) - gap).abs());
        } else if gap < -1e-3 && dot(c, c).sqrt() > 1e-3 {
            p_err = p_err.max((depth(&a, &pa, &b, &pb).unwrap() + gap).abs());
        }
    }
    // Sphere against box.
    for _ in 0..2000 {
        let half = Vec3::new(
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
            rng.range(0.1, 1.0),
        );
        let r = rng.range(0.05, 0.8);
        let (cuboid, ball) = (Shape::cuboid(half).unwrap(), Shape::sphere(r).unwrap());
        let (pa, pb) = (pose(&mut rng, 0.5), pose(&mut rng, 2.0));
        let gap = box_signed_distance(d3(pb.position), half, &pa) - f64::from(r);
        if gap > 1e-3 {
            d_err = d_err.max((dist(&cuboid, &pa, &ball, &pb) - gap).abs());
        } else if gap < -1e-3 {
            p_err = p_err.max((depth(&cuboid, &pa, &ball, &pb).unwrap() + gap).abs());
        }
    }
    // Box pairs: overlapping ones against the 15-axis test.
    for _ in 0..2000 {
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
        let (a, b) = (Shape::cuboid(ha).unwrap(), Shape::cuboid(hb).unwrap());
        let (pa, pb) = (pose(&mut rng, 0.5), pose(&mut rng, 1.5));
        let expected = box_box_depth(ha, &pa, hb, &pb);
        if expected > 1e-3 {
            p_err = p_err.max((depth(&a, &pa, &b, &pb).unwrap() - expected).abs());
        }
    }
    // Hull pairs (16 random points each): distances against the brute-force oracle.
    let mut hulls = Vec::new();
    while hulls.len() < 8 {
        let mut pts = [Vec3::ZERO; 16];
        for p in pts.iter_mut() {
            *p = point(&mut rng, 1.0);
        }
        if let Ok(h) = ConvexHull::new(&pts) {
            hulls.push(h);
        }
    }
    for k in 0..1000 {
        let (a, b) = (
            Shape::hull(&hulls[k % 8]),
            Shape::hull(&hulls[(k * 5 + 3) % 8]),
        );
        let (pa, pb) = (pose(&mut rng, 1.0), pose(&mut rng, 4.0));
        let (va, vb) = (
            core_vertices(&a, &pa).unwrap(),
            core_vertices(&b, &pb).unwrap(),
        );
        let o = brute_force_distance(va.points(), vb.points()).unwrap();
        let expected = f64::from(o.distance);
        if expected > 1e-3 {
            d_err = d_err.max((dist(&a, &pa, &b, &pb) - expected).abs());
        }
    }
    (d_err, p_err)
}

/// Largest error (m) of a resting height, a ball and a box on the ground after 3 s, and
/// the error of the top of the `tower` scene (ten 1 m boxes) after its 1000 steps.
fn resting_height_errors() -> (f64, f64) {
    let mut worst = 0.0f64;
    for (shape, rest) in [
        (Shape::sphere(0.5).unwrap(), 0.5),
        (Shape::cuboid(Vec3::new(0.4, 0.3, 0.6)).unwrap(), 0.3),
    ] {
        let mut w: World<'static, 4, 8> = World::new();
        w.add(
            BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0)).unwrap())
                .position(Vec3::new(0.0, -0.5, 0.0)),
        )
        .unwrap();
        let b = w
            .add(BodyDesc::dynamic(shape).position(Vec3::new(0.0, 2.0, 0.0)))
            .unwrap();
        for _ in 0..180 {
            w.step();
        }
        let y = f64::from(w.body(b).unwrap().position().y);
        println!("rest {shape:?}: y {y:.6} (want {rest})");
        worst = worst.max((y - rest).abs());
    }
    let top = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(|| {
            let tetra = ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z]).unwrap();
            let mut hulls = vec![tetra; scenes::REFERENCE_HULLS];
            scenes::make_hulls(&mut hulls, scenes::SEED).unwrap();
            let mut w: Box<ReferenceWorld<'_>> = Box::new(ReferenceWorld::new());
            w.set_config(Scene::Tower.config()).unwrap();
            let top = Scene::Tower.build(&mut w, &hulls).unwrap();
            for _ in 0..Scene::Tower.steps() {
                w.step();
            }
            f64::from(w.body(top).unwrap().position().y)
        })
        .unwrap()
        .join()
        .unwrap();
    println!("tower top: y {top:.6} (want 9.5)");
    (worst, (top - 9.5).abs())
}

#[test]
fn narrow_phase_and_resting_heights_are_within_the_readme_bounds() {
    let (d_err, p_err) = narrow_phase_errors();
    let (rest, tower) = resting_height_errors();
    let backend = if cfg!(feature = "micromath") {
        "micromath"
    } else {
        "libm"
    };
    println!(
        "{backend}: distance error {d_err:.2e} m, depth error {p_err:.2e} m, \
         resting height error {rest:.2e} m, tower top error {tower:.2e} m"
    );
    assert!(d_err < DISTANCE_BOUND, "distance error {d_err:e}");
    assert!(p_err < DEPTH_BOUND, "depth error {p_err:e}");
    assert!(rest < REST_BOUND, "resting height error {rest:e}");
    assert!(tower < TOWER_BOUND, "tower top error {tower:e}");
}
