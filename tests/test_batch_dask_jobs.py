"""A batch on a Dask cluster reports in jobs, and its batch.csv as its manifest is
written; a stopped one takes the jobs that finish and leaves nothing of the others in
--out. The cluster's scheduler runs in this process on loopback."""

import csv
import os
import signal
import threading
import time
from functools import partial
from pathlib import Path

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine import fanout
from frictex.app.engine.batch_folder import BatchFolder

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


def sleeper(marks: str, name: str) -> str:
    """An item: marks that it started, then sleeps until ``<name>.go`` appears in
    ``marks`` (at most 30 s)."""
    folder = Path(marks)
    (folder / f"{name}.start").write_text("")
    end = time.monotonic() + 30
    while not (folder / f"{name}.go").exists() and time.monotonic() < end:
        time.sleep(0.02)
    return name


def test_a_signal_takes_the_items_that_finish_and_warns_of_those_running_on(
        tmp_path, capsys, monkeypatch):
    """'quick' finished just after the signal and was counted stopped while it ran, its
    result dropped; 'slow' ran on unsaid. Now quick's result is taken, slow (still
    running after DASK_STOP_S) is stopped with a warning, 'queued' never starts."""
    monkeypatch.setattr(fanout, "DASK_STOP_S", 1.0)
    with distributed.LocalCluster(n_workers=1, threads_per_worker=2, processes=False,
                                  protocol="tcp://", host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        def signal_once_both_run():
            while not all((tmp_path / f"{n}.start").exists() for n in ("quick", "slow")):
                time.sleep(0.02)
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.2)
            (tmp_path / "quick.go").write_text("")

        threading.Thread(target=signal_once_both_run, daemon=True).start()
        try:
            with pytest.raises(fanout.Interrupted) as stop:
                fanout.fan_out(partial(sleeper, str(tmp_path)), ["quick", "slow", "queued"],
                               scheduler=cluster.scheduler_address)
        finally:
            (tmp_path / "slow.go").write_text("")
    assert (stop.value.results, stop.value.stopped) == (["quick", None, None], [1])
    assert not (tmp_path / "queued.start").exists()
    assert capsys.readouterr().err.strip() == (
        "frictex: warning: 1 of the items stopped still running on their Dask workers after "
        "1 s (Dask cannot stop a running task): results dropped")


def test_a_stopped_batch_leaves_in_out_only_the_folders_batch_csv_lists(tmp_path):
    """A Dask job running on after the batch's end kept writing its staging folder,
    .L6.frictex-staging.*, inside --out."""
    out = tmp_path / "out"
    folder = BatchFolder(out, ["L5", "L6"])
    staged = folder.begin()
    (staged / "L5").mkdir()
    (staged / "L5" / "summary.json").write_text("{}")
    (staged / ".L6.frictex-staging.1.x").mkdir()
    (staged / ".L6.frictex-staging.1.x" / "commands.csv.partial").write_text("t_s\n")
    rows = [{"job": 0, "name": "L5", "scene": "s", "trace": "t", "status": "ok",
             "error": ""},
            {"job": 1, "name": "L6", "scene": "s", "trace": "t", "status": "interrupted",
             "error": "stopped while it ran"}]
    folder.commit([{**dict.fromkeys(("output_s", "wall_s", "x_realtime",
                                     "x_realtime_end_to_end", "clamps", "actuator_limited",
                                     "modal_capped", "modal_unserved", "warnings")), **row}
                   for row in rows],
                  stopped=True)
    assert sorted(p.name for p in out.iterdir()) == ["L5", "batch.csv"]
