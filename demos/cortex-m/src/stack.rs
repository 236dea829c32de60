//! Peak stack use by "painting": fill the free stack below the caller with a pattern, run
//! the work, then find the lowest word the pattern no longer holds. The result is how far
//! below the top of the stack (`_stack_start`, where the reset handler starts it) the
//! work reached (bytes), rounded to words: the frames above the painter (the reset
//! handler's and `main`'s, whose locals the compiler reserves on entry) count whole, as
//! used, and below them the painted peak. It is exact for the paths the run took, not a
//! bound over all inputs.
#![allow(unsafe_code)]
// raw reads and writes of the unused stack; nothing else
// Each firmware includes this file and uses the measures it needs: the whole run's from
// the top of the stack, or a query's own below its painting frame.
#![allow(dead_code)]

/// The pattern written into unused stack.
const PATTERN: u32 = 0xCAFE_F00D;
/// Bytes left untouched just below the caller's stack pointer, for `paint`'s own frame.
const GUARD: u32 = 1024;
/// Bytes painted below the guard: far more than the workload needs, far less than the
/// 4 MiB of RAM in memory.x.
const DEPTH: u32 = 256 * 1024;

extern "C" {
    /// The initial stack pointer, from cortex-m-rt's linker script (the top of RAM in
    /// memory.x): only its address is used.
    static _stack_start: u32;
}

/// The painted region: `[low, high)`, the painting frame's stack pointer and the top of
/// the stack.
pub struct Painted {
    top: u32,
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
    // The address of a linker symbol (taking it is safe); nothing is read through it.
    let top = core::ptr::addr_of!(_stack_start) as u32;
    Painted { top, sp, low, high }
}

/// Bytes of stack from its top down to the lowest word the work touched; down to the
/// guard's end when the work stayed within the guard.
pub fn peak_use(p: &Painted) -> u32 {
    p.top - lowest_touched(p)
}

/// Bytes of stack below the painting frame's stack pointer that the work touched (the
/// work's own need, without the frames above it); the guard's size when the work
/// stayed within the guard.
pub fn peak_below_painter(p: &Painted) -> u32 {
    p.sp - lowest_touched(p)
}

/// The lowest painted word the pattern no longer holds; `high` when none.
fn lowest_touched(p: &Painted) -> u32 {
    let mut a = p.low;
    while a < p.high {
        // SAFETY: the same painted words; only read.
        if unsafe { core::ptr::read_volatile(a as *const u32) } != PATTERN {
            return a;
        }
        a += 4;
    }
    p.high
}
