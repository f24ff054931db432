"""--allow-outside reaches the jobs where they run: it set FRICTEX_ALLOW_OUTSIDE only in the
client's environment, which a Dask worker does not share, so a scene naming '../image.png'
failed there ('leads out of the folder through '..'') though --jobs ran it."""

import csv
import os
import shutil

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.batch import Job, run_job
from frictex.textures.library import bundled_file
from frictex.textures.outside import ALLOW_OUTSIDE_ENV


@pytest.fixture
def study(tmp_path, monkeypatch):
    """``sub/m.csv``, one job whose scene ``sub/rm.toml`` names ``../raster-map.png``;
    the variable unset here and put back as it was after the test."""
    monkeypatch.delenv(ALLOW_OUTSIDE_ENV, raising=False)
    scene = bundled_file("raster-map", "scene")
    shutil.copy(scene.with_suffix(".png"), tmp_path / "raster-map.png")
    (tmp_path / "sub").mkdir()
    text = scene.read_text().replace('image = "raster-map.png"', 'image = "../raster-map.png"')
    assert "../raster-map.png" in text
    (tmp_path / "sub" / "rm.toml").write_text(text)
    (tmp_path / "sub" / "m.csv").write_text("scene,trace,name\nrm.toml,swipe-40mms-50hz,r\n")
    return tmp_path / "sub"


def test_a_job_allowed_outside_runs_so_without_the_variable_and_leaves_it_unset(study):
    job = Job(0, str(study / "rm.toml"), "swipe-40mms-50hz", None, 1e4, 50, "csv", "r",
              allow_outside=True)
    row = run_job(job, str(study / "out"))
    assert (row["status"], row["error"]) == ("ok", "")
    assert ALLOW_OUTSIDE_ENV not in os.environ
    refused = run_job(Job(0, str(study / "rm.toml"), "swipe-40mms-50hz", None, 1e4, 50, "csv",
                          "s"), str(study / "out"))
    assert refused["status"] == "failed" and "--allow-outside" in refused["error"]


def test_allow_outside_on_a_dask_worker_process(study):
    distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed "
                                      "(pip install 'frictex[cluster]')")
    # started before --allow-outside sets the variable here: the worker's environment lacks it
    with distributed.LocalCluster(n_workers=1, threads_per_worker=1, processes=True,
                                  host="127.0.0.1", dashboard_address=None) as cluster:
        code = main(["batch", str(study / "m.csv"), "--out", str(study / "out"), "--quiet",
                     "--allow-outside", "--scheduler", cluster.scheduler_address])
    with open(study / "out" / "batch.csv", newline="") as fh:
        (row,) = csv.DictReader(fh)
    assert (code, row["status"], row["error"]) == (0, "ok", "")
