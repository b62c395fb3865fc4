//! One planner step cut into its phases, each callable on its own, so each can
//! be timed (host) or counted (Cortex-M4F) alone. The calls are the ones
//! [`capp_core::Planner::step`] makes, on the state of a warmed-up planner:
//!
//! | phase | capp-core calls |
//! |---|---|
//! | kinematics | `forward_kinematics` (one pass, eqs. 5-6) |
//! | control law | `pose_error`, then the scenario's law: `lyapunov_terms`, `weighted_rate`, `descent_rate` (first-order laws, eqs. 11-18), or `damped_rate` (damped least squares, its eq. 24 projection included) |
//! | obstacles | `potential_gradient` (eqs. 20, 25-26) |
//! | link pairs | `self_collision::field::link_pairs` (the checked pairs' broad and narrow phase, potential, gradient and rooms) |
//! | projection and integration | first-order laws: `strength`, `project`, `limit_rates` (eq. 24), the step bounds (`end_twist`, `column_sizes`); every law: conservative advancement (`step_size::advancement`) and the clamped Euler update |
//!
//! A step that takes its first step size (no halving) runs each phase once
//! (the kinematics and obstacles on the candidate configuration); what the
//! step costs beyond their sum is the state machine and copying.

use capp_core::avoidance::{potential_gradient, ObstacleField};
use capp_core::control::damped::{damped_rate, DampedWorkspace};
use capp_core::control::{descent_rate, lyapunov_terms, weighted_rate, LawInput, LawKind};
use capp_core::kinematics::{column_sizes, end_twist, forward_kinematics, Frames};
use capp_core::math::dot_slice;
use capp_core::projection::{limit_rates, project, strength};
use capp_core::self_collision::field::link_pairs;
use capp_core::step_size::advancement;
use capp_core::target::{pose_error, PoseError, Target};
use capp_core::{Planner, Scenario};

/// Everything the phases read and write, copied from a planner.
#[derive(Clone, Debug)]
pub struct PhaseBench<const N: usize> {
    n: usize,
    q: [f32; N],
    q_next: [f32; N],
    target: Target,
    frames: Frames<N>,
    error: PoseError,
    terms: [[f32; N]; 4],
    drive: [f32; N],
    /// The law's rate before projection (the input of every projection run).
    law_rate: [f32; N],
    rate: [f32; N],
    gain: [f32; N],
    columns: [f32; N],
    locked: [bool; N],
    mu: [f32; N],
    distance_sq: [f32; N],
    damped: DampedWorkspace<N>,
    field: ObstacleField,
}

impl<const N: usize> PhaseBench<N> {
    /// The phases at `planner`'s configuration, for its first waypoint.
    pub fn new<const M: usize, const W: usize>(
        scenario: &Scenario<N, M, W>,
        planner: &Planner<N>,
    ) -> Self {
        let n = planner.joints().len();
        let mut q = [0.0; N];
        q[..n].copy_from_slice(planner.joints());
        let mut bench = PhaseBench {
            n,
            q,
            q_next: q,
            target: scenario.targets()[0],
            frames: planner.frames().clone(),
            error: PoseError::default(),
            terms: [[0.0; N]; 4],
            drive: [0.0; N],
            law_rate: [0.0; N],
            rate: [0.0; N],
            gain: [0.0; N],
            columns: [0.0; N],
            locked: [false; N],
            mu: [0.0; N],
            distance_sq: [0.0; N],
            damped: DampedWorkspace::default(),
            field: ObstacleField::default(),
        };
        bench.kinematics(scenario);
        bench.obstacles(scenario);
        bench.link_pairs(scenario);
        bench.control_law(scenario);
        bench.law_rate = bench.rate;
        bench
    }

    /// The checked link pairs at the configuration (after [`Self::obstacles`],
    /// as a step runs them). Returns their potential.
    pub fn link_pairs<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> f32 {
        let n = self.n;
        link_pairs(
            scenario.robot(),
            &self.frames,
            scenario.capsules(),
            &mut self.mu[..n],
            &mut self.distance_sq[..n],
            self.field.nearest.map(|h| h.link),
            0.0,
            None,
        )
        .potential
    }

