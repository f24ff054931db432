"""A touch screen (TUIO over UDP, a Linux evdev device) feeding the haptic side from a
thread of its own, sample by sample as they arrive, so that neither the window's frames
nor its input handling delay a finger.

A source is an ``app.live.inputs.TouchSource`` (opened by its ``--input`` kind in
``app.live.inputs.INPUTS``): ``wait(timeout_s)`` (return when samples may be ready, or
after ``timeout_s`` s), ``poll() -> list[TouchSample]`` (never blocking; positions
normalised to 0..1 of the active area, stamped on ``time.monotonic``: TUIO at arrival,
evdev by the kernel), ``close()``, and optionally ``counters() -> dict`` (what it
received and refused, for the demo's summary). The pump maps the positions to mm of the scene
shown now and moves the stamps to the haptic output clock; the haptic side runs a
sample from the first block boundary after it is queued (``app.live.haptic_thread``).
A sender may send faster than blocks are played (a flood of frames): the pump forwards at
most once a block, every DOWN and UP in order but of a finger's MOVEs since the last
forward only the latest, so a flood cannot make the haptic side play touches late.
In the demo's default process mode the pump runs in the haptic child process, which
the window's GL calls cannot hold up; in thread mode, beside the haptic thread.
"""

from __future__ import annotations

import threading
import time

from frictex.rendering.input.trace_file import MOVE, UP

WAIT_S = 0.05  # longest wait for the source before looking whether to stop (s)


class TouchPump(threading.Thread):
    """Moves a touch source's samples into a haptic side's touch queue as they arrive.

    Parameters
    ----------
    source : see the module docstring; the pump owns it and closes it when it stops.
    haptic : the haptic side's touch input (``now()`` s, ``touch_at``).
    display : callable returning the ``Display`` of the scene shown now (mm).
    force_n : callable returning the normal force (N) every sample gets.
    clock : the sources' clock (s), ``time.monotonic``.

    A source that fails (unplugged, speaking nonsense) is closed and the reason kept
    for :meth:`take_error`; the samples it gave before are forwarded, then every finger
    still down is lifted where it was last (a finger the source can no longer report
    would otherwise stay pressed, rendered, until the demo ends); the pump ends.
    """

    def __init__(self, source, haptic, display, force_n, clock=time.monotonic):
        super().__init__(name="frictex-touch", daemon=True)
        self.source = source
        self.haptic = haptic
        self.display = display
        self.force_n = force_n
        self.clock = clock
        self.samples = 0
        self.coalesced = 0  # MOVEs not forwarded: a later MOVE of their finger replaced them
        self._held: list = []  # the samples since the last forward (None: replaced)
        self._moving: dict = {}  # finger -> index in _held of its MOVE that a MOVE replaces
        self._down: dict = {}  # finger -> its last sample forwarded, while down
        self.error: str | None = None
        self._reported = False
        self._quit = threading.Event()

    def forward(self, samples) -> int:
        """Queue ``samples`` on the haptic side in mm, on its clock; returns how many."""
        if not samples:
            return 0
        shift = self.haptic.now() - self.clock()
        d = self.display()
        force = float(self.force_n())
        for s in samples:
            self.haptic.touch_at(s.t_s + shift, s.finger, s.x_mm * d.width_mm,
                                 s.y_mm * d.height_mm, force, s.event)
            if s.event == UP:
                self._down.pop(s.finger, None)
            else:
                self._down[s.finger] = s
        self.samples += len(samples)
        return len(samples)

    def hold(self, samples) -> None:
        """Keep ``samples`` for the next forward: every DOWN and UP, and of a finger's MOVEs
        since its last DOWN or UP only the latest (the ones it replaces are counted in
        ``coalesced``); the order of the samples kept is kept."""
        for s in samples:
            at = self._moving.pop(s.finger, None)
            if s.event == MOVE:
                if at is not None:
                    self._held[at] = None
                    self.coalesced += 1
                self._moving[s.finger] = len(self._held)
            self._held.append(s)

    def release(self) -> int:
        """Forward the samples held (:meth:`hold`); returns how many."""
        held = [s for s in self._held if s is not None]
        self._held.clear()
        self._moving.clear()
        return self.forward(held)

    def run(self) -> None:
        every_s = self.haptic.block_s  # at most one forward a block (s)
        due = float("-inf")  # the source clock's time the next forward may come (s)
        try:
            while not self._quit.is_set():
                self.source.wait(max(due - self.clock(), 0.0) if self._held else WAIT_S)
                self.hold(self.source.poll())
                now = self.clock()
                if self._held and now >= due:
                    self.release()
                    due = now + every_s
            self.release()
        except (OSError, ValueError) as exc:
            self.error = str(exc)
            self.release()
            now = self.clock()
            self.forward([s._replace(t_s=max(now, s.t_s), event=UP) for s in self._down.values()])
        finally:
            self.source.close()

    def counters(self) -> dict:
        """The samples forwarded and coalesced (MOVEs replaced by a later one before a
        forward), and the source's own ``counters()`` if it has them."""
        counts = getattr(self.source, "counters", None)
        return {"samples": self.samples, "coalesced": self.coalesced, **(counts() if counts is not None else {})}

    def take_error(self) -> str | None:
        """Why the source stopped, the first time it is asked; else None."""
        if self.error is None or self._reported:
            return None
        self._reported = True
        return self.error

    def stop(self) -> None:
        """Stop the thread (it closes the source); a pump never started closes it here."""
        self._quit.set()
        if self.is_alive():
            self.join()
        elif self.ident is None:
            self.source.close()
