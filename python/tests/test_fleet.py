"""`gough.fleet.diagnose` on a dask.distributed LocalCluster equals the serial run, over a
handful of logs in CSV and Parquet."""
import pandas as pd
import pytest

from conftest import EXAMPLES, TIR61
import gough
from gough import fleet

FIT_ROWS = 100  # fewer training rows per fit: the same for both runs, quicker


@pytest.fixture(scope="module")
def logs(tmp_path_factory):
    d = tmp_path_factory.mktemp("fleet")
    cam = pd.read_csv(EXAMPLES / "gap_camber.csv", comment="#")
    thm = pd.read_csv(EXAMPLES / "gap_thermal_mu.csv", comment="#")
    # Slices of the bundled examples keep the test quick (a debug build diagnoses them).
    cam.head(400).to_csv(d / "camber_400.csv", index=False)
    cam.head(400).to_parquet(d / "camber_400.parquet")
    thm.head(400).to_csv(d / "thermal_400.csv", index=False)
    thm.iloc[400:800].to_parquet(d / "thermal_b.parquet")
    cam.iloc[400:700].to_csv(d / "camber_b.csv", index=False)
    paths = [d / n for n in ("camber_400.csv", "thermal_400.csv", "camber_400.parquet",
                             "thermal_b.parquet", "camber_b.csv")]
    return [str(p) for p in paths]


def test_distributed_equals_serial(logs):
    from dask.distributed import Client, LocalCluster

    serial = fleet.diagnose(logs, TIR61, client=None, fit_rows=FIT_ROWS)
    with LocalCluster(n_workers=2, threads_per_worker=1, processes=True,
                      dashboard_address=None) as cluster, Client(cluster) as client:
        dist = fleet.diagnose(logs, TIR61, client=client, fit_rows=FIT_ROWS)
    assert list(dist.columns) == fleet.COLUMNS
    assert len(dist) == len(logs)
    pd.testing.assert_frame_equal(dist, serial)
    assert list(dist.log) == logs
    # Parquet and CSV of the same log give the same verdict.
    assert dist.effect[0] == dist.effect[2] and dist.shrink[0] == dist.shrink[2]
    assert dist.rows.tolist() == [400, 400, 400, 400, 300]


def test_a_bad_log_raises_naming_it(tmp_path):
    bad = tmp_path / "short.csv"
    pd.read_csv(EXAMPLES / "gap_camber.csv", comment="#").head(20).to_csv(bad, index=False)
    with pytest.raises(ValueError, match="short.csv"):
        fleet.diagnose([bad], TIR61)
