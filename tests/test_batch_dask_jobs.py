"""A batch on a Dask cluster reports in jobs, and its batch.csv as its manifest is
written. The cluster's scheduler runs in this process on loopback."""

import csv

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine import fanout

distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed "
                                  "(pip install 'frictex[cluster]')")

MANIFEST = "scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\ngrating-5mm,swipe-40mms-50hz,b\n"


@pytest.fixture
def cluster():
    """A scheduler on loopback, in this process, with no worker."""
    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp://",
                                  host="127.0.0.1", dashboard_address=None) as local:
        yield local


def test_a_cluster_without_workers_gives_up_jobs_not_items(tmp_path, cluster, capsys,
                                                           monkeypatch):
    monkeypatch.setattr(fanout, "NO_WORKER_S", 0.5)
    monkeypatch.setattr(fanout, "WORKER_CHECK_S", 0.1)
    (tmp_path / "m.csv").write_text(MANIFEST)
    code = main(["batch", str(tmp_path / "m.csv"), "--out", str(tmp_path / "out"), "--quiet",
                 "--scheduler", cluster.scheduler_address])
    assert code == 1
    assert capsys.readouterr().err.strip().splitlines()[-1].endswith(
        "gave up 2 of 2 jobs unfinished")
