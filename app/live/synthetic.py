"""A synthesized hand on an injected-input window: the demo without a person.

:class:`SyntheticStroke` moves a window's pointer (``rendering.visual.headless.
HeadlessWindow``: ``move``, ``press``, ``release``, ``key``) along a human-like stroke
(``rendering.input.trace_synth.make_motion("human")``: minimum-jerk strokes with
pauses; on a display too thin for one, :data:`HUMAN_MARGIN_MM` twice or less across,
as a beam's: back and forth along its length through its middle) at its own pace on
the wall clock, the left button held throughout, then presses Q. The demo loop takes these events exactly as it takes a real mouse's, so
``frictex demo --headless`` runs the demo loop itself, on synthetic input. The stroke
is made :data:`PIECE_S` at a time, each piece from where the last one ended, so that a
long ``--duration`` costs no more to start, or in memory, than a short one.
"""

from __future__ import annotations

import math
import threading
import time

from frictex.rendering.input.trace_synth import HUMAN_MARGIN_MM, make_motion

STROKE_S = 3.0  # how long the hand strokes (s)
SPEED_MM_S = 60.0  # its typical peak speed (mm/s)
EVENTS_HZ = 120.0  # pointer positions per second, as a mouse reports them
LIFT_WAIT_S = 30.0  # longest wait for the lift to reach the output before quitting (s)
#: the stroke is made this long at a time (s): a few ms to make (a whole 1e6 s stroke
#: took 21 s and 188 MB before its first position)
PIECE_S = 60.0


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
        self.area_mm, self.speed_mm_s, self.seed = area_mm, speed_mm_s, seed
        self.duration_s = float(duration_s)
        self.piece = 0  # which PIECE_S of the stroke ``motion`` is
        # a back-and-forth costs nothing to make, however long: made once, whole
        self.thin = min(area_mm) <= 2 * HUMAN_MARGIN_MM
        self.motion = self._along_length() if self.thin else self._made(0, None)
        self.clock = clock
        self.sleep = sleep
        self.lifted = lifted
        self.positions = 0  # pointer positions sent
        self.stroked_s = 0.0  # how far along the stroke the last position sent was (s)
        self._quit = threading.Event()

    def _made(self, piece: int, start: tuple[float, float] | None):
        """Piece ``piece`` of the stroke (its own seed), from ``start`` (x, y mm; None: the
        motion's own start), :data:`PIECE_S` long or what is left of ``duration_s``."""
        x0, y0 = (None, None) if start is None else start
        return make_motion("human", speed_mm_s=self.speed_mm_s,
                           duration_s=min(PIECE_S, self.duration_s - piece * PIECE_S),
                           x0_mm=x0, y0_mm=y0, area_mm=self.area_mm, seed=self.seed + piece)

    def _along_length(self):
        """The whole stroke on a thin display: back and forth along its longer side through
        the middle of the other, :data:`HUMAN_MARGIN_MM` (at most a quarter of the side)
        from its ends."""
        width, height = self.area_mm
        along_x = width >= height
        side = width if along_x else height
        margin = min(HUMAN_MARGIN_MM, side / 4)
        x0, y0 = (margin, height / 2) if along_x else (width / 2, margin)
        return make_motion("back-and-forth", speed_mm_s=self.speed_mm_s,
                           duration_s=self.duration_s, x0_mm=x0, y0_mm=y0,
                           angle_deg=0.0 if along_x else 90.0, length_mm=side - 2 * margin)

    def _position(self, t: float) -> tuple[float, float]:
        """Where the stroke is at ``t`` (s from its start; mm), made piece by piece."""
        if self.thin:
            return self.motion.position(t)
        piece = min(int(t // PIECE_S), math.ceil(self.duration_s / PIECE_S) - 1)
        while self.piece < piece:
            end = self.motion.position(self.motion.duration_s)
            self.piece += 1
            self.motion = self._made(self.piece, (float(end[0]), float(end[1])))
        return self.motion.position(t - self.piece * PIECE_S)

    def _move(self, t: float) -> None:
        x, y = self._position(t)
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
