"""A batch manifest's scenes and traces must exist (a file in its folder or a bundled
name) when it is read: one that does not is a problem of its line, reported with the
others, and no job runs."""

import json

from frictex.app.commands.cli import main
from frictex.app.engine.batch import read_manifest, run_job
from frictex.rendering.pipeline import RENDERERS

TRACE = "t_s,finger,x_mm,y_mm\n0,0,10,10\n0.01,0,10.4,10\n"


def test_unknown_scenes_and_missing_traces_are_listed_and_nothing_runs(tmp_path, capsys):
    (tmp_path / "p01-trial2.csv").write_text(TRACE)
    manifest = tmp_path / "m.csv"
    manifest.write_text("scene,trace,renderer,name\n"
                        "nope,p01-trial2.csv,,a\n"
                        "grating-5mmm,missing.csv,,b\n"
                        "grating-5mm,p01-trial2.csv,,c\n"
                        "grating-5mm,swipe-40mms-50hz,,d\n")
    assert main(["batch", str(manifest), "--out", str(tmp_path / "out"), "--quiet"]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 3, err
    assert err[0].startswith(f"frictex: error: {manifest}:2: scene nope: no such file, and no "
                             "bundled scene of that name")
    assert err[1].startswith(f"frictex: error: {manifest}:3: scene grating-5mmm: no such file")
    assert "did you mean grating-5mm?" in err[1]
    assert err[2].startswith(f"frictex: error: {manifest}:3: trace missing.csv: no such file, "
                             "and no bundled trace of that name")
    assert not (tmp_path / "out").exists()


def test_a_missing_file_in_a_subfolder_is_a_problem_of_its_line(tmp_path, capsys):
    (tmp_path / "sub").mkdir()
    manifest = tmp_path / "m.csv"
    manifest.write_text("scene,trace\ngrating-5mm,sub/gone.csv\n")
    assert main(["batch", str(manifest), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"frictex: error: {manifest}:2: trace sub/gone.csv: no such file"]


def test_a_name_missing_beside_the_manifest_never_reads_the_current_folders_file(
        tmp_path, monkeypatch, capsys):
    """A stranger's manifest naming secret.csv, which is not in its folder: a file of
    that name where the batch runs is not the trace (it was read by the job)."""
    study, here = tmp_path / "study", tmp_path / "here"
    study.mkdir()
    here.mkdir()
    (here / "secret.csv").write_text(TRACE)
    manifest = study / "m.csv"
    manifest.write_text("scene,trace\ngrating-5mm,secret.csv\n")
    monkeypatch.chdir(here)
    assert main(["batch", str(manifest), "--out", str(tmp_path / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"frictex: error: {manifest}:2: trace secret.csv: no such file, and no "
                   "bundled trace of that name (frictex library lists them)"]


def test_a_bundled_name_runs_the_bundled_file_whatever_the_current_folder_holds(
        tmp_path, monkeypatch):
    study = tmp_path / "study"
    study.mkdir()
    (tmp_path / "grating-5mm.toml").write_text("not a scene")
    (tmp_path / "swipe-40mms-50hz").write_text("not a trace")
    manifest = study / "m.csv"
    manifest.write_text("scene,trace,name\ngrating-5mm.toml,swipe-40mms-50hz,j\n")
    monkeypatch.chdir(tmp_path)
    job, = read_manifest(manifest, ("sho", *RENDERERS))
    row = run_job(job, str(tmp_path / "out"))
    assert row["status"] == "ok", row["error"]
    summary = json.loads((tmp_path / "out" / "j" / "summary.json").read_text())
    assert summary["scene"]["name"] == "grating-5mm"
