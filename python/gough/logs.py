"""Logs as cars record them: ASAM MDF4 (CANape, INCA), BLF and ASC (CANoe), candump (SocketCAN)
and MDF4 CAN bus logging, each channel at its own rate, in the logger's units and axes, read
through a *map* into gough's columns (SI, ISO-W, one time base).

    df = gough.logs.read("run.mf4", "car.toml")      # or a dict with the map's content

The map (TOML, or the same as a dict)::

    dbc = "vehicle.dbc"        # bus logs only: frames decoded with this DBC (relative to the map)
    convention = "SAE"         # or "ISO-W" (default): SAE is converted to ISO-W
    wheels = ["FL", "FR", "RL", "RR"]   # optional: {wheel} in a name, list position = wheel 0..3
    [time]
    master = "fy"              # rows at this column's sample times (default "fy"), or rate = 200.0
    [channels]                 # gough column = { name = channel or "Message.Signal", unit = ... }
    fz = { name = "Fz_{wheel}", unit = "kN" }
    vx = { name = "VehSpd", unit = "km/h" }

Channels at other rates than the master are interpolated linearly onto the master's times; no
extrapolation: a row outside a channel's time span is dropped and counted, as is a row where a
channel is not a number. The result's ``attrs["dropped"]`` lists every count with its reason
(``attrs["frames"]`` counts the frames of a bus log that were not used, and why).

The readers are those chassis engineers already use: asammdf (MDF), python-can (BLF, ASC,
candump, MDF4 bus logging), cantools (DBC). Install them with ``pip install 'gough[logs]'``.
The console script ``gough-logs convert IN --map MAP.toml --out OUT.csv|OUT.parquet`` writes
what the ``gough`` CLI reads.
"""
from __future__ import annotations

import argparse
import difflib
import math
import os
import sys
from pathlib import Path
from typing import Any, Mapping

import numpy as np

__all__ = ["read", "load_map", "Map", "write", "LogError", "UNITS", "COLUMNS", "SAE_NEGATED", "main"]


class LogError(ValueError):
    """A log or map gough cannot read: the message is one line naming the file and, where one is
    concerned, the channel (``.file``, ``.channel``; ``.column`` the gough column)."""

    def __init__(self, file, message: str, channel: str | None = None, column: str | None = None):
        self.file = os.fspath(file)
        self.channel = channel
        self.column = column
        where = self.file
        if channel is not None:
            where += f": channel '{channel}'"
            if column is not None:
                where += f" (column {column})"
        elif column is not None:
            where += f": column {column}"
        super().__init__(f"{where}: {message}")


#: Units, by dimension: the factor to SI.
UNITS: dict[str, dict[str, float]] = {
    "force": {"N": 1.0, "kN": 1e3},
    "moment": {"Nm": 1.0, "N*m": 1.0, "N.m": 1.0, "N·m": 1.0, "kNm": 1e3, "kN*m": 1e3, "kN.m": 1e3},
    "angle": {"rad": 1.0, "deg": math.pi / 180.0, "mrad": 1e-3},
    "speed": {"m/s": 1.0, "km/h": 1.0 / 3.6},
    "ratio": {"1": 1.0, "%": 1e-2},
    "pressure": {"Pa": 1.0, "kPa": 1e3, "bar": 1e5},
    "time": {"s": 1.0, "ms": 1e-3, "us": 1e-6, "µs": 1e-6},
}

#: gough's columns a map can fill, with their dimension (the unit must be one of it).
COLUMNS: dict[str, str] = {
    "fz": "force", "fy": "force", "mz": "moment", "fx": "force", "kappa": "ratio",
    "vx": "speed", "gamma": "angle", "alpha": "angle", "p": "pressure",
}

#: The columns whose sign differs between SAE (J670 tyre axes: x forward, y right, z down) and
#: ISO-W (TYDEX W: x forward, y left, z up), the SAE axes being the ISO-W axes turned 180° about
#: x: forces along y and z, the moment about z, the slip angle (a rotation about z) and the
#: inclination angle (positive when the wheel's top leans towards +y). Fx, κ, Vx, p are equal.
SAE_NEGATED = ("fy", "fz", "mz", "alpha", "gamma")

_ORDER = ("t", "fz", "fy", "mz", "fx", "kappa", "vx", "gamma", "alpha", "p")
_MDF = (".mf4", ".mdf", ".mf3", ".dat")
_BUS = (".blf", ".asc", ".log", ".trc")


