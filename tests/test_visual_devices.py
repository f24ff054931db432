"""Device panels of the visual layer: |W| of the modal devices (seeds 000, 001) from the
commands sent, force arrows and the key-click button's state (seeds 002, 004).

References come from the haptic pipeline itself (achieved amplitude under each finger,
key-click states) and from the scene's geometry, never from stored images."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.rendering.layers.keyclick import CLICKED, IDLE, ON
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.input.trace_file import make_trace
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.device_panels import FORCE_ARROW_MM, force_scale_n
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.modal_view import ModalEnvelope, heat_rgb, modal_envelope
from frictex.rendering.visual.overlay import FINGER_RGB, OverlayState, record_from_output
from frictex.rendering.visual.scene_image import from_srgb8, to_srgb8
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene


def run_pipeline(scene, fingers_xy, force_n=0.5, seconds=0.2):
    """Fingers held still at ``fingers_xy`` (mm) from t = 0; the last block's output."""
    t = np.arange(0.0, seconds, 0.01)
    n = t.size
    trace = make_trace(np.repeat(t, len(fingers_xy)), np.tile(np.arange(len(fingers_xy)), n),
                       np.tile([x for x, _ in fingers_xy], n), np.tile([y for _, y in fingers_xy], n),
                       np.broadcast_to(force_n, (n, len(fingers_xy))).ravel())
    pipe = build_pipeline(scene, block_size=50)
    blocks = int(seconds * pipe.rate_hz / pipe.block_size)
    out, _ = pipe.process(0, trace, pipe.initial_state(), n_blocks=blocks)
    return pipe, out


@pytest.mark.parametrize("name, fingers", [
    ("two-finger-beam-seed000", [(100.0, 3.0), (230.0, 3.0)]),
    ("two-finger-plate-seed001", [(30.0, 40.0), (95.0, 110.0)]),
])
def test_envelope_under_the_fingers_is_the_achieved_amplitude(name, fingers):
    """|W| recovered from the commands alone (W_M = A^+ c, then |Phi W_M|) equals the
    amplitude the actuation reports under each finger, which it computed from its own
    modal solution: the two paths meet only if the panel inverts the commands right."""
    scene = load_scene(resolve_scene(name))
    pipe, out = run_pipeline(scene, fingers)
    env_view = modal_envelope(scene, pipe.actuation)
    assert isinstance(env_view, ModalEnvelope)
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    env = env_view.at(overlay.commands, overlay.current())
    achieved = out.amplitude_um[:, -1]
    assert achieved.min() > 0.05  # the fingers do feel a vibration
    assert [fid for fid, *_ in env.fingers] == [0, 1]
    assert_allclose([a for *_, a in env.fingers], achieved, rtol=1e-9)
    # the grid, sampled once per scene, agrees with the fingers' values next to them
    if env.kind == "beam":
        near = [np.argmin(np.abs(env.x_mm - x)) for x, _ in fingers]
        step = env.x_mm[1] - env.x_mm[0]
        slope = np.abs(np.gradient(env.amplitude_um, step))
        for k, (i, (x, _)) in enumerate(zip(near, fingers)):
            assert abs(env.amplitude_um[i] - achieved[k]) <= slope[i] * abs(env.x_mm[i] - x) * 1.5 + 1e-6
        assert env.amplitude_um.shape == env.x_mm.shape
    else:
        assert env.amplitude_um.shape == (env.y_mm.size, env.x_mm.size)
    assert np.isfinite(env.amplitude_um).all() and env.peak_um >= achieved.max()


def test_no_envelope_for_a_single_mode_plate():
    scene = load_scene(resolve_scene("grating-5mm"))
    assert modal_envelope(scene, build_pipeline(scene).actuation) is None


