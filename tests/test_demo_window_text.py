"""What the demo's window says: a status box that leaves a small window's scene visible,
the work area named as it is, and one line (no glfw warnings) for a display that cannot
be opened, naming the display the environment gives."""

import os
import subprocess
import sys

import pytest

from frictex.app.live.demo_loop import DemoLoop
from frictex.app.live.haptic_thread import HapticThread
from frictex.rendering.visual.compositor import STATUS_SHARE, status_rows
from frictex.rendering.visual.context import display_names, fit_size
from frictex.rendering.visual.device_panels import default_frame_size
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from scenes import GRATING_4MM
from test_demo_window_fit import CutWindow

GRATING = resolve_scene("grating-5mm")


class SizedWindow(CutWindow):
    """A window opened at the ``size`` asked for."""

    def __init__(self, ctx, size):
        super().__init__(ctx, size, size)


def status_box(loop) -> tuple[int, int]:
    """The status box's height and the scene's drawn height (px) in ``loop``'s frame."""
    loop.draw()
    box = loop.compositor.status_bottom - 4.0
    return box, loop.compositor.viewport.height_px


@pytest.mark.parametrize("size, all_kept", [((300, 200), False), ((800, 615), True)])
def test_the_status_box_leaves_most_of_a_small_window_to_the_scene(gl, tmp_path, size,
                                                                   all_kept):
    """At 300 x 200 px (the scene drawn 100 px high above the scope) the three status
    lines wrapped to six rows covered the scene; now the rows beyond a third of the
    scene's height (the keys' help first) are left out."""
    scene = load_scene(GRATING)
    window = SizedWindow(gl, size)
    loop = DemoLoop(window, HapticThread(scene), [GRATING], 0, scene, load_scene, tmp_path)
    try:
        box, scene_px = status_box(loop)
        font_px = loop.compositor.font_px
        wrapped = status_rows(loop.status_lines(), font_px, size[0], 10_000)
        rows = status_rows(loop.status_lines(), font_px, size[0], scene_px)
    finally:
        loop.close()
        window.close()
    assert rows == wrapped[:len(rows)] and (rows == wrapped) == all_kept
    assert box == len(rows) * round(font_px * 1.25) + 8  # the box drawn holds these rows
    assert box <= STATUS_SHARE * scene_px or len(rows) == 1


def test_a_cut_window_names_the_work_area_as_it_is(gl, tmp_path, capsys):
    """A 1200 x 940 px window on a 1280 x 800 screen said 'the window is 1200 x 800 px,
    the screen's work area'; the work area is 1280 x 800."""
    path = tmp_path / "lines.toml"
    path.write_text(GRATING_4MM)
    scene = load_scene(path)
    asked = default_frame_size(scene)
    window = CutWindow(gl, asked, fit_size(asked, (1280, 800)))
    window.work_area = (1280, 800)
    DemoLoop(window, HapticThread(scene), [path], 0, scene, load_scene, tmp_path).close()
    err = capsys.readouterr().err
    assert (f"the window is cut to 1200 x 800 px ({asked[0]} x {asked[1]} asked) to fit, with "
            "its title bar and borders, the screen's work area (1280 x 800 px)") in err


@pytest.mark.parametrize("env, said", [
    ({"DISPLAY": ":77"}, "display ':77'"),
    ({"DISPLAY": "", "WAYLAND_DISPLAY": "wayland-9"}, "Wayland display 'wayland-9'"),
    ({"DISPLAY": ":77", "WAYLAND_DISPLAY": "wayland-9"},
     "Wayland display 'wayland-9' or display ':77'"),
])
def test_the_display_is_named_as_the_environment_gives_it(monkeypatch, env, said):
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    for name, value in env.items():
        monkeypatch.setenv(name, value)
    assert display_names() == said


def test_a_display_that_cannot_be_opened_is_one_line(tmp_path):
    """glfw's own warnings ('GLFWError: (65550) X11: Failed to open display :77', with
    the line of Python that warned) came twice before the demo's line."""
    pytest.importorskip("glfw")
    env = {k: v for k, v in os.environ.items() if k != "WAYLAND_DISPLAY"}
    display = next(f":{n}" for n in range(77, 300)  # no server there (nor its lock)
                   if not os.path.exists(f"/tmp/.X11-unix/X{n}") and not os.path.exists(f"/tmp/.X{n}-lock"))
    env["DISPLAY"] = display
    done = subprocess.run([sys.executable, "-m", "frictex", "demo", "grating-5mm", "--haptic",
                           "thread", "--duration", "1"], cwd=tmp_path, env=env,
                          capture_output=True, text=True, timeout=300)
    assert done.returncode != 0 and done.stderr.count("\n") == 1, done.stderr and "GLFWError" not in done.stderr
    assert f"glfw cannot initialise on display '{display}'" in done.stderr
