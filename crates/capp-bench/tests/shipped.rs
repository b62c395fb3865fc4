//! The escape scenes are the shipped scenarios: planned from the bench's
//! constructors and from the TOML files `capp run` loads, every step's joint
//! vector agrees to the bit, and so does the outcome. So the board's escape
//! figures are for the scenarios users run.

use std::path::Path;

use capp_bench::scenes::{self, Scene, PIPS_JOINTS};
use capp_core::{Outcome, Phase, Planner};
use capp_sim::plan;
use capp_sim::Problem;

fn same_plan(scene: &Scene<PIPS_JOINTS>, file: &str) -> (Outcome, usize) {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("../../host-sim/scenarios")
        .join(file);
    let problem = Problem::load(&path).unwrap();
    let core = problem.validate().unwrap();
    let host = plan::run(&problem, &core, |_| {}).unwrap();

    let sc = &scene.scenario;
    let mut planner = Planner::new(sc, &scene.start).unwrap();
    let mut steps = vec![planner.joints().to_vec()];
    while !planner.is_done() {
        planner.step(sc).unwrap();
        steps.push(planner.joints().to_vec());
    }
    let Phase::Done(outcome) = planner.phase() else {
        panic!("not done");
    };
    assert_eq!(outcome, host.outcome, "{file}");
    let host_steps: Vec<&[f32]> = host.rows.iter().map(|r| r.q.as_slice()).collect();
    assert_eq!(steps.len(), host_steps.len(), "{file}: step count");
    for (i, (a, b)) in steps.iter().zip(&host_steps).enumerate() {
        let bits = |q: &[f32]| q.iter().map(|x| x.to_bits()).collect::<Vec<_>>();
        assert_eq!(bits(a), bits(b), "{file}: step {i}");
    }
    (outcome, steps.len() - 1)
}

#[test]
fn the_escape_scene_is_pips_escape_toml() {
    let (outcome, _) = same_plan(&scenes::pips_escape().unwrap(), "pips_escape.toml");
    assert_eq!(outcome, Outcome::Reached);
}

#[test]
fn the_dead_end_scene_is_pips_dead_end_toml() {
    let (outcome, _) = same_plan(&scenes::pips_dead_end().unwrap(), "pips_dead_end.toml");
    assert_eq!(outcome, Outcome::Stalled);
}
