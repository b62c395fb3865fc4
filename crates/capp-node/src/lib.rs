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
//! (or [`Node::poll_queue`]) drains without blocking. [`RESERVE`] (512) bytes of it are kept for
//! replies:
//!
//! * **Setpoints** are queued only if they fit with the reserve left free;
//!   otherwise the setpoint is **dropped**, its sequence number is used all
//!   the same (the host sees the gap) and `Status::dropped` counts it. The
//!   planner never waits for the UART: the control loop keeps its rate.
//! * **Replies** (acks, errors, pongs, statuses) are never dropped: a byte is
//!   taken from the UART (or the receive queue) only while the reserve is
//!   free, so a command's reply always fits; a host that floods the board is
//!   slowed down, not ignored (with receive by interrupt, bytes that no
//!   longer fit the receive queue are dropped and counted, `Status::rx_overflows`,
//!   and their frame is answered with an error).
//! * The **final status** of a plan waits, if the queue is full, until it fits.
//!
//! ## Receive
//!
//! The boards receive by interrupt ([`rx`]): the UART's interrupt puts bytes
//! into a fixed-size queue at a higher priority than the planner step, and
//! [`serve_queued`] drains it between steps, so a command sent while a plan
//! runs (`Stop`, the host's `Status` poll) is never lost to a one-byte
//! receive register. [`serve`] is the polled loop (bytes read from the UART
//! between steps), kept for UARTs that hold bytes back (a host socket).
//!
//! ## Timing
//!
//! One planner step per tick. Ticks that arrive while a step runs are not
//! made up: they count as `Status::overruns`. With a cycle counter
//! ([`Node::set_cycle_counter`]) each tick's work is timed and the fewest,
//! mean and most cycles of the plan go into `Status::step_cycles_*`; in a
//! tracked plan (capp-core's `Motion::Tracked`), a tick whose work took more
//! cycles than the control period (`time_step_s` times the core clock the
//! counter runs at) counts in `Status::period_overruns`: the board could not
//! have kept the drive's period in real time. A stepped plan has no period
//! and counts none.
//!
//! ## Setpoints
//!
//! Each carries the joints' positions, velocities and accelerations: with
//! tracked motion the planner's drive state after the tick
//! (`Planner::drive`), with stepped motion the step's rate as the velocity
//! and its change over the step as the acceleration (`Planner::drive` too).
//!
//! ## Memory
//!
//! A node is about 30 KiB (the model for 32 joints and 64 obstacles, the
//! workspace, the draft load, the transmit queue). A board keeps it in a
//! `static` (zeroed storage in `.bss`, made a node in place by
//! [`Node::reset`]) and never moves it: `Run` re-initialises the scenario and
//! the planner in place (`Scenario::init`, `Planner::restart`), so no
//! scenario-sized value is ever on the stack.
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
pub mod rx;

use capp_core::robot::Placement;
use capp_core::scenario::MAX_JOINT_GOALS;
use capp_core::setpoint::Decimator;
use capp_core::{
    MissionError, Motion, ObstacleError, Phase, Planner, RobotError, Scenario, ScenarioError,
    SetpointFilter, Solid, StartError,
};
use capp_proto::{
    Command, ErrorCode, EscapeMode, Feed, FrameError, HullVertices, Joints, Part, Preset, Reply,
    State, Status, MAX_FRAME, MAX_HULLS, MAX_JOINTS as N, MAX_OBSTACLES as M, MAX_WAYPOINTS as W,
    NO_COMMAND, NO_INDEX,
};
use embedded_hal_nb::{nb, serial};
use heapless::{Deque, Vec};
use rx::{Consumer, RxCounters};

/// Bytes of the transmit queue kept free for replies: two frames of any
/// reply but a setpoint, each at most 256 bytes (capp-proto's wire tests
/// pin that), whatever [`MAX_FRAME`] (which a setpoint of 32 joints with its
/// velocities and accelerations needs) is.
pub const RESERVE: usize = 512;