def _toml(path: Path) -> dict:
    try:
        import tomllib  # Python ≥ 3.11
    except ModuleNotFoundError:  # pragma: no cover - 3.9/3.10
        import tomli as tomllib
    try:
        text = path.read_text(encoding="utf-8")
    except OSError as e:
        raise LogError(path, f"cannot read the map: {e.strerror or e}") from None
    try:
        return tomllib.loads(text)
    except tomllib.TOMLDecodeError as e:
        msg = str(e).splitlines()[0]
        line = getattr(e, "lineno", None)
        if line is None:  # tomli/tomllib before 3.14: "... (at line L, column C)"
            import re

            m = re.search(r"line (\d+)", msg)
            line = int(m.group(1)) if m else None
        key = None
        if line is not None and 0 < line <= len(text.splitlines()):
            src = text.splitlines()[line - 1].split("=", 1)[0].strip().strip("[]").strip()
            key = src.rsplit(".", 1)[-1].strip().strip('"') or None
        if key is not None and "overwrite" in msg.lower():
            raise LogError(path, f"the map names column '{key}' twice (line {line})",
                           column=key) from None
        raise LogError(path, f"not a TOML map: {msg}", column=key) from None


class Map(dict):
    """A checked map (what `load_map` returns); `read` and `load_map` take it as it is."""


def load_map(map: str | os.PathLike | Mapping[str, Any]) -> Map:
    """The map as a checked dict: ``file`` (the map's path or ``'<map>'``), ``dbc`` (an absolute
    path or None), ``convention``, ``wheels``, ``wheel_signal``, ``master``, ``rate``, ``time_unit`` and
    ``channels`` {column: {name, unit, sign}}. Raises LogError naming the map and the column."""
    if isinstance(map, Map):
        return map
    if isinstance(map, (str, os.PathLike)):
        file = Path(map)
        raw = _toml(file)
        base = file.resolve().parent
    elif isinstance(map, Mapping):
        file, raw, base = Path("<map>"), dict(map), Path.cwd()
    else:
        raise TypeError("map: expected a path to a TOML file or a dict")

    def err(msg, column=None):
        return LogError(file, msg, column=column)

    known = {"dbc", "convention", "time", "channels", "wheels", "wheel_signal"}
    for k in raw:
        if k not in known:
            raise err(f"unknown key '{k}' (expected one of {', '.join(sorted(known))})")
    conv = str(raw.get("convention", "ISO-W")).upper().replace("_", "-")
    if conv not in ("ISO-W", "SAE"):
        raise err(f"convention '{raw.get('convention')}': expected ISO-W or SAE")
    dbc = raw.get("dbc")
    if dbc is not None:
        dbc = Path(dbc)
        dbc = dbc if dbc.is_absolute() else base / dbc
    wheels = raw.get("wheels")
    if wheels is not None:
        if (not isinstance(wheels, (list, tuple)) or not 1 <= len(wheels) <= 4
                or not all(isinstance(w, str) and w for w in wheels)
                or len(set(wheels)) != len(wheels)):
            raise err("wheels: expected 1 to 4 different names, in the order FL, FR, RL, RR "
                      "(the position is the wheel's index)")
        wheels = list(wheels)
    wsig = raw.get("wheel_signal")
    if wsig is not None:
        if not isinstance(wsig, str) or wsig.count(".") < 1 or dbc is None or wheels is None:
            raise err(f"wheel_signal {wsig!r}: expected \"Message.Signal\" of a bus log (with dbc "
                      "and wheels = [...]) whose value is the wheel's index in wheels")
    time = raw.get("time", {})
    if not isinstance(time, Mapping):
        raise err("[time]: expected a table")
    for k in time:
        if k not in ("master", "rate", "unit"):
            raise err(f"[time]: unknown key '{k}' (expected master, rate or unit)")
    if "master" in time and "rate" in time:
        raise err("[time]: master or rate, not both")
    rate = time.get("rate")
    if rate is not None:
        if isinstance(rate, bool) or not isinstance(rate, (int, float)) or not (
                math.isfinite(rate) and rate > 0):
            raise err(f"[time] rate {rate!r}: expected a number of samples per second > 0")
        rate = float(rate)
    tunit = time.get("unit", "s")
    if tunit not in UNITS["time"]:
        raise err(f"[time] unit '{tunit}': unknown (time units: {', '.join(UNITS['time'])})")
    chans = raw.get("channels")
    if not isinstance(chans, Mapping) or not chans:
        raise err("[channels]: expected a table of gough columns, e.g. fy = { name = \"Fy_FL\", "
                  "unit = \"kN\" }")
    out = {}
    seen = {}
    for col, spec in chans.items():
        if col == "t":
            raise err("'t' is not a channel: the rows' time is the master's ([time] master or "
                      "rate)", column=col)
        if col == "wheel":
            raise err("'wheel' is not a channel: use wheels = [...] and {wheel} in the names",
                      column=col)
        if col not in COLUMNS:
            close = difflib.get_close_matches(col.lower(), list(COLUMNS), n=1)
            hint = f"; did you mean '{close[0]}'?" if close else ""
            raise err(f"unknown column (expected one of {', '.join(COLUMNS)}){hint}", column=col)
        if isinstance(spec, str):
            spec = {"name": spec}
        if not isinstance(spec, Mapping) or not isinstance(spec.get("name"), str) or not spec["name"]:
            raise err("expected { name = \"...\", unit = \"...\" }", column=col)
        for k in spec:
            if k not in ("name", "unit", "sign"):
                raise err(f"unknown key '{k}' (expected name, unit, sign)", column=col)
        unit = spec.get("unit")
        if unit is not None and not isinstance(unit, str):
            raise err(f"unit {unit!r}: expected a string", column=col)
        if unit is not None and unit not in UNITS[COLUMNS[col]]:
            raise LogError(file, _unit_msg(unit, col), channel=spec["name"], column=col)
        sign = spec.get("sign", 1)
        if sign not in (1, -1) or isinstance(sign, bool):
            raise err(f"sign {sign!r}: expected 1 or -1", column=col)
        key = spec["name"]
        if key in seen:
            raise LogError(file, f"the map names this channel twice (columns {seen[key]} and "
                           f"{col})", channel=key, column=col)
        seen[key] = col
        if "{wheel}" in key and wheels is None:
            raise err("{wheel} in the name but no wheels = [...] in the map", column=col)
        out[col] = {"name": key, "unit": unit, "sign": int(sign)}
    master = None
    if rate is None:
        master = time.get("master", "fy")
        if master not in out:
            raise err(f"[time] master '{master}': not a column of the map's [channels] (or give "
                      "rate = ...)", column=master)
    return Map(file=str(file), dbc=dbc, convention=conv, wheels=wheels, wheel_signal=wsig,
               master=master, rate=rate, time_unit=tunit, channels=out)


