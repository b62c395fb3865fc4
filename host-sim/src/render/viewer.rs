//! `viewer.html`: the run as a 3-D scene to turn, zoom and play, in one
//! self-contained file (works offline, from `file://`).
//!
//! The page inlines three things: three.js (`assets/three.min.js`, the parts
//! listed in `assets/three-entry.js`, MIT licence in `assets/LICENSE-three.txt`;
//! `assets/build-three.sh` rebuilds it from npm), the run's data as one JSON
//! object `RUN` written here, and the page's own code (`assets/viewer.js`).
//!
//! `RUN` holds, for each of up to [`FRAMES`] rows (picked by
//! [`super::views::frames`]): step, plan time, `V`, errors, clearance, the
//! frame origins `o_0..o_n` and the end effector's axes, and the escape
//! under way (`escape`: a phrase, or `null` while the law drives); the
//! end-effector path; the escape stretches (`escapes`: kind, colour, the step
//! it started, a phrase, and its stretch of the path); the waypoints (with
//! their orientation when they have one); and each obstacle's surface as a
//! `(lat + 1) x lon` grid of world points, or for a convex hull its faces
//! (`triangles`: flat, three world points a triangle; `outlines`: each
//! face's closed polygon). The row where each escape started
//! is always among the frames.
//!
//! What the drives are asked for: `joint_names`, and per frame each
//! joint's velocity as a fraction of its rate limit (`velocity_fraction`,
//! `frames x n`, row-major) and its acceleration as a fraction of its
//! acceleration limit (`acceleration_fraction`), the limits from
//! `Problem::drive`; `null` when the trajectory has no velocities (a file
//! written before them). The page draws them as a bar chart per frame
//! (`|fraction|`, the limit a line at 1, a bar over it red) and names the
//! largest of each.
//!
//! The link capsules ([`capp_core::self_collision`]): `capsules`, each
//! link's radius; `link_segments`, per frame each link's capsule segment
//! in world coordinates, `[ax, ay, az, bx, by, bz]` per link flat
//! ([`crate::geometry::Pose::capsules`]), or `null` when every link's
//! capsule is round its chord (link `k` between origins `o_k` and
//! `o_{k+1}`, so the page draws it from the frames it already has);
//! `self_collision`, whether the scenario keeps them apart; and
//! `closest_links`, per frame, the closest pair the scenario checks as
//! `[a, b, gap]` (DH link numbers, the capsules' distance in length units;
//! `null` when no pair is checked). The page draws the capsules as
//! see-through tubes with round ends, the closest checked pair in red,
//! behind a checkbox (off when the page opens; `c` toggles it,
//! `viewer.html#capsules` opens with them shown; `capsules_shown`: the
//! page opens with them shown whatever the URL says).
//!
//! `collision_capsules` (`null` unless asked for, [`ViewerOptions`]): per
//! frame, a URDF robot's fitted collision capsules in world coordinates,
//! each `[ax, ay, az, bx, by, bz, r]` ([`collision_capsules`]), drawn
//! in orange with the link capsules (same checkbox).

use std::fmt::Write as _;

use super::canvas::escape;
use super::chart::nice_step;
use super::views::{bounds, escape_color, frames, hull_faces, origins, surface};
use crate::escapes::{classify, side_name, Kind};
use crate::geometry::{collision_capsules, forward, Geometry, Pose};
use crate::problem::Problem;
use crate::trajectory::{Trajectory, TrajectoryRow};

/// Most frames in a page.
pub const FRAMES: usize = 400;
const LAT: usize = 32;
const LON: usize = 64;

static THREE_JS: &str = include_str!("../../assets/three.min.js");
static VIEWER_JS: &str = include_str!("../../assets/viewer.js");

/// What a page shows beyond a run's (the default: a run's page).
#[derive(Clone, Copy, Debug, Default)]
pub struct ViewerOptions {
    /// Open with the link capsules shown (as `viewer.html#capsules`).
    pub capsules_shown: bool,
    /// A URDF robot's fitted collision capsules, per frame.
    pub collision_capsules: bool,
}

