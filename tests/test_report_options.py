"""``frictex report``'s --scenes and --out refused in one line before anything runs (the
matrix is replaced by a stand-in that fails the test if it is reached)."""

import pytest

from frictex.app.commands import report
from frictex.app.commands.cli import main
from frictex.app.measure import report_matrix as rm


@pytest.fixture(autouse=True)
def _no_matrix(monkeypatch):
    def ran(*_):
        raise AssertionError("the report ran past its option checks")
    monkeypatch.setattr(report, "_matrix", ran)


def _refused(argv, capsys) -> str:
    assert main(["report", "--quick", "--no-progress", *argv]) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: ") and err.count("\n") == 1
    return err


def test_a_scene_named_twice_is_refused_naming_it(tmp_path, capsys):
    """Its draws would be paired twice: 8 draws on grating-5mm gave the interval
    [-0.398, -0.007], the same scene twice [-0.323, -0.082] over '16 draws'."""
    out = tmp_path / "o"
    err = _refused(["--scenes", "grating-5mm", "grating-15mm", "grating-5mm", "--out", str(out)],
                   capsys)
    assert "--scenes: grating-5mm given twice" in err
    assert not out.exists()


def test_a_bundled_scene_outside_the_matrix_is_not_called_unknown(tmp_path, capsys):
    err = _refused(["--scenes", "height-bump", "--out", str(tmp_path / "o")], capsys)
    assert "--scenes: height-bump is not among the report's scenes" in err
    assert "unknown" not in err and ", ".join(rm.SCENES) in err


def test_the_scenes_help_names_the_scenes_it_takes():
    import argparse
    parser = argparse.ArgumentParser()
    report.add_arguments(parser)
    text = " ".join(parser.format_help().split())
    assert "bundled scenes to include" not in text and "the matrix's scenes" in text
    assert all(scene in text.split("--scenes", 1)[1] for scene in rm.SCENES)


def test_an_out_folder_that_cannot_be_made_is_said_in_one_line(tmp_path, capsys):
    (tmp_path / "f").write_text("x")
    out = tmp_path / "f" / "sub"
    err = _refused(["--out", str(out)], capsys)
    assert f"--out {out}: cannot make the report folder (Not a directory)" in err
    assert "Errno" not in err
