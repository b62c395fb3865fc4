//! `V`, the errors and the clearance against step, on log scales, with
//! titles, units, ticks and legends; below them what the drives are asked
//! for: each joint's velocity as a fraction of its rate limit and its
//! acceleration as a fraction of its acceleration limit (`Problem::drive`),
//! on linear scales with the limits `±1` dashed. The steps spent escaping
//! dead ends are shaded in every panel (a band per walk, detour or return,
//! in its colour of `arm.png`).

use super::canvas::{Anchor, Canvas, Clip, Rgb, Shape, P2};
use super::chart::{Axes, Marker, Scale, PALETTE};
use super::views::{escape_color, escape_legend, lerp};
use crate::escapes::Stretch;
use crate::problem::Problem;
use crate::trajectory::{Trajectory, TrajectoryRow};

type Series = (String, Rgb, Vec<Option<f64>>);

/// The pale fill of an escape band (opaque, so it lies under the grid).
pub fn band_color(stretch: &Stretch) -> Rgb {
    lerp(escape_color(stretch.kind), [255, 255, 255], 0.72)
}

/// The colour of the drive limits' `±1` lines.
pub const LIMIT: Rgb = [190, 30, 45];

/// Draws `values` (against `steps`) as lines, broken where a value is
/// missing or off the scale; at most about 3000 points.
fn series(
    canvas: &mut Canvas,
    axes: &Axes,
    steps: &[f64],
    values: &[Option<f64>],
    style: (Rgb, f64),
) {
    let (color, width) = style;
    let stride = (values.len() / 3000).max(1);
    let mut run: Vec<P2> = Vec::new();
    let flush = |run: &mut Vec<P2>, canvas: &mut Canvas| {
        if run.len() >= 2 {
            canvas.push(Shape::line(std::mem::take(run), color, width).clipped(axes.rect));
        }
        run.clear();
    };
    for (s, v) in steps.iter().zip(values).step_by(stride) {
        match v.and_then(|v| axes.map(*s, v)) {
            Some(p) => run.push(p),
            None => flush(&mut run, canvas),
        }
    }
    flush(&mut run, canvas);
}

/// A band per escape, from the step it started to the step it ended.
fn escape_bands(canvas: &mut Canvas, axes: &Axes, steps: &[f64], escapes: &[Stretch]) {
    for e in escapes {
        let from = steps[e.first];
        let to = steps[e.end(steps.len())].max(from + 0.5);
        let (Some(a), Some(mut b)) = (axes.map(from, axes.y.lo), axes.map(to, axes.y.hi)) else {
            continue;
        };
        // At least 2 px, so a short one is still seen.
        b.0 = b.0.max(a.0 + 2.0);
        canvas.push(Shape::Polygon {
            points: vec![(a.0, a.1), (b.0, a.1), (b.0, b.1), (a.0, b.1)],
            fill: band_color(e),
            opacity: 1.0,
            clip: Some(axes.rect),
        });
    }
}

/// One of the drive panels: per joint, `value(row)[j] / limit[j]`.
struct DrivePanel<'a> {
    title: &'a str,
    y_label: &'a str,
    /// What the fraction is of, for the legend (`"rate"`).
    quantity: &'a str,
    value: fn(&TrajectoryRow) -> Option<&Vec<f64>>,
    limit: Vec<f64>,
}

