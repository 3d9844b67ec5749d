"""gough.logs: the demo's log as cars record it (MDF4 signals by asammdf; BLF, ASC, candump and
MDF4 bus logging by python-can with frames encoded by cantools) in SAE axes, kN, degrees, km/h
and percent, the speed at a tenth of the rate, read back through a map: the same columns, the
same estimates and the same gap verdict as from the CSV; the SAE conversion checked through the
Magic Formula; every error path one line naming the file and the channel."""
import json
import math
import subprocess
import sys
import tomllib
from pathlib import Path

import numpy as np
import pandas as pd
import pytest

import gough
from gough import fleet, logs
from conftest import EXAMPLES, TIR61
import logdata

pytest.importorskip("asammdf")
pytest.importorskip("can")
pytest.importorskip("cantools")

FORMATS = ["signals.mf4", "bus.blf", "bus.asc", "bus.log", "bus.mf4"]

# What a round trip through the logger may move, per column (SI): half a DBC step (1e-6 kN,
# 1e-4 N·m, 1e-6 %, 1e-7 deg; the MDF4 signals are f64 and move by rounding only). The speed
# (0.01 km/h steps, recorded at a tenth of the rate) is interpolated linearly: on the demo's
# sine with dwell its error is at most 9.3 mm/s (measured); the bound is 2 cm/s.
QUANT = {"fz": 0.5e-3 * 1.0001, "fy": 0.5e-3 * 1.0001, "fx": 0.5e-3 * 1.0001,
         "mz": 0.5e-4 * 1.0001, "kappa": 0.5e-8 * 1.0001,
         "alpha": 0.5e-7 * math.pi / 180 * 1.0001, "gamma": 0.5e-7 * math.pi / 180 * 1.0001}
VX_BOUND = 0.02


@pytest.fixture(scope="module")
def demo(gough_cli, tmp_path_factory):
    """The README's first command's log (`gough mu demo`: log_fl.csv, 6,000 rows at 1 kHz) and
    the recordings of it, with their maps."""
    d = tmp_path_factory.mktemp("demo")
    gough_cli("mu", "demo", "--out", d)
    csv = d / "log_fl.csv"
    df = pd.read_csv(csv, comment="#")
    (d / "vehicle.dbc").write_text(logdata.DBC)
    (d / "bus.toml").write_text(logdata.BUS_MAP)
    (d / "signals.toml").write_text(logdata.MDF_MAP)
    logdata.write_mdf(df, d / "signals.mf4")
    for f in FORMATS[1:]:
        logdata.write_bus(df, d / f)
    return d, csv, df


def map_of(d, fmt):
    return d / ("signals.toml" if fmt == "signals.mf4" else "bus.toml")


@pytest.mark.parametrize("fmt", FORMATS)
def test_read_gives_the_csv_columns(demo, fmt):
    d, _, df = demo
    got = logs.read(d / fmt, map_of(d, fmt))
    assert list(got.columns) == ["t", "fz", "fy", "mz", "fx", "kappa", "vx", "gamma", "alpha"]
    assert len(got) == len(df) and got.attrs["dropped"] == [] and got.attrs["rows_in"] == len(df)
    # Times: candump and ASC keep µs, BLF ns, MDF4 bus logging f64 relative to its start.
    assert np.abs(got.t.to_numpy() - df.t.to_numpy()).max() <= 5e-7
    for c, q in QUANT.items():
        err = np.abs(got[c].to_numpy() - df[c].to_numpy()).max()
        bound = 1e-9 * np.abs(df[c]).max() if fmt == "signals.mf4" else q
        assert err <= bound, (c, err, bound)
    vx_err = np.abs(got.vx.to_numpy() - df.vx.to_numpy())
    assert vx_err.max() <= VX_BOUND
    # The speed is interpolated between its own samples, not held: exact at them.
    i = logdata.slow_rows(len(df))
    assert vx_err[i].max() <= (1e-9 if fmt == "signals.mf4" else 0.005 / 3.6 * 1.0001)
    if fmt != "signals.mf4":
        fr = got.attrs["frames"]
        # Four messages a row, the speed's at its rows: every frame decoded and used.
        assert fr["read"] == fr["used"] == 4 * len(df) + len(i)


