"""An error on a run's staging folder is one line that starts with ``--out``, as the
project's other errors do: never Python's ``[Errno N]`` (``frictex: error: [Errno 30]
/mnt/ro/o: cannot create its staging folder beside it (Read-only file system)``); the
errno stays on the exception. A folder another run committed into ``--out`` meanwhile is
said to be that, not a folder that is no run's output."""

import errno
import os
from pathlib import Path

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.staging import Staging
from frictex.device.errors import RunFailed


@pytest.fixture
def read_only_staging(monkeypatch):
    """Making a staging folder fails as on a read-only file system (EROFS)."""
    mkdir = Path.mkdir

    def refused(self, *args, **kwargs):
        if ".frictex-staging." in self.name:
            raise OSError(errno.EROFS, os.strerror(errno.EROFS), str(self))
        return mkdir(self, *args, **kwargs)

    monkeypatch.setattr(Path, "mkdir", refused)


def test_a_staging_folder_that_cannot_be_made_keeps_its_errno_out_of_the_line(
        tmp_path, read_only_staging):
    out = tmp_path / "o"
    with pytest.raises(OSError) as caught:
        Staging(out).begin()
    assert caught.value.errno == errno.EROFS
    assert str(caught.value) == (f"{out}: cannot create its staging folder beside it "
                                 f"({os.strerror(errno.EROFS)})")


@pytest.mark.parametrize("command", [["replay", "grating-5mm", "swipe-40mms-50hz"],
                                     ["batch", "m1.csv"]])
def test_replay_and_batch_name_out_first(tmp_path, read_only_staging, monkeypatch, capsys,
                                         command):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m1.csv").write_text("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\n")
    out = tmp_path / "o"
    assert main([*command, "--out", str(out), "--quiet"]) == 1
    assert capsys.readouterr().err == (f"frictex: error: {out}: cannot create its staging "
                                       f"folder beside it ({os.strerror(errno.EROFS)})\n")
    assert sorted(os.listdir(tmp_path)) == ["m1.csv"]


def _commit_with(tmp_path: Path, make) -> str:
    """The error of a commit into ``out`` after ``make(out)`` ran during the run."""
    out = tmp_path / "out"
    out.mkdir()
    staging = Staging(out)
    staging.begin()
    make(out)
    with pytest.raises(RunFailed) as caught:
        staging.commit()
    staging.abort()
    return str(caught.value)


def test_a_run_folder_committed_meanwhile_is_said_to_be_another_runs(tmp_path):
    """Two batches into one --out: the other's job folder x1 holds a summary.json."""
    def other_batch(out):
        (out / "x1").mkdir()
        (out / "x1" / "summary.json").write_text("{}")

    said = _commit_with(tmp_path, other_batch)
    assert said.startswith(f"{tmp_path / 'out'}: another run committed its outputs into it "
                           "during this run (the folder 'x1', with a summary.json)")
    assert "not a run's output" not in said


def test_a_folder_not_a_runs_that_appeared_keeps_its_message(tmp_path):
    said = _commit_with(tmp_path, lambda out: (out / "late").mkdir())
    assert said.startswith(f"{tmp_path / 'out'}: the folder 'late', not a run's output, "
                           "appeared in it during the run; nothing was replaced")
