"""gough for numpy and pandas: the Magic Formula, the road-friction estimator and the
sim-to-real gap diagnosis of the gough project, on arrays and DataFrames.

Everything is computed by the Rust core (`gough`) and host library (`gough-host`) through the
extension module `gough._gough`: `Tyre.eval` runs what `gough mf eval` runs, `estimate_mu` what
`gough mu estimate` runs, `diagnose_gap` what `gough gap diagnose` runs. Units SI, angles in
radians, forces and moments ISO-W at the contact point.
"""
from __future__ import annotations

import json
import os
from typing import Any, Mapping

import numpy as np

from . import _gough
from . import logs  # gough.logs.read; its readers (asammdf, python-can, cantools) load on use

__all__ = ["Tyre", "TirError", "estimate_mu", "diagnose_gap", "simulate", "read_log",
           "OUTPUT_COLUMNS", "logs", "Signer", "Verifier", "Refused", "read_key"]

#: The columns `Tyre.eval` returns: those of `gough mf eval` after its inputs.
OUTPUT_COLUMNS = tuple(_gough.OUTPUT_COLUMNS)


class TirError(ValueError):
    """A `.tir` file gough cannot read. `line` is 1-based (0: the file as a whole); `key` is
    the parameter's name ('' when the error concerns no key)."""

    def __init__(self, message: str, line: int, key: str):
        super().__init__(message)
        self.line = line
        self.key = key


def _tir(fn, arg):
    try:
        return fn(arg)
    except _gough.TirError as e:
        msg, line, key = e.args
        raise TirError(msg, line, key) from None


#: The scalar types `Tyre.eval` sends down its one-point path.
_SCALARS = (float, int, np.float64, np.float32, np.int64, np.int32)


def _f64(x, name: str) -> np.ndarray:
    try:
        return np.asarray(x, dtype=np.float64)
    except (TypeError, ValueError) as e:
        raise ValueError(f"{name}: not numbers ({e})") from None


