//! Every kind of bad input gives one clear message naming the file, the line
//! and the problem, and never a panic or a partial output folder.

use std::path::{Path, PathBuf};

use capp_sim::Problem;

mod common;

const PLANAR_TAIL: &str = r#"
[target]
position = [0.4, 0.7, 0.0]

[[obstacles]]
name = "post"
centre = [0.9, 0.42, 0.0]
semi_axes = [0.08, 0.08, 0.5]
exponents = [2.0, 2.0, 8.0]
"#;

fn write(dir: &tempfile::TempDir, name: &str, text: &str) -> PathBuf {
    let p = dir.path().join(name);
    std::fs::write(&p, text).unwrap();
    p
}

/// Loads `text` as `name`; expects an error at `line` containing `needle`.
fn rejects(name: &str, text: &str, line: usize, needle: &str) {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, name, text);
    let err = Problem::load(&path).expect_err("must be rejected");
    let msg = err.to_string();
    assert!(
        msg.starts_with(&format!("{}:{line}: ", path.display())),
        "wrong file/line in {msg:?} (want line {line})"
    );
    assert!(msg.contains(needle), "{msg:?} lacks {needle:?}");
    assert!(!msg.contains('\n'), "one line: {msg:?}");
}

fn planar(middle: &str, tail: &str) -> String {
    format!("name = \"bad\"\n{}{middle}{tail}", common::PLANAR_ARM)
}

#[test]
fn the_good_planar_text_loads() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "ok.toml", &planar("", PLANAR_TAIL));
    Problem::load(&path).unwrap();
}

#[test]
fn toml_missing_field() {
    let text = planar("", PLANAR_TAIL)
        .replace("max_rate = 30.0\n\n[[robot.joints]]", "\n[[robot.joints]]");
    rejects("s.toml", &text, 6, "missing field `max_rate`");
}

#[test]
fn toml_wrong_count() {
    let text = planar("", &PLANAR_TAIL.replace("[0.4, 0.7, 0.0]", "[0.4, 0.7]"));
    rejects("s.toml", &text, 25, "expected an array of length 3");
    let text = format!("start = [1.0, 2.0, 3.0]\n{}", planar("", PLANAR_TAIL));
    rejects("s.toml", &text, 1, "start: 3 values for 2 joints");
}

#[test]
fn toml_nan() {
    let text = planar(
        "",
        &PLANAR_TAIL.replace("[0.08, 0.08, 0.5]", "[0.08, nan, 0.5]"),
    );
    rejects(
        "s.toml",
        &text,
        27,
        "obstacle 1: semi-axes is not finite (\"post\")",
    );
}

#[test]
fn toml_unknown_joint_type() {
    let text = planar("", PLANAR_TAIL).replacen("type = \"revolute\"", "type = \"helical\"", 1);
    rejects(
        "s.toml",
        &text,
        7,
        "unknown variant `helical`, expected `revolute` or `prismatic`",
    );
}

#[test]
fn toml_negative_semi_axis() {
    let text = planar(
        "",
        &PLANAR_TAIL.replace("[0.08, 0.08, 0.5]", "[0.08, -0.08, 0.5]"),
    );
    rejects(
        "s.toml",
        &text,
        27,
        "obstacle 1: every semi-axis must be between",
    );
}

#[test]
fn toml_start_inside_an_obstacle() {
    // Straight arm pointing at the post.
    let text = format!("start = [25.0, 0.0]\n{}", planar("", PLANAR_TAIL));
    rejects(
        "s.toml",
        &text,
        1,
        "start configuration puts the arm inside obstacle 1 \"post\"",
    );
}

#[test]
fn toml_start_outside_limits() {
    let text = format!("start = [0.0, 160.0]\n{}", planar("", PLANAR_TAIL));
    rejects("s.toml", &text, 1, "start configuration: joint 2 = 2.7925");
    rejects("s.toml", &text, 1, "is outside its limits");
}

#[test]
fn toml_unknown_key_and_missing_units() {
    let text = planar("", PLANAR_TAIL).replace("[target]", "[target]\npositon = [0.0, 0.0, 0.0]");
    rejects("s.toml", &text, 25, "unknown field `positon`");
    let text =
        planar("", PLANAR_TAIL).replace("[units]\nangle = \"degrees\"\nlength = \"metres\"\n", "");
    rejects("s.toml", &text, 1, "missing field `units`");
}

