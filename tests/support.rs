//! Shared by the workspace-level tests: finding the firmware and QEMU.
//!
//! These tests boot the release firmware for `mps2-an386` under
//! `qemu-system-arm`. Where either is missing they are skipped with a
//! message, except when `CAPP_REQUIRE_QEMU` is set (`scripts/firmware.sh`
//! sets it after building the firmware): there a skip is a failure.
#![forbid(unsafe_code)]
#![warn(missing_docs)]

pub mod fault_proxy;

use std::path::PathBuf;
use std::process::ExitCode;

use capp_link::qemu::{default_elf, qemu_available};

/// `capp ARGS...` in process, exactly as the binary runs it.
pub fn capp(args: &[&str]) -> ExitCode {
    capp_sim::cli::main(std::iter::once("capp").chain(args.iter().copied()))
}

/// The firmware ELF to boot, or `None` (after saying why) if the test is to
/// be skipped. Panics if a skip is not allowed.
pub fn firmware_or_skip() -> Option<PathBuf> {
    let elf = default_elf();
    let required = std::env::var_os("CAPP_REQUIRE_QEMU").is_some();
    let missing = if !qemu_available() {
        Some("qemu-system-arm is not installed (apt-get install qemu-system-arm)".to_string())
    } else if !elf.exists() {
        Some(format!(
            "firmware ELF {} is missing (cd firmware && cargo build --release)",
            elf.display()
        ))
    } else {
        None
    };
    match missing {
        Some(why) => {
            assert!(!required, "CAPP_REQUIRE_QEMU is set but {why}");
            eprintln!("SKIPPED: {why}");
            None
        }
        None => Some(elf),
    }
}