/// A JSON number, or `null` for a missing or non-finite value.
fn num(v: Option<f64>, out: &mut String) {
    match v.filter(|v| v.is_finite()) {
        Some(0.0) => out.push('0'),
        Some(v) if (1e-3..1e6).contains(&v.abs()) => {
            let _ = write!(out, "{}", (v * 1e4).round() / 1e4);
        }
        Some(v) => {
            let _ = write!(out, "{v:.4e}");
        }
        None => out.push_str("null"),
    }
}

fn list(values: impl IntoIterator<Item = Option<f64>>) -> String {
    let mut s = String::from("[");
    for (i, v) in values.into_iter().enumerate() {
        if i > 0 {
            s.push(',');
        }
        num(v, &mut s);
    }
    s.push(']');
    s
}

fn string(s: &str) -> String {
    let mut out = String::from("\"");
    for c in s.chars() {
        match c {
            '"' => out.push_str("\\\""),
            '\\' => out.push_str("\\\\"),
            '<' => out.push_str("\\u003c"),
            c if (c as u32) < 0x20 => {
                let _ = write!(out, "\\u{:04x}", c as u32);
            }
            c => out.push(c),
        }
    }
    out.push('"');
    out
}

/// An obstacle in words: `"box"`, or `obstacle 3` when it has no name.
fn obstacle_name(problem: &Problem, o: usize) -> String {
    match problem.obstacle_names.get(o).filter(|n| !n.is_empty()) {
        Some(n) => format!("\"{n}\""),
        None => format!("obstacle {}", o + 1),
    }
}

/// The escape under way, in words (`None` while the law drives).
pub fn escape_phrase(problem: &Problem, state: capp_core::escape::EscapeState) -> Option<String> {
    let (kind, attempt, side) = classify(state)?;
    let on = |s: capp_core::escape::Side| {
        (
            obstacle_name(problem, s.obstacle as usize),
            side_name(s).replace('-', "−"),
        )
    };
    Some(match (kind, side.map(on)) {
        (Kind::Detour, Some((o, s))) => format!("detour {attempt} round {o}, its {s} side"),
        (Kind::Walk, Some((o, s))) => format!("walk {attempt} to the {s} side of {o}"),
        (Kind::Walk | Kind::Detour, None) => format!("walk {attempt}, no obstacle blocking"),
        (Kind::Search, _) => format!("search {attempt} for a path (the arm holds still)"),
        (Kind::Path, Some((o, s))) => {
            format!("path {attempt} found by a search, to the {s} side of {o}")
        }
        (Kind::Path, None) => format!("path {attempt} found by a search"),
        (Kind::Return, _) => "return to the best configuration".into(),
    })
}

fn hex(c: [u8; 3]) -> String {
    format!("#{:02x}{:02x}{:02x}", c[0], c[1], c[2])
}

/// Per frame (the arm at each, [`Geometry::pose`]), the closest pair of
/// links the scenario checks, by the independent model `geometry`
/// ([`Geometry::link_gaps`], as the summary names it): DH link numbers
/// (1-based) and the capsules' distance; `None` for every frame when no
/// pair is checked.
pub fn closest_links(geometry: &Geometry, frames: &[Pose]) -> Vec<Option<(usize, usize, f64)>> {
    frames
        .iter()
        .map(|pose| {
            geometry
                .worst_gap(&geometry.link_gaps(pose))
                .map(|g| (g.links.0 + 1, g.links.1 + 1, g.gap))
        })
        .collect()
}

