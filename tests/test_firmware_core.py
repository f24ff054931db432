"""The C firmware core on a virtual clock (device/firmware/ccore.py over libfwsim.so): the
reference device's behaviour, and the same replies and played samples as the Python
reference device (device/link/simdevice.py) for the same traffic, faults included."""

import dataclasses

import numpy as np
import pytest

from device.firmware.build import FirmwareBuildError, sim_library
from device.firmware.ccore import CDeviceCore
from device.link import protocol as p
from device.link.faults import Faults, inject
from device.link.protocol import DeviceState as S
from device.link.simdevice import DeviceConfig, DeviceCore

RATE = 10_000.0
STEP = p.AMPLITUDE_STEP_UM


@pytest.fixture(scope="module", autouse=True)
def library():
    try:
        return sim_library()
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


def config(**kw):
    return DeviceConfig(**kw)


class Recorder:
    def __init__(self):
        self.index, self.values, self.t, self.setpoint, self.plate = [], [], [], [], []

    def log(self, index, values, phases):
        self.index.append(index)
        self.values.append(values)

    def plate_log(self, t, state, setpoint, plate):
        self.t.append(t)
        self.setpoint.append(setpoint)
        self.plate.append(plate)

    def played(self):
        if not self.index:
            return np.zeros(0, dtype=np.int64), np.zeros((0, 1))
        return np.concatenate(self.index), np.concatenate(self.values)

    def ticks(self):
        return np.concatenate(self.t), np.concatenate(self.setpoint), np.concatenate(self.plate)


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


def test_played_samples_are_the_commanded_fixed_point_values():
    core, host, rec = make()
    signal = 1.5 + np.sin(np.arange(3000) / 37.0)
    stream(core, host, signal)
    index, values = rec.played()
    np.testing.assert_array_equal(index, np.arange(3000))
    np.testing.assert_allclose(values[:, 0], signal, atol=STEP / 2)
    assert core.counters.underruns == 1 and core.counters.gap_samples == 0
    assert core.state == S.BUFFERING and core.counters.watchdog_trips == 0


def test_the_modelled_plate_is_first_order_at_its_bandwidth():
    core, host, rec = make(config(bandwidth_hz=400.0))
    k = np.arange(4000)
    stream(core, host, 2.0 + np.sin(2 * np.pi * 400.0 * k / RATE))
    t, sp, plate = rec.ticks()
    start = int(np.argmax(sp[:, 0] > 0))
    y = plate[start + 2000:start + 3000, 0] - 2.0
    u = sp[start + 2000:start + 3000, 0] - 2.0
    assert np.std(y) / np.std(u) == pytest.approx(1 / np.sqrt(2), rel=0.005)
    ref = np.exp(-2j * np.pi * 400 * np.arange(1000) / RATE)
    assert np.degrees(np.angle(np.sum(y * ref) / np.sum(u * ref))) == pytest.approx(-45.0, abs=0.5)


def test_the_watchdog_ramps_to_zero_within_50_ms_of_the_last_valid_frame():
    core, host, rec = make()
    for b in range(0, 600, 50):
        core.receive(host(block(b, np.full(50, 2.0))), 0.0)
    core.advance_to(0.200)  # the host never speaks again
    t, sp, plate = rec.ticks()
    assert core.counters.watchdog_trips == 1 and core.state == S.SILENT and core.level == 0
    assert np.all(sp[t < 0.025, 0] == 2.0)            # playing until the 250th tick
    assert np.all(sp[t >= 0.0449, 0] == 0.0)           # zero 449 ticks after the frame
    fall = -np.diff(sp[(t >= 0.0249) & (t < 0.046), 0])
    assert np.all(fall >= 0) and fall.max() <= 2.0 / 200 + STEP  # a ramp, in whole counts
    assert plate[t >= 0.050, 0].max() < 0.01 * 2.0
    assert rec.played()[0].max() < 260                 # the rest was flushed, not played


def test_a_slow_host_underruns_but_loses_nothing():
    core, host, rec = make()
    signal = np.linspace(0.0, 3.0, 2000)
    t = 0.0
    for b in range(0, 2000, 50):
        t += 0.007
        core.advance_to(t)
        core.receive(host(block(b, signal[b:b + 50])), t)
    keep_alive(core, host, t, t + 0.02)
    index, values = rec.played()
    np.testing.assert_array_equal(index, np.arange(2000))
    np.testing.assert_allclose(values[:, 0], signal, atol=STEP / 2)
    assert core.counters.underruns >= 5 and core.counters.gap_samples == 0


def test_a_lost_block_is_a_gap_that_holds_the_previous_value():
    core, host, rec = make()
    signal = np.arange(1000) / 500.0
    for b in range(0, 1000, 50):
        if b != 300:
            core.receive(host(block(b, signal[b:b + 50])), 0.0)
    keep_alive(core, host, 0.0, 0.101)
    index, _ = rec.played()
    np.testing.assert_array_equal(index, np.setdiff1d(np.arange(1000), np.arange(300, 350)))
    assert core.counters.gap_samples == 50
    _, sp, _ = rec.ticks()
    np.testing.assert_allclose(sp[300:350, 0], signal[299], atol=STEP / 2)


def test_late_overflowing_and_wrong_blocks_are_refused_and_counted():
    core, host, rec = make(config(buffer_samples=256), prefill=10)
    core.receive(host(block(0, np.ones(50))), 0.0)
    core.advance_to(0.002)
    replies = p.Decoder().feed(core.receive(host(block(10, np.ones(50))), 0.002)
                               + core.receive(host(block(200, np.ones(100))), 0.002)
                               + core.receive(host(p.Block(300, np.zeros((5, 2), np.uint16))),
                                              0.002))
    assert [(f.message.code, f.message.detail, f.message.text) for f in replies] == [
        (p.ErrorCode.LATE, 10, "10 samples arrived after their time"),
        (p.ErrorCode.OVERFLOW, 24, "24 samples beyond the buffer"),
        (p.ErrorCode.BAD_BLOCK, 2, "block has 2 channels, phases=False; device has 1, "
                                   "phases=False")]
    assert core.counters.late_samples == 10 and core.counters.overflow_samples == 24


