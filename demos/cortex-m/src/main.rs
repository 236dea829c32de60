//! carom on a Cortex-M4F: prints the golden lines of `tests/golden/checksums.txt` over
//! semihosting, then restores the host's snapshot of `mixed` at step 500
//! (`tests/golden/mixed_500.snap`, built into the image), finishes the run and prints
//! `restored mixed 1000 0x<checksum>`, then the peak stack the run used
//! (`stack <bytes> bytes`), and exits QEMU with status 0. An error or a panic prints its
//! message and exits with status 1.
//!
//! Output, in order:
//!
//! ```text
//! mixed 1000 0x…      the reference scenes (Scene::REFERENCE), each in a fresh world
//! bullets 1000 0x…
//! tower 1000 0x…
//! narrow 256 0x…      the narrow-phase workload (carom::scenes::narrow)
//! restored mixed 1000 0x…
//! stack <n> bytes
//! ```
//!
//! Memory: the world (`ReferenceWorld`, about 540 KB) and its hulls (about 28 KB) live in
//! `.bss` statics handed out once by `cortex_m::singleton!`; nothing large is on the stack.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

mod stack;

use carom::scenes::{self, ReferenceWorld, Scene, REFERENCE_HULLS, SEED};
use carom::{ConvexHull, Vec3};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};

/// The host's snapshot of the `mixed` scene at step [`scenes::SNAPSHOT_STEP`].
static MIXED_500: &[u8] = include_bytes!("../../../tests/golden/mixed_500.snap");

/// Why the run stopped early.
enum Failure {
    /// carom refused an input (a scene, the snapshot).
    Carom(carom::Error),
    /// A static was already handed out (`run` is called once).
    StaticTaken,
}

impl From<carom::Error> for Failure {
    fn from(e: carom::Error) -> Self {
        Failure::Carom(e)
    }
}

#[entry]
fn main() -> ! {
    let painted = stack::paint();
    let outcome = run();
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
    debug::exit(status);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Print the golden lines and the restored line.
fn run() -> Result<(), Failure> {
    let hulls = reference_hulls()?;
    let world: &'static mut ReferenceWorld<'static> =
        cortex_m::singleton!(: ReferenceWorld<'static> = ReferenceWorld::new())
            .ok_or(Failure::StaticTaken)?;
    for scene in Scene::REFERENCE {
        *world = ReferenceWorld::new();
        let checksum = scene.run(world, hulls)?;
        hprintln!("{}", scene.line(checksum));
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
