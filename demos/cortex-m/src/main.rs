//! carom on a Cortex-M4F: prints the golden lines of `tests/golden/checksums.txt` over
//! semihosting, then restores the host's snapshot of `mixed` at step 500
//! (`tests/golden/mixed_500.snap`, built into the image), finishes the run and prints
//! `restored mixed 1000 0x<checksum>`, then the peak stack the run used
//! (`stack <bytes> bytes`, from the top of the stack: `stack.rs`) and that of the world's
//! own work in it (`stack world <bytes> bytes`: the scenes' building, steps and hashing,
//! the restore and its steps; not the hull builder or the narrow workload) and the SysTick ticks of each reference scene's steps
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
//! stack world <n> bytes
//! ticks mixed 1000 steps total <t> max <m>
//! ticks bullets 1000 steps total <t> max <m>
//! ticks tower 1000 steps total <t> max <m>
//! ticks terrain 600 steps total <t> max <m>
//! ticks terrain_mesh 600 steps total <t> max <m>
//! ```
//!
//! Memory: the world (`ReferenceWorld`, about 1.2 MB) is a `static` the compiler builds
//! (in `.data`: an empty world is not all zero bits, so its image takes as much flash),
//! emptied between scenes where it lies (`World::reset`); its hulls (about 28 KB) and the
//! terrain scenes' ground (`TerrainData`, about 50 KB) live in `.bss` statics handed out
//! once by `cortex_m::singleton!`, which builds each on the stack first (the run's
//! largest frames but for the hull builder's). `cortex_m::singleton!` would build the
//! world on the stack too (a 1.2 MB frame), as would `*world = ReferenceWorld::new()` (a
//! 113 KB one, in `World::new`).
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
    // Built by the compiler (`World::new` is `const`): the empty world's bytes are in the
    // image's data, copied to RAM at reset, and never on the stack. `#[entry]` hands it
    // out as a `&'static mut`.
    static mut WORLD: ReferenceWorld<'static> = ReferenceWorld::new();
    let painted = stack::paint();
    let mut step_ticks = [StepTicks::default(); Scene::REFERENCE.len()];
    let mut peaks = StackPeaks::default();
    let outcome = run(WORLD, &mut step_ticks, &painted, &mut peaks);
    let used = peaks.deepest.max(stack::peak_use(&painted));
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
    hprintln!("stack world {} bytes", peaks.world);
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

/// Peak stack (bytes from the top, `stack.rs`) of parts of the run.
#[derive(Default)]
struct StackPeaks {
    /// The deepest of the parts measured with their own painting (the hulls' and
    /// terrain's set-up, the scenes with the narrow workload, the restore): a later
    /// painting covers what an earlier part touched, so each is read before the next.
    deepest: u32,
    /// The world's own work: building, stepping and hashing the reference scenes, and
    /// restoring and finishing the snapshot (not the hull builder, not the narrow
    /// workload's buffers).
    world: u32,
}

/// Print the golden lines and the restored line; time each reference scene's steps.
/// Each scene starts from `world` emptied where it lies (`World::reset`). `painted`:
/// the caller's painting, read once the set-up is done; `peaks` gets the parts' peaks.
fn run(
    world: &'static mut ReferenceWorld<'static>,
    step_ticks: &mut [StepTicks; Scene::REFERENCE.len()],
    painted: &stack::Painted,
    peaks: &mut StackPeaks,
) -> Result<(), Failure> {
    let hulls = reference_hulls()?;
    let terrain = reference_terrain()?;
    peaks.deepest = stack::peak_use(painted);
    let scenes_painted = stack::paint();
    let core = cortex_m::Peripherals::take().ok_or(Failure::StaticTaken)?;
    let ticks = ticks::Ticks::start(core.SYST);
    for (scene, timed) in Scene::REFERENCE.into_iter().zip(step_ticks.iter_mut()) {
        world.reset();
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
    peaks.world = stack::peak_use(&scenes_painted);
    print_narrow();
    peaks.deepest = peaks.deepest.max(stack::peak_use(&scenes_painted));
    world.reset();
    let restore_painted = stack::paint();
    let checksum = scenes::continue_from_snapshot(Scene::Mixed, world, hulls, MIXED_500)?;
    let restore = stack::peak_use(&restore_painted);
    peaks.world = peaks.world.max(restore);
    peaks.deepest = peaks.deepest.max(restore);
    hprintln!("restored {}", Scene::Mixed.line(checksum));
    Ok(())
}

/// Run the narrow-phase workload and print its line. Out of line, as
/// [`reference_hulls`]: the workload's buffers (about 45 KB) are its own frame's.
#[inline(never)]
fn print_narrow() {
    hprintln!("{}", scenes::narrow::run());
}

/// The reference hulls (`make_hulls` with the scenes' seed), in a static so the world can
/// borrow them for `'static`. Out of line: `cortex_m::singleton!` builds the hulls in
/// this frame before moving them into their static, and inlined, that frame would stay
/// reserved under every scene's steps.
#[inline(never)]
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
/// borrow it for `'static`. Out of line, as [`reference_hulls`].
#[inline(never)]
fn reference_terrain() -> Result<&'static TerrainShapes<'static>, Failure> {
    let data: &'static mut TerrainData =
        cortex_m::singleton!(: TerrainData = TerrainData::EMPTY).ok_or(Failure::StaticTaken)?;
    let shapes = data.shapes()?;
    let shapes: &'static TerrainShapes<'static> =
        cortex_m::singleton!(: TerrainShapes<'static> = shapes).ok_or(Failure::StaticTaken)?;
    Ok(shapes)
}
