"""A disk that fills while a table is written is said in one line naming the output
folder (not its staging folder) and the file, with what to do; nothing is left behind."""

import errno
import shutil
from pathlib import Path

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.engine import tables
from frictex.app.engine.sinks import friction_columns
from frictex.app.engine.staging import Staging
from frictex.app.engine.tables import TableWriter
from frictex.device.errors import OutputSpaceError


def _disk_full(*args):
    raise OSError(errno.ENOSPC, "No space left on device")


def _rows(n):
    return {name: np.zeros(n, dtype=dtype) for name, dtype, _ in friction_columns(False)}


@pytest.mark.parametrize("fmt, hint", [
    ("csv", "; free some space, write elsewhere, or use --format parquet (format=\"parquet\" "
             "from Python)"),
    ("parquet", "; free some space, or write elsewhere")])
def test_a_full_disk_names_the_output_folder_and_file(tmp_path, monkeypatch, fmt, hint):
    out = tmp_path / "o"
    staging = Staging(out)
    folder = staging.begin()
    monkeypatch.setattr(tables._OPENERS[fmt], "write", _disk_full)
    table = TableWriter(folder, "friction", friction_columns(False), fmt)
    table.write(_rows(100))
    with pytest.raises(OutputSpaceError) as raised:
        table.commit()
    table.abort()
    staging.abort()
    message = str(raised.value)
    assert message.startswith(f"{out}: the disk filled while friction.{fmt} was written")
    assert message.endswith(hint) and "\n" not in message and "staging" not in message
    assert raised.value.errno == errno.ENOSPC
    assert list(tmp_path.iterdir()) == []


def test_a_full_disk_at_the_npz_commit_is_said_too(tmp_path, monkeypatch):
    """npz copies its columns into the zip at the commit: the disk can fill then."""
    monkeypatch.setattr(tables, "_copy_file", _disk_full)
    table = TableWriter(tmp_path, "friction", friction_columns(False), "npz")
    table.write(_rows(100))
    with pytest.raises(OutputSpaceError, match=r"friction\.npz was written .*--format parquet"):
        table.commit()



def test_a_full_disk_at_the_summary_names_the_output_folder(tmp_path, monkeypatch, capsys):
    """summary.json is written into the staging folder last: a disk full then is said of
    the output folder too (it was a bare '[Errno 28] No space left on device'), and the
    previous outputs stay."""
    out = tmp_path / "o"
    out.mkdir()
    (out / "summary.json").write_text("{}\n")
    original = Path.write_text

    def write_text(path, *args, **kwargs):
        if path.name == "summary.json" and path.parent != out:
            _disk_full()
        return original(path, *args, **kwargs)

    monkeypatch.setattr(Path, "write_text", write_text)
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out), "--format",
                 "csv", "--quiet"]) == 1
    assert capsys.readouterr().err == (f"frictex: error: {out}: the disk is full (No space left "
                                       "on device); nothing was replaced\n")
    assert (out / "summary.json").read_text() == "{}\n"
    assert [p.name for p in tmp_path.iterdir()] == ["o"]


def test_a_parquet_replay_refused_for_room_is_not_told_to_write_parquet(tmp_path, monkeypatch,
                                                                        capsys):
    from frictex.app.engine import tables
    for fmt, free in (("parquet", 1 << 20), ("csv", tables.RESERVE_BYTES + (1 << 20))):
        # csv needs about 1.85 MB and is told of Parquet, which fits (643 kB); Parquet is not
        monkeypatch.setattr(shutil, "disk_usage", lambda path, free=free: shutil._ntuple_diskusage(
            1 << 40, 0, free))
        assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out",
                     str(tmp_path / fmt), "--format", fmt, "--quiet"]) == 1
        err = capsys.readouterr().err
        assert "need about" in err and ("--format parquet" in err) == (fmt != "parquet"), err
