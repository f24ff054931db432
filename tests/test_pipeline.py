"""The assembled pipeline: seed 003's grating claims, block-split invariance, composition."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose

from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.tracking.tracks import apply_index
from scenes import disc_scene, grating_scene


def _run(scene, trace, mode=None, rate=10_000.0, splits=None):
    p = build_pipeline(scene, rate_hz=rate, render_override=mode, t0_s=float(trace.t_s[0]))
    applied = apply_index(trace.t_s, p.tracker_config)
    total = int(applied[-1] // p.block_size) + 1
    bounds = [0, *(s for s in splits or [] if s < total), total]
    state, outs = p.initial_state(), []
    for lo, hi in zip(bounds[:-1], bounds[1:]):
        if hi <= lo:
            continue
        a, b = np.searchsorted(applied, [lo * p.block_size, hi * p.block_size])
        chunk = trace.slice(a, b) if b > a else None
        out, state = p.process(lo, chunk, state, n_blocks=hi - lo)
        outs.append(out)
    return outs


def _cat(outs, name):
    return np.concatenate([getattr(o, name) for o in outs], axis=-1 if name != "commands_um" else 0)


def test_5mm_grating_steps_land_within_0_1_mm_of_the_true_edges():
    """Issue check: a 1 kHz swipe over the 5 mm grating; each friction step, mapped to
    the true finger position at that instant, lies within 0.1 mm of a grating edge. A
    sample straddling an edge plays both sides in proportion, so a step is one change of
    mu' or two on consecutive samples (``rendering.layers.band_limit``)."""
    motion = make_motion("swipe", speed_mm_s=40.0, duration_s=2.0, x0_mm=10.0)
    trace = sample(motion, 1000.0)
    out = _run(grating_scene(5.0), trace, "sho-predicted")[0]
    mu, t = out.mu_target[0], out.t_s
    changes = np.flatnonzero(np.diff(mu) != 0) + 1
    steps = changes[np.diff(changes, prepend=-2) > 1]
    steps = steps[(t[steps] > 0.05) & (t[steps] < 1.95)]
    x_true, _ = motion.position(t[steps])
    edge_error = np.abs(x_true - 2.5 * np.round(x_true / 2.5))
    assert steps.size == 31  # 80 mm less the ends at 2.5 mm per edge
    assert edge_error.max() < 0.1


def _spectrum(mu, t, lo, hi):
    seg = (t > lo) & (t < hi)
    x = mu[seg] - mu[seg].mean()
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    freq = np.fft.rfftfreq(x.size, t[1] - t[0])
    band = (freq > 5.0) & (freq < 1000.0)
    return freq[band], spec[band]


def test_plain_sho_cannot_render_0_6mm_at_50hz_but_sht_can():
    """Seed 003 section 4.4.1: at 40 mm/s the 0.6 mm grating is a 66.7 Hz signal, above
    the 25 Hz a 50 Hz screen can render. Plain SHO aliases it to |66.7 - 50| = 16.7 Hz;
    SHT puts its spectral peak at 66.7 Hz."""
    motion = make_motion("swipe", speed_mm_s=40.0, duration_s=2.0, x0_mm=10.0)
    trace = sample(motion, 50.0)
    f0 = 40.0 / 0.6
    peaks = {}
    for mode in ("sho-held", "sht"):
        out = _run(grating_scene(0.6), trace, mode)[0]
        freq, spec = _spectrum(out.mu_target[0], out.t_s, 0.3, 1.9)
        near = np.abs(freq - f0) < 2.0
        peaks[mode] = (freq[np.argmax(spec)], spec[near].max() / spec.max())
    assert abs(peaks["sht"][0] - f0) < 1.0 and peaks["sht"][1] == 1.0
    assert abs(peaks["sho-held"][0] - abs(f0 - 50.0)) < 1.0  # the alias
    assert peaks["sho-held"][1] < 0.5  # no peak of its own at the grating frequency


@settings(max_examples=15, derandomize=True, deadline=None)
@given(splits=st.lists(st.integers(1, 200), max_size=5, unique=True).map(sorted),
       mode=st.sampled_from(["sho-held", "sho-predicted", "sht"]))
def test_any_split_into_blocks_equals_one_call(splits, mode):
    motion = make_motion("human", speed_mm_s=60.0, duration_s=1.0, seed=4)
    trace = sample(motion, 120.0, noise_mm=0.05, seed=4)
    whole = _run(grating_scene(0.6 if mode == "sht" else 5.0), trace, mode)
    parts = _run(grating_scene(0.6 if mode == "sht" else 5.0), trace, mode, splits=splits)
    assert_allclose(_cat(parts, "mu_target"), _cat(whole, "mu_target"), atol=1e-9)
    assert_allclose(_cat(parts, "commands_um"), _cat(whole, "commands_um"), atol=1e-9)
    assert_allclose(_cat(parts, "t_s"), _cat(whole, "t_s"), rtol=0, atol=0)


def test_disc_object_rendered_only_inside():
    motion = make_motion("swipe", speed_mm_s=50.0, duration_s=1.6, x0_mm=14.0)  # y = 32.4
    trace = sample(motion, 240.0)
    out = _run(disc_scene(), trace, "sho-predicted")[0]
    x_true, _ = motion.position(out.t_s)
    inside = np.abs(x_true - 54.0) < 15.0 - 0.3
    outside = np.abs(x_true - 54.0) > 15.0 + 0.3
    contact = out.contact[0]
    assert_allclose(out.mu_target[0, inside & contact], 0.7)
    assert_allclose(out.mu_target[0, outside & contact], 1.0)
    assert np.all(out.commands_um[outside & contact] == 0.0)


def test_no_contact_means_no_vibration_and_output_is_finite():
    motion = make_motion("human", speed_mm_s=80.0, duration_s=1.0, seed=2)
    trace = sample(motion, 50.0)
    out = _run(grating_scene(5.0), trace, "sht")[0]
    assert np.all(np.isfinite(out.commands_um))
    assert np.all(out.commands_um[~out.contact.any(axis=0)] == 0.0)
    assert np.all((out.commands_um >= 0) & (out.commands_um <= 2.5))


def test_unknown_renderer_is_a_clear_error():
    with pytest.raises(ValueError, match="unknown renderer 'shx'"):
        build_pipeline(grating_scene(5.0), render_override="shx")