@pytest.fixture(scope="module")
def tyre():
    return gough.Tyre.from_tir(TIR61)


@pytest.mark.parametrize("fmt", FORMATS)
def test_the_same_estimates_as_from_the_csv(demo, tyre, fmt):
    """Tolerance: states equal, |Δμ| ≤ 1e-6 and |Δσ| ≤ 1e-5. The recordings differ from the CSV
    by the DBC's half steps and the slow speed's interpolation (test above): measured, they move
    μ by ≤ 9e-8 and σ by ≤ 3e-6 on the demo's 6,000 rows (the estimator reads Fy, Mz, Fz, Fx, κ;
    the speed only for the relaxation lengths)."""
    d, csv, _ = demo
    ref = gough.estimate_mu(tyre, csv)
    got = gough.estimate_mu(tyre, d / fmt, map=map_of(d, fmt))
    assert len(got) == len(ref)
    assert (got.state.to_numpy() == ref.state.to_numpy()).all()
    assert np.abs(got.mu.to_numpy() - ref.mu.to_numpy()).max() <= 1e-6
    assert np.abs(got.sigma.to_numpy() - ref.sigma.to_numpy()).max() <= 1e-5
    assert (ref.state == "identifiable").any()


def verdict(rep):
    v = rep["verdict"]
    return v["effect"], v.get("channel"), [e["effect"] for e in v.get("effects") or []]


@pytest.fixture(scope="module")
def gap_ref(demo, tyre):
    return gough.diagnose_gap(tyre, demo[1])


@pytest.mark.parametrize("fmt", FORMATS)
def test_the_same_gap_verdict_as_from_the_csv(demo, tyre, gap_ref, fmt):
    d = demo[0]
    got = gough.diagnose_gap(tyre, d / fmt, map=map_of(d, fmt))
    assert verdict(got) == verdict(gap_ref)
    assert got["verdict"]["effect"]
    # The held-out shrink moves with the recording's half steps and the speed's interpolation
    # (measured: by at most 1.9e-5 of 0.756).
    assert abs(got["verdict"]["shrink"] - gap_ref["verdict"]["shrink"]) <= 1e-4


def test_fleet_diagnose_takes_a_map(demo, gap_ref):
    d = demo[0]
    got = fleet.diagnose([d / "bus.blf", d / "bus.log"], TIR61, map=d / "bus.toml")
    assert list(got.effect) == [gap_ref["verdict"]["effect"]] * 2
    assert list(got.rows) == [6000, 6000]


def gough_logs():
    exe = Path(sys.executable).parent / "gough-logs"
    assert exe.exists(), f"{exe}: the console script is installed with the package"
    return str(exe)


