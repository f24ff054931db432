"""Session folders: every trial recorded as it ends, replayable with frictex replay, and a
session killed with SIGKILL at a random trial resumed with no trial lost or repeated."""

import csv
import json
import os
import signal
import subprocess
import sys
import time
from pathlib import Path

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import make_presenter, run_session
from frictex.app.experiment.session import RESULT_COLUMNS
from frictex.device.errors import InputError

PROTOCOL = """format = 1
method = "2afc"
repetitions = 2
practice = 1
break_every = 5

[stimuli]
scene = "grating-5mm"
vary = "depth"
reference = 0.3
levels = [0.32, 0.36, 0.42]

[presentation]
exploration_s = 0.4
"""
PARTICIPANT = "simulated:weber=0.11,lapse=0.02,seed=3"
SEED = 5
#: the columns that say what happened (the others are times)
WHAT = [c for c in RESULT_COLUMNS if c not in ("rt_s", "ended_utc")]


@pytest.fixture
def protocol_file(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    return path


def rows(folder):
    with open(Path(folder) / "results.csv", newline="", encoding="utf-8") as fh:
        return [{c: r[c] for c in WHAT} for r in csv.DictReader(fh)]


def session(protocol_file, out, record="traces", **kw):
    return run_session(load_protocol(protocol_file), make_presenter(PARTICIPANT), out,
                       seed=SEED, participant=PARTICIPANT, record=record, **kw)


def test_every_trial_is_recorded_and_replays(tmp_path, protocol_file):
    out = tmp_path / "s"
    s = session(protocol_file, out, record="all")
    assert len(s.rows) == 1 + 3 * 2 * 2
    assert [r["trial"] for r in rows(out)] == [str(i) for i in range(1, 14)]
    assert sorted(p.name for p in (out / "trials").iterdir()) == [f"{i:04d}" for i in range(1, 14)]
    trial = out / "trials" / "0007"
    assert sorted(p.name for p in trial.iterdir()) == ["1", "1.csv", "1.toml", "2", "2.csv", "2.toml"]
    again = tmp_path / "again"
    assert main(["replay", str(trial / "2.toml"), str(trial / "2.csv"), "--out", str(again),
                 "--quiet"]) == 0
    assert (again / "commands.csv").read_bytes() == (trial / "2" / "commands.csv").read_bytes()
    # the scene played is the stimulus the row names
    names = rows(out)[6]["stimuli"].split("|")
    assert (trial / "2.toml").read_text() == (out / "stimuli" / f"{names[1]}.toml").read_text()


def test_a_second_session_in_the_same_folder_is_refused(tmp_path, protocol_file):
    session(protocol_file, tmp_path / "s", record="results")
    with pytest.raises(InputError, match="already holds a session; continue it with --resume"):
        session(protocol_file, tmp_path / "s", record="results")


def test_resume_refuses_another_protocol_or_participant(tmp_path, protocol_file):
    session(protocol_file, tmp_path / "s", record="results")
    other = tmp_path / "other.toml"
    other.write_text(PROTOCOL.replace("repetitions = 2", "repetitions = 3"), encoding="utf-8")
    with pytest.raises(InputError, match="not the protocol"):
        session(other, tmp_path / "s", resume=True)
    with pytest.raises(InputError, match="was started with"):
        run_session(load_protocol(protocol_file), make_presenter(PARTICIPANT), tmp_path / "s",
                    participant="simulated:weber=0.2", resume=True)
    with pytest.raises(InputError, match=r"--seed 9: .* started with seed 5.*leave --seed out"):
        run_session(load_protocol(protocol_file), make_presenter(PARTICIPANT), tmp_path / "s",
                    seed=9, participant=PARTICIPANT, resume=True)
    assert len(session(protocol_file, tmp_path / "s", record="results", resume=True).rows) == 13


def test_the_participant_id_is_recorded_and_checked(tmp_path, protocol_file, capsys):
    """--participant-id: a plain name, in session.json; --resume refuses another one."""
    out = tmp_path / "s"
    base = ["experiment", str(protocol_file), "--out", str(out), "--record", "results", "--quiet"]
    assert main([*base, "--participant", PARTICIPANT, "--participant-id", "P07"]) == 0
    info = json.loads((out / "session.json").read_text())
    assert (info["participant_id"], info["participant"]) == ("P07", PARTICIPANT)
    capsys.readouterr()
    assert main([*base, "--resume", "--participant-id", "P08"]) == 2
    assert "--participant-id P08: " in capsys.readouterr().err
    assert main([*base, "--resume", "--participant-id", "P07"]) == 0
    capsys.readouterr()
    for bad in ("", "a b", "../x", "p\n7", "_p", "p" * 65):
        assert main([*base, "--participant", PARTICIPANT, "--participant-id", bad]) == 2
        err = capsys.readouterr().err
        assert "expected a plain name" in err and err.count("\n") == 1


@pytest.mark.parametrize("out, words", [("", "expected a folder name"),
                                        ("a\nb", "control character")])
def test_an_empty_or_unprintable_out_is_refused(tmp_path, protocol_file, monkeypatch, capsys,
                                                out, words):
    """``--out ""`` would write the session into the current folder; a newline in the
    name would break every line naming it: both one error line, exit 2, nothing written."""
    monkeypatch.chdir(tmp_path)
    assert main(["experiment", str(protocol_file), "--participant", PARTICIPANT,
                 "--out", out]) == 2
    err = capsys.readouterr().err
    assert words in err and err.count("\n") == 1
    assert sorted(p.name for p in tmp_path.iterdir()) == ["p.toml"]


def test_a_row_cut_short_and_a_trial_without_its_row_are_redone(tmp_path, protocol_file):
    whole = tmp_path / "whole"
    session(protocol_file, whole)
    cut = tmp_path / "cut"
    session(protocol_file, cut)
    lines = (cut / "results.csv").read_text().splitlines(keepends=True)
    kept = 1 + 6  # the header and six trials
    (cut / "results.csv").write_text("".join(lines[:kept]) + lines[kept][:17])
    assert (cut / "trials" / "0009").is_dir()  # files of trials without rows are there
    session(protocol_file, cut, resume=True)
    assert rows(cut) == rows(whole)
    assert (cut / "results.csv").read_text().count("\n") == len(lines)


def test_killed_at_a_random_trial_and_resumed(tmp_path, protocol_file):
    """SIGKILL while the session runs (at a trial drawn at random), then --resume: the
    results are those of a session never killed, each trial once."""
    whole = tmp_path / "whole"
    session(protocol_file, whole, record="all")
    expected = rows(whole)
    at = int(np.random.default_rng(29).integers(2, len(expected) - 2))
    out = tmp_path / "killed"
    command = [sys.executable, "-m", "frictex", "experiment", str(protocol_file),
               "--participant", PARTICIPANT, "--seed", str(SEED), "--out", str(out), "--quiet"]
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE)
    try:
        deadline = time.monotonic() + 120.0
        while time.monotonic() < deadline and proc.poll() is None:
            results = out / "results.csv"
            if results.exists() and results.read_bytes().count(b"\n") > at:
                break
            time.sleep(0.005)
        assert proc.poll() is None, f"the session ended before trial {at}: {proc.stderr.read()}"
        os.kill(proc.pid, signal.SIGKILL)
    finally:
        proc.kill()
        proc.wait(timeout=30)
        proc.stderr.close()
    assert proc.returncode == -signal.SIGKILL
    before = len(rows(out))
    assert at <= before < len(expected)
    resumed = subprocess.run(command[:5] + ["--out", str(out), "--resume", "--quiet"],
                             capture_output=True, text=True, timeout=300)
    assert resumed.returncode == 0, resumed.stderr
    assert rows(out) == expected
    trials = sorted(p.name for p in (out / "trials").iterdir())
    assert trials == [f"{i:04d}" for i in range(1, len(expected) + 1)]
    for name in trials:
        assert (out / "trials" / name / "2" / "commands.csv").is_file()