def _unit_msg(unit, col):
    dim = COLUMNS[col]
    for d, table in UNITS.items():
        if unit in table:
            return f"unit '{unit}' is a {d} unit; column {col} takes {dim}: {', '.join(UNITS[dim])}"
    return f"unknown unit '{unit}' ({dim} units: {', '.join(UNITS[dim])})"


class _Signal:
    __slots__ = ("t", "v", "unit")

    def __init__(self, t, v, unit):
        self.t, self.v, self.unit = t, v, unit


class _Source:
    """Channels by name: ``get(name) -> _Signal`` or None; ``names()`` for suggestions."""

    frames: dict | None = None

    def close(self):
        pass


class _MdfSource(_Source):
    def __init__(self, path: Path):
        try:
            from asammdf import MDF
        except ModuleNotFoundError:
            raise LogError(path, "reading MDF needs asammdf: pip install 'gough[logs]'") from None
        try:
            self.mdf = MDF(path)
        except Exception as e:  # asammdf raises its own and plain exceptions
            raise LogError(path, f"not an MDF file asammdf reads: {_one_line(e)}") from None
        self.path = path

    def close(self):
        self.mdf.close()

    def names(self):
        return list(self.mdf.channels_db)

    def get(self, name):
        if name not in self.mdf.channels_db:
            return None
        occ = self.mdf.channels_db[name]
        if len(occ) > 1:
            groups = sorted({g for g, _ in occ})
            raise LogError(self.path, f"in {len(occ)} channel groups ({groups}): ambiguous",
                           channel=name)
        s = self.mdf.get(name)
        return _Signal(np.asarray(s.timestamps, dtype=np.float64),
                       np.asarray(s.samples, dtype=np.float64), (s.unit or None))


