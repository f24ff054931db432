"""The bundled seed003-gratings protocol (shortened: one repetition, one practice trial,
a break every 3 trials) end to end in the real window under Xvfb, on a simulated
device, driven by xdotool as a participant would: Enter on the instructions, a drag
over each grating, Enter to move on, a digit to rate it, Enter after the break; then
``frictex experiment analyse`` on the session. Each step waits for the window to
confirm it in live/events.csv (see test_demo)."""

import os
import signal
import subprocess
import sys
from pathlib import Path

import numpy as np
from PIL import Image

from frictex.app.commands.cli import main as cli_main
import frictex.app.experiment as experiment_package
from frictex.rendering.visual.experiment_view import BUTTON_RGBA
from test_demo import drag, events_of, finish, read_csv, wait_event, xdo, xdotool  # noqa: F401

SIZE = (800, 600)
RATINGS = ["0", "7", "3", "9", "5", "2", "8"]  # the keys pressed: 0 is 10 on the 1-10 scale


def shortened(tmp_path):
    text = (Path(experiment_package.__file__).parent / "protocols" / "seed003-gratings.toml").read_text()
    for old, new in (("repetitions = 3", "repetitions = 1"), ("practice = 2", "practice = 1"),
                     ("break_every = 9", "break_every = 3")):
        assert old in text
        text = text.replace(old, new)
    path = tmp_path / "seed003-short.toml"
    path.write_text(text)
    return path


def screens(rec):
    return [e["detail"] for e in events_of(rec, "screen")]


def test_seed003_gratings_in_the_window_under_xvfb(xvfb_display, xdotool, tmp_path):
    protocol = shortened(tmp_path)
    out, shots = tmp_path / "session", tmp_path / "shots"
    rec = out / "live"
    with open(tmp_path / "stderr.txt", "w") as err:
        proc = subprocess.Popen(
            [sys.executable, "-u", "-m", "frictex", "experiment", str(protocol),
             "--participant", "window", "--out", str(out), "--device", "sim",
             "--size", f"{SIZE[0]}x{SIZE[1]}", "--screenshots", str(shots), "--seed", "3"],
            env={**os.environ, "DISPLAY": xvfb_display, "PYTHONFAULTHANDLER": "1"},
            cwd=tmp_path, stdout=subprocess.PIPE, stderr=err, text=True)
    proc.stderr_path = tmp_path / "stderr.txt"
    try:
        win = xdo(xvfb_display, "search", "--sync", "--onlyvisible", "--name",
                  "frictex experiment").split()[0]
        xdo(xvfb_display, "windowfocus", "--sync", win)
        wait_event(proc, rec, "screen")
        wait_event(proc, rec, "first-frame")
        xdo(xvfb_display, "key", "p")
        wait_event(proc, rec, "screenshot")
        xdo(xvfb_display, "key", "Return")
        breaks = 0
        for k, rating in enumerate(RATINGS, start=1):
            while not events_of(rec, "interval-start")[k - 1:]:
                if screens(rec).count("Break") > breaks:  # a break first: go on
                    breaks += 1
                    xdo(xvfb_display, "key", "Return")
                wait_event(proc, rec, "screen", len(screens(rec)))  # bounded, and alive
            asked = len(screens(rec))
            if k == 1:  # the first interval as shown: the grating, the Next button
                xdo(xvfb_display, "key", "p")
                wait_event(proc, rec, "screenshot", 2)
            y = SIZE[1] // 2
            drag(xvfb_display, win, proc, rec,
                 [(x, y) for x in np.linspace(150, 650, 20)], k - 1)
            xdo(xvfb_display, "key", "Return")
            wait_event(proc, rec, "screen", asked + 1)  # the question
            if k == 1:
                xdo(xvfb_display, "key", "p")
                wait_event(proc, rec, "screenshot", 3)
            xdo(xvfb_display, "key", rating)
            wait_event(proc, rec, "response", k)
        finish(proc)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert "7 trials" in proc.stderr_path.read_text()
    rows = read_csv(out / "results.csv")
    assert [r["practice"] for r in rows] == ["1"] + ["0"] * 6
    assert [r["response"] for r in rows] == ["10" if r == "0" else r for r in RATINGS]
    assert sorted(r["stimuli"] for r in rows[1:]) == sorted(
        f"{p}-{m}" for p in ("15mm", "5mm", "0.6mm") for m in ("sho", "sht"))
    assert breaks == 2 and screens(rec).count("Break") == 2  # after the practice, after 3 trials
    for k in range(1, 8):
        assert (out / "trials" / f"{k:04d}" / "1" / "commands.csv").exists()
    # the screenshots: the instructions, an interval and the question, their buttons drawn
    button = np.round(np.array(BUTTON_RGBA[:3]) * 255)
    for path in sorted(shots.glob("*.png")):
        Image.open(path).save(Path(os.environ.get("FRICTEX_KEEP_SHOTS", tmp_path)) / path.name)
        rgb = np.asarray(Image.open(path).convert("RGB")).astype(int)
        assert np.all(np.abs(rgb - button) <= 2, axis=-1).sum() > 500, path.name
    # named for the session, not the stimulus shown (a shared screenshot must not unblind)
    assert sorted(p.name for p in shots.glob("*.png")) == [
        f"frictex-experiment-{k:03d}.png" for k in range(3)]
    assert cli_main(["experiment", "analyse", str(out), "--out", str(tmp_path / "analysis")]) == 0
    assert (tmp_path / "analysis" / "analysis.json").exists()


