//! Peak stack use by "painting": fill the free stack below the caller with a pattern, run
//! the work, then find the lowest word the pattern no longer holds. The result is how far
//! below the caller's stack pointer the work reached (bytes), rounded to words; it is
//! exact for the paths the run took, not a bound over all inputs.
#![allow(unsafe_code)] // raw reads and writes of the unused stack; nothing else

/// The pattern written into unused stack.
const PATTERN: u32 = 0xCAFE_F00D;
/// Bytes left untouched just below the caller's stack pointer, for `paint`'s own frame.
const GUARD: u32 = 1024;
/// Bytes painted below the guard: far more than the workload needs, far less than the
/// 4 MiB of RAM in memory.x.
const DEPTH: u32 = 256 * 1024;

/// The painted region: `[low, high)` and the caller's stack pointer.
pub struct Painted {
    sp: u32,
    low: u32,
    high: u32,
}

/// Paint the stack below the caller; call it from the frame that then runs the work.
#[inline(always)]
pub fn paint() -> Painted {
    let sp = cortex_m::register::msp::read();
    let high = (sp - GUARD) & !3;
    let low = high - DEPTH;
    let mut a = low;
    while a < high {
        // SAFETY: [low, high) lies in RAM below every live frame (the guard covers this
        // function's own), and nothing else uses it until the work runs.
        unsafe { core::ptr::write_volatile(a as *mut u32, PATTERN) };
        a += 4;
    }
    Painted { sp, low, high }
}

/// Bytes of stack below the painting frame's stack pointer that the work touched; the
/// guard's size when it stayed within the guard.
pub fn peak_use(p: &Painted) -> u32 {
    let mut a = p.low;
    while a < p.high {
        // SAFETY: the same painted words; only read.
        if unsafe { core::ptr::read_volatile(a as *const u32) } != PATTERN {
            return p.sp - a;
        }
        a += 4;
    }
    GUARD
}
