#!/usr/bin/env bash
# Runs the CAPP firmware under QEMU (mps2-an386) with its UART on a TCP port.
#
#   firmware/qemu.sh [--port PORT] [--elf ELF] [--no-build]
#
# Builds the release firmware (unless --no-build or --elf is given), then
# starts qemu-system-arm, which waits for a client on 127.0.0.1:PORT (default
# 4444) before the CPU starts; connect the host library (capp-link) or
# `nc 127.0.0.1 PORT`. The defmt log goes to stdout (decoded by defmt-print
# if it is installed). Needs: rustup target thumbv7em-none-eabihf,
# apt package qemu-system-arm.
set -euo pipefail
here="$(cd "$(dirname "$0")" && pwd)"
port=4444
elf=""
build=1
while [ $# -gt 0 ]; do
  case "$1" in
    --port) port="$2"; shift 2 ;;
    --elf) elf="$2"; build=0; shift 2 ;;
    --no-build) build=0; shift ;;
    *) elf="$1"; build=0; shift ;;  # as a cargo runner: the ELF path
  esac
done
if [ -z "$elf" ]; then
  elf="$here/target/thumbv7em-none-eabihf/release/capp-firmware"
fi
if [ "$build" = 1 ]; then
  (cd "$here" && cargo build --release)
fi
echo "qemu: firmware $elf, UART on tcp 127.0.0.1:$port (waiting for a client)" >&2
cmd=(qemu-system-arm -machine mps2-an386 -nographic -monitor none
     -semihosting-config enable=on,target=native
     -serial "tcp:127.0.0.1:$port,server=on,wait=on"
     -kernel "$elf")
if command -v defmt-print >/dev/null; then
  "${cmd[@]}" | defmt-print -e "$elf"
else
  exec "${cmd[@]}"
fi
