"""AHAP import (textures.ahap): the mapping onto clips, and clear errors for bad files."""

import json

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from frictex.textures.ahap import parse_ahap, read_ahap
from frictex.textures.errors import TextureError

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


def _level(clip, t_s):
    """The clip's level sum at times t_s (s), from its mu'."""
    mu, _ = clip.sample(RATE)
    return (1.0 - mu[np.round(np.asarray(t_s) * RATE).astype(int)]) / clip.depth


def _control(pid, time, value=None, points=None):
    if points is None:
        return {"Parameter": {"ParameterID": pid, "Time": time, "ParameterValue": value}}
    return {"ParameterCurve": {"ParameterID": pid, "Time": time, "ParameterCurveControlPoints": [
        {"Time": t, "ParameterValue": v} for t, v in points]}}


def test_a_parameter_holds_until_the_next_of_its_control():
    clip, _ = parse_ahap(_doc(_event("HapticContinuous", 0.0, 2.0, HapticSharpness=0.0),
                              _control("HapticIntensityControl", 0.0, 0.2),
                              _control("HapticIntensityControl", 1.0, 1.0)), depth=0.5)
    assert_allclose(_level(clip, [0.0, 0.5, 0.999, 1.0, 1.5]), [0.2, 0.2, 0.2, 1.0, 1.0])


def test_a_later_curve_takes_over_from_an_earlier_one():
    """A ramp from 1 to 0 over 1 s, taken over at 0.5 s by a Parameter of 0.8, then by a
    curve from 0.4 up to 0.6 over 0.2 s starting at 1.2 s."""
    clip, _ = parse_ahap(_doc(_event("HapticContinuous", 0.0, 2.0, HapticSharpness=0.0),
                              _control("HapticIntensityControl", 1.2, points=[(0.0, 0.4), (0.2, 0.6)]),
                              _control("HapticIntensityControl", 0.0, points=[(0.0, 1.0), (1.0, 0.0)]),
                              _control("HapticIntensityControl", 0.5, 0.8)), depth=0.5)
    assert_allclose(_level(clip, [0.0, 0.25, 0.4999, 0.5, 1.0, 1.1999, 1.2, 1.3, 1.9]),
                    [1.0, 0.75, 0.5001, 0.8, 0.8, 0.8, 0.4, 0.5, 0.6], atol=1e-9)


def test_a_transient_plays_its_whole_pulse_at_the_sharpness_the_curve_gives_it():
    """Sharpness 1 (5 ms) lowered by the control to 0: a whole 30 ms pulse, back at 1."""
    clip, _ = parse_ahap(_doc(_event("HapticTransient", 0.0, HapticSharpness=1.0),
                              _control("HapticSharpnessControl", 0.0, -1.0)), depth=0.5)
    mu, _ = clip.sample(RATE)
    t = np.arange(mu.size) / RATE
    assert clip.duration_s == pytest.approx(0.030) and mu.size == 301 and mu[-1] == 1.0
    assert_allclose(mu, 1.0 - 0.5 * np.sin(np.pi * t / 0.030) ** 2, atol=1e-12)


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
    ('{"Pattern": [{"Event": {"Time": 1' + "0" * 400 + ', "EventType": "HapticTransient"}}]}',
     r"Pattern\[0\]\.Event: Time is 1000000000.*, expected a number from 0 to 60"),
    ('{"Pattern": [{"Event": {"Time": 1' + "0" * 5000 + ', "EventType": "HapticTransient"}}]}',
     r"AHAP: not JSON that can be read \(Exceeds the limit"),
    (_doc({"Event": {"Time": 0.0, "EventType": "HapticTransient", "EventParameters": [
        {"ParameterID": ["HapticIntensity"], "ParameterValue": 1.0}]}}),
     r"EventParameters\[0\]: ParameterID is \[\"HapticIntensity\"\], expected a string"),
    (_doc(_event("HapticTransient", 0.0), {"Parameter": {"ParameterID": {"a": 1}, "Time": 0.0}}),
     r"Pattern\[1\]\.Parameter: ParameterID is \{\"a\": 1\}, expected a string"),
    (_doc(_event("HapticTransient", 0.0), _control("HapticSharpnessControl", 0.0, points=[])),
     r"ParameterCurveControlPoints: no control points"),
    (_doc(*[_event("HapticContinuous", 0.0, 59.0)] * 11), r"Pattern: the events play for 649 s"),
    ('{"Pattern": [], "Pattern": [' + json.dumps(_event("HapticTransient", 0.5)) + ']}',
     r'AHAP: key "Pattern" appears twice in one object; expected distinct keys'),
    ('{"Pattern": [{"Event": {"Time": 0.0, "Time": 0.5, "EventType": "HapticTransient"}}]}',
     r'key "Time" appears twice'),
    ('{"Pattern": [{"Event": {"Time": NaN, "EventType": "HapticTransient"}}]}',
     r"AHAP: NaN is not a JSON number"),
    ('{"Pattern": [{"Event": {"Time": -Infinity, "EventType": "HapticTransient"}}]}',
     r"AHAP: -Infinity is not a JSON number"),
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
    assert np.isfinite(mu).all() and (mu >= 0.5).all() and (mu <= 1.0).all() and mu[-1] == 1.0
