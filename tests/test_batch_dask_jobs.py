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


def test_batch_csv_names_a_scene_and_a_trace_as_the_manifest_writes_them(tmp_path):
    """They were the files' resolved paths (/tmp/.../bad.toml for bad.toml)."""
    (tmp_path / "sub").mkdir()
    (tmp_path / "sub" / "bad.toml").write_text("not a scene\n")
    (tmp_path / "m.csv").write_text("scene,trace,name\n./sub/bad.toml,swipe-40mms-50hz,a\n")
    out = tmp_path / "out"
    assert main(["batch", str(tmp_path / "m.csv"), "--out", str(out), "--quiet",
                 "--jobs", "1"]) == 1
    with open(out / "batch.csv", newline="") as fh:
        (row,) = csv.DictReader(fh)
    assert (row["status"], row["scene"], row["trace"]) == (
        "failed", "./sub/bad.toml", "swipe-40mms-50hz")
