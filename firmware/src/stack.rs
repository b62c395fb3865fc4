//! The stack: its guard and its painting.
//!
//! cortex-m-rt puts the stack at the top of RAM, growing down toward the
//! static data (`.data`, `.bss`, `.uninit`) that ends at `_stack_end`. The
//! lowest [`GUARD`] bytes of the stack (from `_stack_end` rounded up to
//! `GUARD`) are made inaccessible with the MPU ([`guard`]): a stack that grows
//! into them faults (`MemoryManagement`) before it reaches the planner's
//! state. The handler gives up the stack it had (back to the top) and
//! reports the overflow; it does not return.
//!
//! Painting: at boot the stack above the guard is filled with a pattern; the
//! deepest use is where the pattern first differs, scanning up from the guard.

use core::ptr::{addr_of, read_volatile, write_volatile};

use cortex_m::peripheral::{scb::Exception, MPU, SCB};

const PAINT: u32 = 0xCCCC_CCCC;

/// Size of the guard region, bytes (a power of two, at least 32, and
/// aligned to itself, as the ARMv7-M MPU wants). It must hold no data: it is
/// the bottom of the stack, of which the firmware uses a few KiB at most.
pub const GUARD: usize = 256;

extern "C" {
    static _stack_start: u32; // top (initial SP)
    static _stack_end: u32; // bottom (end of static data)
}

/// `(guard start, guard end = lowest usable stack address, top of stack)`.
pub fn bounds() -> (usize, usize, usize) {
    // Linker symbols: only their addresses are taken.
    let bottom = addr_of!(_stack_end) as usize;
    let top = addr_of!(_stack_start) as usize;
    let guard = (bottom + GUARD - 1) & !(GUARD - 1);
    (guard, guard + GUARD, top)
}

/// Fills the stack between the guard and the current stack pointer (minus a
/// margin) with the pattern.
///
/// # Safety
/// Call once, early, from the main thread, before [`guard`].
pub unsafe fn paint() {
    let (_, bottom, _) = bounds();
    let sp = cortex_m::register::msp::read() as usize - 64;
    let mut p = bottom;
    while p < sp {
        write_volatile(p as *mut u32, PAINT);
        p += 4;
    }
}

/// Deepest stack use since boot, bytes.
pub fn peak() -> u32 {
    let (_, bottom, top) = bounds();
    let mut p = bottom;
    // SAFETY: reads RAM between the guard and the top of the stack, word aligned.
    while p < top && unsafe { read_volatile(p as *const u32) } == PAINT {
        p += 4;
    }
    (top - p) as u32
}

/// MPU region 0: the guard, no access, never executable; everything else
/// keeps the default memory map (`PRIVDEFENA`). `MemoryManagement` faults are
/// enabled so that an overflow runs [`MemoryManagement`]'s handler.
pub fn guard(mpu: &mut MPU, scb: &mut SCB) {
    let (start, _, _) = bounds();
    const VALID: u32 = 1 << 4;
    const XN: u32 = 1 << 28;
    const AP_NONE: u32 = 0b000 << 24;
    const ENABLE: u32 = 1;
    let size_field = (GUARD.trailing_zeros() - 1) << 1;
    // SAFETY: region 0 covers only the guard, which holds no data; the
    // background map stays as it was for every other address.
    unsafe {
        mpu.rnr.write(0);
        mpu.rbar.write(start as u32 | VALID);
        mpu.rasr.write(XN | AP_NONE | size_field | ENABLE);
        // CTRL: ENABLE | PRIVDEFENA (HFNMIENA off: the fault handlers run
        // without the MPU).
        mpu.ctrl.write(1 | (1 << 2));
    }
    scb.enable(Exception::MemoryManagement);
    cortex_m::asm::dsb();
    cortex_m::asm::isb();
}

// The fault handler owns no stack: the faulting code left SP inside or at the
// guard, and the hardware could not stack its frame there. It starts again at
// the top of the stack (the state below is abandoned) and calls the report.
core::arch::global_asm!(
    ".section .text.MemoryManagement, \"ax\"",
    ".global MemoryManagement",
    ".type MemoryManagement, %function",
    ".thumb_func",
    "MemoryManagement:",
    "ldr r0, =_stack_start",
    "msr msp, r0",
    "isb",
    "b {report}",
    report = sym crate::stack_overflow,
);