/// A source of timer ticks (the control-loop rate).
pub trait Ticker {
    /// Ticks since the last call.
    fn take(&mut self) -> u32;
}

/// The load being built by commands; checked only by `Run`.
#[derive(Clone, Debug)]
struct Draft {
    joints: Vec<capp_core::Joint, N>,
    obstacles: Vec<Solid, M>,
    /// The hulls convex obstacles name, their vertices as sent.
    hulls: Vec<HullVertices, MAX_HULLS>,
    waypoints: Vec<capp_core::Waypoint, W>,
    /// Waypoints that are joint configurations: (waypoint index, values).
    joint_goals: Vec<(u8, Vec<f32, N>), MAX_JOINT_GOALS>,
    /// `None`: the defaults (kept as `None` so `Draft::new` can be `const`).
    settings: Option<capp_core::Settings>,
    start: Vec<f32, N>,
    /// Link capsules, one per joint or none (self-collision off): radii and
    /// checked-pair rows, as `Scenario::set_link_capsules` takes them.
    capsule_radius: Vec<f32, N>,
    capsule_rows: Vec<u64, N>,
    /// The capsules' segments, when they are not chords (one per capsule, or
    /// none), as `Scenario::set_link_segments` takes them; and whether a
    /// capsule came without one.
    capsule_segments: Vec<[[f32; 3]; 2], N>,
    capsule_chords: bool,
    /// Drive limits, one per joint or none (the defaults from the rates):
    /// accelerations and jerks, as `Scenario::set_drive_limits` takes them.
    drive_accel: Vec<f32, N>,
    drive_jerk: Vec<f32, N>,
    /// The tool (the identity until a `Tool` command).
    tool: Placement,
}

impl Draft {
    const fn new() -> Self {
        Draft {
            joints: Vec::new(),
            obstacles: Vec::new(),
            hulls: Vec::new(),
            waypoints: Vec::new(),
            joint_goals: Vec::new(),
            settings: None,
            start: Vec::new(),
            capsule_radius: Vec::new(),
            capsule_rows: Vec::new(),
            capsule_segments: Vec::new(),
            capsule_chords: false,
            drive_accel: Vec::new(),
            drive_jerk: Vec::new(),
            tool: Placement::IDENTITY,
        }
    }

    /// [`Draft::new`] in place.
    fn clear(&mut self) {
        let Draft {
            joints,
            obstacles,
            hulls,
            waypoints,
            joint_goals,
            settings,
            start,
            capsule_radius,
            capsule_rows,
            capsule_segments,
            capsule_chords,
            drive_accel,
            drive_jerk,
            tool,
        } = self;
        joints.clear();
        obstacles.clear();
        hulls.clear();
        waypoints.clear();
        joint_goals.clear();
        *settings = None;
        start.clear();
        capsule_radius.clear();
        capsule_rows.clear();
        capsule_segments.clear();
        *capsule_chords = false;
        drive_accel.clear();
        drive_jerk.clear();
        *tool = Placement::IDENTITY;
    }

    /// No capsules: self-collision off.
    fn clear_capsules(&mut self) {
        self.capsule_radius.clear();
        self.capsule_rows.clear();
        self.capsule_segments.clear();
        self.capsule_chords = false;
    }

    /// No drive limits: the defaults from the rates.
    fn clear_drives(&mut self) {
        self.drive_accel.clear();
        self.drive_jerk.clear();
    }

