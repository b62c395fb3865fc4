#!/usr/bin/env bash
# Where a tracked PIPS + 8 tick's instructions go (issue 22), function by
# function: builds firmware/examples/profile_tick.rs, runs it under QEMU one
# instruction a translation block with the execution trace on, and counts the
# instructions between its two marker calls by the function each belongs to
# (inlined code counts as its caller's). Prints instructions per tick, most
# first. Counts, not timings; needs qemu-system-arm and about 1 GB in /tmp
# for the trace (deleted afterwards).
#
#     bash scripts/profile_tick.sh [TOP]      # TOP functions (default 30)
set -euo pipefail
cd "$(dirname "$0")/../firmware"
top="${1:-30}"
cargo build --release --example profile_tick >&2
elf=target/thumbv7em-none-eabihf/release/examples/profile_tick
trace="$(mktemp /tmp/capp-profile.XXXXXX)"
trap 'rm -f "$trace"' EXIT
qemu-system-arm -machine mps2-an386 -nographic -monitor none \
  -semihosting-config enable=on,target=native -singlestep \
  -d exec,nochain -D "$trace" -kernel "$elf" >&2
ticks="$(grep -o '^const TICKS: usize = [0-9]*' examples/profile_tick.rs | grep -o '[0-9]*$')"
# Each trace line ends with the function's (mangled) symbol; the marker's
# first entry turns counting on, its next entry off.
awk -v ticks="$ticks" -v top="$top" '
  # Rust legacy mangling: _ZN, then length-prefixed path segments.
  function demangle(s,    out, len, seg) {
    if (substr(s, 1, 3) != "_ZN") return s
    s = substr(s, 4); out = ""
    while (match(s, /^[0-9]+/)) {
      len = substr(s, 1, RLENGTH) + 0; seg = substr(s, RLENGTH + 1, len)
      s = substr(s, RLENGTH + 1 + len)
      if (len == 17 && seg ~ /^h[0-9a-f]+$/) break
      out = out (out == "" ? "" : "::") seg
    }
    gsub(/\$LT\$/, "<", out); gsub(/\$GT\$/, ">", out); gsub(/\$u20\$/, " ", out)
    gsub(/\$C\$/, ",", out); gsub(/\$u7b\$/, "{", out); gsub(/\$u7d\$/, "}", out)
    gsub(/\.\./, "::", out)
    return out
  }
  { sym = $NF }
  sym == "capp_profile_marker" && prev != sym { marks++ }
  { prev = sym }
  marks == 1 && sym != "capp_profile_marker" { count[sym]++; total++ }
  END {
    if (total == 0) { print "no instructions between the markers" > "/dev/stderr"; exit 1 }
    printf "%d instructions per tick over %d tracked PIPS + 8 ticks\n", total / ticks, ticks
    n = 0
    for (s in count) order[++n] = s
    for (i = 1; i <= n; i++) for (j = i + 1; j <= n; j++)
      if (count[order[j]] > count[order[i]]) { t = order[i]; order[i] = order[j]; order[j] = t }
    for (i = 1; i <= n && i <= top; i++) {
      name = demangle(order[i])
      printf "%9d  %5.1f %%  %s\n", count[order[i]] / ticks, 100 * count[order[i]] / total, name
    }
  }' "$trace"