    /// Forward kinematics at the configuration. Returns the end effector's x.
    pub fn kinematics<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> f32 {
        forward_kinematics(scenario.robot(), &self.q[..self.n], &mut self.frames);
        self.frames.end_position().x
    }

    /// Pose error and the scenario's law: for the first-order laws the four
    /// `J_i^T e_i` terms, the weighted rate and the descent rate (returned);
    /// for damped least squares its rate, projection included (returns the
    /// time the step needs at the rate limits).
    pub fn control_law<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> f32 {
        let robot = scenario.robot();
        let settings = scenario.settings();
        let law = &settings.law;
        let n = self.n;
        self.error = pose_error(&self.frames, &self.target, law.orientation_scale);
        if law.kind == LawKind::DampedLeastSquares {
            let input = LawInput {
                robot,
                frames: &self.frames,
                q: &self.q[..n],
                error: &self.error,
                mu: &self.mu[..n],
                clearance: self.field.clearance.map(|c| c.value),
                law,
                engage_clearance: settings.avoidance.engage_clearance,
                step: settings.step_rule(),
                error_step: 0.0,
            };
            return damped_rate(&input, &mut self.damped, &mut self.rate[..n]).time_step_s;
        }
        lyapunov_terms(robot, &self.frames, &self.error, &mut self.terms);
        weighted_rate(
            robot,
            &self.q[..n],
            &self.error,
            &self.terms,
            law,
            &mut self.drive,
            &mut self.rate,
            &mut self.gain,
        );
        descent_rate(&self.terms, law, &self.rate[..n])
    }

    /// The potential and its joint-space gradient `mu`. Returns the potential.
    pub fn obstacles<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> f32 {
        self.field = potential_gradient(
            scenario.robot(),
            &self.frames,
            scenario.world(),
            &scenario.settings().avoidance,
            &mut self.mu,
            &mut self.distance_sq,
            None,
        );
        self.field.potential
    }

    /// Projection, rate limits, the step-size bounds (first-order laws),
    /// conservative advancement and the clamped Euler update, from the law's
    /// rate. Returns the step size, seconds.
    pub fn projection_integration<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> f32 {
        let robot = scenario.robot();
        let settings = scenario.settings();
        let n = self.n;
        self.rate = self.law_rate;
        let h = if settings.law.kind == LawKind::DampedLeastSquares {
            settings.time_step_s
        } else {
            self.first_order_bounds(scenario)
        };
        let h = advancement(
            robot,
            &self.frames,
            &self.distance_sq[..n],
            self.field.nearest.as_ref(),
            &self.rate[..n],
            h,
            settings.avoidance.advance_fraction,
        );
        for (j, joint) in robot.joints().iter().enumerate() {
            self.q_next[j] = joint.clamp(self.q[j] + h * self.rate[j]);
        }
        h
    }

    /// The first-order laws' projection, rate limits and step bounds.
    fn first_order_bounds<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
    ) -> f32 {
        let robot = scenario.robot();
        let settings = scenario.settings();
        let n = self.n;
        let engage = strength(
            self.field.clearance.map(|c| c.value),
            settings.avoidance.engage_clearance,
        );
        project(
            robot,
            &self.q[..n],
            &self.mu[..n],
            engage,
            &mut self.rate[..n],
            &mut self.locked[..n],
        );
        limit_rates(robot, &mut self.rate[..n]);
        let mut h = settings.time_step_s;
        let descent = descent_rate(&self.terms, &settings.law, &self.rate[..n]);
        if descent > 0.0 {
            let (v, w) = end_twist(robot, &self.frames, &self.rate[..n]);
            let lambda = settings.law.orientation_scale;
            let speed_sq = v.dot(&v) + 2.0 * lambda * lambda * w.dot(&w);
            if speed_sq > 0.0 {
                h = h.min(0.5 * descent / speed_sq);
            }
        }
        column_sizes(
            robot,
            &self.frames,
            settings.law.orientation_scale,
            &mut self.columns[..n],
        );
        let stiffness = dot_slice(&self.gain[..n], &self.columns[..n]);
        if stiffness > 0.0 {
            h = h.min(1.0 / stiffness);
        }
        h
    }

    /// Avoidance point / obstacle pairs within influence at this configuration.
    pub fn active_pairs(&self) -> u16 {
        self.field.active_pairs
    }
}
