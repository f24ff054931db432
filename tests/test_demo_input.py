"""``frictex demo --input``: two fingers from one mouse (follow), TUIO cursors over real
UDP, and the option's bad values; checked against what the demo recorded (--record)."""

import json
import socket
import time

import numpy as np
import pytest

from app.commands.cli import main
from app.commands.demo import input_option
from test_demo import (finish, focus_window, grating_file, off_edges, read_csv,  # noqa: F401
                       start_demo, wait_event, xdo, xdotool)  # (xdotool is a fixture)
from test_tuio import frame

PX_PER_MM = 800 / 108.0  # an 800x480 window on the 108 x 64.8 mm display


def fingers(rec):
    rows = read_csv(rec / "friction.csv")
    by = {}
    for r in rows:
        by.setdefault(int(r["finger"]), []).append((float(r["t_s"]), float(r["x_mm"]),
                                                    float(r["y_mm"]), float(r["mu_target"])))
    return {f: np.array(v) for f, v in by.items()}


@pytest.mark.parametrize("haptic", ["process", "thread"])
def test_follow_mode_adds_a_second_finger_30_mm_to_the_right(xvfb_display, xdotool, tmp_path,
                                                              haptic):
    rec = tmp_path / "rec"
    proc = start_demo(xvfb_display, tmp_path, grating_file(tmp_path)[0], rec,
                      "--input", "follow", "--duration", "5", "--haptic", haptic)
    try:
        win = focus_window(xvfb_display)
        wait_event(proc, rec)
        xdo(xvfb_display, "mousemove", "--window", win, "100", "240")
        xdo(xvfb_display, "mousedown", "1")
        for x in np.linspace(100, 500, 20):
            xdo(xvfb_display, "mousemove", "--window", win, str(int(x)), "240")
            time.sleep(0.01)
        xdo(xvfb_display, "mouseup", "1")
    finally:
        finish(proc)
    summary = json.loads((rec / "summary.json").read_text())
    assert summary["haptic"] == haptic
    assert summary["cpu_steal_pct"] is None or 0.0 <= summary["cpu_steal_pct"] <= 100.0
    f = fingers(rec)
    assert sorted(f) == [0, 1]
    t0, t1 = f[0][:, 0], f[1][:, 0]
    common, i0, i1 = np.intersect1d(t0, t1, return_indices=True)
    assert common.size > 0.9 * max(t0.size, t1.size) > 500  # they touch together
    # friction.csv holds positions to 1e-4 mm
    np.testing.assert_allclose(f[1][i1, 1] - f[0][i0, 1], 30.0, atol=1.5e-4)
    np.testing.assert_allclose(f[1][i1, 2], f[0][i0, 2], atol=1.5e-4)
    assert f[0][:, 1].min() < 110 / PX_PER_MM and f[0][:, 1].max() > 490 / PX_PER_MM
    # each finger feels the grating where it is (SHO, 5 mm, first half low)
    for rows in f.values():
        low = np.mod(rows[:, 1] / 5.0, 1.0) < 0.5
        clear = off_edges(rows[:, 1])
        np.testing.assert_array_equal(rows[clear, 3], np.where(low, 0.6, 1.0)[clear])


def test_tuio_cursors_over_udp_drive_two_fingers(xvfb_display, tmp_path):
    rec = tmp_path / "rec"
    proc = start_demo(xvfb_display, tmp_path, grating_file(tmp_path)[0], rec,
                      "--input", "tuio:0", "--duration", "4")
    sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM)
    try:
        line = proc.stdout.readline()
        assert "listening for TUIO" in line, line
        port = int(line.split()[-1])
        wait_event(proc, rec)
        fseq = 1
        # session 7 swipes right along y = 0.25 of the height; session 9 holds still low
        for k in range(60):
            u = 0.1 + 0.6 * k / 59
            sock.sendto(frame(fseq, [7, 9], [(7, u, 0.25), (9, 0.8, 0.75)]), ("127.0.0.1", port))
            fseq += 1
            time.sleep(1 / 60)
        sock.sendto(frame(fseq, [9], [(9, 0.8, 0.75)]), ("127.0.0.1", port))  # 7 lifts
        time.sleep(0.2)
        sock.sendto(frame(fseq + 1, []), ("127.0.0.1", port))  # 9 lifts
    finally:
        sock.close()
        finish(proc)
    f = fingers(rec)
    assert sorted(f) == [0, 1]  # TUIO sessions 7 and 9 as fingers 0 and 1
    swipe, still = f[0], f[1]
    np.testing.assert_allclose(swipe[:, 2], 0.25 * 64.8, atol=1e-4)  # float32 on the wire
    # 0.1 to 0.7 of the width in about 1 s (64.8 mm/s; the sender's sleeps may stretch
    # it): the tracker's constant-velocity prediction (60 ms horizon) may overshoot the
    # last sample by ~4 mm, more when a loaded machine delivers the UDP frames in bursts
    x = swipe[:, 1]
    assert x.min() < 0.1 * 108.0 + 1.0 and 0.7 * 108.0 - 1.0 < x.max() < 0.7 * 108.0 + 6.0
    assert 30.0 < np.polyfit(swipe[:, 0], x, 1)[0] < 80.0
    np.testing.assert_allclose(still[:, 1:3], np.tile([0.8 * 108.0, 0.75 * 64.8], (len(still), 1)),
                               atol=1e-4)
    assert still[-1, 0] > swipe[-1, 0] + 0.1  # held after the other lifted


@pytest.mark.parametrize("text, expect", [
    ("mouse", ("mouse", None)), ("follow", ("follow", 30.0)), ("follow:-12.5", ("follow", -12.5)),
    ("tuio", ("tuio", 3333)), ("tuio:0", ("tuio", 0)),
    ("evdev:/dev/input/event5", ("evdev", "/dev/input/event5")),
])
def test_input_option_values(text, expect):
    assert input_option(text) == expect