class Tyre:
    """A tyre: the parameters of one `.tir` file."""

    def __init__(self, inner: "_gough.Tyre"):
        self._inner = inner

    @classmethod
    def from_tir(cls, path: str | os.PathLike) -> "Tyre":
        """Reads a `.tir` file; raises `TirError` with the line and key of a problem."""
        return cls(_tir(_gough.Tyre.from_tir, os.fspath(path)))

    @classmethod
    def from_text(cls, text: str) -> "Tyre":
        """Parses `.tir` text; raises `TirError` with the line and key of a problem."""
        return cls(_tir(_gough.Tyre.from_text, text))

    @property
    def warnings(self) -> list[str]:
        """The reader's warnings (`line N: ...`)."""
        return list(self._inner.warnings)

    @property
    def fnomin(self) -> float:
        """FNOMIN [N]."""
        return self._inner.fnomin

    @property
    def unloaded_radius(self) -> float:
        """UNLOADED_RADIUS R0 [m]."""
        return self._inner.unloaded_radius

    @property
    def longvl(self) -> float:
        """LONGVL [m/s]."""
        return self._inner.longvl

    def eval(self, fz, kappa, alpha, gamma=0.0, vx=None, p=None, phit=0.0, mode=111,
             precision="f64", threads=None, exact=False) -> dict[str, np.ndarray]:
        """The Magic Formula, vectorised: the inputs broadcast against each other (numpy rules)
        and every output has the broadcast shape.

        fz [N], kappa [-], alpha [rad], gamma [rad], vx [m/s] (None: the tyre's LONGVL),
        p [Pa] (None: INFLPRES), phit [1/m]; mode is MFeval's useMode (111: limits on, α* off,
        no turn slip). Returns a dict with the columns of `gough mf eval`: Fx, Fy, Mz, Mx, My,
        mux, muy, Kya, Kxk, t, Mzr, sigmax, sigmay. Raises ValueError for a point the core
        rejects (e.g. not finite), naming its flat index.

        Runs in the core's batch without the GIL; `threads` (None: one per core from 8,192
        points per thread on) splits large arrays. In f64 the points go through the core's
        lanes (`mf::eval_batch_lanes`: AVX-512F, AVX2 or the baseline, whichever this processor
        has), each within 1e-9·FNOMIN of the scalar formula (4.3e-15·FNOMIN at worst over the
        MFeval oracle); `exact=True` takes the scalar batch instead, each point then equal to
        `eval_point`'s and `gough mf eval`'s to the bit (f32 always is). One point takes
        `eval_point`'s path: when every input is a Python or numpy scalar the values are numpy
        float64 scalars (shape ()), else arrays of the broadcast shape.
        """
        if precision not in ("f64", "f32"):
            raise ValueError(f"precision '{precision}': expected f64 or f32")
        if all(type(x) in _SCALARS for x in (fz, kappa, alpha, gamma, phit)) and \
                (vx is None or type(vx) in _SCALARS) and (p is None or type(p) in _SCALARS):
            vals = self._inner._eval_point(
                float(fz), float(kappa), float(alpha), float(gamma), float(phit),
                self._inner.longvl if vx is None else float(vx), 0.0 if p is None else float(p),
                int(mode), precision == "f32")
            return dict(zip(OUTPUT_COLUMNS, np.array(vals)))
        vx = self.longvl if vx is None else vx
        p = 0.0 if p is None else p
        arrs = [_f64(x, n) for x, n in (
            (fz, "fz"), (kappa, "kappa"), (alpha, "alpha"), (gamma, "gamma"),
            (phit, "phit"), (vx, "vx"), (p, "p"))]
        shape = np.broadcast(*arrs).shape
        if all(a.size == 1 for a in arrs):
            # One point in arrays: the one-point path, the values reshaped (views of one array).
            vals = self._inner._eval_point(*(float(a.flat[0]) for a in arrs), int(mode),
                                           precision == "f32")
            return dict(zip(OUTPUT_COLUMNS, np.array(vals).reshape((len(vals),) + shape)))
        # A single value goes down as one (the core repeats it); the others as the broadcast shape.
        flat = [a.ravel() if a.size == 1 else
                np.ascontiguousarray(a if a.shape == shape else np.broadcast_to(a, shape)).ravel()
                for a in arrs]
        out = self._inner._eval(*flat, int(mode), precision == "f32",
                                None if threads is None else int(threads), bool(exact))
        return {k: v.reshape(shape) for k, v in out.items()}

    def eval_point(self, fz: float, kappa: float, alpha: float, gamma: float = 0.0,
                   vx: float | None = None, p: float | None = None, phit: float = 0.0,
                   mode: int = 111, precision: str = "f64") -> tuple:
        """The Magic Formula at one point, without numpy: a tuple of floats in the order of
        `OUTPUT_COLUMNS` (Fx, Fy, Mz, Mx, My, mux, muy, Kya, Kxk, t, Mzr, sigmax, sigmay) —
        the values `eval` gives at that point. For one call per point from Python (a
        simulation step, a controller in the loop). Arguments as `eval`'s, scalars only."""
        if precision not in ("f64", "f32"):
            raise ValueError(f"precision '{precision}': expected f64 or f32")
        return self._inner._eval_point(
            float(fz), float(kappa), float(alpha), float(gamma), float(phit),
            self._inner.longvl if vx is None else float(vx), 0.0 if p is None else float(p),
            int(mode), precision == "f32")


def _columns(log, map=None) -> Mapping[str, Any]:
    """A DataFrame, a dict of arrays, or a path to a CSV or Parquet file, as columns; with
    `map`, a path to a log as cars record it, read through the map (`gough.logs.read`)."""
    if map is not None:
        if not isinstance(log, (str, os.PathLike)):
            raise TypeError("log: with map=, expected the path of a log (MDF4, BLF, ASC, candump)")
        return read_log(log, map)
    if isinstance(log, (str, os.PathLike)):
        return read_log(log)
    if hasattr(log, "columns") and hasattr(log, "__getitem__"):
        return {str(c): log[c].to_numpy() for c in log.columns}
    if isinstance(log, Mapping):
        return log
    raise TypeError("log: expected a pandas DataFrame, a dict of arrays or a path")


def read_log(path: str | os.PathLike, map=None):
    """A CSV (with '#' comment lines, as gough writes them) or Parquet log as a DataFrame; with
    `map` (a TOML file or a dict), a log as cars record it (MDF4, BLF, ASC, candump, MDF4 bus
    logging) read through the map by `gough.logs.read`."""
    import pandas as pd

    if map is not None:
        return logs.read(path, map)
    path = os.fspath(path)
    if path.endswith(".parquet") or path.endswith(".pq"):
        return pd.read_parquet(path)
    return pd.read_csv(path, comment="#")


def _col(cols: Mapping[str, Any], name: str, n: int | None = None, required=True) -> np.ndarray | None:
    if name not in cols:
        if required:
            raise ValueError(f"log: missing column '{name}'")
        return None if n is None else np.full(n, np.nan)
    a = np.asarray(cols[name], dtype=np.float64)
    if a.ndim != 1:
        raise ValueError(f"log: column '{name}' is not one-dimensional")
    return np.ascontiguousarray(a)


