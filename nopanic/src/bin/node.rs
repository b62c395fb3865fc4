//! The whole board logic of capp-node: `serve` (commands in, replies and
//! setpoints out, one planner step per tick) over a UART and a ticker whose
//! values the optimiser cannot see, and the boards' design: the receive
//! interrupt's `rx::on_interrupt` and `serve_queued` fed by its queue, on a
//! node re-initialised in place (`Node::reset`).
#![no_std]
#![no_main]

use capp_nopanic as _;

use capp_node::rx::{self, Queue, RxCounters, RXQ};
use capp_node::{Node, Ticker};
use core::hint::black_box;
use embedded_hal_nb::{nb, serial};

struct Uart;

impl serial::ErrorType for Uart {
    type Error = serial::ErrorKind;
}

impl serial::Read<u8> for Uart {
    fn read(&mut self) -> nb::Result<u8, Self::Error> {
        black_box(Ok(0))
    }
}

impl serial::Write<u8> for Uart {
    fn write(&mut self, word: u8) -> nb::Result<(), Self::Error> {
        black_box(word);
        black_box(Ok(()))
    }
    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        black_box(Ok(()))
    }
}

struct Ticks;

impl Ticker for Ticks {
    fn take(&mut self) -> u32 {
        black_box(1)
    }
}

/// The entry point the linker keeps; everything reachable from it is checked.
#[no_mangle]
pub extern "C" fn _start() -> ! {
    // The firmware's queue size (firmware/src/main.rs).
    let mut node = Node::<4096>::new();
    if black_box(true) {
        capp_node::serve(&mut node, &mut Uart, &mut Ticks)
    }
    node.reset();
    node.set_cycle_counter(|| black_box(0), black_box(25_000_000));
    let mut queue = Queue::<u8, RXQ>::new();
    let (mut producer, mut consumer) = queue.split();
    let counters = RxCounters::new();
    // What the receive interrupt does, then the loop that drains its queue.
    rx::on_interrupt(&mut Uart, &mut producer, &counters);
    capp_node::serve_queued(&mut node, &mut Uart, &mut consumer, &counters, &mut Ticks)
}
