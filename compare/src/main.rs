//! carom against rapier3d (whole scenes) and parry3d (narrow-phase queries), side by side,
//! from one definition of each scene (`carom::scenes::Scene::for_each_body`) and of each
//! query set (`carom::scenes::queries`).
//!
//! ```text
//! cargo run --release --manifest-path compare/Cargo.toml -- [scene|narrow ...] [--reps N] [--steps N]
//! cargo run --release --manifest-path compare/Cargo.toml --features stages -- --stages [scene ...]
//! ```
//!
//! With no names: pyramid20, pyramid100, boxes, spheres, hulls, jolt_pyramid, then the
//! narrow phase. Each repetition runs carom's whole scene then rapier's (which goes first
//! alternates), each in a freshly built world with sleeping off, timing every step; the
//! tables show medians over the repetitions, and the ratio is taken per repetition (paired
//! runs on a shared, noisy machine) before its median. Progress goes to stderr, tables to
//! stdout (Markdown).
//!
//! `--stages` prints instead where each engine's step goes, stage by stage (`stages.rs`);
//! rapier's columns need the `stages` feature (its own timers, off in the ratio table).
//!
//! Built for wasm32-wasip1 (with `-C target-feature=+simd128` for both engines' SIMD) it
//! runs under Node (`demos/wasm/run.mjs`), on the main thread with a 512 MiB stack set at
//! link time (`build.rs`); `BENCHMARKS.md` has the commands.

mod stages;

use std::fmt::Write as _;
use std::hint::black_box;
use std::time::{Duration, Instant};

use carom::collide::{self, SimplexCache};
use carom::scenes::queries::{
    self, PoseQuery, QuerySet, BALL_RADIUS, BOX_HALF, CONTACT_MARGIN, HULLS, HULL_POINTS, PAIRS,
};
use carom::scenes::{self, Scene, SceneBody, SceneKind, SceneShape, JOLT_PYRAMID_GAP};
use carom::shape::HeightField;
use carom::{BodyKind, ConvexHull, Iso, Shape, World, WorldConfig};
use parry3d::query::{
    self as pq, ContactManifold, DefaultQueryDispatcher, PersistentQueryDispatcher,
};
use parry3d::shape::{Ball, ConvexPolyhedron, Cuboid, SharedShape, TriMeshFlags};
use rapier3d::prelude::{
    CoefficientCombineRule, ColliderBuilder, PhysicsWorld, Pose, RigidBodyBuilder, RigidBodyHandle,
    Rotation, Vector,
};

/// The scenes run when none is named.
const DEFAULT_SCENES: [Scene; 7] = [
    Scene::Pyramid20,
    Scene::Pyramid100,
    Scene::Boxes,
    Scene::Spheres,
    Scene::Hulls,
    Scene::JoltPyramid,
    Scene::MeshPile,
];

/// The `mesh_pile` terrain for carom, built once and leaked so every world can borrow it.
fn terrain() -> Result<&'static HeightField<'static>, Fail> {
    let mut heights = vec![0.0f32; scenes::MESH_PILE_SAMPLES];
    scenes::mesh_pile_heights(&mut heights);
    let heights: &'static [f32] = Box::leak(heights.into_boxed_slice());
    Ok(Box::leak(Box::new(scenes::mesh_pile_field(heights)?)))
}

/// The same terrain for rapier: a triangle mesh of the height field's triangles over its
/// samples (vertex `j · columns + i` is sample `(i, j)`), with rapier's internal-edge
/// fix on (`TriMeshFlags::FIX_INTERNAL_EDGES`, its counterpart of carom's rule).
fn rapier_terrain() -> Result<SharedShape, Fail> {
    let field = terrain()?;
    let (n, cell) = (field.columns(), field.cell_size());
    let mut vertices = Vec::new();
    for (k, &h) in field.heights().iter().enumerate() {
        let (i, j) = (k as u32 % n, k as u32 / n);
        vertices.push(Vector::new(i as f32 * cell, h, j as f32 * cell));
    }
    let index = |p: carom::Vec3| {
        let (i, j) = ((p.x / cell).round() as u32, (p.z / cell).round() as u32);
        j * n + i
    };
    let mut indices = Vec::new();
    for t in 0..field.triangle_count() {
        let tri = field
            .triangle(t)
            .ok_or_else(|| Fail(format!("terrain triangle {t}")))?;
        indices.push(tri.vertices.map(index));
    }
    SharedShape::trimesh_with_flags(vertices, indices, TriMeshFlags::FIX_INTERNAL_EDGES)
        .map_err(|e| Fail(format!("rapier trimesh: {e:?}")))
}

/// Hulls the hull scenes cycle through (as `benches/scenes.rs`).
const SCENE_HULLS: usize = 64;

/// Passes over a query set's 4096 pairs per timed narrow-phase repetition.
const NARROW_PASSES: u32 = 25;

