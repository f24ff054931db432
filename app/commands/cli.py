"""The ``frictex`` command.

Each subcommand lives in its own module of ``app`` exposing
``add_arguments(parser)`` and ``run(args) -> int``; the module is imported only
when its subcommand runs, so ``frictex validate`` never loads OpenGL. Its import and
its options are inside the error handling below: an optional extra missing (``frictex
demo`` without ``gui``) or a plugin that breaks is one line, as any other error.

What escapes a command decides its exit status (``frictex.device.errors``):

- a :class:`FrictexError` is one line on stderr, ``frictex: error: ...``, and its kind's
  exit status: 2 for bad input (a file, an option, a name), 1 for the device, the disk
  or a run that could not do what was asked; one that found several problems at once
  (its ``problems``, e.g. a batch manifest's bad rows) is one such line per problem;
- an ``OSError`` the system raised (a file, a port, the disk) is one line too: exit 1,
  or 2 where it names a file the user gave that does not exist or cannot be read;
- an optional part of frictex that is not installed names the pip command (exit 1);
- Ctrl-C is one line, ``frictex: interrupted``, exit 130; SIGTERM or SIGHUP
  ``frictex: terminated by SIGTERM``, exit 128 + the signal; at any moment of the
  start-up too (``app.commands.entry``);
- anything else is a bug in frictex: its traceback, then ``frictex: internal error:
  please report``, exit 70 (EX_SOFTWARE), never dressed as the user's mistake.

Every message is printed with its control characters escaped (``\x1b``), so a value
that came from a file cannot drive the terminal.
"""

from __future__ import annotations

import argparse
import errno
import importlib
import os
import sys
import traceback

from frictex.app.commands.startup_signals import (StartupSignals, ignore_held_signals,
                                                   report_signal)
from frictex.app.engine.driver import Terminated
from frictex.app.engine.heap import keep_freed_memory
from frictex.device.errors import FrictexError, MissingExtra
from frictex.device.safe_text import printable

#: errno values of an OSError on a path the user named that is bad input (exit 2)
INPUT_ERRNOS = frozenset((errno.ENOENT, errno.ENOTDIR, errno.EISDIR, errno.EACCES,
                          errno.ENAMETOOLONG, errno.ELOOP))
#: module of an optional extra -> (extra, what needs it)
EXTRAS = {"moderngl": ("gui", "OpenGL drawing"), "glfw": ("gui", "the demo window"),
          "matplotlib": ("report", "plots and previews"), "dask": ("cluster", "a Dask cluster"),
          "distributed": ("cluster", "a Dask cluster"),
          "sounddevice": ("audio", "the audio output")}
#: report this, with the traceback above it, for anything frictex did not mean to raise
INTERNAL = ("frictex: internal error: please report it with the traceback above "
            "and the command line")

