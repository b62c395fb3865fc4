//! The benchmark scenes build, start and warm up; the listing baseline computes
//! what the planner computes (its finite differences agree with the exact
//! products), so the two are timed doing the same job.

use capp_bench::scenes::{self, SCALING_JOINTS, SCALING_OBSTACLES};
use capp_bench::{listing, Listing, PhaseBench};
use capp_core::control::lyapunov_terms;

use capp_core::target::pose_error;
use capp_core::Phase;

#[test]
fn every_scene_builds_and_warms_up_moving() {
    for k in [0, 3, 8, 32, 64] {
        let scene = scenes::pips(k).unwrap();
        assert_eq!(scene.scenario.obstacles().len(), k);
        let planner = scenes::warm_up(&scene).unwrap();
        assert!(matches!(planner.phase(), Phase::Moving { .. }), "pips {k}");
    }
    for n in SCALING_JOINTS {
        for m in SCALING_OBSTACLES {
            let scene = scenes::chain(n, m).unwrap();
            assert_eq!(scene.scenario.robot().len(), n);
            assert_eq!(scene.scenario.obstacles().len(), m);
            let planner = scenes::warm_up(&scene).unwrap();
            assert!(
                matches!(planner.phase(), Phase::Moving { .. }),
                "chain {n} x {m}"
            );
        }
    }
}

#[test]
fn obstacles_are_near_the_arm() {
    let scene = scenes::pips(32).unwrap();
    let planner = scenes::warm_up(&scene).unwrap();
    let phases = PhaseBench::new(&scene.scenario, &planner);
    assert!(phases.active_pairs() > 20, "{}", phases.active_pairs());
}

#[test]
fn listing_differences_match_the_exact_products() {
    let mut settings = scenes::settings();
    // Every pair counts in the listing; make the planner count them too.
    settings.avoidance.influence_distance = 1.0e4;
    let base = scenes::pips(8).unwrap();
    let planner = scenes::warm_up(&base).unwrap();
    let obstacles: Vec<_> = base
        .scenario
        .obstacles()
        .iter()
        .map(|o| *o.source())
        .collect();
    let waypoints: Vec<_> = base.scenario.waypoints().collect();
    let mission = capp_core::Mission::new(&waypoints, settings).unwrap();
    let scenario =
        capp_core::Scenario::<18, 64, 1>::new(base.scenario.robot().clone(), &obstacles, &mission)
            .unwrap();
    let q = planner.joints();
    let here = listing::evaluate(&scenario, q);
    let frames = planner.frames();
    assert!((here.columns[3] - frames.end_position()).norm() < 1e-3);
    let mut listing = Listing::<18>::new(q);
    listing.step(&scenario);
    // Position column: J_4^T e_4 by differences against the exact product.
    let error = pose_error(frames, &scenario.targets()[0], 1.0);
    let mut terms = [[0.0; 18]; 4];
    lyapunov_terms(scenario.robot(), frames, &error, &mut terms);
    let size = terms[3].iter().fold(0.0f32, |a, t| a.max(t.abs()));
    for (j, exact) in terms[3].iter().enumerate() {
        let fd = listing.jacobian_column(j, 3).dot(&error.e[3]);
        assert!(
            (fd - exact).abs() < 3e-2 * size,
            "joint {j}: {fd} vs {exact}"
        );
    }
    // Obstacle gradient: differences of the powf potential against the exact
    // mu (f32 differences of a steep potential: a few per cent).
    let mut mu = [0.0; 18];
    let mut distance = [0.0; 18];
    capp_core::avoidance::potential_gradient(
        scenario.robot(),
        frames,
        scenario.world(),
        &scenario.settings().avoidance,
        &mut mu,
        &mut distance,
        None,
    );
    let scale = mu.iter().fold(0.0f32, |a, m| a.max(m.abs()));
    for (j, (fd, exact)) in listing.obstacle_gradient().iter().zip(&mu).enumerate() {
        assert!(
            (fd - exact).abs() < 5e-2 * scale,
            "joint {j}: {fd} vs {exact}"
        );
    }
}
