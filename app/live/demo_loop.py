"""The demo's window loop (main thread): input -> haptic side, snapshots -> frames.

The haptic side is an ``app.live.haptic_thread.HapticThread`` or an
``app.live.haptic_process.HapticProcess`` (same interface).

Backend-neutral: it drives any ``rendering.visual.context`` backend that has input
callbacks, ``poll()``, ``swap()`` and ``should_close`` (the glfw window).

Touch input (``--input``): ``mouse``, the mouse is finger 0 (left button held =
touching); ``follow``, the mouse is finger 0 and finger 1 follows it at a fixed offset
along x (seed 001's way of testing two-finger control with one hand); a touch source
(TUIO, evdev: any object with ``poll() -> list[TouchSample]`` in positions normalised to
0..1 of the active area, stamped on ``time.monotonic``), polled once per frame, never
blocking, whose fingers keep the source's ids (small integers, reused after a lift);
the mouse then only hovers. The wheel or up/down set the normal force of every finger.
Keys: N / B next / previous scene, R cycles the renderer (as the file says, SHO, SHT,
hybrid), S scope, O outlines, P screenshot, SPACE emergency stop (latched; SPACE
again resumes, ramped), Q / Escape quit.

The scene file is polled for changes; a good edit reloads (haptics crossfade in one
block), a bad one keeps the last good scene and shows its error on screen.
Events are appended to ``events.csv`` (t_s on the haptic clock, event, detail) when a
record folder is given.
"""

from __future__ import annotations

import queue
import time
from pathlib import Path

import numpy as np
from PIL import Image

from app.live.haptic_thread import EVENTS
from rendering.visual.compositor import Compositor, FrameView
from rendering.visual.modal_view import modal_envelope
from rendering.visual.overlay import OverlayState

RENDERER_CYCLE = (None, "sho", "sht", "hybrid")
FORCE_STEP_N = 0.05
FORCE_RANGE_N = (0.05, 2.0)
RELOAD_POLL_S = 0.25
ENVELOPE_S = 0.2  # a modal device's |W| is redrawn from the latest commands 5 times a second
FRAME_S = 1.0 / 60.0
KEYS_HELP = ("wheel, up/down: force | N/B: scene | R: renderer | S: scope | "
             "O: outlines | P: screenshot | SPACE: emergency stop | Q: quit")


def _mtime(path: Path) -> float | None:
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return None


