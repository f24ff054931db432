"""The ``frictex`` command's entry point: the console script and ``python -m frictex``.

A signal at any moment of a command's start-up ends it as one later would: Ctrl-C as
``frictex: interrupted`` (exit 130), SIGTERM or SIGHUP as ``frictex: terminated by
SIGTERM`` (exit 128 + the signal). :func:`entry` puts :class:`StartupSignals` in place
before it imports the command line (argparse, ctypes, the subcommand's numpy, numba,
pyarrow: 0.15 s and more): a SIGINT 20 ms after start printed a traceback through those
imports, a SIGTERM in the first 0.15 s killed the process without a word. What runs
before this module (the interpreter's own start-up, ``import frictex``) keeps the
interpreter's defaults. This module imports nothing heavy: ``frictex --version`` starts
here too.
"""

from __future__ import annotations

import atexit
import os
import signal
import sys
import threading
from typing import NoReturn

from frictex.app.engine.driver import HELD_SIGNALS, Terminated
from frictex.device.errors import FrictexError


def report_signal(signum: int | None) -> int:
    """Print the one line for a signal that ended the command (None: a Ctrl-C that came
    as a KeyboardInterrupt); return its exit status."""
    if signum in (None, signal.SIGINT):
        print("frictex: interrupted", file=sys.stderr)
        return 130
    ended = Terminated(signum)
    print(f"frictex: {ended.reason}", file=sys.stderr)
    return ended.code


class StartupSignals:
    """Within: SIGINT, SIGTERM and SIGHUP (``driver.HELD_SIGNALS``) during a command's
    start-up raise KeyboardInterrupt, the first one's number kept in ``signum``; the
    caller ends with :func:`report_signal`. A signal the process ignores (``nohup``)
    stays ignored.

    Each raises KeyboardInterrupt, SIGTERM's too: inside a C extension's import of numpy
    (``import_array``: pyarrow, numpy.linalg, numpy.random) the exception is printed
    (``PyErr_Print``, through ``sys.excepthook``) and replaced with ``ImportError:
    numpy._core.multiarray failed to import``, and a SystemExit printed there ends the
    process on the spot, without the line. Within, ``sys.excepthook`` prints nothing for
    a KeyboardInterrupt (the one line comes after) and :meth:`caused` tells what a signal
    caused. Commands that handle signals themselves (a run's ``deferred_interrupts``) put
    their own handlers in place for the run and these back after it. In the main thread
    only (signal handlers can be set nowhere else)."""

    def __init__(self):
        self.signum: int | None = None
        self._handlers: dict[int, object] = {}
        self._hook = None

    def __enter__(self) -> "StartupSignals":
        if threading.current_thread() is threading.main_thread():
            self._hook = sys.excepthook
            sys.excepthook = self._quiet_interrupt
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

    def _on_signal(self, signum, frame) -> None:
        if self.signum is None:
            self.signum = signum
        raise KeyboardInterrupt

    def _quiet_interrupt(self, kind, value, tb) -> None:
        if not issubclass(kind, KeyboardInterrupt):
            self._hook(kind, value, tb)

    def caused(self, exc: BaseException) -> bool:
        """Whether ``exc``, which would be an internal error, came of a signal seen."""
        return self.signum is not None and not isinstance(
            exc, (FrictexError, OSError, SystemExit))


def entry() -> NoReturn:
    """The ``frictex`` command: ``cli.main`` within :class:`StartupSignals` (put in place
    before ``cli`` is imported), then the process ends.

    Once the command has returned (its outputs committed and closed), the atexit handlers
    run and the standard streams are flushed, but the interpreter's teardown is skipped:
    unloading numba's and scipy's modules object by object took 0.24 s of CPU after a
    one-second replay (alternated pairs of whole processes under ``/usr/bin/time``), a
    quarter of what the user waits for.
    A thread still running gets the ordinary exit, which waits for it.
    """
    with StartupSignals() as startup:
        try:
            from frictex.app.commands.cli import main
            code = main(startup=startup)
        except KeyboardInterrupt:  # before main's own handling, or after it
            code = report_signal(startup.signum)
    if threading.active_count() > 1:
        sys.exit(code)
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)
