"""A session with a person: the presenter of the demo's window (participant ``window``).

``frictex experiment PROTOCOL --participant window --out DIR [--device sim|PORT]``
opens the demo's window on the live haptic pipeline (the same haptic side as
``frictex demo``, on any ``--device``) and runs the session in it:

- an instructions screen from the protocol (its name, description, question, how to
  answer, how many practice trials), then the trials, practice first and marked as
  such on the progress line (the frame's top line, with the trial's place in the
  session), a break screen where the protocol asks for one;
- each interval plays its scene under the mouse (left button held = touching) for
  the protocol's exploration time, counted from the interval's first touch (a button
  held from the interval before touches at once); an interval not touched within
  :data:`FIRST_TOUCH_WAIT_S` ends there, so no interval waits longer than that and its
  exploration time together. The window shows a uniform field (or, with
  ``[presentation] show_scene = true``, the scene's picture: visuo-haptic stimuli); with ``exploration = "free"`` the
  participant moves on before that with Enter (or the right arrow) or the Next
  button. Side by side, the half not explored in this interval is dimmed. An interval
  nobody touched is shown again (a trial records what was felt);
- then the question, answered by a key or a click on a button: 1 / 2 for two
  intervals, S / D for same-different, the digits for a scale of one key per value
  (0 for 10 on a 1-10 scale). A wider scale (0-10, 0-100, one below 0: a value
  without a key of its own, as magnitude estimation uses) is answered by typing the
  rating (:func:`typed_scale`): the digits, Backspace or the left arrow (or the
  Delete button) to correct, minus (or the sign button) below 0, shown on the screen
  as typed, Enter (or Confirm) to answer; a value off the scale is said so and not
  taken. The response time ``rt_s`` is measured from the end of the last interval to
  the answer (s, the haptic clock), not from the start of the trial;
- per interval the touches the window sent to the haptic side (its trace, times from
  the interval's start), handed back as ``Presentation.traces`` for the session to
  write and replay (``session.write_interval``); the live output itself (what was
  sent to the device, at full rate) goes to ``DIR/live/`` (``commands.csv``,
  ``friction.csv``, ``events.csv`` with ``interval-start`` / ``interval-end`` at
  their haptic-clock times; ``live-2/`` ... after a reconnect or a resume);
- Escape (or closing the window) ends the session with every answered trial kept
  (:class:`SessionPaused`; ``frictex experiment`` says so in one line and exits 130,
  as for Ctrl-C); ``--resume`` goes on from the next trial. SIGTERM or SIGHUP ends it
  the same way (:func:`stop_on_signals`), the haptic side stopped as for Escape. A lost device
  (the haptic side stopped) pauses the session on a screen saying why: R reconnects
  and repeats the trial from its start, Escape ends it as above.

The window runs on the main thread (its events must arrive there), the runner and
this presenter on a ``frictex-session`` thread (:func:`run_in_window`).
"""

from __future__ import annotations

import queue
import signal
import threading
from contextlib import contextmanager
from pathlib import Path
from typing import Callable, Sequence

import numpy as np

from frictex.app.experiment.presenter import Presentation, Shown
from frictex.app.experiment.runner import PARTICIPANTS
from frictex.app.experiment.scheduler import Scheduler, Trial
from frictex.device.errors import DeviceError, InputError, RunFailed
from frictex.rendering.input.trace_file import DOWN, Trace, make_trace
from frictex.rendering.visual.experiment_view import ExperimentView

NEXT_KEYS = ("enter", "right")
END_KEYS = ("escape",)
WAIT_S = 0.05  # longest wait for an answer before looking at the window and the output
SWITCH_TIMEOUT_S = 120.0  # a scene switch (the haptic child builds the pipeline)
#: the longest an interval waits for its first touch (s): then it ends, not touched
FIRST_TOUCH_WAIT_S = 30.0
CONTINUE = "continue"
NEXT = "next"
RECONNECT = "reconnect"
END = "end"
CONFIRM = "confirm"
DELETE = "delete"
SIGN = "sign"
#: keys that edit a typed rating: the last digit removed, the sign changed
DELETE_KEYS = ("backspace", "left")
SIGN_KEYS = ("minus",)


