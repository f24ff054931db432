"""A replay warns when a sliding finger's touch samples come further apart than the
tracker predicts a finger (its horizon): there SHT and the hybrid play no texture."""

import numpy as np
import pytest

from frictex.app.engine.replay import SlideSteps, run_replay
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.rendering.tracking.tracks import TrackerConfig
from scenes import grating_scene


def _swipe(rate_hz: float):
    """The reproduction's trace: a 2 mm/s swipe over 6 s at ``rate_hz``."""
    return sample(make_motion("swipe", speed_mm_s=2.0, duration_s=6.0), rate_hz)


def _sparse(summary: dict) -> list[str]:
    return [w for w in summary["warnings"] if "sliding finger" in w]


@pytest.mark.parametrize("render", ["hybrid", "sht"])
def test_sparse_trace_warned_with_the_trackers_constants(tmp_path, render):
    summary = run_replay(grating_scene(5.0, render=render), _swipe(5.0), tmp_path,
                         progress=False)
    (said,) = _sparse(summary)
    config = TrackerConfig()
    assert "0.2 s apart (median)" in said
    assert f"{config.predict_horizon_s:g} s prediction horizon" in said
    assert f"velocity window {config.velocity_window_s:g} s" in said
    assert f"layer 'lines' ({render}) plays no texture at all" in said
    assert f"more than {config.max_gap_s:g} s apart" in said
    assert "--renderer sho" in said


def test_between_horizon_and_gap_no_texture_after_the_horizon(tmp_path):
    (said,) = _sparse(run_replay(grating_scene(5.0, render="hybrid"), _swipe(12.0), tmp_path,
                                 progress=False))
    assert "0.0833 s apart" in said
    assert "no texture from 0.06 s after each sample until the next" in said


@pytest.mark.parametrize("scene", ["height-bump", "slider-clips"])
def test_a_sparse_trace_over_layers_of_their_own_renderers_is_not_warned(tmp_path, scene):
    """A height or clip layer's mode names its layer renderer's kind, no renderer: asking
    whether it plays from velocity refused the whole replay ('unknown renderer')."""
    from frictex.app.api import load_scene
    summary = run_replay(load_scene(scene), _swipe(5.0), tmp_path, progress=False)
    assert _sparse(summary) == []


@pytest.mark.parametrize("rate_hz, render", [(20.0, "hybrid"), (5.0, "sho")])
def test_dense_trace_or_sho_not_warned(tmp_path, rate_hz, render):
    summary = run_replay(grating_scene(5.0, render=render), _swipe(rate_hz), tmp_path,
                         progress=False)
    assert _sparse(summary) == []


def test_slide_steps_across_chunks_skip_rests_and_lifts():
    """Only moves to another position within a touch count, a chunk's first sample
    paired with the previous chunk's last of the same finger."""
    t = np.array([0.0, 0.2, 0.4, 0.5, 0.6, 5.0, 5.3])
    x = np.array([1.0, 2.0, 2.0, 3.0, 3.0, 9.0, 9.5])
    event = np.array([DOWN, MOVE, MOVE, MOVE, UP, DOWN, MOVE], dtype=np.int8)
    trace = make_trace(t, np.zeros(7, dtype=np.int64), x, np.zeros(7), np.full(7, 0.5), event)
    steps = SlideSteps()
    for lo, hi in ((0, 3), (3, 7)):
        steps.add(trace.slice(lo, hi))
    assert np.sort(np.concatenate(steps.steps)) == pytest.approx([0.1, 0.2, 0.3])
    assert steps.median_s() == pytest.approx(0.2)
