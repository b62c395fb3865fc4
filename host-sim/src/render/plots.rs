//! `V`, the errors and the clearance against step, on log scales, with
//! titles, units, ticks and legends; the steps spent escaping dead ends
//! shaded (a band per walk, detour or return, in its colour of `arm.png`).

use super::canvas::{Canvas, Rgb, Shape, P2};
use super::chart::{Axes, Marker, Scale, PALETTE};
use super::views::{escape_color, escape_legend, lerp};
use crate::escapes::Stretch;
use crate::problem::Problem;
use crate::trajectory::Trajectory;

type Series = (String, Rgb, Vec<Option<f64>>);

/// The pale fill of an escape band (opaque, so it lies under the grid).
pub fn band_color(stretch: &Stretch) -> Rgb {
    lerp(escape_color(stretch.kind), [255, 255, 255], 0.72)
}

/// The three stacked panels.
pub fn plots(problem: &Problem, t: &Trajectory) -> Canvas {
    let (w, ph, left, right) = (900.0, 170.0, 78.0, 24.0);
    let block = ph + 36.0 + 46.0;
    let top = 44.0;
    let mut canvas = Canvas::new(w as u32, (top + 3.0 * block) as u32);
    let unit = &problem.length_unit;
    canvas.push(
        Shape::text(
            (left, 24.0),
            16.0,
            format!("{}: V, errors and clearance against step", problem.name),
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
        // A band per escape: from the step it started to the step it ended.
        for e in &escapes {
            let from = steps[e.first];
            let to = steps[e.end(steps.len())].max(from + 0.5);
            let (Some(a), Some(mut b)) = (axes.map(from, axes.y.lo), axes.map(to, axes.y.hi))
            else {
                continue;
            };
            // At least 2 px, so a short one is still seen.
            b.0 = b.0.max(a.0 + 2.0);
            canvas.push(Shape::Polygon {
                points: vec![(a.0, a.1), (b.0, a.1), (b.0, b.1), (a.0, b.1)],
                fill: band_color(e),
                opacity: 1.0,
                clip: Some(rect),
            });
        }
        axes.draw(&mut canvas, title, "step", y_label);
        let mut items: Vec<(String, Rgb, Marker)> = Vec::new();
        for (name, color, values) in series {
            let stride = (values.len() / 3000).max(1);
            let mut run: Vec<P2> = Vec::new();
            let flush = |run: &mut Vec<P2>, canvas: &mut Canvas| {
                if run.len() >= 2 {
                    canvas.push(Shape::line(std::mem::take(run), *color, 1.5).clipped(rect));
                }
                run.clear();
            };
            for (s, v) in steps.iter().zip(values).step_by(stride) {
                match v.and_then(|v| axes.map(*s, v)) {
                    Some(p) => run.push(p),
                    None => flush(&mut run, &mut canvas),
                }
            }
            flush(&mut run, &mut canvas);
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
    canvas
}
