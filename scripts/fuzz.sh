#!/usr/bin/env bash
# Bounded fuzzing of every target in fuzz/ (issue 6, part 2): builds the
# targets with libFuzzer's coverage instrumentation and runs each for
# FUZZ_SECONDS (default 20) from its committed seeds, printing the executions
# per target. Any crash fails the script; libFuzzer leaves the input in
# fuzz/artifacts/<target>/ (turn it into a regression test, see
# docs/reliability.md).
#
# CI builds with stable Rust and the same instrumentation flags cargo-fuzz
# uses, minus AddressSanitizer (nightly-only; the fuzzed crates forbid unsafe
# code), which saves installing cargo-fuzz (~1.5 min) on a fresh machine.
# Developers: `cargo install cargo-fuzz` then `cd fuzz && cargo +nightly fuzz
# run <target>` (runs until stopped, or add `-- -max_total_time=60`).
#
# Usage: scripts/fuzz.sh [target...]   (default: all)
set -euo pipefail
cd "$(dirname "$0")/../fuzz"

seconds="${FUZZ_SECONDS:-20}"
targets=("$@")
if [ ${#targets[@]} -eq 0 ]; then
  targets=(proto_decode scenario_toml input_dat planner_step)
fi
host="$(rustc -vV | sed -n 's/^host: //p')"

# cargo-fuzz's instrumentation (sancov with inline 8-bit counters, PC table and
# comparison tracing) plus debug assertions and overflow checks. `--target`
# keeps these flags off build scripts and proc macros.
export RUSTFLAGS="-Cpasses=sancov-module -Cllvm-args=-sanitizer-coverage-level=4 \
-Cllvm-args=-sanitizer-coverage-inline-8bit-counters -Cllvm-args=-sanitizer-coverage-pc-table \
-Cllvm-args=-sanitizer-coverage-trace-compares --cfg fuzzing -Cdebug-assertions -Coverflow-checks"
printf '\n== fuzz: format\n'
cargo fmt --check
printf '\n== fuzz: build %s\n' "${targets[*]}"
bins=()
for t in "${targets[@]}"; do bins+=(--bin "$t"); done
cargo build --release --locked --target "$host" "${bins[@]}"

summary=()
for t in "${targets[@]}"; do
  printf '\n== fuzz: %s for %ss\n' "$t" "$seconds"
  mkdir -p "corpus/$t" "artifacts/$t"
  log="$(mktemp)"
  # The corpus directory collects new inputs (git ignores all but the seeds).
  if ! "target/$host/release/$t" "corpus/$t" \
      -max_total_time="$seconds" -max_len=8192 -rss_limit_mb=2048 -timeout=10 \
      -artifact_prefix="artifacts/$t/" -print_final_stats=1 2>"$log"; then
    tail -n 60 "$log"
    echo "fuzz: $t FAILED; the input is in fuzz/artifacts/$t/" >&2
    exit 1
  fi
  runs="$(sed -n 's/^Done \([0-9]*\) runs in \([0-9]*\) second.*/\1/p' "$log")"
  cov="$(grep -o 'cov: [0-9]*' "$log" | tail -n 1 | cut -d' ' -f2)"
  rm -f "$log"
  echo "$t: ${runs:-?} executions in ${seconds}s, coverage ${cov:-?} edges, no crash"
  summary+=("$t: ${runs:-?} executions in ${seconds}s (coverage ${cov:-?}), no crash")
done
printf '\n== fuzz summary\n'
printf '%s\n' "${summary[@]}"
