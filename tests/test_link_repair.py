"""A noisy link repairs instead of dropping (PROTOCOL.md 4.10): the README's fault
example, ``--faults corrupt=0.001``, over the in-process device, a pty and ``socket://``.

A device plays on its own clock; a host starved past the watchdog (a busy machine)
loses what the trip flushed, which is the safety design and no fault of the repair
(``link_checks``). A resend arrives in time only if the Status that asks for it and the
resend itself outrun the lead the host keeps buffered (40 ms): a host or device
starved for longer than that loses the samples, late, however good the repair. So the
0.1 % bound is asserted for streams without a trip or a recovery whose Statuses never
came more than a quarter of that lead later than the heartbeat period (PROTOCOL.md 6.4,
``longest_status_gap_ms``; a quiet machine: 21-27 ms against 30). Every stream must
account for every sample, and the repair must have run.
"""

import io

import numpy as np
import pytest

from frictex.device.link.faults import parse_faults
from frictex.device.link.host import open_sink
from link_checks import accounted, start_sim_device

RATE = 10_000.0
SECONDS = 3.0


def _stream(spec: str, faults: str, log_path=None) -> dict:
    n = int(SECONDS * RATE)
    signal = (1.5 + np.sin(np.arange(n) / 37.0))[:, None]
    sink = open_sink(spec, 1, RATE, paced=True, faults=parse_faults(faults),
                     stderr=io.StringIO(), log_path=log_path)
    with sink:
        for b in range(0, n, 50):
            sink.send(b, signal[b:b + 50])
    return sink.status()


def _scheduled_in_time(st: dict) -> bool:
    """No Status came later than the heartbeat period (``watchdog_ms / 5``, PROTOCOL.md
    3) plus a quarter of the lead the host keeps buffered (``target_level``)."""
    heartbeat_ms = st["device"]["watchdog_ms"] / 5
    lead_ms = st["target_level"] / RATE * 1e3
    return st["longest_status_gap_ms"] <= heartbeat_ms + lead_ms / 4


def _at_most_a_thousandth_unless_tripped(st: dict) -> None:
    n = int(SECONDS * RATE)
    accounted(st, None, n)
    assert st["resent_frames"] > 0  # frames were lost, and resent
    if st["watchdog_trips"] == 0 and st["recoveries"] == 0 and _scheduled_in_time(st):
        assert st["unplayed_samples"] <= 0.001 * n, (
            f"{st['unplayed_samples']} of {n} unplayed: {st['unplayed_by_cause']}; "
            f"resent {st['resent_frames']}; " + ", ".join(
                f"{k} {st[k]}" for k in ("underruns", "resends_too_late", "stalls",
                                         "latency_ms_p99", "longest_turn_gap_ms",
                                         "longest_status_gap_ms", "device_lost_frames",
                                         "stop_resends")))


@pytest.mark.parametrize("transport", ["sim", "pty", "tcp"])
def test_corrupt_0001_loses_at_most_a_thousandth(tmp_path, transport):
    if transport == "sim":
        spec = "sim"
    else:
        proc, spec = start_sim_device(1, RATE, tcp=transport == "tcp")
    st = _stream(spec, "corrupt=0.001,seed=3")
    _at_most_a_thousandth_unless_tripped(st)
    if transport != "sim":
        proc.wait(timeout=30)


def test_without_repair_the_same_faults_lose_a_tenth():
    """A version 3 device (no Missing): each corrupted byte costs its whole frame."""
    st = _stream("sim:protocol=3", "corrupt=0.001,seed=3")
    assert st["protocol_version"] == 3 and st["resent_frames"] == 0
    assert st["unplayed_by_cause"]["lost"] > 0.05 * SECONDS * RATE


def _stream_losing_stops(lose: int) -> tuple[dict, object]:
    """A short paced stream to the in-process device, which never sees the first ``lose``
    Stop frames (lost on the wire: a Stop is not repaired by Missing, PROTOCOL.md 4.5)."""
    from frictex.device.link import protocol as p
    from frictex.device.link.host import CommandSink
    from frictex.device.link.simdevice import DeviceConfig
    from frictex.device.link.simport import SimDevice

    device = SimDevice(DeviceConfig(channels=1, rate_hz=RATE))
    handle, lost = device.core._handle, []

    def losing_stops(frame):
        if isinstance(frame.message, p.Stop) and len(lost) < lose:
            lost.append(frame)
            return None
        return handle(frame)
    device.core._handle = losing_stops
    n = int(0.3 * RATE)
    with CommandSink(device.open, 1, RATE, paced=True, simulated=True,
                     stderr=io.StringIO()) as sink:
        for b in range(0, n, 50):
            sink.send(b, np.full((50, 1), 1.0))
    st = sink.status()
    accounted(st, None, n)
    return st, device.core


def test_a_lost_stop_is_sent_again_and_the_device_stops():
    from frictex.device.link.session import STOP_RESENDS
    st, core = _stream_losing_stops(1)
    assert core.stopped  # the Stop took: `sim-device --once` exits once its ramp has run
    # a host starved past the watchdog while the device drained cuts the drain short:
    # its Stop is then sent once more
    assert st["stop_resends"] == 1 or 1 < st["stop_resends"] <= STOP_RESENDS and st["watchdog_trips"]


def test_stops_lost_every_time_end_the_close_within_its_bound():
    st, core = _stream_losing_stops(10)
    assert st["stop_resends"] == 3
    assert not core.stopped


def test_a_stalled_host_shows_in_its_longest_gaps():
    """A host whose link thread stops for 0.15 s mid-stream (``stall=0.15@0.4``) shows it
    in its longest gaps without a turn and without a Status (PROTOCOL.md 6.4), whatever
    else the scheduler did: a turn that began inside the stall can split it in two (the
    thread's next port call then waits out the rest), so each gap is at least half of it;
    the figures are what the repair bound above is excused by."""
    st = _stream("sim", "stall=0.15@0.4")
    accounted(st, None, int(SECONDS * RATE))
    assert st["longest_turn_gap_ms"] >= 75.0
    assert st["longest_status_gap_ms"] >= 75.0
    assert not _scheduled_in_time(st)