/// Worlds with at most this many bodies use [`SmallWorld`], larger ones [`LargeWorld`].
const SMALL_BODIES: usize = 1024;
type SmallWorld<'a> = World<'a, SMALL_BODIES, 8192, 64>;
type LargeWorld<'a> = World<'a, 5120, 32768, 64>;

/// Any failure: a message.
#[derive(Debug)]
struct Fail(String);

impl From<carom::Error> for Fail {
    fn from(e: carom::Error) -> Self {
        Fail(format!("carom: {e}"))
    }
}

impl std::fmt::Display for Fail {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        f.write_str(&self.0)
    }
}

struct Args {
    scenes: Vec<Scene>,
    narrow: bool,
    /// The stage table (`stages.rs`) instead of the ratio and narrow-phase tables.
    stages: bool,
    reps: usize,
    steps: Option<u32>,
}

fn usage() -> String {
    // The terrain reference scenes are for determinism only; their ground is not built here.
    let names: Vec<&str> = Scene::ALL
        .iter()
        .filter(|s| !matches!(s, Scene::Terrain | Scene::TerrainMesh))
        .map(|s| s.name())
        .collect();
    format!(
        "usage: compare [NAME ...] [--reps N] [--steps N] [--stages]\n\
         NAME: a scene ({}) or `narrow`; default: {} and narrow\n\
         --reps N: paired repetitions (default 3); --steps N: steps per scene run (default: SCENES.md's)\n\
         --stages: ms per step of each stage of each engine instead (rapier's with `--features stages`)",
        names.join(", "),
        DEFAULT_SCENES.map(|s| s.name()).join(", ")
    )
}

fn parse_args() -> Result<Args, Fail> {
    let mut args = Args {
        scenes: Vec::new(),
        narrow: false,
        stages: false,
        reps: 3,
        steps: None,
    };
    let mut named = false;
    let mut it = std::env::args().skip(1);
    while let Some(a) = it.next() {
        let mut number = |what: &str| -> Result<u64, Fail> {
            it.next()
                .and_then(|v| v.parse::<u64>().ok())
                .filter(|n| *n > 0)
                .ok_or_else(|| Fail(format!("{what} needs a positive number\n{}", usage())))
        };
        match a.as_str() {
            "--reps" => args.reps = number("--reps")? as usize,
            "--steps" => args.steps = Some(number("--steps")?.min(u64::from(u32::MAX)) as u32),
            "--stages" => args.stages = true,
            "-h" | "--help" => {
                println!("{}", usage());
                std::process::exit(0);
            }
            "narrow" => {
                named = true;
                args.narrow = true;
            }
            name => {
                named = true;
                let scene = Scene::from_name(name)
                    .filter(|s| !matches!(s, Scene::Terrain | Scene::TerrainMesh))
                    .ok_or_else(|| Fail(format!("unknown name `{name}`\n{}", usage())))?;
                args.scenes.push(scene);
            }
        }
    }
    if !named {
        args.scenes = DEFAULT_SCENES.to_vec();
        args.narrow = true;
    }
    Ok(args)
}

