"""A gap in PLAYING holds the setpoint no longer than the watchdog would have allowed a
silent host, however often the host heartbeats (PROTOCOL.md 5.1): both the C core and
the Python reference."""

import numpy as np
import pytest

from frictex.device.link import protocol as p
from frictex.device.link.simdevice import DeviceConfig
from device_recorder import Recorder
from link_checks import CORES, core_class


def one_sample(start, counts):
    return p.Block(start, np.full((1, 1), counts, dtype=np.uint16))


@pytest.mark.parametrize("kind", CORES)
def test_a_long_gap_ramps_to_zero_after_the_watchdog_time(kind):
    """Sample 0 at 1000 counts, then nothing until sample 4000: a gap of 3999 ticks at
    10 kHz with a Heartbeat every 5 ms. The hold ends after 250 ticks (25 ms) and the
    20 ms ramp reaches zero by tick 451, well before sample 4000."""
    rec = Recorder()
    core = core_class(kind)(DeviceConfig(limits_um=(1000 * p.AMPLITUDE_STEP_UM,)),
                            log=rec.log, plate_log=rec.plate_log)
    core.receive(p.encode(p.Hello(1), 0), 0.0)
    core.receive(p.encode(one_sample(0, 1000), 1) + p.encode(one_sample(4000, 0), 2), 0.0)
    for k in range(1, 80):
        core.advance_to(k * 0.005)
        core.receive(p.encode(p.Heartbeat(k), 2 + k), k * 0.005)
    _, setpoint, _ = rec.ticks()
    on = np.flatnonzero(setpoint[:, 0] > 0)
    assert core.counters.watchdog_trips == 0
    assert on[-1] <= 451, f"1000 counts held until tick {on[-1]}"
    assert np.all(np.diff(setpoint[1:452, 0]) <= 0), "the hold ramps down, never up"
