"""The demo's window on a screen smaller than the scene and its scope strip: the window
is cut to the screen's work area, and where the scene then fits at its display's pixels
only without the strip, the demo starts with the scope hidden (S shows it) and says so."""

import pytest

from frictex.app.live.demo_loop import DemoLoop
from frictex.app.live.haptic_thread import HapticThread
from frictex.rendering.visual.context import OffscreenBackend, fit_size
from frictex.rendering.visual.device_panels import default_frame_size
from frictex.textures.loader import load_scene
from scenes import GRATING_4MM, rising_edge_period


class CutWindow(OffscreenBackend):
    """A window asked for at ``requested`` and opened at ``size`` (the screen's work area)."""

    def __init__(self, ctx, requested, size):
        super().__init__(size, ctx=ctx)
        self.requested = requested
        self.on_cursor = self.on_button = self.on_scroll = self.on_key = None

    def cursor_px(self):
        return (0.0, 0.0)

    def set_title(self, title):
        self.title = title


def test_a_size_is_cut_to_the_room_side_by_side():
    assert fit_size((1200, 1020), (1280, 800)) == (1200, 800)
    assert fit_size((1920, 1080), (1280, 800)) == (1280, 800)
    assert fit_size((800, 615), (1280, 800)) == (800, 615)
    assert fit_size((5, 5), (0, 0)) == (1, 1)


@pytest.mark.parametrize("screen, scope, said", [
    ((1280, 800), False, "S shows the scope"),  # the scene at its pixels without the strip
    ((1000, 700), True, "the scene is drawn at"),  # not even without it: the strip stays
    (None, True, None),  # the window as asked: the scene and the strip at their sizes
])
def test_a_window_cut_to_the_screen_keeps_the_scene_at_its_pixels_where_it_can(
        gl, tmp_path, capsys, screen, scope, said):
    path = tmp_path / "lines.toml"
    path.write_text(GRATING_4MM)
    scene = load_scene(path)
    asked = default_frame_size(scene)
    assert asked[1] > 800  # the strip under the 800 px scene: taller than a 1280 x 800 screen
    window = CutWindow(gl, asked, fit_size(asked, screen or asked))
    loop = DemoLoop(window, HapticThread(scene), [path], 0, scene, load_scene, tmp_path)
    try:
        assert loop.show_scope == scope
        err = capsys.readouterr().err
        assert (said is None and err == "") or (said in err and err.count("\n") == 1)
        loop.draw()
        view = loop.compositor.viewport
        if said != "the scene is drawn at":
            assert (view.width_px, view.height_px) == (1200, 800)
            grey = window.read_rgb()[view.y0 + 400, view.x0:view.x0 + 1200].mean(axis=1)
            assert rising_edge_period(grey) == pytest.approx(40.0, abs=1.0)
        else:
            assert view.height_px < 800
    finally:
        loop.close()
        window.close()
