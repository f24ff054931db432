"""What the live demo says about its device link: the clamps to the device's limit apart
from the pipeline's (status line, last line) with a warning at connect when the
device's limit is below the scene's; a link whose queued blocks stop moving is
reported stalled by its status, shown in a red banner and said on stderr, and its
losses, returns and stalls are rows of events.csv at their output times; a headless
demo's synthesized stroke lasts --duration."""

import csv
import json
import time

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.live.demo_loop import DemoLoop
from frictex.app.live.haptic_thread import HapticThread, Snapshot
from frictex.device.link.faults import parse_faults
from frictex.device.link.host import open_sink
from frictex.rendering.visual.overlay import BlockRecord
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from test_live_demo_loop import ScriptedWindow

GRATING = resolve_scene("grating-5mm")


def record_at(t_s: float) -> BlockRecord:
    """A block's record at output time ``t_s`` with no finger."""
    empty = np.zeros((0, 1))
    return BlockRecord(t_s=np.array([t_s]), finger_ids=(), contact=empty.astype(bool),
                       x_mm=empty, y_mm=empty, mu_target=empty, amplitude_um=empty)


def link_status(state="simulated", disconnects=0, reconnects=0, clamped=0, limit_um=4.0,
                still_s=0.0):
    return {"state": state, "disconnects": disconnects, "reconnects": reconnects,
            "clamped_samples": clamped, "queued_blocks": 64 if still_s else 0,
            "queue_still_s": still_s, "last_error": "SerialException: device unplugged",
            "frames_sent": 10, "device": {"limits_um": [limit_um]}}


@pytest.fixture
def demo(gl, tmp_path):
    scene = load_scene(GRATING)
    window = ScriptedWindow(gl)
    loop = DemoLoop(window, HapticThread(scene), [GRATING], 0, scene, load_scene, tmp_path,
                    events_path=tmp_path / "events.csv", link_name="starting")
    yield loop
    loop.close()
    window.close()


def feed(loop, t_s: float, link: dict) -> None:
    """The haptic side's snapshot of the block at ``t_s`` carrying ``link``, drawn."""
    loop.haptic.snapshots.put(Snapshot(record_at(t_s), {"clamps": 0, "link": link}))
    loop.drain()


def read_events(path):
    with open(path, newline="") as f:
        return [(float(r["t_s"]), r["event"], r["detail"]) for r in csv.DictReader(f)]


def test_clamps_to_the_device_limit_are_said_apart_with_a_warning_at_connect(demo, capsys):
    scene_limit = demo.scene.device.amplitude_limit_um
    feed(demo, 0.1, link_status(limit_um=scene_limit / 2))
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("frictex demo: warning: the device's ")
    assert f"below grating-5mm's amplitude limit of {scene_limit:.4g} um" in err
    assert demo.error is not None and "below" in demo.error  # on screen, in the banner
    feed(demo, 0.2, link_status(limit_um=scene_limit / 2, clamped=1234))
    assert capsys.readouterr().err == ""  # said once
    assert ("clamps 0 by the friction inversion and 1234 by the device's limit | "
            in demo.status_lines()[0])


def test_a_device_limit_at_the_scene_limit_is_not_warned(demo, capsys):
    feed(demo, 0.1, link_status(limit_um=demo.scene.device.amplitude_limit_um))
    assert capsys.readouterr().err == "" and demo.error is None
    assert "| clamps 0 | " in demo.status_lines()[0]


def test_a_stall_and_a_loss_are_shown_said_and_logged_at_their_output_times(demo, tmp_path,
                                                                             capsys):
    feed(demo, 1.0, link_status())
    feed(demo, 6.55, link_status("stalled", still_s=0.55))
    feed(demo, 6.60, link_status("stalled", still_s=0.60))
    assert demo.link_watch.alarm.startswith("link stalled: no queued block went out for 0.6 s")
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("frictex demo: link stalled at 6.5 s")
    feed(demo, 8.0, link_status())
    assert demo.link_watch.alarm is None
    assert capsys.readouterr().err == ("frictex demo: link moving again at 8.0 s of output, "
                                       "after 1.5 s stalled\n")
    feed(demo, 9.05, link_status("disconnected", disconnects=1))
    assert demo.link_watch.alarm.startswith("link lost (SerialException: device unplugged)")
    feed(demo, 9.5, link_status(disconnects=2, reconnects=2))  # a second loss between two
    demo.close()
    assert [(t, e) for t, e, _ in read_events(tmp_path / "events.csv") if e.startswith("link")] == [
        (6.55, "link-stalled"), (8.0, "link-moving"), (9.05, "link-lost"),
        (9.5, "link-lost"), (9.5, "link-back"), (9.5, "link-back")]


def wait_for_state(sink, stalled: bool, send) -> dict:
    """Call ``send`` (a block to the link) until the link's status says ``stalled``, or
    (``stalled`` False) no longer says it; the deadline bounds a broken link, not a
    timing."""
    deadline = time.monotonic() + 60.0
    while ((status := sink.status())["state"] == "stalled") != stalled:
        assert time.monotonic() < deadline, f"state stayed {status['state']}"
        send()
        time.sleep(0.01)
    return status


def test_the_status_says_stalled_while_the_link_thread_is_stuck_and_not_after():
    sink = open_sink("sim", 1, 10_000.0, faults=parse_faults("stall=3@0.3"))
    index = [0]

    def send():
        sink.send(index[0], np.zeros((25, 1)))
        index[0] += 25

    try:
        stuck = wait_for_state(sink, True, send)
        assert stuck["queue_still_s"] > 0.5 and stuck["queued_blocks"] > 0
        moving = wait_for_state(sink, False, lambda: None)
        assert moving["state"] in ("simulated", "disconnected")
    finally:
        sink.abort()


def test_a_headless_demo_strokes_for_its_duration(tmp_path, monkeypatch, capsys):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)
    out = tmp_path / "out"
    assert main(["demo", "grating-0.6mm", "--headless", "--haptic", "thread",
                 "--duration", "4.5", "--out", str(out)]) == 0
    assert "a synthesized stroke of 4.5 s drove the mouse" in capsys.readouterr().out
    summary = json.loads((out / "summary.json").read_text())
    assert summary["output_s"] >= 4.5 and summary["ended_by"] == "window"
