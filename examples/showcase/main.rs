//! carom's showcase: a few narrow-phase queries, then the standard scenes of SCENES.md
//! stepped one after the other, a table of what they did, and SVG pictures of their final
//! states and of every step's time.
//!
//! Run with `cargo run --release --example showcase [OUTPUT_DIR]` (the pictures go to
//! `target/showcase/` unless a folder is given).

mod svg;

use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::sync::Mutex;
use std::time::Instant;

use carom::collide::{self, SimplexCache};
use carom::scenes::{self, Scene, REFERENCE_HULLS, SEED};
use carom::shape::Ray;
use carom::{BodyKind, ConvexHull, Error, Iso, Quat, Shape, Vec3, World};

/// The scenes run, in order: all of SCENES.md's but the two big pyramids (minutes, not
/// seconds: `compare/` and the benches run them).
const SCENES: [Scene; 8] = [
    Scene::Tower,
    Scene::Pyramid20,
    Scene::Boxes,
    Scene::Spheres,
    Scene::Hulls,
    Scene::Bullet,
    Scene::Bullets,
    Scene::Mixed,
];

/// The golden checksums the reference scenes must reproduce on every target.
const GOLDEN: &str = if cfg!(feature = "micromath") {
    include_str!("../../tests/golden/checksums_micromath.txt")
} else {
    include_str!("../../tests/golden/checksums.txt")
};

/// The world of the one big scene (`spheres`, 4101 bodies): 29 MB.
static BIG: Mutex<World<'static, 4200, 24576>> = Mutex::new(World::new());

/// What one scene's run gave.
struct Outcome {
    scene: Scene,
    bodies: usize,
    ms_per_step: f64,
    contacts: u32,
    awake: u32,
    /// Pairs and contacts that did not fit in the world's pools, over the run.
    dropped: u64,
    /// The deepest penetration among the final state's contacts (m).
    deepest: f32,
    /// How far the top box of a stack ended sideways (x, z) from where it was built (m).
    drift: Option<f32>,
    checksum: u64,
    /// Per step: (time in ms, awake bodies after it).
    series: Vec<(f32, u32)>,
    picture: String,
}

fn main() -> Result<(), Box<dyn std::error::Error>> {
    let dir = PathBuf::from(std::env::args().nth(1).unwrap_or("target/showcase".into()));
    narrow_phase()?;

    // Shared by every world, so borrowed for 'static.
    let mut hulls = vec![ConvexHull::UNIT_TETRAHEDRON; REFERENCE_HULLS];
    scenes::make_hulls(&mut hulls, SEED)?;
    let hulls: &'static [ConvexHull] = Box::leak(hulls.into_boxed_slice());

    let outcomes = if cfg!(debug_assertions) {
        // A debug build's `Box::new` builds a world on the stack before moving it to the
        // heap (README, Capacity), and 9 MB worlds overflow the main thread's 8 MB: give
        // it a thread with room. Release builds build worlds in place and need none.
        std::thread::Builder::new()
            .stack_size(256 << 20)
            .spawn(move || run_all(hulls))?
            .join()
            .map_err(|_| "the scenes' thread panicked")??
    } else {
        run_all(hulls)?
    };
    eprint!("\r{:60}\r", "");

    table(&outcomes);
    write_pictures(&dir, &outcomes)?;
    Ok(())
}

/// Run every scene of [`SCENES`], each in a new world.
fn run_all(hulls: &'static [ConvexHull]) -> Result<Vec<Outcome>, Error> {
    let mut outcomes = Vec::new();
    for scene in SCENES {
        // Worlds are inline and large: on the heap, sized to the scene. The reference
        // scenes run in the world type their golden checksums are defined for.
        let outcome = if scene.body_count() <= 128 {
            in_new_world::<128, 1024, 64>(scene, hulls)?
        } else if scene.body_count() <= 1024 {
            in_new_world::<1024, 8192, 256>(scene, hulls)?
        } else {
            // Too big for `Box::new` on the main thread's stack (README, Capacity): a
            // `static`, built by the compiler (examples/big_world.rs). One scene uses it.
            let mut world = BIG.lock().unwrap_or_else(|e| e.into_inner());
            run(&mut world, scene, hulls)?
        };
        outcomes.push(outcome);
    }
    Ok(outcomes)
}

