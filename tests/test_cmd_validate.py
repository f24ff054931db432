"""``frictex validate``: output lines and exit codes, as a user sees them."""

import pytest

from frictex.app.commands.cli import main
from frictex.textures.library import LIBRARY_DIR

HEAD = "format = 1\n[display]\nwidth_mm = 108.0\nheight_mm = 64.8\nwidth_px = 800\nheight_px = 480\n"
LAYER = '[[layer]]\ntype = "bump"\ncx_mm = 50\ncy_mm = 30\nsigma_mm = 4\nmu = {mu}\n'


@pytest.fixture
def files(tmp_path):
    good = tmp_path / "good.toml"
    good.write_text(HEAD + LAYER.format(mu=0.7))
    low = tmp_path / "low.toml"
    low.write_text(HEAD + LAYER.format(mu=0.3))
    bad = tmp_path / "bad.toml"
    bad.write_text(HEAD.replace("800", "-800") + LAYER.format(mu=1.5))
    return good, low, bad


def test_good_file(files, capsys):
    good, _, _ = files
    assert main(["validate", str(good)]) == 0
    out, err = capsys.readouterr()
    assert out == f"ok {good} (1 layer)\n" and err == ""


def test_warning_does_not_fail(files, capsys):
    _, low, _ = files
    assert main(["validate", str(low)]) == 0
    out, err = capsys.readouterr()
    assert out == f"ok {low} (1 layer)\n"
    assert err.startswith(f"frictex: warning: {low}:12: layer[1].mu: asks for mu' down to 0.3, but the device "
                          f"reaches only 0.5717 at the nominal 0.5 N")
    assert err.count("\n") == 1


def test_bad_file_lists_every_problem_and_exits_2(files, capsys):
    _, _, bad = files
    assert main(["validate", str(bad)]) == 2
    out, err = capsys.readouterr()
    assert out == ""
    assert err.splitlines() == [
        f"frictex: error: {bad}:5: display.width_px: -800 is outside [1, 8192] (px)",
        f"frictex: error: {bad}:12: layer[1].mu: 1.5 is outside (0, 1] (relative friction mu')",
    ]


def test_several_files_and_bundled_names(files, capsys, tmp_path):
    good, low, bad = files
    missing = tmp_path / "missing.toml"
    assert main(["validate", str(good), str(bad), "grating-5mm", str(missing), str(low)]) == 2
    out, err = capsys.readouterr()
    assert out.splitlines() == [f"ok {good} (1 layer)", f"ok {LIBRARY_DIR / 'grating-5mm.toml'} (1 layer)",
                                f"ok {low} (1 layer)"]
    assert f"frictex: error: {missing}: no such file\n" in err
    assert err.splitlines()[-1] == "frictex: error: 2 of 5 files have problems"
    assert all(line.startswith("frictex: ") for line in err.splitlines())


def test_help_and_usage(capsys):
    with pytest.raises(SystemExit) as info:
        main(["validate", "--help"])
    assert info.value.code == 0
    assert "FILE" in capsys.readouterr().out
    with pytest.raises(SystemExit) as info:
        main(["validate"])
    assert info.value.code == 2
    assert "required: FILE" in capsys.readouterr().err
