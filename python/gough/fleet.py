"""Fleet logs: the gap diagnosis of many logs on a dask.distributed cluster.

`diagnose(paths, tir, client=None)` runs `gough.diagnose_gap` once per log, each task reading its
own CSV or Parquet file (or, with `map=`, a log as cars record it: MDF4, BLF, ASC, candump, read
through the map by `gough.logs`) on a worker, and returns one table of verdicts (a pandas DataFrame, one
row per log, in the order of `paths`). With `client=None` it runs serially in this process; with
a `dask.distributed.Client` (a `LocalCluster` or a real cluster) the same call is spread over the
cluster's workers. The engine is Dask's, not ours.
"""
from __future__ import annotations

import os
from typing import Iterable, Sequence

import pandas as pd

#: Columns of the verdict table.
#: `effect` is the first effect named; `effects` every effect named, "+"-joined (a second one
#: when forward selection keeps it); `shrink` the held-out shrink of all of them.
COLUMNS = ["log", "effect", "effects", "shrink", "channel", "indistinguishable_from", "rows"]


def diagnose_one(path: str, tir: str, fit_rows: int | None = None, map=None) -> dict:
    """One row of the verdict table: the diagnosis of the log at `path` (CSV or Parquet; with
    `map`, a log read through the map)."""
    import gough

    tyre = gough.Tyre.from_tir(tir)
    log = gough.read_log(path, map)
    rep = gough.diagnose_gap(tyre, log, tir_name=tir, log_name=path, fit_rows=fit_rows)
    v = rep["verdict"]
    return {
        "log": path,
        "effect": v["effect"],
        "effects": "+".join(e["effect"] for e in v.get("effects") or []) or v["effect"],
        "shrink": v.get("shrink"),
        "channel": v.get("channel"),
        "indistinguishable_from": ",".join(v.get("indistinguishable_from") or []),
        "rows": len(log),
    }


def diagnose(paths: Sequence[str | os.PathLike], tir: str | os.PathLike, client=None,
             fit_rows: int | None = None, map=None) -> pd.DataFrame:
    """The verdict of every log in `paths` against the sim of the `.tir` file `tir`, as one
    DataFrame (columns `COLUMNS`, rows in the order of `paths`). `client`: a
    `dask.distributed.Client`, or None to run here, one log after another. A log that fails
    raises its error (a ValueError naming the file) after the others have been submitted.
    `map`: every log is read through this map (a TOML file or a dict, `gough.logs`); a map file
    is read once here, its DBC path made absolute, so the workers need only the logs and the
    DBC."""
    paths = [os.fspath(p) for p in paths]
    tir = os.fspath(tir)
    if map is not None:
        from .logs import load_map

        map = load_map(map)
    if client is None:
        rows: Iterable[dict] = [diagnose_one(p, tir, fit_rows, map) for p in paths]
    else:
        futures = client.map(diagnose_one, paths, tir=tir, fit_rows=fit_rows, map=map, pure=False)
        rows = client.gather(futures)
    return pd.DataFrame(list(rows), columns=COLUMNS)
