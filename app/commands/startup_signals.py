"""Signals during a command's start-up (see ``app.commands.entry``, which puts
:class:`StartupSignals` in place before the command line is imported, and ``cli.main``,
which reports them)."""

from __future__ import annotations

import os
import signal
import sys
import threading

from frictex.app.engine.driver import HELD_SIGNALS, Terminated
from frictex.device.errors import FrictexError


def ignore_held_signals() -> None:
    """From now on SIGINT, SIGTERM and SIGHUP are ignored (the command is over: its exit
    line is being written, or its code returned); in the main thread only (signal
    handlers can be set nowhere else). A signal already caught and not yet handled is
    dropped too."""
    if threading.current_thread() is threading.main_thread():
        for sig in HELD_SIGNALS:
            signal.signal(sig, signal.SIG_IGN)


def report_signal(signum: int | None) -> int:
    """Print the one line for a signal that ended the command (None: a Ctrl-C that came
    as a KeyboardInterrupt), further signals ignored meanwhile (one more Ctrl-C printed
    the line twice); return its exit status."""
    ignore_held_signals()
    if signum in (None, signal.SIGINT):
        print("frictex: interrupted", file=sys.stderr)
        return 130
    ended = Terminated(signum)
    print(f"frictex: {ended.reason}", file=sys.stderr)
    return ended.code


class StartupSignals:
    """Within: SIGINT, SIGTERM and SIGHUP (``driver.HELD_SIGNALS``) during a command's
    start-up raise KeyboardInterrupt, the first one's number kept in ``signum``; the
    caller ends with :func:`report_signal`. Only the first raises: the ones after it
    (or after the signal a run saw, :meth:`run_saw`) come while the command
    cleans up, and are ignored, so that its cleanup runs to the end and the signal that
    ended the command is the one reported. A signal the process ignores (``nohup``)
    stays ignored.

    Each raises KeyboardInterrupt, SIGTERM's too: inside a C extension's import of numpy
    (``import_array``: pyarrow, numpy.linalg, numpy.random) the exception is printed
    (``PyErr_Print``, through ``sys.excepthook``) and replaced with ``ImportError:
    numpy._core.multiarray failed to import``; ``import_umath`` (numba's and scipy's ufunc
    modules) replaces it before printing (``ImportError: _multiarray_umath failed to
    import``); a SystemExit printed there ends the process on the spot, without the line.
    Within, ``sys.excepthook`` prints nothing for a KeyboardInterrupt nor for what
    :meth:`caused` says a signal caused (the one line comes after), and a KeyboardInterrupt
    dropped where no exception can pass is raised again (:meth:`_raise_again`). Commands that handle signals themselves (a run's ``deferred_interrupts``) put
    their own handlers in place for the run and these back after it. In the main thread
    only (signal handlers can be set nowhere else)."""

    def __init__(self):
        self.signum: int | None = None
        self._handlers: dict[int, object] = {}
        self._hook = None
        self._unraisable_hook = None

    def __enter__(self) -> "StartupSignals":
        if threading.current_thread() is threading.main_thread():
            self._hook = sys.excepthook
            sys.excepthook = self._quiet_interrupt
            self._unraisable_hook = sys.unraisablehook
            sys.unraisablehook = self._raise_again
            for sig in HELD_SIGNALS:
                handler = signal.getsignal(sig)
                if handler is not signal.SIG_IGN:
                    self._handlers[sig] = signal.signal(sig, self._on_signal)
        return self

    def __exit__(self, *exc) -> None:
        for sig, handler in self._handlers.items():
            signal.signal(sig, handler)
        if self._hook is not None:
            sys.excepthook = self._hook
            sys.unraisablehook = self._unraisable_hook

    def run_saw(self, signum: int, ended: bool) -> None:
        """A run within (``driver.deferred_interrupts``) saw ``signum``: one that ended the
        run is the command's first signal, unless one came before (the ones after it
        come during the command's cleanup, and are ignored). One that came during the
        run's commit and was dropped (the run is complete) changes nothing: a later
        signal still stops the command."""
        if ended and self.signum is None:
            self.signum = signum

    def end_with(self, code: int) -> None:
        """The command is over with exit status ``code``: from now on SIGINT, SIGTERM and
        SIGHUP end the process at once with that status, without a line (its outputs are
        complete). Kept so on leaving: a Ctrl-C during the interpreter's exit killed the
        process by SIGINT without a line, and a wait for a thread left running stays
        stoppable. In the main thread only."""
        if threading.current_thread() is not threading.main_thread():
            return

        def end(signum, frame) -> None:
            for stream in (sys.stdout, sys.stderr):
                try:
                    stream.flush()
                except (OSError, ValueError):  # a closed or broken stream: nothing to keep
                    pass
            os._exit(code)

        for sig in HELD_SIGNALS:
            if signal.getsignal(sig) is not signal.SIG_IGN:
                signal.signal(sig, end)
        self._handlers.clear()

    def _on_signal(self, signum, frame) -> None:
        if self.signum is None:
            self.signum = signum
            raise KeyboardInterrupt

    def _raise_again(self, unraisable) -> None:
        """``sys.unraisablehook``: the first signal's KeyboardInterrupt, raised where Python
        cannot pass an exception on (importlib's module-lock weakref callback), was printed
        as "Exception ignored in ... cb" and dropped, and the command ran to the end, exit
        0. It is raised again, quietly, as the main thread next enters a function (a
        one-shot trace function: a signal raised from within this hook would be dropped
        too); any other unraisable exception is printed as before."""
        if self.signum is None or not isinstance(unraisable.exc_value, KeyboardInterrupt):
            self._unraisable_hook(unraisable)
            return
        previous = sys.gettrace()

        def raise_on_entry(frame, event, arg):
            sys.settrace(previous)
            raise KeyboardInterrupt

        sys.settrace(raise_on_entry)

    def _quiet_interrupt(self, kind, value, tb) -> None:
        if not (issubclass(kind, KeyboardInterrupt) or self.caused(value)):
            self._hook(kind, value, tb)

    def caused(self, exc: BaseException) -> bool:
        """Whether ``exc``, which would be an internal error, came of a signal seen."""
        return self.signum is not None and not isinstance(
            exc, (FrictexError, OSError, SystemExit))
