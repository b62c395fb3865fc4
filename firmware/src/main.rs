//! CAPP firmware: the planner served over a UART, one step per timer tick.
//!
//! Everything but the board lives in `capp-node`; this binary picks a board
//! (a cargo feature), hands its UART and tick timer to `capp_node::serve`, and
//! measures the stack.
#![no_std]
#![no_main]

mod stack;
mod tick;

#[cfg(feature = "mps2-an386")]
#[path = "board/mps2_an386.rs"]
mod board;
#[cfg(feature = "nucleo-f446re")]
#[path = "board/nucleo_f446re.rs"]
mod board;

use capp_node::Node;
use cortex_m_rt::entry;

/// Transmit queue: room for about 25 setpoints of 18 joints.
const TXQ: usize = 4096;

#[entry]
fn main() -> ! {
    // SAFETY: first thing in main, before any deep call; paints only below the
    // current stack pointer.
    unsafe { stack::paint() };
    defmt::info!(
        "capp-firmware {} on {}",
        env!("CARGO_PKG_VERSION"),
        board::NAME
    );
    let (mut uart, mut ticker) = board::init();
    // Built at compile time into .bss/.data, never on the stack (it is ~30 KiB).
    static mut NODE: Node<TXQ> = Node::new();
    // SAFETY: `main` runs once and never returns; this is the only reference.
    let node: &'static mut Node<TXQ> = unsafe { &mut *core::ptr::addr_of_mut!(NODE) };
    node.set_stack_probe(stack::peak);
    capp_node::serve(node, &mut uart, &mut ticker)
}
