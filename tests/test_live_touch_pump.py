"""Touch screens feed the haptic side from a thread of their own (``app.live.touch_pump``):
positions to mm of the scene shown now, stamps to the haptic clock, the force the wheel
set; a failing source is closed and reported once; in the haptic child process, TUIO
cursors reach the pipeline with no window involved at all."""

import queue
import socket
import time

import numpy as np
import pytest

from frictex.app.live.haptic_process import HapticConfig, HapticProcess
from frictex.app.live.haptic_thread import HapticThread
from frictex.app.live.inputs import INPUTS, TuioSpec, open_source
from frictex.device.errors import InputError
from frictex.app.live.touch_pump import TouchPump
from frictex.rendering.input.evdev_decode import TouchSample
from frictex.rendering.input.trace_file import DOWN, MOVE, UP
from test_tuio import frame
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

WAIT_S = 120.0  # bound of waits on real threads and processes: only a broken one reaches it


class ScriptedSource:
    """A source handing out one scripted batch per poll (an exception is raised)."""

    def __init__(self, batches):
        self.batches = list(batches)
        self.closed = 0

    def wait(self, timeout_s):
        return bool(self.batches)

    def poll(self):
        if not self.batches:
            return []
        batch = self.batches.pop(0)
        if isinstance(batch, Exception):
            raise batch
        return batch

    def close(self):
        self.closed += 1


def test_samples_reach_the_haptic_queue_in_mm_on_its_clock_with_the_set_force():
    scene = load_scene(resolve_scene("grating-5mm"))  # 108 x 64.8 mm
    now = [50.0]
    haptic = HapticThread(scene, clock=lambda: now[0])  # output clock: 0 at 50 s
    now[0] = 52.0  # haptic.now() = 2.0 s
    source_clock = lambda: 1000.0  # the sources' clock reads 1000 s at that instant
    haptic.touch_force.value = 0.8
    pump = TouchPump(ScriptedSource([]), haptic, lambda: scene.display,
                     lambda: haptic.touch_force.value, clock=source_clock)
    n = pump.forward([TouchSample(999.98, 3, 0.25, 0.5, 0.5, DOWN),
                      TouchSample(999.99, 3, 0.5, 0.5, 0.5, MOVE)])
    queued = [haptic.touches.get_nowait()[0] for _ in range(2)]  # one sample an item
    assert n == 2 and pump.samples == 2 and haptic.touches.empty()
    np.testing.assert_allclose([q[0] for q in queued], [1.98, 1.99], atol=1e-9)
    assert [q[1:] for q in queued] == [(3, 27.0, 32.4, 0.8, DOWN), (3, 54.0, 32.4, 0.8, MOVE)]


def test_positions_follow_the_scene_shown_now():
    plate = load_scene(resolve_scene("grating-5mm"))
    beam = load_scene(resolve_scene("two-finger-beam-seed000"))  # 350 x 6 mm
    shown = [plate]
    haptic = HapticThread(plate)
    pump = TouchPump(ScriptedSource([]), haptic, lambda: shown[0].display, lambda: 0.5)
    pump.forward([TouchSample(0.0, 0, 0.5, 0.5, 0.5, DOWN)])
    shown[0] = beam
    pump.forward([TouchSample(0.0, 0, 0.5, 0.5, 0.5, UP)])
    got = [haptic.touches.get_nowait()[0][2:4] for _ in range(2)]
    assert got == [(54.0, 32.4), (175.0, 3.0)]


def test_a_failing_source_is_closed_and_reported_once():
    scene = load_scene(resolve_scene("grating-5mm"))
    haptic = HapticThread(scene)
    source = ScriptedSource([[TouchSample(time.monotonic(), 0, 0.5, 0.5, 0.5, DOWN)],
                             OSError("read failed (No such device)")])
    haptic.pump = TouchPump(source, haptic, lambda: scene.display, lambda: 0.5)
    haptic.pump.start()
    haptic.pump.join(WAIT_S)
    assert not haptic.pump.is_alive() and source.closed == 1
    assert haptic.touches.get_nowait()[0][1:4] == (0, 54.0, 32.4)
    assert haptic.input_error() == "read failed (No such device)"
    assert haptic.input_error() is None  # once
    haptic.pump.stop()
    assert source.closed == 1


