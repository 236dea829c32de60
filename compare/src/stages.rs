//! `--stages`: where each engine's step goes, stage by stage, on the same scenes.
//!
//! carom names its stages through `World::step_observed` (a callback as each stage ends:
//! an `Instant` read there closes the stage). rapier3d times its own stages in its
//! `PhysicsPipeline::counters` when built with its `profiler` feature, which this crate's
//! `stages` feature turns on. Those timers run on every step, so the ratio table
//! (`compare` without `--stages`) is built without the feature; a build with it prints
//! carom's columns and rapier's, one without it carom's alone.
//!
//! The stages do not map one to one: carom's narrow phase includes the mid phase and the
//! contact cache; its solve includes the prepare of the contact rows, the sub-steps and
//! restitution (rapier splits its solver into the assembly of the constraints and their
//! resolution, shown beside it); projection is carom's alone; "islands" is rapier's island
//! construction and carom's sleep stage. Timing adds a clock read per stage (about 20 ns
//! each), so the totals run slightly above the ratio table's.

use std::fmt::Write as _;
use std::time::{Duration, Instant};

use carom::scenes::Scene;
use carom::{ConvexHull, Shape, Stage, World, WorldConfig};

use super::{median, terrain, Args, Fail, LargeWorld, SmallWorld, SMALL_BODIES};

/// One engine's time per stage over one run (ms per step).
#[derive(Clone, Copy, Debug, Default)]
struct Split {
    broad: f64,
    narrow: f64,
    solve: f64,
    /// rapier: velocity assembly and resolution within `solve`.
    solve_parts: Option<(f64, f64)>,
    ccd: f64,
    /// carom only.
    projection: Option<f64>,
    islands: f64,
    /// The whole step (carom: timed around the call; rapier: its step timer).
    total: f64,
}

/// The runs of one scene.
pub(crate) struct StageRow {
    scene: Scene,
    steps: u32,
    carom: Vec<Split>,
    rapier: Vec<Split>,
}

/// Run `scene` `args.reps` times in each engine (carom first, then rapier, alternating),
/// sleep off, with the stage timers on.
pub(crate) fn compare_stages(
    scene: Scene,
    hulls: &[ConvexHull],
    args: &Args,
) -> Result<StageRow, Fail> {
    let steps = args.steps.unwrap_or_else(|| scene.steps());
    let mut row = StageRow {
        scene,
        steps,
        carom: Vec::new(),
        rapier: Vec::new(),
    };
    #[cfg(feature = "stages")]
    let rapier_hulls = super::rapier_hull_shapes(hulls)?;
    for rep in 0..args.reps {
        let c = carom_split(scene, hulls, steps)?;
        #[cfg(feature = "stages")]
        let r = Some(rapier_split(scene, &rapier_hulls, steps)?);
        #[cfg(not(feature = "stages"))]
        let r: Option<Split> = None;
        eprintln!(
            "{:<13} stages rep {}/{}: carom {:8.3} ms/step{}",
            scene.name(),
            rep + 1,
            args.reps,
            c.total,
            r.map_or(String::new(), |r| format!(
                ", rapier {:8.3} ms/step",
                r.total
            ))
        );
        row.carom.push(c);
        row.rapier.extend(r);
    }
    Ok(row)
}

fn carom_split(scene: Scene, hulls: &[ConvexHull], steps: u32) -> Result<Split, Fail> {
    if scene.body_count() <= SMALL_BODIES {
        let mut w: Box<SmallWorld<'_>> = Box::new(World::new());
        carom_run(&mut w, scene, hulls, steps)
    } else {
        let mut w: Box<LargeWorld<'_>> = Box::new(World::new());
        carom_run(&mut w, scene, hulls, steps)
    }
}

