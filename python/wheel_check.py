"""The installed wheel works without Rust: run by `cargo xtask test-all` with the interpreter of a
fresh venv into which only the abi3 wheel (and its dependencies from the index) was installed,
with no cargo on PATH and from outside the source tree. `Tyre.eval` on an MFeval oracle sweep
within the f64 budget of host-tests/src/tolerance.rs (forces 1e-6·FNOMIN, moments ·R0).

    python wheel_check.py ROOT      # ROOT: the repository (for the .tir and the oracle)
"""
import shutil
import sys
from pathlib import Path

import numpy as np
import pandas as pd

import gough

root = Path(sys.argv[1])
here = Path(gough.__file__).resolve()
assert (root / "python").resolve() not in here.parents, f"gough imported from the source tree: {here}"
assert shutil.which("cargo") is None and shutil.which("rustc") is None, "cargo is on PATH"
tir = root / "host-tests/data/tyres/MagicFormula61_Parameters.tir"
sweep = root / "host-tests/data/oracle/MagicFormula61_Parameters_mfeval40__combined__mode111.csv"
tyre = gough.Tyre.from_tir(tir)
df = pd.read_csv(sweep, comment="#")
out = tyre.eval(df.in_Fz.to_numpy(), df.in_kappa.to_numpy(), df.in_alpha.to_numpy(),
                gamma=df.in_gamma.to_numpy(), vx=df.in_Vx.to_numpy(), p=df.in_P.to_numpy(),
                phit=df.in_phit.to_numpy(), mode=111)
force = 1e-6 * tyre.fnomin
worst = 0.0
for col, ours, budget in (("out_Fx", "Fx", force), ("out_Fy", "Fy", force),
                          ("out_Mz", "Mz", force * tyre.unloaded_radius)):
    err = float(np.abs(out[ours] - df[col].to_numpy()).max())
    assert err <= budget, f"{sweep.name} {col}: max |err| {err:.3e} > {budget:.3e}"
    worst = max(worst, err / budget)
print(f"wheel: gough {here.parent} on Python {sys.version.split()[0]}: Tyre.eval on {len(df)} "
      f"points of {sweep.name} within budget (worst {worst:.1e} of it)")
