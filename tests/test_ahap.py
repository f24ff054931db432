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


def test_a_not_sustained_event_releases_over_its_last_release_time():
    """Decaying from 1 towards 0 over 2 s, the 1 s event is at 0.65 where its 0.3 s
    release begins and ramps to 0 over it (it used to drop from 0.5 to 0 at the end)."""
    clip, _ = parse_ahap(_doc(_event("HapticContinuous", 0.0, 1.0, HapticSharpness=0.0,
                                     Sustained=0, AttackTime=0.0, DecayTime=2.0,
                                     ReleaseTime=0.3)), depth=0.5)
    assert_allclose(clip.events[0].envelope, ((0.0, 1.0), (0.0, 1.0), (0.7, 0.65), (1.0, 0.0)))
    t = np.array([0.0, 0.5, 0.7, 0.8, 0.9, 0.99])
    assert_allclose(_level(clip, t), [1.0, 0.75, 0.65, 0.65 * 2 / 3, 0.65 / 3, 0.65 * 0.01 / 0.3],
                    atol=1e-9)


def test_a_decay_over_before_the_release_stays_at_0():
    clip, _ = parse_ahap(_doc(_event("HapticContinuous", 0.0, 1.0, AttackTime=0.1,
                                     DecayTime=0.2, ReleaseTime=0.3, Sustained=False)), depth=0.5)
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


def _control_by_hand(t):
    """The intensity control of the pattern in the test below, written out piece by piece:
    a Parameter of 0.5 at 0.3 s, then a curve starting at 0.6 s with points 0.2 at +0.1 s
    and 1.0 at +0.3 s."""
    if t < 0.3:
        return 1.0  # before the first control: neutral
    if t < 0.6:
        return 0.5  # the Parameter, held
    if t < 0.7:
        return 0.2  # the curve's first value, held from its Time to its first point
    if t < 0.9:
        return 0.2 + 0.8 * (t - 0.7) / 0.2
    return 1.0  # the curve's last value, held


def test_controls_take_effect_at_their_time_and_hold_to_the_next():
    """Apple's dynamic parameters: a control changes nothing before its Time, a Parameter
    holds its value, a curve interpolates between its points from its Time."""
    clip, _ = parse_ahap(_doc(_event("HapticContinuous", 0.0, 1.2, HapticSharpness=0.0,
                                     HapticIntensity=0.9),
                              _control("HapticIntensityControl", 0.6, points=[(0.1, 0.2), (0.3, 1.0)]),
                              _control("HapticIntensityControl", 0.3, 0.5)), depth=0.5)
    times = [0.0, 0.1, 0.2999, 0.3, 0.45, 0.5999, 0.6, 0.65, 0.7, 0.75, 0.8, 0.85, 0.9, 1.0, 1.19]
    assert_allclose(_level(clip, times), [0.9 * _control_by_hand(t) for t in times], atol=1e-9)


def _pattern(seed):
    """A random AHAP pattern: 1-4 haptic events within 0.5 s, 0-3 controls."""
    rng = np.random.default_rng(seed)
    items = []
    for _ in range(rng.integers(1, 5)):
        start, level, sharp = rng.uniform(0, 0.5), rng.uniform(0, 1), rng.uniform(0, 1)
        if rng.random() < 0.5:
            items.append(_event("HapticTransient", start, HapticIntensity=level,
                                HapticSharpness=sharp))
        else:
            items.append(_event("HapticContinuous", start, rng.uniform(0.01, 0.3),
                                HapticIntensity=level, HapticSharpness=sharp,
                                AttackTime=rng.uniform(0, 0.05)))
    for _ in range(rng.integers(0, 4)):
        items.append(_random_control(rng))
    return items, rng


def _random_control(rng, time=None):
    pid = str(rng.choice(["HapticIntensityControl", "HapticSharpnessControl"]))
    lo = 0.0 if pid == "HapticIntensityControl" else -1.0
    time = rng.uniform(0, 0.8) if time is None else time
    if rng.random() < 0.5:
        return _control(pid, time, rng.uniform(lo, 1.0))
    offsets = np.sort(rng.uniform(0, 0.2, rng.integers(1, 4)))
    return _control(pid, time, points=[(o, rng.uniform(lo, 1.0)) for o in offsets])


@given(st.integers(0, 2**32 - 1), st.floats(0.0, 0.8))
@settings(derandomize=True, max_examples=150, deadline=None)
def test_no_control_changes_anything_before_its_time(seed, time):
    items, rng = _pattern(seed)
    before, _ = parse_ahap(_doc(*items), 0.5)
    after, _ = parse_ahap(_doc(*items, _random_control(rng, time)), 0.5)
    mu0, _ = before.sample(RATE)
    mu1, _ = after.sample(RATE)
    k = np.arange(min(mu0.size, mu1.size))
    early = k[k / RATE < time]
    assert_allclose(mu1[early], mu0[early], rtol=0, atol=0)


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


def test_a_transient_that_ends_by_60_s_is_taken():
    clip, _ = parse_ahap(_doc(_event("HapticTransient", 59.99, HapticSharpness=1.0)), 0.5)
    assert clip.duration_s == pytest.approx(59.995, abs=1e-9)


@pytest.mark.parametrize("text, message", [
    ('{"Pattern": [\n  {"Event": }\n]}', r"AHAP:2: not JSON"),
    (_doc(_event("HapticTransient", 0.0, HapticIntensity=1.5)),
     r"Pattern\[0\]\.Event\.EventParameters\[0\]: HapticIntensity is 1\.5, expected 0 to 1"),
    (_doc(_event("HapticContinuous", 0.0)), r"Pattern\[0\]\.Event: missing EventDuration"),
    (_doc(_event("Rumble", 0.0)), r"EventType is \"Rumble\""),
    (json.dumps({"Version": 1}), r"Pattern: missing"),
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
    (_doc(*[_event("HapticContinuous", 0.0, 59.0)] * 11),
     r"^AHAP: Pattern: the events play for 649 s in total; a clip's events play for at most "
     r"600 s$"),
    (_doc(_event("HapticTransient", 0.0), _event("HapticContinuous", 59.5, 0.6)),
     r"^AHAP: Pattern\[1\]\.Event: ends at 60\.1 s; clips last at most 60 s$"),
    (_doc(_event("HapticTransient", 60.0)),  # a 17.5 ms tick at sharpness 0.5
     r"^AHAP: Pattern\[0\]\.Event: ends at 60\.0175 s; clips last at most 60 s$"),
    (_doc(_event("HapticTransient", 59.99, HapticSharpness=1.0),  # 5 ms, widened by the curve
          _control("HapticSharpnessControl", 0.0, -1.0)),
     r"^AHAP: Pattern\[0\]\.Event: ends at 60\.02 s; clips last at most 60 s$"),
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