/// Run `scene` in a new `World<B, C, E>` on the heap (`Box::new` builds it in place in a
/// release build: README, Capacity).
#[inline(never)]
fn in_new_world<const B: usize, const C: usize, const E: usize>(
    scene: Scene,
    hulls: &'static [ConvexHull],
) -> Result<Outcome, Error> {
    run(
        &mut Box::new(World::<'static, B, C, E>::new()),
        scene,
        hulls,
    )
}

/// Build `scene` in the empty `world`, step it, time every step, and draw the end.
fn run<const B: usize, const C: usize, const E: usize>(
    world: &mut World<'static, B, C, E>,
    scene: Scene,
    hulls: &'static [ConvexHull],
) -> Result<Outcome, Error> {
    world.set_config(scene.config())?;
    let watch = scene.build(world, hulls)?;
    let start = world.body(watch)?.position();
    let mut series = Vec::with_capacity(scene.steps() as usize);
    let mut dropped = 0u64;
    let t0 = Instant::now();
    for step in 1..=scene.steps() {
        let t = Instant::now();
        let report = world.step();
        series.push((t.elapsed().as_secs_f32() * 1e3, report.awake_bodies));
        dropped += u64::from(report.dropped_pairs) + u64::from(report.dropped_contacts);
        if step % 20 == 0 || step == scene.steps() {
            eprint!(
                "\r{:12} step {step:4} of {:4}, {:5} awake   ",
                scene.name(),
                scene.steps(),
                report.awake_bodies
            );
        }
    }
    let ms_per_step = t0.elapsed().as_secs_f64() * 1e3 / f64::from(scene.steps());
    let report = world.last_report();

    // The final state: bodies as drawn, and the contact points of every touching pair
    // (the narrow phase asked again, pair by pair, with a 5 mm margin).
    let bodies: Vec<svg::Body<'static>> = world
        .handles()
        .filter_map(|h| world.body(h).ok())
        .map(|b| svg::Body {
            shape: b.shape(),
            pose: b.pose(),
            kind: b.kind(),
            awake: b.is_awake(),
        })
        .collect();
    let mut points = Vec::new();
    let mut deepest = 0.0f32;
    for (i, a) in bodies.iter().enumerate() {
        let box_a = a.shape.aabb(&a.pose);
        for b in &bodies[i + 1..] {
            if a.kind == BodyKind::Static && b.kind == BodyKind::Static {
                continue;
            }
            let box_b = b.shape.aabb(&b.pose);
            if (box_a.min - box_b.max).max_elem() > 0.005
                || (box_b.min - box_a.max).max_elem() > 0.005
            {
                continue;
            }
            if let Ok(Some(m)) = collide::contact(&a.shape, &a.pose, &b.shape, &b.pose, 0.005) {
                deepest = deepest.max(-m.min_separation());
                points.extend(m.points().iter().map(|p| (p.point_a + p.point_b) * 0.5));
            }
        }
    }
    let title = format!(
        "{}: {} bodies after {} steps",
        scene.name(),
        bodies.len(),
        scene.steps()
    );
    Ok(Outcome {
        scene,
        bodies: bodies.len(),
        ms_per_step,
        contacts: report.contacts,
        awake: report.awake_bodies,
        dropped,
        deepest,
        drift: matches!(scene, Scene::Tower | Scene::Pyramid20).then_some({
            let d = world.body(watch)?.position() - start;
            d.x.hypot(d.z)
        }),
        checksum: world.checksum(),
        picture: svg::scene(&title, &bodies, &points),
        series,
    })
}

fn table(outcomes: &[Outcome]) {
    println!("\n== the standard scenes (SCENES.md), each in a new world ==");
    println!(
        "{:10} {:>6} {:>5} {:>8} {:>8} {:>5} {:>7} {:>9} {:>9}  checksum",
        "scene",
        "bodies",
        "steps",
        "ms/step",
        "contacts",
        "awake",
        "dropped",
        "deepest",
        "top drift"
    );
    for o in outcomes {
        let line = format!(
            "{} {} {:#018x}",
            o.scene.name(),
            o.scene.steps(),
            o.checksum
        );
        let golden = GOLDEN.lines().any(|l| l == line);
        println!(
            "{:10} {:>6} {:>5} {:>8.3} {:>8} {:>5} {:>7} {:>6.1} mm {:>9}  {:#018x}{}",
            o.scene.name(),
            o.bodies,
            o.scene.steps(),
            o.ms_per_step,
            o.contacts,
            o.awake,
            o.dropped,
            o.deepest * 1e3,
            o.drift.map_or("-".into(), |d| format!("{:.1} mm", d * 1e3)),
            o.checksum,
            if golden { " (golden)" } else { "" }
        );
    }
    println!(
        "contacts and awake: after the last step; dropped: pairs and contacts that did not fit \
         the world's pools, over the run (the reference scenes run in the golden world type, \
         `scenes::ReferenceWorld`);\ndeepest: the deepest penetration among the final \
         state's contacts; top drift: how far the top box ended sideways from where it was \
         built;\n(golden): the checksum in tests/golden, the same on every target."
    );
}

fn write_pictures(dir: &Path, outcomes: &[Outcome]) -> std::io::Result<()> {
    std::fs::create_dir_all(dir)?;
    let mut names = String::new();
    for o in outcomes {
        std::fs::write(dir.join(format!("{}.svg", o.scene.name())), &o.picture)?;
        let _ = write!(names, "{}.svg ", o.scene.name());
    }
    let series: Vec<svg::Series<'_>> = outcomes
        .iter()
        .map(|o| svg::Series {
            name: o.scene.name(),
            steps: &o.series,
        })
        .collect();
    std::fs::write(dir.join("steps.svg"), svg::plot(&series))?;
    println!(
        "\npictures in {}: {names}(final states, side and top), steps.svg (step time and awake bodies)",
        dir.display()
    );
    Ok(())
}

/// A few narrow-phase queries on their own: contact manifolds, GJK distance, EPA depth.
fn narrow_phase() -> Result<(), Error> {
    println!("== narrow phase ==");
    let cube = Shape::cuboid(Vec3::splat(0.5))?;
    let ground = Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?;
    let ground_pose = Iso::from_position(Vec3::new(0.0, -0.5, 0.0));
    for (what, pose) in [
        (
            "flat, 1 cm deep",
            Iso::from_position(Vec3::new(0.0, 0.49, 0.0)),
        ),
        (
            "on an edge",
            Iso::new(
                Vec3::new(0.0, 0.69, 0.0),
                Quat::from_axis_angle(Vec3::Z, core::f32::consts::FRAC_PI_4),
            ),
        ),
        (
            "on a corner",
            Iso::new(
                Vec3::new(0.0, 0.85, 0.0),
                Quat::from_axis_angle(Vec3::new(1.0, 0.0, 1.0), 0.9553),
            ),
        ),
    ] {
        match collide::contact(&ground, &ground_pose, &cube, &pose, 0.02)? {
            Some(m) => println!(
                "box {what:16}: {} point(s), deepest {:+.4} m",
                m.points().len(),
                m.min_separation()
            ),
            None => println!("box {what:16}: apart"),
        }
    }
    let mut hulls = vec![ConvexHull::UNIT_TETRAHEDRON; 2];
    scenes::make_hulls(&mut hulls, 1)?;
    let (a, b) = (Shape::hull(&hulls[0]), Shape::hull(&hulls[1]));
    let mut cache = SimplexCache::default();
    for x in [3.0f32, 1.5] {
        let pb = Iso::new(Vec3::new(x, 0.2, 0.0), Quat::from_axis_angle(Vec3::Y, 0.7));
        let d = collide::distance(&a, &Iso::IDENTITY, &b, &pb, &mut cache)?;
        let pen = collide::penetration(&a, &Iso::IDENTITY, &b, &pb)?;
        println!(
            "two 16-point hulls {x} m apart: distance {:.4} m ({} GJK iterations), penetration {}",
            d.distance,
            d.iterations,
            pen.map_or("none".to_string(), |p| format!("{:.4} m", p.depth))
        );
    }
    let ray = Ray::new(Vec3::new(-5.0, 0.0, 0.0), Vec3::X)?;
    if let Some(hit) = a.cast_ray(&Iso::IDENTITY, &ray, 100.0)? {
        println!("a ray along +x hits the hull at t = {:.4} m", hit.t);
    }
    Ok(())
}
