"""The demo loop without a display: the headless window (the glfw window's contract on
an EGL framebuffer, input injected), and ``frictex demo --headless`` /
``--headless-fallback`` running the demo loop itself on a synthesized stroke. No Xvfb:
the tests take DISPLAY away."""

import csv
import json
import os
import subprocess
import sys
import threading

import numpy as np
import pytest
from PIL import Image

from frictex.app.commands.cli import main
from frictex.device.registry import UnknownName
from frictex.rendering.visual.context import Window
from frictex.rendering.visual.windows import WINDOWS, open_backend

pytest.importorskip("moderngl", reason="moderngl (Python package) not installed")


@pytest.fixture
def no_display(monkeypatch):
    monkeypatch.delenv("DISPLAY", raising=False)
    monkeypatch.delenv("WAYLAND_DISPLAY", raising=False)


@pytest.fixture
def window():
    try:
        w = open_backend("headless", (64, 48))
    except OSError as exc:
        pytest.skip(f"EGL unavailable: {exc}")
    yield w
    w.close()


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def test_window_backends_come_from_the_registry():
    assert WINDOWS.names()[:3] == ("egl", "glfw", "headless")
    with pytest.raises(UnknownName, match="unknown window backend 'sdl'; expected one of "
                                          "egl, glfw, headless"):
        open_backend("sdl", (10, 10))


def test_headless_window_hands_injected_events_to_the_callbacks_in_order(window):
    assert isinstance(window, Window)
    got = []
    window.on_cursor = lambda x, y: got.append(("cursor", x, y))
    window.on_button = lambda pressed: got.append(("button", pressed))
    window.on_scroll = lambda dy: got.append(("scroll", dy))
    window.on_key = lambda name, shift: got.append(("key", name, shift))
    window.wait_events(0.0)  # nothing there: returns at once
    window.move(10.25, 3.5)
    window.press()
    window.move(11.75, 3.5)
    window.release()
    window.scroll(-1)
    window.key("q", shift=True)
    window.wait_events(0.0)
    assert got == [("cursor", 10.25, 3.5), ("button", True), ("cursor", 11.75, 3.5),
                   ("button", False), ("scroll", -1.0), ("key", "q", True)]
    assert window.cursor_px() == (11.75, 3.5) and not window.should_close
    window.close_window()
    window.wait_events(1.0)
    assert window.should_close


def test_headless_window_context_moves_to_a_render_thread_and_back(window):
    """As the demo loop does: released here, made current and drawn on another thread,
    swapped (the frame goes to on_frame), released there, current here again."""
    shown = []
    window.on_frame = shown.append
    window.release_context()
    errors = []

    def render():
        try:
            window.make_current()
            window.use()
            window.ctx.clear(1.0, 0.0, 0.0)
            window.swap()
            window.release_context()
        except Exception as exc:  # reported below
            errors.append(exc)
    thread = threading.Thread(target=render)
    thread.start()
    thread.join()
    window.make_current()
    assert errors == [] and window.frames == 1
    assert shown[0].shape == (48, 64, 3) and (shown[0] == [255, 0, 0]).all()
    window.use()
    window.ctx.clear(0.0, 0.0, 1.0)
    assert (window.read_rgb() == [0, 0, 255]).all()
    assert window.ctx.error == "GL_NO_ERROR"


def check_outputs(out):
    """What a headless demo wrote: the stroke's touch in the tables and the events, and
    its frames as PNG files showing the scene."""
    summary = json.loads((out / "summary.json").read_text())
    assert summary["input"] == "mouse" and summary["blocks"] > 0 and summary["frames"] > 0
    rows = read_csv(out / "friction.csv")
    x = np.array([float(r["x_mm"]) for r in rows if r["finger"] == "0"])
    assert x.size > 0 and np.ptp(x) > 10.0  # the synthesized hand moved the finger 0
    events = [e["event"] for e in read_csv(out / "events.csv")]
    assert events.count("finger-down") == 1 and events.count("finger-up") == 1
    assert events.index("first-frame") >= 0
    frames = sorted((out / "frames").glob("frame-*.png"))
    assert 0 < len(frames) <= summary["frames"]
    last = np.asarray(Image.open(frames[-1]))
    assert last.shape == (615, 800, 3) and last.std() > 10.0  # the grating, drawn


def test_headless_demo_runs_the_demo_loop_on_a_synthesized_stroke(no_display, tmp_path, capsys):
    out = tmp_path / "out"
    (out / "frames").mkdir(parents=True)
    (out / "frames" / "frame-99999.png").write_bytes(b"a frame of an earlier run")
    (out / "summary.json").write_text("{}")  # which wrote its summary beside it
    assert main(["demo", "grating-5mm", "--headless", "--haptic", "thread",
                 "--out", str(out)]) == 0
    text = capsys.readouterr().out
    assert "a synthesized stroke of 3 s drove the mouse" in text and str(out) in text
    assert not (out / "frames" / "frame-99999.png").exists()
    check_outputs(out)


def test_headless_fallback_without_a_display_says_so_and_runs_the_demo_loop(tmp_path):
    """The README's first command, on a machine with no display, in the default haptic
    process mode."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    done = subprocess.run([sys.executable, "-m", "frictex", "demo", "grating-5mm",
                           "--headless-fallback"], cwd=tmp_path, env=env, capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "no display" in done.stdout and "headless on a synthesized stroke" in done.stdout
    check_outputs(tmp_path / "frictex-demo-out")


def test_headless_takes_no_touch_screen(no_display, capsys):
    assert main(["demo", "--headless", "--input", "tuio:0"]) == 2
    err = capsys.readouterr().err
    assert "drives the mouse with a synthesized stroke" in err and err.count("\n") == 1


def test_a_headless_demo_of_a_short_duration_ends_cleanly(tmp_path):
    """--duration 1: the synthesized stroke lasts 1 s, then the hand lifts and quits (the
    hand once outlived the demo, and printed a traceback from its thread in about half the
    runs)."""
    env = {k: v for k, v in os.environ.items() if k not in ("DISPLAY", "WAYLAND_DISPLAY")}
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "frictex", "demo", "grating-5mm", "--headless",
                           "--haptic", "thread", "--duration", "1", "--out", str(out)],
                          env=env, capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    assert "Traceback" not in done.stderr and "Exception" not in done.stderr, done.stderr
    assert "a synthesized stroke of 1 s drove the mouse" in done.stdout
    summary = json.loads((out / "summary.json").read_text())
    assert summary["blocks"] > 0 and summary["frames"] > 0


def test_a_stroke_cut_short_is_said_with_what_cut_it():
    from types import SimpleNamespace

    from frictex.app.commands.demo import stroke_said
    cut = SimpleNamespace(stroked_s=1.62, duration_s=3.0)
    assert stroke_said(cut, "SIGTERM") == "a synthesized stroke cut at 1.6 s of its 3 s by SIGTERM"
    assert stroke_said(cut, "window") == ("a synthesized stroke cut at 1.6 s of its 3 s by the "
                                          "window closing")
    assert stroke_said(SimpleNamespace(stroked_s=3.0, duration_s=3.0), "window") == (
        "a synthesized stroke of 3 s")
