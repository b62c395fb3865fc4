//! `capp serial`: the same problem planned by a board (or the firmware under
//! QEMU) and received over its serial line, turned into the same outputs as
//! `capp run`.
//!
//! The board streams setpoints (sequence number, step, joint vector, plan
//! time, waypoint, the joints' velocities and accelerations) chosen by the
//! problem's own setpoint rule, so the received stream is the
//! `setpoints.csv` of `capp run`: the joint vectors bit for bit (and with
//! tracked motion the drive state, `Planner::drive`, bit for bit too).
//! Everything else in a row (end-effector pose, `V`, errors, clearance) is
//! recomputed here from the received joints with the same `capp-core`
//! functions the planner uses. What a board does not send is left empty:
//! `constrained` and `halvings`; `h_s` is the plan time since the previous
//! received setpoint.
//!
//! Nothing is hidden: every gap in the sequence numbers (dropped by the board,
//! which counts its drops, or lost on the line), every damaged frame, every
//! duplicate and every setpoint that does not fit the problem is counted in
//! the [`LinkReport`].

use std::fmt;
use std::io::{Read, Write};
use std::path::PathBuf;
use std::time::{Duration, Instant};

use capp_core::avoidance::potential_gradient;
use capp_core::kinematics::{forward_kinematics, Frames};
use capp_core::target::pose_error;
use capp_core::Outcome;
use capp_link::{FrameErrors, Link, LinkError, PlanRecord, Upload};
use capp_proto::{State, Status};

use crate::plan::{Row, RunResult};
use crate::problem::{CoreScenario, Problem, MAX_JOINTS};

/// Where the board is.
#[derive(Clone, Debug, PartialEq, Eq)]
pub enum Connection {
    /// A serial port (a board's USB serial, a USB adapter) at a baud rate.
    Port {
        /// Device path, e.g. `/dev/ttyACM0`.
        path: String,
        /// Baud rate.
        baud: u32,
    },
    /// A TCP serial, e.g. QEMU's `-serial tcp:...` (see `firmware/qemu.sh`).
    Tcp(String),
    /// Boot this firmware ELF under QEMU (`mps2-an386`) and use its UART.
    Qemu(PathBuf),
}

/// What happened on the line during one plan.
#[derive(Clone, Debug, PartialEq)]
pub struct LinkReport {
    /// The board's protocol version.
    pub protocol: u8,
    /// Setpoints the board produced (sequence numbers `0..produced`).
    pub produced: u32,
    /// Distinct setpoints received intact.
    pub received: usize,
    /// Sequence numbers never received.
    pub missing: Vec<u32>,
    /// Of those, dropped by the board because its transmit queue was full.
    pub dropped_by_board: u32,
    /// Damaged frames (CRC, framing, overfull, unknown message).
    pub frame_errors: FrameErrors,
    /// Setpoints received more than once (kept once).
    pub duplicates: u32,
    /// Intact setpoints that do not fit the problem (wrong joint count,
    /// unknown waypoint, sequence number beyond `produced`): not used.
    pub rejected: u32,
    /// Timer ticks the board missed while stepping.
    pub overruns: u32,
    /// Ticks of a tracked plan whose work took longer than the control
    /// period on the board's cycle counter (0 for stepped plans).
    pub period_overruns: u32,
    /// The board's deepest stack use, bytes (0: not measured).
    pub stack_peak: u32,
    /// Received bytes the board's receive queue could not hold (since boot).
    pub rx_overflows: u32,
    /// Core clock cycles of one tick's work on the board: fewest, mean, most
    /// (0: no cycle counter).
    pub step_cycles: [u32; 3],
}

impl LinkReport {
    /// Whether the stream arrived whole: nothing missing, damaged or rejected.
    pub fn whole(&self) -> bool {
        self.missing.is_empty() && self.frame_errors.total() == 0 && self.rejected == 0
    }

    /// Gaps the board's drop counter does not explain: lost on the line.
    pub fn lost_on_line(&self) -> u32 {
        (self.missing.len() as u32).saturating_sub(self.dropped_by_board)
    }

    /// A warning line when a tracked tick overran its control period on the
    /// board.
    pub fn period_warning(&self) -> Option<String> {
        (self.period_overruns > 0).then(|| {
            format!(
                "warning: {} tracked ticks took longer than the control period on the board (it could not keep the drive's period in real time)",
                self.period_overruns
            )
        })
    }
}

