//! The drive limits as read from files (`[settings] control_period_s`,
//! `[robot] ramp_time_s` / `jerk_time_s`, each joint's `max_accel` and
//! `max_jerk`): defaults from the rate, units, overrides, the listing and
//! the preset.

use std::path::Path;

use capp_core::JointKind;
use capp_sim::input::scenario_file;
use capp_sim::problem::{DEFAULT_CONTROL_PERIOD_S, DEFAULT_JERK_TIME_S, DEFAULT_RAMP_TIME_S};
use capp_sim::Problem;

fn scenario(name: &str) -> Problem {
    let path = Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name);
    Problem::load(&path).unwrap_or_else(|e| panic!("{e}"))
}

fn close(a: f64, b: f64) -> bool {
    (a - b).abs() <= 1e-12 * a.abs().max(b.abs())
}

/// Every joint at the defaults from its rate (as the core holds it).
fn at_defaults(problem: &Problem) {
    assert_eq!(problem.drive.control_period_s, DEFAULT_CONTROL_PERIOD_S);
    assert_eq!(problem.drive.joints.len(), problem.joints.len());
    for (j, d) in problem.joints.iter().zip(&problem.drive.joints) {
        assert_eq!(d.max_rate, j.max_rate as f64);
        assert!(close(d.max_accel, d.max_rate / DEFAULT_RAMP_TIME_S));
        assert!(close(d.max_jerk, d.max_accel / DEFAULT_JERK_TIME_S));
    }
}

#[test]
fn the_shipped_scenarios_and_the_listing_get_the_defaults() {
    for name in [
        "planar_arm.toml",
        "pips_payload_bay.toml",
        "legacy/input.dat",
        "legacy/twin.toml",
    ] {
        at_defaults(&scenario(name));
    }
    // planar_arm's shoulder: 30 deg/s, so 60 deg/s^2 and 600 deg/s^3.
    let p = scenario("planar_arm.toml");
    let deg = std::f64::consts::PI / 180.0;
    assert!((p.drive.joints[0].max_accel - 60.0 * deg).abs() < 1e-6);
    assert!((p.drive.joints[0].max_jerk - 600.0 * deg).abs() < 1e-5);
}

const PLANAR: &str = r#"name = "d"
[units]
angle = "degrees"
length = "metres"

[robot]
ramp_time_s = 0.25
jerk_time_s = 0.2

[[robot.joints]]
type = "revolute"
alpha = 0.0
a = 0.5
min = -170.0
max = 170.0
max_rate = 30.0
max_accel = 90.0

[[robot.joints]]
type = "prismatic"
alpha = 0.0
a = 0.0
d = 0.2
min = 0.0
max = 0.5
max_rate = 0.1
max_jerk = 7.0

[[robot.joints]]
type = "revolute"
alpha = 0.0
a = 0.3
min = -150.0
max = 150.0
max_rate = 45.0

[[robot.overrides]]
joint = 3
max_rate = 20.0

[target]
position = [0.4, 0.7, 0.0]

[settings]
control_period_s = 0.02
"#;

/// Given values in the file's units (degrees for revolute joints, the
/// length unit for prismatic ones), the robot-wide times, overrides.
#[test]
fn given_limits_units_and_overrides() {
    let p = scenario_file::parse(PLANAR, Path::new("d.toml")).unwrap_or_else(|e| panic!("{e}"));
    let deg = std::f64::consts::PI / 180.0;
    let d = &p.drive;
    assert_eq!(d.control_period_s, 0.02);
    // Joint 1: its own acceleration, the jerk from it over jerk_time_s.
    assert!(close(d.joints[0].max_accel, 90.0 * deg));
    assert!(close(d.joints[0].max_jerk, 90.0 * deg / 0.2));
    // Joint 2 (prismatic, metres): the acceleration from the rate over
    // ramp_time_s, its own jerk, neither converted.
    assert!(close(d.joints[1].max_accel, 0.1f32 as f64 / 0.25));
    assert_eq!(d.joints[1].max_jerk, 7.0);
    // Joint 3: the override's rate moves both defaults.
    assert!(close(d.joints[2].max_rate, (20.0 * deg) as f32 as f64));
    assert!(close(d.joints[2].max_accel, d.joints[2].max_rate / 0.25));
    assert!(close(d.joints[2].max_jerk, d.joints[2].max_accel / 0.2));
    // An override of the limits themselves, in degrees.
    let text = PLANAR.replace(
        "joint = 3\nmax_rate = 20.0",
        "joint = 3\nmax_accel = 10.0\nmax_jerk = 50.0",
    );
    let p = scenario_file::parse(&text, Path::new("d.toml")).unwrap_or_else(|e| panic!("{e}"));
    assert!(close(p.drive.joints[2].max_accel, 10.0 * deg));
    assert!(close(p.drive.joints[2].max_jerk, 50.0 * deg));
}

/// PIPS in metres: the prismatic joints' limits are the inch values times
/// 0.0254, the revolute ones unchanged, as the rates are.
#[test]
fn the_preset_in_metres_scales_prismatic_limits() {
    let text = |length: &str| {
        format!(
            "[units]\nangle = \"degrees\"\nlength = \"{length}\"\n[robot]\npreset = \"pips\"\n\
             [target]\nposition = [1.0, 1.0, 1.0]\n"
        )
    };
    let inches = scenario_file::parse(&text("inches"), Path::new("i.toml")).unwrap();
    let metres = scenario_file::parse(&text("metres"), Path::new("m.toml")).unwrap();
    at_defaults(&inches);
    at_defaults(&metres);
    let mut prismatic = 0;
    for ((j, a), b) in inches
        .joints
        .iter()
        .zip(&inches.drive.joints)
        .zip(&metres.drive.joints)
    {
        let k = match j.kind {
            JointKind::Prismatic => {
                prismatic += 1;
                0.0254
            }
            JointKind::Revolute => 1.0,
        };
        assert!((b.max_accel - k * a.max_accel).abs() <= 1e-6 * a.max_accel);
        assert!((b.max_jerk - k * a.max_jerk).abs() <= 1e-6 * a.max_jerk);
    }
    assert!(prismatic > 0);
}
