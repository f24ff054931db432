"""The live demo under Xvfb, driven by xdotool: touch, screenshots, emergency stop,
live reload and a broken edit; checked against what it recorded (--record)."""

import csv
import json
import os
import shutil
import subprocess
import sys
import time

import numpy as np
import pytest

from textures.library import resolve_scene

BLOCK_S = 50 / 10_000.0


def xdo(display, *args):
    return subprocess.run(["xdotool", *args], env={**os.environ, "DISPLAY": display},
                          check=True, capture_output=True, text=True, timeout=20).stdout.strip()


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


@pytest.fixture
def xdotool():
    if shutil.which("xdotool") is None:
        pytest.skip("xdotool binary not installed (Debian: xdotool)")


def off_edges(x_mm, half_period_mm=2.5):
    """Positions friction.csv's 1e-4 mm cannot have rounded across an edge of the grating."""
    return np.abs(x_mm / half_period_mm - np.round(x_mm / half_period_mm)) * half_period_mm > 1e-4


def grating_file(tmp_path):
    """grating-5mm rendered by SHO (mu' follows the position), as a file and its text."""
    scene_file = tmp_path / "lines.toml"
    text = resolve_scene("grating-5mm").read_text().replace('render = "auto"', 'render = "sho"')
    assert 'render = "sho"' in text and "mu_low = 0.6" in text
    scene_file.write_text(text)
    return scene_file, text


def start_demo(display, cwd, scene_file, rec, *args):
    """``frictex demo`` in an 800x480 window on ``display``, recording into ``rec``."""
    return subprocess.Popen([sys.executable, "-u", "-m", "app.commands.cli", "demo", str(scene_file),
                             "--record", str(rec), "--size", "800x480", *args],
                            env={**os.environ, "DISPLAY": display}, cwd=cwd,
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


def focus_window(display) -> str:
    win = xdo(display, "search", "--sync", "--onlyvisible", "--name", "frictex demo").split()[0]
    xdo(display, "windowfocus", "--sync", win)  # no window manager: focus it
    return win


def wait_event(proc, rec, kind="first-frame", count=1):
    """Wait until events.csv holds ``count`` events ``kind``. Input is stamped when the
    loop handles it, so start once it is drawing frames ("first-frame"); a screenshot is
    written after the frame that follows the key, so wait for it before the next key."""
    deadline = time.monotonic() + 20
    path = rec / "events.csv"
    while sum(1 for e in (read_csv(path) if path.exists() else []) if e["event"] == kind) < count:
        assert time.monotonic() < deadline and proc.poll() is None, f"no {kind} event"
        time.sleep(0.05)


def finish(proc) -> str:
    """Wait for the demo to end by itself (--duration); it must exit 0. Its stdout."""
    try:
        out, err = proc.communicate(timeout=30)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 0, err
    return out


def test_demo_window_touch_estop_reload_and_broken_edit(xvfb_display, xdotool, tmp_path):
    scene_file, text = grating_file(tmp_path)
    rec, shots = tmp_path / "rec", tmp_path / "shots"
    proc = start_demo(xvfb_display, tmp_path, scene_file, rec, "--duration", "12",
                      "--screenshots", str(shots))
    try:
        win = focus_window(xvfb_display)
        wait_event(proc, rec)

        def stroke(x_from, x_to, y=240):
            xdo(xvfb_display, "mousemove", "--window", win, str(x_from), str(y))
            xdo(xvfb_display, "mousedown", "1")
            for x in np.linspace(x_from, x_to, 25):
                xdo(xvfb_display, "mousemove", "--window", win, str(int(x)), str(y))
                time.sleep(0.01)
            xdo(xvfb_display, "mouseup", "1")

        stroke(100, 700)
        xdo(xvfb_display, "key", "p")  # screenshot of the scene
        wait_event(proc, rec, "screenshot")
        xdo(xvfb_display, "mousemove", "--window", win, "100", "240")
        xdo(xvfb_display, "mousedown", "1")
        xdo(xvfb_display, "key", "space")  # emergency stop while touching
        for x in range(100, 400, 20):
            xdo(xvfb_display, "mousemove", "--window", win, str(x), "240")
            time.sleep(0.01)
        xdo(xvfb_display, "key", "space")
        xdo(xvfb_display, "mouseup", "1")
        scene_file.write_text(text.replace("mu_low = 0.6", "mu_low = 0.3"))
        time.sleep(0.8)  # polled every 0.25 s
        stroke(100, 700)
        scene_file.write_text(text.replace("period_mm = 5", "period_mm = -5"))
        time.sleep(0.8)
        xdo(xvfb_display, "key", "p")  # screenshot with the error shown
        stroke(100, 700)
    finally:
        finish(proc)

    events = read_csv(rec / "events.csv")
    kinds = [e["event"] for e in events]
    assert kinds == ["first-frame", "screenshot", "estop", "estop-release", "reload",
                     "reload-failed", "screenshot"]
    events = events[1:]
    assert "period_mm" in events[4]["detail"]
    t_stop, t_release, t_reload, t_broken = (float(events[i]["t_s"]) for i in (1, 2, 3, 4))

    rows = read_csv(rec / "friction.csv")
    t = np.array([float(r["t_s"]) for r in rows])
    x = np.array([float(r["x_mm"]) for r in rows])
    y = np.array([float(r["y_mm"]) for r in rows])
    mu = np.array([float(r["mu_target"]) for r in rows])
    # the pointer's path: row 240 of an 800x480 window showing 108 x 64.8 mm
    px_per_mm = 800 / 108.0
    assert np.abs(y - 240 / px_per_mm).max() < 0.2
    assert x.min() < 110 / px_per_mm and x.max() > 690 / px_per_mm
    # SHO: mu' is the grating at the finger's position (period 5 mm, first half low)
    low = np.mod(x / 5.0, 1.0) < 0.5
    # the new scene takes over at the block after the switch; the event is logged just
    # after it, on another thread: leave a margin around that instant
    before = t < t_reload - 0.1
    before &= off_edges(x)
    np.testing.assert_array_equal(mu[before], np.where(low[before], 0.6, 1.0))
    after = t > t_reload + 0.1
    assert np.isin(np.round(mu[after], 6), [0.3, 1.0]).all()  # the broken edit kept mu_low 0.3
    assert (np.round(mu[t > t_broken + 0.1], 6) == 0.3).any()

    cmd = read_csv(rec / "commands.csv")
    ct = np.array([float(r["t_s"]) for r in cmd])
    amp = np.array([float(r[list(r)[1]]) for r in cmd])
    assert amp[ct < t_stop].max() > 0.5
    stopped = (ct > t_stop + BLOCK_S) & (ct < t_release)
    assert stopped.sum() > 10 and (amp[stopped] == 0.0).all()
    assert amp[ct > t_release + BLOCK_S].max() > 0.5

    summary = json.loads((rec / "summary.json").read_text())
    assert summary["frames"] > 30 and isinstance(summary["deadline_misses"], int)
    shots_taken = sorted(shots.glob("*.png"))
    assert len(shots_taken) == 2
    from PIL import Image
    first = np.asarray(Image.open(shots_taken[0]).convert("RGB")).astype(int)
    second = np.asarray(Image.open(shots_taken[1]).convert("RGB")).astype(int)
    row = first[200, :, 1]
    assert (row < 30).sum() > 200 and (row > 225).sum() > 200  # black and white lines
    red = (second[..., 0] > 100) & (second[..., 1] < 40) & (second[..., 2] < 40)
    assert red.sum() > 800 * 20  # the error banner across the window