class _BusSource(_Source):
    """Frames (python-can's readers) decoded with a DBC (cantools), kept per `Message.Signal`."""

    def __init__(self, path: Path, dbc: Path, wanted: list[str], map_file: str,
                 wheel_signal: str | None = None, n_wheels: int = 0):
        try:
            import can
            import cantools
        except ModuleNotFoundError:
            raise LogError(path, "reading bus logs needs python-can and cantools: "
                           "pip install 'gough[logs]'") from None
        try:
            self.db = cantools.database.load_file(os.fspath(dbc))
        except FileNotFoundError:
            raise LogError(map_file, f"dbc '{dbc}': no such file") from None
        except Exception as e:
            raise LogError(dbc, f"not a DBC cantools reads: {_one_line(e)}") from None
        self.path = path
        self.sig: dict[str, _Signal] = {}
        self._names = [f"{m.name}.{s.name}" for m in self.db.messages for s in m.signals]
        want: dict[str, set] = {}
        wmsg, wsig = wheel_signal.split(".", 1) if wheel_signal else (None, None)
        if wmsg is not None:
            try:
                if wsig not in {s.name for s in self.db.get_message_by_name(wmsg).signals}:
                    raise KeyError(wsig)
            except KeyError:
                raise LogError(map_file, "wheel_signal: not in the DBC", channel=wheel_signal) from None
        for full in wanted:
            if "." not in full:
                continue  # reported as missing, with a hint, by read()
            m, s = full.split(".", 1)
            want.setdefault(m, set()).add(s)
        msgs = {}
        for mname, sigs in want.items():
            try:
                msg = self.db.get_message_by_name(mname)
            except KeyError:
                continue
            msgs[(msg.frame_id, bool(msg.is_extended_frame))] = (msg, sigs & {s.name for s in msg.signals})
        rows: dict[str, tuple[list, list]] = {}
        counts = {"read": 0, "used": 0, "not in the map's messages": 0, "error or remote": 0,
                  "not decodable with the DBC": 0}
        if wmsg is not None:
            counts["not the wheel signal's kind"] = 0
            counts["wheel not in the map's wheels"] = 0
        try:
            reader = can.LogReader(os.fspath(path))
        except Exception as e:
            raise LogError(path, f"not a bus log python-can reads: {_one_line(e)}") from None
        try:
            with reader:
                for fr in reader:
                    counts["read"] += 1
                    if fr.is_error_frame or fr.is_remote_frame:
                        counts["error or remote"] += 1
                        continue
                    hit = msgs.get((fr.arbitration_id, bool(fr.is_extended_id)))
                    if hit is None:
                        counts["not in the map's messages"] += 1
                        continue
                    msg, sigs = hit
                    try:
                        vals = msg.decode(bytes(fr.data), decode_choices=False)
                    except Exception:
                        counts["not decodable with the DBC"] += 1
                        continue
                    suffix = ""
                    if msg.name == wmsg:
                        if wsig not in vals:  # a multiplexed message: another of its kinds
                            counts["not the wheel signal's kind"] += 1
                            continue
                        wv = int(vals[wsig])
                        if not 0 <= wv < n_wheels:
                            counts["wheel not in the map's wheels"] += 1
                            continue
                        suffix = f"@{wv}"
                    counts["used"] += 1
                    for s in sigs:
                        if s in vals:  # a multiplexed signal is in some frames only
                            ts, vs = rows.setdefault(f"{msg.name}.{s}{suffix}", ([], []))
                            ts.append(fr.timestamp)
                            vs.append(float(vals[s]))
        except LogError:
            raise
        except Exception as e:
            raise LogError(path, f"bus log unreadable after {counts['read']} frames: "
                           f"{_one_line(e)}") from None
        self.frames = counts
        units = {f"{m.name}.{s.name}": (s.unit or None) for m in self.db.messages for s in m.signals}
        for k, (ts, vs) in rows.items():
            self.sig[k] = _Signal(np.asarray(ts, dtype=np.float64), np.asarray(vs, dtype=np.float64),
                                  units.get(k.split("@", 1)[0]))

    def names(self):
        return self._names

    def get(self, name):
        return self.sig.get(name)


def _one_line(e: BaseException) -> str:
    s = " ".join(str(e).split())
    return s or type(e).__name__


def _is_bus_mdf(path: Path) -> bool:
    from asammdf import MDF

    with MDF(path) as mdf:
        return "CAN_DataFrame" in mdf.channels_db or "CAN_DataFrame.ID" in mdf.channels_db


