"""--allow-outside reaches the jobs where they run: it set FRICTEX_ALLOW_OUTSIDE only in the
client's environment, which a Dask worker does not share, so a scene naming '../image.png'
failed there ('leads out of the folder through '..'') though --jobs ran it."""

import csv
import os
import shutil
import threading
from concurrent.futures import ThreadPoolExecutor

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


def test_a_job_allowed_outside_allows_no_other_job_running_beside_it(study, monkeypatch):
    """A Dask worker runs jobs in threads of one process: while a job with allow_outside
    replays, a job of another batch without it, in another thread, is still refused (it was
    allowed too when the permission was FRICTEX_ALLOW_OUTSIDE, which every thread reads)."""
    from frictex.app.engine import replay
    real, inside, refused = replay.run_replay, threading.Event(), threading.Event()

    def allowed_waits_for_the_other(scene, trace, out, **options):
        if out.name == "allowed":
            inside.set()
            assert refused.wait(60), "the job not allowed never ended"
        return real(scene, trace, out, **options)

    monkeypatch.setattr(replay, "run_replay", allowed_waits_for_the_other)

    def job(name, allow_outside):
        return Job(0, str(study / "rm.toml"), "swipe-40mms-50hz", None, 1e4, 50, "csv", name,
                   allow_outside=allow_outside)

    def not_allowed():
        assert inside.wait(60), "the allowed job never started its replay"
        try:
            return run_job(job("not-allowed", False), str(study / "out"))
        finally:
            refused.set()

    with ThreadPoolExecutor(2) as pool:
        allowed = pool.submit(run_job, job("allowed", True), str(study / "out"))
        other = pool.submit(not_allowed).result()
        allowed = allowed.result()
    assert (allowed["status"], allowed["error"]) == ("ok", "")
    assert other["status"] == "failed" and "--allow-outside" in other["error"]
    assert ALLOW_OUTSIDE_ENV not in os.environ
