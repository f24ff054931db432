"""The demo's window loop (main thread): input -> haptic thread, snapshots -> frames.

Backend-neutral: it drives any ``rendering.visual.context`` backend that has input
callbacks, ``poll()``, ``swap()`` and ``should_close`` (the glfw window). The mouse is
finger 0 (left button held = touching; the wheel or up/down set the normal force).
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

from rendering.visual.compositor import Compositor, FrameView
from rendering.visual.overlay import OverlayState

RENDERER_CYCLE = (None, "sho", "sht", "hybrid")
FORCE_STEP_N = 0.05
FORCE_RANGE_N = (0.05, 2.0)
RELOAD_POLL_S = 0.25
FRAME_S = 1.0 / 60.0
KEYS_HELP = ("drag: touch | wheel, up/down: force | N/B: scene | R: renderer | S: scope | "
             "O: outlines | P: screenshot | SPACE: emergency stop | Q: quit")


def _mtime(path: Path) -> float | None:
    try:
        return path.stat().st_mtime_ns
    except OSError:
        return None


class DemoLoop:
    """See the module docstring. ``load(path) -> Scene`` raises ValueError on a bad file."""

    def __init__(self, backend, haptic, playlist: list[Path], index: int, scene, load,
                 screenshot_dir: Path, events_path: Path | None = None, link_name: str = "none"):
        self.backend = backend
        self.haptic = haptic
        self.playlist = playlist
        self.index = index
        self.scene = scene
        self.load = load
        self.screenshot_dir = screenshot_dir
        self.link_name = link_name
        self.compositor = Compositor(backend.ctx, scene, backend.size)
        self.overlay = OverlayState()
        self.force_n = scene.device.normal_force_n
        self.renderer = haptic.render_override
        self.touching = False
        self.hover_px: tuple[float, float] | None = None
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

    def on_cursor(self, x_px: float, y_px: float) -> None:
        self.hover_px = (x_px, y_px)
        if self.touching:
            self.haptic.touch(0, *self._mm(), self.force_n, "move")

    def on_button(self, pressed: bool) -> None:
        if self.hover_px is None:
            self.hover_px = self.backend.cursor_px()
        if pressed and not self.touching:
            self.touching = True
            self.haptic.touch(0, *self._mm(), self.force_n, "down")
        elif not pressed and self.touching:
            self.touching = False
            self.haptic.touch(0, *self._mm(), self.force_n, "up")

    def on_scroll(self, dy: float) -> None:
        self.set_force(self.force_n + FORCE_STEP_N * dy)

    def set_force(self, force_n: float) -> None:
        self.force_n = float(np.clip(force_n, *FORCE_RANGE_N))
        if self.touching and self.hover_px is not None:
            self.haptic.touch(0, *self._mm(), self.force_n, "move")

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
            self.haptic.switch(scene, renderer)
        except (ValueError, OSError, ModuleNotFoundError) as exc:
            self.error = f"{event} failed (keeping {self.scene.name}, {self.renderer or 'file'}): {exc}"
            self.log(f"{event}-failed", str(exc))
            return False
        self.log(event, detail)  # before redrawing the scene image, which takes a while
        if scene is not self.scene:
            self.compositor.set_scene(scene)
            self.overlay.clear()
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
        return (first, KEYS_HELP)

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
            banner=banner, banner_kind=kind))

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
                raise RuntimeError(f"haptic thread stopped: {self.haptic.error!r}")
            self.backend.poll()
            self.check_reload(t)
            self.drain()
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
        self.compositor.release()
        if self._events is not None:
            self._events.close()
