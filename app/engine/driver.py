"""The one block loop: a source's touch samples through a pipeline into sinks, on a clock.

Replay, the live haptic loop, the report and the benches all run here; only the source
(``app.engine.sources``), the clock (``app.engine.clocks``) and the sinks
(``app.engine.sinks``) differ (DESIGN.md, "One pipeline, one driver")::

    blocks = drive(PipelineStage(pipeline), TraceSource(chunks), [TableSink(...)],
                   VirtualClock(), chunk_blocks=200)

Each step runs up to ``chunk_blocks`` blocks in one pipeline call (replay: fast; live:
1). A sample still takes effect at the block boundary after it, so the result does not
depend on ``chunk_blocks``. After the last block every sink is committed; if anything
raises (a source, the pipeline, a sink, a commit, Ctrl-C) every sink not yet committed
is aborted and the error propagates: a run writes complete outputs or none.

Ctrl-C. A SIGINT that arrives inside a compiled (numba) kernel and raises there makes the
kernel return a value with an exception set, which Python reports as a 30-line
``SystemError`` (3 of 15 Ctrl-Cs of a replay did). :func:`deferred_interrupts` holds the
first Ctrl-C (and SIGTERM, SIGHUP) as a flag that the loop turns into an exception between
steps (``check``), where nothing compiled runs; a second one raises at once. Through a
run's commit (``check.committing()``) both are held, then dropped: the run is complete;
the handler the run restores is told of it (``_pass_on``: ``frictex batch --jobs 1``
stops after this run, ``frictex experiment`` after this trial (:func:`between_runs`), a
lone replay reports its complete run).
Once the run is ending (a signal raised, or ``check.end()`` where an error ends it), every
further signal is held: the cleanup (sinks aborted, staged files removed) is never cut
short. A worker of ``frictex batch`` whose parent dies gets a SIGINT from the system for
each of the parent's threads that ends (``app.engine.fanout``): a second one inside the
cleanup left a job's staging folder behind.
A signal the process ignores (``nohup``) stays ignored. A wait on a device link (a paced
send, the handshake, a close) asks the same ``check`` between its turns
(``device.link.waits``), so a held signal ends it within tens of ms; the link's sink is
then aborted, which stops the plate at once (Stop without drain) instead of playing out
what was queued.
"""

from __future__ import annotations

import signal
import threading
import time
from contextlib import contextmanager

from frictex.device.link.waits import interruptible


class PipelineStage:
    """A pipeline with its state carried between calls; the commands sent are its own.

    ``normal_force_n``: optional callable returning the measured normal force (N) for the
    next block, or None (then the trace's force is used). ``force_reports``: the device's
    force reports for the friction loop (``Pipeline.process``), or None.
    """

    def __init__(self, pipeline, normal_force_n=None, force_reports=None):
        self.pipeline = pipeline
        self.state = pipeline.initial_state()
        self.normal_force_n = normal_force_n
        self.force_reports = force_reports

    def process(self, k: int, samples, n: int):
        force = None if self.normal_force_n is None else self.normal_force_n()
        out, self.state = self.pipeline.process(k, samples, self.state, n_blocks=n,
                                                normal_force_n=force,
                                                force_reports=self.force_reports)
        return out, out.commands_um


def force_reports_of(link):
    """``link.force_report`` for the friction loop, or None for a link whose device
    announces no lateral force sensor (the loop then says the signal is absent)."""
    return link.force_report if link.info.has_force_reports else None


class RunTimer:
    """Wall time (s) spent in each part of the loop: reading input, computing, writing."""

    def __init__(self):
        self.seconds = {"read": 0.0, "compute": 0.0, "write": 0.0, "commit": 0.0}


#: signals held by :func:`deferred_interrupts`: Ctrl-C, and what ``timeout`` or a closed
#: terminal sends
HELD_SIGNALS = (signal.SIGINT, signal.SIGTERM, signal.SIGHUP)


