"""A job that fills the disk is named by where its outputs go (the batch's --out and the
job's folder in it), never by the staging folders they are written in."""

import csv
import shutil
from collections import namedtuple

from frictex.app.commands.cli import main

usage = namedtuple("usage", "total used free")


def test_a_full_disk_mid_job_names_the_jobs_folder_in_out(tmp_path, monkeypatch, capsys):
    """Room enough at the start, 1 MB once the job writes its tables."""
    rows = "".join(f"{0.01 * k:.2f},0,{1 + (k % 100) * 0.1:.1f},1\n" for k in range(3001))
    (tmp_path / "long.csv").write_text("t_s,finger,x_mm,y_mm\n" + rows)
    (tmp_path / "m.csv").write_text("scene,trace,rate_hz,name\ngrating-5mm,long.csv,20000,a\n")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(
        1 << 40, 0, (1 << 20) if ".a.frictex-staging" in str(path) else (1 << 40)))
    out = tmp_path / "out"
    assert main(["batch", str(tmp_path / "m.csv"), "--out", str(out), "--jobs", "1",
                 "--quiet"]) == 1
    with open(out / "batch.csv", newline="") as fh:
        (row,) = csv.DictReader(fh)
    err = capsys.readouterr().err
    assert row["error"].startswith(f"{out / 'a'}: the next ")
    assert "frictex-staging" not in row["error"] + err and f"{out / 'a'}: the next " in err
