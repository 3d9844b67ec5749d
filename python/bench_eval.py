"""Speed of `gough.Tyre.eval`: points per second, one run, printed as the Markdown table of
docs/python.md. Run it on the release build that `pip install ./python` makes:

    python3 -m venv /tmp/gough-venv && /tmp/gough-venv/bin/pip install ./python
    /tmp/gough-venv/bin/python python/bench_eval.py --gough target/release/gough

Beside it, in the same run, the peers that run here: the same points evaluated one call at a time
from Python (the per-point overhead), and the `gough mf eval` CLI on a CSV of the points (its
wall time, file I/O included; `--gough` names the binary). MFeval (MATLAB) does not run on this
machine.
"""
import argparse
import os
import platform
import subprocess
import sys
import tempfile
import time
from pathlib import Path

import numpy as np
import pandas as pd

# Run as a file, this script's directory comes first on sys.path, and the source tree's
# `gough/` (without the compiled `_gough`) would shadow the installed package.
_HERE = Path(__file__).resolve().parent
sys.path = [p for p in sys.path if Path(p or ".").resolve() != _HERE]
import gough  # noqa: E402

ROOT = Path(__file__).resolve().parents[1]
TIR = ROOT / "host-tests" / "data" / "tyres" / "MagicFormula61_Parameters.tir"


def points(n, rng):
    return (rng.uniform(1000.0, 8000.0, n), rng.uniform(-0.3, 0.3, n),
            rng.uniform(-0.25, 0.25, n), rng.uniform(-0.05, 0.05, n))


def best_of(f, repeat):
    best = float("inf")
    for _ in range(repeat):
        t0 = time.perf_counter()
        f()
        best = min(best, time.perf_counter() - t0)
    return best


def main():
    ap = argparse.ArgumentParser()
    ap.add_argument("--gough", help="the gough CLI binary, for the side-by-side row")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    tyre = gough.Tyre.from_tir(TIR)
    rng = np.random.default_rng(1)
    rows = []
    for n in (1_000, 100_000, 1_000_000):
        fz, kappa, alpha, gamma = points(n, rng)
        for prec in ("f64", "f32"):
            dt = best_of(lambda: tyre.eval(fz, kappa, alpha, gamma, vx=16.7, precision=prec), a.repeat)
            lanes = ", lanes" if prec == "f64" else ""
            rows.append((f"`Tyre.eval`, {prec}{lanes}, combined (mode 111)", n, n / dt))
            if prec == "f64":
                dt = best_of(lambda: tyre.eval(fz, kappa, alpha, gamma, vx=16.7, exact=True),
                             a.repeat)
                rows.append(("`Tyre.eval`, f64, `exact=True` (scalar batch), combined (mode 111)",
                             n, n / dt))
            if n >= 100_000:
                dt = best_of(lambda: tyre.eval(fz, kappa, alpha, gamma, vx=16.7, precision=prec,
                                               threads=1), a.repeat)
                rows.append((f"`Tyre.eval`, {prec}{lanes}, combined (mode 111), `threads=1`", n,
                             n / dt))
    n = 10_000
    fz, kappa, alpha, gamma = points(n, rng)
    pts = [(float(fz[i]), float(kappa[i]), float(alpha[i]), float(gamma[i])) for i in range(n)]
    dt = best_of(lambda: [tyre.eval(f, k, al, g, vx=16.7) for f, k, al, g in pts], a.repeat)
    rows.append(("`Tyre.eval` one point per call (Python floats, Python loop), f64", n, n / dt))
    dt = best_of(lambda: [tyre.eval_point(f, k, al, g, vx=16.7) for f, k, al, g in pts], a.repeat)
    rows.append(("`Tyre.eval_point` one point per call (Python loop), f64", n, n / dt))
    one = [np.array([f]) for f, _, _, _ in pts[:2000]]
    dt = best_of(lambda: [tyre.eval(x, 0.0, 0.05, vx=16.7) for x in one], a.repeat)
    rows.append(("`Tyre.eval` one-element arrays (Python loop), f64", 2000, 2000 / dt))
    if a.gough:
        n = 100_000
        fz, kappa, alpha, gamma = points(n, rng)
        with tempfile.TemporaryDirectory() as d:
            inp, out = os.path.join(d, "in.csv"), os.path.join(d, "out.csv")
            pd.DataFrame({"in_Fz": fz, "in_kappa": kappa, "in_alpha": alpha, "in_gamma": gamma,
                          "in_phit": 0.0, "in_Vx": 16.7, "in_P": 0.0}).to_csv(inp, index=False)
            cmd = [a.gough, "mf", "eval", "--tir", str(TIR), "--input", inp, "--output", out]
            dt = best_of(lambda: subprocess.run(cmd, check=True, capture_output=True), a.repeat)
        rows.append(("`gough mf eval` CLI on a CSV (wall, I/O included), f64", n, n / dt))
    print(f"Machine: {platform.machine()}, {os.cpu_count()} cores, Python {platform.python_version()}, "
          f"numpy {np.__version__}; best of {a.repeat}; MagicFormula61_Parameters.tir, random points "
          "(Fz 1–8 kN, |κ| ≤ 0.3, |α| ≤ 0.25 rad, |γ| ≤ 0.05 rad, Vx 16.7 m/s).\n")
    print("| what | points | points/s | µs per point |")
    print("|---|---:|---:|---:|")
    for what, n, pps in rows:
        print(f"| {what} | {n:,} | {pps:,.0f} | {1e6 / pps:.3g} |")


if __name__ == "__main__":
    main()
