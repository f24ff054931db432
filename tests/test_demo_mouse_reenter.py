"""The README's "button held = touching on the scene's drawn area": a drag off the scene
(onto the scope strip) lifts the finger, and coming back onto the scene with the button
still held touches again, a new touch (a down); it used to stay lifted until the next
press."""

from contextlib import contextmanager

from frictex.app.live.demo_loop import DemoLoop
from frictex.app.live.haptic_thread import HapticThread
from frictex.rendering.input.trace_file import DOWN, MOVE, UP
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

from test_live_demo_loop import PX_PER_MM, ScriptedWindow


@contextmanager
def grating_loop(gl, tmp_path):
    """(the demo's loop on grating-5mm in a scripted window, its haptic side: not
    started, its touch queue read by the test); both closed after."""
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene)
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene,
                    tmp_path)
    try:
        yield loop, haptic
    finally:
        loop.close()
        window.close()


def touches_of(haptic):
    """(x px, event) of finger 0's samples queued so far."""
    got = [haptic.touches.get_nowait()[0] for _ in range(haptic.touches.qsize())]
    return [(round(g[2] * PX_PER_MM, 6), g[5]) for g in got]


def test_a_held_button_back_on_the_scene_touches_again(gl, tmp_path):
    with grating_loop(gl, tmp_path) as (loop, haptic):
        view = loop.compositor.viewport
        below = view.y0 + view.height_px + 5.0  # the scope strip, under the scene
        loop.on_cursor(100.0, 240.0)
        loop.on_button(True)
        loop.on_cursor(140.0, 240.0)
        loop.on_cursor(160.0, below)
        loop.on_cursor(180.0, 240.0)
        loop.on_cursor(200.0, 240.0)
        loop.on_button(False)
        loop.flush_mouse()
        assert touches_of(haptic) == [(100.0, DOWN), (140.0, MOVE), (140.0, UP),
                                      (180.0, DOWN), (200.0, MOVE), (200.0, UP)]
        loop.on_cursor(220.0, 240.0)  # let go: moving over the scene touches nothing
        loop.flush_mouse()
        assert touches_of(haptic) == [] and not loop.touching


def test_a_press_on_the_scope_strip_touches_once_dragged_onto_the_scene(gl, tmp_path):
    with grating_loop(gl, tmp_path) as (loop, haptic):
        view = loop.compositor.viewport
        below = view.y0 + view.height_px + 5.0
        loop.on_cursor(100.0, below)
        loop.on_button(True)
        loop.flush_mouse()
        assert touches_of(haptic) == []  # no finger on the scope strip
        loop.on_cursor(120.0, 240.0)
        loop.flush_mouse()
        assert touches_of(haptic)[0] == (120.0, DOWN) and loop.touching


def test_a_touch_ended_by_the_loop_itself_stays_ended_while_held(gl, tmp_path):
    """A touch the loop ends under a held button (the experiment's interval ending:
    ``touching`` set false, the up sent) is not started again by the next moves; only a
    finger that left the scene comes back."""
    with grating_loop(gl, tmp_path) as (loop, haptic):
        loop.on_cursor(100.0, 240.0)
        loop.on_button(True)
        loop.flush_mouse()
        assert touches_of(haptic) == [(100.0, DOWN)]
        loop.touching = False  # ended under the finger
        loop.on_cursor(120.0, 240.0)
        loop.flush_mouse()
        assert touches_of(haptic) == []