impl fmt::Display for LinkReport {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        let e = &self.frame_errors;
        writeln!(
            f,
            "board stream:      {} of {} setpoints received (protocol {}), {}",
            self.received,
            self.produced,
            self.protocol,
            if self.whole() { "whole" } else { "INCOMPLETE" }
        )?;
        writeln!(
            f,
            "missing:           {} ({} dropped by the board, {} lost on the line){}",
            self.missing.len(),
            self.dropped_by_board,
            self.lost_on_line(),
            describe_seqs(&self.missing)
        )?;
        writeln!(
            f,
            "damaged frames:    {} (CRC {}, framing {}, overfull {}, unknown {}); duplicates {}; rejected {}",
            e.total(),
            e.crc,
            e.framing,
            e.overfull,
            e.message,
            self.duplicates,
            self.rejected
        )?;
        writeln!(
            f,
            "board:             {} timer overruns, {} ticks over the control period, peak stack {} bytes, {} receive queue overflows",
            self.overruns, self.period_overruns, self.stack_peak, self.rx_overflows
        )?;
        if let Some(warning) = self.period_warning() {
            writeln!(f, "{warning}")?;
        }
        let [min, mean, max] = self.step_cycles;
        writeln!(
            f,
            "board cycles/step: min {min}, mean {mean}, max {max} (core clock; emulated time under QEMU)"
        )
    }
}

/// The first few sequence numbers of a list, for a message.
fn describe_seqs(seqs: &[u32]) -> String {
    if seqs.is_empty() {
        return String::new();
    }
    let shown: Vec<String> = seqs.iter().take(8).map(u32::to_string).collect();
    let more = if seqs.len() > 8 { ", ..." } else { "" };
    format!(": seq {}{more}", shown.join(", "))
}

/// Why a plan on a board failed.
#[derive(Debug)]
pub enum SerialError {
    /// The link failed (I/O, timeout, a refused command).
    Link(LinkError),
    /// The board speaks another protocol version.
    Version {
        /// The board's.
        board: u8,
        /// Ours.
        host: u8,
    },
    /// The plan was stopped (by another host) before it ended.
    Stopped,
}

impl fmt::Display for SerialError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            SerialError::Link(e) => write!(f, "serial link: {e}"),
            SerialError::Version { board, host } => write!(
                f,
                "the board speaks protocol version {board}, this host {host}: flash matching firmware"
            ),
            SerialError::Stopped => write!(f, "the plan was stopped before it ended"),
        }
    }
}

impl std::error::Error for SerialError {}

impl From<LinkError> for SerialError {
    fn from(e: LinkError) -> Self {
        SerialError::Link(e)
    }
}

/// Uploads `problem` (validated on the host as `scenario`), runs it on the
/// board behind `link` with the problem's setpoint rule, and receives the
/// whole stream; `idle` is how long the line may stay silent (status polls
/// included) before giving up; `watch` sees every status the board sends.
pub fn plan_on_board<T: Read + Write>(
    link: &mut Link<T>,
    problem: &Problem,
    scenario: &CoreScenario,
    idle: Duration,
    watch: impl FnMut(&Status),
) -> Result<(RunResult, LinkReport), SerialError> {
    let protocol = link.ping(0x0CA9_9000)?;
    if protocol != capp_proto::VERSION {
        return Err(SerialError::Version {
            board: protocol,
            host: capp_proto::VERSION,
        });
    }
    let hulls: Vec<&[[f32; 3]]> = problem.hulls.iter().map(Vec::as_slice).collect();
    link.upload(&Upload {
        // DH rows or general (URDF) joints, and the tool: the board's
        // robot is the host's (`Robot::new_with_tool`) to the bit.
        joints: &problem.joints,
        tool: problem.tool,
        capsule_radius: scenario.capsules().radii(),
        capsule_rows: scenario.capsules().checked_rows(),
        // As the host's scenario took them (`Problem::scenario`).
        capsule_segments: if scenario.capsules().is_on() {
            &problem.links.segments
        } else {
            &[]
        },
        // The defaults from the rates need no frames; other limits are
        // the host's to the bit.
        drive: if problem.default_drive_limits() {
            &[]
        } else {
            scenario.drive_limits()
        },
        obstacles: &problem.obstacles,
        hulls: &hulls,
        waypoints: &problem.waypoints,
        joint_goals: &problem.joint_goals,
        settings: problem.settings,
        start: &problem.start,
    })?;
    let started = Instant::now();
    link.run(problem.setpoints)?;
    let record = link.receive_plan_watching(idle, watch)?;
    let wall_time = started.elapsed();
    let outcome = match (record.status.state, record.status.outcome) {
        (State::Done, Some(o)) => match o {
            capp_proto::Outcome::Reached => Outcome::Reached,
            capp_proto::Outcome::Stalled => Outcome::Stalled,
            capp_proto::Outcome::Capped => Outcome::Capped,
        },
        _ => return Err(SerialError::Stopped),
    };
    let (rows, duplicates, rejected) = rows_from_stream(scenario, &record);
    let report = LinkReport {
        protocol,
        produced: record.status.setpoints,
        received: rows.len(),
        missing: record.missing.clone(),
        dropped_by_board: record.status.dropped,
        frame_errors: record.frame_errors,
        duplicates,
        rejected,
        overruns: record.status.overruns,
        period_overruns: record.status.period_overruns,
        stack_peak: record.status.stack_peak,
        rx_overflows: record.status.rx_overflows,
        step_cycles: [
            record.status.step_cycles_min,
            record.status.step_cycles_mean,
            record.status.step_cycles_max,
        ],
    };
    Ok((
        RunResult {
            rows,
            outcome,
            wall_time,
        },
        report,
    ))
}

