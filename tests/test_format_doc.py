"""textures/FORMAT.md is what the loader accepts: generated from its key tables, and equal;
every key defined, every derived default given as its rule; every example on the page
validates and replays; every convention it states holds on the loader's friction map."""

import math
import re
import shutil
import tomllib
from pathlib import Path

import numpy as np
import pytest

from frictex.rendering.compose import ideal_mu
from frictex.textures import format_doc
from frictex.textures import loader as L
from frictex.textures import schema as S

ROOT = Path(__file__).resolve().parents[1]
PAGE = ROOT / "textures" / "FORMAT.md"
LIBRARY = ROOT / "textures" / "library"


def page_examples() -> dict[str, str]:
    """The example files as the page shows them (``<!-- example: NAME -->`` + a toml block)."""
    found = re.findall(r"<!-- example: ([\w-]+) -->\n```toml\n(.*?)```", PAGE.read_text("utf-8"),
                       re.S)
    return dict(found)


def write_examples(folder: Path) -> dict[str, Path]:
    """Every example of the page as a file in ``folder``, beside the files they name
    (``wood.xml``: the complete model AUTHORING.md gives, where the page sends its reader)."""
    shutil.copy(LIBRARY / "raster-map.png", folder / "raster-map.png")
    (folder / "clips").mkdir()
    shutil.copy(LIBRARY / "clips" / "tick-then-buzz.ahap", folder / "clips")
    authoring = (ROOT / "textures" / "AUTHORING.md").read_text("utf-8")
    model = re.search(r"<!-- example: hatt-model -->\n```xml\n(.*?)```", authoring, re.S)
    (folder / "wood.xml").write_text(model.group(1), encoding="utf-8")
    paths = {}
    for name, text in page_examples().items():
        paths[name] = folder / f"{name}.toml"
        paths[name].write_text(text, encoding="utf-8")
    return paths


def scene_of(text: str, folder: Path):
    path = folder / "scene.toml"
    path.write_text(text, encoding="utf-8")
    return L.load_scene(path)


def test_the_page_is_the_loaders_tables():
    assert PAGE.read_text(encoding="utf-8") == format_doc.render(), (
        "textures/FORMAT.md is stale: .venv/bin/python -m frictex.textures.format_doc > textures/FORMAT.md")


def test_every_layer_type_has_its_table():
    assert set(L.LAYER_KEYS) == set(L.LAYER_TYPES)


def test_every_key_is_defined_and_every_derived_default_has_its_rule():
    for title, specs in format_doc.sections():
        for key, spec in specs.items():
            if isinstance(spec, S.Retired):
                continue
            assert len(spec.doc) > 10, (title, key)
            if spec.default is None:
                assert len(spec.rule) > 5, (title, key)
    assert "derived, see" not in PAGE.read_text(encoding="utf-8")


def test_every_key_of_the_bundled_scenes_is_on_the_page():
    """The bundled files use only documented keys (a key the loader read without a table
    entry would be missing from the page)."""
    page = PAGE.read_text(encoding="utf-8")
    for path in LIBRARY.glob("*.toml"):
        doc = tomllib.loads(path.read_text(encoding="utf-8"))
        keys = set()

        def walk(value):
            if isinstance(value, dict):
                for key, inner in value.items():
                    keys.add(key)
                    walk(inner)
            elif isinstance(value, list):
                for inner in value:
                    walk(inner)
        walk(doc)
        tables = {"display", "device", "friction", "calibration", "structure", "driving",
                  "layer", "region", "visual"}
        missing = [k for k in keys - tables if f"| `{k}` |" not in page]
        assert missing == [], f"{path.name}: {missing}"


def test_the_page_has_a_complete_example_of_every_layer_type():
    examples = page_examples()
    assert examples == format_doc.example_files()
    for kind in L.LAYER_TYPES:
        assert f'type = "{kind}"' in examples[f"{kind}-example"], kind