fn main() {
    let args = match parse_args() {
        Ok(a) => a,
        Err(e) => {
            eprintln!("{e}");
            std::process::exit(2);
        }
    };
    // wasm32 (wasip1, under Node) has no threads: its stack is set at link time
    // (`build.rs`), and the run goes on the main thread.
    #[cfg(target_arch = "wasm32")]
    if let Err(e) = run(&args) {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
    // carom's worlds live inline (tens of MB for the large one): build them in a `Box` on
    // a thread with a big stack, in case the value passes through the stack on its way.
    #[cfg(not(target_arch = "wasm32"))]
    let worker = std::thread::Builder::new()
        .stack_size(512 << 20)
        .spawn(move || run(&args));
    #[cfg(not(target_arch = "wasm32"))]
    match worker.map(|h| h.join()) {
        Ok(Ok(Ok(()))) => {}
        Ok(Ok(Err(e))) => {
            eprintln!("error: {e}");
            std::process::exit(1);
        }
        Ok(Err(_)) => {
            eprintln!("error: the benchmark thread panicked");
            std::process::exit(1);
        }
        Err(e) => {
            eprintln!("error: cannot start the benchmark thread: {e}");
            std::process::exit(1);
        }
    }
}

fn run(args: &Args) -> Result<(), Fail> {
    let hulls = scene_hulls()?;
    if args.stages {
        let mut rows = Vec::new();
        for &scene in &args.scenes {
            rows.push(stages::compare_stages(scene, &hulls, args)?);
        }
        print!("{}", stages::stage_table(&rows, args.reps));
        return Ok(());
    }
    if !args.scenes.is_empty() {
        let mut rows = Vec::new();
        for &scene in &args.scenes {
            rows.push(compare_scene(scene, &hulls, args)?);
        }
        print!("{}", scene_table(&rows, args.reps));
    }
    if args.narrow {
        let rows = compare_narrow(args.reps)?;
        print!("{}", narrow_table(&rows, args.reps));
    }
    Ok(())
}

/// The hulls of the hull scenes: [`SCENE_HULLS`] from `make_hulls` with the scenes' seed.
fn scene_hulls() -> Result<Vec<ConvexHull>, Fail> {
    let mut hulls = vec![ConvexHull::UNIT_TETRAHEDRON; SCENE_HULLS];
    scenes::make_hulls(&mut hulls, scenes::SEED)?;
    Ok(hulls)
}

// ---------------------------------------------------------------------------------------
// Scenes
// ---------------------------------------------------------------------------------------

/// What one engine's run of a scene left behind.
#[derive(Clone, Debug, Default)]
struct Outcome {
    /// Time spent in the step calls, summed.
    stepping: Duration,
    steps: u32,
    /// The watched body's position at the start and at the end.
    watched_start: [f32; 3],
    watched_end: [f32; 3],
    /// Dynamic bodies whose centre ended below y = 0.
    below_ground: usize,
    /// Dynamic bodies whose centre ended outside the `spheres` walls (|x| or |z| > 10).
    outside_walls: usize,
    /// Dynamic bodies whose centre ended beyond the `mesh_pile` terrain's edge (|x| or
    /// |z| >= 18: they rolled off it).
    off_terrain: usize,
    /// Dynamic bodies below y = 0 (the terrain's lowest point) but over the terrain:
    /// through it.
    below_terrain: usize,
    /// Dynamic bodies awake at the end.
    awake: usize,
    /// Dynamic bodies.
    dynamic: usize,
    /// carom: candidate pairs and manifolds dropped over the run (capacity overflow).
    dropped_pairs: u64,
    dropped_contacts: u64,
    /// carom: events dropped (the event queue is small on purpose; events are not read).
    dropped_events: u64,
    /// carom: most contacts in one step.
    peak_contacts: u32,
    /// carom: awake bodies as the last step's report counts them.
    awake_reported: u32,
    /// rapier: bodies disabled because their state went non-finite, over the run.
    quarantined: usize,
    /// Contact points handed to the solver, summed over the steps (carom: the step
    /// report's points; rapier: its manifolds' solver contacts), counted outside the
    /// timed calls.
    points: u64,
}

impl Outcome {
    fn ms_per_step(&self) -> f64 {
        self.stepping.as_secs_f64() * 1e3 / f64::from(self.steps.max(1))
    }

    fn points_per_step(&self) -> f64 {
        self.points as f64 / f64::from(self.steps.max(1))
    }

    fn invalid(&self) -> bool {
        self.dropped_pairs > 0 || self.dropped_contacts > 0 || self.quarantined > 0
    }
}

/// One row of the scene table.
struct SceneRow {
    scene: Scene,
    bodies: usize,
    steps: u32,
    carom_ms: Vec<f64>,
    rapier_ms: Vec<f64>,
    ratios: Vec<f64>,
    carom_stability: String,
    rapier_stability: String,
    warnings: Vec<String>,
}

fn compare_scene(scene: Scene, hulls: &[ConvexHull], args: &Args) -> Result<SceneRow, Fail> {
    let steps = args.steps.unwrap_or_else(|| scene.steps());
    let rapier_hulls = rapier_hull_shapes(hulls)?;
    let mut row = SceneRow {
        scene,
        bodies: scene.body_count(),
        steps,
        carom_ms: Vec::new(),
        rapier_ms: Vec::new(),
        ratios: Vec::new(),
        carom_stability: String::new(),
        rapier_stability: String::new(),
        warnings: Vec::new(),
    };
    let mut first: Option<(Outcome, Outcome)> = None;
    for rep in 0..args.reps {
        let carom_first = rep % 2 == 0;
        let (c, r) = if carom_first {
            let c = carom_scene(scene, hulls, steps, false)?;
            let r = rapier_scene(scene, &rapier_hulls, steps, false)?;
            (c, r)
        } else {
            let r = rapier_scene(scene, &rapier_hulls, steps, false)?;
            let c = carom_scene(scene, hulls, steps, false)?;
            (c, r)
        };
        eprintln!(
            "{:<13} rep {}/{} ({} first): carom {:9.3} ms/step (peak {} contacts, {:.0} points/step), rapier {:9.3} ms/step ({:.0} points/step)",
            scene.name(),
            rep + 1,
            args.reps,
            if carom_first { "carom" } else { "rapier" },
            c.ms_per_step(),
            c.peak_contacts,
            c.points_per_step(),
            r.ms_per_step(),
            r.points_per_step()
        );
        check_validity(scene, &c, &r, &mut row.warnings);
        row.carom_ms.push(c.ms_per_step());
        row.rapier_ms.push(r.ms_per_step());
        row.ratios.push(r.ms_per_step() / c.ms_per_step());
        first.get_or_insert((c, r));
    }
    if let Some((c, r)) = first {
        // Boxes and hulls: the awake count comes from a separate, untimed run with sleep on.
        let (c_sleep, r_sleep) = if matches!(scene, Scene::Boxes | Scene::Hulls) {
            eprintln!("{:<13} stability run with sleeping on", scene.name());
            let c_sleep = carom_scene(scene, hulls, steps, true)?;
            let r_sleep = rapier_scene(scene, &rapier_hulls, steps, true)?;
            eprintln!(
                "{:<13} awake at the end: carom {} (its step report: {}), rapier {}",
                scene.name(),
                c_sleep.awake,
                c_sleep.awake_reported,
                r_sleep.awake
            );
            check_validity(scene, &c_sleep, &r_sleep, &mut row.warnings);
            (Some(c_sleep), Some(r_sleep))
        } else {
            (None, None)
        };
        row.carom_stability = stability(scene, &c, c_sleep.as_ref());
        row.rapier_stability = stability(scene, &r, r_sleep.as_ref());
    }
    Ok(row)
}

/// Loud warnings for a run that dropped contacts (the benchmark is then invalid).
fn check_validity(scene: Scene, c: &Outcome, r: &Outcome, warnings: &mut Vec<String>) {
    if c.invalid() {
        let w = format!(
            "INVALID: carom dropped {} pairs and {} contacts in {} (peak {} contacts): raise the world's capacities",
            c.dropped_pairs,
            c.dropped_contacts,
            scene.name(),
            c.peak_contacts
        );
        eprintln!("!!!!!!!! {w} !!!!!!!!");
        if !warnings.contains(&w) {
            warnings.push(w);
        }
    }
    if r.invalid() {
        let w = format!(
            "INVALID: rapier quarantined {} bodies (non-finite state) in {}",
            r.quarantined,
            scene.name()
        );
        eprintln!("!!!!!!!! {w} !!!!!!!!");
        if !warnings.contains(&w) {
            warnings.push(w);
        }
    }
}

/// The stability figure of `scene` for one engine: `o` is the timed run (sleep off),
/// `sleeping` the separate sleep-on run where the scene has one.
fn stability(scene: Scene, o: &Outcome, sleeping: Option<&Outcome>) -> String {
    let [x0, y0, z0] = o.watched_start;
    let [x1, y1, z1] = o.watched_end;
    let sideways_mm = ((x1 - x0).hypot(z1 - z0)) * 1e3;
    match scene {
        Scene::Pyramid20 | Scene::Pyramid100 | Scene::JoltPyramid => {
            // Where the top box should come to rest: where it starts, except in Jolt's
            // pyramid, whose 14 gaps below the top layer close as it settles.
            let rest_y = if scene == Scene::JoltPyramid {
                y0 - 14.0 * JOLT_PYRAMID_GAP
            } else {
                y0
            };
            format!(
                "top: {:.1} mm sideways, {:.1} mm sunk",
                sideways_mm,
                (rest_y - y1) * 1e3
            )
        }
        Scene::Boxes | Scene::Hulls => {
            let awake = sleeping.map_or_else(|| "?".to_string(), |s| s.awake.to_string());
            format!(
                "{} below ground; {}/{} awake (sleep on)",
                o.below_ground, awake, o.dynamic
            )
        }
        Scene::Spheres => format!(
            "{} outside walls, {} below ground",
            o.outside_walls, o.below_ground
        ),
        Scene::MeshPile => format!(
            "{} rolled off the edge, {} below y = 0 ({} of them over the terrain); {}/{} awake",
            o.off_terrain, o.below_ground, o.below_terrain, o.awake, o.dynamic
        ),
        _ => format!(
            "watched moved ({:.3}, {:.3}, {:.3}) m; {} below ground",
            x1 - x0,
            y1 - y0,
            z1 - z0,
            o.below_ground
        ),
    }
}

/// Build `scene` in a fresh carom world, step it `steps` times (timing each step) and
/// summarise. The capacities are picked by size.
fn carom_scene(
    scene: Scene,
    hulls: &[ConvexHull],
    steps: u32,
    sleep: bool,
) -> Result<Outcome, Fail> {
    if scene.body_count() <= SMALL_BODIES {
        let mut w: Box<SmallWorld<'_>> = Box::new(World::new());
        carom_run(&mut w, scene, hulls, steps, sleep)
    } else {
        let mut w: Box<LargeWorld<'_>> = Box::new(World::new());
        carom_run(&mut w, scene, hulls, steps, sleep)
    }
}

fn carom_run<'a, const B: usize, const C: usize, const E: usize>(
    w: &mut World<'a, B, C, E>,
    scene: Scene,
    hulls: &'a [ConvexHull],
    steps: u32,
    sleep: bool,
) -> Result<Outcome, Fail> {
    w.set_config(WorldConfig {
        sleep_enabled: sleep,
        ..scene.config()
    })?;
    let watch = scene.build_on(w, hulls, Some(carom::Shape::HeightField(terrain()?)))?;
    let mut o = Outcome {
        steps,
        watched_start: v3(w.body(watch)?.position()),
        ..Outcome::default()
    };
    for _ in 0..steps {
        let t0 = Instant::now();
        let report = w.step();
        o.stepping += t0.elapsed();
        o.dropped_pairs += u64::from(report.dropped_pairs);
        o.dropped_contacts += u64::from(report.dropped_contacts);
        o.dropped_events += u64::from(report.dropped_events);
        o.peak_contacts = o.peak_contacts.max(report.contacts);
        o.awake_reported = report.awake_bodies;
        o.points += u64::from(report.points);
    }
    o.watched_end = v3(w.body(watch)?.position());
    let handles: Vec<_> = w.handles().collect();
    for h in handles {
        let b = w.body(h)?;
        if b.kind() != BodyKind::Dynamic {
            continue;
        }
        let p = b.position();
        o.dynamic += 1;
        o.below_ground += usize::from(p.y < 0.0);
        o.outside_walls += usize::from(p.x.abs() > 10.0 || p.z.abs() > 10.0);
        let over = p.x.abs() < 18.0 && p.z.abs() < 18.0;
        o.off_terrain += usize::from(!over);
        o.below_terrain += usize::from(over && p.y < 0.0);
        o.awake += usize::from(b.is_awake());
    }
    Ok(o)
}

