"""A batch stopped by SIGTERM or SIGHUP ends with the line and the status a replay's
SIGTERM gives: ``frictex: terminated by SIGTERM``, 128 + the signal."""

import signal

import pytest

from frictex.app.commands import batch
from frictex.app.commands.cli import main
from frictex.app.engine.fanout import Interrupted


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_a_terminated_batch_says_so_as_a_replay_does(tmp_path, monkeypatch, capsys, sig):
    manifest = tmp_path / "m.csv"
    manifest.write_text("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\n")

    def stopped(args, jobs, out_dir):  # the signal came before the job started
        stop = Interrupted(sig, [None], [])
        return [batch._interrupted(jobs[0], stop)], stop

    monkeypatch.setattr(batch, "_run_jobs", stopped)
    with pytest.raises(SystemExit) as exit_:
        main(["batch", str(manifest), "--out", str(tmp_path / "out"), "--quiet"])
    assert exit_.value.code == 128 + sig
    err = capsys.readouterr().err.strip().splitlines()
    assert err[0].startswith("0 of 1 jobs finished")
    assert err[1:] == [f"frictex: terminated by {signal.Signals(sig).name}"]
    assert (tmp_path / "out" / "batch.csv").exists()