/// Per picked row, each joint's `value / limit(joint)`, flat (`null` for
/// the whole list when a picked row has no values, or the problem fewer
/// limits than joints).
fn fractions(
    t: &Trajectory,
    picks: &[usize],
    value: fn(&TrajectoryRow) -> Option<&Vec<f64>>,
    limit: impl Fn(usize) -> Option<f64>,
) -> String {
    let Some(limits) = (0..t.joints).map(limit).collect::<Option<Vec<f64>>>() else {
        return "null".into();
    };
    let mut flat = Vec::with_capacity(picks.len() * t.joints);
    for &k in picks {
        match value(&t.rows[k]) {
            Some(v) if v.len() == t.joints => {
                flat.extend(v.iter().zip(&limits).map(|(x, l)| Some(x / l)))
            }
            _ => return "null".into(),
        }
    }
    list(flat)
}

/// Per picked row, the robot's fitted collision capsules as
/// `[ax,ay,az,bx,by,bz,r]` lists, to 6 decimals (the page draws them; a
/// test checks them against the link capsules); `null` for a robot without
/// a URDF.
fn collision_json(problem: &Problem, t: &Trajectory, picks: &[usize]) -> String {
    if problem.urdf.is_none() {
        return "null".into();
    }
    let fine = |v: f64| format!("{}", (v * 1e6).round() / 1e6);
    let frames: Vec<String> = picks
        .iter()
        .map(|&k| {
            let capsules: Vec<String> = collision_capsules(problem, &t.rows[k].q)
                .iter()
                .map(|c| format!("[{}]", c.map(fine).join(",")))
                .collect();
            format!("[{}]", capsules.join(","))
        })
        .collect();
    format!("[{}]", frames.join(","))
}

/// The `RUN` object of a run's page.
pub fn run_json(problem: &Problem, t: &Trajectory) -> String {
    run_json_with(problem, t, ViewerOptions::default())
}

