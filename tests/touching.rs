//! Exact touching: GJK's distance for shapes a known tiny gap apart.
//!
//! For gaps from 1e-7 m to 0.1 m (40 log-spaced values) and many random rotations, a
//! shape `O` is placed so that its lowest vertex along a face normal `n` of a shape `F`
//! (the supporting vertex along `−n`) sits the gap above a point `p` of that face. The
//! distance is then exactly the gap: it is at least the gap along `n` (the plane of the
//! face separates them) and at most the height of `v` over the face's plane (its foot is
//! inside the face). Both bounds are computed in f64 from the f32
//! poses the query receives, so the oracle carries no f32 rounding; the construction is
//! checked by the two bounds agreeing to 1e-9 m.
//!
//! Asserted for unit boxes, box–hull (both orders), hull–hull and sphere–box (both orders):
//! GJK's `distance` is within [`ABS`] of the exact gap, it never decreases by more than
//! [`ROUNDING`] as the gap grows, and `intersects` is false from a gap of 1e-6 m on.

use carom::collide::{distance, intersects, SimplexCache};
use carom::math::{Iso, Quat, Vec3};
use carom::rng::SplitMix64;
use carom::scenes::queries::{self, HULLS, HULL_POINTS};
use carom::shape::{ConvexHull, Shape};

/// Largest allowed |GJK distance − exact gap| (m).
const ABS: f64 = 1.0e-6;
/// Largest allowed decrease of the distance from one gap to the next larger one (m): one
/// f32 ulp at 1 m (`f32::EPSILON`). B's vertices in A's frame carry about half an ulp of
/// their 1–2 m coordinates, so two answers a few 1e-8 m apart in gap can come out in
/// either order by that much (the largest seen is 1.08e-7 m, at gaps near 2.5e-7 m).
const ROUNDING: f64 = f32::EPSILON as f64;
/// Gaps from which `intersects` must say false (m).
const APART_FROM: f64 = 1.0e-6;
/// Number of gaps in the sweep.
const GAPS: usize = 40;
/// Rotations tried per pair kind.
const ROTATIONS: usize = 150;

type V = [f64; 3];

fn v64(v: Vec3) -> V {
    [v.x as f64, v.y as f64, v.z as f64]
}
fn v32(v: V) -> Vec3 {
    Vec3::new(v[0] as f32, v[1] as f32, v[2] as f32)
}
fn add(a: V, b: V) -> V {
    [a[0] + b[0], a[1] + b[1], a[2] + b[2]]
}
fn sub(a: V, b: V) -> V {
    [a[0] - b[0], a[1] - b[1], a[2] - b[2]]
}
fn scale(a: V, s: f64) -> V {
    [a[0] * s, a[1] * s, a[2] * s]
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
fn length(a: V) -> f64 {
    dot(a, a).sqrt()
}
fn unit(a: V) -> V {
    scale(a, 1.0 / length(a))
}

/// `q` (normalised in f64) applied to `v`.
fn rotate(q: Quat, v: V) -> V {
    let n =
        ((q.x as f64).powi(2) + (q.y as f64).powi(2) + (q.z as f64).powi(2) + (q.w as f64).powi(2))
            .sqrt();
    let (x, y, z, w) = (
        q.x as f64 / n,
        q.y as f64 / n,
        q.z as f64 / n,
        q.w as f64 / n,
    );
    let u = [x, y, z];
    let t = scale(cross(u, v), 2.0);
    add(add(v, scale(t, w)), cross(u, t))
}
fn inverse_rotate(q: Quat, v: V) -> V {
    rotate(Quat::from_xyzw(-q.x, -q.y, -q.z, q.w), v)
}
fn to_world(pose: &Iso, p: V) -> V {
    add(rotate(pose.rotation, p), v64(pose.position))
}

/// A shape with its geometry in f64: core vertices, radius, faces (outward unit normal
/// and vertices, planar to 1e-12 m).
struct Solid<'h> {
    shape: Shape<'h>,
    vertices: Vec<V>,
    radius: f64,
    faces: Vec<(V, Vec<V>)>,
}

fn cuboid(h: f32) -> Solid<'static> {
    let mut vertices = Vec::new();
    for i in 0..8 {
        let s = |bit: usize| if i & bit != 0 { h as f64 } else { -(h as f64) };
        vertices.push([s(1), s(2), s(4)]);
    }
    let mut faces = Vec::new();
    for axis in 0..3 {
        for sign in [1.0, -1.0] {
            let mut n = [0.0; 3];
            n[axis] = sign;
            let on: Vec<V> = vertices
                .iter()
                .copied()
                .filter(|v| v[axis] * sign > 0.0)
                .collect();
            faces.push((n, on));
        }
    }
    Solid {
        shape: Shape::cuboid(Vec3::splat(h)).unwrap(),
        vertices,
        radius: 0.0,
        faces,
    }
}

