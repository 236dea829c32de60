//! carom on a Cortex-M4F: prints the golden lines of `tests/golden/checksums.txt` over
//! semihosting, then restores the host's snapshot of `mixed` at step 500
//! (`tests/golden/mixed_500.snap`, built into the image), finishes the run and prints
//! `restored mixed 1000 0x<checksum>`, then the peak stack the run used
//! (`stack <bytes> bytes`) and the SysTick ticks of each reference scene's steps
//! (`ticks.rs`: instructions under `qemu-system-arm -icount shift=0`, see `measure.sh`),
//! and exits QEMU
//! with status 0. An error or a panic prints its message and exits with status 1. With
//! the feature `micromath` the lines are those of `tests/golden/checksums_micromath.txt`
//! and the snapshot is `tests/golden/mixed_500_micromath.snap`.
//!
//! Output, in order:
//!
//! ```text
//! mixed 1000 0x…      the reference scenes (Scene::REFERENCE), each in a fresh world
//! bullets 1000 0x…
//! tower 1000 0x…
//! terrain 600 0x…
//! terrain_mesh 600 0x…
//! narrow 256 0x…      the narrow-phase workload (carom::scenes::narrow)
//! restored mixed 1000 0x…
//! stack <n> bytes
//! ticks mixed 1000 steps total <t> max <m>
//! ticks bullets 1000 steps total <t> max <m>
//! ticks tower 1000 steps total <t> max <m>
//! ticks terrain 600 steps total <t> max <m>
//! ticks terrain_mesh 600 steps total <t> max <m>
//! ```
//!
//! Memory: the world (`ReferenceWorld`, about 1.1 MB), its hulls (about 28 KB) and the
//! terrain scenes' ground (`TerrainData`, about 50 KB) live in `.bss` statics handed out
//! once by `cortex_m::singleton!`; nothing large is on the stack.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod stack;
mod ticks;

use carom::scenes::{
    self, ReferenceWorld, Scene, TerrainData, TerrainShapes, REFERENCE_HULLS, SEED,
};
use carom::{ConvexHull, Vec3};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};

/// The host's snapshot of the `mixed` scene at step [`scenes::SNAPSHOT_STEP`].
#[cfg(not(feature = "micromath"))]
static MIXED_500: &[u8] = include_bytes!("../../../tests/golden/mixed_500.snap");
/// The host's snapshot of the `mixed` scene at step [`scenes::SNAPSHOT_STEP`], taken by a
/// `micromath` build (the feature `micromath`: the lines of `checksums_micromath.txt`).
#[cfg(feature = "micromath")]
static MIXED_500: &[u8] = include_bytes!("../../../tests/golden/mixed_500_micromath.snap");

/// Why the run stopped early.
enum Failure {
    /// carom refused an input (a scene, the snapshot).
    Carom(carom::Error),
    /// A static was already handed out (`run` is called once).
    StaticTaken,
}

/// SysTick ticks of one scene's steps: their sum and the largest.
#[derive(Clone, Copy, Default)]
struct StepTicks {
    total: u64,
    max: u32,
}

impl From<carom::Error> for Failure {
    fn from(e: carom::Error) -> Self {
        Failure::Carom(e)
    }
}

#[entry]
fn main() -> ! {
    let painted = stack::paint();
    let mut step_ticks = [StepTicks::default(); Scene::REFERENCE.len()];
    let outcome = run(&mut step_ticks);
    let used = stack::peak_use(&painted);
    let status = match outcome {
        Ok(()) => debug::EXIT_SUCCESS,
        Err(Failure::Carom(e)) => {
            hprintln!("error: {:?}", e);
            debug::EXIT_FAILURE
        }
        Err(Failure::StaticTaken) => {
            hprintln!("error: a static was taken twice");
            debug::EXIT_FAILURE
        }
    };
    hprintln!("stack {} bytes", used);
    for (scene, t) in Scene::REFERENCE.iter().zip(step_ticks) {
        hprintln!(
            "ticks {} {} steps total {} max {}",
            scene.name(),
            scene.steps(),
            t.total,
            t.max
        );
    }
    debug::exit(status);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Print the golden lines and the restored line; time each reference scene's steps.
fn run(step_ticks: &mut [StepTicks; Scene::REFERENCE.len()]) -> Result<(), Failure> {
    let hulls = reference_hulls()?;
    let terrain = reference_terrain()?;
    let world: &'static mut ReferenceWorld<'static> =
        cortex_m::singleton!(: ReferenceWorld<'static> = ReferenceWorld::new())
            .ok_or(Failure::StaticTaken)?;
    let core = cortex_m::Peripherals::take().ok_or(Failure::StaticTaken)?;
    let ticks = ticks::Ticks::start(core.SYST);
    for (scene, timed) in Scene::REFERENCE.into_iter().zip(step_ticks.iter_mut()) {
        *world = ReferenceWorld::new();
        // What Scene::run does, with each step timed.
        world.set_config(scene.config())?;
        scene.build_on(world, hulls, terrain.ground(scene))?;
        for _ in 0..scene.steps() {
            let start = ticks.now();
            world.step();
            let t = ticks.since(start);
            timed.total += u64::from(t);
            timed.max = timed.max.max(t);
        }
        hprintln!("{}", scene.line(world.checksum()));
    }
    hprintln!("{}", scenes::narrow::run());
    *world = ReferenceWorld::new();
    let checksum = scenes::continue_from_snapshot(Scene::Mixed, world, hulls, MIXED_500)?;
    hprintln!("restored {}", Scene::Mixed.line(checksum));
    Ok(())
}

/// The reference hulls (`make_hulls` with the scenes' seed), in a static so the world can
/// borrow them for `'static`.
fn reference_hulls() -> Result<&'static [ConvexHull], Failure> {
    let placeholder = ConvexHull::new(&[Vec3::ZERO, Vec3::X, Vec3::Y, Vec3::Z])?;
    let hulls: &'static mut [ConvexHull; REFERENCE_HULLS] =
        cortex_m::singleton!(: [ConvexHull; REFERENCE_HULLS] = [placeholder; REFERENCE_HULLS])
            .ok_or(Failure::StaticTaken)?;
    scenes::make_hulls(hulls, SEED)?;
    Ok(hulls)
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// The terrain scenes' ground ([`TerrainData::shapes`]), in statics so the world can
/// borrow it for `'static`.
fn reference_terrain() -> Result<&'static TerrainShapes<'static>, Failure> {
    let data: &'static mut TerrainData =
        cortex_m::singleton!(: TerrainData = TerrainData::EMPTY).ok_or(Failure::StaticTaken)?;
    let shapes = data.shapes()?;
    let shapes: &'static TerrainShapes<'static> =
        cortex_m::singleton!(: TerrainShapes<'static> = shapes).ok_or(Failure::StaticTaken)?;
    Ok(shapes)
}