/// The `RUN` object, with `options`.
pub fn run_json_with(problem: &Problem, t: &Trajectory, options: ViewerOptions) -> String {
    let origins = origins(problem, t);
    let (centre, side) = bounds(problem, &origins);
    let escapes = t.escapes();
    // Where each escape started is always a frame.
    let starts: Vec<usize> = escapes.iter().map(|e| e.first).take(FRAMES / 4).collect();
    let mut picks = frames(&origins, FRAMES - starts.len());
    picks.extend(&starts);
    picks.sort_unstable();
    picks.dedup();
    let mut time = Vec::with_capacity(t.rows.len());
    let mut clock = 0.0;
    for r in &t.rows {
        clock += r.h;
        time.push(clock);
    }
    let joints = origins.first().map_or(0, Vec::len);
    let rows = |f: &dyn Fn(usize) -> Option<f64>| list(picks.iter().map(|&k| f(k)));
    let mut s = String::from("{\n");
    let _ = writeln!(s, "\"name\": {},", string(&problem.name));
    let _ = writeln!(s, "\"unit\": {},", string(&problem.length_unit));
    let _ = writeln!(s, "\"steps\": {},", t.rows.last().map_or(0, |r| r.step));
    let _ = writeln!(s, "\"frames\": {},", picks.len());
    let _ = writeln!(s, "\"joints\": {joints},");
    let _ = writeln!(s, "\"centre\": {},", list(centre.map(Some)));
    let _ = writeln!(
        s,
        "\"side\": {},",
        list([Some(side)]).trim_matches(['[', ']'])
    );
    let _ = writeln!(s, "\"grid\": {},", nice_step(side, 8.0));
    let floor = origins
        .iter()
        .flatten()
        .map(|p| p[2])
        .chain(problem.waypoints.iter().map(|w| w.position[2] as f64))
        .fold(f64::INFINITY, f64::min);
    let _ = writeln!(
        s,
        "\"floor\": {},",
        list([Some(floor)]).trim_matches(['[', ']'])
    );
    let _ = writeln!(
        s,
        "\"radius\": {},",
        list([Some(0.012 * side)]).trim_matches(['[', ']'])
    );
    let engage = problem.settings.avoidance.engage_clearance as f64;
    let _ = writeln!(
        s,
        "\"engage\": {},",
        list([Some(engage)]).trim_matches(['[', ']'])
    );
    let _ = writeln!(s, "\"step\": {},", rows(&|k| Some(t.rows[k].step as f64)));
    let _ = writeln!(s, "\"time\": {},", rows(&|k| Some(time[k])));
    let _ = writeln!(s, "\"v\": {},", rows(&|k| t.rows[k].v));
    let _ = writeln!(
        s,
        "\"position_error\": {},",
        rows(&|k| t.rows[k].position_error)
    );
    let _ = writeln!(
        s,
        "\"orientation_error\": {},",
        rows(&|k| t.rows[k].orientation_error)
    );
    let _ = writeln!(s, "\"clearance\": {},", rows(&|k| t.rows[k].clearance));
    let names: Vec<String> = (0..t.joints)
        .map(|j| {
            string(
                problem
                    .joint_names
                    .get(j)
                    .filter(|n| !n.is_empty())
                    .map_or(&format!("joint {}", j + 1), |n| n),
            )
        })
        .collect();
    let _ = writeln!(s, "\"joint_names\": [{}],", names.join(","));
    let limits = &problem.drive.joints;
    let _ = writeln!(
        s,
        "\"velocity_fraction\": {},",
        fractions(
            t,
            &picks,
            |r| r.velocity.as_ref(),
            |j| limits.get(j).map(|l| l.max_rate)
        )
    );
    let _ = writeln!(
        s,
        "\"acceleration_fraction\": {},",
        fractions(
            t,
            &picks,
            |r| r.acceleration.as_ref(),
            |j| limits.get(j).map(|l| l.max_accel)
        )
    );
    let phrases: Vec<String> = picks
        .iter()
        .map(|&k| {
            t.rows[k]
                .escape
                .and_then(|e| escape_phrase(problem, e))
                .map_or("null".into(), |p| string(&p))
        })
        .collect();
    let _ = writeln!(s, "\"escape\": [{}],", phrases.join(","));
    s.push_str("\"escapes\": [");
    for (i, e) in escapes.iter().enumerate() {
        let path = origins[e.first..=e.end(origins.len())]
            .iter()
            .filter_map(|o| o.last())
            .flat_map(|p| p.map(Some));
        let phrase = t.rows[e.first]
            .escape
            .and_then(|x| escape_phrase(problem, x))
            .unwrap_or_default();
        let _ = write!(
            s,
            "{}{{\"kind\": {}, \"colour\": {}, \"step\": {}, \"text\": {}, \"path\": {}}}",
            if i > 0 { ",\n" } else { "\n" },
            string(e.kind.name()),
            string(&hex(escape_color(e.kind))),
            e.step,
            string(&phrase),
            list(path),
        );
    }
    s.push_str("],\n");
    let flat = picks
        .iter()
        .flat_map(|&k| origins[k].iter().flatten().map(|v| Some(*v)));
    let _ = writeln!(s, "\"origins\": {},", list(flat));
    let axes = picks.iter().flat_map(|&k| {
        let m = forward(problem, &t.rows[k].q).1;
        // Columns: the end effector's x, y and z axes.
        [0, 1, 2]
            .into_iter()
            .flat_map(move |c| (0..3).map(move |r| Some(m[r][c])))
    });
    let _ = writeln!(s, "\"end_axes\": {},", list(axes));
    let _ = writeln!(
        s,
        "\"capsules\": {},",
        list(problem.links.radius.iter().map(|&r| Some(r as f64)))
    );
    let _ = writeln!(s, "\"self_collision\": {},", problem.links.enabled);
    let _ = writeln!(s, "\"capsules_shown\": {},", options.capsules_shown);
    let collision = match options.collision_capsules {
        true => collision_json(problem, t, &picks),
        false => "null".into(),
    };
    let _ = writeln!(s, "\"collision_capsules\": {collision},");
    let geometry = Geometry::new(problem);
    let shown: Vec<Pose> = picks.iter().map(|&k| geometry.pose(&t.rows[k].q)).collect();
    let segments = match problem.links.segments.is_empty() {
        true => "null".into(),
        false => list(
            shown
                .iter()
                .flat_map(|p| p.capsules.iter().flatten().flatten().map(|v| Some(*v))),
        ),
    };
    let _ = writeln!(s, "\"link_segments\": {segments},");
    let pairs: Vec<String> = closest_links(&geometry, &shown)
        .into_iter()
        .map(|p| match p {
            Some((a, b, gap)) => {
                format!("[{a},{b},{}]", list([Some(gap)]).trim_matches(['[', ']']))
            }
            None => "null".into(),
        })
        .collect();
    let _ = writeln!(s, "\"closest_links\": [{}],", pairs.join(","));
    let stride = (origins.len() / 2000).max(1);
    let path = origins
        .iter()
        .step_by(stride)
        .chain(origins.last())
        .filter_map(|o| o.last())
        .flat_map(|p| p.map(Some));
    let _ = writeln!(s, "\"path\": {},", list(path));
    s.push_str("\"waypoints\": [");
    for (i, w) in problem.waypoints.iter().enumerate() {
        let axes = match w.orientation {
            // Rows r11 r12 r13 / ...: columns are the wanted axes.
            Some(r) => list(
                [0, 1, 2]
                    .into_iter()
                    .flat_map(|c| (0..3).map(move |row| Some(r[row][c] as f64))),
            ),
            None => "null".into(),
        };
        let _ = write!(
            s,
            "{}{{\"position\": {}, \"axes\": {axes}}}",
            if i > 0 { ", " } else { "" },
            list(w.position.map(|v| Some(v as f64))),
        );
    }
    s.push_str("],\n\"obstacles\": [\n");
    for o in 0..problem.obstacles.len() {
        let name = problem
            .obstacle_names
            .get(o)
            .filter(|n| !n.is_empty())
            .cloned()
            .unwrap_or_else(|| format!("obstacle {}", o + 1));
        let sep = if o > 0 { ", " } else { "" };
        if let Some(faces) = hull_faces(problem, o) {
            // A hull: its face triangles (fans) with their own corners, so
            // each face is shaded flat, and each face's outline.
            let triangles = faces
                .iter()
                .flat_map(|f| (1..f.len() - 1).flat_map(move |k| [f[0], f[k], f[k + 1]]));
            let outlines: Vec<String> = faces
                .iter()
                .map(|f| list(f.iter().chain(f.first()).flatten().map(|v| Some(*v))))
                .collect();
            let _ = writeln!(
                s,
                "{sep}{{\"name\": {}, \"triangles\": {}, \"outlines\": [{}]}}",
                string(&name),
                list(triangles.flatten().map(Some)),
                outlines.join(", "),
            );
            continue;
        }
        let xyz = surface(problem, o, LAT, LON);
        let _ = writeln!(
            s,
            "{sep}{{\"name\": {}, \"lat\": {LAT}, \"lon\": {LON}, \"xyz\": {}}}",
            string(&name),
            list(xyz.iter().flatten().map(|v| Some(*v))),
        );
    }
    s.push_str("]\n}");
    s
}

