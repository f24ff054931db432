"""The simulated device's logic on a virtual clock: playing, jitter buffer, plate, watchdog.
Every test runs against the Python reference device and the C firmware core."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from frictex.device.errors import InputError
from frictex.device.link import protocol as p
from frictex.device.link.faults import Faults, inject
from frictex.device.link.protocol import DeviceState as S
from frictex.device.link.simdevice import DeviceConfig, DeviceCore as PythonDeviceCore
from device_recorder import Recorder
from link_checks import CORES, core_class

RATE = 10_000.0
STEP = p.AMPLITUDE_STEP_UM
DeviceCore = PythonDeviceCore


@pytest.fixture(scope="module", autouse=True, params=CORES)
def device_core(request):
    """Swap the class the tests build their device with (module scope: @given tests)."""
    global DeviceCore
    DeviceCore = core_class(request.param)
    yield
    DeviceCore = PythonDeviceCore


class Host:
    """Frames from a test host, numbered like the real one."""

    def __init__(self):
        self.seq = 0

    def __call__(self, msg) -> bytes:
        self.seq += 1
        return p.encode(msg, self.seq - 1)


def make(config=DeviceConfig(), prefill=100):
    rec = Recorder()
    core = DeviceCore(config, log=rec.log, plate_log=rec.plate_log)
    host = Host()
    reply = p.Decoder().feed(core.receive(host(p.Hello(prefill)), 0.0))
    assert [f.message for f in reply] == [config.info()]
    return core, host, rec


def block(start, um):
    return p.Block(start, p.amplitude_to_wire(np.asarray(um, dtype=float).reshape(-1, 1))[0])


def stream(core, host, signal, t_start=0.0, lead_s=0.02, block_n=50, heartbeat=True,
           end_s=None):
    """Send ``signal`` in blocks, each ``lead_s`` before it is due, and advance the clock."""
    n = len(signal)
    t = t_start
    for b in range(0, n, block_n):
        t = t_start + max(b / RATE - lead_s, 0.0)
        core.advance_to(t)
        core.receive(host(block(b, signal[b:b + block_n])), t)
        if heartbeat:
            core.receive(host(p.Heartbeat(b)), t)
    end = t_start + n / RATE + 0.05 if end_s is None else end_s
    while t < end:  # keep the host talking while the buffer plays out
        t += 0.005
        core.advance_to(t)
        if heartbeat:
            core.receive(host(p.Heartbeat(0)), t)
    return t


def test_played_samples_are_the_commanded_fixed_point_values():
    core, host, rec = make()
    signal = 1.5 + np.sin(np.arange(3000) / 37.0)
    stream(core, host, signal)
    index, values = rec.played()
    np.testing.assert_array_equal(index, np.arange(3000))
    np.testing.assert_allclose(values[:, 0], signal, atol=STEP / 2)
    # the stream's end is the only time the buffer ran dry
    assert core.counters.underruns == 1 and core.counters.gap_samples == 0
    assert core.state == S.BUFFERING and core.counters.watchdog_trips == 0


def test_plate_model_is_first_order_with_the_configured_bandwidth():
    # steady state of a 400 Hz sine through a 400 Hz first-order loop: |H| = 1/sqrt(2)
    # (0.26 % off, the exact discretisation, PROTOCOL.md 5.4), and the phase of
    # (1 - a) / (1 - a e^-jw): -45 deg less the half tick the plate lags the held setpoint
    core, host, rec = make(DeviceConfig(bandwidth_hz=400.0, limits_um=(4.0,)))
    k = np.arange(4000)
    signal = 2.0 + 1.0 * np.sin(2 * np.pi * 400.0 * k / RATE)
    stream(core, host, signal, end_s=0.4)
    t, sp, plate = rec.ticks()
    start = int(np.argmax(sp[:, 0] > 0))  # first tick played
    y = plate[start + 2000:start + 3000, 0] - 2.0
    u = sp[start + 2000:start + 3000, 0] - 2.0
    gain = np.sqrt(2 * np.mean(y ** 2)) / np.sqrt(2 * np.mean(u ** 2))
    assert gain == pytest.approx(1 / np.sqrt(2), rel=0.005)
    lag = np.angle(np.sum(y * np.exp(-2j * np.pi * 400 * np.arange(1000) / RATE))
                   / np.sum(u * np.exp(-2j * np.pi * 400 * np.arange(1000) / RATE)))
    w, a = 2 * np.pi * 400.0 / RATE, np.exp(-2 * np.pi * 400.0 / RATE)
    model = np.angle((1 - a) / (1 - a * np.exp(-1j * w)))
    assert np.degrees(lag) == pytest.approx(np.degrees(model), abs=0.5)
    assert np.degrees(lag) == pytest.approx(-45.0 + np.degrees(w) / 2, abs=0.5)


def test_watchdog_ramps_to_zero_within_50_ms_of_host_silence():
    core, host, rec = make()
    signal = np.full(600, 2.0)  # 60 ms of 2 um, all sent up front
    for b in range(0, 600, 50):
        core.receive(host(block(b, signal[b:b + 50])), 0.0)
    core.advance_to(0.200)  # the host never speaks again
    t, sp, plate = rec.ticks()
    assert core.counters.watchdog_trips == 1
    assert core.state == S.SILENT and core.level == 0
    assert sp[t < 0.024, 0].min() == pytest.approx(2.0)     # playing until the timeout
    silent_from = 0.025 + 0.020
    assert np.all(sp[t >= silent_from, 0] == 0.0)
    assert np.all(np.diff(sp[(t >= 0.025), 0]) <= 0)        # a ramp, no step up
    assert np.max(np.abs(np.diff(sp[:, 0]))) < 2.0 / 100    # no click: at most 1/200 per tick
    assert plate[t >= 0.050, 0].max() < 0.01 * 2.0
    index, _ = rec.played()
    assert index.max() < 260                                 # the rest was flushed, not played


def _held_then_ramped(sp, value):
    """(ticks the setpoint stayed at ``value`` after its first tick, ticks of the ramp
    after them until zero, the ramp's values) in a per-tick setpoint ``sp``."""
    first = int(np.flatnonzero(sp == value)[0])
    after = sp[first + 1:]
    hold = int(np.argmax(after != value))
    ramp = after[hold:]
    return hold, int(np.argmax(ramp == 0.0)) + 1, ramp


def test_a_host_that_heartbeats_but_sends_no_samples_gets_a_bounded_hold():
    """PROTOCOL.md 5.1: a BUFFERING device holds a non-zero setpoint for ticks(watchdog_ms)
    after the last sample played, then ramps it to zero over ticks(ramp_ms), keeping its
    play position; the samples sent later all play, from where it stopped."""
    cfg = DeviceConfig()
    core, host, rec = make(cfg)
    first = STEP * (4096 + 4 * np.arange(1000))  # distinct, exact on the wire: 1 to 1.97 um
    t = stream(core, host, first, end_s=0.2)  # 0.1 s of heartbeats after it ran dry
    assert (core.state, core.play_index, core.level) == (S.BUFFERING, 1000, 0)
    assert core.counters.watchdog_trips == 0 and core.session.flushes == 0
    _, sp, _ = rec.ticks()
    held, to_zero, ramp = _held_then_ramped(sp[:, 0], first[-1])
    assert held == cfg.ticks(cfg.watchdog_ms) == 250
    assert to_zero == cfg.ticks(cfg.ramp_ms) == 200
    k = np.arange(1, to_zero + 1)
    np.testing.assert_allclose(ramp[:to_zero], first[-1] * (1 - k / to_zero), atol=STEP)
    assert np.all(ramp[to_zero:] == 0.0)
    second = 0.5 + np.arange(1000) / 2000.0
    for b in range(0, 1000, 50):  # the host is back: blocks 1000.. as if never late
        core.advance_to(t)
        core.receive(host(block(1000 + b, second[b:b + 50])), t)
        core.receive(host(p.Heartbeat(b)), t)
        t += 0.004
    stream(core, host, np.zeros(0), t_start=t, end_s=t + 0.15)
    index, values = rec.played()
    np.testing.assert_array_equal(index, np.arange(2000))
    np.testing.assert_allclose(values[:, 0], np.concatenate([first, second]), atol=STEP / 2)
    assert core.counters.gap_samples == 0 and core.counters.watchdog_trips == 0


def test_a_zero_ramp_steps_to_zero_on_the_tick_after_the_hold():
    """``ramp_ms = 0`` (``sim-device --ramp-ms 0``, in the range its message states): the
    held setpoint reaches zero one tick after the hold, as ticks(0) = 1 says."""
    cfg = DeviceConfig(ramp_ms=0)
    core, host, rec = make(cfg)
    first = STEP * (4096 + 4 * np.arange(500))
    stream(core, host, first, end_s=0.15)
    _, sp, _ = rec.ticks()
    held, to_zero, ramp = _held_then_ramped(sp[:, 0], first[-1])
    assert (held, to_zero) == (cfg.ticks(cfg.watchdog_ms), 1) == (250, 1)
    assert np.all(ramp == 0.0)


def test_a_hello_ramps_the_flushed_streams_setpoint_out_at_once():
    """PROTOCOL.md 5.1: a Hello voids what the host sent before; the setpoint it left
    ramps to zero from the Hello's tick (no watchdog_ms hold), and the new stream plays
    from its own first sample."""
    cfg = DeviceConfig()
    core, host, rec = make(cfg)
    core.receive(host(block(0, np.full(1000, 2.0))), 0.0)
    t = stream(core, host, np.zeros(0), end_s=0.05)
    assert core.state == S.PLAYING
    core.receive(host(p.Hello(100)), t)  # mid-stream, about 500 ticks in
    hello = core.play_index
    t = stream(core, host, np.zeros(0), t_start=t, end_s=t + 0.05)
    t_s, sp, _ = rec.ticks()
    after = sp[np.round(t_s * RATE).astype(int) >= hello, 0]
    r = cfg.ticks(cfg.ramp_ms)
    np.testing.assert_allclose(after[:r], 2.0 * (1 - np.arange(1, r + 1) / r), atol=STEP)
    assert np.all(after[r - 1:] == 0.0)
    assert core.level == 0 and core.counters.watchdog_trips == 0
    core.receive(host(block(7000, np.full(200, 1.0))), t)
    stream(core, host, np.zeros(0), t_start=t, end_s=t + 0.05)
    index, values = rec.played()
    np.testing.assert_array_equal(index, np.concatenate([np.arange(hello), 7000 + np.arange(200)]))


def test_a_host_back_during_the_watchdog_ramp_does_not_stop_it():
    """A Heartbeat ends SILENT mid-ramp: the ramp goes on to zero (BUFFERING holds nothing
    a trip began ramping out), and the stream resumes where it stopped."""
    cfg = DeviceConfig()
    core, host, rec = make(cfg)
    core.receive(host(block(0, np.full(1000, 2.0))), 0.0)
    core.advance_to(0.03)  # the trip: 25 ms of silence
    assert core.state == S.SILENT
    core.receive(host(p.Heartbeat(1)), 0.03)
    t = stream(core, host, np.zeros(0), t_start=0.03, end_s=0.1)
    assert core.state == S.BUFFERING
    t_s, sp, _ = rec.ticks()
    trip = cfg.ticks(cfg.watchdog_ms)
    r = cfg.ticks(cfg.ramp_ms)
    ramp = sp[trip:, 0]
    np.testing.assert_allclose(ramp[:r], 2.0 * (1 - np.arange(1, r + 1) / r), atol=STEP)
    assert np.all(ramp[r - 1:] == 0.0)
    core.receive(host(block(trip, np.full(100, 1.5))), t)
    stream(core, host, np.zeros(0), t_start=t, end_s=t + 0.05)
    index, _ = rec.played()
    np.testing.assert_array_equal(index, np.arange(trip + 100))


def test_a_slow_host_underruns_but_loses_nothing():
    core, host, rec = make()
    signal = np.linspace(0.0, 3.0, 2000)
    t = 0.0
    for b in range(0, 2000, 50):
        t += 0.007  # 7 ms per 5 ms block: the device runs dry again and again
        core.advance_to(t)
        core.receive(host(block(b, signal[b:b + 50])), t)
    stream(core, host, np.zeros(0), t_start=t, end_s=t + 0.05)
    index, values = rec.played()
    np.testing.assert_array_equal(index, np.arange(2000))
    np.testing.assert_allclose(values[:, 0], signal, atol=STEP / 2)
    assert core.counters.underruns >= 5
    assert core.counters.gap_samples == 0


def test_a_lost_block_is_a_gap_that_holds_the_previous_value():
    core, host, rec = make()
    signal = np.arange(1000) / 500.0
    for b in range(0, 1000, 50):
        if b != 300:
            core.receive(host(block(b, signal[b:b + 50])), 0.0)
    stream(core, host, np.zeros(0), end_s=0.099)
    index, values = rec.played()
    expect = np.setdiff1d(np.arange(1000), np.arange(300, 350))
    np.testing.assert_array_equal(index, expect)
    assert core.counters.gap_samples == 50
    _, sp, _ = rec.ticks()
    np.testing.assert_allclose(sp[300:350, 0], signal[299], atol=STEP / 2)


def test_late_overflowing_and_wrong_blocks_are_refused_and_counted():
    core, host, rec = make(DeviceConfig(buffer_samples=256), prefill=10)
    core.receive(host(block(0, np.ones(50))), 0.0)
    core.advance_to(0.002)  # 20 played
    replies = p.Decoder().feed(core.receive(host(block(10, np.ones(50))), 0.002)
                               + core.receive(host(block(200, np.ones(100))), 0.002)
                               + core.receive(host(p.Block(300, np.zeros((5, 2), np.uint16))),
                                              0.002))
    codes = [(f.message.code, f.message.detail) for f in replies]
    assert codes == [(p.ErrorCode.LATE, 10), (p.ErrorCode.OVERFLOW, 24),
                     (p.ErrorCode.BAD_BLOCK, 2)]
    assert core.counters.late_samples == 10 and core.counters.overflow_samples == 24


def test_blocks_before_hello_are_refused():
    core = DeviceCore(DeviceConfig())
    reply = p.Decoder().feed(core.receive(p.encode(block(0, np.ones(5)), 0), 0.0))
    assert reply[0].message.code == p.ErrorCode.NOT_READY
    assert core.level == 0


def test_blocks_before_hello_are_refused_even_after_a_watchdog_trip():
    """PROTOCOL.md 4.3 step 1: NOT_READY before the first Hello, whatever the state."""
    core = DeviceCore(DeviceConfig())
    host = Host()
    core.receive(host(p.Heartbeat(1)), 0.0)  # arms the watchdog
    core.advance_to(0.1)
    assert core.state == S.SILENT
    core.receive(host(p.Heartbeat(2)), 0.1)  # back to buffering...
    (reply,) = p.Decoder().feed(core.receive(host(block(0, np.ones(5))), 0.1))
    assert reply.message.code == p.ErrorCode.NOT_READY and core.level == 0  # ...not ready


@pytest.mark.parametrize("watchdog_ms, rate_hz, ticks", [(9, 10_000.0, 90), (25, 10_000.0, 250),
                                                          (7, 3_333.0, 24), (1, 300.0, 1)])
def test_the_watchdog_counts_integer_ticks_of_the_declared_rate(watchdog_ms, rate_hz, ticks):
    """PROTOCOL.md 5.3: ceil(ms * rate_mHz / 10^6) ticks (9 ms * 10 kHz in floats is
    90.00000000000001, one tick more)."""
    assert ticks == -(-watchdog_ms * round(rate_hz * 1000) // 1_000_000)
    core = DeviceCore(DeviceConfig(rate_hz=rate_hz, watchdog_ms=watchdog_ms, ramp_ms=0,
                                   bandwidth_hz=rate_hz / 10))
    core.receive(Host()(p.Heartbeat(1)), 0.0)  # the frame arrives at tick 0
    core.advance_to((ticks + 0.5) / rate_hz)   # ticks 0 .. ticks - 1 ran
    assert core.state == S.IDLE and core.counters.watchdog_trips == 0
    core.advance_to((ticks + 1.5) / rate_hz)   # tick `ticks`: silent for that many
    assert core.state == S.SILENT and core.counters.watchdog_trips == 1


def test_the_device_clamps_to_exactly_the_limit_it_declares():
    """3.0002 um is 12288.8 counts: declared and enforced are both 12288 (floored: never
    above the configured limit)."""
    core, host, rec = make(DeviceConfig(limits_um=(3.0002,)), prefill=1)
    assert core.config.info().limits_um == (12288 * STEP,)
    wire = np.array([[12288], [12289], [12290]], dtype=np.uint16)
    core.receive(host(p.Block(0, wire)), 0.0)
    core.advance_to(0.001)
    np.testing.assert_array_equal(rec.played()[1][:, 0], [12288 * STEP] * 3)
    assert core.counters.clamped == 2


def test_the_device_clamps_to_its_own_limit_whatever_arrives():
    core, host, rec = make(DeviceConfig(limits_um=(1.0,)), prefill=1)
    core.receive(host(block(0, [0.5, 3.0, 9.0])), 0.0)
    core.advance_to(0.001)
    _, values = rec.played()
    np.testing.assert_allclose(values[:, 0], [0.5, 1.0, 1.0], atol=STEP / 2)
    assert core.counters.clamped == 2


def test_status_reports_measured_amplitude_and_force_when_sensors_exist():
    core, host, rec = make(DeviceConfig(sensor=True, force_n=0.75), prefill=1)
    core.receive(host(block(0, np.full(200, 2.0))), 0.0)
    core.advance_to(0.015)
    (frame,) = p.Decoder().feed(core.receive(host(p.Heartbeat(42)), 0.015))
    st_ = frame.message
    assert st_.echo == 42 and st_.force_n == 0.75
    # after 150 ticks of a 2 um step the modelled plate has settled (tau = 0.4 ms)
    assert st_.measured_um[0] == pytest.approx(2.0, abs=STEP)


def test_drained_stop_plays_everything_then_finishes():
    core, host, rec = make()
    core.receive(host(block(0, np.full(500, 1.0))), 0.0)
    core.receive(host(p.Stop(drain=True)), 0.0)
    t = 0.0
    while not core.finished and t < 1.0:
        t += 0.005
        core.receive(host(p.Heartbeat(0)), t)
        core.advance_to(t)
    assert core.finished
    assert t == pytest.approx(0.05 + 0.02, abs=0.006)
    index, _ = rec.played()
    np.testing.assert_array_equal(index, np.arange(500))


@settings(derandomize=True, max_examples=25, deadline=None)
@given(st.lists(st.floats(0.0, 0.12), min_size=1, max_size=12))
def test_advancing_the_clock_in_pieces_equals_one_advance(cuts):
    def run(times):
        core, host, rec = make()
        core.receive(host(block(0, 1 + np.sin(np.arange(800) / 9.0))), 0.0)
        for t in times:
            core.advance_to(t)
        return rec

    whole = run([0.12])
    split = run(sorted(cuts) + [0.12])
    for a, b in zip(whole.ticks(), split.ticks()):
        np.testing.assert_allclose(a, b, rtol=1e-12, atol=1e-15)
    np.testing.assert_array_equal(whole.played()[0], split.played()[0])


@settings(derandomize=True, max_examples=20, deadline=None)
@given(st.integers(0, 2**32 - 1))
def test_nothing_that_failed_its_check_is_played(seed):
    core, host, rec = make()
    rng = np.random.default_rng(seed)
    signal = rng.uniform(0, 3.5, 4000)
    faults = Faults(flip=0.0005, drop=0.0003, garbage=0.0003)
    t = 0.0
    for b in range(0, 4000, 50):
        t = max(b / RATE - 0.01, 0.0)
        core.advance_to(t)
        core.receive(inject(host(block(b, signal[b:b + 50])) + host(p.Heartbeat(b)),
                            faults, rng), t)
    core.advance_to(t + 0.02)
    index, values = rec.played()
    np.testing.assert_allclose(values[:, 0], signal[index], atol=STEP / 2)
    assert len(index) >= 3000  # most blocks got through
    assert core.decoder.counts.discarded > 0
    assert len(np.unique(index)) == len(index)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.integers(0, 2**64 - 1), st.integers(1, 400))
def test_any_u64_start_index_plays_on_across_the_wrap(start, n_blocks_samples):
    """Sample numbers are u64 and wrap (PROTOCOL.md 4.3): block indices of 2**63 and
    more, and streams crossing 2**64, play in order and never raise."""
    core, host, rec = make(prefill=10)
    n = 50 * (n_blocks_samples // 50 + 2)
    signal = np.linspace(0.1, 3.0, n)
    for b in range(0, n, 50):
        core.receive(host(block((start + b) % 2**64, signal[b:b + 50])), 0.0)
    stream(core, host, np.zeros(0), end_s=n / RATE + 0.01)
    index, values = rec.played()
    expect = (start + np.arange(n, dtype=object)) % 2**64
    assert [int(i) for i in index] == list(expect)
    np.testing.assert_allclose(values[:, 0], signal, atol=STEP / 2)
    assert core.counters.late_samples == core.counters.overflow_samples == 0


def test_a_block_far_from_the_play_position_is_late_or_beyond_never_an_error():
    core, host, rec = make(prefill=10)
    core.receive(host(block(2**63 + 5, np.ones(50))), 0.0)   # sets the origin
    replies = p.Decoder().feed(core.receive(host(block(5, np.ones(50))), 0.0)
                               + core.receive(host(block(2**63 + 2**62, np.ones(50))), 0.0))
    # 5 - (2**63 + 5) = -2**63: before the play position; +2**62: beyond the buffer
    assert [f.message.code for f in replies] == [p.ErrorCode.LATE, p.ErrorCode.OVERFLOW]
    assert core.play_index == 2**63 + 5


def test_a_watchdog_trip_is_reported_with_where_the_device_restarts():
    core, host, rec = make()
    for b in range(0, 600, 50):
        core.receive(host(block(b, np.full(50, 2.0))), 0.0)
    out = core.advance_to(0.100)  # the host never speaks again: trip at 25 ms
    (frame,) = p.Decoder().feed(out)
    flushed = frame.message
    assert frame.version == p.PROTOCOL_VERSION and isinstance(flushed, p.Flushed)
    assert flushed.cause == p.FlushCause.WATCHDOG and flushed.flushes == 1
    # played from the first block until the trip, the rest of the 600 flushed
    played = core.session.played
    assert played == len(rec.played()[0]) and flushed.flushed == 600 - played
    assert flushed.play_index == played  # where it stopped, and will restart
    (reply,) = p.Decoder().feed(core.receive(host(p.Heartbeat(9)), 0.1))
    st_ = reply.message
    assert (st_.buffer_end, st_.level, st_.state) == (played, 0, S.BUFFERING)
    assert st_.played_samples + st_.flushed_samples + st_.level == 600
    assert st_.flushes == 1 and st_.watchdog_trips == 1


def test_a_version_1_host_only_ever_sees_version_1_frames():
    core = DeviceCore(DeviceConfig())
    old = p.Decoder(max_version=1)
    seq = iter(range(100))

    def v1(msg):
        return p.encode(msg, next(seq), version=1)
    replies = old.feed(core.receive(v1(p.Hello(10)), 0.0))
    assert replies[0].message.protocol_version == p.PROTOCOL_VERSION  # it says what it speaks
    for b in range(0, 300, 50):
        replies += old.feed(core.receive(v1(block(b, np.ones(50))), 0.0))
    replies += old.feed(core.advance_to(0.1))   # a trip: no Flushed for a version 1 host
    replies += old.feed(core.receive(v1(p.Heartbeat(3)), 0.1))
    assert old.counts.discarded == 0
    assert [type(f.message) for f in replies] == [p.Info, p.Status]
    assert not replies[-1].message.accounted and replies[-1].message.watchdog_trips == 1


def test_a_version_1_device_declares_1_and_drops_version_2_frames():
    core = DeviceCore(DeviceConfig(protocol_version=1))
    (info,) = p.Decoder().feed(core.receive(p.encode(p.Hello(10), 0, version=1), 0.0))
    assert info.message.protocol_version == 1
    assert core.receive(p.encode(p.Heartbeat(1), 1, version=2), 0.0) == b""
    assert core.decoder.counts.bad_version == 1


@st.composite
def host_traffic(draw):
    """A random session of valid host frames (any u64 block index, right or wrong
    shapes) with clock advances between them."""
    steps = []
    for _ in range(draw(st.integers(1, 25))):
        kind = draw(st.sampled_from(["hello", "block", "block", "block", "heartbeat", "stop",
                                     "wait"]))
        if kind == "hello":
            steps.append(p.Hello(draw(st.integers(0, 2**32 - 1))))
        elif kind == "block":
            n = draw(st.integers(0, 80))
            ch = draw(st.sampled_from([1, 1, 2]))
            amps = np.full((n, ch), draw(st.integers(0, 65535)), dtype=np.uint16)
            phases = amps.copy() if draw(st.booleans()) else None
            steps.append(p.Block(draw(st.integers(0, 2**64 - 1)
                                      | st.integers(2**63 - 100, 2**63 + 100)
                                      | st.integers(2**64 - 100, 2**64 - 1)), amps, phases))
        elif kind == "heartbeat":
            steps.append(p.Heartbeat(draw(st.integers(0, 2**32 - 1))))
        elif kind == "stop":
            steps.append(p.Stop(draw(st.booleans())))
        else:
            steps.append(draw(st.floats(0.0, 0.1)))
    return steps


@settings(derandomize=True, max_examples=150, deadline=None)
@given(host_traffic(), st.sampled_from([1, 2, 3]))
def test_no_valid_host_traffic_makes_the_device_fail(steps, version):
    core = DeviceCore(DeviceConfig(buffer_samples=512, lateral_n=0.25, force_n=0.5))
    decoder = p.Decoder()
    t = 0.0
    for seq, step in enumerate(steps):
        if isinstance(step, float):
            t += step
            replies = decoder.feed(core.advance_to(t))
        else:
            replies = decoder.feed(core.receive(p.encode(step, seq, version), t))
        assert decoder.counts.discarded == 0
        assert all(f.version == version for f in replies)
        st_ = core.status(0)
        if version >= 2:
            assert 0 <= st_.buffer_end < 2**64 and 0 <= core.level <= 512
            ahead = (st_.buffer_end - st_.play_index) % 2**64
            assert core.level <= ahead <= 512


# ---------------------------------------------------------------------------- force reports

V3 = 3


def _reports(data: bytes) -> list:
    return [f.message for f in p.Decoder().feed(data) if isinstance(f.message, p.ForceReport)]


def test_force_reports_carry_the_sensor_over_each_played_sample_range():
    """PROTOCOL.md 4.9: 10 values of 4 samples a report, consecutive sample numbers, the
    constant sensor's values in whole counts (0.3 N lateral is 1228.8 counts: 1229)."""
    cfg = DeviceConfig(lateral_n=0.3, force_n=0.5)
    core, host, rec = make(cfg, prefill=1)
    assert core.config.info().has_force_reports
    core.receive(host(block(0, np.full(400, 1.0))), 0.0)
    out = core.advance_to(0.02)
    core.receive(host(p.Heartbeat(1)), 0.02)  # no watchdog trip
    reports = _reports(out + core.advance_to(0.0305))  # 305 ticks played
    assert [r.start_index for r in reports] == list(range(0, 280, 40))  # 7 complete
    for r in reports:
        assert r.decimation == 4 and len(r.lateral_n) == 10
        assert set(r.lateral_n) == {1229 * p.FORCE_STEP_N} and set(r.normal_n) == {0.5}


def test_a_version_2_host_gets_no_force_reports_and_a_stop_in_playing_drops_the_partial():
    cfg = DeviceConfig(lateral_n=0.3, force_n=0.5)
    core = DeviceCore(cfg)
    old = p.Decoder(max_version=2)
    seq = iter(range(100))

    def v2(msg):
        return p.encode(msg, next(seq), version=1 if isinstance(msg, p.Hello) else 2)
    old.feed(core.receive(v2(p.Hello(1)), 0.0))
    old.feed(core.receive(v2(block(0, np.full(400, 1.0))), 0.0))
    assert [f.message for f in old.feed(core.advance_to(0.02))] == []
    assert old.counts.discarded == 0
    # the same device, now driven by a version 3 host: reports from the first tick after
    host = Host()
    host.seq = 50
    core.receive(p.encode(p.Heartbeat(1), 50, V3), 0.02)
    reports = _reports(core.advance_to(0.03))
    assert [r.start_index for r in reports] == [200, 240]  # built since 200, sent in v3


def test_ticks_that_do_not_play_restart_the_report():
    """An underrun (the buffer ran dry at 30) drops the 30-sample partial report; the next
    one starts where playing resumes."""
    core, host, rec = make(DeviceConfig(lateral_n=-1.0), prefill=1)
    core.receive(host(block(0, np.full(30, 1.0))), 0.0)
    assert _reports(core.advance_to(0.01)) == []
    assert core.counters.underruns == 1
    core.receive(host(block(30, np.full(100, 1.0))), 0.01)
    reports = _reports(core.advance_to(0.02))
    assert [r.start_index for r in reports] == [30, 70]
    assert set(reports[0].lateral_n) == {-1.0} and set(reports[0].normal_n) == {0.0}


def test_without_a_lateral_sensor_there_is_no_flag_and_no_report():
    core, host, rec = make(DeviceConfig(force_n=0.5), prefill=1)
    assert not core.config.info().has_force_reports
    core.receive(host(block(0, np.full(400, 1.0))), 0.0)
    assert _reports(core.advance_to(0.05)) == []


def test_force_reports_need_protocol_version_3():
    with pytest.raises(ValueError, match="protocol_version = 2: expected 3 for force reports"):
        DeviceConfig(lateral_n=0.1, protocol_version=2)


def _feed(core, data: bytes, t: float, cuts: list[int]) -> bytes:
    """``data`` to the core in pieces of the ``cuts`` lengths (then the rest)."""
    out, pos = bytearray(), 0
    for cut in [*cuts, len(data)]:
        out += core.receive(data[pos:pos + cut], t)
        pos += cut
        if pos >= len(data):
            break
    return bytes(out)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(st.sets(st.integers(0, 59)), st.lists(st.integers(1, 120), max_size=20))
def test_lost_blocks_are_asked_for_and_their_resends_play_on_time(lost, cuts):
    """Version 4 repair (PROTOCOL.md 4.10): whichever Block frames the wire loses, the
    device names their sequence numbers in Missing, the host resends them, and every
    sample plays as commanded, on time, whatever the chunking of the byte stream; a
    resend that comes again (the device no longer misses it) has no effect."""
    core, host, rec = make()
    signal = 1.5 + np.sin(np.arange(3000) / 37.0)
    replies, kept, asked, dropped = p.Decoder(), {}, [], set()
    t = 0.0
    for k, b in enumerate(range(0, 3000, 50)):
        t = max(b / RATE - 0.02, 0.0)
        core.advance_to(t)
        kept[host.seq] = block(b, signal[b:b + 50])
        if k in lost:
            dropped.add(host.seq)
        frame = host(kept[host.seq])
        data = (b"" if k in lost else frame) + host(p.Heartbeat(k + 1))
        pending = _feed(core, data, t, cuts)
        while pending:  # the host answers each Missing at once, as the link does
            resend = b""
            for f in replies.feed(pending):
                if isinstance(f.message, p.Missing):
                    asked += f.message.seqs
                    resend += b"".join(host(p.Resend(kept[q].start_index, kept[q].amplitudes,
                                                     None, q))
                                       for q in f.message.seqs if q in kept)
            pending = _feed(core, resend, t, cuts) if resend else b""
    stream(core, host, np.zeros(0), t_start=t, end_s=0.4)
    index, values = rec.played()
    np.testing.assert_array_equal(index, np.arange(3000))
    np.testing.assert_allclose(values[:, 0], signal, atol=STEP / 2)
    assert core.counters.late_samples == 0 and core.counters.gap_samples == 0
    assert set(asked) & set(kept) == dropped  # it asked for exactly the blocks lost
    again = kept[1]  # the first block, long played: a duplicate now
    assert core.receive(host(p.Resend(again.start_index, again.amplitudes, None, 1)), 0.5) == b""
    assert core.counters.late_samples == 0


def test_a_version_3_host_gets_no_missing_reports():
    core, host, rec = make()
    host.seq += 3  # three frames lost on the wire
    frames = p.Decoder().feed(core.receive(p.encode(p.Heartbeat(7), host.seq, 3), 0.0))
    assert [type(f.message) for f in frames] == [p.Status]
    assert frames[0].message.lost_frames == 3


@pytest.mark.parametrize("rate_hz", [float("nan"), float("inf")])
def test_a_rate_that_is_not_a_number_is_refused_naming_it(rate_hz):
    """A NaN or infinite rate was a ValueError from counting ticks ("cannot convert float
    NaN to integer") before the checks could name it."""
    with pytest.raises(InputError, match=r"^sim-device rate_hz = (nan|inf): expected in "):
        DeviceConfig(rate_hz=rate_hz, watchdog_ms=1, ramp_ms=0)
