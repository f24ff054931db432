"""The ``frictex`` command.

Each subcommand lives in its own module of ``app`` exposing
``add_arguments(parser)`` and ``run(args) -> int``; the module is imported only
when its subcommand runs, so ``frictex validate`` never loads OpenGL.
Errors raised as ``ValueError`` (bad input: texture, trace, option) or ``OSError``
(files, ports) become one line on stderr, ``frictex: error: ...``, and exit 2; a run that
could not finish (the device stopped taking data, the disk filled up) exits 1.
"""

from __future__ import annotations

import argparse
import atexit
import errno
import importlib
import os
import sys
import threading
from typing import NoReturn

from frictex.app.engine.heap import keep_freed_memory

#: subcommand -> (module in app/, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "validate": ("frictex.app.commands.validate", "check texture files; report every problem with file, line and field"),
    "library": ("frictex.app.commands.library", "list the bundled scenes and traces"),
    "replay": ("frictex.app.commands.replay", "run the haptic pipeline on a recorded trace, headless"),
    "batch": ("frictex.app.commands.batch", "replay many (scene, trace, renderer) jobs over the cores or a Dask cluster"),
    "trace": ("frictex.app.commands.trace", "synthesise or import touch traces"),
    "sim-device": ("frictex.app.commands.sim_device", "run a simulated plate microcontroller on a pseudo-terminal or TCP"),
    "bench": ("frictex.app.commands.bench", "measure speed: pipeline, link, visual layer, modal solves"),
    "modes": ("frictex.app.commands.modes", "natural frequencies, wavelengths and nodes of beams, plates and rings"),
    "report": ("frictex.app.commands.report", "speed against error over a matrix of scenes, motions and renderers"),
    "demo": ("frictex.app.commands.demo", "the live demo window (mouse or multi-touch as fingers)"),
    "preview": ("frictex.app.commands.preview", "render a scene and its friction map to a PNG"),
    "warm": ("frictex.app.commands.warm", "compile the pipeline's kernels now (setup does this once)"),
    "calibrate": ("frictex.app.commands.calibrate", "fit the friction model to a finger on a plate (simulated or real)"),
}


class OneLineParser(argparse.ArgumentParser):
    """argparse, but a bad command line is one line on stderr, ``frictex: error: ...``
    (exit 2), as every other error; ``--help`` still shows the usage."""

    def error(self, message: str):
        self.exit(2, f"frictex: error: {self.prog.removeprefix('frictex ')}: {message}\n"
                     if self.prog != "frictex" else f"frictex: error: {message}\n")


def version() -> str:
    """The installed frictex's version."""
    from importlib.metadata import PackageNotFoundError, version as installed
    try:
        return installed("frictex")
    except PackageNotFoundError:
        return "unknown (not installed)"


def build_parser() -> tuple[argparse.ArgumentParser, dict[str, argparse.ArgumentParser]]:
    parser = OneLineParser(
        prog="frictex",
        description="Render textures on ultrasonic friction-modulation touchscreens.")
    parser.add_argument("--version", action="version", version=f"frictex {version()}")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers = {}
    for name, (_, help_text) in COMMANDS.items():
        subparsers[name] = sub.add_parser(name, help=help_text, description=help_text)
    return parser, subparsers


def main(argv: list[str] | None = None) -> int:
    """Run ``frictex`` with ``argv`` (default: sys.argv[1:]); return the exit code."""
    keep_freed_memory()  # a replay's blocks would fault their pages in again every call
    argv = sys.argv[1:] if argv is None else argv
    parser, subparsers = build_parser()
    name = next((a for a in argv if not a.startswith("-")), None)
    module = None
    if name in COMMANDS:
        module = importlib.import_module(COMMANDS[name][0])
        module.add_arguments(subparsers[name])
    args = parser.parse_args(argv)
    if module is None:
        parser.print_help()
        return 2 if argv else 0
    try:
        return int(module.run(args) or 0)
    except BrokenPipeError:  # output piped into e.g. head, which stopped reading
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except KeyboardInterrupt:
        print("frictex: interrupted", file=sys.stderr)
        return 130
    except (ValueError, OSError) as exc:
        print(f"frictex: error: {exc}", file=sys.stderr)
        return 1 if run_failed(exc) else 2


def run_failed(exc: BaseException) -> bool:
    """True for errors of a run that could not finish (a device that stopped taking data,
    a disk that filled up): exit 1; anything else is bad input: exit 2."""
    if isinstance(exc, OSError) and exc.errno == errno.ENOSPC:
        return True
    from frictex.device.link.host import LinkStalled  # on the error path only: no cost to a run
    return isinstance(exc, LinkStalled)


def entry() -> NoReturn:
    """The ``frictex`` console script: :func:`main`, then the process ends.

    Once the command has returned (its outputs committed and closed), the atexit handlers
    run and the standard streams are flushed, but the interpreter's teardown is skipped:
    unloading numba's and scipy's modules object by object took 0.24 s of CPU after a
    one-second replay (paired runs, farm-bench), a quarter of what the user waits for.
    A thread still running gets the ordinary exit, which waits for it.
    """
    code = main()
    if threading.active_count() > 1:
        sys.exit(code)
    atexit._run_exitfuncs()
    sys.stdout.flush()
    sys.stderr.flush()
    os._exit(code)


if __name__ == "__main__":
    entry()