/// A run's page.
pub fn viewer(problem: &Problem, t: &Trajectory) -> String {
    viewer_with(problem, t, ViewerOptions::default())
}

/// The page, with `options`.
pub fn viewer_with(problem: &Problem, t: &Trajectory, options: ViewerOptions) -> String {
    format!(
        r#"<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<meta name="viewport" content="width=device-width, initial-scale=1">
<title>loading {name}</title>
<style>
html, body {{ margin: 0; height: 100%; overflow: hidden; background: #f4f6f9;
  font: 13px "DejaVu Sans", Verdana, sans-serif; color: #1e1e1e; }}
#view {{ position: absolute; inset: 0; }}
#hud {{ position: absolute; left: 12px; top: 12px; width: 310px; padding: 10px 12px;
  max-height: calc(100% - 46px); overflow-y: auto;
  background: rgba(255, 255, 255, 0.93); border: 1px solid #c8ccd4; border-radius: 6px; }}
#hud h1 {{ font-size: 15px; margin: 0 0 8px; }}
#controls {{ display: flex; gap: 6px; align-items: center; margin-bottom: 8px; }}
#seek {{ flex: 1; }}
table {{ border-collapse: collapse; width: 100%; margin-bottom: 8px; }}
td {{ padding: 1px 0; }} td.value {{ text-align: right; font-variant-numeric: tabular-nums; }}
.swatch {{ display: inline-block; width: 12px; height: 12px; margin-right: 6px; vertical-align: -1px; border-radius: 2px; }}
#legend div {{ margin: 2px 0; }}
#escape {{ margin: -4px 0 8px; min-height: 16px; }}
#options {{ margin: -2px 0 8px; }} #options input {{ margin: 0 4px 0 0; vertical-align: -2px; }}
.help {{ color: #667; font-size: 11px; margin-top: 8px; }}
#drive {{ margin: 0 0 8px; }}
#drive .caption {{ font-size: 11px; color: #445; margin-bottom: 3px; }}
#drive-bars {{ position: relative; height: 64px; display: flex; align-items: flex-end; gap: 3px;
  border-bottom: 1px solid #889; }}
#drive-bars .joint {{ flex: 1; height: 100%; display: flex; align-items: flex-end; gap: 1px; }}
#drive-bars .bar {{ flex: 1; min-height: 0; }}
#drive-bars .velocity {{ background: #0072b2; }} #drive-bars .acceleration {{ background: #e69f00; }}
#drive-bars .over {{ background: #be1e2d; }}
#drive-limit {{ position: absolute; left: 0; right: 0; bottom: 80%; border-top: 1px dashed #be1e2d; }}
#drive-limit span {{ position: absolute; right: 0; top: -13px; font-size: 10px; color: #be1e2d; }}
#drive-joints {{ display: flex; gap: 3px; font-size: 9px; color: #667; }}
#drive-joints span {{ flex: 1; text-align: center; overflow: hidden; }}
#drive-none {{ font-size: 11px; color: #667; }}
</style></head>
<body>
<div id="view"></div>
<div id="hud">
<h1>{name}</h1>
<div id="controls"><button id="play">pause</button><input id="seek" type="range" min="0" value="0"></div>
<div id="options"><label><input type="checkbox" id="capsules"> link capsules (what self-collision keeps apart)</label></div>
<table id="now"></table>
<div id="drive"><div class="caption"><span class="swatch" style="background:#0072b2"></span>|velocity| / rate limit &nbsp; <span class="swatch" style="background:#e69f00"></span>|acceleration| / acceleration limit, per joint (red: over)</div>
<div id="drive-bars"><div id="drive-limit"><span>limit 1</span></div></div>
<div id="drive-joints"></div><div id="drive-none"></div></div>
<div id="escape"><span class="swatch" id="escape-swatch"></span><span id="escape-text"></span></div>
<div id="legend"></div>
<div class="help">drag: orbit &middot; right-drag or shift-drag: pan &middot; wheel: zoom &middot; space: play / pause &middot; &larr; &rarr;: step &middot; h: home view &middot; c: link capsules &middot; viewer.html#frame=N opens at frame N, #capsules with the capsules shown</div>
</div>
<script>
{three}
</script>
<script>
const RUN = {run};
</script>
<script>
{viewer}
</script>
</body></html>
"#,
        name = escape(&problem.name),
        three = THREE_JS.trim_end(),
        run = run_json_with(problem, t, options),
        viewer = VIEWER_JS.trim_end(),
    )
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn numbers_and_strings_are_json() {
        let mut s = String::new();
        for v in [
            Some(0.0),
            Some(1.5),
            Some(-2.25e-7),
            Some(f64::NAN),
            None,
            Some(1e9),
        ] {
            num(v, &mut s);
            s.push(' ');
        }
        assert_eq!(s, "0 1.5 -2.2500e-7 null null 1.0000e9 ");
        assert_eq!(string("a\"b</script>"), "\"a\\\"b\\u003c/script>\"");
    }
}