/// Each joint's fraction of its limit over the steps (a thin line per
/// joint), the limits `±1` dashed, the largest `|fraction|` marked and
/// named; a note instead when the trajectory has no such column.
fn drive_panel(
    canvas: &mut Canvas,
    problem: &Problem,
    t: &Trajectory,
    (rect, steps, escapes): (Clip, &[f64], &[Stretch]),
    panel: &DrivePanel,
) {
    let n = t.joints.min(panel.limit.len());
    let fractions: Vec<Vec<Option<f64>>> = (0..n)
        .map(|j| {
            t.rows
                .iter()
                .map(|r| {
                    (panel.value)(r)
                        .and_then(|v| v.get(j))
                        .map(|v| v / panel.limit[j])
                        .filter(|f| f.is_finite())
                })
                .collect()
        })
        .collect();
    // The largest |fraction| (the first row, then the first joint, at it):
    // joint, row, value.
    let mut peak: Option<(usize, usize, f64)> = None;
    for k in 0..t.rows.len() {
        for (j, f) in fractions.iter().enumerate() {
            if let Some(v) = f[k] {
                if peak.is_none_or(|p| v.abs() > p.2.abs()) {
                    peak = Some((j, k, v));
                }
            }
        }
    }
    let reach = peak.map_or(1.0, |p| p.2.abs()).max(1.0) * 1.1;
    let smax = steps.last().copied().unwrap_or(1.0).max(1.0);
    let axes = Axes::new(rect, Scale::linear(0.0, smax), Scale::linear(-reach, reach));
    escape_bands(canvas, &axes, steps, escapes);
    let x_label = match problem.settings.motion {
        capp_core::Motion::Tracked => format!(
            "step (tracked: t = step × {} s)",
            problem.drive.control_period_s
        ),
        capp_core::Motion::Stepped => "step".into(),
    };
    axes.draw(canvas, panel.title, &x_label, panel.y_label);
    let mut items: Vec<(String, Rgb, Marker)> = Vec::new();
    for f in [-1.0, 1.0] {
        if let (Some(a), Some(b)) = (axes.map(axes.x.lo, f), axes.map(axes.x.hi, f)) {
            canvas.push(Shape::line(vec![a, b], LIMIT, 1.2).dashed());
        }
    }
    items.push((
        format!("its {} limit, ±1", panel.quantity),
        LIMIT,
        Marker::Dashed,
    ));
    let Some((pj, pk, pv)) = peak else {
        let (x0, y0, x1, y1) = rect;
        canvas.push(
            Shape::text(
                ((x0 + x1) / 2.0, (y0 + y1) / 2.0 - 12.0),
                12.0,
                "not recorded: the trajectory has no such columns (written before them)",
            )
            .anchored(Anchor::Middle)
            .colored([90, 90, 90]),
        );
        axes.legend(canvas, &items);
        return;
    };
    for (j, f) in fractions.iter().enumerate() {
        series(canvas, &axes, steps, f, (PALETTE[j % PALETTE.len()], 1.2));
    }
    let name = |j: usize| {
        problem
            .joint_names
            .get(j)
            .filter(|s| !s.is_empty())
            .map_or(format!("joint {}", j + 1), |s| {
                format!("joint {} ({s})", j + 1)
            })
    };
    if n <= PALETTE.len() {
        for j in 0..n {
            items.push((name(j), PALETTE[j % PALETTE.len()], Marker::Line));
        }
    } else {
        items.push((
            format!(
                "{n} joints, a line each (colours repeat every {})",
                PALETTE.len()
            ),
            PALETTE[0],
            Marker::Line,
        ));
    }
    if let Some(at) = axes.map(steps[pk], pv) {
        canvas.push(Shape::Disc {
            centre: at,
            radius: 3.5,
            color: [30, 30, 30],
        });
        items.push((
            format!("largest: {pv:.3} at step {}, {}", t.rows[pk].step, name(pj)),
            [30, 30, 30],
            Marker::Dot,
        ));
    }
    axes.legend(canvas, &items);
}

