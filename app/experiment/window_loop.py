"""The demo's window loop hosting an experiment session (``window_presenter``).

:class:`ExperimentLoop` is the demo loop (``app.live.demo_loop.DemoLoop``: the input
thread hands the mouse to the haptic side, the render thread draws) with what a session
changes:

- what is drawn: the screen the presenter sets (``screen``, an
  ``rendering.visual.experiment_view.ExperimentView``, replaced whole) over the scene;
  the scene's picture is shown only where the protocol asks for it (``show_scene``):
  by default a uniform field (:data:`FIELD_RGBA`) takes its place on every screen (a
  message's cover leaves the strip of the status line uncovered), with no trail and no
  hover ring, so that nothing but touch tells the stimuli apart;
  the buttons drawn (``buttons``, replaced whole each frame) are what a press hits,
  once they are the current screen's (a press before its first frame hits nothing);
- the mouse touches only while an interval accepts touches (``accept_touch``); a press
  on a button is an answer, never a touch; a button held from before (across the end of
  the interval before) touches once touches are accepted, at the cursor, as the
  instructions ask for no lift between intervals; the touches sent during an interval are
  recorded (:meth:`start_recording`, :meth:`stop_recording`) exactly as the haptic side
  received them (haptic clock);
- the window's title stays as it was opened (:class:`_FixedTitle`), never a stimulus's
  name;
- keys: SPACE (emergency stop), up/down (force) and P (screenshot) act as in the demo;
  every other key is queued to the presenter (``answers``), Q included: the demo's
  keys that would change the scene or open the layer panel do nothing here;
- scene switches and reconnecting the output are asked of the render thread
  (``requests``), which owns the haptic side's lifetime;
- a haptic side that stops (a device lost) no longer ends the loop: ``lost`` says
  why, and the presenter pauses the session (:meth:`check_output`).

Threads: as THREADS.md says for the demo, plus the ``frictex-session`` thread (the
runner and the presenter), which only reads ``answers`` and ``lost`` and sets
``screen``, ``accept_touch`` and the recording.
"""

from __future__ import annotations

import queue
import threading
import time

from frictex.app.live.demo_loop import DemoLoop, output_stopped
from frictex.app.live.haptic_thread import EVENTS
from frictex.rendering.input.trace_file import UP
from frictex.rendering.visual.compositor import FrameView
from frictex.rendering.visual.experiment_view import ExperimentView, draw_experiment, hit
from frictex.textures.loader import load_scene

#: keys the demo loop handles itself in a session (the emergency stop, the force)
DEMO_KEYS = ("space", "up", "down")
SCREENSHOT_KEYS = ("p", "f12")
ANSWER_POLL_S = 0.05  # how often a wait for the render thread looks at the window closing
#: what an interval shows instead of the stimulus's picture (a mid grey)
FIELD_RGBA = (0.5, 0.5, 0.5, 1.0)


class _FixedTitle:
    """The window ``backend`` with its title kept as it was opened ("frictex experiment:
    PROTOCOL"): the demo loop names the scene shown in the title, and a stimulus's name
    (``period_mm=5.5``) there would tell the participant what is felt. Every other
    attribute is the backend's."""

    def __init__(self, backend):
        object.__setattr__(self, "_backend", backend)

    def __getattr__(self, name: str):
        return getattr(self._backend, name)

    def __setattr__(self, name: str, value) -> None:
        setattr(self._backend, name, value)

    def set_title(self, title: str) -> None:
        """Ignored: the title stays as the window was opened."""


