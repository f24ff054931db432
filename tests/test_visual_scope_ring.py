"""The scope's ring of time bins: written a few columns a frame, it holds what drawing every
visible bin at once gives, and it forgets a cleared history."""

import numpy as np

from frictex.app.measure.bench_visual import FRAME_S, RECORD_HZ, stroke_record
from frictex.rendering.visual.overlay import FINGER_RGB, OverlayState
from frictex.rendering.visual.scope_ring import ScopeRing

PLOTS = ((0.0, 300.0, 400.0, 40.0), (0.0, 371.0, 400.0, 40.0))


def visible(ring: ScopeRing, overlay: OverlayState, plots=PLOTS) -> np.ndarray:
    """The ring's columns on screen, oldest first: RGBA (height, columns)."""
    texture, _, _ = ring.update(overlay, plots, 2.5)
    width, height = texture.size
    image = np.frombuffer(texture.read(alignment=1), np.uint8).reshape(height, width, 4)
    columns = int(np.ceil(plots[0][2]))
    now_bin = int(np.floor(overlay.now_s / (overlay.scope_s / columns)))
    return image[:, np.arange(now_bin - columns + 1, now_bin + 1) % width]


def test_incremental_columns_equal_a_fresh_ring(gl):
    """3 s of history, then 90 frames of 1/60 s each (the ring wraps), then a gap longer
    than the scope: at every check the columns written a few at a time equal a new ring's."""
    overlay = OverlayState()
    overlay.add(stroke_record(0.0, 3.0))
    ring = ScopeRing(gl)
    for frame in range(90):
        overlay.add(stroke_record(overlay.now_s + 1 / RECORD_HZ, overlay.now_s + FRAME_S))
        shown = visible(ring, overlay)
        if frame % 30 == 29:
            fresh = ScopeRing(gl)
            assert np.array_equal(shown, visible(fresh, overlay))
            fresh.release()
    blue = np.round(255 * np.array(FINGER_RGB[0])).astype(np.uint8)
    assert (shown[..., :3] == blue).all(axis=2).sum() > 400  # finger 0's traces are there
    overlay.add(stroke_record(overlay.now_s + 5.0, overlay.now_s + 5.5))  # a jump ahead
    fresh = ScopeRing(gl)
    assert np.array_equal(visible(ring, overlay), visible(fresh, overlay))
    fresh.release()
    ring.release()


def test_a_cleared_history_leaves_no_trace(gl):
    overlay = OverlayState()
    overlay.add(stroke_record(0.0, 3.0))
    ring = ScopeRing(gl)
    assert visible(ring, overlay)[..., 3].any()
    overlay.clear()
    overlay.add(stroke_record(3.0, 3.01))  # 10 ms of new history, at the right edge
    shown = visible(ring, overlay)
    drawn = np.flatnonzero(shown[..., 3].any(axis=0))
    assert drawn.size and drawn.min() >= 395  # only the last 10 ms (about 1.3 columns)
    ring.release()
