"""A device whose Info breaks the rules the host relies on is refused at the handshake in
one line: a watchdog that never trips or leaves the plate moving past 50 ms
(PROTOCOL.md 5.3; 5000 + 5000 ms and 0 ms were accepted and heartbeated at 1 s and 1 ms),
and a protocol version below 1 (it crashed the link thread with a KeyError)."""

from __future__ import annotations

import dataclasses

import pytest

from frictex.device.link.host import CommandSink
from frictex.device.link.protocol import LinkError
from frictex.device.link.simdevice import DeviceConfig
from frictex.device.link.simport import SimDevice

RATE = 10_000.0


def handshake(said: dict) -> CommandSink:
    """A handshake with the simulated device declaring ``said`` (Info fields) in its Info
    (it keeps its own 25 ms watchdog)."""

    class RogueConfig(DeviceConfig):
        def info(self):
            return dataclasses.replace(super().info(), **said)

    device = SimDevice(RogueConfig(channels=1, rate_hz=RATE))
    try:
        return CommandSink(device.open, 1, RATE, label="rogue", handshake_s=2.0)
    finally:
        device.close()


@pytest.mark.parametrize("said, message", [
    ({"watchdog_ms": 5000, "ramp_ms": 5000},
     "rogue (frictex sim-device) has watchdog_ms 5000 + ramp_ms 5000 over 50 ms (PROTOCOL.md 5.3: "
     "the plate must be still within 50 ms of the host falling silent)"),
    ({"watchdog_ms": 30, "ramp_ms": 21},
     "rogue (frictex sim-device) has watchdog_ms 30 + ramp_ms 21 over 50 ms (PROTOCOL.md 5.3: "
     "the plate must be still within 50 ms of the host falling silent)"),
    ({"watchdog_ms": 0}, "rogue (frictex sim-device) has watchdog_ms 0: a watchdog that never trips"),
    ({"protocol_version": 0},
     "rogue (frictex sim-device) says protocol version 0; this host speaks 1 to 4"),
])
def test_a_device_breaking_the_watchdog_rule_or_version_is_refused(said, message):
    with pytest.raises(LinkError) as refused:
        handshake(said)
    assert str(refused.value) == message


def test_the_rule_s_edge_is_accepted():
    sink = handshake({"watchdog_ms": 30, "ramp_ms": 20})
    sink.close()
    assert sink.info.watchdog_ms == 30