fn carom_run<'a, const B: usize, const C: usize, const E: usize>(
    w: &mut World<'a, B, C, E>,
    scene: Scene,
    hulls: &'a [ConvexHull],
    steps: u32,
) -> Result<Split, Fail> {
    w.set_config(WorldConfig {
        sleep_enabled: false,
        ..scene.config()
    })?;
    scene.build_on(w, hulls, Some(Shape::HeightField(terrain()?)))?;
    let mut sums = [Duration::ZERO; Stage::COUNT];
    let mut whole = Duration::ZERO;
    for _ in 0..steps {
        let start = Instant::now();
        let mut last = start;
        w.step_observed(&mut |stage| {
            let now = Instant::now();
            if let Some(s) = sums.get_mut(stage as usize) {
                *s += now - last;
            }
            last = now;
        });
        whole += start.elapsed();
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3 / f64::from(steps.max(1));
    let stage = |s: Stage| sums.get(s as usize).copied().map_or(0.0, ms);
    Ok(Split {
        broad: stage(Stage::BroadPhase),
        narrow: stage(Stage::NarrowPhase),
        solve: stage(Stage::Solve),
        solve_parts: None,
        ccd: stage(Stage::Continuous),
        projection: Some(stage(Stage::Projection)),
        islands: stage(Stage::Sleep),
        total: ms(whole),
    })
}

#[cfg(feature = "stages")]
fn rapier_split(
    scene: Scene,
    hulls: &[rapier3d::prelude::SharedShape],
    steps: u32,
) -> Result<Split, Fail> {
    let (mut w, _) = super::rapier_build(scene, hulls, false)?;
    w.physics_pipeline.counters.enable();
    // The counters restart with every step: read them after each.
    let mut d = [Duration::ZERO; 8];
    for _ in 0..steps {
        w.step();
        let c = &w.physics_pipeline.counters;
        let now = [
            c.cd.broad_phase_time.time() + c.cd.final_broad_phase_time.time(),
            c.cd.narrow_phase_time.time(),
            c.stages.solver_time.time(),
            c.solver.velocity_assembly_time.time(),
            c.solver.velocity_resolution_time.time(),
            c.stages.ccd_time.time(),
            c.stages.island_construction_time.time(),
            c.step_time(),
        ];
        for (sum, x) in d.iter_mut().zip(now) {
            *sum += x;
        }
    }
    let ms = |d: Duration| d.as_secs_f64() * 1e3 / f64::from(steps.max(1));
    let [broad, narrow, solve, assembly, resolution, ccd, islands, total] = d.map(ms);
    Ok(Split {
        broad,
        narrow,
        solve,
        solve_parts: Some((assembly, resolution)),
        ccd,
        projection: None,
        islands,
        total,
    })
}

/// The Markdown table of the rows: per scene and engine, the median over the repetitions
/// of each stage's ms per step.
pub(crate) fn stage_table(rows: &[StageRow], reps: usize) -> String {
    let mut t = String::new();
    let _ = writeln!(
        t,
        "\n## Stages: ms per step (sleep off, medians of {reps} repetitions)\n"
    );
    let _ = writeln!(
        t,
        "| scene | steps | engine | broad phase | narrow phase | solve | (assembly / resolution) | ccd | projection | islands, sleep | total |"
    );
    let _ = writeln!(
        t,
        "| --- | ---: | --- | ---: | ---: | ---: | ---: | ---: | ---: | ---: | ---: |"
    );
    for r in rows {
        for (engine, runs) in [("carom", &r.carom), ("rapier", &r.rapier)] {
            if runs.is_empty() {
                continue;
            }
            let m = |f: &dyn Fn(&Split) -> f64| median(&runs.iter().map(f).collect::<Vec<_>>());
            let parts = if runs.iter().all(|s| s.solve_parts.is_some()) {
                let a = m(&|s| s.solve_parts.map_or(f64::NAN, |p| p.0));
                let b = m(&|s| s.solve_parts.map_or(f64::NAN, |p| p.1));
                format!("{a:.3} / {b:.3}")
            } else {
                "-".to_string()
            };
            let projection = if runs.iter().all(|s| s.projection.is_some()) {
                format!("{:.3}", m(&|s| s.projection.unwrap_or(f64::NAN)))
            } else {
                "-".to_string()
            };
            let _ = writeln!(
                t,
                "| {} | {} | {} | {:.3} | {:.3} | {:.3} | {} | {:.3} | {} | {:.3} | {:.3} |",
                r.scene.name(),
                r.steps,
                engine,
                m(&|s| s.broad),
                m(&|s| s.narrow),
                m(&|s| s.solve),
                parts,
                m(&|s| s.ccd),
                projection,
                m(&|s| s.islands),
                m(&|s| s.total)
            );
        }
    }
    if rows.iter().all(|r| r.rapier.is_empty()) {
        let _ = writeln!(
            t,
            "\nrapier's stages need its timers: run with `--features stages` (they time every \
             step, so the ratio table is run without them)."
        );
    }
    let _ = writeln!(
        t,
        "\ncarom's narrow phase includes the mid phase and the contact cache, its solve the \
         prepare of the contact rows; rapier's solve is its assembly and resolution and the \
         position update. Totals: carom timed around the step, rapier's own step timer."
    );
    t
}
