"""The demo's window loop with a window the test drives: input is handed to the haptic
side by the input thread however long a frame takes (here: forever); a batch of events
handled late keeps its order, its path and its pace; a touch screen's failure hands
the fingers to the mouse; screenshots never overwrite."""

import queue
import threading
import time

import numpy as np
import pytest

from frictex.app.live.demo_loop import DemoLoop, HapticStopped, next_screenshot, starved
from frictex.app.live.haptic_thread import HapticThread
from frictex.device.link.host import LinkStalled
from frictex.rendering.input.trace_file import DOWN, MOVE, UP
from frictex.rendering.visual.context import OffscreenBackend
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

SIZE = (800, 615)  # the default frame: the 800 x 480 px scene above the scope
PX_PER_MM = 800 / 108.0


class ScriptedWindow(OffscreenBackend):
    """An offscreen frame with the window interface for one-thread tests (no events)."""

    def __init__(self, ctx):
        super().__init__(SIZE, ctx=ctx)
        self.on_cursor = self.on_button = self.on_scroll = self.on_key = None

    def cursor_px(self):
        return (0.0, 0.0)

    def set_title(self, title):
        self.title = title


class StuckFrame(Exception):
    """Ends a frame that never finished."""


class StuckWindow(ScriptedWindow):
    """A window whose first frame never finishes (``use`` blocks until ``unstick``,
    then raises StuckFrame) while the test feeds it events from another thread:
    ``wait_events`` holds them back until ``deliver`` (so the inbox never runs dry
    mid-stroke, where a finger held still 10 ms would add a 'still' MOVE), then hands
    them over one a call."""

    def __init__(self, ctx):
        super().__init__(ctx)
        self.inbox = queue.Queue()
        self.drawing, self._unstick = threading.Event(), threading.Event()
        self._delivering = threading.Event()
        self.should_close = False

    def deliver(self):
        self._delivering.set()

    def wait_events(self, timeout_s):
        self._delivering.wait()
        try:
            kind, *args = self.inbox.get(timeout=timeout_s)
        except queue.Empty:
            return
        if kind != "wake":
            {"cursor": self.on_cursor, "button": self.on_button, "key": self.on_key}[kind](*args)

    def use(self):
        self.drawing.set()
        self._unstick.wait()
        raise StuckFrame

    def unstick(self):
        self._unstick.set()

    def make_current(self):
        """The test's GL context stays on the test's thread: nothing is drawn elsewhere."""

    release_context = make_current

    def wake(self):
        self.inbox.put(("wake",))


def wait_for(condition, what):
    deadline = time.monotonic() + 120.0  # a bound for a broken loop, not a timing
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.005)


def test_a_frame_that_never_ends_holds_up_neither_the_finger_nor_the_stop(gl, tmp_path):
    """While the render thread is stuck in a frame, the input thread still hands every
    pointer position of a stroke to the haptic side, in order, and the emergency stop
    acts; the frame's failure then comes out of run()."""
    scene = load_scene(resolve_scene("grating-5mm"))
    window = StuckWindow(gl)
    haptic = HapticThread(scene)  # not started: its queue is read here
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene, tmp_path)
    raised = []

    def run():
        try:
            loop.run()
        except StuckFrame as exc:
            raised.append(exc)

    runner = threading.Thread(target=run)
    runner.start()
    xs = [100.0 + 6 * k for k in range(50)]
    try:
        wait_for(window.drawing.is_set, "the first frame never started")
        window.inbox.put(("cursor", xs[0], 240.0))
        window.inbox.put(("button", True))
        for x in xs[1:]:
            window.inbox.put(("cursor", x, 240.0))
        window.inbox.put(("button", False))
        window.inbox.put(("key", "space", False))
        window.deliver()
        wait_for(haptic.estop.is_set, "the emergency stop waited for the frame")
        touches = [haptic.touches.get(timeout=120.0)[0] for _ in range(51)]  # one finger an item
        assert loop.frames == 0  # all that while, the first frame was not done
    finally:
        window.deliver()
        window.unstick()
        runner.join()
        loop.close()
        window.close()
    assert len(raised) == 1  # run() raised the frame's failure
    assert [q[5] for q in touches] == [DOWN] + [MOVE] * 49 + [UP]
    np.testing.assert_allclose([q[2] * PX_PER_MM for q in touches], xs + [xs[-1]], atol=1e-9)
    t = [q[0] for q in touches]
    assert t == sorted(t)