def test_every_example_validates_without_warning_and_replays_clean(tmp_path):
    """Each example as a reader copies it: no warning from the loader or from validate's
    reach check, and a short fast swipe and a 40 mm/s one across 70 % of the display
    replay with none either (no force out of reach, no mu' clipped by the layer's
    limits); but the walk-through's first plank, whose clamps the page shows and
    corrects."""
    from frictex.app.commands.validate import force_reach_warnings
    from frictex.app.engine.replay import run_replay
    from frictex.rendering.input.trace_synth import make_motion, sample
    for name, path in write_examples(tmp_path).items():
        scene, problems, warnings = L.check_scene(path)
        assert scene is not None and problems == [], (name, [str(p) for p in problems])
        assert warnings == [], (name, [str(w) for w in warnings])
        assert force_reach_warnings(path, scene) == [], name
        d = scene.display
        motion = make_motion("swipe", speed_mm_s=60.0, duration_s=0.5, x0_mm=0.2 * d.width_mm,
                             y0_mm=0.5 * d.height_mm)
        summary = run_replay(scene, sample(motion, 60.0), tmp_path / f"run-{name}", progress=False)
        assert summary["output"]["duration_s"] > 0.4, name
        if name == "plank-first":
            continue
        assert summary["warnings"] == [], name
        across = make_motion("swipe", speed_mm_s=40.0, duration_s=0.7 * d.width_mm / 40.0,
                             x0_mm=0.1 * d.width_mm, y0_mm=0.5 * d.height_mm)
        slow = run_replay(scene, sample(across, 50.0), tmp_path / f"slow-{name}", progress=False)
        assert slow["warnings"] == [], name
        mu = np.loadtxt(tmp_path / f"run-{name}" / "friction.csv", delimiter=",", skiprows=1,
                        usecols=4)
        assert np.isfinite(mu).all() and ((mu > 0) & (mu <= 1)).all(), name


# ---- the conventions the page states, on the loader's friction map ------------------------

def _periodic(tmp_path, angle: float) -> object:
    return scene_of(format_doc.example_files()["grating-example"]
                    .replace("angle_deg = 0.0", f"angle_deg = {angle}")
                    .replace('edge = "smooth"\nedge_mm = 0.5\n', ""), tmp_path)


def _along(scene, x, y, dx, dy, n=40):
    """mu' at n points from (x, y) along (dx, dy) mm steps."""
    k = np.arange(n)
    return ideal_mu(scene, x + dx * k, y + dy * k)


@pytest.mark.parametrize("angle, line_deg", [(0.0, 90.0), (90.0, 0.0), (45.0, -45.0),
                                             (95.0, 5.0), (-30.0, 60.0)])
def test_angle_deg_of_a_grating_is_the_normal_of_its_lines_clockwise_with_y_down(
        tmp_path, angle, line_deg):
    """Along the lines (angle_deg - 90, from +x towards +y) mu' is constant; across them
    (angle_deg) it runs through both levels. 0: vertical lines; 90: horizontal; 45: lines
    rising to the right on the screen (direction (1, -1) in y-down coordinates)."""
    scene = _periodic(tmp_path, angle)
    a, t = math.radians(angle), math.radians(line_deg)
    start = (50.3, 30.1)
    along = _along(scene, *start, 0.5 * math.cos(t), 0.5 * math.sin(t))
    across = _along(scene, *start, 0.5 * math.cos(a), 0.5 * math.sin(a))
    assert np.ptp(along) == 0.0
    assert set(np.round(across, 12)) == {0.6, 1.0}


def test_phase_zero_lies_offset_mm_along_the_axis_and_starts_with_mu_low(tmp_path):
    scene = _periodic(tmp_path, 0.0)
    assert ideal_mu(scene, np.array([0.1, 2.4, 2.6, 4.9]), np.full(4, 10.0)).tolist() == [
        0.6, 0.6, 1.0, 1.0]


def test_waveform_shapes_start_as_the_page_says(tmp_path):
    from frictex.textures.model import Waveform
    p = np.array([0.0, 0.25, 0.5])
    expected = {"sine": [0.6, 0.8, 1.0], "triangle": [1.0, 0.8, 0.6], "sawtooth": [1.0, 0.9, 0.8]}
    for shape, values in expected.items():
        w = Waveform(name="w", render="sho", blend="multiply", region=None, visual=None,
                     shape=shape, mu_min=0.6, mu_max=1.0)
        np.testing.assert_allclose(w.profile(p), values, atol=1e-12)
    square = Waveform(name="w", render="sho", blend="multiply", region=None, visual=None,
                      shape="square", mu_min=0.6, mu_max=1.0, duty=0.3)
    assert square.profile(np.array([0.1, 0.4])).tolist() == [0.6, 1.0]


@pytest.mark.parametrize("angle, inside, outside", [(0.0, (60.0, 10.0), (50.0, 10.0)),
                                                    (90.0, (20.0, 40.0), (20.0, 25.0))])
