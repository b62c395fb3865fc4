//! Starting a plan, in place: the start's checks, then every buffer of the
//! planner to its value at the start (a board keeps its planner in a
//! `static` and restarts it; no planner-sized value on the stack).

use super::progress::Progress;
use super::{Outcome, Phase, Planner, StartError, StepReport};
use crate::avoidance::Clearance;
use crate::scenario::Scenario;
use crate::tracker::DriveState;

impl<const N: usize> Planner<N> {
    /// [`Planner::new`] in place: the same checks and the same plan (to the
    /// bit), without a planner-sized value on the stack. On error `self` is
    /// left as [`Planner::empty`].
    pub fn restart<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        start: &[f32],
    ) -> Result<(), StartError> {
        let result = self.begin(scenario, start);
        if result.is_err() {
            self.clear();
        }
        result
    }

    /// Makes this planner [`Planner::empty`], in place.
    pub fn clear(&mut self) {
        self.reset(&[]);
    }

    fn begin<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        start: &[f32],
    ) -> Result<(), StartError> {
        let robot = scenario.robot();
        let n = robot.len();
        if start.len() != n {
            return Err(StartError::WrongLength {
                given: start.len(),
                joints: n,
            });
        }
        if let Some(joint) = start.iter().position(|x| !x.is_finite()) {
            return Err(StartError::NotFinite { joint: joint as u8 });
        }
        if let Some(joint) = robot.first_outside_limits(start) {
            return Err(StartError::OutsideLimits { joint: joint as u8 });
        }
        self.reset(start);
        self.escape.reset(scenario.settings().escape.seed, start);
        // Scenario::new refuses a mission without waypoints, so this never fails.
        let Some(&target) = scenario.targets().first() else {
            return Err(StartError::ScenarioMismatch);
        };
        let n = self.n.min(N);
        self.evals
            .now_mut()
            .evaluate(scenario, &self.q[..n], &target);
        if !self.evals.now().links.clear {
            let links = self.evals.now().links.closest.map_or([0, 0], |p| p.links);
            return Err(StartError::SelfCollision { links });
        }
        if !self.evals.now().field.clear {
            let c = self.evals.now().field.clearance.unwrap_or(Clearance {
                value: 0.0,
                point: 0,
                obstacle: 0,
            });
            return Err(StartError::InObstacle {
                point: c.point,
                obstacle: c.obstacle,
            });
        }
        self.progress.restart(self.evals.now().error.v, 0);
        self.last = self.report(0.0, false, 0);
        Ok(())
    }

    /// Every field to its value at the start of a plan from `start` (at most
    /// `N` values; none: the empty planner), in place.
    pub(super) fn reset(&mut self, start: &[f32]) {
        // Every field is named: a field added to `Planner` fails to compile here.
        let Planner {
            n,
            q,
            evals,
            q_next,
            rate,
            law,
            escape,
            step,
            phase,
            error_step,
            progress,
            last,
            drive,
            velocity_target,
            share,
            ending,
        } = self;
        let len = start.len().min(N);
        *n = len;
        q.fill(0.0);
        q[..len].copy_from_slice(&start[..len]);
        evals.reset();
        *q_next = *q;
        rate.fill(0.0);
        law.clear();
        escape.reset(0, start);
        *step = 0;
        *phase = if len == 0 {
            Phase::Done(Outcome::Stalled)
        } else {
            Phase::Moving { waypoint: 0 }
        };
        *error_step = 0.0;
        *progress = Progress::new();
        *last = StepReport::at_start(*phase);
        *drive = DriveState::at_rest(len);
        velocity_target.fill(0.0);
        *share = 1.0;
        *ending = None;
    }
}