def follow_loop(gl, tmp_path, **haptic_options):
    """A demo loop on grating-5mm in follow mode (30 mm): (loop, window, haptic thread)."""
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene, **haptic_options)
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene,
                    tmp_path, follow_mm=30.0)
    return loop, window, haptic


def stroke(loop, haptic, xs_px, y_px: float = 240.0) -> list:
    """A press at ``xs_px[0]``, a drag through the others, a release, handled as one
    batch: the touch samples sent to the haptic side, in order."""
    loop.on_cursor(xs_px[0], y_px)
    loop.on_button(True)
    for x in xs_px[1:]:
        loop.on_cursor(x, y_px)
    loop.on_button(False)
    loop.flush_mouse()
    return [sample for _ in range(haptic.touches.qsize()) for sample in haptic.touches.get_nowait()]


def test_a_late_batch_is_spread_over_the_time_it_covers(gl, tmp_path):
    """Events handled together (the window was drawing) keep their order and path and
    are stamped evenly over the time since the previous batch, not all at one instant."""
    clock = [1.0]
    loop, window, haptic = follow_loop(gl, tmp_path, clock=lambda: clock[0])
    try:
        loop.flush_mouse()  # the previous batch, at haptic time 0
        clock[0] += 0.2
        got = stroke(loop, haptic, (100.0, 120.0, 140.0, 160.0))
    finally:
        loop.close()
        window.close()
    # finger 0 and its follower 30 mm to the right, at the same instants
    assert [(q[1], round(q[2] * PX_PER_MM, 6), q[5]) for q in got[::2]] == [
        (0, 100.0, DOWN), (0, 120.0, MOVE), (0, 140.0, MOVE), (0, 160.0, MOVE), (0, 160.0, UP)]
    assert [q[2] - p[2] for p, q in zip(got[::2], got[1::2])] == pytest.approx([30.0] * 5)
    assert [q[0] for q in got[1::2]] == [q[0] for q in got[::2]]
    np.testing.assert_allclose([q[0] for q in got[::2]], [0.04, 0.08, 0.12, 0.16, 0.2])


def test_the_follower_lifts_off_the_display_and_comes_back_down_on_it(gl, tmp_path):
    """Follow mode's finger 1, 30 mm right of the mouse's, past the 108 mm display's edge:
    it lifts at its last place on the display and touches again where it comes back,
    finger 0 touching throughout. It was held at the edge, feeling the edge's texture
    16.5 mm from where the spacing puts it."""
    loop, window, haptic = follow_loop(gl, tmp_path)
    try:
        # finger 0 at 67.5 mm, finger 1 at 97.5; at 94.5 and 97.2 finger 1 is off; 74.25: back
        got = stroke(loop, haptic, (500.0, 700.0, 720.0, 550.0))
    finally:
        loop.close()
        window.close()
    by_finger = {f: [(round(q[2], 6), q[5]) for q in got if q[1] == f] for f in (0, 1)}
    assert by_finger[0] == [(67.5, DOWN), (94.5, MOVE), (97.2, MOVE), (74.25, MOVE), (74.25, UP)]
    assert by_finger[1] == [(97.5, DOWN), (97.5, UP), (104.25, DOWN), (104.25, UP)]


def test_a_press_off_the_scene_touches_nothing_and_a_drag_off_it_lifts(gl, tmp_path):
    """The scope strip, a panel column or beyond the window is no place to touch: a press
    there makes no finger, and a drag that leaves the scene lifts where it last was on it
    (X goes on reporting the pointer beyond the window while the button is held)."""
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene)
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene, tmp_path)
    view = loop.compositor.viewport
    below = view.y0 + view.height_px + 5.0  # the scope strip, under the scene
    try:
        loop.on_cursor(100.0, below)
        loop.on_button(True)
        loop.on_cursor(120.0, below)
        loop.on_button(False)
        loop.flush_mouse()
        assert haptic.touches.empty()
        loop.on_cursor(100.0, 240.0)
        loop.on_button(True)
        loop.on_cursor(140.0, 240.0)
        loop.on_cursor(160.0, below)
        loop.on_cursor(-50.0, below)
        loop.flush_mouse()
        got = [haptic.touches.get_nowait()[0] for _ in range(haptic.touches.qsize())]
        assert [(round(g[2] * PX_PER_MM, 6), g[5]) for g in got] == [
            (100.0, DOWN), (140.0, MOVE), (140.0, UP)]
        assert not loop.touching
        loop.on_button(False)  # released beyond the window: nothing more
        loop.flush_mouse()
        assert haptic.touches.empty()
    finally:
        loop.close()
        window.close()


