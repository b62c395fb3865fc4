//! # capp-node: a CAPP board, minus the board
//!
//! Everything the firmware does that does not touch a peripheral: it reads
//! bytes from a UART, answers [`capp_proto::Command`]s, builds and validates a
//! scenario, takes one planner step per timer tick and queues the setpoints
//! for the UART. The board glue (firmware/) only supplies a serial port
//! (`embedded-hal-nb` traits), a tick counter ([`Ticker`]) and, optionally, a
//! stack probe; so this crate runs unchanged on the host, where its tests
//! drive it with a simulated UART.
//!
//! ## Transmit policy (what happens when the UART cannot keep up)
//!
//! Frames wait in a bounded byte queue of `TXQ` bytes that [`Node::poll`]
//! drains without blocking. `RESERVE = 2 * MAX_FRAME` bytes of it are kept for
//! replies:
//!
//! * **Setpoints** are queued only if they fit with the reserve left free;
//!   otherwise the setpoint is **dropped**, its sequence number is used all
//!   the same (the host sees the gap) and `Status::dropped` counts it. The
//!   planner never waits for the UART: the control loop keeps its rate.
//! * **Replies** (acks, errors, pongs, statuses) are never dropped: a byte is
//!   read from the UART only while the reserve is free, so a command's reply
//!   always fits; a host that floods the board is slowed down, not ignored.
//! * The **final status** of a plan waits, if the queue is full, until it fits.
//!
//! ## Timing
//!
//! One planner step per tick. Ticks that arrive while a step runs are not
//! made up: they count as `Status::overruns`.
//!
//! ## Bad input
//!
//! Every bad frame or refused command gets a [`Reply::Error`]; nothing a
//! command carries reaches the planner before it was validated, and a failed
//! `Run` leaves the previous plan and its status as they were.
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

#[cfg(test)]
extern crate std;

mod log;

use capp_core::setpoint::Decimator;
use capp_core::{
    Mission, MissionError, ObstacleError, Phase, Planner, Robot, RobotError, Scenario,
    ScenarioError, SetpointFilter, StartError, SuperEllipsoid,
};
use capp_proto::{
    Command, ErrorCode, FrameError, Part, Preset, Reply, State, Status, MAX_FRAME, MAX_JOINTS as N,
    MAX_OBSTACLES as M, MAX_WAYPOINTS as W, NO_COMMAND, NO_INDEX,
};
use embedded_hal_nb::{nb, serial};
use heapless::{Deque, Vec};

/// Bytes of the transmit queue kept free for replies.
pub const RESERVE: usize = 2 * MAX_FRAME;

/// A source of timer ticks (the control-loop rate).
pub trait Ticker {
    /// Ticks since the last call.
    fn take(&mut self) -> u32;
}

/// The load being built by commands; checked only by `Run`.
#[derive(Clone, Debug)]
struct Draft {
    joints: Vec<capp_core::Joint, N>,
    obstacles: Vec<SuperEllipsoid, M>,
    waypoints: Vec<capp_core::Waypoint, W>,
    /// `None`: the defaults (kept as `None` so `Draft::new` can be `const`).
    settings: Option<capp_core::Settings>,
    start: Vec<f32, N>,
}

impl Draft {
    const fn new() -> Self {
        Draft {
            joints: Vec::new(),
            obstacles: Vec::new(),
            waypoints: Vec::new(),
            settings: None,
            start: Vec::new(),
        }
    }
}

/// A validated plan in progress (or finished).
struct Active {
    scenario: Scenario<N, M, W>,
    planner: Planner<N>,
    decimator: Decimator,
    /// Whether the start setpoint was offered (at the first tick, after `Run`'s ack).
    streaming: bool,
    /// Plan time, seconds: the sum of the step sizes taken.
    time_s: f32,
}

type Refusal = (ErrorCode, u8);

/// The board's state. `TXQ` is the transmit queue's size in bytes (at least
/// `RESERVE + MAX_FRAME` to ever send a setpoint).
pub struct Node<const TXQ: usize> {
    rx: capp_proto::Accumulator<{ MAX_FRAME - 1 }>,
    tx: Deque<u8, TXQ>,
    draft: Draft,
    active: Option<Active>,
    status: Status,
    final_pending: bool,
    stack_probe: Option<fn() -> u32>,
}

fn finite(xs: &[f32]) -> bool {
    xs.iter().all(|x| x.is_finite())
}

impl<const TXQ: usize> Default for Node<TXQ> {
    fn default() -> Self {
        Self::new()
    }
}