fn v3(v: carom::Vec3) -> [f32; 3] {
    [v.x, v.y, v.z]
}

fn vector(v: carom::Vec3) -> Vector {
    Vector::new(v.x, v.y, v.z)
}

/// rapier's shape of each carom hull, built from the hull's vertices (so both engines
/// see one polytope), once: colliders share it.
fn rapier_hull_shapes(hulls: &[ConvexHull]) -> Result<Vec<SharedShape>, Fail> {
    hulls
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let pts: Vec<Vector> = h.vertices().iter().map(|p| vector(*p)).collect();
            SharedShape::convex_hull(&pts)
                .ok_or_else(|| Fail(format!("rapier: hull {i} does not build")))
        })
        .collect()
}

/// The scene in a fresh rapier world: every [`SceneBody`] becomes one rigid body with one
/// collider. Returns the world and the watched body.
fn rapier_build(
    scene: Scene,
    hulls: &[SharedShape],
    sleep: bool,
) -> Result<(PhysicsWorld, RigidBodyHandle), Fail> {
    let mut world = PhysicsWorld::new();
    let config = scene.config();
    world.gravity = vector(config.gravity);
    world.integration_parameters.dt = config.dt;
    let mut n = 0usize;
    let mut watched = None;
    scene.for_each_body(hulls.len(), |b: &SceneBody| -> Result<(), Fail> {
        let body = match b.kind {
            SceneKind::Dynamic => RigidBodyBuilder::dynamic(),
            SceneKind::Static => RigidBodyBuilder::fixed(),
        }
        .pose(Pose::from_parts(
            vector(b.position),
            Rotation::from_xyzw(b.rotation.x, b.rotation.y, b.rotation.z, b.rotation.w),
        ))
        .linvel(vector(b.velocity))
        .linear_damping(b.linear_damping)
        .angular_damping(b.angular_damping)
        .can_sleep(sleep);
        let collider = match b.shape {
            SceneShape::Sphere { radius } => ColliderBuilder::ball(radius),
            SceneShape::Capsule {
                half_height,
                radius,
            } => ColliderBuilder::capsule_y(half_height, radius),
            SceneShape::Cuboid { half_extents: h } => ColliderBuilder::cuboid(h.x, h.y, h.z),
            SceneShape::Hull(i) => ColliderBuilder::new(
                hulls
                    .get(i)
                    .cloned()
                    .ok_or_else(|| Fail(format!("no hull {i}")))?,
            ),
            SceneShape::Terrain => ColliderBuilder::new(rapier_terrain()?),
        }
        .density(b.density)
        // rapier has one friction coefficient: the static one. carom's combine rules:
        // friction by the geometric mean, restitution by the larger.
        .friction(b.static_friction)
        .friction_combine_rule(CoefficientCombineRule::GeometricMean)
        .restitution(b.restitution)
        .restitution_combine_rule(CoefficientCombineRule::Max);
        let (h, _) = world.insert(body, collider);
        if n == scene.watched() {
            watched = Some(h);
        }
        n += 1;
        Ok(())
    })?;
    let watched = watched.ok_or_else(|| Fail(format!("{}: no watched body", scene.name())))?;
    Ok((world, watched))
}

