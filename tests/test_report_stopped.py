"""``frictex report`` stopped by a signal says which, with its status, and leaves no
empty --out behind."""

import signal

import pytest

from frictex.app.commands import report
from frictex.app.commands.cli import main
from frictex.app.engine.fanout import Interrupted


@pytest.mark.parametrize("sig, line, code", [
    (signal.SIGTERM, "frictex: terminated by SIGTERM", 143),
    (signal.SIGHUP, "frictex: terminated by SIGHUP", 129),
    (signal.SIGINT, "frictex: interrupted", 130)])
def test_a_report_stopped_by_a_signal_says_which(tmp_path, monkeypatch, capsys, sig, line, code):
    def stopped(fn, cases, **kwargs):  # the signal came before the first case ended
        raise Interrupted(sig, [None] * len(cases), [0])

    monkeypatch.setattr(report, "fan_out", stopped)
    out = tmp_path / "new" / "report"
    assert main(["report", "--quick", "--out", str(out), "--no-progress"]) == code
    assert capsys.readouterr().err.strip().splitlines()[-1] == line
    assert not (tmp_path / "new").exists()  # the folders it made for --out, all of them


def test_a_stopped_report_leaves_a_folder_it_did_not_make(tmp_path, monkeypatch):
    def stopped(fn, cases, **kwargs):
        raise Interrupted(signal.SIGTERM, [None] * len(cases), [])

    monkeypatch.setattr(report, "fan_out", stopped)
    assert main(["report", "--quick", "--out", str(tmp_path), "--no-progress"]) == 143
    assert tmp_path.is_dir()