fn sphere(r: f32) -> Solid<'static> {
    Solid {
        shape: Shape::sphere(r).unwrap(),
        vertices: vec![[0.0; 3]],
        radius: r as f64,
        faces: Vec::new(),
    }
}

/// A hull with its triangular faces (their planes are exact in f64; a polygon face is
/// split into the triangles of a fan, each with its own f64 plane, and kept only when its
/// vertices lie on that plane to 1e-12 m).
fn hull(h: &ConvexHull) -> Solid<'_> {
    let vertices: Vec<V> = h.vertices().iter().map(|&p| v64(p)).collect();
    let mut faces = Vec::new();
    for f in 0..h.face_count() {
        let idx = h.face_vertices(f);
        let pts: Vec<V> = idx.iter().map(|&i| vertices[i as usize]).collect();
        let n = unit(cross(sub(pts[1], pts[0]), sub(pts[2], pts[0])));
        let planar = pts.iter().all(|p| dot(n, sub(*p, pts[0])).abs() <= 1.0e-12);
        if planar {
            faces.push((n, pts));
        }
    }
    Solid {
        shape: Shape::hull(h),
        vertices,
        radius: 0.0,
        faces,
    }
}

/// One random placement, swept over the gaps: `F` with the face, `O` above it.
struct Placement {
    pose_f: Iso,
    rot_o: Quat,
    /// The face's normal and point `p`, world frame.
    n: V,
    p: V,
    /// `O`'s lowest core vertex along `−n` (local frame).
    low_o: V,
}

fn place(f: &Solid, o: &Solid, rng: &mut SplitMix64, offset: f32) -> Placement {
    let pose_f = Iso::new(
        Vec3::new(
            rng.range(-offset, offset),
            rng.range(-offset, offset),
            rng.range(-offset, offset),
        ),
        rng.rotation(),
    );
    let rot_o = rng.rotation();
    let k = (rng.next_u64() % f.faces.len() as u64) as usize;
    let (n_local, pts) = &f.faces[k];
    // A random point of the face: a convex combination of its vertices, weights >= 0.05.
    let weights: Vec<f64> = pts.iter().map(|_| 0.05 + rng.next_f32() as f64).collect();
    let total: f64 = weights.iter().sum();
    let mut p_local = [0.0; 3];
    for (w, q) in weights.iter().zip(pts) {
        p_local = add(p_local, scale(*q, w / total));
    }
    let n = rotate(pose_f.rotation, *n_local);
    let p = to_world(&pose_f, p_local);
    let down = inverse_rotate(rot_o, scale(n, -1.0));
    let low_o = *o
        .vertices
        .iter()
        .max_by(|a, b| dot(**a, down).total_cmp(&dot(**b, down)))
        .unwrap();
    Placement {
        pose_f,
        rot_o,
        n,
        p,
        low_o,
    }
}

/// `O`'s pose for gap `g`, and the exact gap of the f32 poses (f64).
fn pose_for_gap(f: &Solid, o: &Solid, pl: &Placement, g: f64) -> (Iso, f64) {
    // The lowest surface point of O (core vertex minus n·radius) at p + n·g.
    let target = add(pl.p, scale(pl.n, g + o.radius));
    let centre = sub(target, rotate(pl.rot_o, pl.low_o));
    let pose_o = Iso::new(v32(centre), pl.rot_o);
    // Lower bound: the gap along n between the f32-posed shapes.
    let top_f = f
        .vertices
        .iter()
        .map(|v| dot(pl.n, to_world(&pl.pose_f, *v)))
        .fold(f64::NEG_INFINITY, f64::max)
        + f.radius;
    let low = o
        .vertices
        .iter()
        .map(|v| dot(pl.n, to_world(&pose_o, *v)))
        .fold(f64::INFINITY, f64::min)
        - o.radius;
    let lower = low - top_f;
    // Upper bound: from O's lowest point to its foot on the face's plane, which is inside
    // the face: the foot is p moved sideways by the f32 rounding of O's position (1e-7 m),
    // and p is at least 5 % of the face's size from its edges.
    let lowest = to_world(&pose_o, pl.low_o);
    let upper = dot(pl.n, sub(lowest, pl.p)) - o.radius;
    // Off the origin, the f32 rounding of the positions (1e-7 m) can close a gap of 1e-7 m:
    // the shapes then touch, at distance 0.
    assert!(
        upper - lower <= 1.0e-9 && lower > -1.0e-6,
        "construction: {lower} {upper} at {g}"
    );
    (pose_o, lower.max(0.0))
}

/// Results of one sweep kind.
#[derive(Default, Debug)]
struct Stats {
    max_error: f64,
    max_decrease: f64,
    worst: String,
    /// Placements at a gap of at least [`APART_FROM`] that `intersects` called touching.
    intersecting: usize,
    worst_decrease: String,
    largest_intersecting: f64,
}

