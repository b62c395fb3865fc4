#!/usr/bin/env python3
"""Lists the places in an ELF that call the panic machinery.

Disassembles the ELF (`llvm-objdump`), finds every branch to a function whose
name says panic / fail / unwrap / expect, and prints where each came from:
the chain of inlined source locations (`llvm-addr2line -i`), outermost last,
with the standard library's frames left out. Deduplicated by source chain.
Usage: panic_sites.py ELF    (exit status 1 when any call is found)
"""
import re
import subprocess
import sys

PANICKY = re.compile(r"panic|_fail|unwrap_failed|expect_failed|assert_failed")


def main(elf: str) -> int:
    out = subprocess.run(
        ["llvm-objdump", "-d", "--no-show-raw-insn", "-C", elf],
        check=True, capture_output=True, text=True,
    ).stdout
    function, calls = "?", []
    for text in out.splitlines():
        m = re.match(r"^[0-9a-f]+ <(.*)>:$", text)
        if m:
            if not m.group(1).startswith("$"):
                function = m.group(1)
            continue
        m = re.match(r"^\s*([0-9a-f]+):\s+(bl|b|b\.w|blx|beq\.w|bne\.w|bhs\.w|blo\.w|bhi\.w|bls\.w|bge\.w|blt\.w|bgt\.w|ble\.w|b\w*)\s+0x[0-9a-f]+\s+<(.*)>", text)
        if m and PANICKY.search(m.group(3)) and not PANICKY.search(function):
            calls.append((m.group(1), m.group(3)))
    sites = {}
    if calls:
        lines = subprocess.run(
            ["llvm-addr2line", "-i", "-f", "-C", "-a", "-e", elf] + ["0x" + a for a, _ in calls],
            check=True, capture_output=True, text=True,
        ).stdout.splitlines()
        chains, current = [], None
        for line in lines:
            if line.startswith("0x"):
                current = []
                chains.append(current)
            elif current is not None:
                current.append(line)
        for (addr, callee), chain in zip(calls, chains):
            pairs = list(zip(chain[0::2], chain[1::2]))
            ours = [f"{loc.split('/work/')[-1].split('/', 1)[-1]} ({fn.split('::h')[0]})"
                    for fn, loc in pairs if "/rustc/" not in loc and "/registry/" not in loc]
            key = (tuple(ours), callee.split("::h")[0])
            sites.setdefault(key, []).append(addr)
    for (chain, callee), addrs in sorted(sites.items()):
        print(f"{callee} ({len(addrs)} call(s))")
        for loc in chain:
            print(f"    at {loc}")
    print(f"{len(sites)} panic call sites")
    return 0 if not sites else 1


if __name__ == "__main__":
    sys.exit(main(sys.argv[1]))
