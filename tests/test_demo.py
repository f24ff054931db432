"""The live demo under Xvfb, driven by xdotool: touch, screenshots, emergency stop,
live reload and a broken edit; checked against what it recorded (--record).

Nothing here depends on how fast the machine is: the test waits for the demo to confirm
each step in events.csv (a finger down or up reaching the output, the output stopping,
resuming or switching scene, a screenshot written) before the next, ends the demo with
Q, and checks the output against the times the output itself reports."""

import csv
import json
import os
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from frictex.textures.library import resolve_scene

BLOCK_S = 50 / 10_000.0


def xdo(display, *args, timeout_s=120):
    """xdotool on ``display``; its output. The bound is for a broken X server only."""
    return subprocess.run(["xdotool", *args], env={**os.environ, "DISPLAY": display},
                          check=True, capture_output=True, text=True, timeout=timeout_s).stdout.strip()


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture
def xdotool():
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool binary not installed (Debian: xdotool)")


def off_edges(x_mm, half_period_mm=2.5):
    """Rows (one finger's, in order) at positions friction.csv's 1e-4 mm cannot have rounded
    across an edge of the grating, on the band of the row before: a sample that moved
    across an edge plays both sides in proportion (``rendering.layers.band_limit``)."""
    clear = np.abs(x_mm / half_period_mm - np.round(x_mm / half_period_mm)) * half_period_mm > 1e-4
    band = np.floor(x_mm / half_period_mm)
    return clear & np.concatenate(([False], clear[:-1] & (band[1:] == band[:-1])))


def grating_file(tmp_path):
    """grating-5mm rendered by SHO (mu' follows the position), as a file and its text."""
    scene_file = tmp_path / "lines.toml"
    text = resolve_scene("grating-5mm").read_text().replace('render = "auto"', 'render = "sho"')
    assert 'render = "sho"' in text and "mu_low = 0.6" in text
    scene_file.write_text(text)
    return scene_file, text


def start_demo(display, cwd, scene_file, rec, *args):
    """``frictex demo`` in its default window (the scene's 800 x 480 px at the top left,
    the scope under it) on ``display``, recording into ``rec``; --duration is only a
    safety net: the tests end it with Q. Its stderr goes to ``demo-stderr.txt`` beside
    ``rec`` (a pipe would stay open as long as its children, the haptic process and a
    simulated device, if it were killed)."""
    with open(rec.parent / "demo-stderr.txt", "w") as err:
        proc = subprocess.Popen([sys.executable, "-u", "-m", "frictex", "demo",
                                 str(scene_file), "--record", str(rec), "--duration", "300", *args],
                                env={**os.environ, "DISPLAY": display, "PYTHONFAULTHANDLER": "1"},
                                cwd=cwd, stdout=subprocess.PIPE, stderr=err, text=True)
    proc.stderr_path = rec.parent / "demo-stderr.txt"
    return proc


def focus_window(display) -> str:
    """The demo's window, focused (waits until it is shown, however long that takes)."""
    win = xdo(display, "search", "--sync", "--onlyvisible", "--name", "frictex demo").split()[0]
    xdo(display, "windowfocus", "--sync", win)  # no window manager: focus it
    return win


def live_folder(rec):
    """Where a running demo writes its recording ``rec``: its staging folder beside
    ``rec`` while it runs, ``rec`` itself once it has ended (or for a recording that is
    not staged)."""
    staged = sorted(rec.parent.glob(f".{rec.name}.frictex-staging.*"))
    return staged[0] if staged else rec


def events_of(rec, kind):
    path = live_folder(rec) / "events.csv"
    if not path.exists():  # ended between the two looks
        path = rec / "events.csv"
    return [e for e in (read_csv(path) if path.exists() else []) if e["event"] == kind]


def wait_event(proc, rec, kind="first-frame", count=1):
    """Wait until events.csv holds ``count`` events ``kind`` (however long the machine
    takes, within a generous bound); returns the last of them."""
    deadline = time.monotonic() + 120
    while len(found := events_of(rec, kind)) < count:
        assert proc.poll() is None, f"the demo exited before {count} {kind} events"
        assert time.monotonic() < deadline, f"no {kind} event #{count}"
        time.sleep(0.02)
    return found[count - 1]


