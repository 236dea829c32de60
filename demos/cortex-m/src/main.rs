//! carom on a Cortex-M4F: runs the cross-target narrow-phase workload
//! (`demos/workload.rs`), prints `narrow <count> 0x<hash>` over semihosting, then the peak
//! stack the workload used (`stack <bytes>`), and exits QEMU with status 0. A panic prints
//! its message and exits with status 1.
#![no_std]
#![no_main]
#![deny(unsafe_code)]

#[path = "../../workload.rs"]
mod workload;

mod stack;

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};

#[entry]
fn main() -> ! {
    let painted = stack::paint();
    let result = workload::run_narrow_workload();
    let used = stack::peak_use(&painted);
    hprintln!("{}", result);
    hprintln!("stack {} bytes", used);
    debug::exit(debug::EXIT_SUCCESS);
    #[allow(clippy::empty_loop)]
    loop {}
}

#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    hprintln!("panic: {}", info);
    debug::exit(debug::EXIT_FAILURE);
    #[allow(clippy::empty_loop)]
    loop {}
}