def estimate_mu(tyre: Tyre, log, method: str = "bank", precision: str = "f64",
                wheelbase: float | None = None, calibration_in=None, calibration_out=None, map=None):
    """The friction estimator of `gough mu estimate` over a log (a DataFrame, a dict of arrays
    or a CSV/Parquet path) with its columns: t [s], fz, fy [N], mz [N·m] required; fx [N],
    vx [m/s], kappa, alpha, gamma [rad] optional. Returns a DataFrame t, mu, sigma, state
    (identifiable, not_identifiable, fallback). A car's log of four wheels has a `wheel` column
    (0–3 = FL, FR, RL, RR, rows interleaved, time increasing per wheel): a bank per wheel, and
    with `wheelbase` [m] each rear wheel is told what its front wheel read (`gough mu estimate
    --wheelbase`); the DataFrame then has a `wheel` column. `method`: 'bank' (the product's
    estimator), or a published peer on one wheel's log, 'hsu-gerdes' or 'slip-slope' (as
    `gough mu estimate --method`); `precision`: the bank's float path, 'f64' or 'f32'.
    `calibration_in`: a calibration file (as `gough mu estimate --calibration-in`) each wheel's
    bank starts from (a warm start; a file of another form or values the bank refuses raise
    ValueError); `calibration_out`: where to write each wheel's calibration after the log (as
    `--calibration-out`). The bank's only. `map`: the log is a path to a log as cars record it
    (MDF4, BLF, ASC, candump), read through this map (a TOML file or a dict; `gough.logs`)."""
    import pandas as pd

    cols = _columns(log, map)
    t = _col(cols, "t")
    n = len(t)
    req = [_col(cols, c) for c in ("fz", "fy", "mz")]
    opt = [_col(cols, c, n, required=False) for c in ("fx", "vx", "kappa", "alpha", "gamma")]
    wheel = _col(cols, "wheel", required=False)
    mu, sigma, state = _gough._estimate_mu(tyre._inner, t, *req, *opt, "fx" in cols, method, precision,
                                           wheel, None if wheelbase is None else float(wheelbase),
                                           None if calibration_in is None else os.fspath(calibration_in),
                                           None if calibration_out is None else os.fspath(calibration_out))
    out = {"t": t}
    if wheel is not None:
        out["wheel"] = wheel.astype(np.int64)
    out.update({"mu": mu, "sigma": sigma, "state": state})
    return pd.DataFrame(out)


_GAP_REQUIRED = ("t", "vx", "alpha", "kappa", "gamma", "fz", "fx", "fy", "mz")


def diagnose_gap(tyre: Tyre, log, tir_name: str = "<tyre>", log_name: str | None = None,
                 fit_rows: int | None = None, map=None, write_tir=None, exact: bool = False) -> dict:
    """The sim-to-real gap diagnosis of `gough gap diagnose`: the report as a dict (the JSON
    the CLI writes). The log has the columns t, vx, alpha, kappa, gamma, fz, fx, fy, mz and
    optionally p, phit, mu. `tir_name` and `log_name` name the inputs in the report. `map`: the
    log is a path to a log as cars record it, read through this map (`gough.logs`).
    `write_tir`: a path; the corrected tyre file is written there (`gough gap diagnose
    --write-tir`: the tyre's `.tir` text with the verdict's fitted effect(s) put into its
    coefficients; the report's `corrected_tir` says what went in and what is left out).
    `exact`: the fits evaluated row by row with the scalar formula (`--exact`): the same report,
    bit for bit, from every build of the CLI and the package; by default they run in lanes,
    about 1.5× faster, different in the last bits."""
    if log_name is None:
        log_name = os.fspath(log) if isinstance(log, (str, os.PathLike)) else "<log>"
    cols = _columns(log, map)
    req = [_col(cols, c) for c in _GAP_REQUIRED]
    opt = [_col(cols, c, required=False) for c in ("p", "phit", "mu")]
    out = None if write_tir is None else os.fspath(write_tir)
    text = _gough._diagnose_gap(tyre._inner, req, *opt, tir_name, log_name, fit_rows, out,
                               bool(exact))
    return json.loads(text)


