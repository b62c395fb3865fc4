//! `capp robot SCENARIO`: the robot as the planner sees it. The chain (a DH
//! table, or general joints with their origins as `xyz` and `rpy`, axes and
//! the tool), every joint's limits and rate, the reach bound, and per link
//! the capsule the planner checks (its chord, or its segment in its body's
//! frame when the scenario gives one, and its radius) with, for a URDF
//! robot, the capsules fitted to the link's `<collision>` geometry that the
//! radius encloses.

use std::fmt::Write;

use capp_core::robot::Placement;
use capp_core::JointKind;

use crate::geometry::link_segment;
use crate::problem::{LoadError, Problem};

/// `(x, y, z)` with 4 decimals.
fn xyz(v: [f64; 3]) -> String {
    format!("{:.4} {:.4} {:.4}", v[0], v[1], v[2])
}

/// URDF's `rpy` of a rotation (`R = Rz(yaw) Ry(pitch) Rx(roll)`), radians.
pub fn rpy(r: &[[f32; 3]; 3]) -> [f64; 3] {
    let m = |i: usize, j: usize| r[i][j] as f64;
    let pitch = (-m(2, 0)).clamp(-1.0, 1.0).asin();
    if m(2, 0).abs() < 1.0 - 1e-9 {
        [m(2, 1).atan2(m(2, 2)), pitch, m(1, 0).atan2(m(0, 0))]
    } else {
        // Gimbal lock: all of the turn about z as yaw.
        [0.0, pitch, (-m(0, 1)).atan2(m(1, 1))]
    }
}

fn placement(p: &Placement) -> String {
    format!(
        "xyz {}  rpy {}",
        xyz(p.translation.map(f64::from)),
        xyz(rpy(&p.rotation))
    )
}

/// The report `capp robot` prints.
pub fn report(problem: &Problem) -> Result<String, LoadError> {
    let robot = problem
        .robot()
        .map_err(|e| LoadError::new(&problem.source, problem.lines.robot, format!("robot: {e}")))?;
    let unit = &problem.length_unit;
    let mut out = String::new();
    let n = problem.joints.len();
    let _ = match &problem.urdf {
        Some(u) => writeln!(
            out,
            "{}: robot \"{}\" from {}, {} -> {}: {n} moving joints (general joints; lengths in {unit}, angles in radians)",
            problem.name,
            u.robot_name,
            u.file.display(),
            u.base_link,
            u.tip_link
        ),
        None => writeln!(
            out,
            "{}: {n} joints (DH rows, eq. 5; lengths in {unit}, angles in radians)",
            problem.name
        ),
    };
    let name = |k: usize| {
        problem
            .joint_names
            .get(k)
            .filter(|s| !s.is_empty())
            .cloned()
            .unwrap_or_else(|| format!("joint {}", k + 1))
    };
    let _ = writeln!(out, "\njoints:");
    for (k, j) in problem.joints.iter().enumerate() {
        let kind = match j.kind {
            JointKind::Revolute => "revolute",
            JointKind::Prismatic => "prismatic",
        };
        let rate_unit = match j.kind {
            JointKind::Revolute => "rad/s".to_string(),
            JointKind::Prismatic => format!("{unit}/s"),
        };
        let _ = writeln!(
            out,
            "  {:>2} {:<22} {kind:<9}  limits [{:.4}, {:.4}]  max_rate {} {rate_unit}  weight {}",
            k + 1,
            name(k),
            j.min,
            j.max,
            j.max_rate,
            j.weight
        );
        let slide = problem
            .urdf
            .as_ref()
            .and_then(|u| u.pivot_slide.get(k))
            .filter(|s| **s != 0.0)
            .map(|s| format!("  (pivot slid {s:+.4} m along the axis from the URDF's origin)"))
            .unwrap_or_default();
        let _ = match j.origin {
            Some(o) => writeln!(
                out,
                "     origin {}  axis {}{slide}",
                placement(&o.placement),
                xyz(o.axis.map(f64::from))
            ),
            None => writeln!(
                out,
                "     DH alpha {:.4}  a {:.4}  theta {:.4}  d {:.4}",
                j.alpha, j.a, j.theta, j.d
            ),
        };
    }
    if !problem.tool.is_identity() {
        let _ = writeln!(
            out,
            "  tool (the tip's frame in the last joint's): {}",
            placement(&problem.tool)
        );
    }
    let _ = writeln!(
        out,
        "\nreach bound: {:.4} {unit} (the longest the arm can stretch from the base)",
        robot.reach()
    );
    let _ = match problem.links.segments.is_empty() {
        true => writeln!(
            out,
            "\nlink capsules (the chord from each joint's pivot to the next, or to the end effector; the radius the self-collision checks use):"
        ),
        false => writeln!(
            out,
            "\nlink capsules (each link's segment, fixed in the frame of the body its joint moves, and the radius the self-collision checks use):"
        ),
    };
    // A link capsule this many times the body's thickest fitted capsule is
    // reported as round a segment that misses its body.
    const CHORD_OFF_BODY: f64 = 1.5;
    for k in 0..n {
        let radius = problem.links.radius.get(k).copied().unwrap_or(0.0);
        let segment = link_segment(&problem.joints, &problem.links.segments, k);
        let _ = match segment {
            Some([a, b]) => writeln!(
                out,
                "  {:<40} segment a {}  b {} ({unit}, in joint \"{}\"'s frame), radius {radius:.4} {unit}",
                problem.link_label(k),
                xyz(a),
                xyz(b),
                name(k)
            ),
            None => writeln!(
                out,
                "  {:<40} chord up to {:.4} {unit}, radius {radius:.4} {unit}",
                problem.link_label(k),
                robot.longest_link(k)
            ),
        };
        if let Some(body) = problem.urdf.as_ref().and_then(|u| u.bodies.get(k + 1)) {
            let _ = writeln!(
                out,
                "     URDF links {}: {} collision capsules (metres, in joint \"{}\"'s frame):",
                body.links.join(", "),
                body.capsules.len(),
                name(k)
            );
            for c in &body.capsules {
                let _ = writeln!(
                    out,
                    "       a {}  b {}  radius {:.4}",
                    xyz([c.a.x, c.a.y, c.a.z]),
                    xyz([c.b.x, c.b.y, c.b.z]),
                    c.radius
                );
            }
            // Where the body lies off the checked segment (the chord, or
            // the link's own), the capsule round it is much fatter than
            // the body: say so, since it is what self-collision checks (a
            // start refused as links touching, a dead end at a pair's
            // floor). Fitted capsules are in metres, the radius in `unit`.
            let thickest = body.capsules.iter().map(|c| c.radius).fold(0.0, f64::max);
            let checked = radius as f64 / problem.urdf.as_ref().map_or(1.0, |u| u.per_metre);
            if thickest > 0.0 && checked >= CHORD_OFF_BODY * thickest {
                let _ = writeln!(
                    out,
                    "     the {} misses this body: its capsule is {:.1} times as thick as the body's thickest, and self-collision checks the capsule",
                    if segment.is_some() { "segment" } else { "chord" },
                    checked / thickest
                );
            }
        }
    }
    if let Some(base) = problem.urdf.as_ref().and_then(|u| u.bodies.first()) {
        let _ = writeln!(
            out,
            "  base ({}): {} collision capsules, not checked (no link before the first joint)",
            base.links.join(", "),
            base.capsules.len()
        );
    }
    Ok(out)
}