    /// A command that changes the load (`Clear`, `Preset`, `Joint`, ...,
    /// `Start`); the others change nothing here. Not generic (unlike
    /// [`Node`]): compiled once, with capp-node's optimisation level (the
    /// firmware builds this cold code for size).
    #[inline(never)]
    fn load(&mut self, command: &Command) -> Result<(), Refusal> {
        let d = self;
        match command {
            Command::Clear(part) => match part {
                // In place: a draft is 6 KiB, too big for a temporary on
                // the serving loop's stack.
                Part::All => d.clear(),
                Part::Robot => {
                    d.joints.clear();
                    d.start.clear();
                    d.clear_capsules();
                    d.clear_drives();
                    d.tool = Placement::IDENTITY;
                }
                Part::Obstacles => {
                    d.obstacles.clear();
                    d.hulls.clear();
                }
                Part::Waypoints => {
                    d.waypoints.clear();
                    d.joint_goals.clear();
                }
                Part::Capsules => d.clear_capsules(),
                Part::Drives => d.clear_drives(),
            },
            Command::Preset(Preset::Pips) => {
                let joints = capp_core::pips::joints();
                d.joints.clear();
                d.start.clear();
                // The old robot's capsules, drives and tool do not fit the preset.
                d.clear_capsules();
                d.clear_drives();
                d.tool = Placement::IDENTITY;
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
                let ok = finite(&values)
                    && j.origin
                        .is_none_or(|o| o.placement.is_finite() && finite(&o.axis));
                append(&mut d.joints, *index, j, ok)?;
            }
            Command::Obstacle { index, obstacle } => {
                let o = *obstacle;
                let ok = [o.centre, o.semi_axes, o.exponents, o.euler_123]
                    .iter()
                    .all(|v| finite(v));
                append(&mut d.obstacles, *index, Solid::from(o), ok)?;
            }
            Command::Hull { index, vertices } => {
                let ok = vertices.iter().all(|v| finite(v));
                append(&mut d.hulls, *index, vertices.clone(), ok)?;
            }
            Command::Waypoint { index, waypoint } => {
                let w = *waypoint;
                let ok = finite(&w.position)
                    && w.orientation
                        .is_none_or(|r| r.iter().all(|row| finite(row)));
                append(&mut d.waypoints, *index, w.into(), ok)?;
            }
            Command::JointWaypoint { index, joints } => {
                if let Some(i) = joints.iter().position(|x| !x.is_finite()) {
                    return Err((ErrorCode::NotFinite, i as u8));
                }
                if d.joint_goals.is_full() {
                    return Err((ErrorCode::Capacity, *index));
                }
                // A waypoint slot whose pose the core fills in at `Run`.
                append(
                    &mut d.waypoints,
                    *index,
                    capp_core::Waypoint::at([0.0; 3]),
                    true,
                )?;
                let _ = d.joint_goals.push((*index, joints.clone()));
            }
            Command::Capsule { index, capsule } => {
                let finite = capsule.radius.is_finite();
                append(&mut d.capsule_radius, *index, capsule.radius, finite)?;
                // The same length as the radii: they cannot be full.
                let _ = d.capsule_rows.push(capsule.checked);
                match capsule.segment {
                    Some(segment) => {
                        let _ = d.capsule_segments.push(segment);
                    }
                    None => d.capsule_chords = true,
                }
            }
            Command::Drive { index, drive } => {
                let finite = drive.max_accel.is_finite() && drive.max_jerk.is_finite();
                append(&mut d.drive_accel, *index, drive.max_accel, finite)?;
                // The same length as the accelerations: it cannot be full.
                let _ = d.drive_jerk.push(drive.max_jerk);
            }
            Command::Tool(tool) => {
                let tool = Placement::from(*tool);
                if !tool.is_finite() {
                    return Err((ErrorCode::NotFinite, NO_INDEX));
                }
                d.tool = tool;
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
            Command::Ping { .. } | Command::Run { .. } | Command::Stop | Command::Status => {}
        }
        Ok(())
    }
}

/// The status of a board that has run nothing.
const IDLE: Status = Status {
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
    rx_overflows: 0,
    step_cycles_min: 0,
    step_cycles_mean: 0,
    step_cycles_max: 0,
    escape: EscapeMode::Descending,
    escape_attempt: 0,
    period_overruns: 0,
};

/// The plan: valid while `Status::state` is `Running` (and after, until the
/// next `Run`), re-initialised in place by `Run`.
struct Active {
    scenario: Scenario<N, M, W>,
    planner: Planner<N>,
    decimator: Decimator,
    /// Whether the start setpoint was offered (at the first tick, after `Run`'s ack).
    streaming: bool,
    /// Plan time, seconds: the sum of the step sizes taken.
    time_s: f32,
    /// Tracked motion (`Motion::Tracked`): setpoints carry the drive state.
    tracked: bool,
    /// Cycles of the control period, for `Status::period_overruns`: tracked
    /// plans on a board with a cycle counter, else `None`.
    period_cycles: Option<u32>,
}

type Refusal = (ErrorCode, u8);

/// The board's state. `TXQ` is the transmit queue's size in bytes (at least
/// `RESERVE + MAX_FRAME` to ever send a setpoint).
pub struct Node<const TXQ: usize> {
    rx: capp_proto::Accumulator<{ MAX_FRAME - 1 }>,
    tx: Deque<u8, TXQ>,
    draft: Draft,
    plan: Active,
    status: Status,
    final_pending: bool,
    stack_probe: Option<fn() -> u32>,
    cycle_counter: Option<fn() -> u32>,
    /// The rate `cycle_counter` counts at, Hz (0: unknown).
    cycle_hz: u32,
    cycles: CycleStats,
    /// `RxCounters::line_errors` already added to `status.rx_errors`.
    line_errors_seen: u32,
}

/// Cycles per tick's work in the current plan.
#[derive(Clone, Copy, Debug, Default)]
struct CycleStats {
    min: u32,
    max: u32,
    sum: u64,
    count: u32,
}

impl CycleStats {
    fn add(&mut self, cycles: u32) {
        self.min = if self.count == 0 {
            cycles
        } else {
            self.min.min(cycles)
        };
        self.max = self.max.max(cycles);
        self.sum = self.sum.wrapping_add(cycles as u64);
        self.count = self.count.saturating_add(1);
    }

