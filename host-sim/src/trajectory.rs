//! Reading a trajectory CSV (as [`crate::output`] writes it) back.
//!
//! Required columns: `h_s` and `q1..qn`. `step`, `v1..vn` and `a1..an`
//! (the joints' velocities and accelerations; files written before they
//! were have none), `x y z`, `v`, `position_error`, `orientation_error`,
//! `clearance` and `escape` are read when present.

use std::collections::HashMap;
use std::path::Path;

use crate::problem::LoadError;

/// One row of a trajectory file.
#[derive(Clone, Debug, PartialEq)]
pub struct TrajectoryRow {
    /// 1-based line in the file.
    pub line: usize,
    /// Step number (the row index when the column is absent).
    pub step: u64,
    /// Step size that led to this row, seconds.
    pub h: f64,
    /// Joint values.
    pub q: Vec<f64>,
    /// Recorded joint velocities (per second), one per joint, if present
    /// (`v1..vn`; not in files written before them, empty cells in a row
    /// whose velocities were not known).
    pub velocity: Option<Vec<f64>>,
    /// Recorded joint accelerations (per second squared), as `velocity`
    /// (`a1..an`).
    pub acceleration: Option<Vec<f64>>,
    /// Recorded end-effector position, if present.
    pub position: Option<[f64; 3]>,
    /// Recorded `V`, if present.
    pub v: Option<f64>,
    /// Recorded position error, if present.
    pub position_error: Option<f64>,
    /// Recorded orientation error, if present.
    pub orientation_error: Option<f64>,
    /// Recorded clearance `C - 1`, if present and not empty.
    pub clearance: Option<f64>,
    /// The escape motion under way after this row's step (walk, detour,
    /// return; see [`crate::escapes`]); `None` while the law drives, or
    /// when not recorded.
    pub escape: Option<capp_core::escape::EscapeState>,
}

/// A joint trajectory.
#[derive(Clone, Debug, PartialEq)]
pub struct Trajectory {
    /// Joints per row.
    pub joints: usize,
    /// Rows in file order.
    pub rows: Vec<TrajectoryRow>,
}

impl Trajectory {
    /// Where the run escaped dead ends.
    pub fn escapes(&self) -> Vec<crate::escapes::Stretch> {
        // The waypoint column is not read; a new waypoint restarts the
        // attempts, so the attempt number still separates stretches.
        crate::escapes::stretches(self.rows.iter().map(|r| (r.step as u32, 0, r.escape)))
    }

    /// The robot standing still at `q`: one row, step 0, nothing recorded
    /// but the joint values (what `capp robot --render` draws).
    pub fn still(q: &[f64]) -> Trajectory {
        Trajectory {
            joints: q.len(),
            rows: vec![TrajectoryRow {
                line: 2,
                step: 0,
                h: 0.0,
                q: q.to_vec(),
                velocity: None,
                acceleration: None,
                position: None,
                v: None,
                position_error: None,
                orientation_error: None,
                clearance: None,
                escape: None,
            }],
        }
    }

    /// The rows of a plan, as a trajectory file would give them back (the
    /// `f32` values widened exactly; `line` is the row's line in a CSV with a
    /// header).
    pub fn from_rows(rows: &[crate::plan::Row]) -> Trajectory {
        Trajectory {
            joints: rows.first().map_or(0, |r| r.q.len()),
            rows: rows
                .iter()
                .enumerate()
                .map(|(i, r)| TrajectoryRow {
                    line: i + 2,
                    step: r.step as u64,
                    h: r.h as f64,
                    q: r.q.iter().map(|&x| x as f64).collect(),
                    velocity: widen(&r.velocity, r.q.len()),
                    acceleration: widen(&r.acceleration, r.q.len()),
                    position: Some(r.position.map(f64::from)),
                    v: Some(r.v as f64),
                    position_error: Some(r.position_error as f64),
                    orientation_error: Some(r.orientation_error as f64),
                    clearance: r.clearance.map(|c| c.value as f64),
                    escape: r.escape.filter(|&e| crate::escapes::classify(e).is_some()),
                })
                .collect(),
        }
    }
}

/// `values` widened, when there is one per joint.
fn widen(values: &[f32], joints: usize) -> Option<Vec<f64>> {
    (values.len() == joints).then(|| values.iter().map(|&x| x as f64).collect())
}

/// Reads a trajectory CSV.
pub fn read(path: &Path) -> Result<Trajectory, LoadError> {
    let text = std::fs::read_to_string(path)
        .map_err(|e| LoadError::new(path, None, format!("cannot read the file: {e}")))?;
    parse(&text, path)
}

