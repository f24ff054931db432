"""Tracking bounded by what a finger can do: a jump is a move beyond a finger's
acceleration, and a velocity needs samples spanning long enough to tell motion from a
re-reported position."""

import numpy as np

from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
from frictex.rendering.tracking.tracks import TrackerConfig, TrackerState, track

CFG = TrackerConfig(rate_hz=10_000.0, quantum=50)


def _tracks(t, x, n_out):
    ev = np.full(t.size, MOVE, np.int8)
    ev[0], ev[-1] = DOWN, UP
    return track(0, n_out, make_trace(t, np.zeros(t.size, int), x, np.full(t.size, 30.0), None, ev),
                 TrackerState(), CFG)


def test_a_30_mm_teleport_within_one_50_hz_sample_is_a_jump():
    # 20 mm/s, then 30 mm aside within 20 ms: 75 m/s^2, beyond any finger (the bound
    # at 50 Hz is 10 mm + 12 mm); a bound of 2 m/s times 20 ms (40 mm) took it for motion
    t = np.arange(0, 1.0, 0.02)
    x = 10 + 20 * t + np.where(t >= 0.5, 30.0, 0.0)
    block, state = _tracks(t, x, 10_000)
    assert state.jumps == 1
    after = (block.t_s > 0.5) & (block.t_s < 0.6)
    assert np.abs(block.vx[0, after]).max() < 100.0


def test_a_long_gap_is_no_jump():
    # silent for 0.5 s, then 80 mm on: a finger can get there, so the same touch
    t = np.r_[np.arange(0, 0.2, 0.02), 0.7, 0.72]
    x = np.r_[10 + 20 * np.arange(0, 0.2, 0.02), 100.0, 100.4]
    _, state = _tracks(t, x, 8_000)
    assert state.jumps == 0


def test_a_refined_report_right_after_the_down_gives_no_velocity():
    # down at 20.0 mm, the refined position 20.3 mm 0.6 ms later, then still at 50 Hz:
    # a line through the first two was 500 mm/s and the prediction ran 10 mm on
    t = np.r_[0.0, 0.0006, 0.02 * np.arange(1, 30)]
    x = np.r_[20.0, 20.3, np.full(29, 20.3)]
    block, _ = _tracks(t, x, 6_000)
    touching = block.contact[0]
    assert np.abs(block.x_pred[0, touching] - 20.3).max() < 0.5
    assert np.abs(block.vx[0, touching]).max() < 15.0


def test_a_fit_over_ten_ms_gives_the_velocity():
    # a 1 kHz screen: the velocity is known from the fit spanning 10 ms on
    t = np.arange(0, 0.1, 0.001)
    block, _ = _tracks(t, 10 + 40 * t, 1_000)
    late = block.contact[0] & (block.t_s >= 0.015)
    np.testing.assert_allclose(block.vx[0, late], 40.0, rtol=1e-9)
    assert (block.vx[0, block.t_s < 0.009] == 0.0).all()