    fn mean(&self) -> u32 {
        match self.count {
            0 => 0,
            n => (self.sum / n as u64).min(u32::MAX as u64) as u32,
        }
    }
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
    /// A node with nothing loaded, by value (about 30 KiB: for a host). A
    /// board keeps its node in a `static` and calls [`Node::reset`] on it
    /// instead, so that it is never built on the stack.
    pub fn new() -> Self {
        Node {
            rx: capp_proto::Accumulator::new(),
            tx: Deque::new(),
            draft: Draft::new(),
            plan: Active {
                scenario: Scenario::empty(),
                planner: Planner::empty(),
                decimator: Decimator::new(SetpointFilter::Every(1)),
                streaming: false,
                time_s: 0.0,
                tracked: false,
                period_cycles: None,
            },
            status: IDLE,
            final_pending: false,
            stack_probe: None,
            cycle_counter: None,
            cycle_hz: 0,
            cycles: CycleStats {
                min: 0,
                max: 0,
                sum: 0,
                count: 0,
            },
            line_errors_seen: 0,
        }
    }

    /// [`Node::new`] in place: every field back to its initial value, with
    /// no node-sized (or scenario-sized) value on the stack.
    pub fn reset(&mut self) {
        // Every field is named: a field added to `Node` fails to compile here.
        let Node {
            rx,
            tx,
            draft,
            plan,
            status,
            final_pending,
            stack_probe,
            cycle_counter,
            cycle_hz,
            cycles,
            line_errors_seen,
        } = self;
        *rx = capp_proto::Accumulator::new();
        tx.clear();
        draft.clear();
        let Active {
            scenario,
            planner,
            decimator,
            streaming,
            time_s,
            tracked,
            period_cycles,
        } = plan;
        scenario.clear();
        planner.clear();
        *decimator = Decimator::new(SetpointFilter::Every(1));
        *streaming = false;
        *time_s = 0.0;
        *tracked = false;
        *period_cycles = None;
        *status = IDLE;
        *final_pending = false;
        *stack_probe = None;
        *cycle_counter = None;
        *cycle_hz = 0;
        *cycles = CycleStats::default();
        *line_errors_seen = 0;
    }