def drag(display, win, proc, rec, points, strokes_before, hold=None):
    """Press at the first of ``points`` (px), move through them, release; waits for the
    output to see the finger down and, after the release, up (so every position moved
    through reached it). ``hold``: called while the button is held, after the first move."""
    (x0, y0), rest = points[0], points[1:]
    xdo(display, "mousemove", "--window", win, str(int(x0)), str(int(y0)))
    xdo(display, "mousedown", "1")
    wait_event(proc, rec, "finger-down", strokes_before + 1)
    for k, (x, y) in enumerate(rest):
        xdo(display, "mousemove", "--window", win, str(int(x)), str(int(y)))
        if k == 0 and hold is not None:
            hold()
    xdo(display, "mouseup", "1")
    wait_event(proc, rec, "finger-up", strokes_before + 1)


def quit_demo(display, proc) -> str:
    """Q, then wait for the demo to exit 0; its stdout."""
    xdo(display, "key", "q")
    return finish(proc)


def finish(proc, expected: int = 0) -> str:
    """Wait for the demo to end; it must exit ``expected``. Its stdout. One that hangs is stopped
    with SIGABRT, which makes it print every thread's stack (faulthandler) for the
    failure message."""
    try:
        proc.wait(timeout=120)
    except subprocess.TimeoutExpired:
        proc.send_signal(signal.SIGABRT)
        try:
            proc.wait(timeout=30)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        err = proc.stderr_path.read_text()
        pytest.fail(f"the demo did not exit within 120 s after Q; its threads:\n{err[-8000:]}")
    out = proc.stdout.read()
    proc.stdout.close()
    assert proc.returncode == expected, proc.stderr_path.read_text()
    return out


def test_demo_window_touch_estop_reload_and_broken_edit(xvfb_display, xdotool, tmp_path):
    scene_file, text = grating_file(tmp_path)
    rec, shots = tmp_path / "rec", tmp_path / "shots"
    proc = start_demo(xvfb_display, tmp_path, scene_file, rec, "--screenshots", str(shots))
    stroke = [(x, 240) for x in np.linspace(100, 700, 25)]
    try:
        win = focus_window(xvfb_display)
        wait_event(proc, rec)
        drag(xvfb_display, win, proc, rec, stroke, 0)
        xdo(xvfb_display, "key", "p")  # screenshot of the scene
        wait_event(proc, rec, "screenshot")

        def stop_while_touching():
            xdo(xvfb_display, "key", "space")
            wait_event(proc, rec, "output-stop")
            for x in range(120, 400, 20):
                xdo(xvfb_display, "mousemove", "--window", win, str(x), "240")
            xdo(xvfb_display, "key", "space")
            wait_event(proc, rec, "output-resume")

        drag(xvfb_display, win, proc, rec, [(100, 240), (110, 240), (400, 240)], 1,
             hold=stop_while_touching)
        scene_file.write_text(text.replace("mu_low = 0.6", "mu_low = 0.3"))
        wait_event(proc, rec, "output-switch")  # seen, held still for a poll, then switched
        drag(xvfb_display, win, proc, rec, stroke, 2)
        scene_file.write_text(text.replace("period_mm = 5", "period_mm = -5"))
        wait_event(proc, rec, "reload-failed")
        xdo(xvfb_display, "key", "p")  # screenshot with the error shown
        wait_event(proc, rec, "screenshot", 2)
        drag(xvfb_display, win, proc, rec, stroke, 3)
    finally:
        quit_demo(xvfb_display, proc)

    events = read_csv(rec / "events.csv")
    window = [e["event"] for e in events if not e["event"].startswith(("finger-", "output-"))]
    assert window == ["first-frame", "screenshot", "estop", "estop-release", "reload",
                      "reload-failed", "screenshot"]
    t_of = {e["event"]: float(e["t_s"]) for e in events}  # each of these happens once
    assert "period_mm" in next(e["detail"] for e in events if e["event"] == "reload-failed")

    rows = read_csv(rec / "friction.csv")
    t = np.array([float(r["t_s"]) for r in rows])
    x = np.array([float(r["x_mm"]) for r in rows])
    y = np.array([float(r["y_mm"]) for r in rows])
    mu = np.array([float(r["mu_target"]) for r in rows])
    # the pointer's path: row 240 of the 800 x 480 px showing 108 x 64.8 mm
    px_per_mm = 800 / 108.0
    assert np.abs(y - 240 / px_per_mm).max() < 0.2
    assert x.min() < 110 / px_per_mm and x.max() > 690 / px_per_mm
    # SHO: mu' is the grating at the finger's position (period 5 mm, first half low);
    # the new scene shapes the output from the block the output reports it switched at
    low = np.mod(x / 5.0, 1.0) < 0.5
    t_switch = t_of["output-switch"]
    before = (t < t_switch) & off_edges(x)
    assert before.sum() > 1000
    np.testing.assert_array_equal(mu[before], np.where(low[before], 0.6, 1.0))
    after = t >= t_switch
    clear = after & off_edges(x)
    assert clear.sum() > 1000 and np.isin(np.round(mu[clear], 6), [0.3, 1.0]).all()
    assert (np.round(mu[t > t_of["reload-failed"]], 6) == 0.3).any()  # kept mu_low 0.3

    cmd = read_csv(rec / "commands.csv")
    ct = np.array([float(r["t_s"]) for r in cmd])
    amp = np.array([float(r[list(r)[1]]) for r in cmd])
    t_on, t_off = t_of["output-stop"], t_of["output-resume"]
    # the output never runs ahead of the clock: it stops within a block of the key
    assert t_on < t_of["estop"] + BLOCK_S and t_off < t_of["estop-release"] + BLOCK_S
    assert amp[ct < t_on].max() > 0.5
    stopped = (ct >= t_on) & (ct < t_off)
    assert stopped.sum() >= 50 and (amp[stopped] == 0.0).all()
    assert amp[ct >= t_off].max() > 0.5

    summary = json.loads((rec / "summary.json").read_text())
    assert summary["frames"] >= 2 and isinstance(summary["deadline_misses"], int)
    assert [c["event"] for c in summary["output_changes"]] == ["output-stop", "output-resume",
                                                               "output-switch"]
    assert summary["output_changes"][0]["t_s"] == pytest.approx(t_on, abs=1e-6)
    shots_taken = sorted(shots.glob("*.png"))
    assert [p.name for p in shots_taken] == ["frictex-grating-5mm-000.png",
                                               "frictex-grating-5mm-001.png"]
    from PIL import Image
    first = np.asarray(Image.open(shots_taken[0]).convert("RGB")).astype(int)
    second = np.asarray(Image.open(shots_taken[1]).convert("RGB")).astype(int)
    row = first[200, :, 1]
    assert (row < 30).sum() > 200 and (row > 225).sum() > 200  # black and white lines
    red = (second[..., 0] > 100) & (second[..., 1] < 40) & (second[..., 2] < 40)
    assert red.sum() > 800 * 20  # the error banner across the window


