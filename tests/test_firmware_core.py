"""The C firmware core on a virtual clock (device/firmware/ccore.py over libfwsim.so):
what only it does (PROTOCOL.md followed where the Python reference is laxer), and the same
replies and played samples as the Python reference device (device/link/simdevice.py) for
the same traffic, faults included. The behaviour both share is tested once, for both, in
tests/test_simdevice.py."""

import dataclasses

import numpy as np
import pytest

from frictex.device.firmware.ccore import CDeviceCore
from frictex.device.link import protocol as p
from frictex.device.link.faults import Faults, inject
from frictex.device.link.simdevice import DeviceConfig, DeviceCore
from device_recorder import Recorder

RATE = 10_000.0
STEP = p.AMPLITUDE_STEP_UM


pytestmark = pytest.mark.usefixtures("firmware_sim_library")


def config(**kw):
    return DeviceConfig(**kw)


class Host:
    """Frames numbered like the real host's: Hello in version 1, the rest in ``version``."""

    def __init__(self, version=2):
        self.seq = 0
        self.version = version

    def __call__(self, msg) -> bytes:
        self.seq += 1
        return p.encode(msg, self.seq - 1, 1 if isinstance(msg, p.Hello) else self.version)


def make(cfg=None, prefill=100, cls=CDeviceCore):
    cfg = cfg or config()
    rec = Recorder()
    core = cls(cfg, log=rec.log, plate_log=rec.plate_log)
    host = Host()
    reply = p.Decoder().feed(core.receive(host(p.Hello(prefill)), 0.0))
    assert [f.message for f in reply] == [cfg.info()]
    return core, host, rec


def block(start, um):
    return p.Block(start, p.amplitude_to_wire(np.asarray(um, dtype=float).reshape(-1, 1))[0])


def keep_alive(core, host, t, end):
    """Advance the clock to ``end`` with a heartbeat every 5 ms (no watchdog trip)."""
    while t < end:
        t = min(t + 0.005, end)
        core.advance_to(t)
        core.receive(host(p.Heartbeat(0)), t)


def stream(core, host, signal, lead_s=0.02, block_n=50):
    t = 0.0
    for b in range(0, len(signal), block_n):
        t = max(b / RATE - lead_s, 0.0)
        core.advance_to(t)
        core.receive(host(block(b, signal[b:b + block_n])), t)
        core.receive(host(p.Heartbeat(b)), t)
    keep_alive(core, host, t, len(signal) / RATE + 0.05)


# ---------------------------------------------------------------------------- differential

class PatternSensor:
    """Lateral and normal force readings that differ tick by tick (a pure function of the
    tick, so the C core can be handed them ahead), covering the i16 range and halves of
    a count, so the means and their rounding are exercised."""

    def read(self, tick0, setpoint_um):
        t = tick0 + np.arange(len(setpoint_um))
        lateral = ((t * 7919) % 65536 - 32768) * p.FORCE_STEP_N
        normal = ((t * 104729) % 4001 - 1000) * p.FORCE_STEP_N + 0.5 * p.FORCE_STEP_N * (t % 3 == 0)
        return lateral, normal


def _session(cls, seed, cfg, version):
    """Random traffic in ``version`` with faults on the wire, late and early blocks, host
    stalls that trip the watchdog, a Stop; returns (every decoded frame the device sent,
    played, setpoints, counters)."""
    rec = Recorder()
    sensor = PatternSensor() if cfg.force_reports else None
    core = cls(cfg, log=rec.log, plate_log=rec.plate_log, sensor=sensor)
    rng = np.random.default_rng(seed)
    host = Host(version)
    sent = []

    def heard(data):
        sent.extend((f.version, f.message) for f in p.Decoder().feed(data))

    def send(msg, t):
        heard(core.receive(inject(host(msg), Faults(flip=1e-3, drop=5e-4, garbage=5e-4),
                                  rng), t))

    send(p.Hello(100), 0.0)
    t = 0.0
    for b in range(0, 6000, 50):
        t = max(b / RATE - 0.01, 0.0) + rng.uniform(0, 0.004)
        heard(core.advance_to(t))
        amps = rng.integers(0, 20000, (50, cfg.channels)).astype(np.uint16)
        send(p.Block(b + int(rng.integers(-3, 3)) if b else 0, amps), t)
        if rng.random() < 0.7:
            send(p.Heartbeat(b), t)
        if rng.random() < 0.02:
            t += 0.06
            heard(core.advance_to(t))
    send(p.Stop(False), t)
    while t < 1.0:
        t += 0.005
        heard(core.advance_to(t))
        send(p.Heartbeat(0), t)
    index, values = rec.played()
    counters = {k: getattr(core.counters, k) for k in (
        "underruns", "gap_samples", "late_samples", "overflow_samples", "watchdog_trips",
        "clamped")}
    counters["discarded"] = core.decoder.counts.discarded
    return sent, (index, values), rec.ticks()[1], counters


