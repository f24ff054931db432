"""A replay never deletes a file it did not write: an --out without a summary.json holds no
run's outputs, so a file there named as one (a trace saved as commands.csv) is refused
before anything is written, and so is a run's input that its commit would replace. Both
deleted the user's file before (a folder of a trace and notes, replayed to Parquet, kept
the notes and lost the trace)."""

import shutil

import pytest

from frictex.app.commands.cli import main
from frictex.textures.library import resolve_trace

TRACE = "swipe-40mms-50hz"


def _refused(argv, capsys) -> str:
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1, err
    return err


@pytest.mark.parametrize("name, fmt", [("commands.csv", "parquet"), ("friction.csv", "csv")])
def test_a_file_named_as_a_table_in_a_folder_without_a_summary_is_kept(tmp_path, capsys,
                                                                         name, fmt):
    out = tmp_path / "d"
    out.mkdir()
    trace = out / name
    shutil.copyfile(resolve_trace(TRACE), trace)
    (out / "notes.txt").write_text("mine\n")
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    err = _refused(["replay", "grating-5mm", str(trace), "--out", str(out), "--format", fmt,
                    "--quiet"], capsys)
    assert f"holds '{name}' but no summary.json, so not a run's output" in err, err
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["d"]  # no staging folder left


def test_an_input_that_the_commit_would_replace_is_refused(tmp_path, capsys):
    out = tmp_path / "run"
    assert main(["replay", "grating-5mm", TRACE, "--out", str(out), "--quiet"]) == 0
    trace = out / "commands.csv"  # the run's own output, overwritten with a trace
    shutil.copyfile(resolve_trace(TRACE), trace)
    err = _refused(["replay", "grating-5mm", str(trace), "--out", str(out), "--quiet"], capsys)
    assert f"{trace}: an input of the run, in --out {out}, where the run replaces it" in err
    assert trace.read_bytes() == resolve_trace(TRACE).read_bytes()


def test_a_previous_runs_folder_is_still_replaced(tmp_path):
    out = tmp_path / "run"
    assert main(["replay", "grating-5mm", TRACE, "--out", str(out), "--quiet"]) == 0
    (out / "notes.txt").write_text("mine\n")
    assert main(["replay", "grating-5mm", TRACE, "--out", str(out), "--quiet",
                 "--format", "npz"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["commands.npz", "friction.npz",
                                                     "notes.txt", "summary.json"]



def test_a_table_file_the_previous_runs_summary_does_not_list_is_kept(tmp_path, capsys):
    """A Parquet run's folder, and the user's commands.csv dropped into it: its summary.json
    lists commands.parquet and friction.parquet only, so commands.csv is not that run's."""
    out = tmp_path / "run"
    assert main(["replay", "grating-5mm", TRACE, "--out", str(out), "--quiet",
                 "--format", "parquet"]) == 0
    (out / "commands.csv").write_text("mine\n")
    err = _refused(["replay", "grating-5mm", TRACE, "--out", str(out), "--quiet"], capsys)
    assert "holds 'commands.csv' but its summary.json does not list it" in err, err
    assert (out / "commands.csv").read_text() == "mine\n"
    (out / "commands.csv").unlink()
    assert main(["replay", "grating-5mm", TRACE, "--out", str(out), "--quiet"]) == 0
    assert sorted(p.name for p in out.iterdir()) == ["commands.csv", "friction.csv",
                                                     "summary.json"]
