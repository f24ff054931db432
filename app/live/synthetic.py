"""A synthesized hand on an injected-input window: the demo without a person.

:class:`SyntheticStroke` moves a window's pointer (``rendering.visual.headless.
HeadlessWindow``: ``move``, ``press``, ``release``, ``key``) along a human-like stroke
(``rendering.input.trace_synth.make_motion("human")``: minimum-jerk strokes with
pauses) at its own pace on the wall clock, the left button held throughout, then
presses Q. The demo loop takes these events exactly as it takes a real mouse's, so
``frictex demo --headless`` runs the demo loop itself, on synthetic input.
"""

from __future__ import annotations

import threading
import time

from frictex.rendering.input.trace_synth import make_motion

STROKE_S = 3.0  # how long the hand strokes (s)
SPEED_MM_S = 60.0  # its typical peak speed (mm/s)
EVENTS_HZ = 120.0  # pointer positions per second, as a mouse reports them
LIFT_WAIT_S = 30.0  # longest wait for the lift to reach the output before quitting (s)


class SyntheticStroke(threading.Thread):
    """Drives ``window`` along a human-like stroke over the scene, then quits.

    Parameters
    ----------
    window : a window taking injected input (``move(x_px, y_px)``, ``press()``,
        ``release()``, ``key(name)``).
    to_px : callable (x_mm, y_mm) -> (x_px, y_px), the scene's viewport in the window.
    area_mm : (width, height) of the scene's display (mm); the stroke stays inside.
    duration_s, speed_mm_s, seed : the stroke's length (s), typical peak speed (mm/s)
        and draw.
    lifted : callable, True once the lift has reached the output (the demo loop's
        ``fingers_down`` is empty): Q waits for it, at most ``LIFT_WAIT_S``, so that the
        run's record ends with the finger up. None: Q follows the release at once.
    clock, sleep : the wall clock (s) and how to wait on it.
    """

    def __init__(self, window, to_px, area_mm: tuple[float, float], duration_s: float = STROKE_S,
                 speed_mm_s: float = SPEED_MM_S, seed: int = 0, lifted=None,
                 clock=time.perf_counter, sleep=time.sleep):
        super().__init__(name="frictex-synthetic-hand", daemon=True)
        self.window = window
        self.to_px = to_px
        self.motion = make_motion("human", speed_mm_s=speed_mm_s, duration_s=duration_s,
                                  area_mm=area_mm, seed=seed)
        self.duration_s = float(duration_s)
        self.clock = clock
        self.sleep = sleep
        self.lifted = lifted
        self.positions = 0  # pointer positions sent
        self.stroked_s = 0.0  # how far along the stroke the last position sent was (s)
        self._quit = threading.Event()

    def _move(self, t: float) -> None:
        x, y = self.motion.position(t)
        self.window.move(*self.to_px(float(x), float(y)))
        self.positions += 1
        self.stroked_s = t

    def run(self) -> None:
        start = self.clock()
        self._move(0.0)
        self.window.press()
        step = 1.0 / EVENTS_HZ
        k = 1
        while not self._quit.is_set():
            t = min(k * step, self.duration_s)
            wait = start + t - self.clock()
            if wait > 0.0:
                self.sleep(wait)
            self._move(t)
            if t >= self.duration_s:
                break
            k += 1
        self.window.release()
        deadline = self.clock() + LIFT_WAIT_S
        while (self.lifted is not None and not self._quit.is_set() and not self.lifted()
               and self.clock() < deadline):
            self._quit.wait(0.01)
        self.window.key("q")

    def stop(self, timeout_s: float = 5.0) -> None:
        """Stop early (the button is released and Q pressed, the lift not waited for) and
        wait for the thread to end, at most ``timeout_s`` (s): the window it drives is
        closed next."""
        self._quit.set()
        if self.is_alive():
            self.join(timeout_s)
