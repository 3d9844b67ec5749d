#!/usr/bin/env python3
"""Instruction profile of a bracketed workload of an mps2-an386 firmware image under QEMU.

Runs ELF under `qemu-system-arm -machine mps2-an386 -icount shift=0` with QEMU's execution log
(`-d exec,nochain,in_asm`), counts every instruction executed between the K-th call of the
image's `bench_start` (`--bracket K`, default 1) and the next call of `bench_stop`, and
attributes each to a source line
through the debug info (`llvm-addr2line`, innermost inlined frame in the `gough` crate's `src/`,
else the innermost frame). Prints the totals by file, function and line, divided by `--per`
(e.g. the number of evaluations in the bracket).

The counts are QEMU's: one per executed Thumb instruction (conditional ones included), the
measure the README's instruction counts use. The log is large (about 50 MB per million
instructions executed in the image, inside the bracket or not); it is written to a temporary
directory and removed. `--only REGEX` keeps it to the functions whose demangled names match (QEMU's
`-dfilter`; the markers are always kept): a workload after a long set-up (the estimator after its
table build) is then profiled without gigabytes of log, but instructions in functions that do
not match are not counted, so name every function the workload calls that is not inlined.

    cd firmware && cargo build --release --bin profile
    python3 ../tools/qemu_profile.py target/thumbv7em-none-eabihf/release/profile --per 256
    python3 ../tools/qemu_profile.py target/thumbv7em-none-eabihf/release/profile \
        --bracket 2 --only 'profile::estimator_stream|gough::mu::' --per 1000

The no-FPU bench (`firmware-m0/`, brackets in the order of its output) runs on the micro:bit's
Cortex-M0: `--machine microbit --cpu cortex-m0`.

Needs qemu-system-arm and llvm-addr2line, llvm-nm (Debian: `apt-get install qemu-system-arm llvm`).
"""

import argparse
import collections
import json
import os
import re
import shutil
import subprocess
import sys
import tempfile

TB_START = re.compile(r"^IN:")
INSN = re.compile(r"^0x([0-9a-f]{8}):")
EXEC = re.compile(r"^Trace \d+: 0x[0-9a-f]+ \[[0-9a-f]+/([0-9a-f]+)/")


def symbol(nm, elf, name):
    out = subprocess.run([nm, elf], capture_output=True, text=True, check=True).stdout
    for line in out.splitlines():
        parts = line.split()
        if len(parts) == 3 and parts[2] == name:
            return int(parts[0], 16) & ~1
    sys.exit(f"qemu_profile: no symbol {name} in {elf}")


def ranges(nm, elf, pattern):
    """QEMU `-dfilter` ranges (start+size) of the functions whose demangled names match."""
    out = subprocess.run(
        [nm, "-S", "-C", "--defined-only", elf], capture_output=True, text=True, check=True
    ).stdout
    rx = re.compile(pattern)
    found = []
    for line in out.splitlines():
        parts = line.split(None, 3)
        if len(parts) == 4 and parts[2] in "tT" and rx.search(parts[3]):
            found.append(f"0x{int(parts[0], 16) & ~1:x}+0x{int(parts[1], 16):x}")
    if not found:
        sys.exit(f"qemu_profile: no function matches {pattern!r} in {elf}")
    return found


def count(log, start, stop, nth):
    """Instructions executed per address between the `nth` `start` and the next `stop`."""
    blocks, cur, on, done, seen = {}, None, False, False, 0
    counts = collections.Counter()
    with open(log, errors="replace") as f:
        for line in f:
            if TB_START.match(line):
                cur = []
                continue
            m = INSN.match(line)
            if m and cur is not None:
                a = int(m.group(1), 16)
                cur.append(a)
                if len(cur) == 1:
                    blocks[a] = cur
                continue
            m = EXEC.match(line)
            if m:
                cur = None
                a = int(m.group(1), 16)
                if a == start and not done and not on:
                    seen += 1
                    on = seen == nth
                elif a == stop and on:
                    on, done = False, True
                if on:
                    for x in blocks.get(a, ()):
                        counts[x] += 1
    if not done:
        sys.exit(f"qemu_profile: bracket {nth} (bench_start..bench_stop) was not completed")
    return counts


