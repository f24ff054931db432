"""--resume after a kill: the killed part's trials are counted from results.csv and its
end is said to be unknown; a participant id on a session without one is said so."""

import json

import pytest

from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import make_presenter, run_session
from frictex.device.errors import InputError

PROTOCOL = """format = 1
method = "2afc"
repetitions = 2
[stimuli]
scene = "grating-5mm"
vary = "depth"
reference = 0.3
levels = [0.32, 0.42]
[presentation]
exploration_s = 0.3
"""
PARTICIPANT = "simulated:weber=0.11,seed=3"


def run(path, out, **kw):
    return run_session(load_protocol(path), make_presenter(PARTICIPANT), out, seed=4,
                       participant=PARTICIPANT, record="results", **kw)


@pytest.fixture
def killed(tmp_path):
    """A session whose run was killed after 5 of its 8 trials (no end in session.json)."""
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    out = tmp_path / "s"
    run(path, out)
    lines = (out / "results.csv").read_text().splitlines(keepends=True)
    (out / "results.csv").write_text("".join(lines[:6]))
    info = json.loads((out / "session.json").read_text())
    info["parts"][0].update(ended_utc=None, trials=0, ended=None)
    info["ended_utc"] = None
    (out / "session.json").write_text(json.dumps(info))
    return path, out


def test_a_killed_part_is_counted_on_resume(killed):
    path, out = killed
    run(path, out, resume=True)
    parts = json.loads((out / "session.json").read_text())["parts"]
    assert [(p["first_trial"], p["trials"], p["ended"]) for p in parts] == [
        (1, 5, "killed (no end recorded)"), (6, 3, "complete")]


def test_a_participant_id_for_a_session_without_one(killed):
    path, out = killed
    with pytest.raises(InputError, match="was started without a participant id$"):
        run(path, out, resume=True, participant_id="P07")


def test_resuming_a_complete_session_says_so_and_leaves_session_json_alone(tmp_path):
    """Each --resume of a finished session added an empty part (first_trial 9, trials 0)."""
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    out = tmp_path / "s"
    run(path, out)
    before = (out / "session.json").read_bytes()
    for _ in range(2):
        resumed = run(path, out, resume=True)
        assert resumed.complete_before and len(resumed.rows) == 8
    assert (out / "session.json").read_bytes() == before


def test_the_command_says_a_resumed_session_was_already_complete(tmp_path, capsys):
    from frictex.app.commands.cli import main
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    out = tmp_path / "s"
    argv = ["experiment", str(path), "--participant", PARTICIPANT, "--out", str(out),
            "--quiet"]
    assert main(argv) == 0
    capsys.readouterr()
    assert main(argv + ["--resume"]) == 0
    err = capsys.readouterr().err
    assert err.startswith(f"{out}: the session is already complete (8 trials); nothing ran")
    assert err.count("\n") == 1