def test_force_changes_while_still_make_a_sample_and_reach_a_touch_screen(gl, tmp_path):
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene)
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene, tmp_path)
    try:
        loop.on_cursor(100.0, 240.0)
        loop.on_button(True)
        loop.flush_mouse()
        loop.flush_mouse()  # held still: reported still, where it was
        assert haptic.touches.qsize() == 2
        loop.set_force(0.9)
        loop.flush_mouse()
        assert haptic.touches.qsize() == 3
        got = [haptic.touches.get_nowait()[0] for _ in range(3)]
        assert [g[4] for g in got] == [0.5, 0.5, 0.9]
        assert got[0][2:4] == got[1][2:4] == got[2][2:4] and got[0][5] == DOWN != got[1][5]
        assert haptic.touch_force.value == 0.9  # what a touch screen's fingers press with
    finally:
        loop.close()
        window.close()


def test_a_failed_touch_screen_hands_the_fingers_to_the_mouse(gl, tmp_path):
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene)
    failures = ["read failed (No such device)"]
    haptic.input_error = lambda: failures.pop() if failures else None
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene,
                    tmp_path, touch_screen=True, input_name="evdev test", events_path=tmp_path / "e.csv")
    try:
        loop.on_cursor(100.0, 240.0)
        loop.on_button(True)  # the touch screen's emulated mouse does not add a finger
        loop.flush_mouse()
        assert haptic.touches.empty()
        loop.on_button(False)
        loop.check_input()
        assert "evdev test stopped" in loop.error and "No such device" in loop.error
        loop.on_button(True)  # now the mouse touches
        loop.flush_mouse()
        assert haptic.touches.get_nowait()[0][1] == 0
    finally:
        loop.close()
        window.close()
    assert "input-failed" in (tmp_path / "e.csv").read_text()


def test_screenshots_are_numbered_after_those_in_the_folder(tmp_path):
    for name in ("frictex-a-000.png", "frictex-a-007.png", "frictex-a-x.png", "frictex-b-020.png",
                 "frictex-a-012.txt"):
        (tmp_path / name).write_bytes(b"earlier")
    paths = []
    for _ in range(2):
        path, f = next_screenshot(tmp_path, "frictex-a")
        with f:
            f.write(b"new")
        paths.append(path.name)
    assert paths == ["frictex-a-008.png", "frictex-a-009.png"]
    assert (tmp_path / "frictex-a-007.png").read_bytes() == b"earlier"
    path, f = next_screenshot(tmp_path / "new" / "folder", "frictex-a")
    f.close()
    assert path.name == "frictex-a-000.png"


@pytest.mark.parametrize("error, raised, message", [
    (LinkStalled("sim: device took no blocks through 5 waits"), LinkStalled, "took no blocks"),
    (ZeroDivisionError("float division by zero"), HapticStopped,
     "haptic output stopped: float division by zero"),
])
def test_a_stopped_haptic_side_ends_the_loop_with_a_one_line_error(gl, tmp_path, error, raised,
                                                                     message):
    """A device that stopped taking data ends the demo as it ends a replay (LinkStalled:
    the command's one-line error, exit 1); anything else as an OSError saying so."""
    scene = load_scene(resolve_scene("grating-5mm"))
    window = StuckWindow(gl)
    window.unstick()
    haptic = HapticThread(scene)
    haptic.error = error
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene, tmp_path)
    try:
        with pytest.raises(raised, match=message):
            loop.run()
    finally:
        loop.close()
        window.close()
    assert loop.frames == 0
    assert issubclass(raised, OSError)  # frictex: error: ..., never a traceback


