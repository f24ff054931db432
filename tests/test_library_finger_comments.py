"""The bundled scenes' comments on numbered ``fingers`` selectors say what the selector
does: touch order among the fingers down now, from 1 (not the trace's finger ids, which
the outputs keep), renumbered when a finger lifts."""

import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
from numpy.testing import assert_array_equal

from frictex.rendering.tracking.finger_select import finger_masks

LIBRARY = Path(__file__).resolve().parents[1] / "textures" / "library"


def selector_comments(name: str) -> dict[str, str]:
    """Selector -> its comment, continuation lines (only a comment) joined."""
    out, current = {}, None
    for line in (LIBRARY / name).read_text(encoding="utf-8").splitlines():
        m = re.match(r'fingers = "(\d+)"\s*#\s*(.*)', line)
        if m:
            current = m.group(1)
            out[current] = m.group(2)
        elif current and re.match(r"\s+#", line):
            out[current] += " " + line.split("#", 1)[1].strip()
        else:
            current = None
    return out


def test_the_beam_scene_comments_describe_touch_order():
    comments = selector_comments("two-finger-beam-seed000.toml")
    assert "touch order, from 1" in comments["1"] and "touching longest" in comments["1"]
    assert "not a trace finger id" in comments["1"]
    assert 'becomes "1" when the first lifts' in comments["2"]


def test_the_selectors_do_what_the_comments_say():
    # trace row 0 (id 0) touches down after row 1 (id 1); row 1 lifts at sample 2
    contact = np.array([[1, 1, 1], [1, 1, 0]], dtype=bool)
    fingers = SimpleNamespace(contact=contact, touch_start=np.array([[2.0] * 3, [1.0] * 3]),
                              x_pred=np.zeros((2, 3)), y_pred=np.zeros((2, 3)))
    one, two = finger_masks(["1", "2"], fingers)
    assert_array_equal(one, [[0, 0, 1], [1, 1, 0]])  # touching longest, not row 0
    assert_array_equal(two, [[1, 1, 0], [0, 0, 0]])  # the next one down, "1" once the first lifts
