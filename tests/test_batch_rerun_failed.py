"""A stopped rerun whose job failed before the stop: that job's row is ``failed`` with its
error (saying the earlier batch's folder of it was kept), not ``earlier ... stopped
before it replaced it`` as it was."""

import csv
import json
import signal

import pytest

from frictex.app.commands.cli import main


def batch(path, out) -> int:
    return main(["batch", str(path), "--out", str(out), "--jobs", "1", "--quiet"])


def rows(out) -> dict:
    with open(out / "batch.csv", newline="") as fh:
        return {row["name"]: row for row in csv.DictReader(fh)}


def test_a_job_that_failed_before_the_stop_is_listed_failed(tmp_path, capsys, monkeypatch):
    from frictex.app.commands import batch as command
    from frictex.app.engine.fanout import Interrupted
    (tmp_path / "broken-trace.csv").write_text("not,a,trace\n")
    first, rerun = tmp_path / "m4.csv", tmp_path / "m5.csv"
    first.write_text("scene,trace,name\n" + "".join(f"grating-5mm,swipe-40mms-50hz,j{k}\n"
                                                    for k in range(3)))
    rerun.write_text(first.read_text().replace("swipe-40mms-50hz,j0", "broken-trace.csv,j0"))
    out = tmp_path / "o6"
    assert batch(first, out) == 0
    summary = (out / "j0" / "summary.json").read_bytes()
    real = command.fan_out

    def stopped_after_first(fn, items, **kwargs):  # SIGTERM once j0 has failed
        done = real(fn, items[:1], workers=1, on_done=kwargs["on_done"])
        raise Interrupted(signal.SIGTERM, done + [None] * (len(items) - 1), [1])
    monkeypatch.setattr(command, "fan_out", stopped_after_first)
    with pytest.raises(SystemExit) as stop:
        batch(rerun, out)
    assert stop.value.code == 128 + signal.SIGTERM
    err = capsys.readouterr().err
    assert "job j0 failed" in err
    assert ", 3 earlier job folders kept; " in err  # j0's too, though its row is failed
    listed = rows(out)
    assert {name: row["status"] for name, row in listed.items()} == {
        "j0": "failed", "j1": "earlier", "j2": "earlier"}
    assert listed["j0"]["trace"] == "broken-trace.csv"
    assert "broken-trace.csv" in listed["j0"]["error"]
    assert listed["j0"]["error"].endswith("the earlier batch's output of this job was kept "
                                          "(this one was stopped)")
    assert listed["j0"]["output_s"] == ""
    assert "stopped before it replaced it" in listed["j1"]["error"]
    assert (out / "j0" / "summary.json").read_bytes() == summary
    assert json.loads(summary)["output"]["duration_s"] > 0
