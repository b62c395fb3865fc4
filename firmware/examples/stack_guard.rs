//! The stack guard, tested under QEMU: with the firmware's MPU guard
//! (`src/stack.rs`) set up, a runaway recursion must end in the
//! `MemoryManagement` handler, with the static data below the stack intact.
//!
//!     cargo build --release --example stack_guard
//!     qemu-system-arm -machine mps2-an386 -nographic -monitor none \
//!         -semihosting-config enable=on,target=native \
//!         -kernel target/thumbv7em-none-eabihf/release/examples/stack_guard
//!
//! Prints `stack_guard: caught ...` and exits 0 when the guard works; exits 1
//! if the recursion returned or the data below the stack changed.
#![no_std]
#![no_main]

use core::hint::black_box;
use core::ptr::{addr_of, read_volatile};

use cortex_m_rt::entry;
use cortex_m_semihosting::{debug, hprintln};
use panic_semihosting as _;

/// The board's interrupt vectors (cortex-m-rt's `device` feature is on).
#[path = "../src/board/mps2_an386_pac.rs"]
#[allow(dead_code, unused_imports)]
mod pac;
#[path = "../src/stack.rs"]
#[allow(dead_code)]
mod stack;

const PATTERN: u32 = 0x5AFE_C0DE;

/// The last static data before the stack (`.uninit` follows `.bss`): what an
/// overflow would overwrite first.
#[link_section = ".uninit.SENTINEL"]
static mut SENTINEL: [u32; 64] = [0; 64];

fn sentinel_intact() -> bool {
    // SAFETY: reads of a static no one writes after `main` filled it.
    (0..64).all(|i| unsafe { read_volatile(addr_of!(SENTINEL[i])) } == PATTERN)
}

/// Reached from the `MemoryManagement` handler, on a fresh stack.
#[no_mangle]
extern "C" fn stack_overflow() -> ! {
    let (guard, _, _) = stack::bounds();
    if sentinel_intact() {
        hprintln!(
            "stack_guard: caught at the guard (0x{:08x}); data below the stack intact",
            guard
        );
        debug::exit(debug::EXIT_SUCCESS);
    } else {
        hprintln!("stack_guard: FAILED: the data below the stack changed");
        debug::exit(debug::EXIT_FAILURE);
    }
    loop {
        cortex_m::asm::wfi();
    }
}

/// Never returns: it recurses until the stack reaches the guard.
#[inline(never)]
#[allow(unconditional_recursion)]
fn recurse(depth: u32) -> u32 {
    let mut frame = [depth; 64];
    black_box(&mut frame);
    recurse(depth + 1).wrapping_add(frame[depth as usize % 64])
}

#[entry]
fn main() -> ! {
    let mut cp = cortex_m::Peripherals::take().unwrap();
    // SAFETY: first thing in main; the sentinel is written before anything reads it.
    unsafe {
        stack::paint();
        let sentinel = &mut *core::ptr::addr_of_mut!(SENTINEL);
        for word in sentinel.iter_mut() {
            core::ptr::write_volatile(word, PATTERN);
        }
    }
    stack::guard(&mut cp.MPU, &mut cp.SCB);
    let (guard, bottom, top) = stack::bounds();
    hprintln!(
        "stack_guard: guard 0x{:08x}..0x{:08x}, stack top 0x{:08x}; recursing",
        guard,
        bottom,
        top
    );
    let r = recurse(0);
    hprintln!("stack_guard: FAILED: the recursion returned {}", r);
    debug::exit(debug::EXIT_FAILURE);
    loop {
        cortex_m::asm::wfi();
    }
}