impl<const TXQ: usize> Node<TXQ> {
    /// A node with nothing loaded. `const`, so a board can place it in a
    /// `static` without building it on the stack first.
    pub const fn new() -> Self {
        Node {
            rx: capp_proto::Accumulator::new(),
            tx: Deque::new(),
            draft: Draft::new(),
            active: None,
            status: Status {
                state: State::Idle,
                outcome: None,
                step: 0,
                v: 0.0,
                position_error: 0.0,
                orientation_error: 0.0,
                clearance: None,
                setpoints: 0,
                dropped: 0,
                rx_errors: 0,
                overruns: 0,
                stack_peak: 0,
            },
            final_pending: false,
            stack_probe: None,
        }
    }

    /// Sets the function that measures the deepest stack use, for `Status`.
    pub fn set_stack_probe(&mut self, probe: fn() -> u32) {
        self.stack_probe = Some(probe);
    }

    /// The current status (as a `Status` command would report it, minus the stack probe).
    pub fn status(&self) -> &Status {
        &self.status
    }

    /// Bytes waiting in the transmit queue.
    pub fn tx_len(&self) -> usize {
        self.tx.len()
    }

    /// Moves bytes between the UART and the node without blocking: queued
    /// bytes out while the UART takes them, received bytes in (and their
    /// commands answered) while the reply reserve is free.
    pub fn poll<S: serial::Read<u8> + serial::Write<u8>>(&mut self, uart: &mut S) {
        self.flush_final();
        while let Some(&b) = self.tx.front() {
            match uart.write(b) {
                Ok(()) => {
                    self.tx.pop_front();
                }
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => break,
            }
        }
        while TXQ - self.tx.len() >= RESERVE {
            match uart.read() {
                Ok(b) => self.receive(b),
                Err(nb::Error::WouldBlock) => break,
                Err(nb::Error::Other(_)) => {
                    // A UART error (overrun, framing): the frame in progress is
                    // damaged; its CRC or COBS check will fail and be answered.
                    self.status.rx_errors = self.status.rx_errors.wrapping_add(1);
                    break;
                }
            }
        }
    }

    /// Feeds one received byte.
    pub fn receive(&mut self, byte: u8) {
        let result = match self.rx.feed_message::<Command>(byte) {
            None => return,
            Some(r) => r,
        };
        match result {
            Ok(command) => {
                let code = command.code();
                let reply = match self.handle(&command) {
                    Ok(Some(reply)) => reply,
                    Ok(None) => Reply::Ack { command: code },
                    Err((error, index)) => {
                        log::warning!("command {} refused", code);
                        Reply::Error {
                            command: code,
                            code: error,
                            index,
                        }
                    }
                };
                self.queue_reply(&reply);
                // After `Stop`'s ack: the final status.
                self.flush_final();
            }
            Err(e) => {
                self.status.rx_errors = self.status.rx_errors.wrapping_add(1);
                let code = match e {
                    FrameError::Cobs | FrameError::TooLong => ErrorCode::Framing,
                    FrameError::Crc => ErrorCode::Crc,
                    FrameError::Version { .. } => ErrorCode::Version,
                    FrameError::Message => ErrorCode::UnknownMessage,
                    FrameError::Overfull => ErrorCode::Overfull,
                };
                self.queue_reply(&Reply::Error {
                    command: NO_COMMAND,
                    code,
                    index: NO_INDEX,
                });
            }
        }
    }

