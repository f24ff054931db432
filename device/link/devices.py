"""Output devices by name: the registry ``--device NAME[:ARG]`` is looked up in.

:data:`DEVICES` is a :class:`~device.registry.Registry` (entry-point group
``frictex.devices``): another package adds an output device with one module and one
entry point::

    [project.entry-points."frictex.devices"]
    mydev = "mypkg.mydev:open_mydev"

``open_mydev(arg, request)`` gets ARG (the text after ``mydev:``, or after ``mydev://``;
"" when none) and a :class:`DeviceRequest`, and returns an :class:`OutputDevice`. Raise
``frictex.device.errors.InputError`` for a bad ARG (exit 2) and ``DeviceError`` when the
device cannot be reached (exit 1). A request with ``faults`` is refused for another
package's device before its factory is called: frictex injects faults into its own
serial links only (``sim``, ``port``). Anything else another package's factory or device
raises (and a factory that is not callable, or returns no :class:`OutputDevice`) is a
``PluginError`` naming the package (exit 1), not frictex's internal error
(:func:`open_device`, :class:`PluginDevice`).

``device.link.host.open_sink`` is what the engine calls; importing ``device.link.host``
registers the built-ins: ``sim`` (the simulated device in this process, ``device.link.simport``; ARG:
its options, ``sim:finger=3,force=0.5``) and ``port`` (a serial port or pyserial URL,
``device.link.port``). :func:`resolve` reads a spec: ``NAME://...`` goes to the device
NAME if one is registered, a pyserial URL of a scheme ``device.link.port.URL_SCHEMES``
names to ``port``, any other is refused listing both; ``NAME[:ARG]`` to NAME if one is
registered, else a path (``/dev/ttyACM0``, ``./tty``, ``COM3``) to ``port``.
"""

from __future__ import annotations

import os
import re
import sys
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Protocol, runtime_checkable
from urllib.parse import parse_qsl

import numpy as np

from frictex.device.errors import InputError
from frictex.device.link.port import URL_SCHEMES
from frictex.device.link.session import PREFILL_S
from frictex.device.link.status_contract import status_problem
from frictex.device.registry import (OWN_DISTRIBUTION, Expect, PluginError, Registry,
                                     build_entry, guarded, warn_once)


@dataclass(frozen=True)
class DeviceRequest:
    """What the pipeline asks of an output device (``open_sink``'s arguments).

    channels : actuator channels per sample. rate_hz : samples per second (Hz); the
    device must play at it. phases : a phase (rad) comes with each amplitude.
    paced : True: :meth:`OutputDevice.send` may wait for the device (replay); False: it
    never blocks (live). queue_blocks : blocks a link may hold before the device takes
    them. log_path : a played-sample CSV (simulated devices). faults : a
    ``device.link.faults.FaultPlan`` to inject on a link, or None. stderr : where
    warnings go. stall_s, max_stalls : bound of one wait (s), and its multiple a paced
    link may spend without progress. sim_args : ``frictex sim-device`` flags (``sim``).
    profile : the scene's device profile (``device.profile.PROFILES``), for a device
    whose drive depends on the plate (an audio output's carrier and um per volt), or None.
    prefill_s, catch_up : a link's jitter-buffer prefill (s) and live catch-up
    (``device.link.host.open_sink``).
    """

    channels: int
    rate_hz: float
    phases: bool = False
    paced: bool = False
    queue_blocks: int = 64
    log_path: Any = None
    faults: Any = None
    stderr: Any = sys.stderr
    stall_s: float = 1.0
    max_stalls: int = 5
    sim_args: tuple[str, ...] = ()
    profile: str | None = None
    prefill_s: float = PREFILL_S
    catch_up: bool = False

    def link_options(self) -> dict:
        """The keyword arguments of ``device.link.host.CommandSink`` this request sets."""
        return {"phases": self.phases, "paced": self.paced, "queue_blocks": self.queue_blocks,
                "stderr": self.stderr, "stall_s": self.stall_s, "max_stalls": self.max_stalls,
                "prefill_s": self.prefill_s, "catch_up": self.catch_up,
                "injected": None if self.faults is None else str(self.faults)}


