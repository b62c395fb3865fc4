#!/usr/bin/env bash
# Every check the project has, in one place: README, CI and people run this.
# Installs what it needs on a fresh machine (the thumb targets, chromium;
# scripts/firmware.sh installs qemu-system-arm).
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n== %s\n' "$*"; }

step "toolchain targets"
rustup target add thumbv7em-none-eabihf thumbv6m-none-eabi

# Headless Chromium loads each run's viewer.html in the host tests
# (host-sim/tests/viewer_browser.rs); Debian's package, as for QEMU.
if ! command -v chromium >/dev/null; then
  step "installing chromium"
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq && apt-get install -y -qq chromium >/dev/null
  else
    sudo apt-get update -qq && sudo apt-get install -y -qq chromium >/dev/null
  fi
fi

step "format"
cargo fmt --all --check

step "lints"
cargo clippy --workspace --all-targets -- -D warnings

step "host tests (the 3-D viewer in headless Chromium must run here, not skip)"
CAPP_REQUIRE_CHROMIUM=1 cargo test --workspace

step "no panic path in the firmware's planner, protocol and board code (link check)"
bash scripts/nopanic.sh

step "fuzzing: every target for a bounded time (FUZZ_SECONDS, default 20 s each)"
bash scripts/fuzz.sh

step "capp-core builds for Cortex-M4F and Cortex-M0+ (no_std, with and without defmt)"
cargo build -p capp-core --target thumbv7em-none-eabihf
cargo build -p capp-core --target thumbv6m-none-eabi --features defmt

step "serial protocol, firmware (both boards) and the end-to-end test under QEMU"
bash scripts/firmware.sh
