//! The serial line in byte times, as on the Nucleo-F446RE: a receive register
//! that holds one byte and overruns when it is not read within one byte time,
//! a transmit register that sends one byte per byte time, a tick every 115
//! byte times (100 Hz at 115 200 baud), a planner step that lasts 3 byte
//! times (250 us against 87 us) and a setpoint every third step. A host sends one command at a time, waiting
//! for its reply, for as long as the plan runs (its `Status` poll, pings).
//!
//! The polled loop ([`Node::poll`] between steps) must lose bytes here; the
//! interrupt-driven design ([`rx::on_interrupt`] on every arrival, at a
//! higher priority than the step, and [`Node::poll_queue`] between steps)
//! must lose none, answer every command, and stream the host's plan bit for
//! bit.
//!
//! Time is simulated (a byte-time counter), never measured: the same run every
//! time. While a step runs no loop code runs, and every byte that arrives in
//! those byte times lands in the register; with receive by interrupt the
//! interrupt takes it at once, which is what preemption does on the board
//! (the interrupt touches only the register, the queue and its counters).

use std::collections::VecDeque;
use std::vec::Vec;

use capp_proto::{Accumulator, Command, Reply, State, MAX_FRAME};
use embedded_hal_nb::{nb, serial};

use super::{host_plan_with, load_commands_with, long_plan};

/// Exchanges before the plan runs: the load, the settings and `Run`.
const LOAD: usize = 5;
/// The stream's decimation (`Run { every }`).
const EVERY: u32 = 3;
use crate::rx::{self, Queue, RxCounters};
use crate::Node;

/// Byte times per tick: 100 Hz at 115 200 baud, 10 bits a byte.
const TICK: u64 = 115;
/// Byte times one planner step lasts: ~250 us on the F446 at 180 MHz.
const STEP: u64 = 3;
/// A host gives up waiting for a reply after this many byte times.
const TIMEOUT: u64 = 4 * TICK;
/// And sends its next command one to three ticks after a reply (a status
/// poll every few ticks: the line also carries a setpoint every tick), at a
/// pseudo-random moment: a host's clock is not locked to the board's.
fn pause(seed: &mut u64) -> u64 {
    *seed ^= *seed << 13;
    *seed ^= *seed >> 7;
    *seed ^= *seed << 17;
    TICK + *seed % (2 * TICK)
}

/// The board's UART: one receive register, one transmit register.
#[derive(Default)]
struct Uart {
    /// The receive data register.
    data: Option<u8>,
    /// Overrun flag: a byte arrived while `data` was full (and was lost).
    overrun: bool,
    /// Bytes lost to overruns.
    lost: usize,
    /// The transmit data register (on the wire during the next byte time).
    out: Option<u8>,
}

impl Uart {
    /// A byte comes off the wire into the receive register.
    fn arrive(&mut self, b: u8) {
        if self.data.is_some() {
            self.overrun = true;
            self.lost += 1;
        } else {
            self.data = Some(b);
        }
    }
}

impl serial::ErrorType for Uart {
    type Error = serial::ErrorKind;
}

impl serial::Read<u8> for Uart {
    fn read(&mut self) -> nb::Result<u8, Self::Error> {
        // As the STM32 USART: the overrun is reported (and cleared) first,
        // the byte that was kept is read next.
        if self.overrun {
            self.overrun = false;
            return Err(nb::Error::Other(serial::ErrorKind::Overrun));
        }
        self.data.take().ok_or(nb::Error::WouldBlock)
    }
}

impl serial::Write<u8> for Uart {
    fn write(&mut self, b: u8) -> nb::Result<(), Self::Error> {
        if self.out.is_some() {
            return Err(nb::Error::WouldBlock);
        }
        self.out = Some(b);
        Ok(())
    }
    fn flush(&mut self) -> nb::Result<(), Self::Error> {
        Ok(())
    }
}

/// The host end: one command outstanding at a time.
struct Host {
    /// Bytes waiting to go on the wire, one per byte time.
    wire: VecDeque<u8>,
    acc: Accumulator<{ MAX_FRAME - 1 }>,
    /// Commands sent, and the reply each got (`None`: timed out).
    exchanges: Vec<(Command, Option<Reply>)>,
    /// Since when the last command waits for its reply.
    waiting: Option<u64>,
    /// When the next command may go.
    next_at: u64,
    /// Replies that answered nothing outstanding.
    unmatched: usize,
    seed: u64,
    setpoints: Vec<Reply>,
    final_status: Option<Reply>,
    /// Frames the host could not decode.
    damaged: usize,
    nonce: u32,
}

impl Host {
    fn new() -> Self {
        Host {
            wire: VecDeque::new(),
            acc: Accumulator::new(),
            exchanges: Vec::new(),
            waiting: None,
            next_at: 0,
            unmatched: 0,
            seed: 0x2545_f491_4f6c_dd1d,
            setpoints: Vec::new(),
            final_status: None,
            damaged: 0,
            nonce: 0,
        }
    }

