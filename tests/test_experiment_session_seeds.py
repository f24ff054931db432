"""A session's seeds and its record: a simulated participant without its own seed= is
drawn from the session's seed (different seeds, independent observers; the same seed,
the same answers, resumed or not); a bad --seed is refused before anything is written;
session.json records the participant seed, the versions, each part run and the end."""

import csv
import json
from pathlib import Path

import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment.observer import participant_seed
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import make_presenter, run_session
from frictex.device.errors import InputError
from test_experiment_session import PROTOCOL as SESSION_PROTOCOL

#: the session tests' protocol without practice trials and breaks: every trial answered
PROTOCOL = SESSION_PROTOCOL.replace("practice = 1\nbreak_every = 5\n", "")
assert "practice" not in PROTOCOL, "the session tests' protocol changed: take its practice out"
SPEC = "simulated:weber=0.11,lapse=0.02"  # no seed=: the session's gives it
TRIALS = 3 * 2 * 2


@pytest.fixture
def protocol_file(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    return path


def answers(folder):
    """Every trial's stimuli, response and response time (the participant's draws)."""
    with open(Path(folder) / "results.csv", newline="", encoding="utf-8") as fh:
        return [(r["stimuli"], r["response"], r["rt_s"]) for r in csv.DictReader(fh)]


def run(protocol_file, out, seed, spec=SPEC, **kw):
    return run_session(load_protocol(protocol_file), make_presenter(spec), out, seed=seed,
                       participant=spec, record="results", **kw)


def cut_to(folder, kept):
    """``folder`` as a session stopped after ``kept`` trials."""
    lines = (folder / "results.csv").read_text().splitlines(keepends=True)
    (folder / "results.csv").write_text("".join(lines[:1 + kept]))


def test_sessions_of_different_seeds_are_different_participants(tmp_path, protocol_file):
    run(protocol_file, tmp_path / "a", 1)
    run(protocol_file, tmp_path / "b", 2)
    run(protocol_file, tmp_path / "a2", 1)
    a, b = answers(tmp_path / "a"), answers(tmp_path / "b")
    # the response times are the participant's draws alone: none shared across seeds
    assert not {rt for *_, rt in a} & {rt for *_, rt in b}
    assert answers(tmp_path / "a2") == a  # the same seed: the same participant
    seeds = [json.loads((tmp_path / s / "session.json").read_text())["participant_seed"]
             for s in ("a", "b", "a2")]
    assert seeds == [participant_seed(1), participant_seed(2), participant_seed(1)]
    assert seeds[0] != seeds[1]
    # a spec's own seed= is kept and recorded
    run(protocol_file, tmp_path / "own", 1, spec=SPEC + ",seed=7")
    assert json.loads((tmp_path / "own" / "session.json").read_text())["participant_seed"] == 7


def test_a_resumed_session_answers_as_the_unbroken_one(tmp_path, protocol_file):
    run(protocol_file, tmp_path / "whole", 4)
    run(protocol_file, tmp_path / "cut", 4)
    cut_to(tmp_path / "cut", 5)
    run(protocol_file, tmp_path / "cut", None, resume=True)
    assert answers(tmp_path / "cut") == answers(tmp_path / "whole")
    info = json.loads((tmp_path / "cut" / "session.json").read_text())
    first, second = info["parts"]
    assert (first["first_trial"], first["trials"], first["ended"]) == (1, TRIALS, "complete")
    assert (second["first_trial"], second["trials"], second["ended"]) == (6, TRIALS - 5,
                                                                         "complete")
    assert info["ended_utc"] == second["ended_utc"] is not None
    for key in ("frictex", "python", "numpy", "scipy", "platform"):
        assert isinstance(info[key], str) and isinstance(second[key], str)


def test_a_session_from_before_participant_seed_resumes(tmp_path, protocol_file):
    """A session.json written before participant_seed, parts and ended_utc (its simulated
    participant then answered with seed 0) resumes answering as it did."""
    run(protocol_file, tmp_path / "whole", 4, spec=SPEC + ",seed=0")
    old = tmp_path / "old"
    run(protocol_file, old, 4)
    info = json.loads((old / "session.json").read_text())
    for key in ("participant_seed", "parts", "ended_utc", "python", "numpy", "scipy",
                "platform"):
        del info[key]
    (old / "session.json").write_text(json.dumps(info))
    lines = (tmp_path / "whole" / "results.csv").read_text().splitlines(keepends=True)
    (old / "results.csv").write_text("".join(lines[:1 + 5]))  # 5 trials of that participant
    run(protocol_file, old, None, resume=True)
    assert answers(old) == answers(tmp_path / "whole")
    assert [p["first_trial"] for p in json.loads((old / "session.json").read_text())["parts"]] == [6]


def test_a_stopped_part_is_recorded(tmp_path, protocol_file):
    presenter = make_presenter(SPEC)
    answer = presenter.present

    def stop_at_four(trial, shown):
        if trial.number == 4:
            raise KeyboardInterrupt
        return answer(trial, shown)

    presenter.present = stop_at_four
    with pytest.raises(KeyboardInterrupt):
        run_session(load_protocol(protocol_file), presenter, tmp_path / "s", seed=3,
                    participant=SPEC, record="results")
    info = json.loads((tmp_path / "s" / "session.json").read_text())
    [part] = info["parts"]
    assert (part["trials"], part["ended"], info["ended_utc"]) == (3, "stopped (KeyboardInterrupt)",
                                                                  None)


@pytest.mark.parametrize("seed", ["-3", str(2**63), "x"])
def test_a_bad_seed_is_refused_before_anything_is_written(tmp_path, protocol_file, capsys,
                                                          seed):
    out = tmp_path / "s"
    argv = ["experiment", str(protocol_file), "--participant", SPEC, "--seed", seed,
            "--out", str(out), "--quiet"]
    with pytest.raises(SystemExit) as exit_:
        main(argv)
    assert exit_.value.code == 2
    assert "--seed" in capsys.readouterr().err
    assert not out.exists()
    if seed != "x":  # the library call refuses it as early
        with pytest.raises(InputError, match="expected an integer from 0 to 2"):
            run(protocol_file, out, int(seed))
        assert not out.exists()
    # the folder is free for a good seed
    assert main(argv[:5] + ["0"] + argv[6:]) == 0
