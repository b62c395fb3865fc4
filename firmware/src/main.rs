//! CAPP firmware: the planner served over a UART, one step per timer tick.
//!
//! Everything but the board lives in `capp-node`; this binary picks a board
//! (a cargo feature) and wires it up with RTIC 2: the UART's receive
//! interrupt (priority 2) puts bytes into a queue, SysTick (priority 1)
//! counts ticks, and `idle` (thread mode, the lowest priority) runs
//! `capp_node::serve_queued`: commands from the queue, one planner step per
//! tick, setpoints out. The node (30 KiB) is built once, in place, in a
//! `static` in `.bss`; the stack has an MPU guard below it.
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

#[cfg(all(feature = "mps2-an386", not(feature = "nopanic")))]
use defmt_semihosting as _;
#[cfg(all(feature = "nucleo-f446re", not(feature = "nopanic")))]
use {defmt_rtt as _, panic_probe as _};

/// Panics on QEMU: where and what on stderr, exit status 1
/// ([`board::panicked`]).
#[cfg(all(feature = "mps2-an386", not(feature = "nopanic")))]
#[panic_handler]
fn panic(info: &core::panic::PanicInfo) -> ! {
    board::panicked(info)
}

#[cfg(feature = "nopanic")]
mod nopanic {
    //! The no-panic link check (scripts/nopanic.sh): a panic handler that
    //! calls a symbol no one defines, so any panic path left in the
    //! optimised firmware (RTIC's code, the board glue, capp-node) fails the
    //! link. The defmt transport is left out (defmt-semihosting asserts that
    //! its logger is not re-entered): logs go to a logger that drops them.

    #[defmt::global_logger]
    struct Discard;

    // SAFETY: nothing is written anywhere, so there is nothing to guard.
    unsafe impl defmt::Logger for Discard {
        fn acquire() {}
        unsafe fn flush() {}
        unsafe fn release() {}
        unsafe fn write(_: &[u8]) {}
    }

    extern "C" {
        fn capp_firmware_panic_path_survived() -> !;
    }

    #[panic_handler]
    fn panic(_: &core::panic::PanicInfo) -> ! {
        // SAFETY: never runs: the link fails whenever this call is reachable.
        unsafe { capp_firmware_panic_path_survived() }
    }
}

use capp_node::rx::RxCounters;
// The reset handler, the exception table and the linker script (RTIC
// provides `main`).
use core::mem::MaybeUninit;
use core::ptr::addr_of_mut;
use cortex_m_rt as _;

use capp_node::Node;

/// Transmit queue: room for about 25 setpoints of 18 joints.
const TXQ: usize = 4096;

/// The node's storage, in `.bss`: zeroed by the reset handler, no flash
/// image, no copy. `init` makes it a node in place ([`node`]).
static mut NODE: MaybeUninit<Node<TXQ>> = MaybeUninit::zeroed();

/// The node, built in place in [`NODE`]: once, from `init`.
///
/// # Safety
/// Call once (the result is the only reference to the node).
unsafe fn node() -> &'static mut Node<TXQ> {
    // SAFETY: all-zero bytes are a valid `Node`: every field is an integer,
    // a float, a bool, an array or a heapless container of those (length 0),
    // a fieldless enum with a variant numbered 0, an `Option` of those, or an
    // `Option<fn>` (zero: `None`); no reference, `NonZero` or pointer that
    // must be non-null. (Were a field added that breaks this, `reset` would
    // still run, but this claim must be checked again.) `reset` then gives
    // every field its `Node::new` value, in place.
    let node = unsafe { (*addr_of_mut!(NODE)).assume_init_mut() };
    node.reset();
    node
}
/// What the receive interrupt counts (full queue, UART errors).
static RX_COUNTERS: RxCounters = RxCounters::new();

/// Reached from the `MemoryManagement` handler (`stack.rs`) on a fresh stack.
#[no_mangle]
extern "C" fn stack_overflow() -> ! {
    board::fatal("stack overflow: the stack reached its MPU guard")
}

/// The application, the same on every board; `$rx` is the board's UART
/// receive interrupt.
macro_rules! app {
    ($rx:ident) => {
        #[rtic::app(device = crate::board::pac, peripherals = false)]
        mod app {
            use capp_node::rx::{self, Consumer, Producer, Queue, RXQ};
            use capp_node::Node;

            use crate::{board, stack, tick, RX_COUNTERS, TXQ};

            #[shared]
            struct Shared {}

            #[local]
            struct Local {
                node: &'static mut Node<TXQ>,
                tx: board::Tx,
                rx: board::Rx,
                producer: Producer<'static, u8, RXQ>,
                consumer: Consumer<'static, u8, RXQ>,
                ticker: tick::SysTicker,
            }

            #[init(local = [queue: Queue<u8, RXQ> = Queue::new()])]
            fn init(cx: init::Context) -> (Shared, Local) {
                // SAFETY: first thing, before any deep call; paints only
                // below the current stack pointer.
                unsafe { stack::paint() };
                let mut core = cx.core;
                stack::guard(&mut core.MPU, &mut core.SCB);
                defmt::info!(
                    "capp-firmware {} on {}",
                    env!("CARGO_PKG_VERSION"),
                    board::NAME
                );
                let b = board::init(core.SYST, &mut core.DCB, &mut core.DWT);
                board::log_clocks();
                // SAFETY: `init` runs once.
                let node = unsafe { crate::node() };
                node.set_stack_probe(stack::peak);
                node.set_cycle_counter(board::cycles, board::CORE_HZ);
                let (producer, consumer) = cx.local.queue.split();
                (
                    Shared {},
                    Local {
                        node,
                        tx: b.tx,
                        rx: b.rx,
                        producer,
                        consumer,
                        ticker: b.ticker,
                    },
                )
            }

            /// Every received byte into the queue, at the highest priority.
            #[task(binds = $rx, priority = 2, local = [rx, producer])]
            fn uart_rx(cx: uart_rx::Context) {
                rx::on_interrupt(cx.local.rx, cx.local.producer, &RX_COUNTERS);
            }

            /// The control loop's clock.
            #[task(binds = SysTick, priority = 1)]
            fn systick(_: systick::Context) {
                tick::on_tick();
            }

            /// Commands, planner steps and setpoints, below both interrupts.
            #[idle(local = [node, tx, consumer, ticker])]
            fn idle(cx: idle::Context) -> ! {
                let l = cx.local;
                capp_node::serve_queued(*l.node, l.tx, l.consumer, &RX_COUNTERS, l.ticker)
            }
        }
    };
}

#[cfg(feature = "mps2-an386")]
app!(UART0RX);
#[cfg(feature = "nucleo-f446re")]
app!(USART2);