    fn handle(&mut self, command: &Command) -> Result<Option<Reply>, Refusal> {
        let d = &mut self.draft;
        match command {
            Command::Ping { nonce } => {
                return Ok(Some(Reply::Pong {
                    nonce: *nonce,
                    version: capp_proto::VERSION,
                    max_joints: N as u8,
                    max_obstacles: M as u8,
                    max_waypoints: W as u8,
                }))
            }
            Command::Clear(part) => match part {
                Part::All => *d = Draft::new(),
                Part::Robot => {
                    d.joints.clear();
                    d.start.clear();
                }
                Part::Obstacles => d.obstacles.clear(),
                Part::Waypoints => d.waypoints.clear(),
            },
            Command::Preset(Preset::Pips) => {
                let joints = capp_core::pips::joints();
                d.joints.clear();
                d.start.clear();
                for (j, q) in joints.iter().zip(capp_core::pips::home()) {
                    let _ = d.joints.push(*j);
                    let _ = d.start.push(q);
                }
            }
            Command::Joint { index, joint } => {
                let j = capp_core::Joint::from(*joint);
                let values = [
                    j.alpha, j.a, j.theta, j.d, j.min, j.max, j.max_rate, j.weight,
                ];
                append(&mut d.joints, *index, j, finite(&values))?;
            }
            Command::Obstacle { index, obstacle } => {
                let o = *obstacle;
                let ok = [o.centre, o.semi_axes, o.exponents, o.euler_123]
                    .iter()
                    .all(|v| finite(v));
                append(&mut d.obstacles, *index, SuperEllipsoid::from(o), ok)?;
            }
            Command::Waypoint { index, waypoint } => {
                let w = *waypoint;
                let ok = finite(&w.position)
                    && w.orientation
                        .is_none_or(|r| r.iter().all(|row| finite(row)));
                append(&mut d.waypoints, *index, w.into(), ok)?;
            }
            Command::Settings(s) => {
                let s = capp_core::Settings::from(*s);
                s.validate()
                    .map_err(|_| (ErrorCode::InvalidMission, NO_INDEX))?;
                d.settings = Some(s);
            }
            Command::Start(q) => {
                if let Some(i) = q.iter().position(|x| !x.is_finite()) {
                    return Err((ErrorCode::NotFinite, i as u8));
                }
                d.start = q.clone();
            }
            Command::Run {
                every,
                error_change,
            } => {
                if self.status.state == State::Running || self.final_pending {
                    return Err((ErrorCode::Busy, NO_INDEX));
                }
                if error_change
                    .is_some_and(|c| !(c.position.is_finite() && c.orientation.is_finite()))
                {
                    return Err((ErrorCode::NotFinite, NO_INDEX));
                }
                self.start(capp_proto::setpoint_filter(*every, *error_change))?;
            }
            Command::Stop => {
                if self.status.state != State::Running {
                    return Err((ErrorCode::NotRunning, NO_INDEX));
                }
                self.status.state = State::Stopped;
                self.final_pending = true;
                log::info!("stopped at step {}", self.status.step);
            }
            Command::Status => {
                self.status.stack_peak = self.stack_probe.map_or(0, |p| p());
                return Ok(Some(Reply::Status(self.status)));
            }
        }
        Ok(None)
    }

    /// Validates the draft and, if it is good, replaces the active plan.
    /// Not inlined: its scenario-sized temporaries stay off the stack of the
    /// serving loop.
    #[inline(never)]
    fn start(&mut self, filter: SetpointFilter) -> Result<(), Refusal> {
        let d = &self.draft;
        let robot = Robot::<N>::new(&d.joints).map_err(robot_refusal)?;
        let mission = Mission::<W>::new(&d.waypoints, d.settings.unwrap_or_default())
            .map_err(|e| scenario_refusal(e.into()))?;
        let scenario = Scenario::new(robot, &d.obstacles, &mission).map_err(scenario_refusal)?;
        let planner = Planner::new(&scenario, &d.start).map_err(start_refusal)?;
        self.active = Some(Active {
            scenario,
            planner,
            decimator: Decimator::new(filter),
            streaming: false,
            time_s: 0.0,
        });
        let s = &mut self.status;
        s.state = State::Running;
        s.outcome = None;
        s.step = 0;
        s.setpoints = 0;
        s.dropped = 0;
        s.overruns = 0;
        log::info!("plan started");
        Ok(())
    }

    /// Handles `ticks` timer ticks: one planner step if a plan runs (the
    /// other ticks count as overruns), its setpoint queued or dropped.
    pub fn tick(&mut self, ticks: u32) {
        if ticks == 0 {
            return;
        }
        if self.status.state != State::Running {
            return;
        }
        self.status.overruns = self.status.overruns.wrapping_add(ticks - 1);
        let Some(active) = self.active.as_mut() else {
            return;
        };
        if !active.streaming {
            // The start configuration is the stream's first setpoint (seq 0).
            active.streaming = true;
            let start = *active.planner.last_report();
            self.offer_setpoint(&start);
        }
        let Some(active) = self.active.as_mut() else {
            return;
        };
        let report = match active.planner.step(&active.scenario) {
            Ok(r) => r,
            Err(_) => {
                // Cannot happen: the planner was built from this scenario.
                self.status.state = State::Stopped;
                self.final_pending = true;
                return;
            }
        };
        active.time_s += report.time_step_s;
        let s = &mut self.status;
        s.step = report.step;
        s.v = report.v;
        s.position_error = report.position_error;
        s.orientation_error = report.orientation_error;
        s.clearance = report.clearance.map(|c| c.value);
        self.offer_setpoint(&report);
        let s = &mut self.status;
        if let Phase::Done(outcome) = report.phase {
            s.state = State::Done;
            s.outcome = Some(outcome.into());
            self.final_pending = true;
            log::info!("plan done after {} steps", report.step);
            self.flush_final();
        }
    }