fn rapier_scene(
    scene: Scene,
    hulls: &[SharedShape],
    steps: u32,
    sleep: bool,
) -> Result<Outcome, Fail> {
    let (mut w, watch) = rapier_build(scene, hulls, sleep)?;
    let start = w.bodies[watch].translation();
    let mut o = Outcome {
        steps,
        watched_start: start.to_array(),
        ..Outcome::default()
    };
    for _ in 0..steps {
        let t0 = Instant::now();
        w.step();
        o.stepping += t0.elapsed();
        o.quarantined += w.quarantine().bodies().len();
        o.points += w
            .narrow_phase
            .contact_pairs()
            .flat_map(|p| p.manifolds().iter())
            .map(|m| m.data.solver_contacts.len() as u64)
            .sum::<u64>();
    }
    o.watched_end = w.bodies[watch].translation().to_array();
    for (_, b) in w.bodies.iter() {
        if !b.is_dynamic() {
            continue;
        }
        let p = b.translation();
        o.dynamic += 1;
        o.below_ground += usize::from(p.y < 0.0);
        o.outside_walls += usize::from(p.x.abs() > 10.0 || p.z.abs() > 10.0);
        let over = p.x.abs() < 18.0 && p.z.abs() < 18.0;
        o.off_terrain += usize::from(!over);
        o.below_terrain += usize::from(over && p.y < 0.0);
        o.awake += usize::from(!b.is_sleeping());
    }
    Ok(o)
}

