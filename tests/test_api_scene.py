"""A Scene given to the API as an object (built or changed in code) is checked by the
rules of the texture file's keys, as a file is when read: a bad value is one
TextureError line naming the layer and the field, never a NaN in the output or a numpy
error from deep inside."""

import dataclasses
import math

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

import frictex
from frictex._inputs import checked_scene
from frictex.textures.errors import TextureError
from frictex.textures.library import list_scenes

TRACE = "swipe-40mms-50hz"
MU = "relative friction mu'"


@pytest.fixture(scope="module")
def short_trace():
    return frictex.synth_trace("swipe", duration_s=0.2)


def changed(scene_name: str, where: str, value):
    """The bundled scene with one field changed: ``where`` is ``layers[i].field``,
    ``layers[i].part.field`` (region, geometry, visual), ``display.field``,
    ``device.field`` or ``device.friction.field``."""
    scene = frictex.load_scene(scene_name)
    head, *rest = where.split(".")

    def replace(obj, names):
        if len(names) == 1:
            return dataclasses.replace(obj, **{names[0]: value})
        return dataclasses.replace(obj, **{names[0]: replace(getattr(obj, names[0]), names[1:])})

    if head.startswith("layers["):
        i = int(head[len("layers["):-1])
        layers = list(scene.layers)
        layers[i] = replace(layers[i], rest)
        return dataclasses.replace(scene, layers=tuple(layers))
    return replace(scene, [head, *rest])


BAD = [  # scene, field, value, the message after "<field>: "
    ("grating-5mm", "layers[0].mu_low", 5.0, f"5.0 is outside (0, 1] ({MU})"),
    ("grating-5mm", "layers[0].mu_low", math.nan, f"nan is not a finite number ({MU})"),
    ("grating-5mm", "layers[0].mu_low", -math.inf, f"-inf is not a finite number ({MU})"),
    ("grating-5mm", "layers[0].mu_low", np.float32("nan"), f"nan is not a finite number ({MU})"),
    ("grating-5mm", "layers[0].mu_low", 0.0, f"0.0 is outside (0, 1] ({MU})"),
    ("grating-5mm", "layers[0].mu_low", "0.5", f'expected a number ({MU}), got the string "0.5"; '
                                               "write the number without quotes: mu_low = 0.5"),
    ("grating-5mm", "layers[0].mu_low", None, f"expected a number ({MU}), got None"),
    ("grating-5mm", "layers[0].mu_low", True, f"expected a number ({MU}), got the boolean true"),
    ("grating-5mm", "layers[0].period_mm", 0.0, "0.0 is outside [0.01, 10000] (mm)"),
    ("grating-5mm", "layers[0].period_mm", -3.0, "-3.0 is outside [0.01, 10000] (mm)"),
    ("grating-5mm", "layers[0].duty", 1.0, "1.0 is outside (0, 1) (fraction of the period)"),
    ("grating-5mm", "layers[0].duty", [0.5], "expected a number (fraction of the period), got "
                                             "the list [0.5]"),
    ("grating-5mm", "layers[0].duty", object(), "expected a number (fraction of the period), "
                                                "got a value of type object"),
    ("grating-5mm", "layers[0].blend", "add", '"add" is not one of multiply, replace'),
    ("grating-5mm", "layers[0].fingers", "0", '"0": finger numbers start at "1" (the finger '
                                              "touching longest)"),
    ("grating-5mm", "layers[0].visual.outline", "yes", 'expected true or false, got the '
                                                       'string "yes"'),
    ("grating-5mm", "display.width_mm", 0.0, "0.0 is outside [0.001, 10000] (mm)"),
    ("grating-5mm", "display.width_px", 1.5, "expected an integer (px), got the number 1.5"),
    ("grating-5mm", "device.amplitude_limit_um", math.nan, "nan is not a finite number (um "
                                                           "zero-to-peak)"),
    ("grating-5mm", "device.friction.b_per_um", -1.0, "-1.0 is not > 0 (1/um)"),
    ("keyclick-ring", "layers[0].geometry.width_mm", 0.0, "0.0 is outside [0.001, 10000] (mm)"),
    ("keyclick-ring", "layers[0].press_n", math.inf, "inf is not a finite number (N)"),
    ("height-bump", "layers[0].gain", -1.0, "-1.0 is not > 0 (mu' per unit slope or mu' per "
                                            "m/s^2)"),
    ("objects-bump-edge-disc", "layers[0].mu", 1.5, f"1.5 is outside (0, 1] ({MU})"),
]


