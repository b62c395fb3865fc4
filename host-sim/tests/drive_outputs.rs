//! The joints' velocities and accelerations in the output folder
//! (`trajectory.csv`'s `v1..vn`, `a1..an`, issue 22): a tracked run's are
//! the backward differences of its positions over the control period, a
//! stepped run's the step's rate and its change over `h`; the reader gives
//! them back and still reads files written before them.

use std::path::{Path, PathBuf};
use std::process::Command;

use capp_sim::output::{header, rows_csv};
use capp_sim::trajectory::{self, Trajectory};
use capp_sim::{plan, Problem};

fn shipped(name: &str) -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR"))
        .join("scenarios")
        .join(name)
}

/// `planar_arm.toml` with `[settings] motion = "tracked"` (its last table
/// is `[settings]`), written into `dir`.
fn tracked_planar(dir: &Path) -> PathBuf {
    let text = std::fs::read_to_string(shipped("planar_arm.toml")).unwrap();
    let last = text.rfind('[').unwrap();
    assert!(text[last..].starts_with("[settings]"));
    let path = dir.join("planar_tracked.toml");
    std::fs::write(&path, format!("{text}\nmotion = \"tracked\"\n")).unwrap();
    path
}

/// `capp run FILE -o OUT`, quietly; the output folder.
fn capp_run(file: &Path, out: &Path) {
    let o = Command::new(env!("CARGO_BIN_EXE_capp"))
        .args(["run", file.to_str().unwrap(), "-o", out.to_str().unwrap()])
        .arg("--quiet")
        .output()
        .unwrap();
    assert!(
        o.status.success(),
        "capp run failed:\n{}",
        String::from_utf8_lossy(&o.stderr)
    );
}

/// One `f32` unit in the last place at `x`'s magnitude (the rounding a
/// stored value carries).
fn ulp(x: f64) -> f64 {
    let x = (x as f32).abs();
    if x == 0.0 {
        f32::MIN_POSITIVE as f64
    } else {
        (f32::from_bits(x.to_bits() + 1) - x) as f64
    }
}

/// The header's joint columns: `q1..qn`, then `v1..vn`, then `a1..an`,
/// between `h_s` and `x`.
fn joint_columns_in_order(csv: &str, n: usize) {
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let mut want = vec!["step".to_string(), "h_s".into()];
    for c in ["q", "v", "a"] {
        want.extend((1..=n).map(|j| format!("{c}{j}")));
    }
    want.push("x".into());
    assert_eq!(head[..want.len()], want[..], "{head:?}");
    assert_eq!(head, header(n));
}

