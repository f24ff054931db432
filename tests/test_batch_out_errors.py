"""A batch's --out refused or failed as a replay's is: on a file system that holds no
files (/proc: it was ``[Errno 2] /proc/frx: cannot create its staging folder beside it``,
exit 1, where replay says bad input, exit 2), and a full disk while ``batch.csv`` is
written named by --out, never the hidden staging folder, saying the finished jobs'
outputs were not kept."""

import errno
import os
import shutil
from collections import namedtuple

from frictex.app.commands.cli import main
from frictex.app.engine import batch
from frictex.app.engine.batch import RESULTS_PARTIAL

usage = namedtuple("usage", "total used free")
MANIFEST = "scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\ngrating-5mm,swipe-40mms-50hz,b\n"


def test_a_file_system_of_no_size_is_bad_input_as_for_replay(tmp_path, monkeypatch, capsys):
    """/proc simulated: every file system reports a total of 0 bytes."""
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.csv").write_text(MANIFEST)
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(0, 0, 0))
    out = tmp_path / "new" / "frx"
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
                 "--quiet"]) == 2
    said = capsys.readouterr().err
    assert main(["batch", "m.csv", "--out", str(out), "--quiet"]) == 2
    assert capsys.readouterr().err == said == (
        f"frictex: error: {tmp_path}: a file system that holds no files (such as /proc or "
        "/sys); write the outputs elsewhere\n")
    assert sorted(os.listdir(tmp_path)) == ["m.csv"]


def test_a_full_disk_writing_batch_csv_names_out(tmp_path, monkeypatch, capsys):
    monkeypatch.chdir(tmp_path)
    (tmp_path / "m.csv").write_text(MANIFEST)
    out = tmp_path / "out"
    assert main(["batch", "m.csv", "--out", str(out), "--jobs", "1", "--quiet"]) == 0
    before = sorted(os.listdir(out))

    def full(path, *args, **kwargs):
        if str(path).endswith(RESULTS_PARTIAL):
            raise OSError(errno.ENOSPC, os.strerror(errno.ENOSPC), str(path))
        return open(path, *args, **kwargs)

    monkeypatch.setattr(batch, "open", full, raising=False)
    assert main(["batch", "m.csv", "--out", str(out), "--jobs", "1", "--quiet"]) == 1
    assert capsys.readouterr().err == (
        f"frictex: error: {out}: the disk is full ({os.strerror(errno.ENOSPC)}); nothing was "
        "replaced; the outputs of the jobs that finished (2) were not kept either (a batch "
        "replaces its --out all or nothing)\n")
    assert sorted(os.listdir(out)) == before and sorted(os.listdir(tmp_path)) == ["m.csv", "out"]