/// The received setpoints as rows, in sequence order, each once; with the
/// number of duplicates and of setpoints that do not fit the problem.
fn rows_from_stream(scenario: &CoreScenario, record: &PlanRecord) -> (Vec<Row>, u32, u32) {
    let n = scenario.robot().len();
    let targets = scenario.targets();
    let mut received: Vec<&capp_link::Setpoint> = Vec::new();
    let mut rejected = 0;
    for s in &record.setpoints {
        let fits = s.joints.len() == n
            && s.velocity.len() == n
            && s.acceleration.len() == n
            && (s.waypoint as usize) < targets.len()
            && s.seq < record.status.setpoints;
        if fits {
            received.push(s);
        } else {
            rejected += 1;
        }
    }
    received.sort_by_key(|s| s.seq);
    let before = received.len();
    received.dedup_by_key(|s| s.seq);
    let duplicates = (before - received.len()) as u32;
    let mut previous_time = 0.0f32;
    let mut previous_step = 0u32;
    let tracked = scenario.settings().motion == capp_core::Motion::Tracked;
    let rows = received
        .into_iter()
        .map(|s| {
            // Tracked: a whole number of periods since the last setpoint.
            let h = if tracked {
                s.step.saturating_sub(previous_step) as f32 * scenario.settings().time_step_s
            } else {
                s.time_s - previous_time
            };
            previous_time = s.time_s;
            previous_step = s.step;
            derived_row(scenario, s, h)
        })
        .collect();
    (rows, duplicates, rejected)
}

/// A row from a received setpoint: pose, errors and clearance recomputed with
/// the planner's own functions for the setpoint's waypoint.
fn derived_row(scenario: &CoreScenario, s: &capp_link::Setpoint, h: f32) -> Row {
    let robot = scenario.robot();
    let settings = scenario.settings();
    let mut frames = Frames::<MAX_JOINTS>::default();
    forward_kinematics(robot, &s.joints, &mut frames);
    let target = &scenario.targets()[s.waypoint as usize];
    let error = pose_error(&frames, target, settings.law.orientation_scale);
    let mut mu = [0.0f32; MAX_JOINTS];
    let mut distance = [0.0f32; MAX_JOINTS];
    let field = potential_gradient(
        robot,
        &frames,
        scenario.world(),
        &settings.avoidance,
        &mut mu[..s.joints.len()],
        &mut distance[..s.joints.len()],
        None,
    );
    let p = frames.end_position();
    let r = frames.end_rotation();
    Row {
        step: s.step,
        h,
        q: s.joints.clone(),
        velocity: s.velocity.clone(),
        acceleration: s.acceleration.clone(),
        position: [p.x, p.y, p.z],
        rotation: [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]),
        v: error.v,
        position_error: error.position,
        orientation_error: error.orientation,
        clearance: field.clearance,
        waypoint: s.waypoint,
        constrained: None,
        halvings: None,
        escape: None,
        setpoint: true,
    }
}