def read(path: str | os.PathLike, map: str | os.PathLike | Mapping[str, Any]):
    """The log at `path` (MDF4/MDF3, BLF, ASC, candump .log, MDF4 CAN bus logging) as a pandas
    DataFrame of gough's columns (``t`` first, then those the map fills, then ``wheel`` when the
    map has ``wheels``), SI units, ISO-W axes. ``df.attrs``: ``dropped`` (a list of {column,
    channel, wheel, rows, reason}), ``rows_in`` (master rows before dropping), ``frames`` (bus
    logs: frames read, used, and not used with why), ``source``, ``map``. Raises LogError (a
    ValueError) with one line naming the file and the channel."""
    m = load_map(map)
    path = Path(path)
    if not path.exists():
        raise LogError(path, "no such file")
    suffix = path.suffix.lower()
    wheels = m["wheels"] or [None]
    names = {}
    for w in wheels:
        for col, spec in m["channels"].items():
            names[(w, col)] = spec["name"].replace("{wheel}", w) if w is not None else spec["name"]
    if suffix in _BUS or (suffix in _MDF and m["dbc"] is not None and _is_bus_mdf(path)):
        if m["dbc"] is None:
            raise LogError(path, f"a bus log ({suffix}): the map needs dbc = \"...\" to decode "
                           "its frames")
        src: _Source = _BusSource(path, m["dbc"], sorted(set(names.values())), m["file"],
                                  m.get("wheel_signal"), len(m["wheels"] or []))
    elif suffix in _MDF:
        if m.get("wheel_signal"):
            raise LogError(path, "wheel_signal is for bus logs: an MDF of signals names each wheel's "
                           "channel ({wheel} in the name)")
        src = _MdfSource(path)
    else:
        raise LogError(path, f"unknown log format '{suffix}' (MDF: {', '.join(_MDF)}; bus logs: "
                       f"{', '.join(_BUS)})")
    try:
        return _read(path, m, src, names)
    finally:
        src.close()


def _read(path, m, src, names):
    import pandas as pd

    wheels = m["wheels"] or [None]
    tscale = UNITS["time"][m["time_unit"]]
    sae = m["convention"] == "SAE"
    frames = []
    dropped = []
    rows_in = 0
    wmsg = m["wheel_signal"].split(".", 1)[0] if m.get("wheel_signal") else None
    for wi, w in enumerate(wheels):
        sigs = {}
        for col, spec in m["channels"].items():
            name = names[(w, col)]
            routed = wmsg is not None and name.split(".", 1)[0] == wmsg
            s = src.get(f"{name}@{wi}" if routed else name)
            if s is None and routed and name in src.names():
                raise LogError(path, f"no frame of it for wheel {w} ({m['wheel_signal']} = {wi})",
                               channel=name, column=col)
            if s is None:
                cands = src.names()
                close = difflib.get_close_matches(name, cands, n=1)
                hint = f"; did you mean '{close[0]}'?" if close else ""
                what = "no frame of it in the log" if isinstance(src, _BusSource) and name in cands \
                    else "not in the log" if not isinstance(src, _BusSource) \
                    else "not in the DBC (a bus log's channels are 'Message.Signal')"
                raise LogError(path, what + hint, channel=name, column=col)
            unit = spec["unit"] or s.unit
            if unit is None:
                raise LogError(path, "no unit in the map nor in the file: give unit = \"...\"",
                               channel=name, column=col)
            if unit not in UNITS[COLUMNS[col]]:
                where = "the file's" if spec["unit"] is None else "the map's"
                raise LogError(path, f"{where} " + _unit_msg(unit, col), channel=name, column=col)
            t = s.t * tscale
            if len(t) == 0:
                raise LogError(path, "no samples", channel=name, column=col)
            d = np.diff(t)
            bad = np.flatnonzero(~(d > 0))
            if len(bad):
                i = int(bad[0])
                raise LogError(path, f"time does not increase at sample {i + 1} ({t[i]!r} s then "
                               f"{t[i + 1]!r} s)", channel=name, column=col)
            v = s.v * UNITS[COLUMNS[col]][unit] * spec["sign"]
            if sae and col in SAE_NEGATED:
                v = -v
            sigs[col] = (name, t, v)
        if m["rate"] is not None:
            t0 = min(t[0] for _, t, _ in sigs.values())
            t1 = max(t[-1] for _, t, _ in sigs.values())
            n = int(math.floor((t1 - t0) * m["rate"] + 1e-9)) + 1
            tm = t0 + np.arange(n) / m["rate"]
        else:
            tm = sigs[m["master"]][1]
        rows_in += len(tm)
        keep = np.ones(len(tm), dtype=bool)
        cols = {"t": tm}
        for col, (name, t, v) in sigs.items():
            if len(t) == len(tm) and np.array_equal(t, tm):
                val = v.copy()
                outside = np.zeros(len(tm), dtype=bool)
            else:
                outside = (tm < t[0]) | (tm > t[-1])
                val = np.interp(tm, t, v)
            nan = ~np.isfinite(val) & ~outside
            for what, mask in (("outside the channel's time span (no extrapolation)", outside),
                               ("not a number", nan)):
                k = int((mask & keep).sum())
                if k:
                    dropped.append({"column": col, "channel": name, "wheel": w, "rows": k,
                                    "reason": what})
                keep &= ~mask
            cols[col] = val
        df = pd.DataFrame({c: cols[c] for c in _ORDER if c in cols})[keep]
        if m["wheels"] is not None:
            df["wheel"] = wi
        frames.append(df)
    df = pd.concat(frames, ignore_index=True)
    if m["wheels"] is not None and len(wheels) > 1:
        df = df.sort_values(["t", "wheel"], kind="stable", ignore_index=True)
    df.attrs["source"] = str(path)
    df.attrs["map"] = m["file"]
    df.attrs["rows_in"] = rows_in
    df.attrs["dropped"] = dropped
    if src.frames is not None:
        df.attrs["frames"] = dict(src.frames)
    if len(df) == 0:
        raise LogError(path, f"no rows left of {rows_in} ({_drops(dropped)})")
    return df