fn median(v: &[f64]) -> f64 {
    let mut s: Vec<f64> = v.iter().copied().filter(|x| x.is_finite()).collect();
    s.sort_by(f64::total_cmp);
    match s.len() {
        0 => f64::NAN,
        n if n % 2 == 1 => s[n / 2],
        n => 0.5 * (s[n / 2 - 1] + s[n / 2]),
    }
}

fn scene_table(rows: &[SceneRow], reps: usize) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "\n## Scenes: carom vs rapier3d (sleep off, medians of {reps} paired repetitions)\n"
    );
    let _ = writeln!(
        t,
        "| scene | bodies | steps | carom ms/step | rapier ms/step | rapier/carom | carom stability | rapier stability |"
    );
    let _ = writeln!(t, "| --- | ---: | ---: | ---: | ---: | ---: | --- | --- |");
    for r in rows {
        let _ = writeln!(
            t,
            "| {} | {} | {} | {:.3} | {:.3} | {:.2} | {} | {} |",
            r.scene.name(),
            r.bodies,
            r.steps,
            median(&r.carom_ms),
            median(&r.rapier_ms),
            median(&r.ratios),
            r.carom_stability,
            r.rapier_stability
        );
    }
    let _ = writeln!(
        t,
        "\nrapier/carom below 1: rapier takes less time per step. carom worlds: \
         `World<{SMALL_BODIES}, 8192, 64>` up to {SMALL_BODIES} bodies, `World<5120, 32768, 64>` above."
    );
    let warnings: Vec<&String> = rows.iter().flat_map(|r| r.warnings.iter()).collect();
    if warnings.is_empty() {
        let _ = writeln!(
            t,
            "No run dropped a pair or a contact (carom) or quarantined a body (rapier)."
        );
    } else {
        let _ = writeln!(t);
        for w in warnings {
            let _ = writeln!(t, "**{w}**");
        }
    }
    t
}

// ---------------------------------------------------------------------------------------
// Narrow phase
// ---------------------------------------------------------------------------------------

/// One row of the narrow-phase table.
struct NarrowRow {
    set: QuerySet,
    query: &'static str,
    carom_ns: Vec<f64>,
    parry_ns: Vec<f64>,
    ratios: Vec<f64>,
    agreement: String,
}

/// parry's pose of a carom pose.
fn pose(iso: &Iso) -> Pose {
    let q = iso.rotation;
    Pose::from_parts(
        vector(iso.position),
        Rotation::from_xyzw(q.x, q.y, q.z, q.w),
    )
}

/// The shared query sets, ready for both libraries.
struct Sets {
    carom_hulls: Vec<ConvexHull>,
    parry_hulls: Vec<ConvexPolyhedron>,
    ball: Ball,
    cube: Cuboid,
}

fn query_sets() -> Result<Sets, Fail> {
    let mut clouds = vec![[carom::Vec3::ZERO; HULL_POINTS]; HULLS];
    queries::hull_clouds(&mut clouds);
    let carom_hulls = clouds
        .iter()
        .map(|c| ConvexHull::new(c))
        .collect::<Result<Vec<_>, _>>()?;
    let parry_hulls = carom_hulls
        .iter()
        .enumerate()
        .map(|(i, h)| {
            let pts: Vec<Vector> = h.vertices().iter().map(|p| vector(*p)).collect();
            ConvexPolyhedron::from_convex_hull(&pts)
                .ok_or_else(|| Fail(format!("parry: query hull {i} does not build")))
        })
        .collect::<Result<Vec<_>, _>>()?;
    Ok(Sets {
        carom_hulls,
        parry_hulls,
        ball: Ball::new(BALL_RADIUS),
        cube: Cuboid::new(Vector::splat(BOX_HALF)),
    })
}

/// parry's form of one query: the poses converted once, outside the timing, as carom's
/// are given.
struct ParryQuery {
    pose_a: Pose,
    pose_b: Pose,
    hull_a: usize,
    hull_b: usize,
}

/// Time `passes` passes of `f` over the queries: ns per query.
fn time_per_query<T>(queries: &[T], passes: u32, mut f: impl FnMut(&T)) -> f64 {
    let t0 = Instant::now();
    for _ in 0..passes {
        for q in queries {
            f(q);
        }
    }
    t0.elapsed().as_secs_f64() * 1e9 / (f64::from(passes) * queries.len().max(1) as f64)
}

