"""An edge clip fires on a strict crossing of its line only: a finger that reaches the
line exactly and goes back fired twice coming from the normal's far side and never from
the other (the sample on the line counted as the normal's side)."""

import numpy as np
import pytest

from frictex.rendering.layers.clips import TRIGGER_CODES, FingerPrev, _fired
from test_clips import TICK, _layer

LINE_X = 90.0  # a vertical line, normal +x: the normal's side is x > 90


def _fired_at(xs, split=None):
    """The samples where one finger touching along ``xs`` (mm, y fixed) fires the edge
    trigger, the path given in two blocks at ``split`` if one, the finger's last
    sample carried between them as the renderer carries it."""
    layer = _layer(TICK, "edge", x_mm=LINE_X, y_mm=30.0)
    x = np.array([xs], dtype=np.float64)
    side = layer.side(x, np.full_like(x, 30.0))
    ones = np.ones_like(x, dtype=bool)
    blocks = [slice(0, len(xs))] if split is None else [slice(0, split), slice(split, len(xs))]
    prev, fired = np.array([FingerPrev(1, 0, 1, 0)], dtype=np.int64), []
    for b in blocks:
        got, prev = _fired(TRIGGER_CODES["edge"], ones[:, b], np.zeros_like(x[:, b], np.int64),
                           ones[:, b], side[:, b], prev)
        fired.extend(np.flatnonzero(got) + b.start)
    return fired


def test_the_side_is_0_exactly_on_the_line():
    layer = _layer(TICK, "edge", x_mm=LINE_X, y_mm=30.0)
    assert layer.side(np.array([89.5, 90.0, 90.5]), 30.0).tolist() == [-1, 0, 1]


@pytest.mark.parametrize("xs", [[89.0, 89.5, 90.0, 89.5, 89.0], [91.0, 90.5, 90.0, 90.5, 91.0],
                                [90.0, 90.0, 90.5, 91.0], [90.0, 89.5, 89.0]],
                         ids=["from below", "from above", "from on the line up",
                              "from on the line down"])
def test_reaching_the_line_and_going_back_fires_nothing(xs):
    assert _fired_at(xs) == []


@pytest.mark.parametrize("xs", [[89.0, 89.5, 90.0, 90.5, 91.0], [91.0, 90.5, 90.0, 89.5, 89.0]],
                         ids=["up", "down"])
def test_a_crossing_through_the_line_fires_once_on_the_far_side(xs):
    assert _fired_at(xs) == [3]
    assert _fired_at(xs[:2] + [90.0, 90.0] + xs[3:]) == [4]  # lingering on the line
    assert _fired_at(xs, split=3) == [3]  # the block ends on the line


@pytest.mark.parametrize("xs", [[89.0, 91.0], [91.0, 89.0]], ids=["up", "down"])
def test_a_crossing_over_the_line_fires_on_the_first_sample_past_it(xs):
    assert _fired_at(xs) == [1]


@pytest.mark.parametrize("angle_deg", [0.0, 90.0, 180.0, 270.0, 30.0, 135.0])
def test_the_line_is_the_line_at_every_angle(angle_deg):
    """At 90 and 180 degrees cos and sin round to 6e-17 and 1.2e-16, not 0: a finger on
    the line was on the normal's side and fired twice reaching it and going back."""
    layer = _layer(TICK, "edge", x_mm=LINE_X, y_mm=30.0, angle_deg=angle_deg)
    a = np.radians(angle_deg)
    normal, along = np.array([np.cos(a), np.sin(a)]), np.array([-np.sin(a), np.cos(a)])
    # off the line by -1, -0.5, 0, -0.5, -1 mm, sliding along it
    offsets = np.array([-1.0, -0.5, 0.0, -0.5, -1.0])
    points = (np.array([LINE_X, 30.0]) + offsets[:, None] * normal
              + np.arange(5)[:, None] * 0.3 * along)
    sides = layer.side(points[:, 0], points[:, 1]).tolist()
    assert sides == [-1, -1, 0, -1, -1], sides
    x, y = points[None, :, 0], points[None, :, 1]
    ones = np.ones_like(x, dtype=bool)
    got, _ = _fired(TRIGGER_CODES["edge"], ones, np.zeros_like(x, np.int64), ones,
                    layer.side(x, y), np.array([FingerPrev(1, 0, 1, 0)], dtype=np.int64))
    assert not got.any()