class SessionPaused(RunFailed):
    """The participant ended the session (Escape, the window closed): a planned stop,
    every trial answered kept, ``--resume`` goes on. ``trial``: the trial it stopped
    at; ``why``: what stopped it ("Escape", "the window was closed")."""

    def __init__(self, trial: int, why: str):
        super().__init__(f"session stopped at trial {trial} ({why}): the trials answered "
                         f"before it are kept; go on with --resume")
        self.trial, self.why = trial, why


class _Repeat(Exception):
    """The output came back after a loss: the trial starts again."""


def response_keys(responses: Sequence[str]) -> dict[str, str]:
    """The key (as the window names keys) of each response that has one: a one-character
    response is its own key, a word its first letter (the first word to claim it), "10"
    is 0 on a scale without a 0."""
    keys: dict[str, str] = {}
    for r in responses:
        if len(r) == 1:
            key = r.lower()
        elif r == "10" and "0" not in responses:
            key = "0"
        elif r.isalpha():
            key = r[0].lower()
        else:
            continue
        keys.setdefault(key, r)
    return keys


def button_label(response: str, keys: dict[str, str]) -> str:
    """A response's button: its text, and its key where that differs."""
    key = next((k for k, r in keys.items() if r == response), None)
    return response if key in (None, response) else f"{response} ({key.upper()})"


def how_to_answer(responses: Sequence[str], keys: dict[str, str]) -> str:
    """One sentence telling the participant how to answer."""
    listed = ", ".join(k if k == r else f"{k.upper()} = {r}" for k, r in keys.items())
    if not listed:
        return "Answer by clicking a button."
    rest = "" if len(keys) == len(responses) else " (the others by their button)"
    return f"Answer with a key ({listed}){rest} or by clicking a button."


def typed_scale(responses: Sequence[str]) -> tuple[int, int] | None:
    """(min, max) of a rating scale answered by typing: one whose values (``responses``,
    integers in order) are not each a key of their own (:func:`response_keys`), so that
    a key per value or a button per value cannot reach them all (0-100 has 101); None
    for other responses."""
    try:
        values = [int(r) for r in responses]
    except ValueError:
        return None
    if len(response_keys(responses)) == len(responses):
        return None
    return values[0], values[-1]


def how_to_type(scale: tuple[int, int]) -> str:
    """One sentence telling the participant how to type a rating on ``scale``."""
    low, high = scale
    sign = " (minus, or the sign button, for a value below 0)" if low < 0 else ""
    return (f"Type your rating, a whole number from {low} to {high}, with the number keys"
            f"{sign}; Backspace or the left arrow removes the last digit; Enter (or Confirm) "
            f"answers.")


def edit_rating(text: str, key: str, scale: tuple[int, int]) -> str:
    """The typed rating ``text`` after ``key`` (a digit, one of :data:`DELETE_KEYS` or
    :data:`SIGN_KEYS`; others leave it): digits beyond the scale's widest value are
    not taken; a sign is, on any scale, so that a negative rating on a scale from 0 is
    shown and refused (:func:`rating_problem`), not taken as its magnitude."""
    digits = text.lstrip("-")
    if key in DELETE_KEYS:
        return text[:-1]
    if key in SIGN_KEYS:
        return digits if text.startswith("-") else "-" + digits
    if len(key) == 1 and key.isdigit() and len(digits) < max(len(str(abs(v))) for v in scale):
        return text + key
    return text


def rating_problem(text: str, scale: tuple[int, int]) -> str | None:
    """Why the typed ``text`` is no rating on ``scale``, or None."""
    low, high = scale
    if not text.lstrip("-"):
        return f"Type a number from {low} to {high} first."
    if not low <= int(text) <= high:
        return f"{int(text)} is not on the scale: type a number from {low} to {high}."
    return None


