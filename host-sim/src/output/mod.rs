//! The output folder of a run, written so that a folder that exists is complete.
//!
//! | file | contents |
//! |---|---|
//! | `trajectory.csv` | every step: [`LEAD_COLUMNS`], the joint columns ([`header`]: `q1..qn`, `v1..vn`, `a1..an`), then [`TRAJECTORY_COLUMNS`] |
//! | `setpoints.csv` | the decimated setpoint stream, same columns |
//! | `joints.dat` | the setpoints in the listing's layout ([`crate::input::legacy::joints_dat_record`]) |
//! | `summary.txt` | the summary printed on stdout ([`summary`]) |
//! | `scenario.toml` / `input.dat` | a copy of the input, so `capp check` finds it |
//! | `COMPLETE` | written last |
//!
//! Everything is written into a sibling staging folder, which is renamed onto
//! the requested path at the end; a failed run leaves at most a
//! `.NAME.partial-PID` folder, never a folder that looks complete.

pub mod summary;

use std::fmt::Write as _;
use std::fs;
use std::path::{Path, PathBuf};

use anyhow::{bail, Context, Result};
use capp_core::escape::EscapeState;

use self::summary::{outcome_name, Summary};
use crate::plan::{Row, RunResult};
use crate::problem::{Problem, SourceKind};

/// Columns before the joint values.
pub const LEAD_COLUMNS: [&str; 2] = ["step", "h_s"];
/// The joint columns, in order, each `1..=n`: position (radians or length
/// units), velocity (per second), acceleration (per second squared)
/// ([`crate::plan::Row`]).
pub const JOINT_COLUMNS: [&str; 3] = ["q", "v", "a"];
/// Columns after the joint columns.
pub const TRAJECTORY_COLUMNS: [&str; 22] = [
    "x",
    "y",
    "z",
    "r11",
    "r12",
    "r13",
    "r21",
    "r22",
    "r23",
    "r31",
    "r32",
    "r33",
    "v",
    "position_error",
    "orientation_error",
    "clearance",
    "clearance_point",
    "clearance_obstacle",
    "waypoint",
    "constrained",
    "halvings",
    "escape",
];
/// The marker written last into a finished output folder.
pub const COMPLETE_MARKER: &str = "COMPLETE";

/// What the `escape` column says ([`crate::escapes::label`]): empty while
/// the law drives, else `walk K`, `detour K obstacle O +z` (1-based attempt
/// and obstacle, the side of the obstacle in its own frame) or `return`.
pub fn escape_label(state: EscapeState) -> String {
    crate::escapes::label(state)
}

/// The CSV header for `n` joints: [`LEAD_COLUMNS`], `q1..qn`, `v1..vn`,
/// `a1..an` ([`JOINT_COLUMNS`]), [`TRAJECTORY_COLUMNS`].
pub fn header(n: usize) -> Vec<String> {
    LEAD_COLUMNS
        .iter()
        .map(|s| s.to_string())
        .chain(
            JOINT_COLUMNS
                .iter()
                .flat_map(|c| (1..=n).map(move |i| format!("{c}{i}"))),
        )
        .chain(TRAJECTORY_COLUMNS.iter().map(|s| s.to_string()))
        .collect()
}

/// Rows as CSV text (full `f32` precision: values read back bit for bit).
/// `v1..vn` and `a1..an` are the rows' velocities and accelerations (per
/// second, per second squared; [`crate::plan`]; empty in a row that has
/// not one per joint). Clearance point and obstacle are 1-based; empty when nothing is within
/// influence. `constrained` and `halvings` are empty where not known (a plan
/// received from a board).
pub fn rows_csv<'a>(n: usize, rows: impl IntoIterator<Item = &'a Row>) -> Result<String> {
    let mut w = csv::Writer::from_writer(Vec::new());
    w.write_record(header(n))?;
    for r in rows {
        let mut rec: Vec<String> = vec![r.step.to_string(), r.h.to_string()];
        rec.extend(r.q.iter().map(|v| v.to_string()));
        for values in [&r.velocity, &r.acceleration] {
            if values.len() == n {
                rec.extend(values.iter().map(|v| v.to_string()));
            } else {
                // Not known: empty cells.
                rec.extend((0..n).map(|_| String::new()));
            }
        }
        rec.extend(r.position.iter().map(|v| v.to_string()));
        rec.extend(r.rotation.iter().flatten().map(|v| v.to_string()));
        rec.push(r.v.to_string());
        rec.push(r.position_error.to_string());
        rec.push(r.orientation_error.to_string());
        match r.clearance {
            Some(c) => {
                rec.push(c.value.to_string());
                rec.push((c.point as u32 + 1).to_string());
                rec.push((c.obstacle as u32 + 1).to_string());
            }
            None => rec.extend([String::new(), String::new(), String::new()]),
        }
        rec.push((r.waypoint as u32 + 1).to_string());
        rec.push(
            r.constrained
                .map_or(String::new(), |c| u8::from(c).to_string()),
        );
        rec.push(r.halvings.map_or(String::new(), |h| h.to_string()));
        rec.push(r.escape.map_or(String::new(), escape_label));
        w.write_record(&rec)?;
    }
    Ok(String::from_utf8(w.into_inner()?)?)
}

/// The setpoints in the listing's `joints.dat` layout.
pub fn joints_dat<'a>(rows: impl IntoIterator<Item = &'a Row>) -> String {
    let mut out = String::new();
    for r in rows {
        crate::input::legacy::joints_dat_record(&r.q, &mut out);
    }
    out
}

/// The name of the scenario copy inside an output folder.
pub fn scenario_copy_name(problem: &Problem) -> &'static str {
    match problem.kind {
        SourceKind::Toml => "scenario.toml",
        SourceKind::Legacy => "input.dat",
    }
}

