//! Picks the selected board's memory map and passes the linker scripts.
//!
//! * `mps2-an386` (default): the workspace's root `memory.x`;
//! * `nucleo-f446re`: `boards/nucleo-f446re/memory.x`.
//!
//! The chosen file is copied to `OUT_DIR/memory.x`, where cortex-m-rt's
//! `link.x` includes it from; for the mps2-an386, whose device module is the
//! firmware's own, also `boards/mps2-an386/device.x` (the F446's comes with
//! its PAC).

use std::{env, fs, path::PathBuf};

fn main() {
    let manifest = PathBuf::from(env::var("CARGO_MANIFEST_DIR").unwrap());
    let mps2 = env::var_os("CARGO_FEATURE_MPS2_AN386").is_some();
    let f446 = env::var_os("CARGO_FEATURE_NUCLEO_F446RE").is_some();
    let memory = match (mps2, f446) {
        (true, false) => manifest.join("../memory.x"),
        (false, true) => manifest.join("boards/nucleo-f446re/memory.x"),
        _ => panic!(
            "select exactly one board: --features mps2-an386 (the default) or \
             --no-default-features --features nucleo-f446re"
        ),
    };
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    fs::copy(&memory, out.join("memory.x")).unwrap();
    if mps2 {
        // The interrupt handlers' weak aliases, as a PAC's build script
        // provides them (cortex-m-rt's `device` feature includes device.x).
        let device = manifest.join("boards/mps2-an386/device.x");
        fs::copy(&device, out.join("device.x")).unwrap();
        println!("cargo:rerun-if-changed={}", device.display());
    }
    println!("cargo:rustc-link-search={}", out.display());
    println!("cargo:rerun-if-changed={}", memory.display());
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rustc-link-arg=--nmagic");
    println!("cargo:rustc-link-arg=-Tlink.x");
    println!("cargo:rustc-link-arg=-Tdefmt.x");
}
