"""The demo on the glass: fullscreen at the scene's display pixels (or under a touch
screen) the scene fills the screen, mm -> px per axis, so that what is drawn lies where
it is felt; the scope starts hidden and S draws it over the scene without moving it; the
status lines are hidden. In a window the scene keeps its aspect-preserving fit, and a
touch screen there is said not to coincide with the drawing."""

import pytest

from frictex.app.live.demo_loop import DemoLoop
from frictex.app.live.haptic_thread import HapticThread
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.viewport import frame_layout, on_glass
from frictex.textures.loader import load_scene
from frictex.textures.model import Display
from scenes import rising_edge_period

#: seed 003's 800 x 480 px screen as 120 x 64.8 mm: pixels 0.150 x 0.135 mm
NON_SQUARE = Display(width_mm=120.0, height_mm=64.8, width_px=800, height_px=480)
SQUARE = Display(width_mm=108.0, height_mm=64.8, width_px=800, height_px=480)


def grating(angle_deg: float, width_mm: float = 120.0) -> str:
    """A 5 mm black/white grating on an 800 x 480 px display ``width_mm`` x 64.8 mm."""
    return f"""format = 1
name = "g5"
[display]
width_mm = {width_mm}
height_mm = 64.8
width_px = 800
height_px = 480

[[layer]]
type = "grating"
period_mm = 5.0
angle_deg = {angle_deg}
duty = 0.5
mu_low = 0.6
"""


class Screen(OffscreenBackend):
    """A frame of ``size`` px standing for a fullscreen window (or, ``fullscreen`` false,
    an ordinary one)."""

    def __init__(self, ctx, size, fullscreen=True):
        super().__init__(size, ctx=ctx)
        self.fullscreen = fullscreen
        self.on_cursor = self.on_button = self.on_scroll = self.on_key = None

    def cursor_px(self):
        return (0.0, 0.0)

    def set_title(self, title):
        self.title = title


def test_the_glass_is_the_frame_at_its_own_pixels():
    assert on_glass(SQUARE, (800, 480), fullscreen=True, touch_screen=False)
    assert on_glass(SQUARE, (1920, 1080), fullscreen=True, touch_screen=True)
    assert not on_glass(SQUARE, (1920, 1080), fullscreen=True, touch_screen=False)
    assert not on_glass(SQUARE, (800, 480), fullscreen=False, touch_screen=True)


@pytest.mark.parametrize("scope", [False, True])
def test_on_the_glass_the_scene_fills_the_frame_per_axis_and_the_strip_lies_over_it(scope):
    view, strip, _ = frame_layout(NON_SQUARE, 800, 480, scope, side_px=120, glass=True)
    assert (view.x0, view.y0, view.width_px, view.height_px) == (0, 0, 800, 480)
    assert view.px_per_mm == pytest.approx((800 / 120.0, 480 / 64.8))
    assert (strip is not None) == scope
    x, y = view.to_px(10.0, 60.0)  # drawn at the felt mm: 0.150 x 0.135 mm pixels
    assert (float(x), float(y)) == pytest.approx((66.667, 444.444), abs=1e-3)
    assert tuple(map(float, view.to_mm(x, y))) == pytest.approx((10.0, 60.0))


def test_in_a_window_the_scene_keeps_its_aspect():
    view, _, _ = frame_layout(NON_SQUARE, 800, 615, scope=True)
    sx, sy = view.px_per_mm
    assert sx == pytest.approx(sy, rel=0.01)
    assert view.width_px < 800 or view.height_px < 480


@pytest.mark.parametrize("angle, axis, period_px", [
    (0.0, 1, 5.0 * 800 / 120.0),  # vertical lines: along x at 6.67 px/mm
    (90.0, 0, 5.0 * 480 / 64.8),  # horizontal lines: along y at 7.41 px/mm, not 6.67
])
def test_a_fullscreen_demo_draws_the_grating_at_the_panels_pixels(
        gl, tmp_path, capsys, angle, axis, period_px):
    path = tmp_path / "g5.toml"
    path.write_text(grating(angle))
    scene = load_scene(path)
    screen = Screen(gl, (800, 480))
    loop = DemoLoop(screen, HapticThread(scene), [path], 0, scene, load_scene, tmp_path)
    try:
        assert not loop.show_scope
        assert "as it lies on the glass" in capsys.readouterr().err
        loop.draw()
        grey = screen.read_rgb().mean(axis=2)
        profile = grey[240, :] if axis == 1 else grey[:, 400]
        assert rising_edge_period(profile) == pytest.approx(period_px, abs=0.5)
        assert loop.compositor.text_boxes == []  # no status lines over the scene
        before = loop.compositor.viewport
        loop.handle_key("s", False)
        loop.draw()
        assert loop.compositor.viewport == before  # the scope drawn over it, not moving it
        assert loop.compositor.scope_rect()[3] > 0
        assert loop._mm((400.0, 240.0)) == pytest.approx((60.0, 32.4))
    finally:
        loop.close()
        screen.close()


def test_a_touch_screen_on_a_window_is_said_not_to_coincide(gl, tmp_path, capsys):
    path = tmp_path / "g5.toml"
    path.write_text(grating(0.0, width_mm=108.0))
    scene = load_scene(path)
    screen = Screen(gl, (800, 615), fullscreen=False)
    loop = DemoLoop(screen, HapticThread(scene), [path], 0, scene, load_scene, tmp_path,
                    touch_screen=True, input_name="evdev")
    try:
        err = capsys.readouterr().err
        assert "the drawing and the touches do not coincide" in err
        assert err.count("\n") == 1
        assert loop.show_scope
    finally:
        loop.close()
        screen.close()
