"""The layer panel in the demo loop itself, on the headless window (no display): L opens
it, a slider drag made of injected mouse events changes the scene the haptic side
renders from the block that takes the switch on, and the picture from the next frame;
Ctrl+Z takes the drag back; Ctrl+S saves the file keeping its untouched lines. Every
wait is for the demo to confirm a step, bounded."""

import csv
import re
import threading
import time
from dataclasses import replace

import numpy as np
import pytest

from frictex.app.live.demo_loop import DemoLoop
from frictex.app.live.haptic_setup import open_haptic
from frictex.app.live.haptic_thread import EVENTS
from frictex.rendering.visual.layer_panel import PanelRow
from frictex.rendering.visual.viewport import default_frame_size
from frictex.rendering.visual.windows import open_backend
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

pytest.importorskip("moderngl", reason="moderngl (Python package) not installed")

FINGER, X_MM, Y_MM = 5, 1.25, 30.0  # a finger held in the first quarter of a 5 mm period
DUTY_AT = 0.2  # the slider is dragged to this fraction of its track: duty 0.201


def read_csv(path):
    with open(path, newline="") as f:
        return list(csv.DictReader(f))


def wait_for(what, test, timeout_s=120.0):
    deadline = time.monotonic() + timeout_s
    while not test():
        assert time.monotonic() < deadline, f"waited {timeout_s} s for {what}"
        time.sleep(0.01)


class Frames:
    """The frames the window shows, each with the scene it was drawn with: the last
    before each change of scene and the first after it."""

    def __init__(self):
        self.loop = None
        self.pairs = []  # (last frame of the scene before, first frame of the new one)
        self._last = None  # (scene, frame)

    def __call__(self, rgb):
        scene = self.loop.scene
        if self._last is not None and scene is not self._last[0]:
            self.pairs.append((self._last[1], rgb.copy(), self.loop.compositor.viewport))
        self._last = (scene, rgb.copy())


def run_demo(scene_file, rec, hand, on_frame=None) -> None:
    """The demo loop on the headless window with ``scene_file``, its haptic thread in this
    process, recording into ``rec``; ``hand(window, loop, haptic)``, the user, runs on a
    thread of its own, then Q. What the hand raises is raised here."""
    scene = load_scene(scene_file)
    try:
        window = open_backend("headless", default_frame_size(scene.display), on_frame=on_frame)
    except OSError as exc:
        pytest.skip(f"EGL unavailable: {exc}")
    haptic, finish = open_haptic(scene, 10_000.0, 50, None, None, rec)
    haptic.start()
    loop = DemoLoop(window, haptic, [scene_file], 0, scene, load_scene, rec.parent,
                    events_path=rec / "events.csv")
    if on_frame is not None:
        on_frame.loop = loop
    failures = []

    def user():
        try:
            wait_for("the first frame", lambda: window.frames > 0)
            hand(window, loop, haptic)
        except BaseException as exc:  # raised below
            failures.append(exc)
        finally:
            window.key("q")
    thread = threading.Thread(target=user, name="test-hand")
    thread.start()
    try:
        loop.run(duration_s=300.0)
    finally:
        thread.join()
        finish()
        loop.close()
        window.close()
    if failures:
        raise failures[0]


def edit_duty(detail: str) -> float:
    """The duty an edit of events.csv set ("undo": back to the file's 0.5)."""
    m = re.search(r"duty = ([0-9.]+)$", detail)
    return float(m.group(1)) if m else 0.5


def grating_mu(duty: float) -> float:
    """The target friction under the finger, at phase 0.25 of the grating's period: low
    (0.6) where the phase is below the duty."""
    return 0.6 if 0.25 < duty else 1.0


def wait_for_a_frame(window) -> None:
    """Wait for a frame drawn after what the caller waited for: the demo draws at its
    frame rate, so edits made faster than that share a frame."""
    n = window.frames
    wait_for("a frame", lambda: window.frames > n)


def row_of(loop, key):
    return next(r for r in loop.compositor.panel_rows if r.key == key)


def click(window, row):
    x, y, w, h = row.box
    window.move(x + w / 4, y + h / 2)
    window.press()
    window.release()


def make_edge_smooth(window, loop) -> None:
    """Open the panel (L) and choose a smooth edge for the first layer from its menu."""
    window.key("l")
    wait_for("the panel", lambda: any(r.key == "edge" for r in loop.compositor.panel_rows))
    click(window, row_of(loop, "edge"))
    wait_for("the menu", lambda: any(r.kind == "option" for r in loop.compositor.panel_rows))
    click(window, next(r for r in loop.compositor.panel_rows if r.option == "smooth"))
    wait_for("a smooth edge", lambda: loop.scene.layers[0].edge == "smooth")