def test_fingers_down_when_the_source_fails_are_lifted_where_they_were():
    """An evdev screen that sent ABS_MT_SLOT 99 (or was unplugged) after two contacts went
    down: the pump stopped with the error and never lifted them, and the haptic side
    rendered both where they were until the demo ended."""
    scene = load_scene(resolve_scene("grating-5mm"))  # 108 x 64.8 mm
    haptic = HapticThread(scene)
    t0 = time.monotonic()
    source = ScriptedSource([[TouchSample(t0, 0, 0.5, 0.5, 0.5, DOWN),
                              TouchSample(t0, 1, 0.2, 0.25, 0.5, DOWN),
                              TouchSample(t0, 2, 0.9, 0.9, 0.5, DOWN)],
                             [TouchSample(t0 + 0.01, 1, 0.25, 0.25, 0.5, MOVE),
                              TouchSample(t0 + 0.01, 2, 0.9, 0.9, 0.5, UP)],
                             ValueError("ABS_MT_SLOT 99 is out of range (expected 0..63)")])
    haptic.pump = TouchPump(source, haptic, lambda: scene.display, lambda: 0.5)
    haptic.pump.start()
    haptic.pump.join(WAIT_S)
    assert not haptic.pump.is_alive() and source.closed == 1
    queued = []
    while not haptic.touches.empty():
        queued.append(haptic.touches.get_nowait()[0][1:])
    lifted = {q[0]: q[1:3] for q in queued if q[4] == UP}
    assert lifted == {2: (97.2, 58.32), 0: (54.0, 32.4), 1: (27.0, 16.2)}
    assert queued[-2:] == [(0, 54.0, 32.4, 0.5, UP), (1, 27.0, 16.2, 0.5, UP)]
    assert haptic.input_error() == "ABS_MT_SLOT 99 is out of range (expected 0..63)"


def test_a_pump_never_started_closes_its_source_when_stopped():
    source = ScriptedSource([])
    TouchPump(source, None, None, None).stop()
    assert source.closed == 1


def test_open_source_refuses_what_is_not_a_touch_screen(tmp_path):
    fifo = tmp_path / "events"
    import os
    os.mkfifo(fifo)
    with pytest.raises(ValueError, match=r"evdev:.*events is not a multi-touch device"):
        open_source("evdev", str(fifo))
    with pytest.raises(ValueError, match="read by the window, not opened"):
        open_source("mouse", None)
    with pytest.raises(ValueError, match="unknown touch input 'pen'; expected one of mouse, "
                                         "follow, tuio, evdev"):
        open_source("pen", None)
    assert [n for n in INPUTS.names() if INPUTS.get(n).touch_screen] == ["tuio", "evdev"]


def free_udp_port() -> int:
    with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as s:
        s.bind(("127.0.0.1", 0))
        return s.getsockname()[1]


def test_tuio_reaches_the_child_pipeline_with_no_window(tmp_path):
    """The child listens for TUIO itself: the window's side (this test) only reads
    snapshots; the finger appears at the sent position, and lifts."""
    path = resolve_scene("grating-5mm")
    port = free_udp_port()
    haptic = HapticProcess(load_scene(path), HapticConfig(path, 10_000.0, 50, "sho", None, None,
                                                          ("tuio", TuioSpec("127.0.0.1", port))))
    snaps = []

    def until(done):
        deadline = time.monotonic() + WAIT_S
        while not done():
            assert time.monotonic() < deadline and haptic.error is None
            try:
                snaps.append(haptic.snapshots.get(timeout=0.05))
            except queue.Empty:
                pass

    def contact():
        return [r for r in (s.record for s in snaps) if r.contact.size and r.contact[0].any()]

    try:
        with socket.socket(socket.AF_INET, socket.SOCK_DGRAM) as tx:
            tx.sendto(frame(1, [5], [(5, 0.25, 0.5)]), ("127.0.0.1", port))
            until(lambda: len(contact()) >= 3)
            touched = contact()
            tx.sendto(frame(2, []), ("127.0.0.1", port))
            until(lambda: snaps[-1].record.contact.size == 0
                  or not snaps[-1].record.contact[0, -1])
    finally:
        haptic.stop()
    x = np.concatenate([r.x_mm[0][r.contact[0]] for r in touched])
    y = np.concatenate([r.y_mm[0][r.contact[0]] for r in touched])
    np.testing.assert_allclose(x, 27.0, atol=1e-4)  # float32 on the wire
    np.testing.assert_allclose(y, 32.4, atol=1e-4)
    assert haptic.error is None and haptic.stats.dropped_touches == 0
    counts = haptic.stats.input  # the child's touch screen's counts came back with its stats
    assert counts["datagrams"] == 2 and counts["refused"] == counts["dropped"] == 0
    assert counts["samples"] == 2 and counts["sender"].startswith("127.0.0.1:")


def test_a_touch_screen_that_cannot_open_fails_the_child_start(tmp_path):
    path = resolve_scene("grating-5mm")
    with pytest.raises(InputError, match="no-such-device: no such device"):  # as the child raised it
        HapticProcess(load_scene(path), HapticConfig(path, 10_000.0, 50, None, None, None,
                                                     ("evdev", str(tmp_path / "no-such-device"))))