    /// Offers the joint vector after `report` to the decimator; a setpoint
    /// takes the next sequence number and is queued, or dropped (and counted)
    /// if it does not fit beside the reply reserve.
    fn offer_setpoint(&mut self, report: &capp_core::StepReport) {
        let Some(active) = self.active.as_mut() else {
            return;
        };
        if !active.decimator.offer(report) {
            return;
        }
        let s = &mut self.status;
        let seq = s.setpoints;
        s.setpoints = s.setpoints.wrapping_add(1);
        let last_waypoint = active.scenario.waypoints().len().saturating_sub(1) as u8;
        let setpoint = Reply::Setpoint {
            seq,
            step: report.step,
            joints: Vec::from_slice(active.planner.joints()).unwrap_or_default(),
            time_s: active.time_s,
            waypoint: match report.phase {
                Phase::Moving { waypoint } => waypoint,
                Phase::Done(_) => last_waypoint,
            },
        };
        let mut frame = [0u8; MAX_FRAME];
        let sent = match capp_proto::encode(&setpoint, &mut frame) {
            Ok(n) if TXQ - self.tx.len() >= n + RESERVE => {
                for &b in frame.iter().take(n) {
                    let _ = self.tx.push_back(b);
                }
                true
            }
            _ => false,
        };
        if !sent {
            s.dropped = s.dropped.wrapping_add(1);
        }
    }

    /// Queues the final status of a plan if it fits.
    fn flush_final(&mut self) {
        if !self.final_pending {
            return;
        }
        self.status.stack_peak = self.stack_probe.map_or(0, |p| p());
        let mut frame = [0u8; MAX_FRAME];
        if let Ok(n) = capp_proto::encode(&Reply::Status(self.status), &mut frame) {
            if TXQ - self.tx.len() >= n {
                for &b in frame.iter().take(n) {
                    let _ = self.tx.push_back(b);
                }
                self.final_pending = false;
            }
        }
    }

    fn queue_reply(&mut self, reply: &Reply) {
        let mut frame = [0u8; MAX_FRAME];
        if let Ok(n) = capp_proto::encode(reply, &mut frame) {
            // Fits: bytes are read only while RESERVE is free (see `poll`).
            for &b in frame.iter().take(n) {
                let _ = self.tx.push_back(b);
            }
        }
    }
}

/// Serves forever: the board's main loop.
pub fn serve<const TXQ: usize, S, T>(node: &mut Node<TXQ>, uart: &mut S, ticker: &mut T) -> !
where
    S: serial::Read<u8> + serial::Write<u8>,
    T: Ticker,
{
    loop {
        node.poll(uart);
        let ticks = ticker.take();
        node.tick(ticks);
    }
}

fn append<T, const C: usize>(
    list: &mut Vec<T, C>,
    index: u8,
    item: T,
    finite: bool,
) -> Result<(), Refusal> {
    if !finite {
        return Err((ErrorCode::NotFinite, index));
    }
    if index as usize != list.len() {
        return Err((ErrorCode::OutOfOrder, index));
    }
    list.push(item).map_err(|_| (ErrorCode::Capacity, index))
}

fn robot_refusal(e: RobotError) -> Refusal {
    let index = match e {
        RobotError::Empty | RobotError::TooManyJoints { .. } => NO_INDEX,
        RobotError::NotFinite { joint, .. }
        | RobotError::InvertedLimits { joint }
        | RobotError::NonPositiveRate { joint }
        | RobotError::WeightOutOfRange { joint }
        | RobotError::OutOfRange { joint, .. } => joint,
    };
    (ErrorCode::InvalidRobot, index)
}

fn scenario_refusal(e: ScenarioError) -> Refusal {
    match e {
        ScenarioError::Robot(e) => robot_refusal(e),
        ScenarioError::Obstacle(e) => {
            let index = match e {
                ObstacleError::TooMany { .. } => NO_INDEX,
                ObstacleError::NotFinite { obstacle, .. }
                | ObstacleError::SemiAxisOutOfRange { obstacle }
                | ObstacleError::CentreOutOfRange { obstacle }
                | ObstacleError::ExponentOutOfRange { obstacle } => obstacle,
            };
            (ErrorCode::InvalidObstacle, index)
        }
        ScenarioError::Mission(e) => {
            let index = match e {
                MissionError::BadPosition { waypoint }
                | MissionError::NotARotation { waypoint } => waypoint,
                _ => NO_INDEX,
            };
            (ErrorCode::InvalidMission, index)
        }
    }
}

fn start_refusal(e: StartError) -> Refusal {
    let index = match e {
        StartError::NotFinite { joint } | StartError::OutsideLimits { joint } => joint,
        _ => NO_INDEX,
    };
    (ErrorCode::InvalidStart, index)
}

#[cfg(test)]
mod tests;