def test_contacts_logged_follow_the_fingers_touching_not_every_id_seen(gl, tmp_path):
    """1,000 one-touch ids through the snapshots: each down and up is logged once, and
    the loop remembers only the fingers touching."""
    from frictex.rendering.visual.overlay import BlockRecord
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene)
    loop = DemoLoop(window, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene,
                    tmp_path, events_path=tmp_path / "e.csv")

    def record(t0, fids, contact):
        n, f = 3, len(fids)
        rows = np.full((f, n), 20.0)
        return BlockRecord(t0 + np.arange(n) * 1e-3, tuple(fids), np.array(contact, bool),
                           rows, rows, np.ones((f, n)), np.zeros((f, n)))
    try:
        for fid in range(1_000):  # each touch lands in one snapshot and lifts in the next,
            loop._log_contacts(record(fid, [fid], [[False, True, True]]))
            assert loop._contact == {fid: True}
            if fid % 2:  # ... or leaves the tracks without a sample out of contact
                loop._log_contacts(record(fid + 0.5, [], np.zeros((0, 3))))
            else:
                loop._log_contacts(record(fid + 0.5, [fid], [[True, False, False]]))
            assert loop._contact == {}
    finally:
        loop.close()
        window.close()
    events = (tmp_path / "e.csv").read_text().splitlines()[1:]
    assert sum(",finger-down," in e for e in events) == 1_000
    assert sum(",finger-up," in e for e in events) == 1_000


def test_the_window_title_names_the_scene_and_follows_a_switch(gl, tmp_path):
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene)
    playlist = [resolve_scene("grating-5mm"), resolve_scene("grating-15mm")]
    loop = DemoLoop(window, haptic, playlist, 0, scene, load_scene, tmp_path)
    try:
        assert window.title == "frictex demo: grating-5mm"
        loop.select(1)
        assert window.title == "frictex demo: grating-15mm"
    finally:
        loop.close()
        window.close()


def test_n_and_b_skip_the_scenes_the_open_recording_cannot_play(gl, tmp_path, capsys):
    """With a recording (or a link) open for one plate, N and B move to the next scene
    that drives the same channels; those skipped are said once, on stderr and on
    screen, and skipped silently afterwards."""
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene, recorder=object())  # never started: only switch() runs
    names = ["grating-5mm", "two-finger-beam-seed000", "grating-15mm", "keyclick-ring"]
    loop = DemoLoop(window, haptic, [resolve_scene(n) for n in names], 0, scene, load_scene,
                    tmp_path)
    try:
        loop.step_scene(1)
        assert (loop.index, loop.scene.name) == (2, "grating-15mm")
        said = capsys.readouterr().err.splitlines()
        assert len(said) == 1 and "skipped 1 scene" in said[0]
        assert "two-finger-beam-seed000 (channels xA, xB (beam-seed000" in said[0]
        assert "opened for ch0 (plate-seed003)" in said[0] and loop.error is None
        assert loop.notice == said[0].removeprefix("frictex demo: ")  # a note, not an error
        loop.step_scene(1)  # past the ring, back to the first
        assert loop.index == 0 and "keyclick-ring (channels mode_sym" in capsys.readouterr().err
        loop.step_scene(-1)  # B: past the ring again, silently
        assert loop.index == 2 and capsys.readouterr().err == "" and loop.error is None
        assert sorted(p.stem for p in loop.unplayable) == ["keyclick-ring", "two-finger-beam-seed000"]
    finally:
        loop.close()
        window.close()


def test_when_no_other_scene_fits_n_says_so_and_stays(gl, tmp_path, capsys):
    scene = load_scene(resolve_scene("grating-5mm"))
    window = ScriptedWindow(gl)
    haptic = HapticThread(scene, recorder=object())
    playlist = [resolve_scene("grating-5mm"), resolve_scene("two-finger-beam-seed000")]
    loop = DemoLoop(window, haptic, playlist, 0, scene, load_scene, tmp_path)
    try:
        for _ in range(2):
            loop.step_scene(1)
            assert (loop.index, loop.scene.name) == (0, "grating-5mm")
            assert loop.error.startswith("no other scene of the playlist plays on the "
                                         "recording opened for ch0 (plate-seed003)")
        assert capsys.readouterr().err.count("skipped 1 scene") == 1
    finally:
        loop.close()
        window.close()


@pytest.mark.parametrize("link, said", [
    ({"state": "none"}, ""),
    ({"commanded_samples": 0, "unplayed_samples": 0, "underruns": None}, ""),
    ({"commanded_samples": 2000, "unplayed_samples": 0, "underruns": 0}, ""),
    ({"commanded_samples": 2000, "unplayed_samples": 152, "underruns": 0}, ", 7.6 % unplayed"),
    ({"commanded_samples": 2000, "unplayed_samples": 152, "underruns": 3},
     ", 7.6 % unplayed, 3 underruns"),
    ({"commanded_samples": 2000, "unplayed_samples": 0, "underruns": 1}, ", 1 underrun"),
])
def test_the_status_line_shows_what_the_device_did_not_play(link, said):
    assert starved(link) == said
