"""--record is kept in session.json: --resume goes on with the session's own (a session
started with --record results wrote 94 MB of trial folders after a resume without it),
and refuses another one given again."""

import json

import pytest

from frictex.app.commands.cli import main as cli_main
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import make_presenter, run_session
from frictex.device.errors import InputError

from test_experiment_resume_parts import PARTICIPANT, PROTOCOL


class Stop(Exception):
    """Ends a run between trials, as a kill would."""


def stopped_after(trials: int):
    """A ``between_trials`` that stops the run once ``trials`` trials are answered."""
    seen = []

    def check():
        seen.append(1)
        if len(seen) >= trials:
            raise Stop()
    return check


@pytest.fixture
def half_done(tmp_path):
    """A session started with --record results, stopped after 3 of its 8 trials."""
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    out = tmp_path / "s"
    with pytest.raises(Stop):
        run_session(load_protocol(path), make_presenter(PARTICIPANT), out, seed=4,
                    participant=PARTICIPANT, record="results", between_trials=stopped_after(3))
    return path, out


def test_resume_keeps_the_record_the_session_started_with(half_done, capsys):
    path, out = half_done
    assert json.loads((out / "session.json").read_text())["record"] == "results"
    assert cli_main(["experiment", str(path), "--out", str(out), "--resume", "--quiet"]) == 0
    assert len((out / "results.csv").read_text().splitlines()) == 9
    assert list((out / "trials").iterdir()) == []  # no trial's scene, trace or replay
    assert json.loads((out / "session.json").read_text())["record"] == "results"


def test_resume_refuses_another_record(half_done):
    path, out = half_done
    with pytest.raises(InputError, match=r"--record all: .* was started with --record "
                                         r"results, and a resumed session keeps it; leave "
                                         r"--record out$"):
        run_session(load_protocol(path), make_presenter(PARTICIPANT), out, resume=True,
                    record="all")
    assert len((out / "results.csv").read_text().splitlines()) == 4  # nothing ran


def test_a_new_session_records_all_by_default(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    out = tmp_path / "s"
    session = run_session(load_protocol(path), make_presenter(PARTICIPANT), out, seed=4,
                          participant=PARTICIPANT)
    assert session.info["record"] == "all"
    assert (out / "trials" / "0001" / "1" / "commands.csv").exists()


def test_resuming_from_the_sessions_protocol_keeps_the_studys_name(half_done, monkeypatch):
    """DIR/protocol.toml of a protocol without ``name`` would be named "protocol"."""
    path, out = half_done
    named = []
    presenter = make_presenter(PARTICIPANT)
    begin = presenter.begin
    monkeypatch.setattr(presenter, "begin", lambda protocol: (named.append(protocol.name),
                                                              begin(protocol)))
    run_session(load_protocol(out / "protocol.toml"), presenter, out, resume=True)
    assert named == ["p"]
