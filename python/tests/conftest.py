"""Paths shared by the tests: the repository's data and the `gough` CLI (GOUGH, set by
`cargo xtask test-all`: the debug build its host tests built; else target/debug/gough). The
gap diagnosis is compared with `--exact`/`exact=True`: the same in every build.)"""
import os
import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parents[2]
DATA = ROOT / "host-tests" / "data"
EXAMPLES = ROOT / "examples"
TIR61 = DATA / "tyres" / "MagicFormula61_Parameters.tir"


@pytest.fixture(scope="session")
def gough_cli():
    exe = os.environ.get("GOUGH", str(ROOT / "target" / "debug" / "gough"))
    assert Path(exe).exists(), f"{exe}: build it with `cargo build -p gough-host --bin gough`"

    def run(*args):
        return subprocess.run([exe, *map(str, args)], check=True, capture_output=True, text=True)

    def start(*args):
        """The CLI started in the background (for a test that computes the Python side
        meanwhile); `finish` waits for it."""
        return subprocess.Popen(
            [exe, *map(str, args)], stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True
        )

    def finish(proc):
        out, err = proc.communicate()
        assert proc.returncode == 0, f"{proc.args}: exit {proc.returncode}: {err}"
        return out

    run.start = start
    run.finish = finish
    return run
