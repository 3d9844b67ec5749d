"""`estimate_mu` and `diagnose_gap` give what the CLI gives on the bundled examples (the same
host library functions run underneath); bad logs raise."""
import json

import numpy as np
import pandas as pd
import pytest

import gough
from conftest import EXAMPLES, TIR61

LOGS = [EXAMPLES / "gap_camber.csv", EXAMPLES / "gap_thermal_mu.csv"]


@pytest.mark.parametrize("log", LOGS, ids=lambda p: p.stem)
def test_estimate_mu_equals_cli(log, gough_cli, tmp_path):
    out = tmp_path / "est.csv"
    gough_cli("mu", "estimate", "--tir", TIR61, "--log", log, "--out", out)
    cli = pd.read_csv(out)
    tyre = gough.Tyre.from_tir(TIR61)
    df = pd.read_csv(log, comment="#")
    for got in (gough.estimate_mu(tyre, df), gough.estimate_mu(tyre, {c: df[c].to_numpy() for c in df}),
                gough.estimate_mu(tyre, log)):
        assert list(got.columns) == ["t", "mu", "sigma", "state"]
        assert len(got) == len(cli)
        np.testing.assert_array_equal(got.t.to_numpy(), cli.t.to_numpy())
        # The CLI prints 6 decimals.
        assert np.abs(got.mu.to_numpy() - cli.mu.to_numpy()).max() <= 5.1e-7
        assert np.abs(got.sigma.to_numpy() - cli.sigma.to_numpy()).max() <= 5.1e-7
        assert (got.state.to_numpy() == cli.state.to_numpy()).all()
    assert (cli.state == "identifiable").any()


@pytest.mark.parametrize("log", LOGS, ids=lambda p: p.stem)
def test_diagnose_gap_equals_cli(log, gough_cli, tmp_path):
    rep = tmp_path / "r.json"
    # The CLI runs beside the Python side (each takes about 16 s in the debug build). Both exact:
    # the release wheel's lanes and a debug CLI's reference differ in the last bits.
    proc = gough_cli.start("gap", "diagnose", "--tir", TIR61, "--log", log, "--report", rep,
                           "--write-tir", tmp_path / "cli.tir", "--exact")
    tyre = gough.Tyre.from_tir(TIR61)
    got = gough.diagnose_gap(tyre, pd.read_csv(log, comment="#"), tir_name=str(TIR61), log_name=str(log),
                             write_tir=tmp_path / "py.tir", exact=True)
    gough_cli.finish(proc)
    cli = json.loads(rep.read_text())
    assert got == cli
    assert got["verdict"]["effect"]
    # The corrected file: the same text from both, read back with the coefficients the report gives.
    text = (tmp_path / "py.tir").read_text()
    assert text == (tmp_path / "cli.tir").read_text()
    assert got["corrected_tir"]["coefficients"]
    gough.Tyre.from_text(text)


def test_bad_logs_raise():
    tyre = gough.Tyre.from_tir(TIR61)
    with pytest.raises(ValueError, match="missing column 'fy'"):
        gough.estimate_mu(tyre, {"t": [0.0, 1.0], "fz": [1.0, 1.0], "mz": [0.0, 0.0]})
    with pytest.raises(ValueError, match="time does not increase"):
        gough.estimate_mu(tyre, {"t": [0.0, 0.0], "fz": [4e3, 4e3], "fy": [0.0, 0.0], "mz": [0.0, 0.0]})
    with pytest.raises(ValueError, match="not a finite number"):
        gough.estimate_mu(tyre, {"t": [0.0, 1.0], "fz": [4e3, np.nan], "fy": [0.0, 0.0], "mz": [0.0, 0.0]})
    with pytest.raises(ValueError, match="method"):
        gough.estimate_mu(tyre, {"t": [0.0], "fz": [4e3], "fy": [0.0], "mz": [0.0]}, method="magic")
    with pytest.raises(TypeError):
        gough.estimate_mu(tyre, 42)
    df = pd.read_csv(LOGS[0], comment="#").head(50)
    with pytest.raises(ValueError, match="100"):
        gough.diagnose_gap(tyre, df)


def test_simulate_equals_cli(gough_cli, tmp_path):
    args = dict(manoeuvre="step-steer", road="mu=0.8", speed=20.0, duration=1.5, log_every=10)
    gough_cli("sim", "--manoeuvre", "step-steer", "--tir", TIR61, "--road", "mu=0.8", "--speed", "20",
              "--duration", "1.5", "--log-every", "10", "--no-plots", "--out", tmp_path)
    cli = pd.read_csv(tmp_path / "log.csv", comment="#")
    got = gough.simulate(gough.Tyre.from_tir(TIR61), **args)
    assert list(got.columns) == list(cli.columns)
    assert len(got) == len(cli) > 10
    # The CLI writes its CSV with enough digits to round-trip f64 (csvio); allow the last digit.
    np.testing.assert_allclose(got.to_numpy(), cli.to_numpy(), rtol=1e-12, atol=1e-12)
    assert got.ay.abs().max() > 1.0  # it turned
    with pytest.raises(ValueError, match="manoeuvre|one of"):
        gough.simulate(gough.Tyre.from_tir(TIR61), "moonwalk")
    with pytest.raises(ValueError, match="--dt"):
        gough.simulate(gough.Tyre.from_tir(TIR61), "step-steer", dt=float("nan"))