@pytest.mark.parametrize("version, seed", [(1, 0), (1, 1), (2, 2), (2, 3), (2, 4), (3, 5),
                                           (3, 6)])
def test_same_traffic_same_frames_and_samples_as_the_python_reference(version, seed):
    """Agreement frame for frame (Info, Status with its version 2 accounting, Error,
    Flushed, ForceReport with the same tick-by-tick sensor readings) on everything but
    one thing: the C ramps to zero in whole counts where the reference ramps in floats,
    so a measured amplitude during a ramp may differ by one count."""
    cfg = config(limits_um=(3.0,), sensor=True, force_n=0.5, lateral_n=0.0)
    py, c = (_session(cls, seed, cfg, version) for cls in (DeviceCore, CDeviceCore))
    assert len(py[0]) == len(c[0]) > 100
    for (va, a), (vb, b) in zip(py[0], c[0]):
        assert va == vb == (1 if isinstance(a, p.Info) else version)
        if isinstance(a, p.Status):
            assert dataclasses.replace(a, measured_um=None) == dataclasses.replace(
                b, measured_um=None)
            assert abs(a.measured_um[0] - b.measured_um[0]) <= STEP
        else:
            assert a == b
    flushed = sum(isinstance(m, p.Flushed) for _, m in c[0])
    assert flushed == (c[3]["watchdog_trips"] if version >= 2 else 0)
    reports = [m for _, m in c[0] if isinstance(m, p.ForceReport)]
    if version == 3:
        assert len(reports) > 50  # a report per 4 ms while playing
    else:
        assert reports == []
    np.testing.assert_array_equal(py[1][0], c[1][0])
    np.testing.assert_array_equal(py[1][1], c[1][1])
    np.testing.assert_allclose(py[2], c[2], atol=STEP)
    assert py[3] == c[3] and c[3]["discarded"] > 0


def _stalls(cls, seed):
    """Random blocks with heartbeat-only stalls (the host talks, sends no samples: the hold
    ramps out, PROTOCOL.md 5.1), Hellos mid-stream and in a ramp, and silences that trip
    the watchdog; returns (played, per-tick setpoints, counters)."""
    rec = Recorder()
    core = cls(config(limits_um=(3.0,)), log=rec.log, plate_log=rec.plate_log)
    rng = np.random.default_rng(seed)
    host = Host(2)
    core.receive(host(p.Hello(50)), 0.0)
    t, start = 0.0, 0
    for _ in range(60):
        n = int(rng.integers(20, 400))
        amps = rng.integers(1, 12000, (n, 1)).astype(np.uint16)
        core.receive(host(p.Block(start, amps)), t)
        start += n
        pause = rng.choice(["heartbeats", "hello", "silence"], p=[0.7, 0.15, 0.15])
        end = t + n / RATE + rng.uniform(0.0, 0.08)
        while t < end:
            t = min(t + rng.uniform(0.001, 0.006), end)
            core.advance_to(t)
            if pause != "silence" or rng.random() < 0.1:
                core.receive(host(p.Heartbeat(0)), t)
            if pause == "hello" and rng.random() < 0.05:
                core.receive(host(p.Hello(50)), t)
                start += 10_000
    core.advance_to(t + 0.1)
    counters = (core.counters.underruns, core.counters.watchdog_trips, core.counters.gap_samples)
    return rec.played(), rec.ticks()[1], counters


@pytest.mark.parametrize("seed", [0, 1, 2])
def test_the_bounded_hold_is_the_same_in_both_cores(seed):
    """Tick for tick the same setpoints (the C ramps in whole counts: within one count) and
    the same played samples, through holds that ramp out, Hellos and watchdog trips."""
    (pi, pv), psp, pk = _stalls(DeviceCore, seed)
    (ci, cv), csp, ck = _stalls(CDeviceCore, seed)
    np.testing.assert_array_equal(pi, ci)
    np.testing.assert_array_equal(pv, cv)
    np.testing.assert_allclose(psp, csp, atol=STEP)
    assert pk == ck and pk[0] > 10 and pk[1] > 0
    assert np.sum((psp[:, 0] == 0) & (np.roll(psp[:, 0], 1) > 0)) > 10  # ramped out often


