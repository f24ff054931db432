"""``frictex validate``: output lines and exit codes, as a user sees them."""

import re

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
    layer, reach = err.splitlines()
    assert layer.startswith(f"frictex: warning: {low}:12: layer[1].mu: asks for mu' down to 0.3, but the "
                            f"device reaches only 0.5717 at the nominal 0.5 N")
    assert reach.startswith(f"frictex: warning: {low}: layers: ")
    assert 'from layer "bump-1"; lowest where layers overlap: 0.3, layer "bump-1" alone;' in reach


def test_strict_fails_a_file_with_warnings_with_exit_2(files, capsys):
    good, low, _ = files
    assert main(["validate", "--strict", str(good)]) == 0
    assert capsys.readouterr().out == f"ok {good} (1 layer)\n"
    assert main(["validate", "--strict", str(good), str(low)]) == 2
    out, err = capsys.readouterr()
    assert out == f"ok {good} (1 layer)\n"
    assert f"frictex: error: {low}: 2 warnings (--strict)" in err.splitlines()
    assert err.splitlines()[-1] == "frictex: error: 1 of 2 files have problems"


def _plank(tmp_path, name):
    from frictex.textures.format_doc import example_files
    path = tmp_path / "plank.toml"
    path.write_text(example_files()[name], encoding="utf-8")
    return path


def test_the_plank_as_first_written_warns_of_its_stroke_below_the_floor(tmp_path, capsys):
    """Each layer alone is within reach (no warning of the loader's); their product is
    not: 12-13 % of a typical stroke, naming the grain and the rings."""
    path = _plank(tmp_path, "plank-first")
    assert main(["validate", str(path)]) == 0
    out, err = capsys.readouterr()
    assert out == f"ok {path} (3 layers)\n"
    [line] = err.splitlines()
    share = float(re.search(r"layers: ([\d.]+)% of a typical stroke", line).group(1))
    assert 12.0 <= share <= 13.0
    assert ('floor 0.5717 at the nominal 0.5 N, from layers "grain", "rings"; lowest where layers '
            'overlap: 0.346, the product of layers "grain", "rings", "knot";') in line
    assert main(["validate", "--strict", str(path)]) == 2


def test_the_corrected_plank_validates_without_a_warning_even_strict(tmp_path, capsys):
    path = _plank(tmp_path, "plank")
    assert main(["validate", "--strict", str(path)]) == 0
    assert capsys.readouterr() == (f"ok {path} (3 layers)\n", "")


@pytest.mark.parametrize("path", sorted(LIBRARY_DIR.glob("*.toml")), ids=lambda p: p.stem)
def test_every_bundled_scene_validates_strict(path, capsys):
    assert main(["validate", "--strict", str(path)]) == 0, capsys.readouterr().err


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


def test_a_share_above_zero_never_reads_zero():
    from frictex.app.commands.validate import _share
    assert [_share(f) for f in (0.0, 1e-6, 0.0004999, 0.0005, 0.129)] == [
        "0.0%", "under 0.1%", "under 0.1%", "0.1%", "12.9%"]


def test_file_names_and_names_reach_the_terminal_escaped(tmp_path, capsys):
    """A file named with ESC/BEL sequences is printed escaped (it would set the terminal's
    title); a name holding a format character (U+202E reverses what follows) is refused."""
    hostile = tmp_path / "a\x1b]0;PWNED\x07\u202e.toml"
    hostile.write_text(HEAD + LAYER.format(mu=0.7))
    assert main(["validate", str(hostile)]) == 0
    out, err = capsys.readouterr()
    assert "\x1b" not in out and "\x07" not in out and "\u202e" not in out
    assert out.startswith("ok ") and "a\\x1b]0;PWNED\\x07\\u202e.toml (1 layer)" in out
    for name, char in (("ok\u202eTXT.exe", "\\u202e"), ("a\u200bb", "\\u200b"),
                       ("\u2066x", "\\u2066")):
        scene = tmp_path / "named.toml"
        scene.write_text(f'name = "{name}"\n' + HEAD + LAYER.format(mu=0.7).replace(
            "[[layer]]\n", f'[[layer]]\nname = "{name}"\n'))
        assert main(["validate", str(scene)]) == 2
        out, err = capsys.readouterr()
        assert out == "" and err.count(f"holds the format character '{char}'") == 2
        assert name not in err


