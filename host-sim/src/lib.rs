//! # capp-sim: the host-side CAPP simulator
//!
//! Loads a planning problem (a TOML scenario, or the listing's own `input.dat`),
//! runs `capp-core` on it, writes the results (trajectory CSV, the decimated
//! setpoint stream, `joints.dat`, a summary), checks a trajectory independently
//! of the planner, and draws pictures of it; or has a board (or the firmware
//! under QEMU) plan it and receives the stream ([`serial`]). The `capp`
//! binary is [`cli`], a thin command-line front end over these modules.
//!
//! | module | owns |
//! |---|---|
//! | [`problem`] | the loaded problem (core types + start + settings) and its validation, with file/line errors; a leaf the readers build on |
//! | [`input`] | reading a problem from a file: [`Problem::load`] picks the reader by file kind |
//! | [`input::scenario_file`] | the TOML scenario format (documented in `docs/scenario.md`) |
//! | [`input::legacy`] | CAPP.c's `input.dat` reader and `joints.dat` writer |
//! | [`plan`] | running the planner and recording every step |
//! | [`escapes`] | where a run escaped dead ends (walks, detours, the return), and the CSV's `escape` column |
//! | [`output`] | the output folder: CSVs, `joints.dat`, summary, written atomically |
//! | [`output::summary`] | the run summary text (stdout and `summary.txt`) |
//! | [`trajectory`] | reading a trajectory CSV back |
//! | [`geometry`] | the independent f64 model of the robot, obstacles and link capsules (own kinematics, own super-ellipsoids, own segment distance), used by [`check`], the summary, [`render`] and the suite |
//! | [`polytope`] | convex hulls in f64: a mesh's hull (its corners) for `shape = "mesh"`, a hull's faces and exact signed distance for [`geometry`] |
//! | [`check`] | the independent trajectory checker (limits, rates, kinematics, clearance, self-collision), on [`geometry`] |
//! | [`drive_check`] | whether a trajectory is motion a joint drive can follow (issue 22): the fixed period, rate, acceleration and jerk from positions, at rest on arrival, braking stops clear; the *drive figures* of [`check`]'s report |
//! | [`render`] | SVG/PNG pictures with text, the 3-D `viewer.html`, `motion.gif`, report charts |
//! | [`serial`] | `capp serial`: upload to a board, receive its stream, account for every setpoint |
//! | [`cli`] | the `capp` command line |
//!
//! Units: radians, the scenario's length unit, seconds, everywhere after loading.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod acm;
pub mod check;
pub mod cli;
pub mod decompose;
pub mod drive_check;
pub mod enclosure;
pub mod escapes;
pub mod geometry;
pub mod input;
pub mod mesh_parts;
pub mod output;
pub mod plan;
pub mod polytope;
pub mod problem;
pub mod render;
pub mod robot_report;
pub mod serial;
pub mod trajectory;

pub use problem::{LoadError, Problem};