def render(gl, scene, view, size=(800, 480)):
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    comp.draw(view)
    rgb = backend.read_rgb()
    row = comp.panels.row_px
    rect = comp.panels.envelope_rect(view.envelope.kind) if view.envelope is not None else None
    if rect is not None and view.envelope.kind == "plate":
        rect = comp.panels.heat_map_rect(rect)
    vp = comp.viewport
    comp.release()
    backend.close()
    return rgb, vp, rect, row


def test_beam_envelope_curve_is_drawn_at_its_amplitude(gl):
    """The filled curve's height in each pixel column of the strip against |W| at the
    column's x: within 2 px over the whole beam."""
    scene = load_scene(resolve_scene("two-finger-beam-seed000"))
    pipe, out = run_pipeline(scene, [(100.0, 3.0), (230.0, 3.0)])
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    env = modal_envelope(scene, pipe.actuation).at(overlay.commands, overlay.current())
    scale = 1.0
    rgb, vp, (x, y, w, h), row = render(gl, scene, FrameView(overlay=overlay, show_scope=True,
                                                        envelope=env, envelope_scale_um=scale),
                                   size=(1400, 480))
    lin = from_srgb8(rgb)
    top, base = y + row, y + h - 2.0
    orange = (lin[..., 0] > 0.3) & (lin[..., 2] < 0.1)  # the fill and its line
    cols = np.arange(int(x) + 30, int(x + w) - 30, 7)
    for _, fx, _, _ in env.fingers:  # leave out the finger markers
        cols = cols[np.abs(cols + 0.5 - vp.to_px(fx, 0)[0]) > 12]
    rows = np.arange(rgb.shape[0])
    inside = (rows >= top - 3) & (rows <= base + 1)
    drawn = np.array([base - rows[inside & orange[:, c]].min() for c in cols])
    x_mm = vp.to_mm(cols + 0.5, 0)[0]
    expect = (base - top) * np.clip(np.interp(x_mm, env.x_mm, env.amplitude_um) / scale, 0, 1)
    assert np.abs(drawn - expect).max() < 2.5


def test_plate_heat_map_is_bright_where_the_plate_vibrates(gl):
    scene = load_scene(resolve_scene("two-finger-plate-seed001"))
    pipe, out = run_pipeline(scene, [(30.0, 40.0), (95.0, 110.0)])
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    env = modal_envelope(scene, pipe.actuation).at(overlay.commands, overlay.current())
    rgb, vp, (ax, ay, aw, ah), _ = render(gl, scene, FrameView(
        overlay=overlay, show_scope=False, envelope=env, envelope_scale_um=env.peak_um),
        size=(640, 560))
    # the expected heat map: |W| / scale through the colour ramp, bilinearly filtered as GL
    # does (texel centres at (i + 0.5) / n), at the centre of every pixel of the map
    expected = to_srgb8(heat_rgb(env.amplitude_um / env.peak_um)).astype(np.float64)
    ny, nx = env.amplitude_um.shape
    cols = np.arange(int(np.ceil(ax)) + 1, int(ax + aw) - 1)
    rows = np.arange(int(np.ceil(ay)) + 1, int(ay + ah) - 1)
    fx = np.clip((cols + 0.5 - ax) / aw * nx - 0.5, 0, nx - 1)
    fy = np.clip((rows + 0.5 - ay) / ah * ny - 0.5, 0, ny - 1)
    x0, y0 = np.minimum(fx.astype(int), nx - 2), np.minimum(fy.astype(int), ny - 2)
    tx, ty = (fx - x0)[None, :, None], (fy - y0)[:, None, None]
    e = expected
    want = ((e[y0][:, x0] * (1 - tx) + e[y0][:, x0 + 1] * tx) * (1 - ty)
            + (e[y0 + 1][:, x0] * (1 - tx) + e[y0 + 1][:, x0 + 1] * tx) * ty)
    got = rgb[rows][:, cols].astype(np.float64)
    far = np.ones(got.shape[:2], bool)  # leave out the finger markers
    for _, fxm, fym, _ in env.fingers:
        mx, my = ax + aw * fxm / 140.0, ay + ah * fym / 140.0
        far &= np.hypot(cols[None, :] + 0.5 - mx, rows[:, None] + 0.5 - my) > 9
    assert far.mean() > 0.9
    assert np.abs(got - want)[far].max() <= 4.0  # 8-bit filtering and rounding