/// Parses trajectory CSV text.
pub fn parse(text: &str, path: &Path) -> Result<Trajectory, LoadError> {
    let mut reader = csv::ReaderBuilder::new()
        .has_headers(true)
        .from_reader(text.as_bytes());
    let headers = reader
        .headers()
        .map_err(|e| LoadError::new(path, Some(1), format!("bad header: {e}")))?
        .clone();
    let index: HashMap<&str, usize> = headers.iter().enumerate().map(|(i, h)| (h, i)).collect();
    let mut joints = 0;
    while index.contains_key(format!("q{}", joints + 1).as_str()) {
        joints += 1;
    }
    if joints == 0 {
        return Err(LoadError::new(
            path,
            Some(1),
            "no joint columns (q1, q2, ...)",
        ));
    }
    let Some(&h_col) = index.get("h_s") else {
        return Err(LoadError::new(path, Some(1), "no step-size column `h_s`"));
    };
    let q_cols: Vec<usize> = (1..=joints)
        .map(|j| index[format!("q{j}").as_str()])
        .collect();
    let col = |name: &str| index.get(name).copied();
    // `v1..vn`, `a1..an`: all of a kind, or none of it.
    let per_joint = |prefix: &str| -> Option<Vec<usize>> {
        (1..=joints)
            .map(|j| col(format!("{prefix}{j}").as_str()))
            .collect()
    };
    let (velocity_cols, acceleration_cols) = (per_joint("v"), per_joint("a"));
    let (step_col, x_col, y_col, z_col) = (col("step"), col("x"), col("y"), col("z"));
    let escape_col = col("escape");
    let (v_col, pe_col, oe_col, c_col) = (
        col("v"),
        col("position_error"),
        col("orientation_error"),
        col("clearance"),
    );
    let mut rows = Vec::new();
    for (i, record) in reader.records().enumerate() {
        let line = i + 2;
        let record = record.map_err(|e| LoadError::new(path, Some(line), e.to_string()))?;
        let number = |c: usize, name: &str| -> Result<f64, LoadError> {
            let s = record.get(c).unwrap_or("").trim();
            s.parse::<f64>().map_err(|_| {
                LoadError::new(
                    path,
                    Some(line),
                    format!("column `{name}`: \"{s}\" is not a number"),
                )
            })
        };
        let optional = |c: Option<usize>, name: &str| -> Result<Option<f64>, LoadError> {
            match c {
                Some(c) if !record.get(c).unwrap_or("").trim().is_empty() => {
                    number(c, name).map(Some)
                }
                _ => Ok(None),
            }
        };
        let q = q_cols
            .iter()
            .enumerate()
            .map(|(j, &c)| number(c, &format!("q{}", j + 1)))
            .collect::<Result<Vec<_>, _>>()?;
        // A row's velocities (or accelerations): every cell a number, or
        // every cell empty (not known).
        let joint_values =
            |cols: &Option<Vec<usize>>, prefix: &str| -> Result<Option<Vec<f64>>, LoadError> {
                let Some(cols) = cols else {
                    return Ok(None);
                };
                let values = cols
                    .iter()
                    .enumerate()
                    .map(|(j, &c)| optional(Some(c), &format!("{prefix}{}", j + 1)))
                    .collect::<Result<Vec<_>, _>>()?;
                if values.iter().all(Option::is_none) {
                    return Ok(None);
                }
                values
                    .iter()
                    .enumerate()
                    .map(|(j, v)| {
                        v.ok_or_else(|| {
                            LoadError::new(
                                path,
                                Some(line),
                                format!("column `{prefix}{}` is empty, others are not", j + 1),
                            )
                        })
                    })
                    .collect::<Result<Vec<_>, _>>()
                    .map(Some)
            };
        let velocity = joint_values(&velocity_cols, "v")?;
        let acceleration = joint_values(&acceleration_cols, "a")?;
        let position = match (x_col, y_col, z_col) {
            (Some(x), Some(y), Some(z)) => {
                Some([number(x, "x")?, number(y, "y")?, number(z, "z")?])
            }
            _ => None,
        };
        let escape = match escape_col {
            Some(c) => crate::escapes::parse_label(record.get(c).unwrap_or(""))
                .map_err(|e| LoadError::new(path, Some(line), format!("column `escape`: {e}")))?,
            None => None,
        };
        rows.push(TrajectoryRow {
            line,
            step: match step_col {
                Some(c) => number(c, "step")? as u64,
                None => i as u64,
            },
            h: number(h_col, "h_s")?,
            q,
            velocity,
            acceleration,
            position,
            v: optional(v_col, "v")?,
            position_error: optional(pe_col, "position_error")?,
            orientation_error: optional(oe_col, "orientation_error")?,
            clearance: optional(c_col, "clearance")?,
            escape,
        });
    }
    if rows.is_empty() {
        return Err(LoadError::new(path, None, "the trajectory has no rows"));
    }
    Ok(Trajectory { joints, rows })
}
