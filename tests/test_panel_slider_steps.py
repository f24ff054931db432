"""A panel slider keeps the file's value when its knob is grabbed and not moved, on
every bundled scene and every example of FORMAT.md; its range for a force or a time
is narrowed around the value (not the format's 100 N or 60 s catch-all) and its step
is fine enough for the value (at most a tenth of it); the gain validate advises for a
loud recorded layer can be set and is kept."""

import re
from pathlib import Path

import pytest

from frictex.app.live.layer_edit import LayerEdit, Slider
from frictex.textures.library import list_scenes
from frictex.textures.loader import check_scene, load_scene

ROOT = Path(__file__).resolve().parents[1]
LIBRARY = ROOT / "textures" / "library"


@pytest.fixture(autouse=True)
def user_folder(tmp_path, monkeypatch):
    """The user's scene folder under the test's own folder."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))


def page_examples() -> dict[str, str]:
    """FORMAT.md's example files (``<!-- example: NAME -->`` + a toml block)."""
    page = (ROOT / "textures" / "FORMAT.md").read_text("utf-8")
    return dict(re.findall(r"<!-- example: ([\w-]+) -->\n```toml\n(.*?)```", page, re.S))


def hatt_model() -> str:
    """The complete HaTT model AUTHORING.md gives (the examples' ``wood.xml``)."""
    page = (ROOT / "textures" / "AUTHORING.md").read_text("utf-8")
    return re.search(r"<!-- example: hatt-model -->\n```xml\n(.*?)```", page, re.S).group(1)


def example_files(folder: Path) -> list[Path]:
    """FORMAT.md's examples as files in ``folder``, beside the files they name."""
    (folder / "raster-map.png").write_bytes((LIBRARY / "raster-map.png").read_bytes())
    (folder / "clips").mkdir()
    clip = LIBRARY / "clips" / "tick-then-buzz.ahap"
    (folder / "clips" / clip.name).write_bytes(clip.read_bytes())
    (folder / "wood.xml").write_text(hatt_model(), encoding="utf-8")
    paths = []
    for name, text in page_examples().items():
        paths.append(folder / f"{name}.toml")
        paths[-1].write_text(text, encoding="utf-8")
    return paths


def sliders(ed: LayerEdit):
    """(layer index, slider) of every layer's sliders, the layer selected."""
    for k in range(len(ed.layer_names())):
        ed.select(k)
        for c in ed.controls():
            if isinstance(c, Slider):
                yield k, c


def test_grabbing_a_knob_without_moving_keeps_every_value_and_steps_fit_it(tmp_path):
    files = [entry.path for entry in list_scenes()] + example_files(tmp_path)
    checked = 0
    for path in files:
        load_scene(path)
        ed = LayerEdit(path)
        for k, c in sliders(ed):
            where = f"{path.name} layer {k + 1} {c.key} = {c.value!r}"
            written = ed.set(c.key, c.value_at(c.fraction))
            assert written == pytest.approx(c.value, rel=1e-12, abs=0.0), where
            assert ed.control(c.key).value == pytest.approx(c.value, rel=1e-12, abs=0.0), where
            if c.value != 0.0 and not c.integer:
                assert c.step <= abs(c.value) / 10, f"{where}: step {c.step:g}"
            checked += 1
    assert checked > 100


def bundled_slider(name: str, key: str) -> Slider:
    ed = LayerEdit(LIBRARY / f"{name}.toml")
    return next(c for _, c in sliders(ed) if c.key == key)


def test_a_force_or_time_slider_spans_about_four_times_its_value():
    force = bundled_slider("keyclick-beam", "force_n")
    assert (force.lo, force.hi) == (pytest.approx(force.step), pytest.approx(4 * 0.065))
    ring = bundled_slider("directional-ring", "force_forward_n")
    assert (ring.lo, ring.hi) == (pytest.approx(-0.12), pytest.approx(0.12))  # either sign
    ramp = bundled_slider("slider-clips", "duration_s")
    assert ramp.hi == pytest.approx(0.6) and ramp.step <= 0.001


def test_a_drag_is_rounded_to_the_step_and_a_small_force_can_be_set(tmp_path):
    ed = LayerEdit(LIBRARY / "keyclick-beam.toml")
    k = next(k for k, c in sliders(ed) if c.key == "force_n")
    ed.select(k)
    force = ed.control("force_n")
    dragged = force.value_at(0.3 + 1e-7)
    written = ed.set("force_n", dragged)  # a drag: rounded to the step, a short decimal
    assert written == round(round(dragged / force.step) * force.step, 4) and len(repr(written)) <= 6
    ed.undo()
    assert ed.set("force_n", 0.0425) == 0.0425


def recorded(tmp_path, gain: float) -> Path:
    (tmp_path / "wood.xml").write_text(hatt_model(), encoding="utf-8")
    path = tmp_path / "loud.toml"
    text = re.sub(r"\ngain = \S+", f"\ngain = {gain!r}", page_examples()["recorded-example"])
    path.write_text(text, encoding="utf-8")
    return path


def advised_gain(path: Path) -> float:
    """The gain validate advises for ``path``'s recorded layer ("lower gain to X")."""
    _, problems, warnings = check_scene(path)
    assert problems == []
    said = " ".join(str(w) for w in warnings)
    return float(re.search(r"lower gain to (\S+) or less", said).group(1))


def test_the_gain_validate_advises_can_be_set_and_is_kept(tmp_path):
    path = recorded(tmp_path, 0.5)
    advice = advised_gain(path)
    assert advice < 0.05
    ed = LayerEdit(path)
    k = next(k for k, c in sliders(ed) if c.key == "gain")
    ed.select(k)
    near = float(f"{advice * 2:.1g}")  # a drag down, close to it: the slider spans 4 x that
    assert ed.set("gain", near) == near
    assert ed.control("gain").step <= advice / 100
    assert ed.set("gain", advice) == advice
    assert ed.set("gain", 0.0075) == 0.0075
    assert advised_gain(path) == advice and not check_scene(path, text=ed.text())[2]