@pytest.mark.parametrize("value, message", [
    ("pen", "expected mouse, follow"), ("follow:abc", "non-zero number of mm"),
    ("follow:0", "non-zero"), ("follow:inf", "non-zero"), ("tuio:70000", "UDP port 0 to 65535"),
    ("evdev", "evdev:PATH"), ("mouse:1", "no argument"),
])
def test_bad_input_option_is_one_line_exit_2(capsys, value, message):
    with pytest.raises(SystemExit) as exc:
        main(["demo", "--input", value, "--headless"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and message in err and "Traceback" not in err


def test_headless_refuses_live_input(capsys):
    assert main(["demo", "--input", "tuio", "--headless"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: --input tuio :3333") and err.count("\n") == 1


def test_unreadable_evdev_device_is_one_line_exit_2(tmp_path, capsys):
    """The touch source opens first: no window flashes up for a bad --input."""
    assert main(["demo", "grating-5mm", "--input", f"evdev:{tmp_path / 'no-such-device'}",
                 "--duration", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error:") and "no-such-device" in err and err.count("\n") == 1


class FakeSource:
    """A touch source as the demo sees one: samples normalised to the active area."""

    def __init__(self, batches):
        self.batches = list(batches)
        self.closed = False

    def poll(self):
        batch = self.batches.pop(0)
        if isinstance(batch, Exception):
            raise batch
        return batch

    def close(self):
        self.closed = True


def test_source_samples_reach_the_haptic_thread_in_mm_with_the_set_force(gl, tmp_path):
    """What an evdev or TUIO source hands the loop (normalised positions, source clock)
    arrives as mm of the scene's display, on the haptic clock, at the force set with the
    wheel; a source that fails is closed, shown, and the mouse takes over."""
    from app.live.demo_loop import DemoLoop
    from app.live.haptic_thread import HapticThread
    from rendering.input.evdev_decode import TouchSample
    from rendering.input.trace_file import DOWN, MOVE
    from rendering.visual.context import OffscreenBackend
    from textures.loader import load_scene
    from textures.library import resolve_scene

    scene = load_scene(resolve_scene("grating-5mm"))
    backend = OffscreenBackend((320, 200), ctx=gl)
    haptic = HapticThread(scene)
    now = time.monotonic()
    source = FakeSource([[TouchSample(now - 0.02, 3, 0.25, 0.5, 0.5, DOWN),
                          TouchSample(now - 0.01, 3, 0.5, 0.5, 0.5, MOVE)],
                         OSError("read failed (No such device)")])
    loop = DemoLoop(backend, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene,
                    tmp_path, source=source, input_name="evdev test")
    try:
        loop.set_force(0.8)
        assert loop.poll_source() == 2
        queued = [haptic.touches.get_nowait() for _ in range(2)]
        assert [q[1:] for q in queued] == [(3, 27.0, 32.4, 0.8, DOWN), (3, 54.0, 32.4, 0.8, MOVE)]
        assert queued[0][0] <= queued[1][0] <= haptic.now()
        loop.hover_px = (100.0, 100.0)
        loop.on_button(True)  # the touch screen's emulated mouse does not add a finger
        loop.flush_mouse()
        assert haptic.touches.empty()
        loop.on_button(False)
        assert loop.poll_source() == 0 and source.closed and loop.source is None
        assert "evdev test stopped" in loop.error and "No such device" in loop.error
        loop.on_button(True)  # now the mouse touches
        loop.flush_mouse()
        assert haptic.touches.get_nowait()[1] == 0
    finally:
        loop.close()
        backend.close()


def test_mouse_events_of_a_frame_make_one_sample_per_finger(gl, tmp_path):
    """A late frame handles a burst of pointer events at once: they must become one sample
    per finger, stamped when the frame handles them, not a finger flying through several
    positions within microseconds (which the tracker would take for a huge velocity)."""
    from app.live.demo_loop import DemoLoop
    from app.live.haptic_thread import HapticThread
    from rendering.input.trace_file import DOWN, MOVE, UP
    from rendering.visual.context import OffscreenBackend
    from textures.library import resolve_scene
    from textures.loader import load_scene

    scene = load_scene(resolve_scene("grating-5mm"))
    backend = OffscreenBackend((800, 480), ctx=gl)
    haptic = HapticThread(scene)
    loop = DemoLoop(backend, haptic, [resolve_scene("grating-5mm")], 0, scene, load_scene,
                    tmp_path, follow_mm=30.0, input_name="follow 30 mm")

    def frame():
        loop.flush_mouse()
        out = []
        while not haptic.touches.empty():
            out.append(haptic.touches.get_nowait())
        return [(f, round(x, 6), e) for _, f, x, _, _, e in out], out

    try:
        loop.on_cursor(100.0, 240.0)
        loop.on_button(True)
        for x in (120.0, 140.0, 160.0):
            loop.on_cursor(x, 240.0)
        mm = 160.0 / PX_PER_MM
        assert frame()[0] == [(0, round(mm, 6), DOWN), (1, round(mm + 30, 6), DOWN)]
        assert frame()[0] == []  # nothing moved
        loop.set_force(0.9)
        samples, raw = frame()
        assert samples == [(0, round(mm, 6), MOVE), (1, round(mm + 30, 6), MOVE)]
        assert raw[0][4] == raw[1][4] == 0.9 and raw[0][0] == raw[1][0]  # one stamp
        loop.on_button(False)
        loop.on_button(True)
        loop.on_button(False)
        assert [e for _, _, e in frame()[0]] == [UP, UP, DOWN, DOWN, UP, UP]
    finally:
        loop.close()
        backend.close()