class ExperimentLoop(DemoLoop):
    """See the module docstring. ``restart(scene) -> (haptic, finish)`` starts a new
    haptic side on ``scene`` (reconnecting after a lost device); ``finish`` is the
    current haptic side's (``app.live.haptic_setup.open_haptic``'s)."""

    def __init__(self, backend, haptic, finish, scene, screenshot_dir, events_path,
                 restart, link_name: str = "none"):
        super().__init__(_FixedTitle(backend), haptic, [scene.source], 0, scene, load_scene,
                         screenshot_dir,
                         events_path=events_path, link_name=link_name)
        self.finish = finish
        self.restart = restart
        self.show_scope = False
        self.screen = ExperimentView("message")
        self.buttons: tuple = ()
        self._buttons_of: ExperimentView | None = None  # the screen they were drawn for
        self.answers: queue.SimpleQueue = queue.SimpleQueue()  # ("key" | "button", value, t_s)
        self.requests: queue.SimpleQueue = queue.SimpleQueue()  # (what, args, reply queue)
        self.accept_touch = False
        self.held = False  # the left button is down, not on an answer's button (input thread)
        self.show_scene = False  # the protocol's [presentation] show_scene
        self.lost: str | None = None
        self._recording: list | None = None
        self._touched_at: float | None = None  # the recording's first down (s, haptic clock)
        self._rec_lock = threading.Lock()

    # -- input thread -------------------------------------------------------------------

    def on_key(self, name: str, shift: bool) -> None:
        if name in DEMO_KEYS:
            super().on_key(name, shift)
        elif name in SCREENSHOT_KEYS:
            self._keys.put((name, shift))
        else:
            self.answers.put(("key", name, self.haptic.now()))

    def on_button(self, pressed: bool) -> None:
        if self.hover_px is None:
            self.hover_px = self.backend.cursor_px()
        answered = (pressed and not self.touching and self._buttons_of is self.screen
                    and self._answer(hit(self.buttons, *self.hover_px)))
        self.held = pressed and not answered
        if answered or not (self.touching or (pressed and self.accept_touch)):
            return  # a release after a button, or a press while nothing is explored
        super().on_button(pressed)

    def _answer(self, button) -> bool:
        """Queue the click on ``button`` (None: the press hit no button) as an answer."""
        if button is not None:
            self.answers.put(("button", button.value, self.haptic.now()))
        return button is not None

    def flush_mouse(self) -> None:
        if self.held and self.accept_touch and not self.touching:
            # pressed while nothing was explored: the press the demo's touch starts at
            self._pending.insert(0, (True, self._pending[0][1] if self._pending else self.hover_px))
        super().flush_mouse()
        if self.touching and not self.accept_touch:  # the interval ended under the finger
            self._pending = []
            self.touching = False
            self._mouse_touch("up", self.hover_px, self.haptic.now())

    def _mouse_touch(self, event: str, px, t_s: float) -> None:
        super()._mouse_touch(event, px, t_s)
        x, y = self._mm(px)
        with self._rec_lock:
            if self._recording is not None:
                # as the haptic queue takes them (touch_at): a stamp never goes back, though
                # an event stamped before the last one recorded may reach here after it
                last = self._recording[-1][0] if self._recording else 0.0
                stamp = max(min(t_s, self.haptic.now()), last)
                self._recording.append((stamp, x, y, self.force_n, EVENTS[event]))
                if event == "down" and self._touched_at is None:
                    self._touched_at = stamp

    # -- session thread -----------------------------------------------------------------

    def start_recording(self) -> None:
        """Record the touches sent from now on."""
        with self._rec_lock:
            self._recording, self._touched_at = [], None

    def touched_at(self) -> float | None:
        """When the first touch since :meth:`start_recording` began (s, haptic clock), or
        None: not touched yet."""
        with self._rec_lock:
            return self._touched_at

    def stop_recording(self) -> list[tuple]:
        """The touches sent since :meth:`start_recording`: (t_s haptic clock, x_mm, y_mm,
        force_n, event code), ending with a lift (added at the last position now if the
        finger was still down)."""
        with self._rec_lock:
            samples, self._recording = self._recording or [], None
        if samples and samples[-1][4] != UP:
            t, x, y, f, _ = samples[-1]
            samples.append((max(t, self.haptic.now()), x, y, f, UP))
        return samples

    def ask(self, what: str, *args, cancel: threading.Event, timeout_s: float):
        """Ask the render thread to ``switch`` (args: scene, text) or ``reconnect``
        (args: scene) and wait for it; returns its error message or None (or a message
        once ``cancel`` is set: the window closed). Raises TimeoutError if the render
        thread does not answer within ``timeout_s``."""
        reply: queue.SimpleQueue = queue.SimpleQueue()
        self.requests.put((what, args, reply))
        deadline = time.monotonic() + timeout_s
        while not cancel.is_set():
            try:
                return reply.get(timeout=ANSWER_POLL_S)
            except queue.Empty:
                if time.monotonic() > deadline:
                    raise TimeoutError(f"the window did not {what} within {timeout_s:g} s"
                                       ) from None
        return "the window was closed"

    # -- render thread ------------------------------------------------------------------

    def check_output(self) -> None:
        """A haptic side that stopped pauses the session (``lost``) instead of ending
        the window."""
        if self.lost is None and (error := self.haptic.error) is not None:
            self.lost = str(output_stopped(error))
            self.log("output-lost", self.lost)

    def check_reload(self, now: float) -> None:
        """A session's scenes are fixed by its protocol: no file is reloaded."""

    def _serve(self) -> None:
        while True:
            try:
                what, args, reply = self.requests.get_nowait()
            except queue.Empty:
                return
            if what == "switch":
                scene, text = args
                ok = self._apply(scene, None, "stimulus", scene.name, text)
                reply.put(None if ok else (self.error or f"cannot show {scene.name}"))
            elif what == "reconnect":
                reply.put(self._reconnect(*args))

    def _reconnect(self, scene) -> str | None:
        """Stop the haptic side that stopped and start a new one on ``scene``."""
        try:
            self.finish()
        except OSError as exc:  # the child ended without its report: nothing more to keep
            self.log("output-finish-failed", str(exc))
        try:
            haptic, finish = self.restart(scene)
        except (OSError, ValueError) as exc:
            self.log("reconnect-failed", str(exc))
            return str(exc)
        self.haptic, self.finish = haptic, finish
        self.scene, self.renderer, self.lost, self.error = scene, None, None, None
        self._applied_seen = 0
        self.compositor.set_scene(scene)
        self.overlay.clear()
        self._set_envelope(scene, haptic.pipeline.actuation)
        self.log("reconnect", scene.name)
        return None

    def frame(self, now: float) -> None:
        self._serve()
        super().frame(now)

    def screenshot_stem(self) -> str:
        """The start of a screenshot's file name: the session's, never the stimulus's (a
        shared screenshot must not say which stimulus a trial showed); they are
        numbered in the order taken."""
        return "frictex-experiment"

    def draw(self) -> None:
        self.compositor.resize(self.backend.size)
        self.backend.use()
        screen = self.screen
        interval = screen.phase == "interval"
        if self.haptic.estop.is_set():
            banner, kind = "EMERGENCY STOP: output is 0 um. SPACE resumes.", "stop"
        else:
            banner, kind = None, "error"
        shown = interval and self.show_scene
        hover = (self._mm(self.hover_px) if shown and self.hover_px is not None
                 and not self.touching else None)
        self.compositor.draw(FrameView(
            overlay=self.overlay if shown else None, hover_mm=hover, show_scope=False,
            amplitude_max_um=self.scene.device.amplitude_limit_um,
            status=(screen.progress,) if screen.progress else (), banner=banner,
            banner_kind=kind, field_rgba=None if self.show_scene else FIELD_RGBA))
        self.buttons, self._buttons_of = draw_experiment(self.compositor, screen), screen