class Terminated(SystemExit):
    """A run ended by SIGTERM or SIGHUP: ``SystemExit(128 + signal)``, the status the
    signal's default action gives, with ``reason`` (one line: the signal's name) for the
    command to print."""

    def __init__(self, signum: int):
        super().__init__(128 + signum)
        self.signum = signum
        self.reason = f"terminated by {signal.Signals(signum).name}"


class HeldSignals:
    """What :func:`deferred_interrupts` yields: call it to raise a held signal;
    :meth:`committing` for the step after which a run is complete."""

    def __init__(self):
        self.held: list[int] = []
        self.dropped: list[int] = []
        self._committing = False
        self._ending = False

    def __call__(self) -> None:
        """Raise the first signal held, if any (see :func:`deferred_interrupts`); the run
        is ending from then on (:meth:`end`)."""
        if self.held:
            self._ending = True
            if self.held[0] == signal.SIGINT:
                raise KeyboardInterrupt
            raise Terminated(self.held[0])

    def end(self) -> None:
        """The run is ending (an error or a signal raised): from now on every signal is
        held, none raised, so that its cleanup runs to the end."""
        self._ending = True

    def hold(self, signum, frame) -> None:
        """The signal handler: hold ``signum``; a second one raises at once, except
        while committing and once the run is ending."""
        self.held.append(signum)
        if len(self.held) > 1 and not self._committing and not self._ending:
            self()

    @contextmanager
    def committing(self):
        """Within: the run's commit (the swap of its outputs into place). Every signal is
        held through it, a second one too; once it has succeeded the run is complete and
        the signals held are dropped (kept in ``dropped``): the run reports success, as its
        outputs are all in place (a run that could still stop raised at the ``check()``
        before)."""
        self()
        self._committing = True
        try:
            yield
        except BaseException:
            self._committing = False
            raise
        self.dropped, self.held = self.held, []
        self._committing = False


@contextmanager
def deferred_interrupts():
    """Within: the first SIGINT (Ctrl-C), SIGTERM or SIGHUP is held until the ``check()``
    this yields (a :class:`HeldSignals`) is called, which raises then (see the module
    docstring): Ctrl-C as ``KeyboardInterrupt``, the others as :class:`Terminated` (a
    ``SystemExit(128 + signal)``, their default exit status), so that the run is aborted
    cleanly (its sinks and staged files removed). A second signal raises at once, except within
    ``check.committing()`` and once the run is ending (``check.end()``). A signal whose handler is ``SIG_IGN`` (``nohup``, a shell's
    background job) stays ignored. Outside the main thread (where Python runs no signal
    handler) ``check`` does nothing. Within, the waits on device links ask ``check``
    too (``device.link.waits.interruptible``)."""
    check = HeldSignals()
    if threading.current_thread() is not threading.main_thread():
        yield check
        return
    previous = {sig: signal.getsignal(sig) for sig in HELD_SIGNALS}
    for sig, handler in previous.items():
        if handler is not signal.SIG_IGN:
            signal.signal(sig, check.hold)
    try:
        with interruptible(check):
            yield check
    finally:
        for sig, handler in previous.items():
            if handler is not signal.SIG_IGN:
                signal.signal(sig, handler)
        _pass_on(check, previous)
    check()


def _pass_on(check: HeldSignals, previous: dict) -> None:
    """Tell the handler :func:`deferred_interrupts` restored (``previous``) of the first
    signal its run saw, where that handler is, or is bound to, an object with
    ``run_saw(signum, ended)`` (a loop of runs: ``fanout``; a command:
    ``StartupSignals``): one that ended the run, or one dropped after its complete
    commit. It decides (a loop stops before its next run; a command keeps the one that
    ended a run as its first signal, so that the signals after it, during its cleanup,
    do not cut it short). Any other handler is told nothing: a run whose commit dropped a
    signal completes and returns (``replay_with``)."""
    seen = check.held or check.dropped
    if seen:
        tell_run_saw(previous[seen[0]], seen[0], ended=bool(check.held))


