"""The device's own frames echoed back (a half-duplex RS-485 adapter, a loopback fault)
must not feed the watchdog (PROTOCOL.md 5.3): both the C core and the Python reference."""

import numpy as np
import pytest

from frictex.device.link import protocol as p
from frictex.device.link.simdevice import DeviceConfig
from device_recorder import Recorder
from link_checks import CORES, core_class

ECHOED_STATUS = p.Status(0, int(p.DeviceState.PLAYING), 0, 2000, buffer_end=2000,
                         played_samples=0, flushed_samples=0, flushes=0)


@pytest.mark.parametrize("kind", CORES)
def test_echoed_device_frames_do_not_keep_the_output_up(kind):
    """One 2000-sample Block, then only echoes of a Status every ms: the watchdog trips
    25 ms (250 ticks) after the Block and the 20 ms ramp ends by tick 450."""
    rec = Recorder()
    core = core_class(kind)(DeviceConfig(limits_um=(1000 * p.AMPLITUDE_STEP_UM,)),
                            log=rec.log, plate_log=rec.plate_log)
    core.receive(p.encode(p.Hello(1), 0), 0.0)
    core.receive(p.encode(p.Block(0, np.full((2000, 1), 1000, dtype=np.uint16)), 1, 2), 0.0)
    for ms in range(1, 300):
        core.advance_to(ms / 1000)
        core.receive(p.encode(ECHOED_STATUS, ms), ms / 1000)
    _, setpoint, _ = rec.ticks()
    last_on = int(np.flatnonzero(setpoint[:, 0] > 0)[-1])
    assert last_on < 450, f"output on until tick {last_on}"
    assert core.counters.watchdog_trips == 1