/// The five stacked panels: `V`, the errors, the clearance; the joints'
/// velocities and accelerations against their limits.
pub fn plots(problem: &Problem, t: &Trajectory) -> Canvas {
    let (w, ph, left, right) = (900.0, 170.0, 78.0, 24.0);
    let block = ph + 36.0 + 46.0;
    let top = 44.0;
    let mut canvas = Canvas::new(w as u32, (top + 5.0 * block) as u32);
    let unit = &problem.length_unit;
    canvas.push(
        Shape::text(
            (left, 24.0),
            16.0,
            format!(
                "{}: V, errors, clearance and the joints' drive limits against step",
                problem.name
            ),
        )
        .colored([30, 30, 30]),
    );
    let steps: Vec<f64> = t.rows.iter().map(|r| r.step as f64).collect();
    let smax = steps.last().copied().unwrap_or(1.0).max(1.0);
    let column = |f: fn(&crate::trajectory::TrajectoryRow) -> Option<f64>| -> Vec<Option<f64>> {
        t.rows.iter().map(f).collect()
    };
    let engage = problem.settings.avoidance.engage_clearance as f64;
    let escapes = t.escapes();
    let panels: [(String, String, Vec<Series>); 3] = [
        (
            "Lyapunov function V (eq. 12, orientation weighted by λ²)".into(),
            format!("V [{unit}²]"),
            vec![("V".into(), PALETTE[0], column(|r| r.v))],
        ),
        (
            "errors to the active waypoint".into(),
            format!("position error [{unit}], orientation error [1]"),
            vec![
                (
                    format!("position [{unit}]"),
                    PALETTE[0],
                    column(|r| r.position_error),
                ),
                (
                    "orientation".into(),
                    PALETTE[1],
                    column(|r| r.orientation_error),
                ),
            ],
        ),
        (
            "clearance of the closest avoidance point (within the influence distance)".into(),
            "C − 1 [1] (0: on the inflated surface)".into(),
            vec![("C − 1".into(), PALETTE[2], column(|r| r.clearance))],
        ),
    ];
    for (i, (title, y_label, series)) in panels.iter().enumerate() {
        let y0 = top + 36.0 + i as f64 * block;
        let rect = (left, y0, w - right, y0 + ph);
        let mut values: Vec<f64> = series
            .iter()
            .flat_map(|s| s.2.iter().flatten().copied())
            .collect();
        if i == 2 && engage > 0.0 {
            values.push(engage);
        }
        let axes = Axes::new(
            rect,
            Scale::linear(0.0, smax),
            Scale::log_of(values.iter().copied()),
        );
        escape_bands(&mut canvas, &axes, &steps, &escapes);
        axes.draw(&mut canvas, title, "step", y_label);
        let mut items: Vec<(String, Rgb, Marker)> = Vec::new();
        for (name, color, values) in series {
            self::series(&mut canvas, &axes, &steps, values, (*color, 1.5));
            items.push((name.clone(), *color, Marker::Line));
        }
        if i == 2 && engage > 0.0 {
            if let (Some(a), Some(b)) = (axes.map(0.0, engage), axes.map(smax, engage)) {
                canvas.push(Shape::line(vec![a, b], [120, 120, 120], 1.0).dashed());
                items.push((
                    format!("engage_clearance = {engage}"),
                    [120, 120, 120],
                    Marker::Dashed,
                ));
            }
        }
        if i == 0 {
            // The escapes' kinds, once, in their pale band colours.
            for (name, color, _) in escape_legend(&escapes) {
                let pale = lerp(color, [255, 255, 255], 0.72);
                items.push((format!("{name} (shaded)"), pale, Marker::Bar));
            }
        }
        axes.legend(&mut canvas, &items);
    }
    let limits = &problem.drive.joints;
    let panels = [
        DrivePanel {
            title: "velocity / rate limit: each joint's velocity as a fraction of its max_rate",
            y_label: "velocity / rate limit [1]",
            quantity: "rate",
            value: |r| r.velocity.as_ref(),
            limit: limits.iter().map(|l| l.max_rate).collect(),
        },
        DrivePanel {
            title: "acceleration / acceleration limit: each joint's acceleration as a fraction of its max_accel",
            y_label: "acceleration / acceleration limit [1]",
            quantity: "acceleration",
            value: |r| r.acceleration.as_ref(),
            limit: limits.iter().map(|l| l.max_accel).collect(),
        },
    ];
    for (i, panel) in panels.iter().enumerate() {
        let y0 = top + 36.0 + (3 + i) as f64 * block;
        let rect = (left, y0, w - right, y0 + ph);
        drive_panel(&mut canvas, problem, t, (rect, &steps, &escapes), panel);
    }
    canvas
}
