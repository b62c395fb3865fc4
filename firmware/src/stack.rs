//! Stack painting: at boot the unused stack is filled with a pattern; the
//! deepest use is where the pattern first differs, scanning up from the bottom.

use core::ptr::{addr_of, read_volatile, write_volatile};

const PAINT: u32 = 0xCCCC_CCCC;

extern "C" {
    static _stack_start: u32; // top (initial SP)
    static _stack_end: u32; // bottom (end of static data)
}

fn bounds() -> (usize, usize) {
    // Linker symbols: only their addresses are taken.
    (
        addr_of!(_stack_end) as usize,
        addr_of!(_stack_start) as usize,
    )
}

/// Fills the stack below the current stack pointer (minus a margin) with the pattern.
///
/// # Safety
/// Call once, early, from the main thread.
pub unsafe fn paint() {
    let (bottom, _) = bounds();
    let sp = cortex_m::register::msp::read() as usize - 64;
    let mut p = (bottom + 3) & !3;
    while p < sp {
        write_volatile(p as *mut u32, PAINT);
        p += 4;
    }
}

/// Deepest stack use since boot, bytes.
pub fn peak() -> u32 {
    let (bottom, top) = bounds();
    let mut p = (bottom + 3) & !3;
    // SAFETY: reads RAM between the linker's stack bounds, word aligned.
    while p < top && unsafe { read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    (top - p) as u32
}
