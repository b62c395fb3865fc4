//! # capp-bench: what the benchmarks measure, shared by host and target
//!
//! `no_std`, so the same code builds the same scenarios (to the bit) for the
//! criterion benches on the host (`benches/step.rs`) and for the instruction
//! counter on the Cortex-M4F (`firmware/examples/step_count.rs`, under QEMU).
//! `BENCHMARKS.md` at the repository root has the method and the figures;
//! `cargo xtask bench` reproduces them.
//!
//! | module | owns |
//! |---|---|
//! | [`scenes`] | PIPS with k obstacles, chains of n joints with m obstacles, the warm-up |
//! | [`phases`] | one planner step cut into its phases (kinematics, control law, obstacles, projection and integration) |
//! | [`listing`] | the paper's listing (CAPP.c) in Rust: central differences over the whole chain, `powf` costs; the baseline |
#![no_std]
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod listing;
pub mod phases;
pub mod scenes;

pub use listing::Listing;
pub use phases::PhaseBench;
pub use scenes::{chain, pips, warm_up, Scene, SceneError};