def attribute(addr2line, elf, counts, src_marker):
    addrs = sorted(counts)
    by = {k: collections.Counter() for k in ("file", "function", "line")}
    for i in range(0, len(addrs), 2000):
        chunk = addrs[i : i + 2000]
        out = subprocess.run(
            [addr2line, "--output-style=JSON", "-f", "-i", "-C", "-e", elf]
            + [hex(a) for a in chunk],
            capture_output=True,
            text=True,
            check=True,
        ).stdout
        for a, rec in zip(chunk, json.loads(out)):
            frames = rec.get("Symbol") or [{"FileName": "?", "Line": 0, "FunctionName": "?"}]
            pick = next((s for s in frames if src_marker in s["FileName"]), frames[0])
            name = pick["FileName"]
            if src_marker in name:
                name = "src/" + name.split(src_marker, 1)[1]
            else:
                name = os.path.basename(name) or "?"
            fn = re.sub(r"::h[0-9a-f]{16}$", "", pick["FunctionName"])
            n = counts[a]
            by["file"][name] += n
            by["function"][fn] += n
            by["line"][f"{name}:{pick['Line']}"] += n
    return by


def main():
    ap = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    ap.add_argument("elf")
    ap.add_argument("--per", type=float, default=1.0, help="divide every count by this")
    ap.add_argument("--top", type=int, default=25, help="rows per table")
    ap.add_argument("--bracket", type=int, default=1, help="profile the K-th bracket (from 1)")
    ap.add_argument("--only", help="log only the functions whose demangled names match")
    ap.add_argument("--machine", default="mps2-an386", help="QEMU machine (M0 bench: microbit)")
    ap.add_argument("--cpu", default="cortex-m4", help="QEMU CPU (M0 bench: cortex-m0)")
    ap.add_argument("--qemu", default="qemu-system-arm")
    ap.add_argument("--addr2line", default="llvm-addr2line")
    ap.add_argument("--nm", default="llvm-nm")
    ap.add_argument(
        "--src",
        default=os.path.join(os.path.dirname(os.path.abspath(__file__)), "..", "src") + os.sep,
        help="path prefix of the crate's sources in the debug info",
    )
    args = ap.parse_args()
    for tool in (args.qemu, args.addr2line, args.nm):
        if shutil.which(tool) is None:
            sys.exit(f"qemu_profile: {tool} not found (apt-get install qemu-system-arm llvm)")
    start = symbol(args.nm, args.elf, "bench_start")
    stop = symbol(args.nm, args.elf, "bench_stop")
    filt = []
    if args.only:
        keep = ranges(args.nm, args.elf, args.only)
        keep += ranges(args.nm, args.elf, r"^bench_st(art|op)$")
        filt = ["-dfilter", ",".join(keep)]
    with tempfile.TemporaryDirectory() as tmp:
        log = os.path.join(tmp, "exec.log")
        run = subprocess.run(
            [args.qemu, "-cpu", args.cpu, "-machine", args.machine, "-nographic",
             "-semihosting-config", "enable=on,target=native", "-icount", "shift=0",
             "-d", "exec,nochain,in_asm", "-D", log] + filt + ["-kernel", args.elf],
            stdout=subprocess.DEVNULL, timeout=600,
        )
        if run.returncode != 0:
            sys.exit(f"qemu_profile: the image exited with {run.returncode}")
        counts = count(log, start, stop, args.bracket)
    src = os.path.normpath(args.src) + os.sep
    by = attribute(args.addr2line, args.elf, counts, src)
    total = sum(counts.values())
    print(f"{total / args.per:.1f} instructions per unit ({total} in the bracket, / {args.per:g})")
    for key in ("file", "function", "line"):
        print(f"\nby {key}:")
        for k, v in by[key].most_common(args.top):
            print(f"{v / args.per:9.1f}  {100.0 * v / total:5.1f} %  {k}")


if __name__ == "__main__":
    main()