def _validate(tmp_path, capsys, text):
    path = tmp_path / "s.toml"
    path.write_text(text)
    code = main(["validate", str(path)])
    return code, capsys.readouterr().err


@pytest.mark.parametrize("width_mm, width_px, warned, hint", [
    (0.108, 800, True, "in metres? 0.108 m = 108 mm"),  # the reviewer's file
    (108.0, 800, False, None),  # 0.135 mm per pixel
    (8.0, 800, False, None),  # 0.01: the bound itself
    (7.9, 800, True, None),  # 0.0099 mm per pixel, and in metres 9.9
    (1600.0, 800, False, None),  # 2.0
    (1700.0, 800, True, None),
    (108.0, 1, True, None),  # 108 mm per pixel: width_px is not the pixel count
])
def test_a_pixel_pitch_no_screen_has_is_warned_about(tmp_path, capsys, width_mm, width_px,
                                                     warned, hint):
    head = HEAD.replace("width_mm = 108.0", f"width_mm = {width_mm}").replace(
        "width_px = 800", f"width_px = {width_px}")
    grating = '[[layer]]\ntype = "grating"\nperiod_mm = 5.0\nmu_low = 0.7\n'
    code, err = _validate(tmp_path, capsys, head + grating)
    lines = [line for line in err.splitlines() if "display.width_mm" in line]
    assert code == 0 and len(lines) == warned
    if warned:
        pitch = width_mm / width_px
        assert lines[0].startswith(f"frictex: warning: {tmp_path / 's.toml'}:3: display.width_mm: "
                                   f"{width_mm:g} mm over width_px = {width_px} is {pitch:.3g} mm "
                                   "per pixel")
        assert "outside 0.01 to 2 mm per pixel" in lines[0]
        assert (hint in lines[0]) if hint else "metres" not in lines[0]


def test_a_length_too_small_in_mm_that_fits_in_metres_says_so(tmp_path, capsys):
    grating = '[[layer]]\ntype = "grating"\nperiod_mm = {}\nmu_low = 0.7\n'
    code, err = _validate(tmp_path, capsys, HEAD + grating.format(0.003))
    assert code == 2 and err.splitlines()[0].endswith(
        "layer[1].period_mm: 0.003 is outside [0.01, 10000] (mm); in metres? 0.003 m = 3 mm")
    code, err = _validate(tmp_path, capsys, HEAD + grating.format(0.000001))  # 1 um in m: too small
    assert code == 2 and "metres" not in err


@pytest.mark.parametrize("tail, table, key", [
    ("[layer.region]\ncx_mm = 50.0\ncy_mm = 30.0\nradius_mm = 10.0\nmu = 0.7\n",
     "[layer.region]", "region.mu"),
    ("[layer.visual]\ncolor_low = \"#000\"\nsigma_mm = 4\n", "[layer.visual]", "visual.sigma_mm"),
])
def test_a_layer_key_written_under_a_sub_table_asks_whether_it_belongs_above(tmp_path, capsys,
                                                                            tail, table, key):
    layer = LAYER.format(mu=0.7).replace(tail.split("\n")[-2] + "\n", "")
    code, err = _validate(tmp_path, capsys, HEAD + layer + tail)
    line = next(line for line in err.splitlines() if f"layer[1].{key}:" in line)
    assert code == 2 and line.endswith(
        f"; {key.split('.')[1]} is a key of the table above: did you mean to put it above "
        f"{table}? (every key after a [table] header belongs to that table)")


