"""What a demo leaves behind: a screenshot that fails is said and the demo goes on; the
force, scope and outlines keys are in events.csv, whose rows are in time order; the
touches taken are a trace file that replays what was felt (the force included); clamps
count only the samples played; headless frames go to --out and the tables to --record."""

import csv
import json
import re
from dataclasses import replace
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.live.demo_loop import DemoLoop, file_stem
from frictex.app.live.haptic_setup import open_haptic
from frictex.app.live.haptic_thread import HapticThread
from frictex.rendering.input.trace_file import read_trace
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from test_live_demo_loop import ScriptedWindow

GRATING = resolve_scene("grating-5mm")


@pytest.fixture
def no_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)


def read_events(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def demo_loop(gl, tmp_path, screenshots):
    scene = load_scene(GRATING)
    window = ScriptedWindow(gl)
    loop = DemoLoop(window, HapticThread(scene), [GRATING], 0, scene, load_scene, screenshots,
                    events_path=tmp_path / "events.csv")
    return loop, window


def test_a_screenshot_that_fails_is_said_and_logged_and_the_demo_goes_on(gl, tmp_path, capsys):
    taken = tmp_path / "afile"
    taken.write_text("a file where the folder would be")
    loop, window = demo_loop(gl, tmp_path, taken)
    try:
        loop.draw()
        assert loop.screenshot() is None
        assert loop.error.startswith("screenshot failed: ") and "File exists" in loop.error
        err = capsys.readouterr().err
        assert err.startswith("frictex demo: screenshot failed: ") and err.count("\n") == 1
        loop.screenshot_dir = tmp_path / "shots"
        loop.scene = replace(loop.scene, name="../escaped")  # a name from a texture file
        path = loop.screenshot()
    finally:
        loop.close()
        window.close()
    assert path.parent == tmp_path / "shots" and path.name == "frictex-.._escaped-000.png"
    assert [e["event"] for e in read_events(tmp_path / "events.csv")] == [
        "screenshot-failed", "screenshot"]


@pytest.mark.parametrize("name, stem", [("grating-5mm", "grating-5mm"), ("../x", ".._x"),
                                        ("a b/c\\d", "a_b_c_d"), ("\u00e9t\u00e9", "_t_")])
def test_a_scene_name_becomes_a_plain_file_name(name, stem):
    assert file_stem(name) == stem


def test_force_scope_and_outlines_are_logged_and_the_rows_are_in_time_order(gl, tmp_path):
    loop, window = demo_loop(gl, tmp_path, tmp_path)
    try:
        loop.log("finger-down", "finger 0", t_s=5.0)  # an output time ahead of the keys
        loop.on_key("up", False)
        loop.on_scroll(30.0)  # beyond the range: held at 2 N
        loop.on_scroll(1.0)  # no change: not logged
        for key in ("s", "o"):
            loop.handle_key(key, False)
        loop.log("output-stop", "", t_s=1e-3)
    finally:
        loop.close()
        window.close()
    events = read_events(tmp_path / "events.csv")
    assert [(e["event"], e["detail"]) for e in events] == [
        ("output-stop", ""), ("force", "0.55 N"), ("force", "2.00 N"), ("scope", "hidden"),
        ("outlines", "on"), ("finger-down", "finger 0")]
    t = [float(e["t_s"]) for e in events]
    assert t == sorted(t)


def test_a_finger_touching_when_the_demo_ends_is_lifted_in_events(gl, tmp_path):
    """A demo ended (Q, a signal) with a finger down: its finger-down gets a finger-up at
    the last output drawn, so that downs and ups pair in events.csv."""
    loop, window = demo_loop(gl, tmp_path, tmp_path)
    t_s = np.array([1.0, 1.0025, 1.005])
    touching = SimpleNamespace(t_s=t_s, finger_ids=(3,), contact=np.array([[False, True, True]]),
                               x_mm=np.full((1, 3), 12.0), y_mm=np.full((1, 3), 8.0))
    try:
        loop._log_contacts(touching)
    finally:
        loop.close()
        window.close()
    events = [(float(e["t_s"]), e["event"], e["detail"]) for e in read_events(tmp_path / "events.csv")]
    assert events == [(1.0025, "finger-down", "finger 3 at 12.00, 8.00 mm"),
                      (1.005, "finger-up", "finger 3: touching when the demo ended")]


def run_recorded(scene, folder, touches, end_s, estop=None):
    """A haptic thread with its recording in ``folder`` (as the demo opens it), run on a
    fake clock in this thread; ``touches``: (t_s, finger, x_mm, y_mm, force_n, event)
    fed as its output clock reaches them."""
    now = [0.0]
    touches = sorted(touches)
    holder = {}

    def sleep(dt):
        now[0] += dt
        thread = holder["thread"]
        while touches and touches[0][0] <= thread.now():
            _, *sample = touches.pop(0)
            thread.touch(*sample)
        if thread.now() >= end_s:
            thread.stop()

    kwargs = {} if estop is None else {"estop": estop}
    haptic, _ = open_haptic(scene, 10_000.0, 25, None, None, folder, clock=lambda: now[0],
                            sleep=sleep, **kwargs)
    holder["thread"] = haptic
    haptic.wall.restart()
    haptic.t0 = haptic.wall.t0
    haptic.run()  # the driver commits the recording as the run ends
    assert haptic.error is None
    return haptic


def hard_drag(force_n=2.0):
    """A drag across grating-5mm pressing ``force_n``: beyond the friction model's range."""
    moves = [(0.1 + 0.01 * i, 0, 20.0 + 0.4 * i, 32.4, force_n, "move") for i in range(1, 60)]
    return [(0.1, 0, 20.0, 32.4, force_n, "down"), *moves, (0.7, 0, 44.0, 32.4, force_n, "up")]


def test_the_touches_are_recorded_as_a_trace_that_replays_what_was_felt(tmp_path, capsys):
    """A recording made pressing 2 N: touches.csv holds every sample with its force, and
    replaying it clamps as the demo did (it replayed at the trace format's 0.5 N and
    clamped nothing, the demo's 2 N was written nowhere)."""
    record = tmp_path / "rec"
    haptic = run_recorded(load_scene(GRATING), record, hard_drag(), end_s=1.0)
    assert haptic.stats.clamps.total > 0
    trace = read_trace(record / "touches.csv")
    assert len(trace) == 61 and (trace.force_n == 2.0).all()
    assert (record / "touches.csv").read_text().startswith("# frictex demo, scene grating-5mm")
    capsys.readouterr()
    assert main(["replay", str(GRATING), str(record / "touches.csv"), "--block", "25",
                 "--out", str(tmp_path / "replayed"), "--quiet"]) == 0
    replayed = json.loads((tmp_path / "replayed" / "summary.json").read_text())
    # the first touch on a block boundary, as here, puts the replay's blocks on the demo's
    assert replayed["clamps"] == haptic.stats.clamps.as_dict()


def test_clamps_are_not_counted_while_the_output_is_stopped(tmp_path):
    """While the emergency stop holds the output at 0 um, the commands not sent clamp
    nothing: the count stays at what was played."""
    class Stopped:
        def is_set(self):
            return True

    haptic = run_recorded(load_scene(GRATING), tmp_path / "rec", hard_drag(), end_s=1.0,
                          estop=Stopped())
    assert haptic.stats.clamps.total == 0
    assert haptic.stats.blocks > 300


def test_headless_frames_go_to_out_and_the_tables_to_record(no_display, tmp_path, capsys):
    record, out = tmp_path / "rec", tmp_path / "out"
    assert main(["demo", "grating-5mm", "--headless", "--haptic", "thread", "--record",
                 str(record), "--out", str(out), "--duration", "1"]) == 0
    text = capsys.readouterr().out
    assert sorted(p.name for p in record.iterdir()) == [
        "commands.csv", "events.csv", "friction.csv", "summary.json", "touches.csv"]
    frames = sorted((out / "frames").glob("frame-*.png"))
    assert [p.name for p in out.iterdir()] == ["frames"] and frames
    summary = json.loads((record / "summary.json").read_text())
    assert f"{summary['frames']} frames drawn (" in text
    kept = re.search(rf"{len(frames)} frames kept \(at most 30 a second; ([0-9.]+) ms each to "
                     rf"save as PNG, within the frames' mean\) in {re.escape(str(out / 'frames'))}",
                     text)
    assert kept and 0 < float(kept[1]) <= summary["frame_ms_mean"] * summary["frames"] / len(frames)
    assert f"outputs in {record}" in text