const LEGACY: &str = "2
0.0 0.0 20 0.0 1.0 1
0.0 0.0 16 0.0 1.0 1
0.05 0.1 1
16 20 0.0
1 0 0 0 1 0 0 0 1
1
36 17 0.0 3 3 20 2 2 8 0 0 0
";

#[test]
fn the_good_legacy_text_loads() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "input.dat", LEGACY);
    let p = Problem::load(&path).unwrap();
    assert_eq!(p.joints.len(), 2);
}

#[test]
fn legacy_missing_field() {
    let text = LEGACY.replace("0.0 0.0 16 0.0 1.0 1\n", "0.0 0.0 16 0.0 1\n");
    // The flag is missing: "0.05" is read as joint 2's flag.
    rejects(
        "input.dat",
        &text,
        4,
        "joint 2: unknown joint type flag \"0.05\"",
    );
    let text = LEGACY.replace("2 2 8 0 0 0\n", "2 2 8 0 0\n");
    rejects(
        "input.dat",
        &text,
        8,
        "the file ends early: expected rz of obstacle 1 of 1",
    );
}

#[test]
fn legacy_wrong_count() {
    let text = LEGACY.replacen("\n1\n36", "\n2\n36", 1);
    rejects(
        "input.dat",
        &text,
        8,
        "ends early: expected cx of obstacle 2 of 2",
    );
    let text = LEGACY.replace("0.05 0.1 1", "0.05 0.1 0");
    rejects("input.dat", &text, 4, "the number of waypoints is 0");
    let text = format!("{LEGACY}7\n");
    rejects("input.dat", &text, 9, "unexpected extra value \"7\"");
}

#[test]
fn legacy_nan() {
    let text = LEGACY.replace("16 20 0.0", "16 nan 0.0");
    rejects(
        "input.dat",
        &text,
        5,
        "y of waypoint 1 is \"nan\", not a finite number",
    );
    let text = LEGACY.replace("16 20 0.0", "16 abc 0.0");
    rejects(
        "input.dat",
        &text,
        5,
        "expected y of waypoint 1 (a number), found \"abc\"",
    );
}

#[test]
fn legacy_unknown_joint_type() {
    let text = LEGACY.replace("0.0 0.0 20 0.0 1.0 1", "0.0 0.0 20 0.0 1.0 3");
    rejects(
        "input.dat",
        &text,
        2,
        "joint 1: unknown joint type flag \"3\" (1 = revolute, 0 = prismatic)",
    );
}

#[test]
fn legacy_negative_semi_axis() {
    let text = LEGACY.replace("3 3 20", "3 -3 20");
    rejects(
        "input.dat",
        &text,
        8,
        "obstacle 1: semi-axis b is -3; semi-axes must be positive",
    );
}

#[test]
fn legacy_start_inside_an_obstacle() {
    let text = LEGACY.replace("0.0 0.0 20 0.0 1.0 1", "0.0 0.4412 20 0.0 1.0 1");
    rejects(
        "input.dat",
        &text,
        2,
        "start configuration puts the arm inside obstacle 1",
    );
}

#[test]
fn legacy_start_outside_limits() {
    let text = LEGACY.replace("0.0 0.0 16 0.0 1.0 1", "0.0 7.0 16 0.0 1.0 1");
    rejects(
        "input.dat",
        &text,
        2,
        "start configuration: joint 2 = 7 is outside its limits",
    );
}

#[test]
fn legacy_not_a_rotation() {
    let text = LEGACY.replace("1 0 0 0 1 0 0 0 1", "1 0 0 0 1 0 0 0 2");
    rejects(
        "input.dat",
        &text,
        6,
        "orientation is not a rotation matrix",
    );
}

use common::capp;

