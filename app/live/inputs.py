"""The demo's touch inputs by name (``--input NAME[:ARG]``): a Protocol and a registry.

An input is either the window's mouse (``mouse``; ``follow``, the mouse and a second
finger following it) or a touch screen the haptic side reads itself as its samples
arrive (``tuio``, ``evdev``; ``app.live.touch_pump``). Each is an :class:`InputKind`
registered in :data:`INPUTS` under its name; another package adds one through the
entry-point group ``frictex.inputs``::

    [project.entry-points."frictex.inputs"]
    mytablet = "frictex_mytablet:TabletInput"      # an InputKind instance

A touch screen's ``open`` returns a :class:`TouchSource`. Its positions are normalised
to 0..1 of the active area and stamped on ``time.monotonic`` (the pump maps them to the
scene's mm and to the haptic clock).
"""

from __future__ import annotations

import math
import os
from dataclasses import dataclass
from typing import Protocol, runtime_checkable

from frictex.device.errors import InputError
from frictex.device.registry import Registry

FOLLOW_OFFSET_MM = 30.0  # the follower finger's default offset along x


@runtime_checkable
class TouchSource(Protocol):
    """A touch screen as the pump reads it (``app.live.touch_pump.TouchPump``)."""

    def wait(self, timeout_s: float) -> bool:
        """Return when samples may be ready, or after ``timeout_s`` s."""

    def poll(self) -> list:
        """The samples received since the last call (``TouchSample``), never blocking."""

    def close(self) -> None:
        """Release the device or socket."""


class InputKind(Protocol):
    """One ``--input`` kind: ``usage`` (its syntax, for help and errors), ``help`` (one
    sentence), ``touch_screen`` (True: read by the haptic side through :meth:`open`;
    False: the window's mouse), :meth:`parse`, :meth:`label` and :meth:`open`."""

    usage: str
    help: str
    touch_screen: bool

    def parse(self, arg: str | None) -> object:
        """The argument after ``NAME:`` (None: no colon), checked; raises InputError."""

    def label(self, arg) -> str:
        """How the status line and the summary name the input."""

    def open(self, arg, **options) -> TouchSource:
        """The touch source (touch screens only); raises OSError or InputError."""


INPUTS: Registry[InputKind] = Registry("touch input", "frictex.inputs")


class _Mouse:
    usage = "mouse"
    help = "the mouse is finger 0 while the left button is held"
    touch_screen = False

    def parse(self, arg):
        if arg is not None:
            raise InputError("mouse takes no argument")
        return None

    def label(self, arg) -> str:
        return "mouse"

    def open(self, arg, **options):
        raise InputError("the mouse is read by the window, not opened as a touch source")


class _Follow(_Mouse):
    usage = "follow[:MM]"
    help = (f"the mouse is finger 0 and finger 1 follows it MM mm to the right along x "
            f"(default {FOLLOW_OFFSET_MM:g}; seed 001's two-finger test), touching while "
            "that point is on the display")

    def parse(self, arg):
        try:
            offset = float(arg) if arg is not None else FOLLOW_OFFSET_MM
        except ValueError:
            offset = math.nan
        if not (math.isfinite(offset) and offset != 0.0):
            raise InputError("expected follow:OFFSET_MM, a non-zero number of mm (e.g. follow:30)")
        return offset

    def label(self, arg) -> str:
        return f"follow {arg:g} mm"


@dataclass(frozen=True)
class TuioSpec:
    """Where ``--input tuio`` listens (IPv4 ``host``, UDP ``port``) and whom it accepts
    (``accept_from``: ``rendering.input.tuio.parse_sender``'s (address, port or None),
    or None: the first sender). Raises InputError for a sender the listener could never
    hear (``rendering.input.tuio.unreachable_sender``): an error rather than a warning, as
    the demo would run with no finger ever moving and nothing said."""

    host: str
    port: int
    accept_from: tuple[str, int | None] | None = None

    def __post_init__(self) -> None:
        from frictex.rendering.input.tuio import unreachable_sender
        problem = unreachable_sender(self.host, self.accept_from)
        if problem is not None:
            raise InputError(problem)