def test_scenes_that_name_files_carry_them(tmp_path):
    """A stimulus whose scene names a map or a clip file: the file is placed beside every
    scene file written from it, and a trial replays from its own folder."""
    path = tmp_path / "files.toml"
    path.write_text('format = 1\nmethod = "magnitude"\nrepetitions = 1\n'
                    '[[stimulus]]\nname = "map"\nscene = "raster-map"\n'
                    '[[stimulus]]\nname = "clips"\nscene = "slider-clips"\n'
                    '[presentation]\nexploration_s = 0.3\n')
    out = tmp_path / "s"
    run_session(load_protocol(path), make_presenter(PARTICIPANT), out, seed=1,
                participant=PARTICIPANT, record="all")
    assert (out / "stimuli" / "raster-map.png").is_file()
    for trial in ("0001", "0002"):
        folder = out / "trials" / trial
        again = tmp_path / f"again{trial}"
        assert main(["replay", str(folder / "1.toml"), str(folder / "1.csv"), "--out",
                     str(again), "--quiet"]) == 0
        assert (again / "commands.csv").read_bytes() == (folder / "1" / "commands.csv").read_bytes()


def test_a_strangers_session_folder_is_one_line_each(tmp_path, protocol_file, monkeypatch, capsys):
    """analyse reads session.json and results.csv as a stranger's files: JSON nested
    100,000 deep was a RecursionError (exit 70), a link to /dev/zero took 3.5 GB, a FIFO
    hung; a results table larger than any protocol's was read whole (2.3 GB for 173 MB);
    a link to /etc/passwd was read (and refused for its columns): links are not followed
    out of the folder."""
    import frictex.app.experiment.session as session_module
    good = tmp_path / "good"
    session(protocol_file, good, record="results")
    cases = {"session.json": [("deep", lambda p: p.write_text("[" * 100_000 + "]" * 100_000),
                               "JSON nested too deep"),
                              ("zero", lambda p: p.symlink_to("/dev/zero"),
                               "symbolic link to /dev/zero, outside the folder"),
                              ("fifo", os.mkfifo, "FIFO")],
             "results.csv": [("rfifo", os.mkfifo, "FIFO"),
                             ("passwd", lambda p: p.symlink_to("/etc/passwd"),
                              "symbolic link to /etc/passwd, outside the folder"),
                             ("rbig", lambda p: p.write_bytes(b"x" * 400_000),
                              "more than the 300,000")]}
    monkeypatch.setattr(session_module, "MAX_SESSION_FILE_BYTES", 300_000)
    for name, made in cases.items():
        for case, make, said in made:
            folder = tmp_path / case
            folder.mkdir()
            for other in ("session.json", "results.csv"):
                if other != name:
                    (folder / other).write_bytes((good / other).read_bytes())
            make(folder / name)
            assert main(["experiment", "analyse", str(folder)]) == 2, case
            err = capsys.readouterr().err.strip().splitlines()
            assert len(err) == 1 and said in err[0] and str(folder / name) in err[0], (case, err)