def save_an_edit(window, loop, said: str = "saved") -> None:
    """A hand for :func:`run_demo`: a smooth edge chosen (:func:`make_edge_smooth`), then
    Ctrl+S, until the panel's note starts with ``said``."""
    make_edge_smooth(window, loop)
    window.key("ctrl+s")
    wait_for(f"the panel to say {said!r}", lambda: loop.panel_note.startswith(said))


def test_a_slider_drag_changes_the_next_block_and_frame(tmp_path, monkeypatch):
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    scene_file = tmp_path / "lines.toml"
    text = resolve_scene("grating-5mm").read_text().replace('render = "auto"', 'render = "sho"')
    scene_file.write_text(text)
    rec = tmp_path / "rec"
    frames = Frames()
    steps = []  # per drag and undo: (its final duty, the output switches made by its end)

    def hand(window, loop, haptic):
        """A finger held on the scene (a touch screen's, beside the mouse), L, a drag on
        the duty slider, Ctrl+Z, the drag again, Ctrl+S."""
        stop = threading.Event()

        def hold():
            event = "down"
            while not stop.is_set():
                haptic.touches_at(haptic.now(), [(FINGER, X_MM, Y_MM, 0.5, EVENTS[event])])
                event = "move"
                stop.wait(0.01)
            haptic.touches_at(haptic.now(), [(FINGER, X_MM, Y_MM, 0.5, EVENTS["up"])])

        def drag_duty():
            row = row_of(loop, "duty")
            tx, ty, tw, th = row.track
            window.move(tx + row.fraction * tw, ty + th / 2)
            window.press()
            for f in np.linspace(row.fraction, DUTY_AT, 8):
                window.move(tx + f * tw, ty + th / 2)
            window.release()
            wait_for("the edit", lambda: loop.scene.layers[0].duty == 0.201)
            wait_for_the_haptic_side(0.201)
            wait_for_a_frame(window)

        def wait_for_the_haptic_side(duty):
            """Wait for the block that took ``duty`` on to have noted its switch (in
            ``stats.applied``), then note how many switches the steps so far made: the
            haptic side takes only the latest of the edits queued at a block, so a step's
            edits may share a switch, and without this wait the next step's could too."""
            wait_for("the haptic side's", lambda: haptic.pipeline.scene.layers[0].duty == duty)
            n = haptic.stats.blocks
            wait_for("its block done", lambda: haptic.stats.blocks > n)
            steps.append((duty, sum(e[1] == "output-switch" for e in list(haptic.stats.applied))))
        holder = threading.Thread(target=hold)
        holder.start()
        try:
            wait_for("the finger's touch", lambda: FINGER in loop.fingers_down)
            window.key("l")
            wait_for("the duty slider", lambda: any(r.key == "duty" for r in loop.compositor.panel_rows))
            drag_duty()
            window.key("ctrl+z")
            wait_for("the undo", lambda: loop.scene.layers[0].duty == 0.5)
            wait_for("the slider back", lambda: row_of(loop, "duty").fraction == 0.5)
            wait_for_the_haptic_side(0.5)
            wait_for_a_frame(window)
            drag_duty()
            window.key("ctrl+s")
            wait_for("the save", lambda: scene_file.read_text() != text)
            n = haptic.stats.blocks
            wait_for("10 blocks more", lambda: haptic.stats.blocks > n + 10)
        finally:
            stop.set()
            holder.join()
        wait_for("the lift", lambda: FINGER not in loop.fingers_down)

    run_demo(scene_file, rec, hand, frames)

    # the file: the duty line changed, its comment kept; every other line as it was
    saved = scene_file.read_text().splitlines(keepends=True)
    changed = [(a, b) for a, b in zip(text.splitlines(keepends=True), saved) if a != b]
    assert len(saved) == len(text.splitlines()) and len(changed) == 1
    assert changed[0][1].startswith("duty = 0.201 ") and changed[0][1].endswith(
        "# the black line is the first half of each period\n")
    assert load_scene(scene_file).layers[0].duty == 0.201

    # the output: at each step's switches the finger's target becomes that of one of the
    # step's edits, at its last switch that of the step's final duty
    events = read_csv(rec / "events.csv")
    switches = [float(e["t_s"]) for e in events if e["event"] == "output-switch"]
    edits = [e["detail"] for e in events if e["event"] == "edit"]
    undo = edits.index("undo")
    steps_edits = [edits[:undo], edits[undo:undo + 1], edits[undo + 1:]]
    assert [duty for duty, _ in steps] == [0.201, 0.5, 0.201] and all(steps_edits)
    assert len(switches) == steps[-1][1] and edits[-1].endswith("duty = 0.201")
    rows = [r for r in read_csv(rec / "friction.csv") if r["finger"] == str(FINGER)]
    t = np.array([float(r["t_s"]) for r in rows])
    mu = np.array([float(r["mu_target"]) for r in rows])
    np.testing.assert_allclose(np.array([float(r["x_mm"]) for r in rows]), X_MM, atol=1e-4)
    mu_now, first = grating_mu(0.5), 0
    for (duty, end), step_edits in zip(steps, steps_edits):
        assert end > first  # the step switched the output at least once
        step_mu = {grating_mu(edit_duty(e)) for e in step_edits}
        for t_switch in switches[first:end]:
            before, after = np.flatnonzero(t < t_switch)[-1], np.flatnonzero(t >= t_switch)[0]
            assert mu[before] == mu_now and mu[after] in step_mu
            assert t[after] - t_switch < 50 / 10_000.0 + 1e-9  # the switch's own block
            mu_now = mu[after]
        assert mu_now == grating_mu(duty)
        first = end
    assert mu[-1] == 1.0 and (mu == 0.6).any()

    # the picture: the frame after each change of scene differs from the one before in
    # the scene's area (lines of another width), not only in the panel
    assert len(frames.pairs) >= len(switches)
    for before, after, vp in frames.pairs:
        area = (slice(vp.y0, vp.y0 + vp.height_px), slice(vp.x0, vp.x0 + vp.width_px))
        changed_px = np.any(before[area] != after[area], axis=-1).mean()
        assert changed_px > 0.0