def test_a_four_wheel_log_equals_cli_with_the_preview(gough_cli, tmp_path):
    """A car's log (a `wheel` column, rows interleaved): estimate_mu(wheelbase=2.9) gives what
    `gough mu estimate --wheelbase 2.9` gives, and the rear wheels differ from a run without it."""
    tyre = gough.Tyre.from_tir(TIR61)
    sim = gough.simulate(tyre, "slalom", road="step=1.0@0,0.3@90", duration=7.0)
    parts = []
    for w, name in enumerate(("fl", "fr", "rl", "rr")):
        parts.append(pd.DataFrame({
            "t": sim.t, "wheel": w, "fz": sim[f"{name}_fz"], "fy": sim[f"{name}_fy"],
            "mz": sim[f"{name}_mz"], "fx": sim[f"{name}_fx"], "vx": sim[f"{name}_vx"],
            "kappa": sim[f"{name}_kappa"], "gamma": sim[f"{name}_gamma"],
        }))
    car = pd.concat(parts).sort_values(["t", "wheel"], kind="stable").reset_index(drop=True)
    log = tmp_path / "car.csv"
    car.to_csv(log, index=False, float_format="%.17g")
    out = tmp_path / "car.est"
    gough_cli("mu", "estimate", "--tir", TIR61, "--log", log, "--out", out, "--wheelbase", "2.9")
    cli = pd.read_csv(out)
    got = gough.estimate_mu(tyre, log, wheelbase=2.9)
    assert list(got.columns) == ["t", "wheel", "mu", "sigma", "state"] == list(cli.columns)
    np.testing.assert_array_equal(got.wheel.to_numpy(), cli.wheel.to_numpy())
    assert np.abs(got.mu.to_numpy() - cli.mu.to_numpy()).max() <= 5.1e-7
    assert (got.state.to_numpy() == cli.state.to_numpy()).all()
    alone = gough.estimate_mu(tyre, log)
    front = got.wheel < 2
    np.testing.assert_array_equal(got.mu[front].to_numpy(), alone.mu[front].to_numpy())
    assert (got.mu[~front].to_numpy() != alone.mu[~front].to_numpy()).any()
    with pytest.raises(ValueError, match="needs method 'bank'"):
        gough.estimate_mu(tyre, log, method="hsu-gerdes")
    with pytest.raises(ValueError, match="column wheel: 4"):
        gough.estimate_mu(tyre, {"t": [0.0], "wheel": [4], "fz": [4e3], "fy": [0.0], "mz": [0.0]})


def test_calibration_in_and_out_as_the_cli(gough_cli, tmp_path):
    """`calibration_out` writes the file `gough mu estimate --calibration-out` writes; with it as
    `calibration_in` the next run starts warm (its batches carried on, its first estimates not
    the cold start's); a file the bank refuses raises."""
    log = EXAMPLES / "replay_log.csv"
    tyre = gough.Tyre.from_tir(TIR61)
    py1, cli1 = tmp_path / "py1.json", tmp_path / "cli1.json"
    cold = gough.estimate_mu(tyre, log, calibration_out=py1)
    gough_cli("mu", "estimate", "--tir", TIR61, "--log", log, "--out", tmp_path / "e.csv",
              "--calibration-out", cli1)
    assert json.loads(py1.read_text()) == json.loads(cli1.read_text())
    c1 = json.loads(py1.read_text())
    assert c1["format"] == "gough-calibration-1"
    assert [w["wheel"] for w in c1["wheels"]] == [0, 1]
    assert all(w["batches"] > 0 for w in c1["wheels"])
    assert all(set(w["properties"]) == {"trail", "trail_shape", "trail_shift", "kx"}
               for w in c1["wheels"])
    py2 = tmp_path / "py2.json"
    warm = gough.estimate_mu(tyre, log, calibration_in=py1, calibration_out=py2)
    c2 = json.loads(py2.read_text())
    assert all(b["batches"] > a["batches"] for a, b in zip(c1["wheels"], c2["wheels"]))
    assert not np.array_equal(cold.mu.to_numpy()[:40], warm.mu.to_numpy()[:40])
    bad = json.loads(py1.read_text())
    bad["wheels"][0]["properties"]["trail"]["value"] = 5.0  # ln 5 beyond 4 prior σ
    (tmp_path / "bad.json").write_text(json.dumps(bad))
    with pytest.raises(ValueError, match="wheel 0: refused"):
        gough.estimate_mu(tyre, log, calibration_in=tmp_path / "bad.json")
    with pytest.raises(ValueError, match="keeps no calibration"):
        gough.estimate_mu(tyre, EXAMPLES / "gap_camber.csv", method="slip-slope",
                          calibration_out=tmp_path / "x.json")
