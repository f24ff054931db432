"""What ``frictex experiment analyse`` refuses in its input: one session in two folders
(a copy), a ``correct`` other than 0 or 1, and a number that is not finite; each in one
line naming where."""

import re
import shutil

import pytest

from frictex.app.commands.cli import main
import test_experiment_result_columns as result_columns

PARTICIPANT = result_columns.PARTICIPANT
TWO_AFC = result_columns.TWO_AFC.replace("bootstrap = 200", "bootstrap = 0")  # no interval needed


@pytest.fixture(scope="module")
def sessions(tmp_path_factory):
    """Two sessions of one protocol, seeds 4 and 5."""
    root = tmp_path_factory.mktemp("afc")
    (root / "afc.toml").write_text(TWO_AFC)
    for seed in (4, 5):
        assert main(["experiment", str(root / "afc.toml"), "--participant", PARTICIPANT,
                     "--out", str(root / f"s{seed}"), "--seed", str(seed), "--record",
                     "results", "--quiet"]) == 0
    return root / "s4", root / "s5"


def _analyse(tmp_path, capsys, *folders):
    """The exit status of analysing ``folders`` and what it wrote to stderr."""
    capsys.readouterr()
    code = main(["experiment", "analyse", *map(str, folders), "--out", str(tmp_path / "a"),
                 "--no-plot"])
    return code, capsys.readouterr().err


def _copy(folder, to, keep=None, line=None, **cells):
    """A copy of session ``folder`` at ``to``: its results.csv cut to the first ``keep``
    rows, and ``cells`` set on ``line`` (1: the header)."""
    shutil.copytree(folder, to)
    table = to / "results.csv"
    lines = table.read_text().splitlines(keepends=True)
    if keep is not None:
        lines = lines[:1 + keep]
    if cells:
        header = lines[0].rstrip("\n").split(",")
        row = lines[line - 1].rstrip("\n").split(",")
        for name, value in cells.items():
            row[header.index(name)] = value
        lines[line - 1] = ",".join(row) + "\n"
    table.write_text("".join(lines))
    return to


def test_two_sessions_of_different_seeds_pool(sessions, tmp_path, capsys):
    assert _analyse(tmp_path, capsys, *sessions) == (0, "")


def test_a_copied_session_is_refused_naming_both_folders(sessions, tmp_path, capsys):
    """Before, the copy pooled as a second session: the same trials twice, and a pooled
    interval narrower than the session's own."""
    copy = _copy(sessions[0], tmp_path / "copy")
    code, err = _analyse(tmp_path, capsys, sessions[0], sessions[1], copy)
    rows = len((copy / "results.csv").read_text().splitlines()) - 1
    assert code == 2 and len(err.splitlines()) == 1
    assert re.search(rf"analyse: {re.escape(str(copy))} holds the same session as "
                     rf"{re.escape(str(sessions[0]))} \(started .*, seed 4, its first "
                     rf"{rows} trials alike\); each session counts once$", err.strip())


def test_a_copy_taken_before_the_session_went_on_is_refused(sessions, tmp_path, capsys):
    """A copy of a session stopped after 3 trials, its original resumed to its end."""
    early = _copy(sessions[0], tmp_path / "early", keep=3)
    code, err = _analyse(tmp_path, capsys, early, sessions[0])
    assert code == 2 and f"{sessions[0]} holds the same session as {early}" in err
    assert "its first 3 trials alike" in err


def test_one_start_and_seed_with_other_trials_pools(sessions, tmp_path, capsys):
    """Two stations started in the same second with the same seeds: their trials (times
    at least) differ, so they are two sessions."""
    other = _copy(sessions[0], tmp_path / "other", line=3, ended_utc="2000-01-01T00:00:00Z")
    assert _analyse(tmp_path, capsys, sessions[0], other) == (0, "")


@pytest.mark.parametrize("column, cell, words", [
    ("correct", "1x", "correct '1x': expected 0 or 1 (whether response is answer)"),
    ("correct", "", "correct '': expected 0 or 1 (whether response is answer)"),
    ("practice", "yes", "practice 'yes': expected 0 or 1 (whether the trial is a practice one)"),
    ("practice", "", "practice '': expected 0 or 1 (whether the trial is a practice one)"),
    ("difference", "nan", "difference 'nan': expected a finite number"),
    ("difference", "inf", "difference 'inf': expected a finite number"),
    ("difference", "1e999", "difference '1e999': expected a finite number"),
    ("difference", "x", "difference 'x': expected a finite number"),
])
def test_a_malformed_cell_is_refused_by_file_and_line(sessions, tmp_path, capsys, column,
                                                      cell, words):
    """Before, a correct of '1x' was warned of as "counted as written" and counted as 0,
    a practice of 'yes' counted the row as a practice one, and a difference of nan was
    refused without its file and line."""
    edited = _copy(sessions[0], tmp_path / "e", line=9, **{column: cell})
    code, err = _analyse(tmp_path, capsys, edited)
    assert (code, err) == (2, f"frictex: error: {edited / 'results.csv'}:9: {words}\n")


@pytest.mark.parametrize("cells, words", [
    ({"difference": "-0.1"},
     "difference '-0.1': expected a number above 0 (a comparison above the reference)"),
    ({"difference": "0"},
     "difference '0': expected a number above 0 (a comparison above the reference)"),
    ({"value": "0.42", "difference": "0.1234"},
     "difference '0.1234' is not value '0.42' minus the reference 0.3 (0.12)"),
    ({"value": "", "difference": "0.12"}, "value '': expected a finite number"),
])
def test_a_difference_that_is_no_comparison_is_refused_by_file_and_line(
        sessions, tmp_path, capsys, cells, words):
    """Before, a difference of -0.1 was refused as "a psychometric fit needs differences
    > 0 ..." naming no file or line, and a difference of 0.1234 beside a value of 0.42
    (0.12 above the reference 0.3) was fitted as a level of its own with one trial."""
    edited = _copy(sessions[0], tmp_path / "e", line=9, **cells)
    code, err = _analyse(tmp_path, capsys, edited)
    assert (code, err) == (2, f"frictex: error: {edited / 'results.csv'}:9: {words}\n")


def test_a_difference_within_the_written_digits_of_its_value_is_counted(sessions, tmp_path,
                                                                       capsys):
    """0.42 - 0.3 written as 0.120000000001 (12 significant digits, the last off by one):
    the same comparison."""
    edited = _copy(sessions[0], tmp_path / "e", line=9, value="0.42",
                   difference="0.120000000001")
    assert _analyse(tmp_path, capsys, edited) == (0, "")