def trace_of(samples: list[tuple], t0_s: float) -> Trace:
    """The touches ``samples`` ((t_s, x_mm, y_mm, force_n, event) on the haptic clock,
    finger 0) as a trace with times from ``t0_s`` (s)."""
    a = np.array(samples, dtype=np.float64)
    t = np.maximum(a[:, 0] - t0_s, 0.0)
    return make_trace(t, np.zeros(len(a), dtype=np.int64), a[:, 1], a[:, 2], a[:, 3],
                      a[:, 4].astype(np.int8), where="the window's touches")


class WindowPresenter:
    """``presenter.Presenter`` on the demo window (see the module docstring); attached
    to its loop by :func:`run_in_window`. ``options``: none yet (the participant spec
    ``window``)."""

    def __init__(self, options: str = ""):
        if options.strip():
            raise InputError(f"participant window: {options!r}: takes no options (the window's "
                             "size and the device are options of the command)")
        self.loop = None
        self.closed = threading.Event()
        self.closed_why = "the window was closed"  # what set ``closed``: a signal's name
        self.protocol = None
        self.practice = 0
        self.main_total: int | None = None
        self.keys: dict[str, str] = {}
        self.responses: tuple[str, ...] = ()
        self.typed: tuple[int, int] | None = None  # the scale typed in (typed_scale)
        self.first = 1  # the trial this run starts at (starts_at)
        self.trial: Trial | None = None

    def attach(self, loop) -> None:
        """Show trials on ``loop`` (an ``window_loop.ExperimentLoop``)."""
        self.loop = loop

    # -- the Presenter protocol -----------------------------------------------------------

    def starts_at(self, first_trial: int) -> None:
        """This run starts at ``first_trial`` (a resumed session): the instructions say
        only the practice trials still to come."""
        self.first = first_trial

    def begin(self, protocol) -> None:
        scheduler = Scheduler(protocol, protocol.seed or 0)
        self.protocol = protocol
        self.loop.show_scene = protocol.presentation.show_scene
        self.practice = len(scheduler.practice)
        self.main_total = len(scheduler.plan) if scheduler.plan is not None else None
        self.responses = tuple(scheduler.responses)
        self.keys = response_keys(self.responses)
        self.typed = typed_scale(self.responses)
        free = protocol.presentation.exploration == "free"
        explore = (f"Explore each texture for up to {protocol.presentation.exploration_s:g} s "
                   "with the left button held (your finger), then press Enter or click Next."
                   if free else
                   f"Explore each texture for {protocol.presentation.exploration_s:g} s with "
                   "the left button held (your finger).")
        left = max(self.practice - (self.first - 1), 0)
        first = "trial is" if left == 1 else f"{left} trials are"
        practice = (f"The {'next' if self.first > 1 else 'first'} {first} practice (marked "
                    f"PRACTICE), not analysed." if left else "")
        lines = tuple(p for p in (protocol.description, protocol.question, explore,
                                  self._how_to_answer(), practice,
                                  "Escape ends the session; it can be continued later.") if p)
        self._message(protocol.name, lines, ((CONTINUE, "Start (Enter)"),), "instructions")

    def rest(self, trial: Trial) -> None:
        done = trial.number - 1 - self.practice
        lines = (f"{done} of {self.main_total} trials done." if self.main_total else
                 f"{done} trials done.", "Rest as long as you like.")
        self._message("Break", lines, ((CONTINUE, "Continue (Enter)"),), self._progress(trial))

    def present(self, trial: Trial, shown: Sequence[Shown]) -> Presentation:
        self.trial = trial
        while True:
            try:
                return self._trial(trial, shown)
            except _Repeat:
                continue

    # -- a trial ------------------------------------------------------------------------

    def _progress(self, trial: Trial, interval: str = "") -> str:
        if trial.practice:
            where = f"PRACTICE {trial.number} of {self.practice}"
        else:
            k = trial.number - self.practice
            where = f"Trial {k} of {self.main_total}" if self.main_total else f"Trial {k}"
        return where + (f" | {interval}" if interval else "")

    def _trial(self, trial: Trial, shown: Sequence[Shown]) -> Presentation:
        traces = []
        for i, item in enumerate(shown, start=1):
            traces.append(self._interval(trial, i, len(shown), item))
        ended = self.loop.haptic.now()
        value, t = self._typed(trial) if self.typed else self._chosen(trial)
        self.loop.log("response", f"trial {trial.number}: {value}")
        return Presentation(value, max(t - ended, 0.0), tuple(traces))

    def _how_to_answer(self) -> str:
        return how_to_type(self.typed) if self.typed else how_to_answer(self.responses, self.keys)

    def _chosen(self, trial: Trial) -> tuple[str, float]:
        """The response chosen by its key or button, and when (s, haptic clock)."""
        buttons = tuple((r, button_label(r, self.keys)) for r in self.responses)
        self._show(ExperimentView("message", self._progress(trial), (
            self.protocol.question, self._how_to_answer()), buttons,
            self._progress(trial, "answer")))
        while True:
            kind, value, t = self._event()
            if kind == "button" and value in self.responses:
                return value, t
            if kind == "key" and value in self.keys:
                return self.keys[value], t

    def _typed(self, trial: Trial) -> tuple[str, float]:
        """The rating typed (:func:`edit_rating`) and confirmed with Enter or Confirm,
        and when (s, haptic clock); the screen shows it as typed."""
        buttons = ((CONFIRM, "Confirm (Enter)"), (DELETE, "Delete (Backspace)"))
        buttons += ((SIGN, "- / +"),) if self.typed[0] < 0 else ()
        by_button = {DELETE: DELETE_KEYS[0], SIGN: SIGN_KEYS[0]}
        text, note, show = "", "", self._show  # later screens keep the keys typed meanwhile
        while True:
            show(ExperimentView("message", self._progress(trial), tuple(p for p in (
                self.protocol.question, self._how_to_answer(), f"Your rating: {text or '_'}",
                note) if p), buttons, self._progress(trial, "answer")))
            show = self._replace
            kind, value, t = self._event()
            if (kind == "button" and value == CONFIRM) or (kind == "key" and value in NEXT_KEYS):
                note = rating_problem(text, self.typed) or ""
                if not note:
                    return str(int(text)), t
                continue
            key = by_button.get(value, "") if kind == "button" else value
            text, note = edit_rating(text, key, self.typed), ""

    def _interval(self, trial: Trial, i: int, n: int, item: Shown) -> Trace:
        """Show ``item`` and record the touches until its time is up or (free
        exploration) the participant moves on; again if it was not touched."""
        error = self.loop.ask("switch", item.scene, item.text, cancel=self.closed,
                              timeout_s=SWITCH_TIMEOUT_S)
        if self.closed.is_set():
            raise self._paused(self.closed_why)
        if error is not None:
            raise DeviceError(f"trial {trial.number}: cannot show {item.name}: {error}")
        display = item.scene.display
        whole = item.area == (0.0, 0.0, display.width_mm, display.height_mm)
        side = "" if whole else (" (the left half)" if item.area[0] == 0.0 else " (the right half)")
        how = "then Enter or Next" if item.free else f"for {item.seconds:g} s"
        label = f"interval {i} of {n}: explore{side}, {how}" if n > 1 else f"explore, {how}"
        while True:
            loop = self.loop
            t0 = loop.haptic.now()
            loop.start_recording()
            loop.accept_touch = True
            self._show(ExperimentView(
                "interval", buttons=((NEXT, "Next (Enter)"),) if item.free else (),
                progress=self._progress(trial, label),
                active_mm=None if whole else item.area))
            loop.log("interval-start", f"trial {trial.number} interval {i}: {item.name}", t_s=t0)
            try:
                while (event := self._event(lambda: self._ends_at(item, t0))) is not None:
                    kind, value, _ = event
                    if item.free and ((kind == "button" and value == NEXT)
                                      or (kind == "key" and value in NEXT_KEYS)):
                        break
            finally:
                loop.accept_touch = False
                samples = loop.stop_recording()
                loop.log("interval-end", f"trial {trial.number} interval {i}")
            if any(s[4] == DOWN for s in samples):
                return trace_of(samples, t0)
            self._message("Not touched", (
                "The texture was not touched, so it is shown again. Hold the left button "
                "down and move over it.",), ((CONTINUE, "Again (Enter)"),),
                self._progress(trial, label))

    def _ends_at(self, item: Shown, t0_s: float) -> float:
        """When the interval shown at ``t0_s`` ends (s, haptic clock): ``item.seconds``
        after its first touch, or :data:`FIRST_TOUCH_WAIT_S` after ``t0_s`` untouched."""
        touched = self.loop.touched_at()  # stamped as early as the batch it came in: clamped
        return t0_s + FIRST_TOUCH_WAIT_S if touched is None else max(touched, t0_s) + item.seconds

    # -- screens and events -------------------------------------------------------------

    def _show(self, view: ExperimentView) -> None:
        """Show ``view``; keys and clicks that came before it are dropped (a double
        press must not answer the next screen)."""
        while True:
            try:
                self.loop.answers.get_nowait()
            except queue.Empty:
                break
        self.loop.screen = view
        if view.phase == "message":  # what the participant is asked to do, logged
            self.loop.log("screen", view.title)

    def _replace(self, view: ExperimentView) -> None:
        """Show ``view`` in place of a screen it updates, keeping the keys and clicks
        that came since (typing on: the next digit may be queued already)."""
        self.loop.screen = view

    def _message(self, title: str, lines: tuple[str, ...], buttons, progress: str) -> None:
        """A screen of text; returns when its button is clicked or Enter pressed."""
        self._show(ExperimentView("message", title, lines, buttons, progress))
        while True:
            kind, value, _ = self._event()
            if (kind == "button" and value == buttons[0][0]) or (kind == "key" and value in NEXT_KEYS):
                return

    def _event(self, until: Callable[[], float] | None = None) -> tuple | None:
        """The participant's next key or click ("key" | "button", value, t_s), or None
        once the haptic clock reaches ``until()`` (s; asked again at every look: it may
        move). Escape or a closed window ends the
        session (:class:`SessionPaused`); a lost output pauses it (:meth:`_lost`)."""
        while True:
            loop = self.loop
            if self.closed.is_set():
                raise self._paused(self.closed_why)
            if loop.lost is not None:
                self._lost(loop.lost)
            wait = WAIT_S
            if until is not None:
                wait = min(wait, until() - loop.haptic.now())
                if wait <= 0.0:
                    return None
            try:
                event = loop.answers.get(timeout=wait)
            except queue.Empty:
                continue
            if event[0] == "key" and event[1] in END_KEYS:
                raise self._paused("Escape")
            return event

    def _paused(self, why: str) -> SessionPaused:
        return SessionPaused(self.trial.number if self.trial is not None else 1, why)

    def _lost(self, why: str) -> None:
        """The output stopped: say so and wait for R (reconnect: the trial starts again,
        raising _Repeat) or Escape (the session ends, DeviceError)."""
        loop = self.loop
        loop.accept_touch = False
        loop.stop_recording()
        number = self.trial.number if self.trial is not None else 1
        self._show(ExperimentView("message", "Output device lost", (
            why, f"The session is paused at trial {number}; every trial answered before "
            "it is kept.", "R (or Reconnect) starts the output again and repeats this "
            "trial. Escape ends the session; it can be continued later with --resume."),
            ((RECONNECT, "Reconnect (R)"), (END, "End (Esc)")), "paused: output device lost"))
        loop.log("paused", why)
        while True:
            try:
                kind, value, _ = loop.answers.get(timeout=WAIT_S)
            except queue.Empty:
                if self.closed.is_set():
                    value = END
                else:
                    continue
            if value in (END, "escape") or self.closed.is_set():
                raise DeviceError(f"output device lost at trial {number} ({why}); the "
                                  "trials answered before it are kept; go on with --resume")
            if value in (RECONNECT, "r"):
                error = loop.ask("reconnect", loop.scene, cancel=self.closed,
                                 timeout_s=SWITCH_TIMEOUT_S)
                if error is None:
                    loop.log("resumed", f"trial {number} again")
                    raise _Repeat()
                why = f"reconnecting failed: {error}"
                self._show(ExperimentView("message", "Output device lost", (
                    why, "R tries again; Escape ends the session (continue later with "
                    "--resume)."), ((RECONNECT, "Reconnect (R)"), (END, "End (Esc)")),
                    "paused: output device lost"))


