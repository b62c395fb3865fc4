//! # capp-suite: how often, how fast and how safely the planner gets there
//!
//! Seeded families of planning cases, each an ordinary scenario file; an
//! RRT-Connect oracle that certifies which cases are solvable; every
//! planner variant run on every case exactly as `capp run` would; the report
//! (`PLANNING.md`, `cargo xtask suite`).
//!
//! | module | owns |
//! |---|---|
//! | [`rng`] | the seeded generator (splitmix64) |
//! | [`case`] | the case and its scenario file (TOML writer) |
//! | [`families`] | the eight families and the scene building they share |
//! | [`oracle`] | RRT-Connect with dense independent collision checks, shortcuts |
//! | [`variants`] | the planner variants compared side by side |
//! | [`metrics`] | what one run is measured by (safety from the independent checker) |
//! | [`runner`] | planning every case with every variant on a few threads |
//! | [`report`] | the markdown tables and the per-case CSV |
//! | [`figures`] | the report's charts (reach rate, motion time against the RRT path) |
//! | [`cli`] | `cargo xtask suite` |
//!
//! Nothing here is used by the planner; the planner code under test is
//! `capp-core`, driven through `capp-sim` as the simulator drives it.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod case;
pub mod cli;
pub mod families;
pub mod figures;
pub mod metrics;
pub mod oracle;
pub mod report;
pub mod rng;
pub mod runner;
pub mod variants;
