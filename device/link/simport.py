"""``sim://``: the simulated device in this process, behind a pyserial-like port.

:class:`SimDevice` binds a sans-IO :class:`~device.link.simdevice.DeviceCore` to the wall
clock; :meth:`SimDevice.open` gives a :class:`SimPort` onto it, which the host's port
thread reads and writes like a serial port. The device has no thread of its own: every
call on its port first plays the ticks up to now, so it runs exactly as far as the wall
clock, and while nobody calls (the host's thread stopped) its clock still counts: the
next call plays the silence, and its watchdog trips as a real device's would: a write
plays the ticks up to now before its bytes are taken (they arrive now, so the silence
before them is played first; ``simdevice.serve`` takes bytes first because they may have
waited in the socket while its process was not scheduled).
No process is started and nothing waits for one.

URL form (pyserial's style, ``sim://?name=value&...``), each option a
:class:`~device.link.simdevice.DeviceConfig` field under its ``frictex sim-device``
flag's name: ``limit`` (um, repeatable), ``buffer``, ``watchdog-ms``, ``ramp-ms``,
``sensor`` (0/1), ``force``, ``lateral``, ``finger``, ``finger-speed``, ``protocol``.
The channels, the rate and the phases are the pipeline's.
"""

from __future__ import annotations

import time
from urllib.parse import parse_qsl

from frictex.device.errors import InputError
from frictex.device.link.port import READ_WAIT_S
from frictex.device.link.simdevice import DeviceConfig, DeviceCore, played_log

#: option name -> (DeviceConfig field, type)
OPTIONS = {"limit": ("limits_um", float), "buffer": ("buffer_samples", int),
           "watchdog-ms": ("watchdog_ms", int), "ramp-ms": ("ramp_ms", int),
           "sensor": ("sensor", bool), "force": ("force_n", float),
           "lateral": ("lateral_n", float), "finger": ("finger", int),
           "finger-speed": ("finger_speed_mm_s", float), "protocol": ("protocol_version", int)}


def sim_config(pairs, channels: int, rate_hz: float, phases: bool) -> DeviceConfig:
    """A :class:`DeviceConfig` from (option, text) pairs (see the module docstring).

    Raises :class:`InputError` naming an unknown option, a bad value, or a value the
    device refuses.
    """
    fields: dict = {"channels": int(channels), "rate_hz": float(rate_hz), "phases": bool(phases)}
    limits = []
    for name, text in pairs:
        if name not in OPTIONS:
            raise InputError(f"sim device option {name!r}: expected one of {', '.join(OPTIONS)}")
        field, kind = OPTIONS[name]
        try:
            value = (text not in ("0", "false", "no")) if kind is bool else kind(text)
        except ValueError:
            raise InputError(f"sim device option {name}={text!r}: expected "
                             f"{'an integer' if kind is int else 'a number'}") from None
        if field == "limits_um":
            limits.append(value)
        else:
            fields[field] = value
    if limits:
        fields["limits_um"] = tuple(limits)
    try:
        return DeviceConfig(**fields)
    except ValueError as exc:
        raise InputError(str(exc)) from None


def parse_sim_url(url: str, channels: int, rate_hz: float, phases: bool) -> DeviceConfig:
    """The :class:`DeviceConfig` of ``sim://?option=value&...`` (module docstring)."""
    _, _, query = url.partition("?")
    return sim_config(parse_qsl(query, keep_blank_values=True), channels, rate_hz, phases)


class SimDevice:
    """A :class:`DeviceCore` on the wall clock (``clock``, s), in this process.

    ``log_path``: the played-sample CSV (``simdevice.played_log``), closed by
    :meth:`close`. The core is reached through :meth:`open`, as often as the host
    reopens it (a reconnect finds the same device, its clock having run on).
    """

    def __init__(self, config: DeviceConfig, log_path=None, clock=time.monotonic):
        self.core = DeviceCore(config)
        self._csv = None
        if log_path is not None:
            self.core.log, self._csv = played_log(log_path, config.channels, config.phases)
        self._clock = clock
        self._t0 = clock()

    def now(self) -> float:
        """Seconds on the device's clock."""
        return self._clock() - self._t0

    def open(self) -> SimPort:
        """A port onto the device (an opener for the host's link)."""
        return SimPort(self)

    def close(self) -> None:
        """Close the played-sample log, if any."""
        if self._csv is not None:
            self._csv.close()
            self._csv = None


class SimPort:
    """The pyserial calls the host's port thread makes (``read``, ``in_waiting``,
    ``write``, ``close``) on a :class:`SimDevice`."""

    def __init__(self, device: SimDevice, timeout: float = READ_WAIT_S):
        self._device = device
        self._out = bytearray()
        self.timeout = timeout
        self.is_open = True

    def _advance(self) -> None:
        self._out += self._device.core.advance_to(self._device.now())

    def _check(self) -> None:
        if not self.is_open:
            raise OSError("sim:// port is closed")

    @property
    def in_waiting(self) -> int:
        """Bytes the device has sent and nobody read yet (as of the last call)."""
        self._check()
        return len(self._out)

    def read(self, size: int = 1) -> bytes:
        """Up to ``size`` bytes the device sent, waiting ``timeout`` if it had none: the
        device speaks on its own only at its ticks (force reports, a watchdog's Flushed),
        which the next call plays, so one wait per read does (a poll every tick would
        cost the host's CPU for nothing)."""
        self._check()
        self._advance()
        if not self._out:
            time.sleep(self.timeout)
            self._advance()
        data = bytes(self._out[:size])
        del self._out[:size]
        return data

    def write(self, data: bytes) -> int:
        self._check()
        self._advance()  # the silence before these bytes trips the watchdog (PROTOCOL.md 5.3)
        self._out += self._device.core.receive(bytes(data), self._device.now())
        return len(data)

    def close(self) -> None:
        self.is_open = False
