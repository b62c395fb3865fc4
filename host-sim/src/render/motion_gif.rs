//! `motion.gif`: the three views with the arm moving, the step's `V`, error
//! and clearance in the corner; loops forever.
//!
//! Every frame is painted over the same page (obstacles, path, ticks), mapped
//! to one 255-colour palette (NeuQuant over the page and a few frames, so it
//! is the same on every machine) and stored as the rectangle that changed
//! since the previous frame, its unchanged pixels transparent.

use std::collections::HashMap;

use anyhow::Result;
use color_quant::NeuQuant;

use super::canvas::{Anchor, Pixmap, Shape};
use super::views::{arm_scene, frames, END};
use super::{format_value, status_line};
use crate::problem::Problem;
use crate::trajectory::Trajectory;

/// Frames of the motion (plus a held last frame).
pub const FRAMES: usize = 90;
/// Side of each view in the GIF, pixels.
const PANEL: f64 = 300.0;
/// Delay between frames, 1/100 s.
const DELAY: u16 = 7;
/// How long the last frame is held, 1/100 s.
const HOLD: u16 = 250;
/// The palette index of "unchanged since the last frame" (transparent).
const UNCHANGED: u8 = 255;

/// The GIF file's bytes.
pub fn motion_gif(problem: &Problem, t: &Trajectory) -> Result<Vec<u8>> {
    let scene = arm_scene(problem, t, PANEL, 0);
    let base = scene.canvas.pixmap();
    let (w, h) = (base.width, base.height);
    let picks = frames(&scene.origins, FRAMES);
    let paint = |k: usize| -> Pixmap {
        let mut px = base.clone();
        for p in &scene.panels {
            let pts: Vec<_> = scene.origins[k].iter().map(|q| p.map(q)).collect();
            px.draw(&Shape::line(pts.clone(), END, 3.0).clipped(p.clip()));
            for &c in &pts {
                px.draw(&Shape::Disc {
                    centre: c,
                    radius: 2.0,
                    color: [60, 20, 20],
                });
            }
        }
        let row = &t.rows[k];
        px.draw(
            &Shape::text(
                (w as f64 - 24.0, 26.0),
                13.0,
                format!(
                    "step {} of {}",
                    row.step,
                    t.rows.last().map_or(0, |r| r.step)
                ),
            )
            .anchored(Anchor::End),
        );
        px.draw(
            &Shape::text(
                (w as f64 - 24.0, 46.0),
                11.5,
                status_line(problem, row, format_value),
            )
            .anchored(Anchor::End)
            .colored([60, 60, 60]),
        );
        px
    };

    // Palette from the page and three frames.
    let mut sample: Vec<u8> = Vec::new();
    let sampled: Vec<usize> = [0, picks.len() / 2, picks.len().saturating_sub(1)]
        .iter()
        .filter_map(|&i| picks.get(i).copied())
        .collect();
    for px in std::iter::once(base.clone()).chain(sampled.iter().map(|&k| paint(k))) {
        for c in px.rgb.chunks(3) {
            sample.extend_from_slice(&[c[0], c[1], c[2], 255]);
        }
    }
    // 255 colours; index 255 is transparent: "unchanged since the last frame".
    let quant = NeuQuant::new(10, 255, &sample);
    let mut palette = quant.color_map_rgb();
    palette.resize(256 * 3, 0);
    let mut cache: HashMap<[u8; 3], u8> = HashMap::new();
    let mut index = |px: &Pixmap| -> Vec<u8> {
        px.rgb
            .chunks(3)
            .map(|c| {
                let key = [c[0], c[1], c[2]];
                *cache
                    .entry(key)
                    .or_insert_with(|| quant.index_of(&[c[0], c[1], c[2], 255]) as u8)
            })
            .collect()
    };

    let mut out = Vec::new();
    {
        let mut enc = gif::Encoder::new(&mut out, w as u16, h as u16, &palette)?;
        enc.set_repeat(gif::Repeat::Infinite)?;
        let mut previous: Option<Vec<u8>> = None;
        for (f, &k) in picks.iter().enumerate() {
            let now = index(&paint(k));
            let (x0, y0, x1, y1) = match &previous {
                None => (0, 0, w, h),
                Some(prev) => changed(prev, &now, w, h).unwrap_or((0, 0, 1, 1)),
            };
            let mut buffer = Vec::with_capacity((x1 - x0) * (y1 - y0));
            for y in y0..y1 {
                let row = y * w + x0..y * w + x1;
                match &previous {
                    Some(prev) => {
                        buffer.extend(now[row.clone()].iter().zip(&prev[row]).map(|(&n, &p)| {
                            if n == p {
                                UNCHANGED
                            } else {
                                n
                            }
                        }))
                    }
                    None => buffer.extend_from_slice(&now[row]),
                }
            }
            let frame = gif::Frame {
                left: x0 as u16,
                top: y0 as u16,
                width: (x1 - x0) as u16,
                height: (y1 - y0) as u16,
                buffer: buffer.into(),
                delay: if f + 1 == picks.len() { HOLD } else { DELAY },
                dispose: gif::DisposalMethod::Keep,
                transparent: previous.is_some().then_some(UNCHANGED),
                ..gif::Frame::default()
            };
            enc.write_frame(&frame)?;
            previous = Some(now);
        }
    }
    Ok(out)
}

/// Bounding box `(x0, y0, x1, y1)` (exclusive ends) of the pixels that differ.
fn changed(a: &[u8], b: &[u8], w: usize, h: usize) -> Option<(usize, usize, usize, usize)> {
    let (mut x0, mut y0, mut x1, mut y1) = (w, h, 0, 0);
    for y in 0..h {
        let (ra, rb) = (&a[y * w..(y + 1) * w], &b[y * w..(y + 1) * w]);
        if ra == rb {
            continue;
        }
        let first = ra.iter().zip(rb).position(|(p, q)| p != q).unwrap_or(0);
        let last = w - ra
            .iter()
            .zip(rb)
            .rev()
            .position(|(p, q)| p != q)
            .unwrap_or(0);
        x0 = x0.min(first);
        x1 = x1.max(last);
        y0 = y0.min(y);
        y1 = y + 1;
    }
    (x1 > x0).then_some((x0, y0, x1, y1))
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_changed_box_bounds_every_difference() {
        let a = vec![0u8; 20];
        let mut b = a.clone();
        assert_eq!(changed(&a, &b, 5, 4), None);
        b[5 + 1] = 1;
        b[3 * 5 + 3] = 1;
        assert_eq!(changed(&a, &b, 5, 4), Some((1, 1, 4, 4)));
    }
}