    fn send(&mut self, c: Command, now: u64) {
        let mut f = [0u8; MAX_FRAME];
        let n = capp_proto::encode(&c, &mut f).unwrap();
        // As capp-link: a delimiter first ends whatever partial frame the board holds.
        self.wire.push_back(0);
        self.wire.extend(&f[..n]);
        self.exchanges.push((c, None));
        self.waiting = Some(now);
    }

    fn receive(&mut self, b: u8, now: u64) {
        match self.acc.feed_message::<Reply>(b) {
            None => {}
            Some(Err(_)) => self.damaged += 1,
            Some(Ok(r @ Reply::Setpoint { .. })) => self.setpoints.push(r),
            Some(Ok(r)) => {
                let waiting = self.waiting.is_some();
                let outstanding = self.exchanges.last_mut().filter(|_| waiting);
                match (outstanding, &r) {
                    // The status that ends a plan comes unasked.
                    (Some((c, _)), Reply::Status(_)) if *c != Command::Status => {
                        self.final_status = Some(r)
                    }
                    (Some((_, reply)), _) => {
                        *reply = Some(r);
                        self.waiting = None;
                        self.next_at = now + pause(&mut self.seed);
                    }
                    (None, Reply::Status(_)) => self.final_status = Some(r),
                    (None, _) => self.unmatched += 1,
                }
            }
        }
    }

    /// Whether the host may send (no reply awaited, or given up on).
    fn idle(&mut self, now: u64) -> bool {
        if let Some(since) = self.waiting {
            if now - since > TIMEOUT {
                self.waiting = None;
                self.next_at = now;
            }
        }
        self.waiting.is_none() && now >= self.next_at
    }
}

#[derive(Clone, Copy, PartialEq, Debug)]
enum Design {
    Polled,
    Interrupt,
}

struct Outcome {
    host: Host,
    /// Bytes lost to receive overruns.
    lost: usize,
    status: crate::Status,
}

fn run(design: Design) -> Outcome {
    let mut node = Node::<4096>::new();
    let mut uart = Uart::default();
    let mut host = Host::new();
    let mut queue = Queue::<u8, { rx::RXQ }>::new();
    let (mut producer, mut consumer) = queue.split();
    let counters = RxCounters::new();
    let mut load = load_commands_with(long_plan());
    // A setpoint every third step: one of PIPS's (positions, velocities and
    // accelerations, ~240 bytes) takes two ticks of line at 115 200 baud.
    load.push(Command::Run {
        every: EVERY,
        error_change: None,
    });
    let mut load = load.into_iter();
    let mut now = 0u64;
    let mut next_tick = TICK;
    let mut running = false;
    for _ in 0..2_000_000 {
        // The main loop between steps: instant against a byte time.
        match design {
            Design::Polled => node.poll(&mut uart),
            Design::Interrupt => node.poll_queue(&mut uart, &mut consumer, &counters),
        }
        // A tick: one planner step, during which no loop code runs (a tick
        // with no plan running returns at once).
        let busy = if now >= next_tick {
            next_tick += TICK;
            let stepping = node.status().state == State::Running;
            node.tick(1);
            if stepping {
                STEP
            } else {
                1
            }
        } else {
            1
        };
        for _ in 0..busy {
            // The host: the load and Run first, then a command at a time while the plan runs.
            if host.idle(now) {
                if let Some(c) = load.next() {
                    host.send(c, now);
                } else if node.status().state == State::Running {
                    running = true;
                    host.nonce += 1;
                    let c = if host.nonce.is_multiple_of(2) {
                        Command::Status
                    } else {
                        Command::Ping { nonce: host.nonce }
                    };
                    host.send(c, now);
                }
            }
            // One byte time on the wire, both ways.
            if let Some(b) = host.wire.pop_front() {
                uart.arrive(b);
                if design == Design::Interrupt {
                    rx::on_interrupt(&mut uart, &mut producer, &counters);
                }
            }
            if let Some(b) = uart.out.take() {
                host.receive(b, now);
            }
            now += 1;
        }
        if running
            && node.status().state != State::Running
            && node.tx_len() == 0
            && uart.out.is_none()
            && host.idle(now)
            && host.final_status.is_some()
        {
            break;
        }
    }
    // The last status, as the host would ask for it.
    let status = *node.status();
    Outcome {
        host,
        lost: uart.lost,
        status,
    }
}

/// Whether `reply` is the right answer to `command`.
fn answers(command: &Command, reply: &Option<Reply>) -> bool {
    match (command, reply) {
        (Command::Ping { nonce }, Some(Reply::Pong { nonce: n, .. })) => n == nonce,
        (Command::Status, Some(Reply::Status(_))) => true,
        (Command::Run { .. }, Some(Reply::Ack { command: 8 })) => true,
        (c, Some(Reply::Ack { command })) => *command == c.code(),
        _ => false,
    }
}