def test_an_edges_angle_is_its_normal_and_mu_lies_where_it_points(tmp_path, angle, inside, outside):
    text = format_doc.example_files()["edge-example"].replace(
        "angle_deg = 0.0", f"angle_deg = {angle}").replace("edge_mm = 1.0", "edge_mm = 0.0")
    scene = scene_of(text, tmp_path)
    assert ideal_mu(scene, *inside) == pytest.approx(0.7)
    assert ideal_mu(scene, *outside) == 1.0


def test_a_rectangles_angle_turns_it_clockwise_on_the_screen(tmp_path):
    """A 40 x 4 mm rectangle at +15 deg: its long axis goes down to the right."""
    scene = scene_of(format_doc.example_files()["rectangle-example"]
                     .replace("edge_mm = 2.0", "edge_mm = 0.0")
                     .replace("height_mm = 20.0", "height_mm = 4.0"), tmp_path)
    cx, cy, reach = 50.0, 22.0, 18.0
    t = math.radians(15.0)
    assert ideal_mu(scene, cx + reach * math.cos(t), cy + reach * math.sin(t)) == pytest.approx(0.7)
    assert ideal_mu(scene, cx + reach * math.cos(t), cy - reach * math.sin(t)) == 1.0


def test_a_guidance_line_angle_is_the_lines_own_direction():
    from frictex.textures.model import Guidance
    g = Guidance(name="g", render="sho", blend="multiply", region=None, visual=None, x_mm=70.0,
                 y_mm=15.0, line=True, line_angle_deg=90.0, gain_n_per_mm=0.002, max_force_n=0.05)
    fx, fy = g.pull(np.array([60.0]), np.array([5.0]))
    assert fx[0] > 0 and fy[0] == pytest.approx(0.0, abs=1e-15)  # towards the vertical line x = 70


def test_a_height_ridges_angle_is_the_way_its_crest_runs(tmp_path):
    scene = L.load_scene(write_examples(tmp_path)["height-example"])
    shape = scene.layers[0].shape
    gx, gy = shape.gradient(np.array([50.0, 50.0]), np.array([10.0, 50.0]))
    assert gx[0] > 0 and gx[0] == pytest.approx(gx[1]) and np.allclose(gy, 0.0, atol=1e-12)


def test_a_region_on_a_height_layer_is_a_step_of_mu_rest_and_without_it_none(tmp_path):
    """The page's warning: the first plank's knot steps at its disc's outline by mu_rest;
    the corrected plank's knot (no region) is continuous there."""
    from frictex.rendering.reach import as_previewed
    paths = write_examples(tmp_path)
    outline = 70.0 + 12.0
    x = np.array([outline - 1e-6, outline + 1e-6])
    y = np.full(2, 32.0)
    knot = as_previewed(L.load_scene(paths["plank-first"])).layers[-1]
    inside, outside = np.where(knot.covers(x, y), knot.mu_at(x, y), 1.0)
    assert inside == pytest.approx(0.8, abs=0.02) and outside == 1.0  # a step of ~0.2
    knot = as_previewed(L.load_scene(paths["plank"])).layers[-1]
    inside, outside = np.where(knot.covers(x, y), knot.mu_at(x, y), 1.0)
    assert inside == pytest.approx(outside, abs=1e-6) and knot.covers(x, y).all()


def test_the_colour_grammar_of_the_page_is_the_parsers(tmp_path):
    kind = format_doc._kind(S.Colour())
    assert '"#rrggbb" or "#rgb"' in kind
    text = format_doc.example_files()["grating-example"]
    assert scene_of(text, tmp_path).layers[0].visual.color_high == (1.0, 1.0, 1.0)
    with pytest.raises(L.TextureError, match='expected a colour "#rrggbb" or "#rgb"'):
        scene_of(text.replace('"#fff"', "[1, 1, 1]"), tmp_path)