class _Tuio:
    usage = "tuio[:[HOST:]PORT]"
    touch_screen = True

    @property
    def help(self) -> str:
        from frictex.rendering.input.tuio import SILENCE_S, TUIO_HOST, TUIO_PORT
        return (f"TUIO 1.1 cursors on UDP PORT (default {TUIO_PORT}, 0: any free port), "
                f"listening on {TUIO_HOST} unless HOST says otherwise (0.0.0.0: every "
                f"interface); one sender at a time (see --tuio-from), whose fingers are "
                f"lifted after {SILENCE_S:g} s of silence, when another may take over")

    def parse(self, arg):
        import ipaddress
        from frictex.rendering.input.tuio import TUIO_HOST, TUIO_PORT
        host, colon, port_text = (arg or "").rpartition(":")
        host = host if colon else TUIO_HOST
        try:
            host = str(ipaddress.IPv4Address(host))
            port = int(port_text) if arg is not None else TUIO_PORT
        except ValueError:
            port = -1
        if not 0 <= port <= 65535:
            raise InputError("expected tuio:PORT or tuio:HOST:PORT, an IPv4 address and a UDP "
                             "port 0 to 65535 (0: any free port)")
        return TuioSpec(host, port)

    def label(self, arg: TuioSpec) -> str:
        return f"tuio {arg.host}:{arg.port}"

    def open(self, arg: TuioSpec, **options):
        from frictex.rendering.input.tuio import TuioListener
        source = TuioListener(arg.port, host=arg.host, accept_from=arg.accept_from,
                              width_mm=1.0, height_mm=1.0)
        whom = ("one sender at a time" if arg.accept_from is None
                else f"from {arg.accept_from[0]}:{arg.accept_from[1] or '*'} only")
        print(f"demo: listening for TUIO 1.1 cursors on UDP {arg.host}:{source.port}, "
              f"accepting {whom}", flush=True)
        return source


class _Evdev:
    usage = "evdev:PATH"
    help = "a Linux multi-touch device such as /dev/input/event5 spanning the scene's display"
    touch_screen = True

    def parse(self, arg):
        if not arg:
            raise InputError("expected evdev:PATH (e.g. evdev:/dev/input/event5)")
        return arg

    def label(self, arg) -> str:
        return f"evdev {arg}"

    def open(self, arg, **options):
        from frictex.rendering.input.evdev_decode import RangeUnknown, ScreenSpec
        from frictex.rendering.input.evdev_live import EvdevReader
        if not os.path.exists(arg):
            raise InputError(f"evdev:{arg}: no such device (expected a path such as "
                             "/dev/input/event5)")
        try:
            return EvdevReader(arg, ScreenSpec(normalised=True))
        except RangeUnknown:  # no axis ranges: a file, a pipe, not a touch screen
            # the reader's own words advise options of 'trace import', which the demo lacks
            raise InputError(f"evdev:{arg} is not a multi-touch device reporting its axis "
                             "ranges (ABS_MT_POSITION_X and _Y); the demo takes them from the "
                             "device (a getevent or evemu recording can be converted with "
                             "'frictex trace import' and replayed)") from None


INPUTS.register("mouse", _Mouse())
INPUTS.register("follow", _Follow())
INPUTS.register("tuio", _Tuio())
INPUTS.register("evdev", _Evdev())


def parse_input(text: str) -> tuple[str, object]:
    """``--input NAME[:ARG]`` as (name, parsed argument); raises InputError (an unknown
    name lists the known ones)."""
    name, colon, arg = text.partition(":")
    kind = INPUTS.get(name)
    try:
        return name, kind.parse(arg if colon else None)
    except InputError as exc:
        raise InputError(f"{text[:80]!r}: {exc}") from None


def open_source(name: str, arg, **options) -> TouchSource:
    """The touch source of a touch-screen input (``INPUTS[name].open``)."""
    return INPUTS.get(name).open(arg, **options)