#[test]
fn the_binary_fails_cleanly_and_leaves_no_output_folder() {
    let dir = tempfile::tempdir().unwrap();
    let path = write(&dir, "input.dat", &LEGACY.replace("3 3 20", "3 -3 20"));
    let out = dir.path().join("out");
    let o = capp()
        .args(["run", path.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    let stderr = String::from_utf8(o.stderr).unwrap();
    assert_eq!(stderr.lines().count(), 1, "{stderr}");
    assert!(
        stderr.contains("input.dat:8: obstacle 1: semi-axis b"),
        "{stderr}"
    );
    assert!(!stderr.contains("panicked"));
    assert!(!out.exists());
    assert_eq!(
        std::fs::read_dir(dir.path()).unwrap().count(),
        1,
        "nothing but the input"
    );
    // A missing file, too.
    let o = capp()
        .args(["run", "/nonexistent/x.toml"])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(2));
    assert!(String::from_utf8(o.stderr)
        .unwrap()
        .contains("/nonexistent/x.toml: cannot read the file"));
}

#[test]
fn the_binary_runs_checks_and_renders() {
    let dir = tempfile::tempdir().unwrap();
    let scenario = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/planar_arm.toml");
    let out = dir.path().join("planar");
    common::run_rendered(&scenario, &out);
    for f in [
        "trajectory.csv",
        "setpoints.csv",
        "joints.dat",
        "summary.txt",
        "scenario.toml",
        "COMPLETE",
    ] {
        assert!(out.join(f).is_file(), "{f}");
    }
    common::check_accepts(&out);
    // Run again onto the same folder: replaced, not refused.
    let o = capp()
        .args([
            "run",
            scenario.to_str().unwrap(),
            "-o",
            out.to_str().unwrap(),
            "-q",
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(0));
    assert!(o.stdout.is_empty());
    // The dead end's exit status says "not reached".
    let dead = Path::new(env!("CARGO_MANIFEST_DIR")).join("scenarios/pips_dead_end.toml");
    let o = capp()
        .args([
            "run",
            dead.to_str().unwrap(),
            "-o",
            dir.path().join("dead").to_str().unwrap(),
        ])
        .output()
        .unwrap();
    assert_eq!(o.status.code(), Some(1));
    assert!(String::from_utf8_lossy(&o.stdout).contains("outcome:           stalled"));
}

#[test]
fn toml_joint_waypoints() {
    // Both a pose and a configuration, or neither, or the wrong count.
    let tail = "\n[target]\nposition = [0.4, 0.7, 0.0]\njoints = [10.0, 20.0]\n";
    rejects(
        "both.toml",
        &planar("", tail),
        24,
        "give either `position` or `joints`",
    );
    let tail = "\n[target]\neuler = [0.0, 0.0, 0.0]\n";
    rejects(
        "neither.toml",
        &planar("", tail),
        24,
        "give `position` or `joints`",
    );
    let tail = "\n[[waypoints]]\njoints = [10.0]\n\n[target]\nposition = [0.4, 0.7, 0.0]\n";
    rejects(
        "count.toml",
        &planar("", tail),
        24,
        "waypoint 1: `joints` has 1 values for 2 joints",
    );
    let tail = "\n[target]\njoints = [10.0, 200.0]\n";
    rejects(
        "limits.toml",
        &planar("", tail),
        24,
        "target: joint configuration: a value is not finite or outside its limits",
    );
    // A good one: its pose is the configuration's, it plans, and it is reached.
    let dir = tempfile::tempdir().unwrap();
    let path = write(
        &dir,
        "ok.toml",
        &planar(
            "",
            "\n[[waypoints]]\njoints = [40.0, 30.0]\n\n[target]\njoints = [90.0, -20.0]\n",
        ),
    );
    let problem = Problem::load(&path).unwrap();
    assert_eq!(problem.joint_goals.len(), 2);
    let (a, b) = (0.5f32, 0.4f32);
    let (t1, t2) = (90f32.to_radians(), -20f32.to_radians());
    let x = a * t1.cos() + b * (t1 + t2).cos();
    let y = a * t1.sin() + b * (t1 + t2).sin();
    let p = problem.waypoints[1].position;
    assert!((p[0] - x).abs() < 1e-5 && (p[1] - y).abs() < 1e-5, "{p:?}");
    let scenario = problem.validate().unwrap();
    let result = capp_sim::plan::run(&problem, &scenario, |_| {}).unwrap();
    assert_eq!(result.outcome, capp_core::Outcome::Reached);
    let end = &result.rows.last().unwrap().q;
    assert!(
        (end[0] - t1).abs() < 1e-2 && (end[1] - t2).abs() < 1e-2,
        "{end:?}"
    );
}

/// A third link (0.3 m), so that links 1 and 3 form a checked pair.
const THIRD_JOINT: &str = r#"
[[robot.joints]]
name = "wrist"
type = "revolute"
alpha = 0.0
a = 0.3
theta = 0.0
min = -175.0
max = 175.0
max_rate = 30.0
"#;

#[test]
fn toml_bad_capsules_and_allowed_pairs() {
    // A joint's radius: the line of its joint.
    let text = planar(
        &THIRD_JOINT.replace("max_rate = 30.0", "max_rate = 30.0\nradius = 0.0"),
        PLANAR_TAIL,
    );
    rejects(
        "r.toml",
        &text,
        24,
        "link 3: the capsule radius must be positive and finite",
    );
    let text = planar(THIRD_JOINT, PLANAR_TAIL)
        .replace("[units]", "[robot]\nlink_radius = -0.01\n\n[units]");
    rejects(
        "lr.toml",
        &text,
        2,
        "robot.link_radius must be positive and finite",
    );
    // [[robot.allow]]: unknown names, links out of range, a link with itself.
    for (allow, needle) in [
        (
            "links = [1, \"elbow\"]",
            "robot.allow: unknown link \"elbow\"",
        ),
        (
            "links = [1, 4]",
            "robot.allow: link 4 does not exist (links are numbered 1 to 3)",
        ),
        (
            "links = [\"wrist\", 3]",
            "robot.allow: a link cannot be paired with itself (link 3)",
        ),
    ] {
        let text = planar(
            THIRD_JOINT,
            &format!("\n[[robot.allow]]\n{allow}\n{PLANAR_TAIL}"),
        );
        rejects("a.toml", &text, 34, needle);
    }
}

#[test]
fn toml_start_in_self_collision_names_the_two_links() {
    // Folded flat: the wrist link lies back across the first link.
    let text = format!(
        "start = [0.0, 170.0, 175.0]\n{}",
        planar(THIRD_JOINT, PLANAR_TAIL)
            .replace("min = -150.0\nmax = 150.0", "min = -175.0\nmax = 175.0")
    );
    rejects(
        "s.toml",
        &text,
        1,
        "start configuration puts link 1 into link 3 (after joint \"wrist\") (self-collision: their capsules touch)",
    );
    // Allowed, the same start is accepted (the pair is not checked).
    let allowed = text.replace("[target]", "[[robot.allow]]\nlinks = [1, 3]\n\n[target]");
    let dir = tempfile::tempdir().unwrap();
    Problem::load(&write(&dir, "ok.toml", &allowed)).unwrap();
}

#[test]
fn toml_bad_drive_limits() {
    // A joint's own limit: the line of its joint, in the file's units.
    let text =
        planar("", PLANAR_TAIL).replacen("max_rate = 30.0", "max_rate = 30.0\nmax_accel = nan", 1);
    rejects(
        "a.toml",
        &text,
        6,
        "robot: joint 1: max_accel must be positive and finite (got NaN)",
    );
    let text = planar(THIRD_JOINT, PLANAR_TAIL).replace(
        "max = 175.0\nmax_rate = 30.0",
        "max = 175.0\nmax_rate = 30.0\nmax_jerk = -5.0",
    );
    rejects(
        "j.toml",
        &text,
        24,
        "robot: joint 3 (\"wrist\"): max_jerk must be positive and finite (got -5)",
    );
    // An override: its own line.
    let text = planar(
        THIRD_JOINT,
        &format!("\n[[robot.overrides]]\njoint = 2\nmax_accel = 0.0\n{PLANAR_TAIL}"),
    );
    rejects(
        "o.toml",
        &text,
        34,
        "robot override of joint 2: max_accel must be positive and finite (got 0)",
    );
    // The robot-wide times: the robot's line.
    for key in ["ramp_time_s = 0.0", "jerk_time_s = inf"] {
        let text =
            planar("", PLANAR_TAIL).replace("[units]", &format!("[robot]\n{key}\n\n[units]"));
        let name = key.split(' ').next().unwrap();
        rejects(
            "t.toml",
            &text,
            2,
            &format!("robot.{name} must be positive and finite"),
        );
    }
    // The control period: in (0, 1] s, the settings' line.
    for (period, shown) in [
        ("0.0", "0"),
        ("1.5", "1.5"),
        ("-0.05", "-0.05"),
        ("nan", "NaN"),
    ] {
        let text = planar(
            "",
            &format!("{PLANAR_TAIL}\n[settings]\ncontrol_period_s = {period}\n"),
        );
        rejects(
            "p.toml",
            &text,
            33,
            &format!("settings.control_period_s must be in (0, 1] s (got {shown})"),
        );
    }
    // 1 s is allowed.
    let text = planar(
        "",
        &format!("{PLANAR_TAIL}\n[settings]\ncontrol_period_s = 1.0\n"),
    );
    let dir = tempfile::tempdir().unwrap();
    Problem::load(&write(&dir, "ok.toml", &text)).unwrap();
}