/// The tracked run's velocities and accelerations are the backward
/// differences of its positions over the control period, rest before row
/// 0, to the `f32` rounding of the stored positions; and they are not
/// trivially so (the arm comes up to speed and stops).
#[test]
fn tracked_velocity_and_acceleration_are_the_positions_differences() {
    let dir = tempfile::tempdir().unwrap();
    let file = tracked_planar(dir.path());
    let out = dir.path().join("out");
    capp_run(&file, &out);
    let problem = Problem::load(&file).unwrap();
    let n = problem.joints.len();
    let csv = std::fs::read_to_string(out.join("trajectory.csv")).unwrap();
    joint_columns_in_order(&csv, n);
    let t = trajectory::read(&out.join("trajectory.csv")).unwrap();
    assert!(t.rows.len() > 50, "{} rows", t.rows.len());
    // The planner's period (an f32); a file's decimals name its f32 values
    // (shortest round trip), so they are read back as f32.
    let dt = problem.drive.control_period_s as f32 as f64;
    let f32s = |x: &[f64]| -> Vec<f64> { x.iter().map(|&v| v as f32 as f64).collect() };

    // Rest before row 0: positions q_{-1} = q_{-2} = q_0.
    let q0 = f32s(&t.rows[0].q);
    let (mut q_prev, mut v_prev) = (q0, vec![0.0; n]);
    let (mut worst_v, mut worst_a) = (0.0f64, 0.0f64);
    let (mut peak_v, mut peak_a) = (0.0f64, 0.0f64);
    for r in &t.rows {
        if r.step > 0 {
            assert_eq!(
                r.h as f32 as f64, dt,
                "row {}: off the control period",
                r.step
            );
        }
        let q = f32s(&r.q);
        let v_rec = f32s(r.velocity.as_ref().expect("v1..vn"));
        let a_rec = f32s(r.acceleration.as_ref().expect("a1..an"));
        let mut v_now = vec![0.0; n];
        for j in 0..n {
            let limits = problem.drive.joints[j];
            let v = (q[j] - q_prev[j]) / dt;
            let a = (v - v_prev[j]) / dt;
            // The positions are f32: each one is off by at most half an ulp
            // of itself (the tracker's `q + v dt` rounded), so a difference
            // by an ulp over dt, and an acceleration by two over dt^2.
            let room_v = (ulp(q[j]) + ulp(q_prev[j])) / dt + 2.0 * ulp(v_rec[j]);
            let room_a = 2.0 * room_v / dt + 2.0 * ulp(a_rec[j]);
            let (ev, ea) = ((v_rec[j] - v).abs(), (a_rec[j] - a).abs());
            assert!(
                ev <= room_v,
                "step {} joint {}: v {} recorded, {v} from positions",
                r.step,
                j + 1,
                v_rec[j]
            );
            assert!(
                ea <= room_a,
                "step {} joint {}: a {} recorded, {a} from positions",
                r.step,
                j + 1,
                a_rec[j]
            );
            worst_v = worst_v.max(ev / limits.max_rate);
            worst_a = worst_a.max(ea / limits.max_accel);
            peak_v = peak_v.max(v_rec[j].abs() / limits.max_rate);
            peak_a = peak_a.max(a_rec[j].abs() / limits.max_accel);
            v_now[j] = v;
        }
        q_prev = q;
        v_prev = v_now;
    }
    eprintln!(
        "{} rows: recorded against differenced, worst {worst_v:.2e} of the rate limit, \
         {worst_a:.2e} of the acceleration limit; peaks {peak_v:.3} and {peak_a:.3} of the limits",
        t.rows.len()
    );
    assert!(
        peak_v > 0.5 && peak_v <= 1.0 + 1e-5,
        "peak velocity {peak_v}"
    );
    assert!(
        peak_a > 0.5 && peak_a <= 1.0 + 1e-5,
        "peak acceleration {peak_a}"
    );
    let last = t.rows.last().unwrap();
    for (j, v) in last.velocity.as_ref().unwrap().iter().enumerate() {
        assert!(
            v.abs() <= 0.01 * problem.drive.joints[j].max_rate,
            "joint {} still at {v} at the end",
            j + 1
        );
    }

    // setpoints.csv carries the same columns and, row for row, the same values.
    let sp = std::fs::read_to_string(out.join("setpoints.csv")).unwrap();
    joint_columns_in_order(&sp, n);
    let sp = trajectory::read(&out.join("setpoints.csv")).unwrap();
    assert!(sp.rows.len() >= 2);
    for s in &sp.rows {
        let r = t.rows.iter().find(|r| r.step == s.step).unwrap();
        assert_eq!(
            (&s.q, &s.velocity, &s.acceleration),
            (&r.q, &r.velocity, &r.acceleration)
        );
    }
}

/// A stepped run (today's default): the velocity is the step's rate, so
/// `q_k - q_(k-1) = v_k h_k` (to rounding, away from the joint limits), and
/// the acceleration its change over `h_k` (0 where `h` is 0, and at row 0).
#[test]
fn stepped_velocity_is_the_steps_rate() {
    let problem = Problem::load(&shipped("planar_arm.toml")).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let rows = &result.rows;
    assert!(rows.len() > 10);
    assert!(rows[0].velocity.iter().all(|&v| v == 0.0));
    assert!(rows[0].acceleration.iter().all(|&a| a == 0.0));
    let mut moving = 0;
    for w in rows.windows(2) {
        let (before, r) = (&w[0], &w[1]);
        let h = r.h as f64;
        for j in 0..r.q.len() {
            let (v, a) = (r.velocity[j] as f64, r.acceleration[j] as f64);
            let dq = r.q[j] as f64 - before.q[j] as f64;
            let room = 2.0 * (ulp(r.q[j] as f64) + ulp(before.q[j] as f64));
            assert!(
                (dq - v * h).abs() <= room + 2.0 * ulp(v) * h,
                "step {} joint {}: moved {dq}, rate {v} over {h} s",
                r.step,
                j + 1
            );
            let want = if h > 0.0 {
                (r.velocity[j] - before.velocity[j]) as f64 / h
            } else {
                0.0
            };
            assert!((a - want).abs() <= 4.0 * ulp(want), "step {}", r.step);
            if v != 0.0 {
                moving += 1;
            }
        }
    }
    assert!(moving > rows.len(), "{moving} joint-steps moving");
}

