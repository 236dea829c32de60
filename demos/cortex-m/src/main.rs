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
//! emptied between scenes where it lies (`World::reset`). Its eight hulls (about 40 KB),
//! the terrain scenes' ground (`TerrainData`, about 50 KB) and the narrow workload's
//! four hulls (`NarrowHulls`, about 20 KB) are `static`s built from constants
//! (`ConvexHull::UNIT_TETRAHEDRON`, `TerrainData::EMPTY`, `NarrowHulls::EMPTY`) and
//! filled in place (`ConvexHull::rebuild`), so none is staged on the stack.
//! (`cortex_m::singleton!` builds its value on the stack and moves it in: it staged each
//! of them, and would the world too, a 1.2 MB frame, as would `*world =
//! ReferenceWorld::new()`, a 113 KB one.) The run's parts (the set-up, the scenes, the
//! narrow workload, the restore) are out-of-line functions called one after the other,
//! so no part's frame is reserved under another's: the run's peak is the deepest part's
//! (the narrow workload's queries), not a sum.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod stack;
mod ticks;

use carom::scenes::narrow::NarrowHulls;
use carom::scenes::{
    self, ReferenceWorld, Scene, TerrainData, TerrainShapes, REFERENCE_HULLS, SEED,
};
use carom::ConvexHull;
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
    /// The core peripherals were already taken (`run` is called once).
    PeripheralsTaken,
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
    // The world's hulls and terrain and the narrow workload's hulls: constants too,
    // filled in place (`ConvexHull::rebuild`, `TerrainData::shapes`), so none of them is
    // ever staged on the stack.
    static mut HULLS: [ConvexHull; REFERENCE_HULLS] =
        [ConvexHull::UNIT_TETRAHEDRON; REFERENCE_HULLS];
    static mut TERRAIN: TerrainData = TerrainData::EMPTY;
    static mut SHAPES: Option<TerrainShapes<'static>> = None;
    static mut NARROW: NarrowHulls = NarrowHulls::EMPTY;
    let painted = stack::paint();
    let mut step_ticks = [StepTicks::default(); Scene::REFERENCE.len()];
    let mut peaks = StackPeaks::default();
    // The set-up runs in frames of its own under `main`'s, not under the run's.
    let outcome = set_up(HULLS, TERRAIN, SHAPES).and_then(|(hulls, terrain)| {
        peaks.deepest = stack::peak_use(&painted);
        let statics = Statics {
            world: WORLD,
            hulls,
            terrain,
            narrow: NARROW,
        };
        run(statics, &mut step_ticks, &mut peaks)
    });
    let used = peaks.deepest.max(stack::peak_use(&painted));
    let status = match outcome {
        Ok(()) => debug::EXIT_SUCCESS,
        Err(Failure::Carom(e)) => {
            hprintln!("error: {:?}", e);
            debug::EXIT_FAILURE
        }
        Err(Failure::PeripheralsTaken) => {
            hprintln!("error: the core peripherals were taken twice");
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
    /// The deepest of the parts measured with their own painting (the hulls' builds and
    /// the terrain's set-up, the scenes with the narrow workload, the restore): a later
    /// painting covers what an earlier part touched, so each is read before the next.
    deepest: u32,
    /// The world's own work: building, stepping and hashing the reference scenes, and
    /// restoring and finishing the snapshot (not the hull builder, not the narrow
    /// workload's buffers).
    world: u32,
}

/// The run's `static`s (`main`'s), the hulls and the terrain built.
struct Statics {
    world: &'static mut ReferenceWorld<'static>,
    hulls: &'static [ConvexHull],
    terrain: &'static TerrainShapes<'static>,
    narrow: &'static mut NarrowHulls,
}

/// Build the reference hulls (`make_hulls` with the scenes' seed), each in its slot, and
/// the terrain scenes' ground, borrowing the terrain's data. Out of line: the hull
/// builder's frames are under this one, not under the run's.
#[inline(never)]
fn set_up(
    hulls: &'static mut [ConvexHull; REFERENCE_HULLS],
    terrain: &'static mut TerrainData,
    shapes: &'static mut Option<TerrainShapes<'static>>,
) -> Result<(&'static [ConvexHull], &'static TerrainShapes<'static>), Failure> {
    scenes::make_hulls(hulls, SEED)?;
    Ok((hulls, shapes.insert(terrain.shapes()?)))
}

/// Print the golden lines and the restored line; time each reference scene's steps.
/// Each scene starts from the world emptied where it lies (`World::reset`); `peaks` gets
/// the parts' peaks.
fn run(
    statics: Statics,
    step_ticks: &mut [StepTicks; Scene::REFERENCE.len()],
    peaks: &mut StackPeaks,
) -> Result<(), Failure> {
    let (world, hulls, terrain) = (statics.world, statics.hulls, statics.terrain);
    let scenes_painted = stack::paint();
    play_scenes(world, hulls, terrain, step_ticks)?;
    peaks.world = stack::peak_use(&scenes_painted);
    print_narrow(statics.narrow);
    peaks.deepest = peaks.deepest.max(stack::peak_use(&scenes_painted));
    world.reset();
    let restore_painted = stack::paint();
    let checksum = restore_mixed(world, hulls)?;
    let restore = stack::peak_use(&restore_painted);
    peaks.world = peaks.world.max(restore);
    peaks.deepest = peaks.deepest.max(restore);
    hprintln!("restored {}", Scene::Mixed.line(checksum));
    Ok(())
}

/// Build, step (timing each step) and hash each reference scene in `world`, emptied
/// where it lies for each (`World::reset`), and print its line. Out of line: the scenes'
/// frames are not reserved under the narrow workload and the restore.
#[inline(never)]
fn play_scenes(
    world: &mut ReferenceWorld<'static>,
    hulls: &'static [ConvexHull],
    terrain: &'static TerrainShapes<'static>,
    step_ticks: &mut [StepTicks; Scene::REFERENCE.len()],
) -> Result<(), Failure> {
    let core = cortex_m::Peripherals::take().ok_or(Failure::PeripheralsTaken)?;
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
    Ok(())
}

/// Restore the host's snapshot of `mixed` into `world` and finish its run: the checksum
/// after its last step. Out of line, as [`play_scenes`].
#[inline(never)]
fn restore_mixed(
    world: &mut ReferenceWorld<'static>,
    hulls: &'static [ConvexHull],
) -> Result<u64, Failure> {
    Ok(scenes::continue_from_snapshot(
        Scene::Mixed,
        world,
        hulls,
        MIXED_500,
    )?)
}

/// Run the narrow-phase workload with its hulls in `hulls` and print its line. Out of
/// line: its queries' buffers are this frame's, not reserved under the scenes' steps.
#[inline(never)]
fn print_narrow(hulls: &mut NarrowHulls) {
    hprintln!("{}", scenes::narrow::run_in(hulls));
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}