/// Sweep `ROTATIONS` placements of `o` over a face of `f`; the query is `distance(f, o)`
/// or, with `f_is_b`, `distance(o, f)`.
fn sweep(f: &Solid, o: &Solid, f_is_b: bool, seed: u64, offset: f32, stats: &mut Stats) {
    let mut rng = SplitMix64::new(seed);
    let gaps: Vec<f64> = (0..GAPS)
        .map(|k| 1.0e-7 * 10f64.powf(6.0 * k as f64 / (GAPS - 1) as f64))
        .collect();
    for r in 0..ROTATIONS {
        let pl = place(f, o, &mut rng, offset);
        let mut previous = (f64::NEG_INFINITY, f64::NEG_INFINITY);
        for &g in &gaps {
            let (pose_o, exact) = pose_for_gap(f, o, &pl, g);
            let (a, pa, b, pb) = if f_is_b {
                (&o.shape, &pose_o, &f.shape, &pl.pose_f)
            } else {
                (&f.shape, &pl.pose_f, &o.shape, &pose_o)
            };
            let d = distance(a, pa, b, pb, &mut SimplexCache::default()).unwrap();
            let got = d.distance as f64;
            let error = (got - exact).abs();
            if error > stats.max_error {
                stats.max_error = error;
                stats.worst = format!(
                    "rotation {r} gap {g:e}: {got:e} vs {exact:e} ({d:?}) poses {pa:?} {pb:?}"
                );
            }
            // A decrease of the exact gap itself (f32 rounding of the poses) is allowed.
            let decrease = (previous.0 - got) - (previous.1 - exact).max(0.0);
            if decrease > stats.max_decrease {
                stats.max_decrease = decrease;
                stats.worst_decrease = format!(
                    "rotation {r} gap {g:e}: {got:e} after {:e} (exact {exact:e} after {:e}), {d:?}, poses {pa:?} {pb:?}",
                    previous.0, previous.1
                );
            }
            previous = (got, exact);
            if exact >= APART_FROM && intersects(a, pa, b, pb).unwrap() {
                stats.intersecting += 1;
                stats.largest_intersecting = stats.largest_intersecting.max(exact);
            }
        }
    }
}

fn benchmark_hulls() -> Vec<ConvexHull> {
    let mut clouds = vec![[Vec3::ZERO; HULL_POINTS]; HULLS];
    queries::hull_clouds(&mut clouds);
    clouds.iter().map(|c| ConvexHull::new(c).unwrap()).collect()
}

fn check(name: &str, stats: &Stats, failures: &mut Vec<String>) {
    eprintln!(
        "{name}: max |error| {:.3e} m, max decrease {:.3e} m, intersecting from 1e-6 m: {} (up to {:.3e} m)",
        stats.max_error, stats.max_decrease, stats.intersecting, stats.largest_intersecting
    );
    if stats.intersecting > 0 {
        failures.push(format!("{name}: intersects at a gap"));
    }
    if stats.max_error > ABS {
        failures.push(format!("{name}: {}", stats.worst));
    }
    if stats.max_decrease > ROUNDING {
        failures.push(format!(
            "{name}: distance decreased by {:e} as the gap grew: {}",
            stats.max_decrease, stats.worst_decrease
        ));
    }
}

/// Every pair kind, with the face shape at the origin and at up to ±`offset` m.
fn run(offset: f32, seed: u64) {
    let hulls = benchmark_hulls();
    let cube = cuboid(0.5);
    let ball = sphere(0.5);
    let mut failures = Vec::new();
    let mut s = Stats::default();
    sweep(&cube, &cube, false, seed + 1, offset, &mut s);
    check("box-box", &s, &mut failures);
    let mut s = Stats::default();
    for (k, h) in hulls.iter().take(8).enumerate() {
        sweep(&cube, &hull(h), false, seed + 10 + k as u64, offset, &mut s);
    }
    check("box-hull (box's face)", &s, &mut failures);
    let mut s = Stats::default();
    for (k, h) in hulls.iter().take(8).enumerate() {
        sweep(&hull(h), &cube, true, seed + 20 + k as u64, offset, &mut s);
    }
    check("box-hull (hull's face)", &s, &mut failures);
    let mut s = Stats::default();
    for (k, pair) in hulls.chunks(2).take(8).enumerate() {
        let (h1, h2) = (hull(&pair[0]), hull(&pair[1]));
        sweep(&h1, &h2, k % 2 == 1, seed + 30 + k as u64, offset, &mut s);
    }
    check("hull-hull", &s, &mut failures);
    let mut s = Stats::default();
    sweep(&cube, &ball, true, seed + 40, offset, &mut s);
    sweep(&cube, &ball, false, seed + 41, offset, &mut s);
    check("sphere-box", &s, &mut failures);
    assert!(failures.is_empty(), "{failures:#?}");
}

#[test]
fn touching_gap_sweep_at_the_origin() {
    run(0.0, 1000);
}

#[test]
fn touching_gap_sweep_off_the_origin() {
    run(1.0, 2000);
}