def test_a_one_to_one_raster_takes_its_size_from_the_display_density(tmp_path):
    """Display pixels and millimetres: one image pixel per display pixel, each axis with its
    own density; a display whose pixel aspect differs stretches the image along one axis."""
    from PIL import Image
    text = (format_doc.example_files()["raster-example"].replace('mode = "tile"', 'mode = "one-to-one"'))
    text = re.sub(r"(width_mm|height_mm|tile_width_mm|tile_height_mm) = [\d.]+\n", "",
                  text.split("[[layer]]")[1])
    head = format_doc.example_files()["raster-example"].split("[[layer]]")[0]
    write_examples(tmp_path)
    cols, rows = Image.open(tmp_path / "raster-map.png").size
    for width_px in (800, 400):  # square pixels, then twice as wide
        scene = scene_of(head.replace("width_px = 800", f"width_px = {width_px}")
                         + "[[layer]]" + text, tmp_path)
        layer = scene.layers[0]
        assert layer.width_mm == pytest.approx(cols * 108.0 / width_px)
        assert layer.height_mm == pytest.approx(rows * 64.8 / 480)


def test_the_walkthroughs_warning_is_what_validate_prints(tmp_path, capsys):
    from frictex.app.commands.cli import main
    path = write_examples(tmp_path)["plank-first"]
    target = tmp_path / "plank.toml"
    path.rename(target)
    assert main(["validate", str(target)]) == 0
    err = capsys.readouterr().err.replace(str(target), "plank.toml")
    page = " ".join(PAGE.read_text(encoding="utf-8").split())
    assert " ".join(err.split()) in page


def test_the_walkthroughs_shares_below_the_floor_are_the_preview_and_validate_ones(tmp_path):
    """The page gives preview's share (mu' averaged over each pixel) beside validate's
    (mu' at points), and why they differ; both take the knot sliding towards +x."""
    from frictex.app.commands.preview import preview_figure
    from frictex.rendering.reach import scene_reach
    scene = L.load_scene(write_examples(tmp_path)["plank-first"])
    below = preview_figure(scene)[1]["below"]
    page = " ".join(PAGE.read_text(encoding="utf-8").split())
    assert (f"hatches the places below the floor: {below:.1%} of the display, not "
            f"{scene_reach(scene).area_share:.1%}, as it averages mu' over each pixel") in page


def test_the_corrected_plank_plays_without_a_clamp_and_its_knot_is_felt(tmp_path):
    """The walk-through's plank, replayed with a vertical swipe at 40 mm/s through the
    knot: no target below the device's floor (the first plank: hundreds), and friction
    higher over the knot's flanks than away from it (magnitude rendering: rougher where
    steeper)."""
    from frictex.app.engine.replay import run_replay
    from frictex.rendering.input.trace_synth import make_motion, sample
    paths = write_examples(tmp_path)
    motion = make_motion("swipe", speed_mm_s=40.0, duration_s=1.4, x0_mm=70.0, y0_mm=4.0,
                         angle_deg=90.0)
    clamped = {}
    for name in ("plank-first", "plank"):
        out = tmp_path / f"run-{name}"
        clamped[name] = run_replay(L.load_scene(paths[name]), sample(motion, 120.0), out,
                                   progress=False)["clamps"]["unreachable"]
    assert clamped["plank"] == 0 and clamped["plank-first"] > 100
    table = np.loadtxt(tmp_path / "run-plank" / "friction.csv", delimiter=",", skiprows=1)
    y, mu = table[:, 3], table[:, 4]
    flank = (np.abs(y - 32.0) > 1.0) & (np.abs(y - 32.0) < 6.0)
    away = np.abs(y - 32.0) > 12.0
    assert mu[flank].mean() > mu[away].mean() + 0.05


def test_every_limit_of_the_loader_is_on_the_page_with_its_value():
    """Every ``MAX_`` constant of ``frictex.textures`` (its modules and sections) is in the
    page's Limits list, and the list shows each one's value (``format_doc.limits``)."""
    import importlib
    import pkgutil

    import frictex.textures as package
    found = {}
    for info in pkgutil.walk_packages(package.__path__, package.__name__ + "."):
        module = importlib.import_module(info.name)
        for name, value in vars(module).items():
            if name.startswith("MAX_") and isinstance(value, (int, float)):
                found[(name, value)] = info.name
    listed = {(name, value) for _, name, value, _ in format_doc.limits()}
    assert set(found) - listed == set(), "limits missing from format_doc.limits()"
    section = PAGE.read_text(encoding="utf-8").split("### Limits")[1].split("\n## ")[0]
    for _, name, value, text in format_doc.limits():
        assert f"- {text.format(format_doc._size(value))}\n" in section
    assert "- at most 32 `[[layer]]` tables in a scene\n" in section
    assert "- arrays and inline tables nested at most 16 deep\n" in section