@contextmanager
def stop_on_signals(presenter: WindowPresenter):
    """While in this block (on the main thread), SIGTERM and SIGHUP end the session as
    Escape does: the session thread stops at its next look at the window, the window
    and the haptic side close in order (no process or semaphore left behind), and the
    block's :class:`SessionPaused` becomes ``Terminated`` (exit 128 + the signal) with
    the trial it stopped at."""
    got: list[int] = []

    def stop(signum, frame):
        got.append(signum)
        presenter.closed_why = signal.Signals(signum).name  # session.json: "stopped (SIGTERM)"
        presenter.closed.set()

    held = (signal.SIGTERM, signal.SIGHUP)
    previous = [signal.signal(s, stop) for s in held]
    try:
        yield
    except SessionPaused as exc:
        if not got:
            raise
        from frictex.app.engine.driver import Terminated
        ended = Terminated(got[0])
        ended.reason += (f" at trial {exc.trial}: the trials answered before it are kept; "
                         f"go on with --resume")
        raise ended from None
    finally:
        for s, handler in zip(held, previous):
            signal.signal(s, handler)


def next_folder(base: Path) -> Path:
    """``base``, or ``base-2``, ``base-3`` ... the first that does not exist yet."""
    path, k = base, 1
    while path.exists():
        k += 1
        path = base.with_name(f"{base.name}-{k}")
    return path


