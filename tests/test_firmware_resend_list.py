"""The C core's list of missing host frames (PROTOCOL.md 4.10) against the Python
reference: a number is listed once however often a gap reveals it, so a second Resend
of it does nothing; and the two devices count the same flushes on Stop (4.6)."""

import numpy as np
import pytest

from frictex.device.firmware.ccore import CDeviceCore
from frictex.device.link import protocol as p
from frictex.device.link.simdevice import DeviceConfig, DeviceCore

CORES = [DeviceCore, CDeviceCore]


pytestmark = pytest.mark.usefixtures("firmware_sim_library")


def _frames(reply: bytes) -> list:
    return [f.message for f in p.Decoder().feed(reply)]


def _after_a_seq_that_went_back(cls, samples: int = 0):
    """A core after a Hello, optionally a Block of ``samples`` at index 0 (seq 1), then
    version 4 Heartbeats with seq 6, 3, 6 (a host whose seq went back once without a
    Hello); returns (core, the Missing sent after the last Heartbeat)."""
    core = cls(DeviceConfig())
    core.receive(p.encode(p.Hello(10), 0, 1), 0.0)
    if samples:
        core.receive(p.encode(p.Block(0, np.full((samples, 1), 4096, np.uint16)), 1, 4), 0.0)
    for seq in (6, 3, 6):
        said = _frames(core.receive(p.encode(p.Heartbeat(seq), seq, 4), 0.001))
    return core, [m for m in said if isinstance(m, p.Missing)]


@pytest.mark.parametrize("cls", CORES)
def test_a_number_revealed_missing_twice_is_listed_once(cls):
    _, missing = _after_a_seq_that_went_back(cls)
    assert missing == [p.Missing((1, 2, 3, 4, 5))]


@pytest.mark.parametrize("cls", CORES)
def test_a_second_resend_of_a_number_is_ignored_and_its_late_samples_counted_once(cls):
    """The first Resend of orig_seq 4 comes after its 20 samples played: one LATE error,
    20 late samples; the same Resend again does nothing at all (4.10)."""
    core, _ = _after_a_seq_that_went_back(cls, samples=20)
    core.advance_to(0.004)
    amps = np.full((20, 1), 4096, np.uint16)
    replies = [_frames(core.receive(p.encode(p.Resend(0, amps, None, 4), seq, 4), 0.004))
               for seq in (7, 8)]
    assert [[type(m).__name__ for m in r] for r in replies] == [["ErrorReport"], []]
    assert core.counters.late_samples == 20


@pytest.mark.parametrize("cls", CORES)
@pytest.mark.parametrize("drain, flushes", [(True, 0), (False, 1)])
def test_only_a_stop_without_drain_counts_a_flush_on_an_empty_buffer(cls, drain, flushes):
    """4.6: flushes counts watchdog trips and Stops without drain; a drained Stop on an
    empty buffer discards nothing."""
    core = cls(DeviceConfig())
    core.receive(p.encode(p.Hello(10), 0, 1), 0.0)
    (status,) = _frames(core.receive(p.encode(p.Stop(drain), 1, 2), 0.0))
    assert (status.state, status.flushes, status.flushed_samples) == (4, flushes, 0)


@pytest.mark.parametrize("field, value", [("force_decimation", 2), ("force_pairs", 5)])
def test_the_c_core_refuses_a_force_report_shape_its_board_does_not_have(field, value):
    cfg = DeviceConfig(lateral_n=0.25, **{field: value})
    with pytest.raises(ValueError, match="force_decimation 4 and force_pairs 10 only"):
        CDeviceCore(cfg)