@runtime_checkable
class OutputDevice(Protocol):
    """What the engine, the live haptic thread and calibration call on an output device
    (the contract :class:`~device.link.host.CommandSink` implements).

    Attributes: ``label`` (str, its name in messages), ``channels``, ``rate_hz`` (Hz),
    ``paced`` (as requested) and ``info`` (a ``device.link.protocol.Info``: what the
    device declared; the engine reads ``info.has_force_reports``, calibration
    ``info.limits_um``).

    A device may also have ``abort()``: stop at once, dropping what is queued, the plate
    ramped to zero, the device released (bounded, idempotent, never raising for the
    stream's faults). A run stopped by a signal or an error calls it where the device
    has one (:class:`CommandSink` and the audio stream do), :meth:`close` otherwise.
    """

    label: str
    channels: int
    rate_hz: float
    paced: bool

    def send(self, start_index: int, amplitudes_um: np.ndarray,
             phases_rad: np.ndarray | None = None) -> None:
        """Play (n, channels) amplitudes (um, zero-to-peak, float64) from output sample
        ``start_index`` on, ``phases_rad`` (n, channels) with them when requested.
        Blocks arrive in order of ``start_index``, without gaps. Paced: may wait, bounded;
        live: never waits (drops, counted, instead). Raises a ``DeviceError`` when the
        device has failed for good."""

    def wait_for_room(self, timeout_s: float) -> bool:
        """Wait at most ``timeout_s`` (s) until :meth:`send` of one more block would not
        wait; False on timeout. True at once when not paced."""

    def status(self) -> dict:
        """JSON-able counters for ``summary.json``'s ``device`` section; the engine reads
        ``commanded_samples``, ``unplayed_samples`` and ``unplayed_by_cause`` (a dict of
        cause -> samples) and, when the keys are there, ``state`` and ``underruns``."""

    def unplayed_share(self) -> float:
        """Commanded samples that never played, over all commanded (0 when none were);
        final once :meth:`close` has returned."""

    def device_force_n(self) -> float | None:
        """The normal force (N) the device last measured, or None."""

    def force_report(self, index0: int | None = None, n: int | None = None):
        """Lateral and normal force (N) per sample (``device.link.forces.ForceReport``):
        the latest report without arguments, else samples ``index0 .. index0 + n - 1``
        exactly or None. None when the device has no lateral force sensor."""

    def forces_covered(self, index0: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        """The (lateral, normal) forces (N) of those samples of the window the device
        reported, in sample order; empty arrays if none."""

    def close(self) -> None:
        """Play out what was sent (paced: bounded), stop the device, release it.
        Idempotent; never raises for the stream's faults."""

    def __enter__(self) -> OutputDevice: ...

    def __exit__(self, *exc) -> None: ...


#: ``factory(arg, request) -> OutputDevice``, by name
DeviceFactory = Callable[[str, DeviceRequest], OutputDevice]
DEVICES: Registry[DeviceFactory] = Registry(
    "output device", "frictex.devices",
    expect=Expect.factory("a factory(arg, request) returning an OutputDevice"))
_COM = re.compile(r"COM\d+", re.IGNORECASE)


def resolve(spec: str) -> tuple[DeviceFactory, str]:
    """The factory and ARG of a ``--device`` spec (see the module docstring); an unknown
    NAME is ``UnknownName`` (an InputError) listing the known."""
    name, arg = _named(spec)
    return DEVICES.get(name), arg


def open_device(spec: str, request: DeviceRequest) -> OutputDevice:
    """The output device of a ``--device`` spec, opened for ``request``: frictex's own as
    its factory returns it, another package's checked and wrapped in a
    :class:`PluginDevice` (the module docstring), or refused (InputError) where the
    request has faults, which only frictex's serial links inject."""
    name, arg = _named(spec)
    if request.faults is not None and DEVICES.origin(name) != OWN_DISTRIBUTION:
        raise InputError(f"device {spec!r}: faults are injected into frictex's serial links "
                         f"(sim or a port), not into output device {name!r} of "
                         f"{DEVICES.origin(name)}, another package's")
    return build_entry(DEVICES, "output device", name, arg, request, doing="opening",
                       members=_MEMBERS, release="close",
                       contract="an OutputDevice (frictex.device.link.devices.OutputDevice)",
                       wrap=PluginDevice)


def _named(spec: str) -> tuple[str, str]:
    """The registered name (or ``port``) and ARG of a ``--device`` spec."""
    if not isinstance(spec, str) or not spec.strip():
        raise InputError(f"device {spec!r}: expected NAME[:ARG], a URL or a port path")
    if "://" in spec:
        scheme, _, rest = spec.partition("://")
        if scheme in DEVICES:
            return scheme, rest
        if scheme not in URL_SCHEMES:
            raise InputError(f"device {spec!r}: unknown URL scheme {scheme!r}; expected a "
                             f"device ({', '.join(DEVICES.names())}) or a pyserial URL "
                             f"({', '.join(s + '://' for s in URL_SCHEMES)})")
        return "port", spec
    name, _, arg = spec.partition(":")
    if name in DEVICES:
        return name, arg
    if spec.startswith(("/", ".")) or _COM.fullmatch(spec) or (os.sep in spec and not arg):
        return "port", spec
    return name, arg  # NAME:ARG of a device not installed: DEVICES.get lists the known


#: what :func:`open_device` requires of another package's device
_MEMBERS = ("label", "channels", "rate_hz", "paced", "info", "send", "wait_for_room",
            "status", "unplayed_share", "device_force_n", "force_report", "forces_covered",
            "close")


class PluginDevice:
    """Another package's output device (``inner``), whose methods raise a
    :class:`PluginError` naming it for anything but frictex's own errors
    (``registry.guarded``); its other attributes are the inner device's. ``abort`` is the
    inner device's, or its ``close``; one that raises while a run is already failing is a
    warning, so that the run's own error is the one reported."""

    def __init__(self, inner: OutputDevice, who: str):
        self.inner = inner
        self._who = who

    def __getattr__(self, name: str):
        return getattr(self.inner, name)

    def send(self, start_index: int, amplitudes_um: np.ndarray,
             phases_rad: np.ndarray | None = None) -> None:
        guarded(self._who, "in send()", self.inner.send, start_index, amplitudes_um,
                phases_rad)

    def wait_for_room(self, timeout_s: float) -> bool:
        return guarded(self._who, "in wait_for_room()", self.inner.wait_for_room, timeout_s)

    def status(self) -> dict:
        """The inner device's status; one that breaks the contract
        (``device.link.status_contract``) is a PluginError naming the package."""
        status = guarded(self._who, "in status()", self.inner.status)
        problem = status_problem(status)
        if problem is not None:
            raise PluginError(f"{self._who} returned {problem} from status(); expected a "
                              "dict of counts (commanded_samples, unplayed_samples, "
                              "unplayed_by_cause) that JSON can hold")
        return status

    def unplayed_share(self) -> float:
        return guarded(self._who, "in unplayed_share()", self.inner.unplayed_share)

    def device_force_n(self) -> float | None:
        return guarded(self._who, "in device_force_n()", self.inner.device_force_n)

    def force_report(self, index0: int | None = None, n: int | None = None):
        return guarded(self._who, "in force_report()", self.inner.force_report, index0, n)

    def forces_covered(self, index0: int, n: int) -> tuple[np.ndarray, np.ndarray]:
        return guarded(self._who, "in forces_covered()", self.inner.forces_covered, index0, n)

    def close(self) -> None:
        guarded(self._who, "in close()", self.inner.close)

    def abort(self) -> None:
        try:
            guarded(self._who, "in abort()", getattr(self.inner, "abort", self.inner.close))
        except PluginError as exc:
            warn_once(str(exc))

    def __enter__(self) -> PluginDevice:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def sim_pairs(arg: str, sim_args: tuple[str, ...]) -> list[tuple[str, str]]:
    """(option, text) pairs of ``sim:ARG`` (``a=1,b=2``; a URL query ``?a=1&b=2``) and of
    ``frictex sim-device`` flags (``--a 1 --b 2``, ``--sensor`` alone)."""
    pairs = parse_qsl(arg.lstrip("/").lstrip("?").replace(",", "&"), keep_blank_values=True,
                      strict_parsing=False)
    if arg.strip("/?") and not pairs:
        raise InputError(f"sim device options {arg!r}: expected NAME=VALUE[,NAME=VALUE...]")
    flags = list(sim_args)
    while flags:
        flag = flags.pop(0)
        if not flag.startswith("--"):
            raise InputError(f"sim device flag {flag!r}: expected --NAME [VALUE]")
        value = flags.pop(0) if flags and not flags[0].startswith("--") else "1"
        pairs.append((flag[2:], value))
    return pairs