def test_blocks_before_hello_are_refused_even_after_a_watchdog_trip():
    """PROTOCOL.md 4.3 step 1: NOT_READY before the first Hello, whatever the state."""
    core = CDeviceCore(config())
    host = Host()
    core.receive(host(p.Heartbeat(1)), 0.0)  # arms the watchdog
    core.advance_to(0.1)
    assert core.state == S.SILENT
    core.receive(host(p.Heartbeat(2)), 0.1)  # back to buffering...
    (reply,) = p.Decoder().feed(core.receive(host(block(0, np.ones(5))), 0.1))
    assert reply.message.code == p.ErrorCode.NOT_READY and core.level == 0  # ...not ready


def test_the_device_clamps_to_its_own_limit_whatever_arrives():
    core, host, rec = make(config(limits_um=(1.0,)), prefill=1)
    core.receive(host(block(0, [0.5, 3.0, 9.0])), 0.0)
    core.advance_to(0.001)
    np.testing.assert_allclose(rec.played()[1][:, 0], [0.5, 1.0, 1.0], atol=STEP / 2)
    assert core.counters.clamped == 2


def test_status_reports_measured_amplitude_and_force():
    core, host, rec = make(config(sensor=True, force_n=0.75), prefill=1)
    core.receive(host(block(0, np.full(200, 2.0))), 0.0)
    core.advance_to(0.015)
    (frame,) = p.Decoder().feed(core.receive(host(p.Heartbeat(42)), 0.015))
    assert frame.message.echo == 42 and frame.message.force_n == 0.75
    assert frame.message.measured_um[0] == pytest.approx(2.0, abs=STEP)


def test_a_drained_stop_plays_everything_then_finishes():
    core, host, rec = make()
    core.receive(host(block(0, np.full(500, 1.0))), 0.0)
    core.receive(host(p.Stop(drain=True)), 0.0)
    t = 0.0
    while not core.finished and t < 1.0:
        t += 0.001
        core.receive(host(p.Heartbeat(0)), t)
        core.advance_to(t)
    assert t == pytest.approx(0.05 + 0.02, abs=0.002)
    np.testing.assert_array_equal(rec.played()[0], np.arange(500))


def test_sample_numbers_wrap_modulo_2_64():
    core, host, rec = make(prefill=10)
    for b in range(0, 400, 50):
        core.receive(host(block((2**64 - 200 + b) % 2**64, np.full(50, 1.0))), 0.0)
    keep_alive(core, host, 0.0, 0.05)
    expect = [(2**64 - 200 + k) % 2**64 for k in range(400)]
    assert [int(i) for i in rec.played()[0].astype(np.uint64)] == expect
    assert core.counters.late_samples == 0 and core.counters.overflow_samples == 0


# ---------------------------------------------------------------------------- differential

def _session(cls, seed, cfg, version):
    """Random traffic in ``version`` with faults on the wire, late and early blocks, host
    stalls that trip the watchdog, a Stop; returns (every decoded frame the device sent,
    played, setpoints, counters)."""
    rec = Recorder()
    core = cls(cfg, log=rec.log, plate_log=rec.plate_log)
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


@pytest.mark.parametrize("version, seed", [(1, 0), (1, 1), (2, 2), (2, 3), (2, 4)])
def test_same_traffic_same_frames_and_samples_as_the_python_reference(version, seed):
    """Agreement frame for frame (Info, Status with its version 2 accounting, Error,
    Flushed) on everything but one thing: the C ramps to zero in whole counts where the
    reference ramps in floats, so a measured amplitude during a ramp may differ by one
    count."""
    cfg = config(limits_um=(3.0,), sensor=True, force_n=0.5)
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
    assert flushed == (c[3]["watchdog_trips"] if version == 2 else 0)
    np.testing.assert_array_equal(py[1][0], c[1][0])
    np.testing.assert_array_equal(py[1][1], c[1][1])
    np.testing.assert_allclose(py[2], c[2], atol=STEP)
    assert py[3] == c[3] and c[3]["discarded"] > 0


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


def test_a_version_1_host_gets_version_1_frames_and_no_flushed():
    core, host, rec = make()
    host.version = 1
    core.receive(host(block(0, np.full(50, 1.0))), 0.0)
    assert core.advance_to(0.1) == b""  # tripped, but a version 1 host has no Flushed
    (frame,) = p.Decoder().feed(core.receive(host(p.Heartbeat(1)), 0.1))
    assert frame.version == 1 and not frame.message.accounted
    assert core.counters.watchdog_trips == 1


def test_nothing_that_failed_its_check_is_played():
    core, host, rec = make()
    rng = np.random.default_rng(5)
    signal = rng.uniform(0, 3.5, 4000)
    t = 0.0
    for b in range(0, 4000, 50):
        t = max(b / RATE - 0.01, 0.0)
        core.advance_to(t)
        core.receive(inject(host(block(b, signal[b:b + 50])) + host(p.Heartbeat(b)),
                            Faults(flip=5e-4, drop=3e-4, garbage=3e-4), rng), t)
    core.advance_to(t + 0.02)
    index, values = rec.played()
    np.testing.assert_allclose(values[:, 0], signal[index], atol=STEP / 2)
    assert len(index) > 3000 and len(np.unique(index)) == len(index)
    assert core.decoder.counts.discarded > 0
