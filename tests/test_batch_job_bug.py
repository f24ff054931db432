"""A job's unexpected exception (a bug in frictex or a plugin renderer) is that job's failed
row, in every runner: the other jobs complete, batch.csv lists it, exit 1. It used to
escape the batch as an internal error (exit 70) with no --out at all."""

import csv
import threading

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.batch import Job, run_job

MANIFEST = ("scene,trace,name\n"
            "grating-5mm,swipe-40mms-50hz,a\n"
            "grating-15mm,circle-30mms-60hz,bug\n"
            "grating-5mm,swipe-40mms-50hz,c\n")


class Unpicklable(RuntimeError):
    """An exception a worker process cannot send back (it holds a lock)."""

    def __init__(self, message):
        super().__init__(message)
        self.lock = threading.Lock()


def plugin_bug(monkeypatch, error):
    """Every job replaying the circle trace raises ``error`` from its replay."""
    from frictex.app.engine import replay
    real = replay.run_replay

    def run_replay(scene, trace, out, **kwargs):
        if "circle" in str(trace):
            raise error
        return real(scene, trace, out, **kwargs)
    monkeypatch.setattr(replay, "run_replay", run_replay)


def statuses(out):
    with open(out / "batch.csv", newline="") as fh:
        return {row["name"]: (row["status"], row["error"]) for row in csv.DictReader(fh)}


@pytest.mark.parametrize("error", [RuntimeError("plugin bug"), Unpicklable("plugin bug")])
@pytest.mark.parametrize("jobs", ["1", "2"])
def test_a_jobs_bug_fails_that_job_only(tmp_path, monkeypatch, capsys, jobs, error):
    plugin_bug(monkeypatch, error)
    manifest = tmp_path / "m.csv"
    manifest.write_text(MANIFEST)
    out = tmp_path / "out"
    assert main(["batch", str(manifest), "--out", str(out), "--jobs", jobs, "--quiet"]) == 1
    rows = statuses(out)
    assert {name: status for name, (status, _) in rows.items()} == {
        "a": "ok", "bug": "failed", "c": "ok"}
    assert rows["bug"][1].startswith("internal error (a bug in frictex or a plugin")
    assert rows["bug"][1].endswith(f"{type(error).__name__}: plugin bug")
    assert sorted(p.name for p in out.iterdir()) == ["a", "batch.csv", "c"]
    err = capsys.readouterr().err
    assert "1 of 3 jobs failed: bug: internal error" in err
    assert "frictex: internal error: please report" not in err  # the whole command's


def test_the_traceback_is_on_stderr_once(tmp_path, monkeypatch, capsys):
    plugin_bug(monkeypatch, KeyError("layer"))
    row = run_job(Job(0, "grating-15mm", "circle-30mms-60hz", None, 1e4, 50, "csv", "j"),
                  str(tmp_path))
    assert row["status"] == "failed" and row["error"].endswith("KeyError: 'layer'")
    err = capsys.readouterr().err
    assert err.count("Traceback (most recent call last)") == 1
    assert "frictex: internal error in job j: please report it" in err


@pytest.mark.parametrize("signal_exit", [KeyboardInterrupt(), SystemExit(143)])
def test_a_signal_still_stops_the_job(tmp_path, monkeypatch, signal_exit):
    plugin_bug(monkeypatch, signal_exit)
    with pytest.raises(type(signal_exit)):
        run_job(Job(0, "grating-15mm", "circle-30mms-60hz", None, 1e4, 50, "csv", "j"),
                str(tmp_path))


def test_a_jobs_bug_on_a_dask_cluster_fails_that_job_only(tmp_path, monkeypatch):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed "
                                      "(pip install 'frictex[cluster]')")
    plugin_bug(monkeypatch, Unpicklable("plugin bug"))
    manifest = tmp_path / "m.csv"
    manifest.write_text(MANIFEST)
    out = tmp_path / "out"
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=False,
                                  protocol="tcp://", host="127.0.0.1",
                                  dashboard_address=None) as cluster:
        code = main(["batch", str(manifest), "--out", str(out),
                     "--scheduler", cluster.scheduler_address, "--quiet"])
    assert code == 1
    assert {name: status for name, (status, _) in statuses(out).items()} == {
        "a": "ok", "bug": "failed", "c": "ok"}


def raise_unpicklable(k: int) -> int:
    if k == 1:
        raise Unpicklable("plugin bug")
    return k


def test_an_exception_a_worker_cannot_send_back_is_its_text():
    """fan_out of any function over worker processes: such an exception used to reach
    the caller as the pickling's own error (TypeError: cannot pickle '_thread.lock')."""
    from frictex.app.engine.fanout import fan_out
    with pytest.raises(RuntimeError, match=r"Unpicklable: plugin bug\n\(raised in a worker"):
        fan_out(raise_unpicklable, [0, 1, 2], workers=2)