def test_a_key_that_belongs_nowhere_gets_no_such_hint(tmp_path, capsys):
    code, err = _validate(tmp_path, capsys, HEAD + LAYER.format(mu=0.7)
                          + "[layer.region]\ncx_mm = 50.0\ncy_mm = 30.0\nradius_mm = 10.0\n"
                            "depth = 0.3\n")
    assert code == 2 and "region.depth: unknown key" in err and "table above" not in err


@pytest.mark.parametrize("region, warned", [
    ("x_mm = 0.0\ny_mm = 0.0\nwidth_mm = 5.0\nheight_mm = 5.0\n", True),  # the reviewer's
    ("cx_mm = 90.0\ncy_mm = 30.0\nradius_mm = 10.0\n", True),
    ("cx_mm = 60.0\ncy_mm = 30.0\nradius_mm = 10.0\n", False),  # meets the bump's 4 sigma
])
def test_a_region_that_never_meets_its_layer_is_warned_about(tmp_path, capsys, region, warned):
    code, err = _validate(tmp_path, capsys, HEAD + LAYER.format(mu=0.7) + "[layer.region]\n" + region)
    assert code == 0
    assert ("layer[1].region: never meets where the layer acts (within x 34 to 66 mm, y 14 to "
            "46 mm): the layer covers nothing" in err) == warned


def _force_scene(tmp_path, name, old, new):
    """A bundled force scene with ``old`` replaced by ``new``."""
    text = (LIBRARY_DIR / f"{name}.toml").read_text()
    assert old in text
    path = tmp_path / f"{name}-changed.toml"
    path.write_text(text.replace(old, new))
    return path


def test_a_directional_region_reaching_the_beams_ends_is_warned_about(tmp_path, capsys):
    """On seed 002's finite beam the wave takes friction down to 0.3 only mid-span (a
    travelling-wave ratio of 0.68 and more, 227-373 mm): the whole beam asks for it where
    it cannot be given; the bundled 230-370 mm validates clean (strict, above)."""
    path = _force_scene(tmp_path, "directional-beam", "x_mm = 230.0, y_mm = 0.0, width_mm = 140.0",
                        "x_mm = 0.0, y_mm = 0.0, width_mm = 600.0")
    assert main(["validate", str(path)]) == 0
    out, err = capsys.readouterr()
    assert out == f"ok {path} (1 layer)\n"
    [line] = err.splitlines()
    share = float(re.search(r"forces: ([\d.]+)% of typical strokes", line).group(1))
    assert 15.0 <= share <= 30.0  # the stroke runs 108-221 mm: 21.6 % at these seeds
    assert "clamped to the nearest reachable (summary.json: clamps.unreachable)" in line
    assert main(["validate", "--strict", str(path)]) == 2
    capsys.readouterr()
    end = _force_scene(tmp_path, "directional-beam", "x_mm = 230.0, y_mm = 0.0, width_mm = 140.0",
                       "x_mm = 450.0, y_mm = 0.0, width_mm = 150.0")  # where no display stroke goes
    assert main(["validate", str(end)]) == 0
    assert "forces:" in capsys.readouterr().err


def test_a_key_click_pushing_harder_than_the_wave_can_is_warned_about(tmp_path, capsys):
    """A still finger pressing at 0.5 N gets at most 0.13 N/um x 0.5 N x (3 um - 1 um) =
    0.13 N from the ring's wave (seed 004, Fig. 3c): 0.1 N is given, 0.3 N is not."""
    path = _force_scene(tmp_path, "keyclick-ring", "force_n = 0.1 ", "force_n = 0.3 ")
    assert main(["validate", str(path)]) == 0
    [line] = capsys.readouterr().err.splitlines()
    assert 'forces: key-click "button":' in line and "of a press at its centre" in line
    share = float(re.search(r'"button": ([\d.]+)% of a press', line).group(1))
    assert share > 50.0  # every sample pressing below 1.15 N (0.3 / 0.13 x 0.5) at least