class DemoLoop:
    """See the module docstring. ``load(path) -> Scene`` raises ValueError on a bad file."""

    def __init__(self, backend, haptic, playlist: list[Path], index: int, scene, load,
                 screenshot_dir: Path, events_path: Path | None = None, link_name: str = "none",
                 follow_mm: float | None = None, source=None, input_name: str = "mouse"):
        self.backend = backend
        self.haptic = haptic
        self.playlist = playlist
        self.index = index
        self.scene = scene
        self.load = load
        self.screenshot_dir = screenshot_dir
        self.link_name = link_name
        self.follow_mm = follow_mm
        self.source = source
        self.input_name = input_name
        self.compositor = Compositor(backend.ctx, scene, backend.size)
        self.overlay = OverlayState()
        self.force_n = scene.device.normal_force_n
        self.renderer = haptic.render_override
        self.touching = False
        self.hover_px: tuple[float, float] | None = None
        self._presses: list[bool] = []  # left button presses (True) and releases since the frame
        self._sent: tuple | None = None  # (pointer px, force N) of the last mouse sample
        self.show_scope = True
        self.outlines = False
        self.error: str | None = None
        self.status: dict = {}
        self.quit = False
        self.screenshot_pending = False
        self.screenshots: list[Path] = []
        self.frames = 0
        self.frame_seconds = 0.0
        self._mtime = _mtime(self.playlist[self.index])
        self._set_envelope(scene, haptic.pipeline.actuation)
        self._next_poll = 0.0
        self._events = open(events_path, "a", encoding="utf-8") if events_path else None
        if self._events is not None and self._events.tell() == 0:
            self._events.write("t_s,event,detail\n")
        backend.on_cursor = self.on_cursor
        backend.on_button = self.on_button
        backend.on_scroll = self.on_scroll
        backend.on_key = self.on_key

    # -- input --------------------------------------------------------------------------

    def log(self, event: str, detail: str = "") -> None:
        if self._events is not None:
            quoted = '"' + detail.replace('"', "'").replace("\n", " ") + '"'
            self._events.write(f"{self.haptic.now():.6f},{event},{quoted}\n")
            self._events.flush()

    def _mm(self) -> tuple[float, float]:
        x, y = self.compositor.viewport.to_mm(*self.hover_px)
        return float(x), float(y)

    def _mouse_touch(self, event: str) -> None:
        """The mouse's finger 0 (and in follow mode finger 1, ``follow_mm`` to its right)."""
        x, y = self._mm()
        code, t = EVENTS[event], self.haptic.now()  # one stamp: the fingers move as one
        self.haptic.touch_at(t, 0, x, y, self.force_n, code)
        if self.follow_mm is not None:
            self.haptic.touch_at(t, 1, x + self.follow_mm, y, self.force_n, code)
        self._sent = (self.hover_px, self.force_n)

    # The callbacks only note what happened; flush_mouse() turns it into at most one
    # sample per finger and frame, stamped then. Stamping each event as it is handled
    # would crowd a frame's worth of motion into microseconds when the window is late
    # (events arrive in bursts), and the tracker would see the finger fly.

    def on_cursor(self, x_px: float, y_px: float) -> None:
        self.hover_px = (x_px, y_px)

    def on_button(self, pressed: bool) -> None:
        if self.hover_px is None:
            self.hover_px = self.backend.cursor_px()
        self._presses.append(pressed)

    def on_scroll(self, dy: float) -> None:
        self.set_force(self.force_n + FORCE_STEP_N * dy)

    def set_force(self, force_n: float) -> None:
        self.force_n = float(np.clip(force_n, *FORCE_RANGE_N))

    def flush_mouse(self) -> None:
        """The mouse's touches since the last call: presses and releases in order, then a
        move if the pointer or the force changed."""
        presses, self._presses = self._presses, []
        if self.source is not None:
            return  # a touch screen drives the fingers; its emulated mouse must not add one
        for pressed in presses:
            if pressed != self.touching:
                self.touching = pressed
                self._mouse_touch("down" if pressed else "up")
        if self.touching and self._sent != (self.hover_px, self.force_n):
            self._mouse_touch("move")

    def poll_source(self) -> int:
        """Hand the touch source's new samples to the haptic thread, in mm on its clock,
        at the current normal force (TUIO cursors carry none); returns how many."""
        if self.source is None:
            return 0
        try:
            samples = self.source.poll()
        except (OSError, ValueError) as exc:  # unplugged, or a device speaking nonsense
            self.error = f"touch input {self.input_name} stopped, the mouse touches now: {exc}"
            self.log("input-failed", str(exc))
            self.source.close()
            self.source = None
            return 0
        if samples:
            shift = self.haptic.now() - time.monotonic()
            d = self.scene.display
            for s in samples:
                self.haptic.touch_at(s.t_s + shift, s.finger, s.x_mm * d.width_mm,
                                     s.y_mm * d.height_mm, self.force_n, s.event)
        return len(samples)

    def on_key(self, name: str, shift: bool) -> None:
        if name == "space":
            if self.haptic.estop.is_set():
                self.log("estop-release")  # logged first: output may resume right after
                self.haptic.estop.clear()
            else:
                self.haptic.estop.set()
                self.log("estop")
        elif name in ("q", "escape"):
            self.quit = True
        elif name in ("n", "b", "tab", "page_down", "page_up"):
            step = -1 if name in ("b", "page_up") or (name == "tab" and shift) else 1
            self.select((self.index + step) % len(self.playlist))
        elif name == "r":
            nxt = RENDERER_CYCLE[(RENDERER_CYCLE.index(self.renderer) + 1) % len(RENDERER_CYCLE)]
            self._apply(self.scene, nxt, "renderer", nxt or "file")
        elif name == "s":
            self.show_scope = not self.show_scope
        elif name == "o":
            self.outlines = not self.outlines
            self.compositor.set_scene(self.scene, outlines=self.outlines)
        elif name in ("p", "f12"):
            self.screenshot_pending = True
        elif name == "up":
            self.set_force(self.force_n + FORCE_STEP_N)
        elif name == "down":
            self.set_force(self.force_n - FORCE_STEP_N)

    # -- scenes -------------------------------------------------------------------------

    def _apply(self, scene, renderer, event: str, detail: str) -> bool:
        """Hand ``scene`` with ``renderer`` to the haptic thread and redraw; on error keep
        the current one and show why."""
        try:
            pipeline = self.haptic.switch(scene, renderer)
        except (ValueError, OSError, ModuleNotFoundError) as exc:
            self.error = f"{event} failed (keeping {self.scene.name}, {self.renderer or 'file'}): {exc}"
            self.log(f"{event}-failed", str(exc))
            return False
        self.log(event, detail)  # before redrawing the scene image
        if scene is not self.scene:
            self.compositor.set_scene(scene)
            self.overlay.clear()
            self._set_envelope(scene, pipeline.actuation)
        self.scene, self.renderer, self.error = scene, renderer, None
        return True

    def select(self, index: int) -> None:
        path = self.playlist[index]
        try:
            scene = self.load(path)
        except (ValueError, OSError) as exc:
            self.error = f"cannot load {path.name} (keeping {self.scene.name}): {exc}"
            self.log("load-failed", str(exc))
            return
        if self._apply(scene, self.renderer, "scene", scene.name):
            self.index = index
            self._mtime = _mtime(path)

    def check_reload(self, now: float) -> None:
        if now < self._next_poll:
            return
        self._next_poll = now + RELOAD_POLL_S
        path = self.playlist[self.index]
        mtime = _mtime(path)
        if mtime is None or mtime == self._mtime:
            return
        self._mtime = mtime
        try:
            scene = self.load(path)
        except (ValueError, OSError) as exc:
            self.error = f"reload failed, keeping the last good scene: {exc}"
            self.log("reload-failed", str(exc))
            return
        self._apply(scene, self.renderer, "reload", scene.name)

    def _set_envelope(self, scene, actuation) -> None:
        self.envelope = modal_envelope(scene, actuation)
        self.envelope_now = None
        self.envelope_scale_um = scene.device.amplitude_limit_um
        self._next_envelope = 0.0

    def update_envelope(self, now: float) -> None:
        """A modal device's |W| from the latest commands, every ENVELOPE_S; its scale
        grows (never shrinks, within a scene) to the largest |W| seen."""
        if self.envelope is None or now < self._next_envelope:
            return
        self._next_envelope = now + ENVELOPE_S
        self.envelope_now = self.envelope.at(self.overlay.commands, self.overlay.current())
        self.envelope_scale_um = max(self.envelope_scale_um, self.envelope_now.peak_um)

    # -- frames -------------------------------------------------------------------------

    def drain(self) -> None:
        while True:
            try:
                snap = self.haptic.snapshots.get_nowait()
            except queue.Empty:
                return
            self.overlay.add(snap.record)
            self.status = snap.status

    def status_lines(self) -> tuple[str, ...]:
        st = self.status
        link = st.get("link", {})
        state = link.get("state", self.link_name)
        frames = f", {link['frames_sent']} frames sent" if "frames_sent" in link else ""
        first = (f"{self.scene.name} ({self.index + 1}/{len(self.playlist)}) | renderer: "
                 f"{self.renderer or 'file'} | force {self.force_n:.2f} N | link: {state}{frames} | "
                 f"clamps {st.get('clamps', 0)} | deadline misses {st.get('deadline_misses', 0)}")
        fingers = len(self.overlay.current())
        touch = ("drag: touch" if self.follow_mm is None
                 else f"drag: two fingers, the second {self.follow_mm:g} mm to the right")
        if self.source is not None:
            touch = "touch the screen"
        return (first, f"input: {self.input_name} ({touch}; {fingers} touching)", KEYS_HELP)

    def draw(self) -> None:
        self.compositor.resize(self.backend.size)
        self.backend.use()
        if self.haptic.estop.is_set():
            banner, kind = "EMERGENCY STOP: output is 0 um. SPACE resumes.", "stop"
        else:
            banner, kind = self.error, "error"
        hover = self._mm() if self.hover_px is not None and not self.touching else None
        self.compositor.draw(FrameView(
            overlay=self.overlay, hover_mm=hover, show_scope=self.show_scope,
            amplitude_max_um=self.scene.device.amplitude_limit_um, status=self.status_lines(),
            banner=banner, banner_kind=kind, envelope=self.envelope_now,
            envelope_scale_um=self.envelope_scale_um))

    def screenshot(self) -> Path:
        self.screenshot_dir.mkdir(parents=True, exist_ok=True)
        path = self.screenshot_dir / f"frictex-{self.scene.name}-{len(self.screenshots):03d}.png"
        Image.fromarray(self.backend.read_rgb()).save(path)
        self.screenshots.append(path)
        self.log("screenshot", str(path))
        return path

    def run(self, duration_s: float | None = None, clock=time.perf_counter) -> None:
        start = clock()
        while not (self.quit or self.backend.should_close):
            t = clock()
            if duration_s is not None and t - start >= duration_s:
                break
            if self.haptic.error is not None:
                raise RuntimeError(f"haptic output stopped: {self.haptic.error}")
            self.backend.poll()
            self.flush_mouse()
            self.poll_source()
            self.check_reload(t)
            self.drain()
            self.update_envelope(t)
            self.draw()
            if self.screenshot_pending:
                self.screenshot_pending = False
                print(f"screenshot: {self.screenshot()}")
            self.backend.swap()
            if self.frames == 0:
                self.log("first-frame", self.scene.name)
            self.frames += 1
            spent = clock() - t
            self.frame_seconds += spent
            if spent < FRAME_S:
                time.sleep(FRAME_S - spent)

    def close(self) -> None:
        """Release the GL objects, the touch source (the loop owns it) and the events file."""
        if self.source is not None:
            self.source.close()
            self.source = None
        self.compositor.release()
        if self._events is not None:
            self._events.close()
