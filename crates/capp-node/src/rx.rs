//! Interrupt-driven receive: the UART's receive interrupt moves every byte
//! into a fixed-size single-producer single-consumer queue; the main loop
//! drains it ([`crate::Node::poll_queue`]) between planner steps.
//!
//! A UART receive register holds one byte (USART2 on the STM32F446): at
//! 115 200 baud the next byte overwrites it 87 us later, while a planner step
//! takes about 250 us on a 180 MHz part. Polled between steps, bytes that
//! arrive during a step are lost; read by an interrupt that preempts the step,
//! none are. The interrupt does nothing but this, so it is short and cannot
//! disturb the step's arithmetic (the plan stays bit-identical).
//!
//! Nothing is lost silently: a byte that finds the queue full is dropped and
//! counted ([`RxCounters::overflows`], reported as `Status::rx_overflows`), a
//! UART error (overrun, framing, noise) is counted as a line error (added to
//! `Status::rx_errors`); in both cases the frame in progress then fails its
//! COBS or CRC check and is answered with an error, so the host resends.

use core::sync::atomic::{AtomicU32, Ordering};

use embedded_hal_nb::{nb, serial};
pub use heapless::spsc::{Consumer, Producer, Queue};

/// The firmware's receive queue size: `RXQ - 1` bytes (heapless keeps one
/// slot free), two full frames.
pub const RXQ: usize = 512;

/// Most bytes one interrupt takes: a UART with a one-byte register has one,
/// one with a FIFO a few; the bound keeps a UART stuck in an error state from
/// holding the interrupt forever.
pub const MAX_PER_INTERRUPT: usize = 32;

/// What the receive interrupt counts. It is the only writer (the main loop
/// only reads), so a load and a store suffice, which every Cortex-M has.
#[derive(Debug, Default)]
pub struct RxCounters {
    overflows: AtomicU32,
    line_errors: AtomicU32,
}

impl RxCounters {
    /// Zero counts; `const`, for a `static` shared by the interrupt and the loop.
    pub const fn new() -> Self {
        RxCounters {
            overflows: AtomicU32::new(0),
            line_errors: AtomicU32::new(0),
        }
    }

    /// Bytes dropped because the queue was full, since boot.
    pub fn overflows(&self) -> u32 {
        self.overflows.load(Ordering::Relaxed)
    }

    /// UART errors (overrun, framing, noise, parity), since boot.
    pub fn line_errors(&self) -> u32 {
        self.line_errors.load(Ordering::Relaxed)
    }

    fn bump(counter: &AtomicU32) {
        // Single writer: no read-modify-write race (and no CAS needed on M0).
        counter.store(
            counter.load(Ordering::Relaxed).wrapping_add(1),
            Ordering::Relaxed,
        );
    }
}

/// The receive interrupt's work: every byte the UART holds into `queue`, a
/// full queue and UART errors counted in `counters`. Returns the bytes queued.
pub fn on_interrupt<R, const Q: usize>(
    uart: &mut R,
    queue: &mut Producer<'_, u8, Q>,
    counters: &RxCounters,
) -> usize
where
    R: serial::Read<u8>,
{
    let mut queued = 0;
    for _ in 0..MAX_PER_INTERRUPT {
        match uart.read() {
            Ok(byte) => match queue.enqueue(byte) {
                Ok(()) => queued += 1,
                Err(_) => RxCounters::bump(&counters.overflows),
            },
            Err(nb::Error::WouldBlock) => break,
            // The driver clears the error when it reports it; keep reading.
            Err(nb::Error::Other(_)) => RxCounters::bump(&counters.line_errors),
        }
    }
    queued
}
