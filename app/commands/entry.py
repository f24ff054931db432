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
import sys
import threading
from typing import NoReturn

from frictex.app.commands.startup_signals import StartupSignals, report_signal


def entry() -> NoReturn:
    """The ``frictex`` command: ``cli.main`` within :class:`StartupSignals` (put in place
    before ``cli`` is imported), then the process ends.

    Once the command has returned (its outputs committed and closed), the atexit handlers
    run and the standard streams are flushed, but the interpreter's teardown is skipped:
    unloading numba's and scipy's modules object by object took 0.24 s of CPU after a
    one-second replay (alternated pairs of whole processes under ``/usr/bin/time``), a
    quarter of what the user waits for.
    A thread still running gets the ordinary exit, which waits for it. From the moment
    the command has returned (its run is complete) a signal ends the process at once
    with the command's status (``StartupSignals.end_with``), in either exit.
    """
    code = 1  # what a signal ends the process with if main escapes any other way
    with StartupSignals() as startup:
        try:
            from frictex.app.commands.cli import main
            code = main(startup=startup)
        except KeyboardInterrupt:  # before main's own handling, or after it
            code = report_signal(startup.signum)
        except SystemExit as exc:  # a run's SIGTERM or SIGHUP, its line printed
            code = exc.code if isinstance(exc.code, int) else 1
            raise
        finally:
            startup.end_with(code)
    if threading.active_count() > 1:
        sys.exit(code)
    atexit._run_exitfuncs()
    for stream in (sys.stdout, sys.stderr):
        _flush(stream)
    os._exit(code)


def _flush(stream) -> None:
    """Flush ``stream``, which may be None (started with it closed, ``>&-``) or gone (a
    reader that left): the run's status stands either way, as the text could not go
    anywhere."""
    if stream is None:
        return
    try:
        stream.flush()
    except (OSError, ValueError):
        pass