def simulate(tyre: Tyre, manoeuvre: str, road: str | None = None, speed: float | None = None,
             duration: float | None = None, dt: float | None = None, steer: float | None = None,
             radius: float | None = None, decel: float | None = None, abs: bool = True,
             log_every: int | None = None):
    """The vehicle simulation of `gough sim` (the same tyre at every wheel): a manoeuvre
    (step-steer, sine-dwell, brake-in-turn, abs-split, constant-radius, slalom, coast-down) on a
    road (`gough sim --road` syntax, e.g. 'mu=0.9', 'split=0.9/0.2'; None: the tyre file's own
    surface). speed [m/s], duration [s], dt [s], steer [deg of steering wheel], radius [m],
    decel [m/s²], as the CLI's flags. Returns the log as a DataFrame with the columns of the
    CLI's log.csv. Raises ValueError for a bad argument, naming its flag."""
    import pandas as pd

    def num(x):
        return None if x is None else float(x)

    if log_every is not None and int(log_every) < 1:
        raise ValueError(f"--log-every {log_every}: expected an integer ≥ 1")
    cols, data = _gough._simulate(
        tyre._inner, manoeuvre, road, num(speed), num(duration), num(dt), num(steer),
        num(radius), num(decel), bool(abs), None if log_every is None else int(log_every))
    return pd.DataFrame(data, columns=cols)


def read_key(path) -> bytes:
    """The 16-byte device key of a key file: 32 hexadecimal digits on one line, blank lines and
    `#` comment lines skipped (`firmware/keys/test.key` is the published TEST KEY)."""
    with open(path) as f:
        lines = [l.strip() for l in f if l.strip() and not l.strip().startswith("#")]
    if len(lines) != 1 or len(lines[0]) != 32:
        raise ValueError(f"{path}: not a key file (32 hexadecimal digits on one line)")
    return bytes.fromhex(lines[0])


class Signer:
    """The device owner's end of the protocol's authentication (docs/protocol.md, "Security"):
    secures state-changing messages with the device key by the core's own `auth::Signer` (and,
    for a device that authenticates every message, `--secure-all`, measurements too: any message
    seals; check that device's answers with `Verifier`).

    `epoch` and `counter` are the device's (its `Status.auth`: the epoch and the last counter it
    accepted); each `seal` takes the next counter, and after counter 2**32 - 1 the next epoch, as
    the device does. `mac_len`: the device's MAC length (4..8 bytes)."""

    def __init__(self, key: bytes, epoch: int, counter: int = 0, mac_len: int = 8):
        if len(key) != 16:
            raise ValueError("key: 16 bytes")
        self.key, self.epoch, self.counter, self.mac_len = bytes(key), epoch, counter, mac_len

    def seal(self, can_id: int, message: bytes) -> bytes:
        """The secured encoding of an encoded message (`[version][type][body][CRC-32]`, as sent
        unsecured) to be sent on CAN identifier `can_id`: type | 0x40, the counter and the MAC
        after the body, a new CRC. ValueError when `message` is not a message of this protocol."""
        out, self.epoch, self.counter = _gough._seal(self.key, self.mac_len, self.epoch,
                                                     self.counter, can_id, bytes(message))
        return bytes(out)


class Refused(ValueError):
    """A message a `Verifier` refused; `code` is the reason, as the device's Ack codes name it:
    "MacMissing" (not secured), "BadMac" (forged, altered, another key, MAC length or epoch) or
    "StaleFreshness" (replayed, reordered on its identifier, or too far ahead)."""

    def __init__(self, code: str):
        super().__init__(f"refused: {code}")
        self.code = code


class Verifier:
    """Checks the answers of a device that authenticates every message (`gough firmware run
    --secure-all`; docs/protocol.md, "Security") by the core's own `auth::Verifier`: each must be
    secured, its MAC (over the CAN identifier it came on) verify under the key and the device's
    `epoch`, and its counter be above the last one accepted on its identifier (at most 65,536
    above the highest). `counter`: the device's transmit counter to continue above (that of a
    `Status` it sent, less one). `mac_len`: the device's MAC length (4..8 bytes)."""

    def __init__(self, key: bytes, epoch: int, counter: int = 0, mac_len: int = 8):
        self._v = _gough._Verifier(bytes(key), mac_len, epoch, counter)

    def open(self, can_id: int, message: bytes) -> bytes:
        """The unsecured encoding (`[version][type][body][CRC-32]`) of the secured message
        `message` received on CAN identifier `can_id`; `Refused` (counted) when it does not
        verify, ValueError when it is not a message of this protocol."""
        ok, out = self._v.open(can_id, bytes(message))
        if not ok:
            raise Refused(bytes(out).decode())
        return bytes(out)

    def counts(self) -> dict:
        """What it accepted and refused (by reason), its epoch and highest accepted counter."""
        names = ("accepted", "missing", "bad_mac", "stale", "epoch", "counter")
        return dict(zip(names, self._v.counts()))