#: subcommand -> (module in app/, one-line help)
COMMANDS: dict[str, tuple[str, str]] = {
    "validate": ("frictex.app.commands.validate", "check texture files; report every problem with file, line and field"),
    "library": ("frictex.app.commands.library", "list the bundled scenes, traces and protocols"),
    "replay": ("frictex.app.commands.replay", "run the haptic pipeline on a recorded trace, headless"),
    "batch": ("frictex.app.commands.batch", "replay many (scene, trace, renderer) jobs over the cores or a Dask cluster"),
    "trace": ("frictex.app.commands.trace", "synthesise or import touch traces"),
    "sim-device": ("frictex.app.commands.sim_device", "run a simulated plate microcontroller on a pseudo-terminal or TCP"),
    "bench": ("frictex.app.commands.bench", "measure speed: pipeline, replay, link, visual layer, modal solves, start-up, the bare-numpy floor, touch-to-output latency"),
    "modes": ("frictex.app.commands.modes", "natural frequencies, wavelengths and nodes of beams, plates and rings"),
    "report": ("frictex.app.commands.report", "speed against error over a matrix of scenes, motions and renderers"),
    "demo": ("frictex.app.commands.demo", "the live demo window (mouse or multi-touch as fingers)"),
    "preview": ("frictex.app.commands.preview", "render a scene and its friction map to a PNG"),
    "warm": ("frictex.app.commands.warm", "compile the pipeline's kernels now (setup does this once)"),
    "calibrate": ("frictex.app.commands.calibrate", "fit the friction model to a finger on a plate (simulated or real)"),
    "experiment": ("frictex.app.commands.experiment", "run a psychophysical session from a protocol file; 'experiment analyse' fits its results"),
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


class _VersionAction(argparse.Action):
    """``--version``: the version is looked up only when asked, not by every command
    as it builds its parser (argparse's own ``version`` action takes the text made)."""

    def __init__(self, option_strings, dest=argparse.SUPPRESS, help=None):
        super().__init__(option_strings, dest, nargs=0, default=argparse.SUPPRESS,
                         help=help)

    def __call__(self, parser, namespace, values, option_string=None):
        print(f"frictex {version()}")
        parser.exit()


def build_parser() -> tuple[argparse.ArgumentParser, dict[str, argparse.ArgumentParser]]:
    parser = OneLineParser(
        prog="frictex",
        description="Render textures on ultrasonic friction-modulation touchscreens.")
    parser.add_argument("--version", action=_VersionAction,
                        help="show frictex's version and exit")
    sub = parser.add_subparsers(dest="command", metavar="COMMAND")
    subparsers = {}
    for name, (_, help_text) in COMMANDS.items():
        subparsers[name] = sub.add_parser(name, help=help_text, description=help_text)
    return parser, subparsers


def main(argv: list[str] | None = None, startup: StartupSignals | None = None) -> int:
    """Run ``frictex`` with ``argv`` (default: sys.argv[1:]); return the exit code.
    ``startup``: the signal handling already in place (``entry``'s); None: main puts its
    own in place for the call."""
    if startup is None:
        with StartupSignals() as startup:
            return main(argv, startup)
    keep_freed_memory()  # a replay's blocks would fault their pages in again every call
    argv = sys.argv[1:] if argv is None else argv
    parser, subparsers = build_parser()
    name = next((a for a in argv if not a.startswith("-")), None)
    environment = dict(os.environ)  # options such as --allow-outside set it for one run
    try:
        return _run(lambda: _command(parser, subparsers, name, argv), startup)
    finally:
        os.environ.clear()
        os.environ.update(environment)


def _command(parser, subparsers, name: str | None, argv: list[str]) -> int:
    """Import the subcommand ``name``'s module, parse ``argv`` and run it."""
    module = None
    if name in COMMANDS:
        module = importlib.import_module(COMMANDS[name][0])
        module.add_arguments(subparsers[name])
    args, extra = parser.parse_known_args(argv)
    if extra:  # said by the command's parser, so that the line names the command
        (subparsers[name] if module is not None else parser).error(
            f"unrecognized arguments: {' '.join(extra)}")
    if module is None:
        parser.print_help()
        return 2 if argv else 0
    return module.run(args)


def _run(command, startup: StartupSignals) -> int:
    """``command()`` (a subcommand's import, parsing and run), with what escapes it
    sorted as the module docstring says (what a signal that ``startup`` saw caused, as
    that signal)."""
    try:
        return int(command() or 0)
    except BrokenPipeError:  # output piped into e.g. head, which stopped reading
        os.dup2(os.open(os.devnull, os.O_WRONLY), sys.stdout.fileno())
        return 0
    except BaseException as exc:  # noqa: BLE001 - sorted into the kinds below
        if not isinstance(exc, (KeyboardInterrupt, Terminated)) and not startup.caused(exc):
            return report_error(exc)  # an error, one met while a signal ended the run too
        first = _first_signal(exc)
        if isinstance(first, Terminated):
            return report_error(first)
        return report_signal(getattr(first, "signum", None) or startup.signum)


def _first_signal(exc: BaseException) -> BaseException | None:
    """The exception of the signal that ended the command, where ``exc`` or one it was
    raised while handling stands for a signal (a KeyboardInterrupt, a run's
    ``Terminated``): the earliest of them (a SIGTERM that ended a run, not a SIGHUP
    during its cleanup). A fan-out's ``Interrupted`` carries its signal (``signum``), as
    ``Terminated`` does; None: no signal."""
    first = None
    while exc is not None:
        if isinstance(exc, (KeyboardInterrupt, Terminated)):
            first = exc
        exc = exc.__context__
    return first


def report_error(exc: BaseException) -> int:
    """Print what escaped a command as the module docstring says; return the exit status.
    SystemExit passes through (a run's SIGTERM or SIGHUP says so first)."""
    if isinstance(exc, SystemExit):
        if isinstance(exc, Terminated):
            ignore_held_signals()
            print(f"frictex: {exc.reason}", file=sys.stderr)
        raise exc
    if isinstance(exc, ModuleNotFoundError) and (exc.name or "").split(".")[0] in EXTRAS:
        extra, what = EXTRAS[exc.name.split(".")[0]]
        exc = MissingExtra(extra, what, exc.name.split(".")[0])
    if isinstance(exc, FrictexError):
        code = exc.exit_code
    elif isinstance(exc, OSError):
        code = 2 if exc.errno in INPUT_ERRNOS and exc.filename is not None else 1
    else:
        traceback.print_exception(exc, file=sys.stderr)
        print(INTERNAL, file=sys.stderr)
        return 70
    for line in getattr(exc, "error_lines", None) or (str(exc),):  # a manifest's: each
        print(f"frictex: error: {printable(line)}", file=sys.stderr)
    return code