def test_force_arrow_points_along_the_achieved_force_at_scale(gl):
    scene = load_scene(resolve_scene("keyclick-ring"))
    pipe, out = run_pipeline(scene, [(70.0, 15.0)], force_n=0.6)  # pressed: wave on, push +x
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    achieved, _ = overlay.forces[0]
    assert achieved[0] > 0.05 and abs(achieved[1]) < 1e-9  # seed 004: pushed along +x
    rgb, vp, *_ = render(gl, scene, FrameView(overlay=overlay, show_scope=False))
    cx, cy = vp.to_px(70.0, 15.0)
    lin = from_srgb8(rgb[int(cy)])
    blue = np.flatnonzero((np.abs(lin - FINGER_RGB[0] ** np.array(2.2)) < 0.15).all(axis=1))
    tip = blue.max() + 1.0
    length = FORCE_ARROW_MM * min(vp.px_per_mm) * achieved[0] / force_scale_n(scene)
    assert abs(tip - (cx + length)) < 2.0


@pytest.mark.parametrize("force_n, state", [(0.3, IDLE), (0.6, ON), (0.9, CLICKED)])
def test_button_state_follows_the_normal_force_and_is_framed_in_its_colour(gl, force_n, state):
    """Seed 004 Fig. 5 thresholds of the scene: press 0.5 N, click 0.8 N."""
    scene = load_scene(resolve_scene("keyclick-ring"))
    _, out = run_pipeline(scene, [(70.0, 15.0)], force_n=force_n)
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    assert overlay.button == state
    rgb, vp, *_ = render(gl, scene, FrameView(overlay=overlay, show_scope=False))
    g = scene.layers[0].geometry
    x0, _ = vp.to_px(g.x_mm, g.y_mm)
    _, y1 = vp.to_px(g.x_mm, g.y_mm + g.height_mm)
    edge = from_srgb8(rgb[int(y1) - 2:int(y1) + 2, int(x0) + 20])  # the frame's bottom side
    expect = {IDLE: (0.45, 0.45, 0.45), ON: (0.95, 0.6, 0.05), CLICKED: (0.1, 0.75, 0.25)}[state]
    assert np.abs(edge - np.array(expect) ** 2.2).sum(axis=1).min() < 0.1


def test_labels_that_change_every_frame_survive_the_text_cache(gl):
    """The |W| labels under the fingers change with every frame; a demo ran 1000s of
    frames. Once more texts were made than the cache keeps, the cache released textures
    made earlier in the same frame and still to be drawn (a crash in the demo). Now the
    frame with the 200th distinct label draws the same as a fresh compositor's."""
    from dataclasses import replace
    scene = load_scene(resolve_scene("two-finger-beam-seed000"))
    pipe, out = run_pipeline(scene, [(100.0, 3.0), (230.0, 3.0)])
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    env = modal_envelope(scene, pipe.actuation).at(overlay.commands, overlay.current())
    size = (1400, 480)
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    for k in range(200):
        fingers = tuple((fid, x, y, 0.01 * k + 0.001 * fid) for fid, x, y, _ in env.fingers)
        view = FrameView(overlay=overlay, status=(f"frame {k}",), envelope=replace(env, fingers=fingers),
                         envelope_scale_um=1.0)
        comp.draw(view)
    long_run = backend.read_rgb()
    comp.release()
    fresh = Compositor(gl, scene, size)
    fresh.draw(view)
    assert np.array_equal(backend.read_rgb(), long_run)
    fresh.release()
    backend.close()
