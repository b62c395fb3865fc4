//! The escape's search ([`crate::tree`]), a bounded slice per planner step:
//! units of work (a descent's law step, a trunk step, a tree extension)
//! until [`SEARCH_EVALUATIONS`] evaluations of the arm are spent. Every
//! unit works in imagination: on `next` and `q_next`, never on the arm's
//! state.

use super::{Planner, CONTACT_FLOOR};
use crate::control::damped::damped_rate;
use crate::control::joint_space::gap;
use crate::control::{time_at_limits, LawKind, Target};
use crate::math::all_finite;
use crate::projection::Guard;
use crate::scenario::Scenario;
use crate::step_size::advancement;
use crate::tree::{
    Stage, DESCENTS, DESCENT_STEPS, EDGE_CHECKS, EDGE_STEPS, EXTENSIONS, GOAL_BIAS, GOAL_NEAR,
    SEARCH_EVALUATIONS, SHORTCUT_CHECKS, TREE_NODES, TRUNK_STEPS,
};

/// What a slice of the search came to.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub(super) enum Slice {
    /// Not done yet.
    Working,
    /// A path ([`crate::tree::Search::path`]).
    Found,
    /// The budget is spent, no path.
    Failed,
}

impl<const N: usize> Planner<N> {
    /// One planner step's share of the search.
    pub(super) fn search_slice<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
    ) -> Slice {
        let mut spent = 0u16;
        while spent < SEARCH_EVALUATIONS {
            let slice = match self.escape.search_mut().stage {
                Stage::Goal => self.goal_unit(scenario, target, &mut spent),
                Stage::Trunk => self.trunk_unit(scenario, target, &mut spent),
                Stage::Grow => self.grow_unit(scenario, target, &mut spent),
                Stage::Shortcut => self.shortcut_unit(scenario, target, &mut spent),
            };
            if slice != Slice::Working {
                return slice;
            }
        }
        Slice::Working
    }

    /// `q_next` drawn uniformly within the joint limits.
    fn draw_configuration(&mut self, n: usize, robot: &crate::robot::Robot<N>) {
        for (j, joint) in robot.joints().iter().enumerate().take(n) {
            let u = 0.5 * (self.escape.uniform() + 1.0);
            self.q_next[j] = joint.min + u * (joint.max - joint.min);
        }
    }

    /// A descent's next unit: start one from a random configuration, or
    /// take its next law step. Keeps `next` the evaluation of the probe
    /// while a descent is under way.
    fn goal_unit<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        spent: &mut u16,
    ) -> Slice {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N);
        let edge_s = EDGE_STEPS * settings.time_step_s;
        if !self.escape.search_mut().probing {
            if self.escape.search_mut().descents >= DESCENTS {
                return Slice::Failed;
            }
            self.escape.search_mut().descents += 1;
            self.draw_configuration(n, robot);
            *spent += 1;
            if self.imagine_accept(scenario, target, f32::INFINITY) {
                let search = self.escape.search_mut();
                search.probe = self.q_next;
                search.probing = true;
                search.probe_steps = 0;
            }
            return Slice::Working;
        }
        let near = GOAL_NEAR * settings.position_tolerance;
        let v = self.evals.next().error.v;
        let search = self.escape.search_mut();
        if v <= 0.5 * near * near {
            search.goal = search.probe;
            search.stage = Stage::Trunk;
            return Slice::Working;
        }
        if search.probe_steps >= DESCENT_STEPS {
            search.probing = false;
            return Slice::Working;
        }
        search.probe_steps += 1;
        let probe = search.probe;
        let c = self.evals.next().closest();
        *spent += 1;
        let taken = self.imagine_law_step(scenario, &probe[..n], edge_s) > 0.0
            && self.imagine_accept(scenario, target, c)
            && self.evals.next().error.v < v;
        let search = self.escape.search_mut();
        if taken {
            search.probe = self.q_next;
        } else {
            search.probing = false;
        }
        Slice::Working
    }

    /// The trunk's next step away from the surface the dead end is on.
    fn trunk_unit<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        spent: &mut u16,
    ) -> Slice {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N);
        let edge_s = EDGE_STEPS * settings.time_step_s;
        let search = self.escape.search_mut();
        if search.trunk_steps >= TRUNK_STEPS {
            search.stage = Stage::Grow;
            return Slice::Working;
        }
        search.trunk_steps += 1;
        let base = search.base as usize;
        let qa = *search.tree.node(base);
        self.evals.next_mut().evaluate(scenario, &qa[..n], target);
        *spent += 2;
        let c_a = self.evals.next().closest();
        let mut leave = c_a >= settings.avoidance.engage_clearance;
        if !leave {
            // Down the potential in the metric of the rate limits.
            for (j, joint) in robot.joints().iter().enumerate().take(n) {
                self.rate[j] = -self.evals.next().mu[j] * joint.max_rate * joint.max_rate;
            }
            let t = time_at_limits(robot, &self.rate[..n]);
            leave = !(t > 0.0 && t.is_finite());
            if !leave {
                self.rate[..n].iter_mut().for_each(|r| *r /= t);
                leave = self.imagine_move(scenario, &qa[..n], edge_s) <= 0.0
                    || !self.imagine_accept(scenario, target, c_a);
            }
        }
        let v = self.evals.next().error.v;
        let search = self.escape.search_mut();
        if leave {
            search.stage = Stage::Grow;
            return Slice::Working;
        }
        match search.tree.push(&self.q_next[..n], base, v) {
            Some(i) => search.base = i as u8,
            None => search.stage = Stage::Grow,
        }
        Slice::Working
    }

    /// One extension of the tree: toward the goal configuration (carrying
    /// on a greedy connection) or toward a random configuration.
    fn grow_unit<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        spent: &mut u16,
    ) -> Slice {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N);
        let edge_s = EDGE_STEPS * settings.time_step_s;
        let search = self.escape.search_mut();
        if search.extensions >= EXTENSIONS || search.tree.is_full() {
            return Slice::Failed;
        }
        search.extensions += 1;
        let goal = search.goal;
        let a = match search.connecting {
            Some(a) => {
                self.q_next = goal;
                a as usize
            }
            None => {
                if self.escape.uniform() < 2.0 * GOAL_BIAS - 1.0 {
                    self.q_next = goal;
                    self.escape.search_mut().connecting = Some(0);
                } else {
                    self.draw_configuration(n, robot);
                }
                self.escape
                    .search_mut()
                    .tree
                    .nearest(robot, &self.q_next[..n])
            }
        };
        let qa = *self.escape.search_mut().tree.node(a);
        let sample = self.q_next;
        for j in 0..n {
            self.rate[j] = (sample[j] - qa[j]) / edge_s;
        }
        let t = time_at_limits(robot, &self.rate[..n]);
        if t > 1.0 {
            self.rate[..n].iter_mut().for_each(|r| *r /= t);
        }
        // The edge, checked at configurations along it: a plan, not a
        // motion (the walk along it checks each of its steps).
        self.evals.next_mut().evaluate(scenario, &qa[..n], target);
        *spent += 1;
        let mut c_from = self.evals.next().closest();
        let mut clear = all_finite(&self.rate[..n]);
        for k in 1..=EDGE_CHECKS {
            if !clear {
                break;
            }
            let s = edge_s * k as f32 / EDGE_CHECKS as f32;
            for (j, joint) in robot.joints().iter().enumerate().take(n) {
                self.q_next[j] = joint.clamp(qa[j] + s * self.rate[j]);
            }
            *spent += 1;
            clear = self.imagine_accept(scenario, target, c_from);
            c_from = self.evals.next().closest();
        }
        let search = self.escape.search_mut();
        if !clear {
            search.connecting = None;
            return Slice::Working;
        }
        let Some(i) = search
            .tree
            .push(&self.q_next[..n], a, self.evals.next().error.v)
        else {
            return Slice::Failed;
        };
        if search.connecting.is_some() {
            search.connecting = Some(i as u8);
        }
        if gap(robot, &self.q_next[..n], &goal[..n]) <= edge_s {
            search.found(i);
        }
        Slice::Working
    }

    /// One configuration of the shortcut being checked: the segment from
    /// path position `from` to `to`, at the spacing of an edge's checks.
    fn shortcut_unit<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        spent: &mut u16,
    ) -> Slice {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N);
        let spacing = EDGE_STEPS * settings.time_step_s / EDGE_CHECKS as f32;
        let search = self.escape.search_mut();
        let len = search.path_len as usize;
        let (from, to) = (search.from as usize, search.to as usize);
        if from + 1 >= len {
            search.path_len = search.out;
            return Slice::Found;
        }
        let node = |s: &crate::tree::Search<N>, k: usize| {
            *s.tree.node(s.path.get(k).copied().unwrap_or(0) as usize)
        };
        let (a, b) = (node(search, from), node(search, to));
        let checks = libm::ceilf(gap(robot, &a[..n], &b[..n]) / spacing) as u16;
        // A tree edge is already checked; a spent budget keeps the rest.
        let keep = to == from + 1 || search.shortcut_checks >= SHORTCUT_CHECKS;
        let mut accept = keep;
        if !keep {
            let k = search.check;
            search.shortcut_checks += 1;
            let s = k as f32 / checks.max(1) as f32;
            for j in 0..n {
                self.q_next[j] = a[j] + s * (b[j] - a[j]);
            }
            *spent += 1;
            let clear = self.imagine_accept(scenario, target, f32::INFINITY);
            let search = self.escape.search_mut();
            if !clear {
                search.to -= 1;
                search.check = 1;
                return Slice::Working;
            }
            if k < checks {
                search.check = k + 1;
                return Slice::Working;
            }
            accept = true;
        }
        let search = self.escape.search_mut();
        if accept {
            let (out, next) = (search.out as usize, if keep { from + 1 } else { to });
            if let (Some(&v), true) = (search.path.get(next), out < TREE_NODES) {
                search.path[out] = v;
            }
            search.out += 1;
            search.from = next as u8;
            search.to = (len - 1) as u8;
            search.check = 1;
        }
        Slice::Working
    }

    /// One law step in imagination from `qa` (evaluated into `next`): the
    /// damped law's step of at most `edge_s` at the rate limits, cut by
    /// conservative advancement, into `q_next`. Returns the step (seconds),
    /// 0 when none can be taken.
    fn imagine_law_step<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        qa: &[f32],
        edge_s: f32,
    ) -> f32 {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N).min(qa.len());
        // The search's descents are the damped law's only: under a
        // first-order law no imagined step is taken (and no goal found).
        if settings.law.kind != LawKind::DampedLeastSquares {
            return 0.0;
        }
        let ws = &mut self.law.damped;
        let guard = Guard::at(
            &self.evals.next().mu[..n],
            self.evals.next().field.clearance.map(|c| c.value),
            settings.avoidance.engage_clearance,
            CONTACT_FLOOR,
        );
        damped_rate(
            robot,
            &self.evals.next().frames,
            &qa[..n],
            &self.evals.next().error,
            &guard,
            &settings.law,
            edge_s,
            ws,
            &mut self.rate[..n],
        );
        self.imagine_move(scenario, qa, edge_s)
    }

    /// `q_next = qa + h rate`, `h <= edge_s` cut by conservative advancement
    /// from `qa` (evaluated into `next`); returns `h`.
    fn imagine_move<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        qa: &[f32],
        edge_s: f32,
    ) -> f32 {
        let (settings, robot) = (scenario.settings(), scenario.robot());
        let n = self.n.min(N).min(qa.len());
        if !all_finite(&self.rate[..n]) {
            return 0.0;
        }
        let h = advancement(
            robot,
            &self.evals.next().frames,
            &self.evals.next().distance_sq[..n],
            self.evals.next().field.nearest.as_ref(),
            &self.rate[..n],
            edge_s,
            settings.avoidance.advance_fraction,
        );
        if h.is_nan() || h <= 0.0 {
            return 0.0;
        }
        let moves = qa.iter().zip(&self.rate).zip(robot.joints()).take(n);
        for (next, ((&a, &r), joint)) in self.q_next.iter_mut().zip(moves) {
            *next = joint.clamp(a + h * r);
        }
        h
    }

    /// Evaluates `q_next` into `next`: whether a step could be accepted
    /// there, coming from a configuration of clearance `c_from` (clear, and
    /// above the contact floor or no closer).
    fn imagine_accept<const M: usize, const W: usize>(
        &mut self,
        scenario: &Scenario<N, M, W>,
        target: &Target,
        c_from: f32,
    ) -> bool {
        let n = self.n.min(N);
        let q = self.q_next;
        self.evals.next_mut().evaluate(scenario, &q[..n], target);
        let floor = CONTACT_FLOOR * scenario.settings().avoidance.engage_clearance;
        self.evals.next().safe_after(c_from, floor) && all_finite(&q[..n])
    }
}