PWIN = """format = 1
method = "2afc"
seed = 3
repetitions = 1
[stimuli]
scene = "grating-5mm"
vary = "period_mm"
reference = 5.0
levels = [5.5]
"""


def test_escape_and_sigterm_stop_a_window_session_in_one_line(xvfb_display, xdotool, tmp_path):
    """Escape is a planned stop: one line saying where and how to resume, exit 130 (as
    Ctrl-C). SIGTERM ends a resumed session the same way: ``terminated by SIGTERM``,
    exit 143, the haptic process ended in order (no leaked-semaphore warning)."""
    protocol, out = tmp_path / "pwin.toml", tmp_path / "session"
    protocol.write_text(PWIN)
    for live, resume in (("live", []), ("live-2", ["--resume"])):
        with open(tmp_path / "stderr.txt", "w") as err:
            proc = subprocess.Popen(
                [sys.executable, "-u", "-m", "frictex", "experiment", str(protocol),
                 "--participant", "window", "--out", str(out), "--size", "640x480", *resume],
                env={**os.environ, "DISPLAY": xvfb_display}, cwd=tmp_path,
                stdout=subprocess.PIPE, stderr=err, text=True)
        proc.stderr_path = tmp_path / "stderr.txt"
        try:
            wait_event(proc, out / live, "screen")  # the instructions
            wait_event(proc, out / live, "first-frame")
            if not resume:
                win = xdo(xvfb_display, "search", "--sync", "--onlyvisible", "--name",
                          "frictex experiment").split()[0]
                xdo(xvfb_display, "windowfocus", "--sync", win)
                xdo(xvfb_display, "key", "Escape")
            else:
                proc.send_signal(signal.SIGTERM)
            proc.wait(timeout=120)
        finally:
            if proc.poll() is None:
                proc.kill()
                proc.wait()
        proc.stdout.close()
        err = proc.stderr_path.read_text()
        assert err.endswith("\n") and err.count("\n") == 1, err
        if not resume:
            assert proc.returncode == 130, err
            assert err.startswith("frictex: session stopped at trial 1 (Escape); resume with: "
                                  f"frictex experiment {protocol} --out {out} --resume"), err
        else:
            assert proc.returncode == 128 + signal.SIGTERM, err
            assert err.startswith("frictex: terminated by SIGTERM at trial 1"), err
    assert (out / "results.csv").read_text().count("\n") == 1  # the header: nothing answered