/// The reader gives back what the writer wrote, velocities and
/// accelerations included, bit for bit; and a file from before those
/// columns (and one whose rows have them empty) still reads, without them.
#[test]
fn the_reader_round_trips_them_and_reads_older_files() {
    let dir = tempfile::tempdir().unwrap();
    let problem = Problem::load(&tracked_planar(dir.path())).unwrap();
    let scenario = problem.validate().unwrap();
    let result = plan::run(&problem, &scenario, |_| {}).unwrap();
    let n = problem.joints.len();
    let csv = rows_csv(n, &result.rows).unwrap();
    let read = trajectory::parse(&csv, Path::new("trajectory.csv")).unwrap();
    // The decimals name the f32 values exactly: read back as f32, bit for
    // bit what the planner recorded.
    let f32s = |x: &Option<Vec<f64>>| -> Option<Vec<f32>> {
        x.as_ref().map(|x| x.iter().map(|&v| v as f32).collect())
    };
    let expected = Trajectory::from_rows(&result.rows);
    assert_eq!(read.rows.len(), expected.rows.len());
    for ((r, e), row) in read.rows.iter().zip(&expected.rows).zip(&result.rows) {
        assert_eq!(
            f32s(&r.velocity),
            Some(row.velocity.clone()),
            "step {}",
            r.step
        );
        assert_eq!(f32s(&r.acceleration), Some(row.acceleration.clone()));
        assert_eq!(f32s(&r.velocity), f32s(&e.velocity));
        assert_eq!(f32s(&r.acceleration), f32s(&e.acceleration));
    }
    assert!(read.rows.iter().any(|r| r
        .velocity
        .as_ref()
        .is_some_and(|v| v.iter().any(|&x| x != 0.0))));

    // The same file without v1..vn and a1..an: everything else as before.
    let head: Vec<&str> = csv.lines().next().unwrap().split(',').collect();
    let keep: Vec<usize> = (0..head.len())
        .filter(|&i| {
            let name = head[i];
            let joint = |p: char| {
                name.strip_prefix(p)
                    .is_some_and(|d| !d.is_empty() && d.bytes().all(|b| b.is_ascii_digit()))
            };
            !(joint('v') || joint('a'))
        })
        .collect();
    assert_eq!(keep.len(), head.len() - 2 * n);
    let old: String = csv
        .lines()
        .map(|l| {
            let cells: Vec<&str> = l.split(',').collect();
            let kept: Vec<&str> = keep.iter().map(|&i| cells[i]).collect();
            kept.join(",") + "\n"
        })
        .collect();
    assert!(old.starts_with("step,h_s,q1,q2,q3,x,"), "{old}");
    let older = trajectory::parse(&old, Path::new("old.csv")).unwrap();
    assert_eq!(older.rows.len(), read.rows.len());
    for (o, r) in older.rows.iter().zip(&read.rows) {
        assert_eq!((o.velocity.as_ref(), o.acceleration.as_ref()), (None, None));
        assert_eq!((&o.q, o.h, o.v, o.clearance), (&r.q, r.h, r.v, r.clearance));
    }

    // Rows whose velocities were not known: empty cells, read as none.
    let mut unknown = result.rows.clone();
    for r in &mut unknown {
        r.velocity.clear();
        r.acceleration.clear();
    }
    let blank = rows_csv(n, &unknown).unwrap();
    assert!(blank.lines().nth(1).unwrap().contains(",,,,,,"));
    let blank = trajectory::parse(&blank, Path::new("blank.csv")).unwrap();
    assert!(blank
        .rows
        .iter()
        .all(|r| r.velocity.is_none() && r.acceleration.is_none()));

    // Half a row's velocities: an error that names the column.
    let mut lines: Vec<String> = csv.lines().map(String::from).collect();
    let v2 = head.iter().position(|&h| h == "v2").unwrap();
    let mut cells: Vec<String> = lines[3].split(',').map(String::from).collect();
    cells[v2].clear();
    lines[3] = cells.join(",");
    let e = trajectory::parse(&lines.join("\n"), Path::new("t.csv")).unwrap_err();
    assert!(
        e.to_string().contains("t.csv:4") && e.to_string().contains("`v2`"),
        "{e}"
    );
}
