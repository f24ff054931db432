"""Cursors read back from the pixels: a touching finger is filled, a lifted one a hollow ring
(in live frames drawn by the compositor and in the replay's headless frames)."""

import numpy as np
from PIL import Image

from frictex.app.engine.frames import FrameWriter
from frictex.app.engine.replay import run_replay
from frictex.rendering.input.trace_file import MOVE, UP, make_trace
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.overlay import CURSOR_RADIUS_MM, FINGER_RGB, BlockRecord, OverlayState
from scenes import grating_scene

WHITE = np.ones(3)


def near(pixel, rgb, tol=0.12) -> bool:
    """Whether an sRGB uint8 pixel shows ``rgb`` (0-1) within ``tol`` per channel."""
    return bool(np.all(np.abs(np.asarray(pixel) / 255.0 - np.asarray(rgb)) < tol))


def tinted(pixel, rgb) -> bool:
    """Whether an sRGB uint8 pixel is white blended with ``rgb`` (0-1) at an alpha of at
    least 0.5 (a ring in the finger's colour, maybe fading, over the white plate)."""
    p, c = np.asarray(pixel) / 255.0 - WHITE, np.asarray(rgb) - WHITE
    alpha = float(p @ c / (c @ c))
    return alpha >= 0.5 and bool(np.abs(p - alpha * c).max() < 0.08)


def ring_hits(image, centre, radius_px, rgb) -> float:
    """Share of 72 directions from ``centre`` (px) in which a pixel within 2 px of the
    circle of ``radius_px`` is tinted with ``rgb``."""
    hits = []
    for a in np.linspace(0.0, 2 * np.pi, 72, endpoint=False):
        reach = radius_px + np.arange(-2.0, 2.5, 0.5)
        cols = (centre[0] + reach * np.cos(a)).astype(int)
        rows = (centre[1] + reach * np.sin(a)).astype(int)
        hits.append(any(tinted(image[r, c], rgb) for r, c in zip(rows, cols)))
    return float(np.mean(hits))


def inside(centre, radius_px):
    """Pixels (row, col) half way to the ring above and below ``centre`` (off a trail
    along x)."""
    col = int(centre[0])
    return [(int(centre[1] + k * radius_px / 2), col) for k in (-1, 1)]


def assert_filled(image, centre, radius_px, rgb):
    assert near(image[int(centre[1]), int(centre[0])], rgb), image[int(centre[1]), int(centre[0])]
    for r, c in inside(centre, radius_px):  # the translucent disc
        assert np.abs(image[r, c] / 255.0 - WHITE).max() > 0.2, image[r, c]
    assert ring_hits(image, centre, radius_px, rgb) > 0.8


def assert_hollow(image, centre, radius_px, rgb):
    for r, c in inside(centre, radius_px):  # the scene shows through
        assert near(image[r, c], WHITE, 0.02), image[r, c]
    assert ring_hits(image, centre, radius_px, rgb) > 0.8


def rows(t, *fingers):
    """A BlockRecord of fingers given as (id, x, y, contact list) at times ``t``."""
    n = len(t)
    return BlockRecord(np.asarray(t, float), tuple(f[0] for f in fingers),
                       np.array([f[3] for f in fingers], bool),
                       np.array([np.full(n, f[1]) for f in fingers]),
                       np.array([np.full(n, f[2]) for f in fingers]),
                       np.ones((len(fingers), n)), np.zeros((len(fingers), n)))


def draw(gl, overlay, size=(400, 240)):
    scene = grating_scene(5.0, mu_low=1.0)  # a plain white plate
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    comp.draw(FrameView(overlay=overlay, show_scope=False))
    image = backend.read_rgb()
    vp = comp.viewport
    comp.release()
    backend.close()
    return image, vp