fn compare_narrow(reps: usize) -> Result<Vec<NarrowRow>, Fail> {
    let sets = query_sets()?;
    let c_ball = Shape::sphere(BALL_RADIUS)?;
    let c_cube = Shape::cuboid(carom::Vec3::splat(BOX_HALF))?;
    let c_hulls: Vec<Shape<'_>> = sets.carom_hulls.iter().map(Shape::hull).collect();
    let mut rows = Vec::new();
    for set in QuerySet::ALL {
        let mut qs = vec![PoseQuery::default(); PAIRS];
        set.fill(&mut qs);
        let pqs: Vec<ParryQuery> = qs
            .iter()
            .map(|q| ParryQuery {
                pose_a: pose(&q.pose_a),
                pose_b: pose(&q.pose_b),
                hull_a: usize::from(q.hull_a) % HULLS,
                hull_b: usize::from(q.hull_b) % HULLS,
            })
            .collect();
        let hull = |i: u8| usize::from(i) % HULLS;
        let poses: Vec<(Pose, Pose)> = pqs.iter().map(|q| (q.pose_a, q.pose_b)).collect();
        let (query, agreement) = match set {
            QuerySet::HullHull => (
                "distance (GJK)",
                hull_agreement(&qs, &poses, &c_hulls, &sets)?,
            ),
            QuerySet::BallBox => (
                "contact",
                ball_box_agreement(&qs, &poses, &c_ball, &c_cube, &sets)?,
            ),
            QuerySet::BoxBox => (
                "contact manifold",
                box_box_agreement(&qs, &poses, &c_cube, &sets)?,
            ),
        };
        let mut row = NarrowRow {
            set,
            query,
            carom_ns: Vec::new(),
            parry_ns: Vec::new(),
            ratios: Vec::new(),
            agreement,
        };
        let mut manifolds: Vec<ContactManifold<(), ()>> = vec![ContactManifold::new()];
        let mut workspace = None;
        for rep in 0..reps {
            let carom_run = || match set {
                QuerySet::HullHull => time_per_query(&qs, NARROW_PASSES, |q| {
                    let (a, b) = (&c_hulls[hull(q.hull_a)], &c_hulls[hull(q.hull_b)]);
                    let mut cache = SimplexCache::default();
                    black_box(&collide::distance(a, &q.pose_a, b, &q.pose_b, &mut cache));
                }),
                QuerySet::BallBox => time_per_query(&qs, NARROW_PASSES, |q| {
                    black_box(&collide::contact(
                        &c_ball,
                        &q.pose_a,
                        &c_cube,
                        &q.pose_b,
                        CONTACT_MARGIN,
                    ));
                }),
                QuerySet::BoxBox => time_per_query(&qs, NARROW_PASSES, |q| {
                    black_box(&collide::contact(
                        &c_cube,
                        &q.pose_a,
                        &c_cube,
                        &q.pose_b,
                        CONTACT_MARGIN,
                    ));
                }),
            };
            let mut parry_run = || match set {
                QuerySet::HullHull => time_per_query(&pqs, NARROW_PASSES, |q| {
                    let (a, b) = (&sets.parry_hulls[q.hull_a], &sets.parry_hulls[q.hull_b]);
                    black_box(&pq::distance(&q.pose_a, a, &q.pose_b, b));
                }),
                QuerySet::BallBox => time_per_query(&pqs, NARROW_PASSES, |q| {
                    black_box(&pq::contact(
                        &q.pose_a,
                        &sets.ball,
                        &q.pose_b,
                        &sets.cube,
                        CONTACT_MARGIN,
                    ));
                }),
                QuerySet::BoxBox => time_per_query(&pqs, NARROW_PASSES, |q| {
                    // A fresh manifold per query (no coherence with the previous, unrelated
                    // pair), keeping the allocation.
                    for m in manifolds.iter_mut() {
                        m.clear();
                    }
                    let pos12 = q.pose_a.inv_mul(&q.pose_b);
                    black_box(
                        DefaultQueryDispatcher
                            .contact_manifolds(
                                &pos12,
                                &sets.cube,
                                &sets.cube,
                                CONTACT_MARGIN,
                                &mut manifolds,
                                &mut workspace,
                            )
                            .ok(),
                    );
                    black_box(&manifolds);
                }),
            };
            let (c, p) = if rep % 2 == 0 {
                let c = carom_run();
                (c, parry_run())
            } else {
                let p = parry_run();
                (carom_run(), p)
            };
            eprintln!(
                "{:<10} rep {}/{}: carom {:8.1} ns/query, parry {:8.1} ns/query",
                set.name(),
                rep + 1,
                reps,
                c,
                p
            );
            row.carom_ns.push(c);
            row.parry_ns.push(p);
            row.ratios.push(p / c);
        }
        rows.push(row);
    }
    Ok(rows)
}