#[test]
fn the_polled_loop_loses_bytes_that_arrive_during_a_step() {
    let o = run(Design::Polled);
    let during_plan = &o.host.exchanges[LOAD..];
    let answered = during_plan.iter().filter(|(c, r)| answers(c, r)).count();
    std::eprintln!(
        "polled: {} bytes lost to overruns, {answered} of {} commands during the plan answered, rx_errors {}",
        o.lost,
        during_plan.len(),
        o.status.rx_errors
    );
    assert!(during_plan.len() > 50, "{} commands", during_plan.len());
    assert!(o.lost > 0, "no byte was lost");
    assert!(
        answered < during_plan.len(),
        "all {answered} commands were answered"
    );
    // Lost bytes are at least seen: the board counts overruns and bad frames.
    assert!(o.status.rx_errors > 0);
}

#[test]
fn receive_by_interrupt_loses_nothing_and_answers_every_command() {
    let o = run(Design::Interrupt);
    assert_eq!(o.lost, 0, "bytes lost to overruns");
    assert_eq!(o.status.rx_errors, 0);
    assert_eq!(o.status.rx_overflows, 0);
    assert_eq!((o.host.damaged, o.host.unmatched), (0, 0));
    let during_plan = &o.host.exchanges[LOAD..];
    std::eprintln!(
        "interrupt: {} bytes lost, {} commands during the plan, {} setpoints",
        o.lost,
        during_plan.len(),
        o.host.setpoints.len()
    );
    assert!(during_plan.len() > 50, "{} commands", during_plan.len());
    for (i, (c, r)) in o.host.exchanges.iter().enumerate() {
        assert!(answers(c, r), "command {i} {c:?} got {r:?}");
    }
    // And the stream is the host's plan, bit for bit: the start, every
    // third step, the last.
    let plan = host_plan_with(long_plan());
    let last = plan.len() - 1;
    let expected: Vec<usize> = (0..=last)
        .filter(|&k| k % EVERY as usize == 0 || k == last)
        .collect();
    assert_eq!(o.status.dropped, 0);
    assert_eq!(o.host.setpoints.len(), expected.len());
    for (i, (r, &k)) in o.host.setpoints.iter().zip(&expected).enumerate() {
        let Reply::Setpoint {
            seq,
            step,
            joints,
            time_s,
            ..
        } = r
        else {
            unreachable!()
        };
        assert_eq!((*seq, *step as usize), (i as u32, k));
        let bits = |v: &[f32]| v.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(joints), bits(&plan[k].0), "setpoint {i}");
        assert_eq!(time_s.to_bits(), plan[k].1.to_bits());
    }
    let Some(Reply::Status(s)) = o.host.final_status else {
        panic!("no final status")
    };
    assert_eq!(s.state, State::Done);
}

#[test]
fn a_full_receive_queue_is_counted_and_answered() {
    // The transmit side stalls (nothing leaves the board), so the node stops
    // taking bytes from its queue once its reply reserve is in use; a host
    // that keeps sending overfills the queue. Every lost byte is counted,
    // and the damaged frames are answered once the line moves again.
    let mut node = Node::<{ crate::RESERVE + 64 }>::new();
    let mut uart = Uart::default();
    // 59 bytes: not a whole number of frames, so one is cut.
    let mut queue = Queue::<u8, 60>::new();
    let (mut producer, mut consumer) = queue.split();
    let counters = RxCounters::new();
    let mut frame = [0u8; MAX_FRAME];
    let n = capp_proto::encode(&Command::Ping { nonce: 7 }, &mut frame).unwrap();
    let mut sent = 0;
    let mut accepted = 0;
    for _ in 0..100 {
        for &b in &frame[..n] {
            uart.arrive(b);
            sent += 1;
            accepted += rx::on_interrupt(&mut uart, &mut producer, &counters);
        }
        // The board's loop runs, but its UART takes nothing.
        uart.out = Some(0);
        node.poll_queue(&mut uart, &mut consumer, &counters);
    }
    assert_eq!(uart.lost, 0);
    assert!(counters.overflows() > 0);
    assert_eq!(accepted + counters.overflows() as usize, sent);
    assert_eq!(node.status().rx_overflows, counters.overflows());
    // The line moves again: everything the node still holds comes out; the
    // host ends the cut frame (a delimiter, as capp-link sends before every
    // command) and pings again. The cut frame is answered with an error.
    let n8 = capp_proto::encode(&Command::Ping { nonce: 8 }, &mut frame).unwrap();
    let mut out = Vec::new();
    let mut again = core::iter::once(0).chain(frame[..n8].iter().copied());
    for _ in 0..100_000 {
        if let Some(b) = uart.out.take() {
            out.push(b);
        }
        node.poll_queue(&mut uart, &mut consumer, &counters);
        if consumer.len() == 0 {
            if let Some(b) = again.next() {
                uart.arrive(b);
                rx::on_interrupt(&mut uart, &mut producer, &counters);
            }
        }
    }
    let replies = super::replies_lossy(&out);
    let pongs = replies
        .iter()
        .filter(|r| matches!(r, Reply::Pong { nonce: 7, .. }))
        .count();
    let errors = replies
        .iter()
        .filter(|r| matches!(r, Reply::Error { .. }))
        .count();
    assert!(pongs > 0 && errors > 0, "{pongs} pongs, {errors} errors");
    assert!(matches!(replies.last(), Some(Reply::Pong { nonce: 8, .. })));
    assert_eq!(node.status().rx_errors as usize, errors);
}
