//! Running the planner on a [`Problem`] and recording every step.
//!
//! Row 0 is the start configuration; row `k` the configuration after step `k`.
//! The setpoint decimation is the core's own ([`capp_core::setpoint::Decimator`]),
//! so the host and the firmware pick the same setpoints.
//!
//! Each row carries every joint's velocity and acceleration, what a drive
//! takes as feed-forward with the position. With `motion = "tracked"` they
//! are the tracker's state after the tick ([`capp_core::Planner::drive`]),
//! which equals the backward differences of the positions over the control
//! period (rest before row 0). With stepped motion the velocity is the rate
//! of the step that led to the row ([`capp_core::Planner::rates`]; 0 for a
//! step not taken, `h = 0`) and the acceleration its change over the row's
//! `h` (0 when `h` is 0, and at row 0).

use std::time::{Duration, Instant};

use capp_core::avoidance::Clearance;
use capp_core::escape::EscapeState;
use capp_core::setpoint::Decimator;
use capp_core::{Outcome, Phase, StepReport};

use crate::problem::{CorePlanner, CoreScenario, LoadError, Problem};

/// One recorded configuration.
#[derive(Clone, Debug, PartialEq)]
pub struct Row {
    /// Step number (0 = start).
    pub step: u32,
    /// Integration step used to get here, seconds (0 at the start and for refused steps).
    pub h: f32,
    /// Joint values (radians or length units).
    pub q: Vec<f32>,
    /// Joint velocities, per second (module docs: the tracker's, or the
    /// step's rate).
    pub velocity: Vec<f32>,
    /// Joint accelerations, per second squared (module docs).
    pub acceleration: Vec<f32>,
    /// End-effector position.
    pub position: [f32; 3],
    /// End-effector orientation, rows of the rotation matrix.
    pub rotation: [[f32; 3]; 3],
    /// `V` of eq. 12 for the active waypoint.
    pub v: f32,
    /// Position error, length units.
    pub position_error: f32,
    /// Orientation error (root sum square of the column errors).
    pub orientation_error: f32,
    /// Closest avoidance point / obstacle pair within influence.
    pub clearance: Option<Clearance>,
    /// Active waypoint, 0-based (the last one once the run is over).
    pub waypoint: u8,
    /// Whether the obstacle projection changed the rate (`None`: not known,
    /// e.g. a setpoint received from a board).
    pub constrained: Option<bool>,
    /// Step halvings (`None`: not known).
    pub halvings: Option<u8>,
    /// What the dead-end escape was doing (`None`: not known).
    pub escape: Option<EscapeState>,
    /// Whether this row is in the decimated setpoint stream.
    pub setpoint: bool,
}

impl Row {
    /// A row of step `step` (reached by a step of `h` seconds) at the joint
    /// values `q`, at rest, with nothing else computed: the end effector's
    /// pose left at the origin, unturned, no error, no clearance, no step
    /// report. What a test or a tool that has only configurations builds
    /// its rows from.
    pub fn with_joints(step: u32, h: f32, q: Vec<f32>) -> Row {
        let n = q.len();
        Row {
            step,
            h,
            q,
            velocity: vec![0.0; n],
            acceleration: vec![0.0; n],
            position: [0.0; 3],
            rotation: [[1.0, 0.0, 0.0], [0.0, 1.0, 0.0], [0.0, 0.0, 1.0]],
            v: 0.0,
            position_error: 0.0,
            orientation_error: 0.0,
            clearance: None,
            waypoint: 0,
            constrained: None,
            halvings: None,
            escape: None,
            setpoint: true,
        }
    }
}

/// A finished plan.
#[derive(Clone, Debug)]
pub struct RunResult {
    /// Every configuration, start first.
    pub rows: Vec<Row>,
    /// How the run ended.
    pub outcome: Outcome,
    /// Wall-clock time of the planning loop.
    pub wall_time: Duration,
}

impl RunResult {
    /// Steps taken.
    pub fn steps(&self) -> u32 {
        self.rows.last().map_or(0, |r| r.step)
    }

    /// The rows of the setpoint stream.
    pub fn setpoints(&self) -> impl Iterator<Item = &Row> {
        self.rows.iter().filter(|r| r.setpoint)
    }
}

/// Every joint's velocity and acceleration after a step: the core's
/// ([`capp_core::Planner::drive`]: the tracker's state, or for a stepped
/// plan the step's rate and its change over the step), as the board streams
/// them.
fn drive(planner: &CorePlanner) -> (Vec<f32>, Vec<f32>) {
    let d = planner.drive();
    (d.velocity().to_vec(), d.acceleration().to_vec())
}

fn row(
    planner: &CorePlanner,
    report: &StepReport,
    waypoints: usize,
    setpoint: bool,
    (velocity, acceleration): (Vec<f32>, Vec<f32>),
) -> Row {
    let frames = planner.frames();
    let p = frames.end_position();
    let r = frames.end_rotation();
    Row {
        step: report.step,
        h: report.time_step_s,
        q: planner.joints().to_vec(),
        velocity,
        acceleration,
        position: [p.x, p.y, p.z],
        rotation: [0, 1, 2].map(|i| [r[(i, 0)], r[(i, 1)], r[(i, 2)]]),
        v: report.v,
        position_error: report.position_error,
        orientation_error: report.orientation_error,
        clearance: report.clearance,
        waypoint: match report.phase {
            Phase::Moving { waypoint } => waypoint,
            Phase::Done(_) => (waypoints - 1) as u8,
        },
        constrained: Some(report.constrained),
        halvings: Some(report.halvings),
        escape: Some(report.escape),
        setpoint,
    }
}

/// Plans `problem` (whose validated scenario is `scenario`), calling
/// `progress` after every step.
pub fn run(
    problem: &Problem,
    scenario: &CoreScenario,
    mut progress: impl FnMut(&StepReport),
) -> Result<RunResult, LoadError> {
    let started = Instant::now();
    let mut planner = CorePlanner::new(scenario, &problem.start)
        .map_err(|e| LoadError::new(&problem.source, problem.lines.start, e.to_string()))?;
    let mut decimator = Decimator::new(problem.setpoints);
    let waypoints = problem.waypoints.len();
    let first = *planner.last_report();
    let at_start = drive(&planner);
    let mut rows = vec![row(
        &planner,
        &first,
        waypoints,
        decimator.offer(&first),
        at_start,
    )];
    let outcome = planner
        .run(scenario, |planner, report| {
            let setpoint = decimator.offer(report);
            let state = drive(planner);
            rows.push(row(planner, report, waypoints, setpoint, state));
            progress(report);
        })
        .map_err(|e| LoadError::new(&problem.source, None, format!("planner: {e}")))?;
    Ok(RunResult {
        rows,
        outcome,
        wall_time: started.elapsed(),
    })
}