def test_a_click_selects_a_layer_and_a_menu_sets_a_word_key(tmp_path, monkeypatch):
    """objects-bump-edge-disc, bundled: the disc (layer 2) selected, its blend menu opened
    and "replace" chosen: the scene shown and rendered takes it; undo takes it back; the
    bundled file is never written (nothing was saved)."""
    monkeypatch.setenv("XDG_DATA_HOME", str(tmp_path / "data"))
    path = resolve_scene("objects-bump-edge-disc")
    text = path.read_text()
    rec = tmp_path / "rec"

    def hand(window, loop, haptic):
        window.key("l")
        wait_for("the layers", lambda: sum(r.kind == "layer" for r in loop.compositor.panel_rows) == 3)
        layer = [r for r in loop.compositor.panel_rows if r.kind == "layer"][1]
        assert layer.text == "disc (disc)"
        click(window, layer)
        wait_for("the disc's keys", lambda: any(r.key == "radius_mm" for r in loop.compositor.panel_rows))
        click(window, row_of(loop, "blend"))
        wait_for("the menu", lambda: any(r.kind == "option" for r in loop.compositor.panel_rows))
        options = [r for r in loop.compositor.panel_rows if r.kind == "option"]
        assert [r.option for r in options] == ["multiply", "replace"]
        click(window, options[1])
        wait_for("the edit", lambda: loop.scene.layers[1].blend == "replace")
        wait_for("the haptic side's", lambda: haptic.pipeline.scene.layers[1].blend == "replace")
        wait_for("the menu closed", lambda: not any(r.kind == "option"
                                                    for r in loop.compositor.panel_rows))
        window.key("u")
        wait_for("the undo", lambda: loop.scene.layers[1].blend == "multiply")
        # rows of a file as it was before a reload: said in the panel, the demo runs on
        loop._panel.put(("click", PanelRow("layer", "gone", (0.0, 0.0, 1.0, 1.0), index=7)))
        wait_for("the note", lambda: "layer 7 does not exist" in loop.panel_note)
        loop._panel.put(("slide", replace(row_of(loop, "mu"), key="colour"), 0.5, 99))
        wait_for("the note", lambda: "no key 'colour'" in loop.panel_note)

    run_demo(path, rec, hand)
    events = read_csv(rec / "events.csv")
    assert [e["detail"] for e in events if e["event"] == "edit"] == [
        "disc (disc) blend = replace", "undo"]
    assert sum(e["event"] == "output-switch" for e in events) == 2
    assert path.read_text() == text and not (tmp_path / "data").exists()