def tell_run_saw(handler, signum: int, ended: bool) -> None:
    """Tell a signal ``handler`` that is, or is bound to, an object with ``run_saw`` that
    a run saw ``signum`` (:func:`_pass_on`); any other handler is told nothing."""
    owner = handler if hasattr(handler, "run_saw") else getattr(handler, "__self__", None)
    if hasattr(owner, "run_saw"):
        owner.run_saw(signum, ended=ended)


class BetweenRuns:
    """The signal handlers of a command that runs replays one after another (an
    experiment's intervals) while :func:`between_runs` is in place: a signal outside a run
    goes to the handler before it (the command's, which raises), and one a run's commit
    dropped (the run is complete, :meth:`HeldSignals.committing`) goes there at the
    command's next :meth:`check`, as if it came then, where the command went on before."""

    def __init__(self):
        self.previous: dict[int, object] = {}
        self.dropped: int | None = None

    def __call__(self, signum, frame) -> None:
        self.previous[signum](signum, frame)

    def run_saw(self, signum: int, ended: bool) -> None:
        tell_run_saw(self.previous[signum], signum, ended)
        if not ended and self.dropped is None:
            self.dropped = signum

    def check(self) -> None:
        """A point where the command may stop (its work so far complete): the signal a
        run's commit dropped, if any, goes to the handler before (which raises)."""
        if self.dropped is not None:
            signum, self.dropped = self.dropped, None
            self.previous[signum](signum, None)


def between_runs():
    """Within: :class:`BetweenRuns` handles SIGINT, SIGTERM and SIGHUP where a Python
    handler did (in the main thread; elsewhere its ``check`` does nothing)."""
    return in_front(BetweenRuns())


@contextmanager
def in_front(handler):
    """Within: ``handler`` (called as a signal handler; a ``previous`` dict) takes each of
    ``HELD_SIGNALS`` where a Python handler did, the one it replaced kept in ``previous``
    (to pass the signal on) and put back after; in the main thread only, where handlers
    can be set (one the process ignores stays ignored). Yields ``handler``."""
    if threading.current_thread() is threading.main_thread():
        for sig in HELD_SIGNALS:
            if callable(signal.getsignal(sig)):
                handler.previous[sig] = signal.signal(sig, handler)
    try:
        yield handler
    finally:
        for sig, previous in handler.previous.items():
            signal.signal(sig, previous)


def drive(stage, source, sinks, clock, *, chunk_blocks: int = 1, stop=None,
          timer: RunTimer | None = None, check: HeldSignals | None = None) -> int:
    """Run until ``source.done`` (or ``stop()`` is true); returns the number of blocks run
    (skipped gaps not counted). ``check()``, if given, is called before each step and may
    raise to end the run (a held Ctrl-C: :func:`deferred_interrupts`).

    ``stage.process(k, samples, n) -> (out, commands_um)``; ``source.resume_at(k)`` (the
    block to run next: ``k``, or later past a skipped gap), ``source.take(k, n) ->
    (samples, n_run)``, ``source.label(out)`` (the output with the source's finger ids); ``sink.write(out, commands_um)``, ``sink.commit()``,
    ``sink.abort()``; ``clock.wait(k)``, ``clock.finished(k, n)``.
    """
    timer = RunTimer() if timer is None else timer
    seconds = timer.seconds
    k = run = 0
    pending = list(sinks)
    try:
        while not source.done and not (stop is not None and stop()):
            if check is not None:
                check()
            k = source.resume_at(k)
            clock.wait(k)
            t0 = time.perf_counter()
            samples, n = source.take(k, chunk_blocks)
            t1 = time.perf_counter()
            out, commands = stage.process(k, samples, n)
            out = source.label(out)
            t2 = time.perf_counter()
            for sink in sinks:
                sink.write(out, commands)
            clock.finished(k, n)
            seconds["read"] += t1 - t0
            seconds["compute"] += t2 - t1
            seconds["write"] += time.perf_counter() - t2
            k += n
            run += n
        if check is not None:
            check()
        t3 = time.perf_counter()
        while pending:
            pending[0].commit()
            pending.pop(0)
        seconds["commit"] += time.perf_counter() - t3
    except BaseException:
        if check is not None:
            check.end()
        for sink in pending:
            sink.abort()
        raise
    return run
