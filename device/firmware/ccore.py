"""The C firmware core on a virtual clock, behind the reference device's interface.

:class:`CDeviceCore` takes a :class:`device.link.simdevice.DeviceConfig` and the same
``log`` / ``plate_log`` callables as :class:`device.link.simdevice.DeviceCore`, and offers
what that class offers (``receive``, ``advance_to``, ``status``, ``state``, ``level``,
``play_index``, ``buffer_end``, ``counters``, ``session``, ``decoder.counts``,
``setpoint``, ``plate_um``, ``finished``), so one test suite runs against both. It drives
``build/host/libfwsim.so`` (``host/sim_lib.c``): the same core and plate model as the pty
host port. Its lateral force sensor reads, per tick, what the Python ``sensor`` reads
(a constant for ``DeviceConfig.lateral_n``); the board has no simulated finger, so a
sensor that reads the setpoints (``DeviceConfig.finger``) is refused, and its ForceReports
have a fixed shape (``host/params.c``, ``FW_FORCE_PAIRS``), so another
``force_decimation`` or ``force_pairs`` is refused too.
"""

from __future__ import annotations

import ctypes
from pathlib import Path
from types import SimpleNamespace

import numpy as np

from frictex.device.link import protocol as p

_CHUNK = 65536
# host/sim_lib.c fwsim_counters, in order
_VALUES = ("state", "level", "play_index", "buffer_end", "tick", "stopped", "finished",
           "prefill", "underruns", "gap_samples", "late_samples", "overflow_samples",
           "watchdog_trips", "clamped", "played_samples", "session_played",
           "session_flushed", "session_flushes", "frames_ok", "lost_frames", "crc_errors",
           "cobs_errors", "short_frames", "oversize", "bad_version", "unknown_type",
           "bad_payload")
_DROPS = ("crc_errors", "cobs_errors", "short_frames", "oversize", "bad_version",
          "unknown_type", "bad_payload")
_libs: dict[Path, tuple[ctypes.CDLL, type]] = {}
#: ticks per ForceReport value on the host board (host/params.c)
BOARD_FORCE_DECIMATION = 4
#: values per ForceReport (FW_FORCE_PAIRS, core/fw_limits.h)
BOARD_FORCE_PAIRS = 10


def _load(path: Path):
    if path not in _libs:
        lib = ctypes.CDLL(str(path))
        maxch = lib.fwsim_max_channels()

        class Params(ctypes.Structure):  # host/params.h host_params
            _fields_ = [("channels", ctypes.c_ulong), ("rate_hz", ctypes.c_double),
                        ("limits_um", ctypes.c_double * maxch), ("n_limits", ctypes.c_uint),
                        ("buffer_samples", ctypes.c_ulong), ("bandwidth_hz", ctypes.c_double),
                        ("watchdog_ms", ctypes.c_ulong), ("ramp_ms", ctypes.c_ulong),
                        ("phases", ctypes.c_bool), ("sensor", ctypes.c_bool),
                        ("has_force", ctypes.c_bool), ("has_lateral", ctypes.c_bool),
                        ("force_n", ctypes.c_double), ("lateral_n", ctypes.c_double),
                        ("name", ctypes.c_char_p), ("protocol_version", ctypes.c_ulong)]

        lib.fwsim_size.restype = ctypes.c_size_t
        lib.fwsim_init.restype = ctypes.c_char_p
        lib.fwsim_init.argtypes = [ctypes.c_void_p, ctypes.POINTER(Params)]
        lib.fwsim_receive.restype = ctypes.c_size_t
        lib.fwsim_receive.argtypes = [ctypes.c_void_p, ctypes.c_char_p, ctypes.c_size_t,
                                      ctypes.c_double, ctypes.c_void_p, ctypes.c_size_t]
        lib.fwsim_advance.restype = ctypes.c_size_t
        lib.fwsim_advance.argtypes = [ctypes.c_void_p, ctypes.c_double, ctypes.c_size_t] + [
            ctypes.c_void_p] * 7
        lib.fwsim_counters.argtypes = [ctypes.c_void_p, ctypes.c_void_p]
        lib.fwsim_poll.restype = ctypes.c_size_t
        lib.fwsim_poll.argtypes = [ctypes.c_void_p, ctypes.c_void_p, ctypes.c_size_t]
        _libs[path] = (lib, Params)
    return _libs[path]


