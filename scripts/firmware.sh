#!/usr/bin/env bash
# The serial stack's checks: the no_std protocol and node crates for thumb
# targets, the firmware for both boards (fmt, clippy, build), its size, and
# the end-to-end test under QEMU (which must run here, not skip).
# Needs: rustup targets thumbv7em-none-eabihf thumbv6m-none-eabi; the Debian
# package qemu-system-arm (installed here if missing and we are root).
set -euo pipefail
cd "$(dirname "$0")/.."

step() { printf '\n== %s\n' "$*"; }

if ! command -v qemu-system-arm >/dev/null; then
  step "installing qemu-system-arm"
  if [ "$(id -u)" = 0 ]; then
    apt-get update -qq && apt-get install -y -qq qemu-system-arm >/dev/null
  else
    sudo apt-get update -qq && sudo apt-get install -y -qq qemu-system-arm >/dev/null
  fi
fi

step "capp-proto and capp-node build for Cortex-M4F and Cortex-M0+ (no_std, with and without defmt)"
cargo build -p capp-proto -p capp-node --target thumbv7em-none-eabihf
cargo build -p capp-proto -p capp-node --target thumbv6m-none-eabi --features capp-node/defmt

step "firmware: format, lints, both boards"
(
  cd firmware
  cargo fmt --check
  cargo clippy --release -- -D warnings
  cargo clippy --profile f446 --no-default-features --features nucleo-f446re --target-dir target/f446 -- -D warnings
  cargo build --release
  cargo build --profile f446 --no-default-features --features nucleo-f446re --target-dir target/f446
)

step "firmware size (flash = .vector_table + .text + .rodata + .data <= 120 KiB (112 KiB before the hulls' faces and edges, 108 KiB before the link capsule segments, 104 KiB before the convex hulls, 96 KiB before issue 24's obstacle shapes); static RAM = .data + .bss + .uninit <= 104 KiB (96 KiB before the hulls' faces and edges), of the F446's 128: 32 KiB before the escape search's tree, which adds 34 KiB for 32 joints)"
for elf in firmware/target/thumbv7em-none-eabihf/release/capp-firmware \
           firmware/target/f446/thumbv7em-none-eabihf/f446/capp-firmware; do
  echo "$elf"
  size -A "$elf" | grep -E '^\.(vector_table|text|rodata|data|bss|uninit) '
  size -A "$elf" | awk -v elf="$elf" '
    $1 ~ /^\.(vector_table|text|rodata)$/ { flash += $2 }
    $1 == ".data" { flash += $2; ram += $2 }
    $1 ~ /^\.(bss|uninit)$/ { ram += $2 }
    END {
      printf "flash %d B (target 122880), static RAM %d B (target 106496)\n", flash, ram
      if (flash > 122880 || ram > 106496) { print elf ": over the memory targets"; exit 1 }
    }'
done

step "end to end under QEMU (mps2-an386)"
CAPP_REQUIRE_QEMU=1 cargo test -p capp-system-tests -- --nocapture

step "the stack guard under QEMU: a runaway recursion must fault at the MPU guard, the data below intact"
(
  cd firmware
  cargo clippy --release --examples -- -D warnings
  cargo build --release --example stack_guard
)
guard="$(timeout 60 qemu-system-arm -machine mps2-an386 -nographic -monitor none \
  -semihosting-config enable=on,target=native \
  -kernel firmware/target/thumbv7em-none-eabihf/release/examples/stack_guard)"
echo "$guard"
grep -q 'stack_guard: caught' <<<"$guard"

step "M4F instruction counter under QEMU (smoke: it runs and finishes; BENCHMARKS.md has the figures)"
(
  cd firmware
  cargo build --release --example step_count
)
counts="$(timeout 120 qemu-system-arm -machine mps2-an386 -icount shift=0,sleep=off -nographic \
  -monitor none -semihosting-config enable=on,target=native \
  -kernel firmware/target/thumbv7em-none-eabihf/release/examples/step_count)"
grep -E '^M4F (calibration|pips 18 8 step )' <<<"$counts"
grep -q 'step_count: done' <<<"$counts"
