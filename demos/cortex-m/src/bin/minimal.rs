//! The smallest useful carom firmware, to measure what carom itself costs in flash and
//! RAM: one `World<4, 8, 8>` (a `static` the compiler builds: in `.data`) with a ground box and a ball dropped
//! from 4 m, stepped 120 times (2 s at 60 Hz), then one line over semihosting:
//!
//! ```text
//! ball 120 0x<World::checksum> y <height of the ball's centre in µm> um
//! ```
//!
//! then `stack <n> bytes` and `ticks ball 120 steps total <t> max <m>` (SysTick ticks of
//! the steps: instructions under `qemu-system-arm -icount shift=0`, see `ticks.rs` and
//! `measure.sh`), and exit 0 (1 on an error or a panic). The ball (radius 0.5 m,
//! no bounce) lands after about 0.85 s and rests with its centre near y = 0.5 m. No float
//! formatting: the height is printed as an integer so `core::fmt`'s float code stays out
//! of the image.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

#[path = "../stack.rs"]
mod stack;
#[path = "../ticks.rs"]
mod ticks;

use carom::{BodyDesc, Shape, Vec3, World};
use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};

/// Four bodies, eight contacts, eight events: the smallest world that makes sense.
type SmallWorld = World<'static, 4, 8, 8>;

/// Steps run: 2 s at the default 60 Hz.
const STEPS: u32 = 120;

#[entry]
fn main() -> ! {
    // Built by the compiler (`World::new` is `const`), never on the stack.
    static mut WORLD: SmallWorld = World::new();
    let painted = stack::paint();
    let mut step_ticks = (0u64, 0u32);
    let outcome = run(WORLD, &mut step_ticks);
    let used = stack::peak_use(&painted);
    let status = match outcome {
        Ok((checksum, y)) => {
            hprintln!("ball {} 0x{:016x} y {} um", STEPS, checksum, micrometres(y));
            debug::EXIT_SUCCESS
        }
        Err(e) => {
            hprintln!("error: {:?}", e);
            debug::EXIT_FAILURE
        }
    };
    hprintln!("stack {} bytes", used);
    hprintln!(
        "ticks ball {} steps total {} max {}",
        STEPS,
        step_ticks.0,
        step_ticks.1
    );
    debug::exit(status);
    #[allow(clippy::empty_loop)]
    loop {}
}

/// Drop the ball, step, and return the world's checksum and the ball's height (m);
/// `step_ticks` gets the SysTick ticks of the steps (their sum and the largest).
fn run(world: &mut SmallWorld, step_ticks: &mut (u64, u32)) -> Result<(u64, f32), carom::Error> {
    let core =
        cortex_m::Peripherals::take().ok_or(carom::Error::OutOfRange(carom::Input::Config))?;
    let ticks = ticks::Ticks::start(core.SYST);
    // Ground: a static box whose top face is at y = 0.
    world.add(
        BodyDesc::fixed(Shape::cuboid(Vec3::new(5.0, 0.5, 5.0))?)
            .position(Vec3::new(0.0, -0.5, 0.0)),
    )?;
    let ball =
        world.add(BodyDesc::dynamic(Shape::sphere(0.5)?).position(Vec3::new(0.0, 4.0, 0.0)))?;
    for _ in 0..STEPS {
        let start = ticks.now();
        world.step();
        let t = ticks.since(start);
        step_ticks.0 += u64::from(t);
        step_ticks.1 = step_ticks.1.max(t);
    }
    Ok((world.checksum(), world.body(ball)?.position().y))
}

/// `y` (m) in whole micrometres, rounded toward zero; saturates far outside ±2 km.
fn micrometres(y: f32) -> i32 {
    (y * 1.0e6) as i32
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}
