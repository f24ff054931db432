"""frictex preview (CLI, PNG content) and the replay frames writer."""

import numpy as np
import pytest
from PIL import Image

from frictex.app.commands.cli import main
from frictex.app.engine.frames import FrameWriter
from frictex.app.engine.replay import run_replay
from frictex.textures.library import LIBRARY_DIR
from scenes import GRATING_4MM, grating_scene, rising_edge_period


def test_preview_writes_scene_beside_its_friction_map(tmp_path, capsys):
    out = tmp_path / "p.png"
    assert main(["preview", "grating-5mm", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "mu' of a finger touching alone 0.600 to 1.000" in printed and "800 x 480 px" in printed
    img = np.asarray(Image.open(out).convert("RGB"))
    assert img.shape[1] > 1000  # two panels side by side


@pytest.mark.parametrize("size, px_per_mm", [(None, 10.0), ("2400x1600", 20.0), ("600x600", 5.0)])
def test_the_scene_image_is_at_the_display_pixels_and_a_gratings_period_measures_in_it(
        tmp_path, capsys, size, px_per_mm):
    scene = tmp_path / "g.toml"
    scene.write_text(GRATING_4MM)
    out = tmp_path / "g.png"
    assert main(["preview", str(scene), "-o", str(out)] + (["--size", size] if size else [])) == 0
    figure, drawn = capsys.readouterr().out.splitlines()[:2]
    image = Image.open(tmp_path / "g-scene.png")
    w, h = round(120 * px_per_mm), round(80 * px_per_mm)
    assert image.size == (w, h)
    assert drawn.startswith(f"wrote {tmp_path / 'g-scene.png'}: the scene as the demo's window "
                            f"draws it, {w} x {h} px, {px_per_mm:g} px/mm along x")
    assert ("the display's pixels" in drawn) == (size is None)
    grey = np.asarray(image.convert("L"), dtype=np.float64)
    for row in grey[::97]:
        assert rising_edge_period(row) == pytest.approx(4.0 * px_per_mm, abs=1.0)
    assert f"a {Image.open(out).size[0]} x {Image.open(out).size[1]} px figure" in figure


def test_the_scene_image_can_be_named_but_not_as_the_figure(tmp_path, capsys):
    out = tmp_path / "g.png"
    assert main(["preview", "grating-5mm", "-o", str(out), "--scene-out",
                 str(tmp_path / "exact.png")]) == 0
    assert Image.open(tmp_path / "exact.png").size == (800, 480)
    assert not (tmp_path / "g-scene.png").exists()
    assert main(["preview", "grating-5mm", "-o", str(out), "--scene-out", str(out)]) == 2
    assert "is the figure's file" in capsys.readouterr().err


@pytest.mark.parametrize("argv, message", [
    (["preview", "no-such-scene", "-o", "x.png"], "no-such-scene"),
    (["preview", "grating-5mm", "-o", "out.jpg"], "expected a .png"),
    (["preview", "grating-5mm", "-o", "missing-dir/out.png"], "does not exist"),
])
def test_preview_bad_input_is_one_line_exit_2(tmp_path, monkeypatch, capsys, argv, message):
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error:") and message in err and err.count("\n") == 1


def test_preview_size_is_validated(capsys):
    with pytest.raises(SystemExit) as exc:
        main(["preview", "grating-5mm", "-o", "x.png", "--size", "800by480"])
    assert exc.value.code == 2 and "WIDTHxHEIGHT" in capsys.readouterr().err


def test_frames_follow_the_replayed_finger(gl, tmp_path):
    scene = grating_scene(5.0)
    frames = FrameWriter(tmp_path, scene, fps=20.0, size=(400, 240))
    run_replay(scene, "swipe-40mms-50hz", tmp_path, progress=False, frames=frames)
    files = sorted((tmp_path / "frames").glob("frame_*.png"))
    import json
    duration = json.loads((tmp_path / "summary.json").read_text())["output"]["duration_s"]
    assert len(files) == int(np.floor(duration * 20.0 + 1e-9)) + 1
    # the cursor (finger 0 is blue) moves right from frame to frame while the finger swipes
    xs = []
    for f in files[2:-2]:
        rgb = np.asarray(Image.open(f).convert("RGB")).astype(int)
        blue = (rgb[..., 2] > 200) & (rgb[..., 0] < 80)
        cols = np.flatnonzero(blue[:150].any(axis=0))
        xs.append(cols.mean())
    assert (np.diff(xs) > 0).all()


def test_default_panel_is_the_display_size_scaled_to_fit_2048_px():
    from types import SimpleNamespace

    from frictex.app.commands.preview import default_size
    assert default_size(SimpleNamespace(width_px=800, height_px=480)) == (800, 480)
    assert default_size(SimpleNamespace(width_px=16384, height_px=4096)) == (2048, 512)
    assert default_size(SimpleNamespace(width_px=3, height_px=16384)) == (1, 2048)


def test_friction_map_in_row_bands_equals_one_pass(monkeypatch):
    from frictex.app.commands import preview
    from frictex.rendering.visual.viewport import fit_viewport
    scene = grating_scene(5.0)
    viewport = fit_viewport(scene.display, 90, 54)
    monkeypatch.setattr(preview, "ROWS_PER_PASS", 10_000)
    whole = preview.mu_map(scene, viewport)
    monkeypatch.setattr(preview, "ROWS_PER_PASS", 7)
    banded = preview.mu_map(scene, viewport)
    assert banded.shape == (54, 90)
    np.testing.assert_array_equal(banded, whole)
    assert whole.min() == pytest.approx(0.6) and whole.max() == pytest.approx(1.0)


@pytest.mark.parametrize("path", sorted(LIBRARY_DIR.glob("*.toml")), ids=lambda p: p.stem)
def test_no_text_of_a_bundled_scenes_preview_overlaps_or_leaves_the_figure(path):
    from frictex.app.commands.preview import preview_figure
    from frictex.app.measure.figure_check import text_flaws
    from frictex.textures.loader import load_scene
    fig, _ = preview_figure(load_scene(path), size=(400, 400))
    assert [str(flaw) for flaw in text_flaws(fig)] == []


def test_the_plank_as_first_written_is_hatched_below_the_floor_and_titled_by_its_layers(tmp_path):
    """The page's first plank: the floor as a red tick of its own, the places below it
    hatched (their share in the title), each layer named by its file's type and shape."""
    from matplotlib.collections import Collection

    from frictex.app.commands.preview import preview_figure
    from frictex.textures.format_doc import example_files
    from frictex.textures.loader import load_scene
    path = tmp_path / "plank.toml"
    shown = {}
    for name in ("plank-first", "plank"):
        path.write_text(example_files()[name], encoding="utf-8")
        fig, info = preview_figure(load_scene(path), size=(400, 240))
        fig.draw_without_rendering()
        hatched = [c for ax in fig.axes for c in ax.collections
                   if isinstance(c, Collection) and "////" in (getattr(c, "hatches", None) or ())]
        shown[name] = info["below"], len(hatched)
        floor = [t for t in fig.axes[-1].get_yticklabels() if t.get_text().startswith("floor")]
        assert [t.get_text() for t in floor] == ["floor 0.57"] and floor[0].get_color() == "red"
        title = fig.get_suptitle().replace("\n", " ")
        assert "grain (triangle waveform, hybrid, 1.5 mm); rings (grating, hybrid, 9 mm); " \
               "knot (height bump, felt moving +x)" in title
    below, hatches = shown["plank-first"]
    assert 0.1 < below < 0.2 and hatches == 1
    assert shown["plank"] == (0.0, 0)


def test_layer_kinds_are_the_files_words():
    from frictex.app.commands.preview import layer_kind
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    kinds = {layer_kind(layer) for name in ("objects-bump-edge-disc", "height-button", "raster-map",
                                            "height-ridge", "composed-fine-grating-in-disc")
             for layer in load_scene(resolve_scene(name)).layers}
    assert {"height button", "height ridge", "raster", "disc", "bump", "edge"} <= kinds
    assert not any(k in kinds for k in ("shape", "rastermap", "height gaussianbump", "height buttonrim"))


def test_preview_prints_its_output_path_escaped(tmp_path, capsys):
    out = tmp_path / "p\x1b[2J\u202e.png"
    assert main(["preview", "grating-5mm", "-o", str(out)]) == 0
    printed = capsys.readouterr().out
    assert "\x1b" not in printed and "\u202e" not in printed
    assert "p\\x1b[2J\\u202e.png: " in printed and out.is_file()


@pytest.mark.parametrize("events, deepest", [
    # a 5 ms tick (sharpness 1) of intensity 0.6: its Hann peak falls on a sample
    ('clip = "tick"\nintensity = 0.6\nsharpness = 1.0\n', 1.0 - 0.5 * 0.6),
    # a ramp from 0 to full level: 1 - depth at its end
    ('clip = "ramp"\nduration_s = 0.1\nlevel_from = 0.0\nlevel_to = 1.0\n', 1.0 - 0.5),
])
def test_a_clips_title_gives_the_deepest_mu_it_plays(tmp_path, events, deepest):
    """Not 1 - depth (0.5) when the events never reach full level."""
    from frictex.app.commands.preview import preview_figure
    from frictex.textures.loader import load_scene
    path = tmp_path / "c.toml"
    path.write_text(GRATING_4MM.split("[[layer]]")[0] + '[[layer]]\ntype = "clip"\nname = "k"\n'
                    f'trigger = "down"\ndepth = 0.5\n{events}', encoding="utf-8")
    fig, _ = preview_figure(load_scene(path), size=(120, 80))
    assert f"deepest mu' {deepest:.3f}; not in the map" in fig.get_suptitle().replace("\n", " ")