def test_touching_is_filled_lifted_is_a_hollow_ring(gl):
    """Finger 0 touching, finger 1 lifted a moment ago (still tracked), finger 2 gone from
    the tracks while its last sample touched, finger 3 lifted longer ago than the trail."""
    ov = OverlayState(trail_s=1.0)
    ov.add(rows([0.0, 0.02], (0, 20.0, 20.0, [1, 1]), (1, 50.0, 20.0, [1, 1]),
                (2, 80.0, 20.0, [1, 1]), (3, 20.0, 45.0, [1, 1])))
    ov.add(rows([1.5, 1.6], (0, 20.0, 20.0, [1, 1]), (3, 20.0, 45.0, [0, 0])))
    ov.add(rows([2.0, 2.1], (0, 20.0, 20.0, [1, 1]), (1, 50.0, 20.0, [1, 0]),
                (2, 80.0, 20.0, [1, 1]), (3, 20.0, 45.0, [0, 0])))
    ov.add(rows([2.12, 2.14], (0, 20.0, 20.0, [1, 1]), (1, 50.0, 20.0, [0, 0]),
                (3, 20.0, 45.0, [0, 0])))
    image, vp = draw(gl, ov)
    radius = CURSOR_RADIUS_MM * min(vp.px_per_mm)
    assert_filled(image, vp.to_px(20.0, 20.0), radius, FINGER_RGB[0])
    assert_hollow(image, vp.to_px(50.0, 20.0), radius, FINGER_RGB[1])
    assert_hollow(image, vp.to_px(80.0, 20.0), radius, FINGER_RGB[2])
    x3, y3 = (int(v) for v in vp.to_px(20.0, 45.0))  # lifted 1.5 s ago: not drawn
    patch = image[y3 - int(radius) - 3:y3 + int(radius) + 4, x3 - int(radius) - 3:x3 + int(radius) + 4]
    assert (patch == 255).all()
    assert [f[0] for f in ov.current()] == [0]


def test_headless_frames_draw_a_lifted_finger_hollow(tmp_path):
    """A replay's frames: finger 0 slides and lifts at 0.5 s while finger 1 rests; before
    the lift finger 0's cursor is filled, 0.1 s after it a hollow ring where it lifted."""
    t = np.arange(0.0, 1.0, 0.001)
    swipe = t <= 0.5
    x0 = 20.0 + 40.0 * t[swipe]  # at y = 35 mm, clear of the status lines
    events = np.full(swipe.sum(), MOVE, np.int8)
    events[-1] = UP
    times = np.concatenate((t[swipe], t))
    order = np.argsort(times, kind="stable")
    trace = make_trace(times[order],
                       np.concatenate((np.zeros(swipe.sum(), int), np.ones(t.size, int)))[order],
                       np.concatenate((x0, np.full(t.size, 80.0)))[order],
                       np.concatenate((np.full(swipe.sum(), 35.0), np.full(t.size, 45.0)))[order],
                       event=np.concatenate((events, np.full(t.size, MOVE, np.int8)))[order])
    scene = grating_scene(5.0, mu_low=1.0)
    frames = FrameWriter(tmp_path, scene, fps=20.0, size=(400, 240))
    run_replay(scene, trace, tmp_path, progress=False, frames=frames)
    vp = frames.compositor.viewport
    radius = CURSOR_RADIUS_MM * min(vp.px_per_mm)

    def frame(k):
        return np.asarray(Image.open(tmp_path / "frames" / f"frame_{k:05d}.png").convert("RGB"))

    before, after = frame(5), frame(12)  # t = 0.25 s and 0.6 s
    assert_filled(before, vp.to_px(30.0, 35.0), radius, FINGER_RGB[0])
    assert_hollow(after, vp.to_px(40.0, 35.0), radius, FINGER_RGB[0])
    for image in (before, after):
        assert_filled(image, vp.to_px(80.0, 45.0), radius, FINGER_RGB[1])


def test_a_trail_is_visible_on_a_scene_of_its_own_colour(gl):
    """Finger 0's blue trail vanished on the blue grating of two-finger-plate-seed001:
    on a field of the finger's own colour, its dark outline still shows where it ran."""
    ov = OverlayState(trail_s=1.0)
    t = np.linspace(0.0, 0.5, 51)
    x = 10.0 + 100.0 * t
    ov.add(BlockRecord(t, (0,), np.ones((1, t.size), bool), x[None], np.full((1, t.size), 30.0),
                       np.ones((1, t.size)), np.zeros((1, t.size))))
    size = (400, 240)
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, grating_scene(5.0, mu_low=1.0), size)
    backend.use()
    comp.draw(FrameView(overlay=ov, show_scope=False, field_rgba=(*FINGER_RGB[0], 1.0)))
    image, vp = backend.read_rgb(), comp.viewport
    comp.release()
    backend.close()
    field = image[5, 5] / 255.0
    assert near(image[5, 5], FINGER_RGB[0], 0.05)
    for x_mm in (20.0, 30.0, 40.0):  # along the trail, behind the cursor
        col, row = (int(v) for v in vp.to_px(x_mm, 30.0))
        across = image[row - 5:row + 6, col] / 255.0
        assert np.abs(across - field).max() > 0.25, across
        assert (np.abs(image[row - 12, col] / 255.0 - field) < 0.02).all()  # and only there