class CDeviceCore:
    """The C core with the interface of the reference ``DeviceCore`` (see module docstring).

    ``sensor`` (used only when ``config.force_reports``, as ``DeviceCore`` does) must be a
    pure function of the tick: :meth:`advance_to` reads it one report's span
    (``force_decimation * force_pairs`` ticks) ahead of the core and plays at most those
    ticks per pass; ticks a pass does not reach (it ends at each completed report) are
    read again on the next.
    """

    def __init__(self, config, log=None, plate_log=None, sensor=None, *,
                 library: Path | None = None):
        if library is None:
            from frictex.device.firmware.build import sim_library
            library = sim_library()
        self._lib, params_type = _load(Path(library))
        self.config = config
        self.log = log
        self.plate_log = plate_log
        if config.finger is not None and sensor is None:
            raise ValueError("the C core's host board has no simulated finger; give it a "
                             "sensor that does not read the setpoints")
        shape = (config.force_decimation, config.force_pairs)
        if shape != (BOARD_FORCE_DECIMATION, BOARD_FORCE_PAIRS):
            raise ValueError("the C core's host board reports forces with force_decimation "
                             f"{BOARD_FORCE_DECIMATION} and force_pairs {BOARD_FORCE_PAIRS} "
                             f"only (got {shape[0]} and {shape[1]})")
        # as DeviceCore: a sensor is read only if Info announces ForceReports
        self.sensor = None if not config.force_reports else \
            (config.force_sensor() if sensor is None else sensor)
        #: ticks read ahead of the core, and played, per pass: fwsim_advance returns after
        #: every completed report, so a pass rarely uses more than one report's span
        self._ahead = max(1, min(config.force_decimation * config.force_pairs, _CHUNK))
        limits = tuple(config.limits_um)
        self._name = config.name.encode("utf-8")  # the core keeps a pointer to it
        params = params_type(
            channels=config.channels, rate_hz=config.rate_hz, n_limits=len(limits),
            buffer_samples=config.buffer_samples, bandwidth_hz=config.bandwidth_hz,
            watchdog_ms=config.watchdog_ms, ramp_ms=config.ramp_ms, phases=config.phases,
            sensor=config.sensor, has_force=config.force_n is not None,
            has_lateral=config.force_reports, force_n=config.force_n or 0.0,
            lateral_n=config.lateral_n or 0.0, name=self._name,
            protocol_version=config.protocol_version)
        for i, x in enumerate(limits[:len(params.limits_um)]):
            params.limits_um[i] = x
        self._mem = ctypes.create_string_buffer(self._lib.fwsim_size())
        problem = self._lib.fwsim_init(self._mem, ctypes.byref(params))
        if problem:
            raise ValueError(f"firmware config: {problem.decode()}")
        ch = config.channels
        self.setpoint = np.zeros(ch)
        self.plate_um = np.zeros(ch)
        self._buf = (np.empty((_CHUNK, ch), np.uint16), np.empty((_CHUNK, ch)),
                     np.empty(_CHUNK, np.uint8), np.empty(_CHUNK, np.uint8),
                     np.empty(_CHUNK, np.uint64), np.empty((_CHUNK, ch), np.uint16))
        self._forces = np.zeros((_CHUNK, 2), np.int16)

    def _values(self) -> dict:
        out = (ctypes.c_uint64 * len(_VALUES))()
        self._lib.fwsim_counters(self._mem, out)
        return dict(zip(_VALUES, out))

    def __getattr__(self, name):
        if name in ("state", "level", "play_index", "buffer_end", "tick", "prefill"):
            return self._values()[name]
        raise AttributeError(name)

    @property
    def finished(self) -> bool:
        return bool(self._values()["finished"])

    @property
    def stopped(self) -> bool:
        return bool(self._values()["stopped"])

    @property
    def counters(self) -> SimpleNamespace:
        v = self._values()
        return SimpleNamespace(**{k: v[k] for k in (
            "underruns", "gap_samples", "late_samples", "overflow_samples", "watchdog_trips",
            "clamped", "played_samples")})

    @property
    def session(self) -> SimpleNamespace:
        v = self._values()
        return SimpleNamespace(played=v["session_played"], flushed=v["session_flushed"],
                               flushes=v["session_flushes"])

    @property
    def decoder(self) -> SimpleNamespace:
        v = self._values()
        counts = SimpleNamespace(**{k: v[k] for k in ("frames_ok", "lost_frames", *_DROPS)},
                                 discarded=sum(v[k] for k in _DROPS))
        return SimpleNamespace(counts=counts)

    def status(self, echo: int) -> p.Status:
        """The device's current Status, as the reference builds it (version 2 fields)."""
        v, c = self._values(), self.config
        return p.Status(echo & 0xFFFFFFFF, v["state"], v["play_index"], v["level"],
                        v["underruns"], self.decoder.counts.discarded, v["frames_ok"],
                        v["lost_frames"], v["gap_samples"], v["late_samples"],
                        v["overflow_samples"], v["watchdog_trips"], v["clamped"],
                        tuple(self.plate_um) if c.sensor else None, c.force_n,
                        v["buffer_end"] % 2**64, v["session_played"], v["session_flushed"],
                        v["session_flushes"])

    def receive(self, data: bytes, t_s: float) -> bytes:
        """Bytes from the host arriving at ``t_s``; returns the reply bytes."""
        data = bytes(data)
        reply = ctypes.create_string_buffer(64 * len(data) + 1024)
        n = self._lib.fwsim_receive(self._mem, data, len(data), t_s, reply, len(reply))
        return reply.raw[:n]

    def advance_to(self, t_s: float) -> bytes:
        """Play every tick up to (not including) tick ``floor(t_s * rate)``; returns the
        frames the device sends on its own meanwhile (a Flushed after a watchdog trip,
        ForceReports)."""
        sp, plate, state, played, index, phase = self._buf
        rate = self.config.rate_hz
        end = int(t_s * rate)
        said = bytearray()
        poll = ctypes.create_string_buffer(1024)
        while True:
            t0 = self._values()["tick"]
            forces, most = None, _CHUNK
            if self.sensor is not None:  # the pass plays only the ticks read
                most = min(max(end - t0, 0), self._ahead)
                lateral, normal = self.sensor.read(t0, np.zeros((most, self.config.channels)))
                self._forces[:most, 0] = p.force_to_wire(lateral)
                self._forces[:most, 1] = p.force_to_wire(normal)
                forces = self._forces.ctypes.data
            n = self._lib.fwsim_advance(self._mem, t_s, most,
                                        *(b.ctypes.data for b in self._buf), forces)
            k = self._lib.fwsim_poll(self._mem, poll, len(poll))
            said += poll.raw[:k]
            if n == 0:
                return bytes(said)
            um = p.amplitude_from_wire(sp[:n])
            self.setpoint = um[-1].copy()
            self.plate_um = plate[n - 1].copy()
            if self.log is not None:
                hit = np.flatnonzero(played[:n])
                if hit.size:
                    phases = p.phase_from_wire(phase[hit]) if self.config.phases else None
                    self.log(index[hit].copy(), um[hit], phases)
            if self.plate_log is not None:
                cuts = [0, *(np.flatnonzero(np.diff(state[:n])) + 1), n]
                for a, b in zip(cuts[:-1], cuts[1:]):
                    self.plate_log((t0 + np.arange(a, b)) / rate, int(state[a]), um[a:b],
                                   plate[a:b].copy())


def built_core_class():
    """:class:`CDeviceCore` bound to a freshly built ``libfwsim.so``, called like
    ``DeviceCore``; raises :class:`device.firmware.build.FirmwareBuildError` (naming the
    package to install) if it cannot be built."""
    from functools import partial

    from frictex.device.firmware.build import sim_library
    return partial(CDeviceCore, library=sim_library())