def test_window_keeps_running_while_the_device_is_unplugged(xvfb_display, xdotool, tmp_path):
    """--faults on the demo: the simulated device is unplugged from 0.3 s after the link
    opens until long after the test ends. The window keeps taking touches and keys
    (each confirmed by the demo), quits at once on Q, and the summary counts what the
    device never got; it exits 1, the link lost and not back by the end."""
    scene_file, _ = grating_file(tmp_path)
    rec, shots = tmp_path / "rec", tmp_path / "shots"
    proc = start_demo(xvfb_display, tmp_path, scene_file, rec, "--screenshots", str(shots),
                      "--device", "sim", "--faults", "unplug=600@0.3")
    stroke = [(x, 240) for x in np.linspace(100, 700, 10)]
    try:
        win = focus_window(xvfb_display)
        wait_event(proc, rec)
        for k in range(3):
            drag(xvfb_display, win, proc, rec, stroke, k)
            xdo(xvfb_display, "key", "p")
            wait_event(proc, rec, "screenshot", k + 1)
    finally:
        xdo(xvfb_display, "key", "q")
        finish(proc, expected=1)
    assert "frictex demo: error: the device link was lost (" in proc.stderr_path.read_text()
    link = json.loads((rec / "summary.json").read_text())["link"]
    assert link["disconnects"] >= 1 and link["dropped_blocks"] > 0
    assert link["unplayed_samples"] > 0
    rows = read_csv(rec / "friction.csv")
    assert len({r["t_s"] for r in rows}) > 100  # the pipeline kept computing the touches


def test_faults_without_a_device_is_one_line_exit_2(capsys):
    from frictex.app.commands.cli import main
    assert main(["demo", "grating-5mm", "--faults", "trip@1"]) == 2
    err = capsys.readouterr().err
    assert err == ("frictex: error: --faults: needs --device (the faults are injected on the link "
                   "to a device); no --device was given\n")


def test_bad_faults_spec_is_one_line_exit_2(capsys):
    from frictex.app.commands.cli import main
    with pytest.raises(SystemExit) as exc:
        main(["demo", "grating-5mm", "--device", "sim", "--faults", "wobble=3"])
    err = capsys.readouterr().err
    assert exc.value.code == 2 and err.startswith("frictex: error:") and err.count("\n") == 1
