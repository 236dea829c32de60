//! Instructions per step, counted by QEMU: the firmwares time each `World::step` with
//! SysTick on the core clock and print the ticks. Under
//! `qemu-system-arm -icount shift=0` QEMU's virtual clock advances exactly 1 ns per
//! executed instruction, and the MPS2 boards clock SysTick at 25 MHz (`hw/arm/mps2.c`),
//! so one tick is 40 instructions (`measure.sh` converts). Without `-icount` the ticks
//! follow the host's wall clock and mean nothing. On a real chip they are core cycles.

use cortex_m::peripheral::syst::SystClkSource;
use cortex_m::peripheral::SYST;

/// SysTick's largest reload: the counter wraps every 2^24 ticks.
const RELOAD: u32 = 0x00ff_ffff;

/// A free-running SysTick on the core clock.
pub struct Ticks {
    _syst: SYST,
}

impl Ticks {
    /// Start SysTick counting down from its largest reload, without interrupts.
    pub fn start(mut syst: SYST) -> Ticks {
        syst.disable_interrupt();
        syst.set_clock_source(SystClkSource::Core);
        syst.set_reload(RELOAD);
        syst.clear_current();
        syst.enable_counter();
        Ticks { _syst: syst }
    }

    /// The counter now (it counts down).
    pub fn now(&self) -> u32 {
        SYST::get_current()
    }

    /// Ticks since `start` (a value of [`Ticks::now`]); exact while under 2^24 ticks
    /// (671 million instructions under `-icount shift=0`).
    pub fn since(&self, start: u32) -> u32 {
        start.wrapping_sub(SYST::get_current()) & RELOAD
    }
}