@pytest.mark.parametrize("scene_name, where, value, message", BAD,
                         ids=[f"{w}={type(v).__name__ if type(v) is object else repr(v)}"
                              for _, w, v, _ in BAD])  # an object()'s repr differs by run
@pytest.mark.parametrize("call", ["replay", "build_pipeline"])
def test_a_bad_value_is_one_line_naming_its_layer_and_field(scene_name, where, value, message,
                                                            call):
    scene = changed(scene_name, where, value)
    with pytest.raises(TextureError) as caught:
        getattr(frictex, call)(scene, TRACE) if call == "replay" else frictex.build_pipeline(scene)
    text = str(caught.value)
    assert "\n" not in text and isinstance(caught.value, frictex.InputError)
    layer = (f", layer {scene.layers[int(where[7])].name!r}" if where.startswith("layers[")
             else "")
    assert text == f"scene {scene.name!r}{layer}: {where}: {message}"


def test_every_problem_is_listed_the_first_in_the_message():
    scene = changed("grating-5mm", "layers[0].mu_low", 5.0)
    scene = dataclasses.replace(scene, layers=(dataclasses.replace(scene.layers[0],
                                                                   period_mm=0.0),))
    with pytest.raises(TextureError) as caught:
        frictex.replay(scene, TRACE)
    assert str(caught.value).endswith("(and 1 more problem)")
    assert [problem.field for problem in caught.value.problems] == ["layers[0].period_mm",
                                                                    "layers[0].mu_low"]


@pytest.mark.parametrize("layers, message", [
    ((), "layers: 0 layers; expected a tuple of 1 to 32 layers"),
    ("lines", "layers: a str; expected a tuple of 1 to 32 layers"),
    ((1.0,), "layers[0]: expected a _LayerBase, got float"),
])
def test_layers_that_are_not_layers_are_refused(layers, message):
    scene = dataclasses.replace(frictex.load_scene("grating-5mm"), layers=layers)
    with pytest.raises(TextureError, match=message.replace("[", r"\[").replace("]", r"\]")):
        frictex.build_pipeline(scene)


@pytest.mark.parametrize("name", [entry.name for entry in list_scenes()])
def test_every_bundled_scene_keeps_the_rules(name):
    scene = frictex.load_scene(name)
    assert checked_scene(scene) is scene


def test_a_good_change_runs_and_takes_effect():
    scene = changed("grating-5mm", "layers[0].mu_low", np.float64(0.7))
    mu = frictex.replay(scene, TRACE).friction.column("mu_target").to_numpy()
    assert mu.min() == pytest.approx(0.7) and mu.max() == pytest.approx(1.0)


@settings(max_examples=30, deadline=None)
@given(field=st.sampled_from(["mu_low", "mu_high", "period_mm", "duty", "offset_mm"]),
       value=st.floats(allow_nan=True, allow_infinity=True) | st.integers(-10**20, 10**20)
       | st.text(max_size=5) | st.none())
def test_any_value_either_runs_finite_or_is_a_texture_error(short_trace, field, value):
    scene = changed("grating-5mm", f"layers[0].{field}", value)
    try:
        r = frictex.replay(scene, short_trace)
    except TextureError as error:
        assert f"layers[0].{field}: " in str(error)
        return
    mu = r.friction.column("mu_target").to_numpy()
    assert np.isfinite(mu).all() and ((mu > 0) & (mu <= 1)).all()


@pytest.mark.parametrize("name, shown", [
    ("a\x1b[31m", r"layer 'a\x1b[31m': layers[0].name: holds the control character '\x1b' "),
    ("x" * 300, f"layer '{'x' * 40}...': layers[0].name: is 300 characters long; "),
])
def test_a_bad_layer_name_is_shown_escaped_and_short(name, shown):
    with pytest.raises(TextureError) as caught:
        frictex.build_pipeline(changed("grating-5mm", "layers[0].name", name))
    assert shown in str(caught.value) and str(caught.value).isprintable()