def run_in_window(presenter: WindowPresenter, session: Callable[[], object], backend,
                  start_haptic: Callable, scene, live_dir: Path, screenshots: Path,
                  link_name: str = "none"):
    """Run ``session()`` (``runner.run_session`` with ``presenter``) on a thread while
    this thread runs the window ``backend`` (opened; closed here) on the live haptic
    side ``start_haptic(scene, record_dir) -> (haptic, finish)`` (started, and started
    again after a lost device), first showing ``scene``; returns what ``session``
    returns and raises what it raised (a window failure first)."""
    from frictex.app.experiment.window_loop import ExperimentLoop

    def start(first_scene):
        return start_haptic(first_scene, next_folder(live_dir))

    record = next_folder(live_dir)
    haptic, finish = start_haptic(scene, record)
    loop = None
    outcome: dict = {}
    try:
        loop = ExperimentLoop(backend, haptic, finish, scene, screenshots, record / "events.csv",
                              start, link_name)
        presenter.attach(loop)

        def work():
            try:
                outcome["value"] = session()
            except BaseException as exc:  # raised again on the window's thread
                outcome["error"] = exc
            finally:
                loop.quit = True
                backend.wake()

        worker = threading.Thread(target=work, name="frictex-session", daemon=True)
        worker.start()
        try:
            loop.run()
        finally:
            presenter.closed.set()
            worker.join()
    finally:
        try:
            (loop.finish if loop is not None else finish)()
        finally:
            if loop is not None:
                loop.close()
            backend.close()
    if "error" in outcome:
        raise outcome["error"]
    return outcome["value"]


def _window(options: str) -> WindowPresenter:
    return WindowPresenter(options)


PARTICIPANTS.register("window", _window)