def test_version_2_accounts_for_every_stored_sample_and_reports_a_trip():
    """PROTOCOL.md 4.6: since a Hello, stored = played + flushed + level; 4.8: a watchdog
    trip is reported once, in a Flushed, to a version 2 host."""
    core, host, rec = make()
    for b in range(0, 600, 50):
        core.receive(host(block(b, np.full(50, 1.0))), 0.0)
    core.advance_to(0.01)
    (status,) = [f.message for f in p.Decoder().feed(core.receive(host(p.Heartbeat(1)), 0.01))]
    assert status.played_samples + status.flushed_samples + status.level == 600
    assert status.buffer_end == 600 and status.play_index == 100
    (flushed,) = [f.message for f in p.Decoder().feed(core.advance_to(0.1))]
    assert flushed == p.Flushed(p.FlushCause.WATCHDOG, 350, 250, 1)
    assert core.advance_to(0.2) == b""  # once
    (status,) = [f.message for f in p.Decoder().feed(core.receive(host(p.Heartbeat(2)), 0.2))]
    assert (status.played_samples, status.flushed_samples, status.flushes, status.level,
            status.buffer_end) == (350, 250, 1, 0, 350)




class CountingSensor(PatternSensor):
    """PatternSensor counting the ticks read."""

    def __init__(self):
        self.ticks_read = 0

    def read(self, tick0, setpoint_um):
        self.ticks_read += len(setpoint_um)
        return super().read(tick0, setpoint_um)


def _reports(cls, cfg, sensor):
    core, host = cls(cfg, sensor=sensor), Host(version=3)  # reports are version 3
    said = list(p.Decoder().feed(core.receive(host(p.Hello(100)), 0.0)))
    t = 0.0
    for b in range(0, 2000, 50):
        t = max(b / RATE - 0.02, 0.0)
        said += p.Decoder().feed(core.advance_to(t))
        core.receive(host(block(b, np.full(50, 1.0))), t)
        core.receive(host(p.Heartbeat(b)), t)
    while t < 0.5:
        t += 0.005
        said += p.Decoder().feed(core.advance_to(t))
        core.receive(host(p.Heartbeat(0)), t)
    return [f.message for f in said if isinstance(f.message, p.ForceReport)], core


@pytest.mark.parametrize("cls", [DeviceCore, CDeviceCore])
def test_a_sensor_is_ignored_unless_the_device_announces_force_reports(cls):
    """Info without ForceReports (no lateral_n, no finger): an explicit sensor is never
    read and no ForceReport is sent, by either core; with them announced, it is read."""
    sensor = CountingSensor()
    cfg = config(limits_um=(3.0,), protocol_version=3)
    assert not cfg.force_reports and not cfg.info().has_force_reports
    reports, _ = _reports(cls, cfg, sensor)
    assert (reports, sensor.ticks_read) == ([], 0)
    reports, _ = _reports(cls, dataclasses.replace(cfg, lateral_n=0.0), sensor)
    assert len(reports) > 0 and sensor.ticks_read > 0


def test_the_c_core_reads_the_sensor_about_once_per_tick():
    """The C core reads ahead at most one report's span (force_decimation * force_pairs
    = 40 ticks) and plays only what it read: advanced 40 ms (400 ticks) at a time, each
    tick is read about once (re-reads where a pass ends at a report), not the rest of
    the call's ticks on every pass (one pass per report: about 5.5 times)."""
    sensor = CountingSensor()
    cfg = config(limits_um=(3.0,), protocol_version=3, lateral_n=0.0, watchdog_ms=49, ramp_ms=1)
    core, host = CDeviceCore(cfg, sensor=sensor), Host(version=3)
    said = list(p.Decoder().feed(core.receive(host(p.Hello(100)), 0.0)))
    t = 0.0
    for b in range(0, 4000, 400):
        core.receive(host(block(b, np.full(400, 1.0))), t)
        core.receive(host(p.Heartbeat(b)), t)
        t += 0.04
        said += p.Decoder().feed(core.advance_to(t))
    assert sum(isinstance(f.message, p.ForceReport) for f in said) >= 90
    assert core.tick <= sensor.ticks_read <= 1.5 * core.tick, (sensor.ticks_read, core.tick)
