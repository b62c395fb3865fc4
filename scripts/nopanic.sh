#!/usr/bin/env bash
# The no-panic check (issue 6, part 3). nopanic/ links, for the firmware's
# target and with its release profile, (1) capp-core's planner (Robot,
# Scenario, Planner::new, step) and capp-proto's receive accumulator, decode
# and encode, and (2) capp-node's whole serving loop, polled and fed by the
# receive interrupt, on inputs the optimiser cannot see, with a panic
# handler that calls an undefined symbol: any panic path left in the
# optimised code fails the link. (3) The mps2-an386 firmware itself, built
# the same way (feature `nopanic`): RTIC, the board glue and capp-node. A canary build with one
# deliberate out-of-bounds index must fail, proving the check can fail.
#
#   scripts/nopanic.sh          the check (CI)
#   scripts/nopanic.sh --list   where the panic calls are (needs llvm-objdump
#                               and llvm-addr2line), with a looping handler
set -euo pipefail
cd "$(dirname "$0")/../nopanic"
rustup target add thumbv7em-none-eabihf >/dev/null 2>&1 || true

if [ "${1:-}" = "--list" ]; then
  cargo build --release --locked --features list
  status=0
  for bin in core_proto node; do
    echo "== $bin"
    python3 ../scripts/panic_sites.py "target/thumbv7em-none-eabihf/release/$bin" || status=1
  done
  exit $status
fi

printf '\n== no panic path in the planner, the protocol and the board logic (link check)\n'
cargo fmt --check
if ! cargo build --release --locked 2>build.log; then
  grep -E "undefined symbol|error" build.log | head -20
  echo "nopanic: a panic path survived; run scripts/nopanic.sh --list to see where" >&2
  rm -f build.log
  exit 1
fi
rm -f build.log
echo "core_proto and node link with a panic handler that cannot link: no panic path"

printf '\n== no panic path in the firmware itself (mps2-an386: RTIC, the board glue, capp-node)\n'
# The same trick on the real binary (feature `nopanic`: the handler that
# cannot link, the defmt transport left out). The F446 build is not checked:
# its HAL's clock setup asserts.
if ! (cd ../firmware && cargo build --release --locked --features nopanic \
      --target-dir target/nopanic 2>../nopanic/build.log); then
  grep -E "undefined symbol|error" build.log | head -20
  echo "nopanic: a panic path survived in the firmware" >&2
  rm -f build.log
  exit 1
fi
rm -f build.log
echo "capp-firmware (mps2-an386) links with a panic handler that cannot link: no panic path"

printf '\n== the check can fail: a canary panic path must break the link\n'
if cargo build --release --locked --features canary 2>canary.log; then
  rm -f canary.log
  echo "nopanic: the canary build linked; the check is broken" >&2
  exit 1
fi
if ! grep -q capp_nopanic_panic_path_survived canary.log; then
  cat canary.log
  rm -f canary.log
  echo "nopanic: the canary build failed for another reason" >&2
  exit 1
fi
rm -f canary.log
echo "canary: link failed on capp_nopanic_panic_path_survived, as it must"