/// How far carom's and parry's hull distances agree.
fn hull_agreement(
    qs: &[PoseQuery],
    poses: &[(Pose, Pose)],
    c_hulls: &[Shape<'_>],
    sets: &Sets,
) -> Result<String, Fail> {
    let (mut worst, mut overlap_c, mut overlap_p) = (0.0f32, 0, 0);
    for (q, (pa, pb)) in qs.iter().zip(poses) {
        let (ia, ib) = (usize::from(q.hull_a) % HULLS, usize::from(q.hull_b) % HULLS);
        let (ca, cb) = (&c_hulls[ia], &c_hulls[ib]);
        let dc =
            collide::distance(ca, &q.pose_a, cb, &q.pose_b, &mut SimplexCache::default())?.distance;
        let dp = pq::distance(pa, &sets.parry_hulls[ia], pb, &sets.parry_hulls[ib])
            .map_err(|_| Fail("parry: hull distance unsupported".into()))?
            .distance;
        worst = worst.max((dc - dp).abs());
        overlap_c += usize::from(dc == 0.0);
        overlap_p += usize::from(dp == 0.0);
    }
    Ok(format!(
        "overlapping: carom {overlap_c}, parry {overlap_p}; max abs Δdistance {:.2e} m",
        worst
    ))
}

/// How far carom's and parry's ball-box contacts agree.
fn ball_box_agreement(
    qs: &[PoseQuery],
    poses: &[(Pose, Pose)],
    c_ball: &Shape<'_>,
    c_cube: &Shape<'_>,
    sets: &Sets,
) -> Result<String, Fail> {
    let (mut found_c, mut found_p, mut worst) = (0, 0, 0.0f32);
    for (q, (pa, pb)) in qs.iter().zip(poses) {
        let c = collide::contact(c_ball, &q.pose_a, c_cube, &q.pose_b, CONTACT_MARGIN)?
            .filter(|m| !m.points().is_empty());
        let p = pq::contact(pa, &sets.ball, pb, &sets.cube, CONTACT_MARGIN)
            .map_err(|_| Fail("parry: ball-box contact unsupported".into()))?;
        found_c += usize::from(c.is_some());
        found_p += usize::from(p.is_some());
        if let (Some(c), Some(p)) = (c, p) {
            worst = worst.max((c.min_separation() - p.dist).abs());
        }
    }
    Ok(format!(
        "in contact: carom {found_c}, parry {found_p}; max abs Δdepth {:.2e} m",
        worst
    ))
}

/// How far carom's and parry's box-box manifolds agree.
fn box_box_agreement(
    qs: &[PoseQuery],
    poses: &[(Pose, Pose)],
    c_cube: &Shape<'_>,
    sets: &Sets,
) -> Result<String, Fail> {
    let (mut found_c, mut found_p, mut points_c, mut points_p, mut worst) = (0, 0, 0, 0, 0.0f32);
    let mut manifolds: Vec<ContactManifold<(), ()>> = Vec::new();
    let mut workspace = None;
    for (q, (pa, pb)) in qs.iter().zip(poses) {
        let c = collide::contact(c_cube, &q.pose_a, c_cube, &q.pose_b, CONTACT_MARGIN)?
            .filter(|m| !m.points().is_empty());
        manifolds.clear();
        DefaultQueryDispatcher
            .contact_manifolds(
                &pa.inv_mul(pb),
                &sets.cube,
                &sets.cube,
                CONTACT_MARGIN,
                &mut manifolds,
                &mut workspace,
            )
            .map_err(|_| Fail("parry: box-box manifold unsupported".into()))?;
        let p_points: Vec<f32> = manifolds
            .iter()
            .flat_map(|m| m.points.iter().map(|p| p.dist))
            .collect();
        found_c += usize::from(c.is_some());
        found_p += usize::from(!p_points.is_empty());
        points_c += c.map_or(0, |m| m.points().len());
        points_p += p_points.len();
        if let Some(c) = c {
            if let Some(p_min) = p_points.iter().copied().reduce(f32::min) {
                worst = worst.max((c.min_separation() - p_min).abs());
            }
        }
    }
    Ok(format!(
        "in contact: carom {found_c}, parry {found_p}; points: carom {points_c}, parry {points_p}; max abs Δdepth {:.2e} m",
        worst
    ))
}

fn narrow_table(rows: &[NarrowRow], reps: usize) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "\n## Narrow phase: carom vs parry3d ({PAIRS} pose pairs per set, {NARROW_PASSES} passes, medians of {reps} paired repetitions)\n"
    );
    let _ = writeln!(
        t,
        "| set | query | carom ns/query | parry ns/query | parry/carom | agreement |"
    );
    let _ = writeln!(t, "| --- | --- | ---: | ---: | ---: | --- |");
    for r in rows {
        let _ = writeln!(
            t,
            "| {} | {} | {:.1} | {:.1} | {:.2} | {} |",
            r.set.name(),
            r.query,
            median(&r.carom_ns),
            median(&r.parry_ns),
            median(&r.ratios),
            r.agreement
        );
    }
    let _ = writeln!(
        t,
        "\nparry/carom below 1: parry takes less time per query. Agreement: both libraries on \
         the same pairs (carom's contact margin {CONTACT_MARGIN} m as parry's prediction)."
    );
    t
}