def test_console_script_writes_what_the_cli_reads(demo, gough_cli, tmp_path):
    d, csv, _ = demo
    out = tmp_path / "converted.csv"
    r = subprocess.run([gough_logs(), "convert", d / "bus.asc", "--map", d / "bus.toml", "--out", out],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    assert "6000 rows of 6000" in r.stdout and "frames: 24601 read, 24601 decoded" in r.stdout
    gough_cli("mu", "estimate", "--tir", TIR61, "--log", out, "--out", tmp_path / "a.csv")
    gough_cli("mu", "estimate", "--tir", TIR61, "--log", csv, "--out", tmp_path / "b.csv")
    a, b = pd.read_csv(tmp_path / "a.csv"), pd.read_csv(tmp_path / "b.csv")
    assert len(a) == len(b) == 6000
    assert (a.state == b.state).all()
    assert np.abs(a.mu - b.mu).max() <= 1e-6 + 1e-6  # the CLI prints 6 decimals
    # Parquet: read back by gough.read_log, the same as the CSV written.
    pq = tmp_path / "converted.parquet"
    r = subprocess.run([gough_logs(), "convert", d / "bus.asc", "--map", d / "bus.toml", "--out", pq],
                       capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    pd.testing.assert_frame_equal(gough.read_log(pq), gough.read_log(out))


def test_sae_round_trip_through_the_magic_formula(tmp_path, tyre):
    """Points in ISO-W through the Magic Formula; inputs and outputs taken to SAE by projecting
    the vectors on the SAE axes (logdata.iso_to_sae, not the reader's table of signs); an MDF4
    of those read back with convention SAE: the ISO-W values again, and the Magic Formula at the
    read-back inputs gives the read-back outputs."""
    from asammdf import MDF, Signal

    rng = np.random.default_rng(58)
    n = 400
    iso = {"fz": rng.uniform(1e3, 8e3, n), "kappa": rng.uniform(-0.2, 0.2, n),
           "alpha": rng.uniform(-0.2, 0.2, n), "gamma": rng.uniform(-0.08, 0.08, n),
           "vx": np.full(n, 20.0)}
    out = tyre.eval(iso["fz"], iso["kappa"], iso["alpha"], iso["gamma"], vx=iso["vx"])
    iso.update(fx=out["Fx"], fy=out["Fy"], mz=out["Mz"])
    sae = logdata.iso_to_sae(iso)
    # The projection's signs are those of the reader's table, and nothing else changes.
    for c in iso:
        ratio = sae[c] / np.where(iso[c] == 0, 1, iso[c])
        want = -1.0 if c in logs.SAE_NEGATED else 1.0
        np.testing.assert_allclose(ratio[iso[c] != 0], want, rtol=1e-12)
    assert (out["Fy"][iso["alpha"] > 0.05] < 0).all()  # ISO-W: α > 0 gives Fy < 0
    assert (sae["fy"][sae["alpha"] > 0.05] < 0).all()  # SAE: so does it (both axes flip)
    assert (sae["fz"] < 0).all()  # SAE: z down, the road pushes up
    t = np.arange(n) * 1e-3
    sigs = [Signal(sae[c], t, name=f"{c}_sae", unit=u) for c, u in
            (("fz", "N"), ("fy", "N"), ("mz", "Nm"), ("fx", "N"), ("kappa", "1"), ("alpha", "rad"),
             ("gamma", "rad"), ("vx", "m/s"))]
    with MDF(version="4.10") as mdf:
        mdf.append(sigs)
        mdf.save(tmp_path / "sae.mf4", overwrite=True)
    m = {"convention": "SAE", "channels": {c: {"name": f"{c}_sae"} for c in
                                           ("fz", "fy", "mz", "fx", "kappa", "alpha", "gamma", "vx")}}
    got = logs.read(tmp_path / "sae.mf4", m)  # units: the file's
    for c in ("fz", "fy", "mz", "fx", "kappa", "alpha", "gamma", "vx"):
        np.testing.assert_allclose(got[c].to_numpy(), iso[c], rtol=1e-12, atol=1e-12, err_msg=c)
    again = tyre.eval(got.fz.to_numpy(), got.kappa.to_numpy(), got.alpha.to_numpy(),
                      got.gamma.to_numpy(), vx=got.vx.to_numpy())
    for c, k in (("fx", "Fx"), ("fy", "Fy"), ("mz", "Mz")):
        np.testing.assert_allclose(again[k], got[c].to_numpy(), rtol=1e-9, atol=1e-9, err_msg=c)
    # Read as ISO-W instead, the same file is another tyre: the conversion is not a no-op.
    iso_read = logs.read(tmp_path / "sae.mf4", {**m, "convention": "ISO-W"})
    assert (iso_read.fz < 0).all()


def write_mdf(path, chans):
    """An MDF4 of {name: (t, values, unit)}, one channel group per channel."""
    from asammdf import MDF, Signal

    with MDF(version="4.10") as mdf:
        for name, (t, v, u) in chans.items():
            mdf.append([Signal(np.asarray(v, float), np.asarray(t, float), name=name, unit=u)])
        mdf.save(path, overwrite=True)


def test_four_wheels_by_the_wheel_placeholder(tmp_path, tyre):
    """`{wheel}` with wheels = [...]: the `wheel` column (position in the list: 0..3 = FL, FR,
    RL, RR), rows by time then wheel, a channel without {wheel} shared; the estimator takes it
    as a car's log, as the CLI does."""
    df = pd.read_csv(EXAMPLES / "replay_log.csv", comment="#")  # wheels 0 and 1 (FL, FR)
    names = ["VL", "VR", "HL", "HR"]  # a German logger's names, in FL, FR, RL, RR order
    chans, src = {}, {}
    for w, nm in enumerate(names):
        one = df[df.wheel == w % 2]
        t = one.t.to_numpy() + 1e-4 * w  # each wheel on its own clock
        fz = one.fz.to_numpy() * (1.0 - 0.05 * (w // 2))  # the rear wheels: their own loads
        src[w] = (t, fz, one.fy.to_numpy())
        chans[f"Fz_{nm}"] = (t, fz / 1e3, "kN")
        chans[f"Fy_{nm}"] = (t, one.fy / 1e3, "kN")
        chans[f"Mz_{nm}"] = (t, one.mz, "Nm")
    v = df[df.wheel == 0]
    tv, vv = v.t.to_numpy()[::2], v.vx.to_numpy()[::2]
    chans["v_ref"] = (tv, vv * 3.6, "km/h")
    write_mdf(tmp_path / "car.mf4", chans)
    m = {"wheels": names, "channels": {"fz": "Fz_{wheel}", "fy": "Fy_{wheel}", "mz": "Mz_{wheel}",
                                       "vx": "v_ref"}}
    got = logs.read(tmp_path / "car.mf4", m)
    assert list(got.columns) == ["t", "fz", "fy", "mz", "vx", "wheel"]
    assert sorted(set(got.wheel)) == [0, 1, 2, 3]
    assert (np.diff(got.t.to_numpy()) >= 0).all()
    for w in range(4):
        one = got[got.wheel == w]
        t, fz, fy = src[w]
        k = len(one)  # v_ref ends before the last rows: those are dropped
        np.testing.assert_allclose(one.t.to_numpy(), t[:k], rtol=0, atol=0)
        np.testing.assert_allclose(one.fz.to_numpy(), fz[:k], rtol=1e-12)
        np.testing.assert_allclose(one.fy.to_numpy(), fy[:k], rtol=1e-12)
        np.testing.assert_allclose(one.vx.to_numpy(), np.interp(t[:k], tv, vv), rtol=1e-12)
    n_src = int((df.wheel == 0).sum())
    drops = got.attrs["dropped"]
    assert got.attrs["rows_in"] == 4 * n_src and sum(x["rows"] for x in drops) == 4 * n_src - len(got) > 0
    assert all(x["column"] == "vx" and x["channel"] == "v_ref" and "span" in x["reason"] for x in drops)
    assert {x["wheel"] for x in drops} <= set(names)
    est = gough.estimate_mu(tyre, got)
    assert list(est.columns) == ["t", "wheel", "mu", "sigma", "state"] and len(est) == len(got)


def test_rate_interpolates_and_counts_what_it_drops(tmp_path, capsys):
    """rate = ...: rows on a grid over all channels' spans; rows outside a channel's span and
    rows where a channel is not a number are dropped, counted with their reasons, and printed
    by the console script."""
    t1 = np.arange(101) / 100.0  # 0..1 s at 100 Hz
    t2 = np.arange(4, 17) / 20.0  # 0.2..0.8 s at 20 Hz
    fz = np.full(len(t1), 4.0)
    fz[50] = np.nan  # 0.5 s
    write_mdf(tmp_path / "r.mf4", {"Fz": (t1, fz, "kN"), "Fy": (t1, 2 * t1, "kN"),
                                   "Mz": (t2, 10 * t2, "Nm")})
    (tmp_path / "r.toml").write_text(
        '[time]\nrate = 50.0\n[channels]\nfz = { name = "Fz", unit = "kN" }\n'
        'fy = { name = "Fy", unit = "kN" }\nmz = { name = "Mz", unit = "Nm" }\n')
    got = logs.read(tmp_path / "r.mf4", tmp_path / "r.toml")
    grid = np.arange(51) / 50.0
    assert got.attrs["rows_in"] == 51
    inside = (grid >= 0.2) & (grid <= 0.8)
    assert len(got) == inside.sum() - 1  # and the NaN at 0.5 s
    np.testing.assert_allclose(got.t, grid[inside][grid[inside] != 0.5], atol=1e-12)
    np.testing.assert_allclose(got.fy, 2e3 * got.t, rtol=1e-12)  # linear: exact on a line
    np.testing.assert_allclose(got.mz, 10 * got.t, rtol=1e-12)
    assert got.attrs["dropped"] == [
        {"column": "fz", "channel": "Fz", "wheel": None, "rows": 1, "reason": "not a number"},
        {"column": "mz", "channel": "Mz", "wheel": None, "rows": int((~inside).sum()),
         "reason": "outside the channel's time span (no extrapolation)"},
    ]
    assert logs.main(["convert", str(tmp_path / "r.mf4"), "--map", str(tmp_path / "r.toml"),
                      "--out", str(tmp_path / "r.csv")]) == 0
    out = capsys.readouterr().out
    assert f"{len(got)} rows of 51" in out
    assert f"dropped {int((~inside).sum())} rows: mz (Mz) outside the channel's time span" in out
    assert "dropped 1 rows: fz (Fz) not a number" in out
    assert len(pd.read_csv(tmp_path / "r.csv")) == len(got)


def test_units_table():
    """Every unit the issue names, with its factor to SI."""
    want = {"N": 1, "kN": 1e3, "Nm": 1, "N*m": 1, "N.m": 1, "kNm": 1e3, "rad": 1,
            "deg": math.pi / 180, "mrad": 1e-3, "m/s": 1, "km/h": 1 / 3.6, "1": 1, "%": 0.01,
            "Pa": 1, "kPa": 1e3, "bar": 1e5, "s": 1, "ms": 1e-3, "us": 1e-6}
    assert gough.logs is logs  # `import gough` is enough for gough.logs.read
    flat = {u: k for table in logs.UNITS.values() for u, k in table.items()}
    for u, k in want.items():
        assert flat[u] == pytest.approx(k, rel=1e-15), u


def test_time_unit_and_sign(tmp_path):
    t = np.arange(5) * 10.0  # ms
    write_mdf(tmp_path / "u.mf4", {"Fz": (t, [1.0] * 5, "kN"), "Fy": (t, [2.0] * 5, "kN"),
                                   "Mz": (t, [3.0] * 5, "N.m"), "P": (t, [2.5] * 5, "bar")})
    m = {"convention": "SAE", "time": {"unit": "ms"},
         "channels": {"fz": {"name": "Fz", "sign": -1}, "fy": "Fy", "mz": "Mz", "p": "P"}}
    got = logs.read(tmp_path / "u.mf4", m)
    np.testing.assert_allclose(got.t, [0, 0.01, 0.02, 0.03, 0.04])
    # A logger that records the SAE load positive: sign = -1 on top of the convention.
    assert (got.fz == 1e3).all() and (got.fy == -2e3).all() and (got.mz == -3.0).all()
    assert (got.p == 2.5e5).all()


# --- errors: one line, naming the file and the channel -------------------------------------


@pytest.fixture()
def small(tmp_path):
    t = np.arange(10) * 0.01
    write_mdf(tmp_path / "s.mf4", {"Fz": (t, [4.0] * 10, "kN"), "Fy": (t, [1.0] * 10, "kN"),
                                   "Mz": (t, [5.0] * 10, "Nm"), "Speed": (t, [50.0] * 10, "kph"),
                                   "Back": ([0, 0.01, 0.03, 0.02, 0.04], [1.0] * 5, "kN")})
    return tmp_path / "s.mf4"


def expect(exc, *parts):
    msg = str(exc.value)
    assert "\n" not in msg, msg
    for p in parts:
        assert str(p) in msg, (p, msg)


BASE = {"fz": {"name": "Fz", "unit": "kN"}, "fy": {"name": "Fy", "unit": "kN"},
        "mz": {"name": "Mz", "unit": "Nm"}}


def test_error_missing_channel(small):
    with pytest.raises(logs.LogError) as e:
        logs.read(small, {"channels": {**BASE, "mz": {"name": "MZ_FL", "unit": "Nm"}}})
    expect(e, small, "channel 'MZ_FL'", "column mz", "not in the log")


def test_error_missing_signal_in_a_bus_log(demo):
    d = demo[0]
    m = tomllib.loads(logdata.BUS_MAP)
    m["dbc"] = str(d / "vehicle.dbc")
    m["channels"]["mz"]["name"] = "FL_Forces2.Mz_FR"
    with pytest.raises(logs.LogError) as e:
        logs.read(d / "bus.log", m)
    expect(e, d / "bus.log", "channel 'FL_Forces2.Mz_FR'", "not in the DBC", "did you mean 'FL_Forces2.Mz_FL'")


def test_error_unknown_unit(small, tmp_path):
    with pytest.raises(logs.LogError) as e:
        logs.read(small, {"channels": {**BASE, "fy": {"name": "Fy", "unit": "lbf"}}})
    expect(e, "<map>", "channel 'Fy'", "unknown unit 'lbf'")
    # The file's own unit, when the map gives none.
    with pytest.raises(logs.LogError) as e:
        logs.read(small, {"channels": {**BASE, "vx": {"name": "Speed"}}})
    expect(e, small, "channel 'Speed'", "the file's unknown unit 'kph'")
    # A unit of another dimension.
    with pytest.raises(logs.LogError) as e:
        logs.read(small, {"channels": {**BASE, "vx": {"name": "Speed", "unit": "deg"}}})
    expect(e, "channel 'Speed'", "angle unit", "column vx takes speed")


def test_error_time_not_increasing(small):
    with pytest.raises(logs.LogError) as e:
        logs.read(small, {"channels": {**BASE, "fx": {"name": "Back", "unit": "kN"}}})
    expect(e, small, "channel 'Back'", "column fx", "time does not increase at sample 3")


def test_error_a_column_named_twice(small, tmp_path):
    p = tmp_path / "twice.toml"
    p.write_text('[channels]\nfz = { name = "Fz", unit = "kN" }\nfy = { name = "Fy", unit = "kN" }\n'
                 'mz = { name = "Mz", unit = "Nm" }\nfy = { name = "Fy2", unit = "N" }\n')
    with pytest.raises(logs.LogError) as e:
        logs.read(small, p)
    expect(e, p, "names column 'fy' twice", "line 5")
    with pytest.raises(logs.LogError) as e:
        logs.read(small, {"channels": {**BASE, "fx": {"name": "Fy", "unit": "kN"}}})
    expect(e, "channel 'Fy'", "names this channel twice", "columns fy and fx")


def test_error_map_problems(small, tmp_path):
    for m, parts in [
        ({"channels": {**BASE, "Fx": "Fx"}}, ["column Fx", "unknown column", "did you mean 'fx'"]),
        ({"channels": {**BASE, "t": "time"}}, ["column t", "master"]),
        ({"channels": {**BASE, "fy": "Fy_{wheel}"}}, ["column fy", "no wheels"]),
        ({"convention": "ISO-C", "channels": BASE}, ["convention 'ISO-C'"]),
        ({"time": {"master": "vx"}, "channels": BASE}, ["[time] master 'vx'"]),
        ({"time": {"rate": -1}, "channels": BASE}, ["rate -1"]),
        ({"channels": {**BASE, "fx": {"name": "Fx", "sign": 2}}}, ["column fx", "sign 2"]),
        ({"chanels": BASE}, ["unknown key 'chanels'"]),
        ({"wheels": ["FL"], "wheel_signal": "M.wheel", "channels": BASE}, ["wheel_signal 'M.wheel'"]),
    ]:
        with pytest.raises(logs.LogError) as e:
            logs.read(small, m)
        expect(e, "<map>", *parts)
    with pytest.raises(logs.LogError) as e:
        logs.read(tmp_path / "nope.mf4", {"channels": BASE})
    expect(e, "nope.mf4", "no such file")
    (tmp_path / "x.csv").write_text("t\n")
    with pytest.raises(logs.LogError) as e:
        logs.read(tmp_path / "x.csv", {"channels": BASE})
    expect(e, "x.csv", "unknown log format")


def test_error_bus_log_without_dbc_and_bad_dbc(demo, tmp_path):
    d = demo[0]
    m = tomllib.loads(logdata.BUS_MAP)
    del m["dbc"]
    with pytest.raises(logs.LogError) as e:
        logs.read(d / "bus.blf", m)
    expect(e, "bus.blf", "needs dbc")
    m["dbc"] = str(tmp_path / "missing.dbc")
    with pytest.raises(logs.LogError) as e:
        logs.read(d / "bus.blf", m)
    expect(e, "missing.dbc", "no such file")
    m.update(dbc=str(d / "vehicle.dbc"), wheels=["FL"], wheel_signal="FL_Forces1.wheel")
    with pytest.raises(logs.LogError) as e:
        logs.read(d / "bus.blf", m)
    expect(e, "<map>", "channel 'FL_Forces1.wheel'", "wheel_signal: not in the DBC")
    with pytest.raises(logs.LogError) as e:
        logs.read(d / "signals.mf4", m)
    expect(e, "signals.mf4", "wheel_signal is for bus logs")


def test_error_frames_not_decodable_are_counted(demo, tmp_path):
    """A frame of a mapped message that the DBC cannot decode (too short) is not used, and
    counted."""
    import can

    d = demo[0]
    with can.Logger(str(tmp_path / "short.log")) as log:
        for i in range(5):
            log.on_message_received(can.Message(timestamp=i * 0.01, arbitration_id=257, is_extended_id=False,
                                                data=bytes(8), channel=0))
            log.on_message_received(can.Message(timestamp=i * 0.01, arbitration_id=258, is_extended_id=False,
                                                data=bytes(8 if i != 2 else 3), channel=0))
            log.on_message_received(can.Message(timestamp=i * 0.01, arbitration_id=0x7FF, is_extended_id=False,
                                                data=bytes(1), channel=0))
    m = tomllib.loads(logdata.BUS_MAP)
    m["dbc"] = str(d / "vehicle.dbc")
    m["channels"] = {c: m["channels"][c] for c in ("fz", "fy", "mz")}
    got = logs.read(tmp_path / "short.log", m)
    assert got.attrs["frames"] == {"read": 15, "used": 9, "not in the map's messages": 5,
                                   "error or remote": 0, "not decodable with the DBC": 1}
    # Row 2's Mz is interpolated between its neighbours, not dropped: it is inside Mz's span.
    assert len(got) == 5


def test_console_script_error_is_one_line(small, tmp_path):
    p = tmp_path / "m.toml"
    p.write_text('[channels]\nfz = { name = "Fz", unit = "kN" }\nfy = { name = "Fy", unit = "kN" }\n'
                 'mz = { name = "Mz_XX", unit = "Nm" }\n')
    r = subprocess.run([gough_logs(), "convert", small, "--map", p, "--out", tmp_path / "o.csv"],
                       capture_output=True, text=True)
    assert r.returncode == 1
    assert r.stderr.count("\n") == 1 and "channel 'Mz_XX'" in r.stderr and str(small) in r.stderr
    assert not (tmp_path / "o.csv").exists()


def test_map_needs_a_path_log(tyre):
    with pytest.raises(TypeError, match="path"):
        gough.estimate_mu(tyre, {"t": [0.0]}, map={"channels": BASE})


@pytest.mark.parametrize("suffix", [".blf", ".log"])
def test_the_devices_own_frames_with_the_dbc_of_gough_proto_dbc(gough_cli, tmp_path, suffix):
    """The device's CompactMeasurement frames (CAN FD, 0x302; `gough proto frames --fd
    --compact` of the replay example, with the device's answers on 0x310) logged by python-can,
    read with the DBC of `gough proto dbc --fd` and wheel_signal: each wheel's rows are the
    example's within half a step of the message's scaling."""
    import can

    (tmp_path / "gough_fd.dbc").write_text(gough_cli("proto", "dbc", "--fd").stdout)
    src = EXAMPLES / "replay_log.csv"
    lines = gough_cli("proto", "frames", "--tir", TIR61, "--log", src, "--fd", "--compact").stdout
    n, t = 0, 0.0
    with can.Logger(str(tmp_path / f"dev{suffix}")) as log:
        for line in lines.splitlines():
            rec = json.loads(line)
            t = rec["msg"].get("t_us", t * 1e6) * 1e-6  # (an Ack or Status: at the last time)
            for fr in rec["frames"]:
                log.on_message_received(can.Message(timestamp=t, arbitration_id=rec["id"], is_extended_id=False,
                                                    is_fd=True, data=bytes.fromhex(fr), channel=0))
                n += 1
    m = {"dbc": str(tmp_path / "gough_fd.dbc"), "wheels": ["FL", "FR"],
         "wheel_signal": "GOUGH_COMPACT.wheel",
         "channels": {"fz": "GOUGH_COMPACT.Fz", "fy": "GOUGH_COMPACT.Fy", "mz": "GOUGH_COMPACT.Mz",
                      "fx": "GOUGH_COMPACT.Fx", "vx": "GOUGH_COMPACT.vx", "alpha": "GOUGH_COMPACT.alpha",
                      "kappa": {"name": "GOUGH_COMPACT.kappa", "unit": "1"}, "gamma": "GOUGH_COMPACT.gamma"}}
    got = logs.read(tmp_path / f"dev{suffix}", m)
    want = pd.read_csv(src, comment="#")
    assert got.attrs["frames"]["read"] == n and got.attrs["frames"]["used"] == len(want)
    assert got.attrs["frames"]["not in the map's messages"] == n - len(want)  # the answers
    assert got.attrs["dropped"] == []
    for w in (0, 1):
        a, b = got[got.wheel == w], want[want.wheel == w]
        assert len(a) == len(b)
        np.testing.assert_allclose(a.t, b.t, atol=1e-6)
        for c, half in (("fz", 0.25), ("fy", 0.5), ("mz", 0.05), ("fx", 0.5), ("vx", 0.005),
                        ("alpha", 5e-5), ("kappa", 5e-5), ("gamma", 5e-5)):
            err = np.abs(a[c].to_numpy() - b[c].to_numpy()).max()
            # The example's own rounding (0.1 N, 0.01 N·m, 1e-6 rad) adds to the half step.
            assert err <= half * 1.0001 + 0.05, (w, c, err)
        assert (a.fy.abs() > 1000).any()
