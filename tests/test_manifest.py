"""A batch manifest: its scenes and traces stay in its folder, and every problem of it is
reported in one run."""

import os

import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.batch import MAX_PROBLEMS_SHOWN, ManifestError, read_manifest
from frictex.rendering.pipeline import RENDERERS
from frictex.textures.outside import ALLOW_OUTSIDE_ENV

RENDERER_NAMES = ("sho", *RENDERERS)
TRACE = "t_s,finger,x_mm,y_mm\n0,0,10,10\n0.01,0,10.4,10\n"


@pytest.fixture
def study(tmp_path, monkeypatch):
    """A study folder with a trace in it, and a trace beside the folder (outside it)."""
    monkeypatch.delenv(ALLOW_OUTSIDE_ENV, raising=False)
    folder = tmp_path / "study"
    folder.mkdir()
    (folder / "inside.csv").write_text(TRACE)
    (tmp_path / "outside.csv").write_text(TRACE)
    return folder


def _outside_specs(folder):
    os.symlink(folder.parent / "outside.csv", folder / "link.csv")
    return {"../outside.csv": "leads out of the folder through '..'",
            str(folder.parent / "outside.csv"): "is an absolute path outside the manifest's folder",
            "link.csv": "passes through a symbolic link to"}


def test_scenes_and_traces_outside_the_manifest_folder_are_refused(study, capsys):
    for n, (spec, how) in enumerate(_outside_specs(study).items()):
        manifest = study / f"m{n}.csv"
        manifest.write_text(f"scene,trace\ngrating-5mm,{spec}\n")
        assert main(["batch", str(manifest), "--out", str(study / "out")]) == 2
        err = capsys.readouterr().err.strip().splitlines()
        assert len(err) == 1 and err[0].startswith(f"frictex: error: {manifest}:2: trace "), err
        assert how in err[0] and "--allow-outside" in err[0]
        assert not (study / "out").exists()


def test_a_scene_outside_is_refused_as_a_trace_is(study):
    (study.parent / "s.toml").write_text("")
    manifest = study / "m.csv"
    manifest.write_text("scene,trace\n../s.toml,inside.csv\n")
    with pytest.raises(ManifestError, match=r"m\.csv:2: scene \"\.\./s\.toml\" leads out"):
        read_manifest(manifest, RENDERER_NAMES)


def test_allow_outside_lets_them_run(study, monkeypatch):
    specs = list(_outside_specs(study))
    manifest = study / "m.csv"
    manifest.write_text("scene,trace\n" + "".join(f"grating-5mm,{s}\n" for s in specs))
    monkeypatch.setenv(ALLOW_OUTSIDE_ENV, "1")
    jobs = read_manifest(manifest, RENDERER_NAMES)
    assert {job.trace for job in jobs} == {os.path.realpath(study.parent / "outside.csv")}
    monkeypatch.delenv(ALLOW_OUTSIDE_ENV)
    assert main(["batch", str(manifest), "--out", str(study / "out"), "--quiet",
                 "--allow-outside"]) == 0
    assert (study / "out" / "0002-grating-5mm-link" / "summary.json").exists()


def test_bundled_names_and_files_inside_stay_allowed(study):
    (study / "sub").mkdir()
    (study / "sub" / "deep.csv").write_text(TRACE)
    manifest = study / "m.csv"
    manifest.write_text("scene,trace\ngrating-5mm,swipe-40mms-50hz\ngrating-5mm,inside.csv\n"
                        f"grating-5mm,sub/deep.csv\ngrating-5mm,{study / 'inside.csv'}\n")
    jobs = read_manifest(manifest, RENDERER_NAMES)
    assert [job.trace for job in jobs] == ["swipe-40mms-50hz", str(study / "inside.csv"),
                                           str(study / "sub" / "deep.csv"),
                                           str(study / "inside.csv")]


def test_every_bad_row_is_reported_in_one_run(study, capsys):
    manifest = study / "m.csv"
    manifest.write_text("scene,trace,renderer,rate_hz,name\n"
                        "grating-5mm,inside.csv,,,good\n"
                        "grating-5mm,../outside.csv,,,a\n"
                        "grating-5mm,inside.csv,fastest,-3,b\n"
                        "grating-5mm,inside.csv\n"
                        ",inside.csv,,,good\n")
    assert main(["batch", str(manifest), "--out", str(study / "out")]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert [line.split(": ", 3)[2] for line in err] == [
        f"{manifest}:3", f"{manifest}:4", f"{manifest}:4", f"{manifest}:5", f"{manifest}:6",
        f"{manifest}:6"]
    assert "trace \"../outside.csv\" leads out" in err[0]
    assert 'renderer "fastest"' in err[1] and 'rate_hz "-3"' in err[2]
    assert "2 fields, expected 5" in err[3] and "scene is empty" in err[4]
    assert 'name "good" is used by an earlier job' in err[5]  # a bad row's name counts too
    assert not (study / "out").exists()


def test_a_name_used_twice_and_a_bad_field_of_a_later_row_both_show(study):
    manifest = study / "m.csv"
    manifest.write_text("scene,trace,name\ngrating-5mm,inside.csv,x\n"
                        "grating-5mm,inside.csv,x\ngrating-5mm,inside.csv,../x\n")
    with pytest.raises(ManifestError) as caught:
        read_manifest(manifest, RENDERER_NAMES)
    assert len(caught.value.error_lines) == 2
    assert 'name "x" is used by an earlier job' in caught.value.error_lines[0]
    assert "expected a plain folder name" in caught.value.error_lines[1]


def test_a_bad_header_stops_the_reading(study):
    manifest = study / "m.csv"
    manifest.write_text("scene,colour\na,b\nc\n")
    with pytest.raises(ManifestError) as caught:
        read_manifest(manifest, RENDERER_NAMES)
    assert caught.value.error_lines == (f"{manifest}:1: not a manifest header (2 fields: scene "
                                     f"and colour); expected scene,trace and optionally "
                                     f"renderer,rate_hz,block,format,name",)


def test_problems_beyond_the_shown_are_counted(study):
    manifest = study / "m.csv"
    manifest.write_text("scene,trace\n" + "a\n" * (MAX_PROBLEMS_SHOWN + 7))
    with pytest.raises(ManifestError) as caught:
        read_manifest(manifest, RENDERER_NAMES)
    problems = caught.value.error_lines
    assert len(problems) == MAX_PROBLEMS_SHOWN + 1
    assert problems[-1] == f"{manifest}: 7 more problems"