def _drops(dropped) -> str:
    return "; ".join(
        f"{d['rows']} rows: {d['column']} ({d['channel']}{', ' + d['wheel'] if d['wheel'] else ''})"
        f" {d['reason']}" for d in dropped) or "none dropped"


def write(df, out: str | os.PathLike) -> None:
    """Writes `df` as the CSV the ``gough`` CLI reads (header, comma-separated, every float with
    the digits that read back the same f64) or as Parquet (suffix .parquet or .pq)."""
    out = os.fspath(out)
    if out.endswith(".parquet") or out.endswith(".pq"):
        try:
            df.to_parquet(out, index=False)
        except ImportError as e:
            raise LogError(out, f"writing Parquet needs pyarrow: pip install 'gough[logs]' "
                           f"({_one_line(e)})") from None
        return
    # pandas writes floats with repr(): the shortest text that reads back the same number.
    df.to_csv(out, index=False)


def main(argv: list[str] | None = None) -> int:
    """``gough-logs convert IN --map MAP.toml --out OUT.csv|OUT.parquet``."""
    ap = argparse.ArgumentParser(prog="gough-logs", description=(
        "Logs as cars record them (MDF4, BLF, ASC, candump, MDF4 bus logging) through a map into "
        "the CSV or Parquet log the gough CLI reads (SI, ISO-W, one time base)."))
    sub = ap.add_subparsers(dest="cmd", required=True)
    c = sub.add_parser("convert", help="read a log through a map and write gough's columns")
    c.add_argument("log", help="the log: .mf4/.mdf/.dat, .blf, .asc, .log (candump)")
    c.add_argument("--map", required=True, help="the map (TOML)")
    c.add_argument("--out", required=True, help="OUT.csv or OUT.parquet")
    a = ap.parse_args(argv)
    try:
        df = read(a.log, a.map)
        write(df, a.out)
    except (LogError, OSError) as e:
        print(f"gough-logs: {e}", file=sys.stderr)
        return 1
    print(f"{a.log}: {len(df)} rows of {df.attrs['rows_in']} -> {a.out} "
          f"(columns {', '.join(map(str, df.columns))})")
    for d in df.attrs["dropped"]:
        w = f", wheel {d['wheel']}" if d["wheel"] else ""
        print(f"  dropped {d['rows']} rows: {d['column']} ({d['channel']}{w}) {d['reason']}")
    fr = df.attrs.get("frames")
    if fr is not None:
        unused = ", ".join(f"{v} {k}" for k, v in fr.items() if k not in ("read", "used") and v)
        print(f"  frames: {fr['read']} read, {fr['used']} decoded" + (f"; not used: {unused}" if unused else ""))
    return 0


if __name__ == "__main__":  # pragma: no cover
    sys.exit(main())
