"""AHAP import (textures.ahap): the mapping onto clips, and clear errors for bad files."""

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from textures.ahap import parse_ahap, read_ahap
from textures.errors import TextureError

RATE = 10_000.0


def _event(kind, time, duration=None, **params):
    ev = {"Time": time, "EventType": kind,
          "EventParameters": [{"ParameterID": k, "ParameterValue": v} for k, v in params.items()]}
    if duration is not None:
        ev["EventDuration"] = duration
    return {"Event": ev}


def _doc(*pattern):
    return json.dumps({"Version": 1.0, "Pattern": list(pattern)}, indent=1)


def test_events_and_curves_map_onto_a_clip():
    text = _doc(
        _event("HapticTransient", 0.0, HapticIntensity=0.6, HapticSharpness=1.0),
        _event("HapticContinuous", 0.1, 0.2, HapticIntensity=0.5, HapticSharpness=0.0,
               AttackTime=0.05, ReleaseTime=0.05),
        _event("AudioCustom", 0.0),
        {"ParameterCurve": {"ParameterID": "HapticIntensityControl", "Time": 0.1,
                            "ParameterCurveControlPoints": [{"Time": 0.0, "ParameterValue": 1.0},
                                                            {"Time": 0.2, "ParameterValue": 0.0}]}})
    clip, notes = parse_ahap(text, depth=0.4)
    assert [e.kind for e in clip.events] == ["transient", "continuous"]
    assert_allclose(clip.events[1].envelope, ((0.0, 0.0), (0.05, 1.0), (0.15, 1.0), (0.2, 0.0)))
    assert_allclose(clip.intensity_curve, ((0.1, 1.0), (0.3, 0.0)))
    assert len(notes) == 1 and "AudioCustom" in notes[0]
    mu, _ = clip.sample(RATE)
    t = np.arange(mu.size) / RATE
    # the continuous event alone (sharpness 0: no carrier), written out from the mapping
    env = np.interp(t - 0.1, [0.0, 0.05, 0.15, 0.2], [0.0, 1.0, 1.0, 0.0])
    control = np.interp(t, [0.1, 0.3], [1.0, 0.0])
    late = t > 0.01  # after the 5 ms transient
    expected = 1.0 - 0.4 * 0.5 * control * np.where((t >= 0.1) & (t <= 0.3 + 1e-12), env, 0.0)
    assert_allclose(mu[late], expected[late], atol=1e-9)
    assert mu[:50].min() == pytest.approx(1.0 - 0.4 * 0.6, abs=1e-3)  # the 5 ms tick's peak


def test_a_not_sustained_event_decays_after_its_attack():
    clip, _ = parse_ahap(_doc(_event("HapticContinuous", 0.0, 1.0, AttackTime=0.1, DecayTime=0.2,
                                     Sustained=False)), depth=0.5)
    assert_allclose(clip.events[0].envelope, ((0.0, 0.0), (0.1, 1.0), (0.3, 0.0), (1.0, 0.0)))


def test_read_ahap_from_a_file(tmp_path):
    path = tmp_path / "tick.ahap"
    path.write_text(_doc(_event("HapticTransient", 0.0)), encoding="utf-8")
    clip, _ = read_ahap(path, 0.3)
    assert clip.events[0].intensity == 1.0 and clip.depth == 0.3


@pytest.mark.parametrize("text, message", [
    ('{"Pattern": [\n  {"Event": }\n]}', r"AHAP:2: not JSON"),
    (_doc(_event("HapticTransient", 0.0, HapticIntensity=1.5)),
     r"Pattern\[0\]\.Event\.EventParameters\[0\]: HapticIntensity is 1\.5, expected 0 to 1"),
    (_doc(_event("HapticContinuous", 0.0)), r"Pattern\[0\]\.Event: missing EventDuration"),
    (_doc(_event("Rumble", 0.0)), r"EventType is \"Rumble\""),
    (json.dumps({"Version": 1}), r"Pattern: expected an array, got NoneType"),
    (_doc(_event("AudioContinuous", 0.0, 1.0)), r"Pattern: no haptic events"),
    (_doc(_event("HapticTransient", 0.0), {"ParameterCurve": {
        "ParameterID": "HapticSharpnessControl", "Time": 0.0,
        "ParameterCurveControlPoints": [{"Time": 0.5, "ParameterValue": 0.0},
                                        {"Time": 0.2, "ParameterValue": 0.0}]}}),
     r"ParameterCurveControlPoints\[1\]: Time goes back"),
    (_doc(_event("HapticTransient", float("1e9"))), r"Time is 1e\+09, expected 0 to 60"),
])
def test_bad_files_get_one_line_errors_that_say_where(text, message):
    with pytest.raises(TextureError, match=message) as info:
        parse_ahap(text, 0.5)
    assert "\n" not in str(info.value)


_json = st.recursive(st.none() | st.booleans() | st.floats(allow_nan=False) | st.integers()
                     | st.text(max_size=8),
                     lambda inner: st.lists(inner, max_size=4)
                     | st.dictionaries(st.sampled_from(["Pattern", "Event", "Time", "EventType",
                                                        "EventDuration", "EventParameters",
                                                        "ParameterID", "ParameterValue",
                                                        "ParameterCurve", "Parameter",
                                                        "ParameterCurveControlPoints",
                                                        "HapticTransient", "HapticContinuous",
                                                        "HapticIntensity", "Sustained"]),
                                       inner, max_size=4),
                     max_leaves=30)


@given(_json)
@settings(derandomize=True, max_examples=300, deadline=None)
def test_any_json_is_a_clip_or_a_texture_error(doc):
    try:
        clip, _ = parse_ahap(json.dumps(doc), 0.5)
    except TextureError:
        return
    mu, _ = clip.sample(1000.0)
    assert np.isfinite(mu).all() and (mu >= 0.5).all() and (mu <= 1.0).all()
