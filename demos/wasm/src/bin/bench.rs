//! Time per step of the box, hull and sphere scenes of `../shared/SCENES.md`, sleeping
//! off, each from a reset world: what `demos/wasm/bench.sh` runs under Node, built once
//! without and once with WebAssembly's SIMD (`-C target-feature=+simd128`), to show what
//! the vector build gains. Prints one line per scene:
//! `<scene> steps <n> checksum 0x... ms/step <t>` (the two builds' checksums must agree).
//! Names on the command line pick the scenes (default: pyramid20 boxes hulls spheres);
//! `--steps N` caps each scene's steps. Each scene first runs [`WARM_UP`] steps untimed:
//! V8 compiles WebAssembly in tiers (a quick baseline, then optimised code for the
//! functions that run hot), and the first scene of a run would otherwise pay for that.

use std::time::Instant;

use carom::scenes::{self, Scene};
use carom::{ConvexHull, World, WorldConfig};

/// Steps run untimed before each scene's timed run (module docs).
const WARM_UP: u32 = 60;

/// Room for `spheres` (4101 bodies) and its contacts.
type BenchWorld<'a> = World<'a, 4200, 32768, 64>;

fn main() {
    // The world is built on the stack before it is boxed: wasm32 links this binary with a
    // 64 MiB stack (`build.rs`); elsewhere it runs on a thread with one.
    #[cfg(target_arch = "wasm32")]
    let result = run();
    #[cfg(not(target_arch = "wasm32"))]
    let result = std::thread::Builder::new()
        .stack_size(64 << 20)
        .spawn(run)
        .map_err(|e| e.to_string())
        .and_then(|t| t.join().unwrap_or_else(|_| Err("the run panicked".into())));
    if let Err(e) = result {
        eprintln!("error: {e}");
        std::process::exit(1);
    }
}

/// A carom error as the message `main` prints.
fn err(e: carom::Error) -> String {
    format!("{e:?}")
}

fn run() -> Result<(), String> {
    let mut names = Vec::new();
    let mut cap = u32::MAX;
    let mut args = std::env::args().skip(1);
    while let Some(a) = args.next() {
        if a == "--steps" {
            cap = args
                .next()
                .and_then(|s| s.parse().ok())
                .ok_or("--steps N")?;
        } else {
            names.push(a);
        }
    }
    if names.is_empty() {
        names = ["pyramid20", "boxes", "hulls", "spheres"]
            .map(String::from)
            .to_vec();
    }
    let mut hulls = vec![ConvexHull::UNIT_TETRAHEDRON; 64];
    scenes::make_hulls(&mut hulls, scenes::SEED).map_err(err)?;
    let mut world: Box<BenchWorld<'_>> = Box::default();
    for name in names {
        let scene = Scene::from_name(&name).ok_or(format!("unknown scene {name}"))?;
        // The warm-up (module docs), then the same scene afresh, timed.
        start(&mut world, scene, &hulls)?;
        for _ in 0..WARM_UP.min(scene.steps()) {
            world.step();
        }
        start(&mut world, scene, &hulls)?;
        let steps = scene.steps().min(cap).max(1);
        let t0 = Instant::now();
        for _ in 0..steps {
            world.step();
        }
        let ms = t0.elapsed().as_secs_f64() * 1e3 / f64::from(steps);
        println!(
            "{} steps {} checksum {:#018x} ms/step {:.3}",
            scene.name(),
            steps,
            world.checksum(),
            ms
        );
    }
    Ok(())
}

/// `scene` built afresh in `world` (reset first), sleeping off.
fn start<'a>(
    world: &mut BenchWorld<'a>,
    scene: Scene,
    hulls: &'a [ConvexHull],
) -> Result<(), String> {
    world.reset();
    let config = WorldConfig {
        sleep_enabled: false,
        ..scene.config()
    };
    world.set_config(config).map_err(err)?;
    scene.build(world, hulls).map_err(err)?;
    Ok(())
}
