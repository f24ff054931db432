"""Lateral force on the wire, host side: the simulated finger's reports against seed 003's
model computed here, the host's per-sample view of them, and hosts and devices without
the capability (PROTOCOL.md 4.9, 5.5, 6.5)."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from frictex.app.commands.cli import main
from frictex.device.finger import draw_finger
from frictex.device.link import protocol as p
from frictex.device.link.forces import ForceHistory, ForceReport, per_sample
from frictex.device.link.host import CommandSink, open_port, open_sink
from link_checks import start_sim_device
from frictex.device.link.simdevice import DeviceConfig, DeviceCore
from link_checks import all_played_unless_tripped

RATE = 10_000.0


def test_the_simulated_fingers_lateral_force_is_seed_003s_friction_of_the_played_amplitude():
    """Person 3 slides at 100 mm/s pressing 0.5 N on a plate held at 1.0 um: each reported
    value is mu0(t) mu'(w, F_n, v, t) F_n (seed 003, eqs 1-2, with the person's constants,
    moisture and speed dependence: device/finger.py), within the sensor's noise (2 mN per
    tick, 1 mN for a mean of 4) once the plate, skin and sensor have settled."""
    core = DeviceCore(DeviceConfig(finger=3, force_n=0.5, finger_speed_mm_s=100.0))
    seq = iter(range(1000))

    def send(msg, t):
        version = 1 if isinstance(msg, p.Hello) else 3
        return core.receive(p.encode(msg, next(seq), version), t)
    send(p.Hello(1), 0.0)
    for b in range(0, 3000, 1000):  # 1.0 um from tick 0
        send(p.Block(b, np.full((1000, 1), 4096, dtype=np.uint16)), 0.0)
    reports = []
    for k in range(1, 61):  # 0.3 s, a heartbeat every 5 ms
        reports += [f.message for f in p.Decoder().feed(core.advance_to(k * 0.005))
                    if isinstance(f.message, p.ForceReport)]
        send(p.Heartbeat(k), k * 0.005)
    assert [r.start_index for r in reports] == list(range(0, 3000, 40))
    f = draw_finger(3)
    lateral = np.concatenate([r.lateral_n for r in reports])
    normal = np.concatenate([r.normal_n for r in reports])
    t = (np.arange(lateral.size) * 4 + 1.5) / RATE   # the middle of each value's 4 ticks
    m = 1.0 - np.exp(-(f.t0_s + t) / f.tau_s)
    a = f.k_per_n * (1.0 + f.k_drift * m) * 0.5
    b = f.b_per_um / (1.0 + 100.0 / f.v_c_mm_s)
    mu_rel = (1.0 - a) * np.exp(-b * 1.0) + a
    expected = f.mu0 * (1.0 + f.mu0_drift * m) * mu_rel * 0.5
    settled = t > 0.05
    assert np.abs(lateral[settled] - expected[settled]).max() < 5e-3  # 5 sigma
    assert abs(np.mean(lateral[settled] - expected[settled])) < 3e-4
    assert abs(np.mean(normal[settled]) - 0.5) < 5e-4
    assert np.std(lateral[settled] - expected[settled]) == pytest.approx(1e-3, rel=0.25)
    # the amplitude matters: the plate at rest gives the friction at rest, mu0 F_n
    assert expected[settled].mean() < 0.9 * f.mu0 * 0.5


@st.composite
def reported(draw):
    """Per-sample forces from sample ``start`` on, cut into ForceReports at random."""
    decimation = draw(st.integers(1, 6))
    values = draw(st.integers(1, 60))
    start = draw(st.integers(0, 2**64 - 1))
    rng = np.random.default_rng(draw(st.integers(0, 2**32 - 1)))
    counts = rng.integers(-32768, 32768, (values, 2))
    cuts = sorted(set(draw(st.lists(st.integers(1, values - 1), max_size=8)))) if values > 1 else []
    msgs, lo = [], 0
    for hi in [*cuts, values]:
        msgs.append(p.ForceReport((start + lo * decimation) % 2**64, decimation,
                                  tuple(counts[lo:hi, 0] * p.FORCE_STEP_N),
                                  tuple(counts[lo:hi, 1] * p.FORCE_STEP_N)))
        lo = hi
    return start, decimation, counts, msgs


@settings(derandomize=True, max_examples=150, deadline=None)
@given(reported(), st.data())
def test_the_host_cuts_any_covered_sample_range_out_of_the_reports(case, data):
    """Reports in wire form (each value held over its decimation samples, numbered modulo
    2**64) read back as the per-sample forces they cover, by the host's numbering; a
    range reaching a sample no report covers is None."""
    start, decimation, counts, msgs = case
    near = start + 10 ** 6  # the host has sent a little beyond what was reported
    history = ForceHistory()
    for msg in msgs:
        history.add(per_sample(msg, near))
    samples = np.repeat(counts * p.FORCE_STEP_N, decimation, axis=0)
    total = len(samples)
    lo = data.draw(st.integers(0, total - 1))
    n = data.draw(st.integers(1, total - lo))
    got = history.window(start + lo, n)
    assert got.index0 == start + lo
    np.testing.assert_array_equal(got.lateral_n, samples[lo:lo + n, 0])
    np.testing.assert_array_equal(got.normal_n, samples[lo:lo + n, 1])
    assert history.window(start + lo, total - lo + 1) is None
    assert history.window(start - 1, 2) is None
    latest = history.latest()
    assert latest.index0 + latest.lateral_n.size == start + total


def test_the_history_keeps_the_last_second_of_samples():
    history = ForceHistory(keep=100)
    for k in range(10):
        history.add(per_sample(p.ForceReport(40 * k, 4, (0.1,) * 10, (0.5,) * 10), 0))
    assert history.window(40 * 7, 120) is not None
    assert history.window(40 * 6, 40) is None  # dropped: older than the last 100 samples


def _scan_window(reports, index0, n):
    """ForceHistory.window as it was: every kept report in arrival order, the newer
    overwriting the older."""
    lateral, normal = np.full(n, np.nan), np.full(n, np.nan)
    for r in reports:
        lo, hi = max(r.index0, index0), min(r.index0 + r.lateral_n.size, index0 + n)
        if lo < hi:
            lateral[lo - index0:hi - index0] = r.lateral_n[lo - r.index0:hi - r.index0]
            normal[lo - index0:hi - index0] = r.normal_n[lo - r.index0:hi - r.index0]
    return None if np.isnan(lateral).any() else (lateral, normal)


@settings(derandomize=True, max_examples=200, deadline=None)
@given(st.data())
def test_the_window_is_the_scan_of_every_kept_report(data):
    """Random report sets (in order, with gaps and overlaps, of mixed lengths, and now
    and then a start going back, as after a device restart) and ranges: the window is
    the one the scan of every kept report (the previous implementation) gives, bit for
    bit, None included; the kept reports are those the old deque kept."""
    keep = data.draw(st.integers(1, 300))
    history, kept, held = ForceHistory(keep=keep), [], 0
    rng = np.random.default_rng(data.draw(st.integers(0, 2**32 - 1)))
    start = data.draw(st.integers(-1000, 1000))
    for _ in range(data.draw(st.integers(1, 150))):  # > 64 dropped: the lists are cut
        start += data.draw(st.sampled_from([0, 40, 40, 40, 40, 37, 45, 80, -20, -500]))
        size = data.draw(st.sampled_from([40, 40, 40, 4, 1, 120]))
        report = ForceReport(start, rng.normal(size=size), rng.normal(size=size))
        history.add(report)
        kept.append(report)
        held += size
        while held - kept[0].lateral_n.size >= keep:
            held -= kept.pop(0).lateral_n.size
        assert history.latest() is kept[-1]
        for _ in range(3):
            index0 = data.draw(st.integers(start - 400, start + 100))
            n = data.draw(st.integers(0, 300))
            got, want = history.window(index0, n), _scan_window(kept, index0, n) if n else None
            if want is None:
                assert got is None
            else:
                assert got.index0 == index0
                np.testing.assert_array_equal(got.lateral_n, want[0])
                np.testing.assert_array_equal(got.normal_n, want[1])


def _stream(sink, n=2000):
    for b in range(0, n, 50):
        sink.send(b, np.full((50, 1), 1.0), None)


@pytest.mark.parametrize("extra, version", [(("--protocol", "2", "--force", "0.5"), 2),
                                            (("--force", "0.5"), p.PROTOCOL_VERSION)])
def test_a_device_without_the_capability_streams_as_before_with_no_lateral_force(extra,
                                                                                  version):
    """A version 2 device, and a newest-version device without a lateral sensor: the stream
    plays every sample (bar what a watchdog trip on a starved host flushed, counted), the
    normal force still arrives in Status, force_report() is None."""
    proc, path = start_sim_device(1, RATE, extra=extra)
    sink = CommandSink(lambda: open_port(path), 1, RATE, paced=True, process=proc)
    try:
        assert not sink.info.has_force_reports
        _stream(sink)
    finally:
        sink.close()
    status = sink.status()
    assert status["protocol_version"] == version
    all_played_unless_tripped(status, None, 2000)
    assert status["force_n"] == 0.5 and status["force_reports"] == 0
    assert sink.force_report() is None and sink.force_report(0, 40) is None


def test_sim_device_finger_reports_reach_the_host():
    """The ``frictex sim-device --finger`` process's reports reach the host and read back.

    The device plays on the wall clock: a host starved past its 25 ms watchdog (a CPU
    hog) makes it drop the report being built and restart at the next sample, which may
    be anywhere. So what is asserted holds however the scheduler behaves: reports of 40
    samples with the finger's friction, each read back as sent, and the run of them that
    ends at the latest (one report at least; all ~100 when nothing starved) read back as
    one window. The windows themselves are property-tested above, deterministically."""
    sink = open_sink("sim", 1, RATE, paced=True, sim_args=("--finger", "3", "--force", "0.5"))
    try:
        assert sink.info.has_force_reports and sink.info.protocol_version == p.PROTOCOL_VERSION
        _stream(sink, 4000)
    finally:
        sink.close()
    latest = sink.force_report()
    assert latest is not None and latest.lateral_n.size == 40
    ratio = latest.lateral_n.mean() / latest.normal_n.mean()  # mu0 mu': person 3's friction
    f = draw_finger(3)
    assert 0.2 * f.mu0 < ratio < 1.05 * f.mu0 * (1 + f.mu0_drift)
    k = 0  # reports contiguous before the latest
    while sink.force_report(latest.index0 - 40 * (k + 1), 40 * (k + 2)) is not None:
        k += 1
    window = sink.force_report(latest.index0 - 40 * k, 40 * (k + 1))
    np.testing.assert_array_equal(window.lateral_n[-40:], latest.lateral_n)
    np.testing.assert_array_equal(window.normal_n[-40:], latest.normal_n)
    assert sink.status()["force_reports"] >= k + 1


@pytest.mark.parametrize("argv, message", [
    (["--finger", "-1"], "finger = -1: expected a seed >= 0"),
    (["--lateral", "0.2", "--protocol", "2"], "expected 3 for force reports"),
    (["--lateral", "9"], "lateral_n = 9.0: expected in [-8, 8] N"),
    (["--lateral", "0.2", "--finger", "1"], "lateral_n = 0.2: expected None with a simulated"),
])
def test_bad_force_flags_are_one_line_errors(argv, message, capsys):
    assert main(["sim-device", *argv]) == 2
    err = capsys.readouterr().err
    assert err.count("\n") == 1 and err.startswith("frictex: error: ") and message in err
