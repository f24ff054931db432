"""N past scenes the open link or recording cannot play: the note saying so is a note,
not an error. It shows in the grey info banner for NOTICE_S seconds of the loop's clock
(it stayed in the red error banner until the next scene switch, over the scene and a
finger drawn under it) and names only the outputs open ("the link and recording" was
said with no recording)."""

import pickle

import pytest

from frictex.app.live.demo_loop import NOTICE_S, DemoLoop
from frictex.app.live.haptic_thread import ChannelMismatch, HapticThread
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

from test_live_demo_loop import ScriptedWindow



class FramedWindow(ScriptedWindow):
    """A scripted window whose frames are shown (nothing to swap offscreen)."""

    def swap(self):
        pass


NAMES = ["grating-5mm", "two-finger-beam-seed000", "grating-15mm"]


def frames_of(loop):
    """The FrameViews the loop draws, in order (the compositor still draws them)."""
    views, draw = [], loop.compositor.draw

    def keep(view):
        views.append(view)
        draw(view)

    loop.compositor.draw = keep
    return views


@pytest.fixture
def loop(gl, tmp_path):
    scene = load_scene(resolve_scene(NAMES[0]))
    window = FramedWindow(gl)
    haptic = HapticThread(scene, sink=object())  # never started: only switch() runs
    loop = DemoLoop(window, haptic, [resolve_scene(n) for n in NAMES], 0, scene, load_scene,
                    tmp_path)
    yield loop
    loop.close()
    window.close()


def test_the_skip_note_is_an_info_banner_for_a_few_seconds(loop):
    views = frames_of(loop)
    loop.step_scene(1)
    assert loop.scene.name == "grating-15mm" and loop.error is None
    start = 100.0
    for now in (start, start + NOTICE_S - 0.1):
        loop.frame(now)
        assert views[-1].banner_kind == "info"
        assert views[-1].banner.startswith("skipped 1 scene the link, opened for ch0")
    loop.frame(start + NOTICE_S)
    assert views[-1].banner is None


def test_an_error_banner_wins_over_the_note(loop):
    views = frames_of(loop)
    loop.step_scene(1)
    loop.error = "reload failed"
    loop.frame(0.0)
    assert (views[-1].banner, views[-1].banner_kind) == ("reload failed", "error")


@pytest.mark.parametrize("sink, recorder, held", [
    (object(), None, "the link was opened"),
    (None, object(), "the recording was opened"),
    (object(), object(), "the link and the recording were opened"),
])
def test_a_refusal_names_only_the_outputs_open(sink, recorder, held):
    plate = load_scene(resolve_scene("grating-5mm"))
    beam = load_scene(resolve_scene("two-finger-beam-seed000"))
    thread = HapticThread(plate, sink=sink, recorder=recorder)
    with pytest.raises(ChannelMismatch) as refused:
        thread.switch(beam)
    assert f"; {held} for ch0 (plate-seed003)" in str(refused.value)
    again = pickle.loads(pickle.dumps(refused.value))  # as the haptic process sends it
    assert str(again) == str(refused.value) and again.held == refused.value.held
