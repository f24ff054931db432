"""The plate's |W| panel has a column of its own beside the scene (issue 15): it never
covers the scene or a finger, and its labels sit in rows of their own, off the map."""

import numpy as np
import pytest

from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.device_panels import DevicePanels, default_frame_size
from frictex.rendering.visual.modal_view import modal_envelope
from frictex.rendering.visual.overlay import OverlayState, record_from_output
from frictex.rendering.visual.viewport import default_frame_size as display_frame_size
from test_visual_devices import run_pipeline
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene


def _overlaps(a, b):
    ax, ay, aw, ah = a
    bx, by, bw, bh = b
    return ax < bx + bw and bx < ax + aw and ay < by + bh and by < ay + ah


@pytest.fixture(scope="module")
def plate():
    scene = load_scene(resolve_scene("two-finger-plate-seed001"))
    pipe, out = run_pipeline(scene, [(30.0, 40.0), (125.0, 20.0)])  # one finger under the old inset
    overlay = OverlayState()
    overlay.add(record_from_output(out, stride=10))
    env = modal_envelope(scene, pipe.actuation).at(overlay.commands, overlay.current())
    return scene, overlay, env


def _draw(gl, scene, view, size):
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    comp.draw(view)
    rgb = backend.read_rgb()
    vp = comp.viewport
    panel = comp.panels.envelope_rect("plate")
    heat = comp.panels.heat_map_rect(panel)
    row = comp.panels.row_px
    comp.release()
    backend.close()
    return rgb, vp, panel, heat, row


def test_the_default_frame_holds_the_plate_at_its_size_beside_its_panel(plate):
    scene, *_ = plate
    w, h = display_frame_size(scene.display)  # 640 x 718: at least 640 wide
    column = DevicePanels.column_px(scene, (w, h))
    assert default_frame_size(scene) == (560 + column, h)
    beam = load_scene(resolve_scene("two-finger-beam-seed000"))
    assert DevicePanels.column_px(beam, (1400, 480)) == 0
    assert default_frame_size(beam) == display_frame_size(beam.display)


@pytest.mark.parametrize("size, scope", [(None, True), (None, False), ((640, 718), True),
                                         ((1024, 600), True)])
def test_the_panel_never_covers_the_scene_and_its_labels_are_off_the_map(gl, plate, size, scope):
    """The scene's pixels are the same with the panel drawn as without it (the layout
    does not depend on the panel being drawn: the column is the scene's device's); the
    panel lies beside the scene, the map between a title row and a bottom row."""
    scene, overlay, env = plate
    size = size or default_frame_size(scene)
    with_panel, vp, panel, heat, row = _draw(gl, scene, FrameView(
        overlay=overlay, show_scope=scope, envelope=env, envelope_scale_um=env.peak_um), size)
    without, vp2, *_ = _draw(gl, scene, FrameView(overlay=overlay, show_scope=scope), size)
    assert vp == vp2
    scene_rect = (vp.x0, vp.y0, vp.width_px, vp.height_px)
    assert not _overlaps(panel, scene_rect)
    assert panel[0] + panel[2] <= size[0] and panel[2] >= 100  # a map one can read
    rows = slice(vp.y0, vp.y0 + vp.height_px)
    cols = slice(vp.x0, vp.x0 + vp.width_px)
    np.testing.assert_array_equal(with_panel[rows, cols], without[rows, cols])
    x, y, w, h = panel
    hx, hy, hw, hh = heat
    assert x <= hx and hx + hw <= x + w  # the map inside the panel ...
    assert hy >= y + row and hy + hh <= y + h - row + 1e-9  # ... clear of its label rows
    if size == default_frame_size(scene):
        assert (vp.width_px, vp.height_px) == (560, 560)  # the plate at its own pixel size


@pytest.mark.parametrize("frame", [(1200, 700), (500, 700), (300, 200), (41, 90)])
@pytest.mark.parametrize("side_px", [0, 180, 400, 10_000])
@pytest.mark.parametrize("scope", [True, False])
def test_the_layout_returns_the_column_beside_the_scene_and_above_the_strip(frame, side_px, scope):
    """frame_layout's column (the device panel's, ``envelope_rect`` reads its left edge):
    at the right of the frame, ``side_px`` wide but at most half the frame, above the
    scope strip, and the scene fitted left of it."""
    from frictex.rendering.visual.viewport import frame_layout
    scene = load_scene(resolve_scene("two-finger-plate-seed001"))
    w, h = frame
    vp, strip, column = frame_layout(scene.display, w, h, scope, side_px)
    x, y, cw, ch = column
    assert (x + cw, y, cw) == (w, 0.0, min(side_px, w // 2))
    assert ch == (strip[1] if scope else h)
    assert vp.x0 + vp.width_px <= x + 1e-9


def test_a_press_touches_the_scene_only_on_its_drawn_area():
    """A press in the scope strip (y ~75 mm on a 64.8 mm display), in the |W| panel's
    column or beyond the window is not on the scene; its edges are."""
    from frictex.rendering.visual.viewport import frame_layout
    display = load_scene(resolve_scene("two-finger-plate-seed001")).display
    vp, strip, column = frame_layout(display, 806, 718, True, side_px=240)
    assert vp.contains_px(vp.x0, vp.y0) and vp.contains_px(vp.x0 + vp.width_px, vp.y0 + vp.height_px)
    assert vp.contains_px(*vp.to_px(display.width_mm / 2, display.height_mm / 2))
    outside = [vp.to_px(display.width_mm / 2, 75.0 / 64.8 * display.height_mm),  # the strip
               (strip[0] + 10.0, strip[1] + 10.0), (column[0] + 10.0, column[1] + 50.0),
               (-5.0, 100.0), (900.0, 100.0), (100.0, -1.0), (100.0, 800.0)]
    for px in outside:
        assert not vp.contains_px(*px), px