    /// Sets the free-running cycle counter (wrapping `u32`, e.g. the DWT's
    /// `CYCCNT`) that times each tick's work, for `Status::step_cycles_*`,
    /// and the rate it counts at (`hz`, the core clock; 0: unknown), for
    /// `Status::period_overruns`. Takes effect at the next `Run`.
    pub fn set_cycle_counter(&mut self, counter: fn() -> u32, hz: u32) {
        self.cycle_counter = Some(counter);
        self.cycle_hz = hz;
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
    ///
    /// This is the polled design: bytes that arrive while a planner step runs
    /// wait in the UART; a UART that holds one byte loses the rest (see
    /// [`rx`] and [`Node::poll_queue`]).
    pub fn poll<S: serial::Read<u8> + serial::Write<u8>>(&mut self, uart: &mut S) {
        self.send(uart);
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

    /// Moves bytes without blocking, receive by interrupt: queued bytes out
    /// while the UART takes them, bytes the receive interrupt queued
    /// ([`rx::on_interrupt`]) in (and their commands answered) while the
    /// reply reserve is free; the interrupt's counts into the status.
    pub fn poll_queue<W: serial::Write<u8>, const Q: usize>(
        &mut self,
        uart: &mut W,
        queue: &mut Consumer<'_, u8, Q>,
        counters: &RxCounters,
    ) {
        self.send(uart);
        self.status.rx_overflows = counters.overflows();
        let line_errors = counters.line_errors();
        let new = line_errors.wrapping_sub(self.line_errors_seen);
        self.line_errors_seen = line_errors;
        self.status.rx_errors = self.status.rx_errors.wrapping_add(new);
        while TXQ - self.tx.len() >= RESERVE {
            match queue.dequeue() {
                Some(b) => self.receive(b),
                None => break,
            }
        }
    }

    /// Queued bytes out while the UART takes them.
    fn send<W: serial::Write<u8>>(&mut self, uart: &mut W) {
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
    }

    /// Feeds one received byte.
    pub fn receive(&mut self, byte: u8) {
        let result = match self.rx.feed(byte) {
            Feed::Consumed => return,
            Feed::Overfull => Err(FrameError::Overfull),
            // Not generic: the decoder is capp-proto's one copy.
            Feed::Frame(frame) => capp_proto::decode_command(frame),
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
            load => self.draft.load(load)?,
        }
        Ok(None)
    }

    /// Validates the draft and, if it is good, replaces the active plan.
    /// Not inlined: its scenario-sized temporaries stay off the stack of the
    /// serving loop.
    #[inline(never)]
    fn start(&mut self, filter: SetpointFilter) -> Result<(), Refusal> {
        // Built in place: a refused load leaves an empty plan, never stepped
        // (the state is not `Running`), and the status as it was.
        let d = &self.draft;
        let plan = &mut self.plan;
        let mut hulls: [&[[f32; 3]]; MAX_HULLS] = [&[]; MAX_HULLS];
        for (slot, vertices) in hulls.iter_mut().zip(&d.hulls) {
            *slot = vertices;
        }
        plan.scenario
            .init_with_hulls(
                &d.joints,
                &d.tool,
                &d.obstacles,
                hulls.get(..d.hulls.len()).unwrap_or_default(),
                &d.waypoints,
                d.settings.unwrap_or_default(),
            )
            .map_err(scenario_refusal)?;
        for (waypoint, joints) in &d.joint_goals {
            plan.scenario
                .set_joint_goal(*waypoint as usize, joints)
                .map_err(scenario_refusal)?;
        }
        // Bit for bit the host's capsules (`Scenario::capsules` there); none
        // sent, none checked.
        if !d.capsule_radius.is_empty() {
            plan.scenario
                .set_link_capsules(&d.capsule_radius, &d.capsule_rows)
                .map_err(scenario_refusal)?;
            // Every capsule round a segment of its own, or none.
            if d.capsule_chords && !d.capsule_segments.is_empty() {
                return Err((ErrorCode::InvalidCapsules, NO_INDEX));
            }
            plan.scenario
                .set_link_segments(&d.capsule_segments)
                .map_err(scenario_refusal)?;
        }
        // Bit for bit the host's drive limits (`Scenario::drive_limits`
        // there); none sent, the defaults from the rates.
        if !d.drive_accel.is_empty() {
            plan.scenario
                .set_drive_limits(&d.drive_accel, &d.drive_jerk)
                .map_err(scenario_refusal)?;
        }
        plan.planner
            .restart(&plan.scenario, &d.start)
            .map_err(start_refusal)?;
        plan.decimator = Decimator::new(filter);
        plan.streaming = false;
        plan.time_s = 0.0;
        let settings = plan.scenario.settings();
        plan.tracked = settings.motion == Motion::Tracked;
        plan.period_cycles = match (plan.tracked, self.cycle_counter, self.cycle_hz) {
            // `as` saturates: a period beyond u32::MAX cycles is never overrun.
            (true, Some(_), hz) if hz > 0 => Some((settings.time_step_s * hz as f32) as u32),
            _ => None,
        };
        self.cycles = CycleStats::default();
        let s = &mut self.status;
        s.state = State::Running;
        s.outcome = None;
        s.step = 0;
        s.setpoints = 0;
        s.dropped = 0;
        s.overruns = 0;
        s.step_cycles_min = 0;
        s.step_cycles_mean = 0;
        s.step_cycles_max = 0;
        s.period_overruns = 0;
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
        let started = self.cycle_counter.map(|c| c());
        if !self.plan.streaming {
            // The start configuration is the stream's first setpoint (seq 0).
            self.plan.streaming = true;
            let start = *self.plan.planner.last_report();
            self.offer_setpoint(&start);
        }
        let active = &mut self.plan;
        let report = match active.planner.step(&active.scenario) {
            Ok(r) => r,
            Err(_) => {
                // Cannot happen: the planner was built from this scenario.
                self.status.state = State::Stopped;
                self.final_pending = true;
                return;
            }
        };
        // Tracked: every tick is one period, so the time is the tick count
        // times it (a running f32 sum would drift off t = k dt).
        active.time_s = if active.tracked {
            report.step as f32 * active.scenario.settings().time_step_s
        } else {
            active.time_s + report.time_step_s
        };
        let s = &mut self.status;
        s.step = report.step;
        s.v = report.v;
        s.position_error = report.position_error;
        s.orientation_error = report.orientation_error;
        s.clearance = report.clearance.map(|c| c.value);
        (s.escape, s.escape_attempt) = capp_proto::escape_status(report.escape);
        self.offer_setpoint(&report);
        if let (Some(counter), Some(t0)) = (self.cycle_counter, started) {
            let cycles = counter().wrapping_sub(t0);
            self.cycles.add(cycles);
            let s = &mut self.status;
            s.step_cycles_min = self.cycles.min;
            s.step_cycles_mean = self.cycles.mean();
            s.step_cycles_max = self.cycles.max;
            if self
                .plan
                .period_cycles
                .is_some_and(|period| cycles > period)
            {
                s.period_overruns = s.period_overruns.wrapping_add(1);
                log::warning!(
                    "tick {} overran the control period: {} cycles",
                    s.step,
                    cycles
                );
            }
        }
        let s = &mut self.status;
        if let Phase::Done(outcome) = report.phase {
            s.state = State::Done;
            s.outcome = Some(outcome.into());
            self.final_pending = true;
            log::info!(
                "plan done after {} steps; cycles per step min {} mean {} max {}, overruns {}, period overruns {}",
                report.step,
                s.step_cycles_min,
                s.step_cycles_mean,
                s.step_cycles_max,
                s.overruns,
                s.period_overruns
            );
            self.flush_final();
        }
    }

    /// Offers the joint vector after `report` to the decimator; a setpoint
    /// takes the next sequence number and is queued, or dropped (and counted)
    /// if it does not fit beside the reply reserve.
    fn offer_setpoint(&mut self, report: &capp_core::StepReport) {
        let active = &mut self.plan;
        if !active.decimator.offer(report) {
            return;
        }
        let s = &mut self.status;
        let seq = s.setpoints;
        s.setpoints = s.setpoints.wrapping_add(1);
        let last_waypoint = active.scenario.targets().len().saturating_sub(1) as u8;
        let planner = &active.planner;
        let joints: Joints = Vec::from_slice(planner.joints()).unwrap_or_default();
        // The core's drive state: the tracker's, or a stepped plan's rate
        // and its change over the step (as `capp run` records them).
        let drive = planner.drive();
        let velocity: Joints = Vec::from_slice(drive.velocity()).unwrap_or_default();
        let acceleration: Joints = Vec::from_slice(drive.acceleration()).unwrap_or_default();
        let setpoint = Reply::Setpoint {
            seq,
            step: report.step,
            joints,
            time_s: active.time_s,
            waypoint: match report.phase {
                Phase::Moving { waypoint } => waypoint,
                Phase::Done(_) => last_waypoint,
            },
            velocity,
            acceleration,
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

/// Serves forever, polled: the UART read between steps ([`Node::poll`]).
/// For UARTs that hold bytes back; the boards use [`serve_queued`].
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

/// Serves forever, receive by interrupt: the boards' main loop (thread mode,
/// the lowest priority). The UART's receive interrupt fills `queue` with
/// [`rx::on_interrupt`]; this loop sends, drains the queue and takes one
/// planner step per tick ([`Node::poll_queue`], [`Node::tick`]).
pub fn serve_queued<const TXQ: usize, const Q: usize, W, T>(
    node: &mut Node<TXQ>,
    uart_tx: &mut W,
    queue: &mut Consumer<'_, u8, Q>,
    counters: &RxCounters,
    ticker: &mut T,
) -> !
where
    W: serial::Write<u8>,
    T: Ticker,
{
    loop {
        node.poll_queue(uart_tx, queue, counters);
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
        | RobotError::OutOfRange { joint, .. }
        | RobotError::NotRotation { joint }
        | RobotError::ZeroAxis { joint }
        | RobotError::MixedJoints { joint } => joint,
    };
    (ErrorCode::InvalidRobot, index)
}

fn scenario_refusal(e: ScenarioError) -> Refusal {
    match e {
        ScenarioError::Robot(e) => robot_refusal(e),
        ScenarioError::Obstacle(e) => match e {
            ObstacleError::TooMany { .. } => (ErrorCode::InvalidObstacle, NO_INDEX),
            ObstacleError::NotFinite { obstacle, .. }
            | ObstacleError::SemiAxisOutOfRange { obstacle }
            | ObstacleError::CentreOutOfRange { obstacle }
            | ObstacleError::ExponentOutOfRange { obstacle }
            | ObstacleError::SizeOutOfRange { obstacle }
            | ObstacleError::NoSuchHull { obstacle } => (ErrorCode::InvalidObstacle, obstacle),
            ObstacleError::TooManyHulls { .. } => (ErrorCode::InvalidHull, NO_INDEX),
            ObstacleError::BadHull { hull, .. } => (ErrorCode::InvalidHull, hull),
        },
        ScenarioError::Mission(e) => {
            let index = match e {
                MissionError::BadPosition { waypoint }
                | MissionError::NotARotation { waypoint }
                | MissionError::BadJointGoal { waypoint, .. } => waypoint,
                _ => NO_INDEX,
            };
            (ErrorCode::InvalidMission, index)
        }
        ScenarioError::Capsules(e) => {
            use capp_core::self_collision::CapsuleError as C;
            let index = match e {
                C::BadRadius { link } | C::BadPair { link } | C::BadSegment { link } => link,
                C::WrongLength { .. } | C::TooManyLinks { .. } | C::SegmentsNeedGeneralJoints => {
                    NO_INDEX
                }
            };
            (ErrorCode::InvalidCapsules, index)
        }
        ScenarioError::Drive { joint, .. } => (ErrorCode::InvalidDrive, joint),
        ScenarioError::DriveLength => (ErrorCode::InvalidDrive, NO_INDEX),
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