/// Copies the scenario into an output folder. A TOML scenario's paths
/// (`[robot] urdf`, `packages`, `package_dirs`, `[[obstacles]] mesh`,
/// relative to the scenario file) are made absolute in the copy, comments
/// and all else kept, so that `capp check` and `capp render` load the copy
/// where it is.
fn copy_scenario(problem: &Problem, to: &Path) -> Result<()> {
    let source = &problem.source;
    let text =
        fs::read_to_string(source).with_context(|| format!("cannot read {}", source.display()))?;
    let mut text = text;
    // Every TOML scenario is rewritten (unchanged where it names no file):
    // a mesh of boxes has no hull left to tell it by.
    if problem.kind == SourceKind::Toml {
        let mut doc: toml_edit::DocumentMut = text
            .parse()
            .with_context(|| format!("cannot re-read {}", source.display()))?;
        let here = source.parent().unwrap_or(Path::new("."));
        let absolute = |v: &mut toml_edit::Value| {
            if let Some(rel) = v.as_str() {
                let path = here.join(rel);
                let path = fs::canonicalize(&path).unwrap_or(path);
                let decor = v.decor().clone();
                *v = toml_edit::Value::from(path.display().to_string());
                *v.decor_mut() = decor;
            }
        };
        if let Some(robot) = doc.get_mut("robot").and_then(|r| r.as_table_like_mut()) {
            if let Some(v) = robot.get_mut("urdf").and_then(|v| v.as_value_mut()) {
                absolute(v);
            }
            if let Some(t) = robot
                .get_mut("packages")
                .and_then(|v| v.as_table_like_mut())
            {
                for (_, v) in t.iter_mut() {
                    if let Some(v) = v.as_value_mut() {
                        absolute(v);
                    }
                }
            }
            if let Some(a) = robot.get_mut("package_dirs").and_then(|v| v.as_array_mut()) {
                a.iter_mut().for_each(absolute);
            }
        }
        if let Some(list) = doc
            .get_mut("obstacles")
            .and_then(|o| o.as_array_of_tables_mut())
        {
            for o in list.iter_mut() {
                if let Some(v) = o.get_mut("mesh").and_then(|v| v.as_value_mut()) {
                    absolute(v);
                }
            }
        }
        text = doc.to_string();
    }
    fs::write(to, text).with_context(|| format!("cannot write {}", to.display()))
}

/// Finds the scenario copy in an output folder.
pub fn find_scenario_copy(dir: &Path) -> Option<PathBuf> {
    ["scenario.toml", "input.dat"]
        .iter()
        .map(|n| dir.join(n))
        .find(|p| p.is_file())
}

/// Writes a run into `dir`, atomically; `extra` may add files (pictures) to the
/// staging folder before it is renamed.
pub fn write_run(
    dir: &Path,
    problem: &Problem,
    result: &RunResult,
    summary: &Summary,
    extra: impl FnOnce(&Path) -> Result<()>,
) -> Result<()> {
    write_folder(dir, outcome_name(result.outcome), |staging| {
        let n = problem.joints.len();
        fs::write(staging.join("trajectory.csv"), rows_csv(n, &result.rows)?)?;
        fs::write(
            staging.join("setpoints.csv"),
            rows_csv(n, result.setpoints())?,
        )?;
        fs::write(staging.join("joints.dat"), joints_dat(result.setpoints()))?;
        fs::write(staging.join("summary.txt"), summary.to_string())?;
        copy_scenario(problem, &staging.join(scenario_copy_name(problem)))?;
        extra(staging)
    })
}

/// Writes a capp output folder `dir`, atomically: `fill` writes the files
/// into a sibling staging folder, then the [`COMPLETE_MARKER`] (holding
/// `what`, a line) is written and the folder renamed onto `dir`. Refuses a
/// `dir` that exists unless it is empty or a finished capp output folder
/// (which is replaced).
pub fn write_folder(dir: &Path, what: &str, fill: impl FnOnce(&Path) -> Result<()>) -> Result<()> {
    let parent = match dir.parent() {
        Some(p) if !p.as_os_str().is_empty() => p.to_path_buf(),
        _ => PathBuf::from("."),
    };
    fs::create_dir_all(&parent).with_context(|| format!("cannot create {}", parent.display()))?;
    let leaf = dir
        .file_name()
        .with_context(|| format!("{} is not a folder name", dir.display()))?
        .to_string_lossy()
        .into_owned();
    if dir.exists() {
        let ours = dir.join(COMPLETE_MARKER).is_file()
            || fs::read_dir(dir)
                .map(|mut d| d.next().is_none())
                .unwrap_or(false);
        if !ours {
            bail!(
                "{} exists and is not a finished capp output folder; not overwriting it",
                dir.display()
            );
        }
    }
    let staging = parent.join(format!(".{leaf}.partial-{}", std::process::id()));
    if staging.exists() {
        fs::remove_dir_all(&staging)?;
    }
    fs::create_dir(&staging).with_context(|| format!("cannot create {}", staging.display()))?;
    let written = (|| -> Result<()> {
        fill(&staging)?;
        let mut marker = String::new();
        let _ = writeln!(marker, "{what}");
        fs::write(staging.join(COMPLETE_MARKER), marker)?;
        Ok(())
    })();
    if let Err(e) = written {
        let _ = fs::remove_dir_all(&staging);
        return Err(e);
    }
    if dir.exists() {
        fs::remove_dir_all(dir).with_context(|| format!("cannot replace {}", dir.display()))?;
    }
    fs::rename(&staging, dir)
        .with_context(|| format!("cannot move {} to {}", staging.display(), dir.display()))?;
    Ok(())
}
