"""PROTOCOL.md 4.7: Error code 1 (BAD_VERSION) is reserved and never sent. A frame of a
version the device does not speak is dropped and counted (section 2), in the C core as
in the Python reference: no reply at all, one more frame in Status.crc_errors."""

import pytest

from frictex.device.firmware.ccore import CDeviceCore
from frictex.device.link import protocol as p
from frictex.device.link.simdevice import DeviceConfig, DeviceCore

pytestmark = pytest.mark.usefixtures("firmware_sim_library")


def _status(core, seq):
    (frame,) = p.Decoder().feed(core.receive(p.encode(p.Heartbeat(seq), seq), 0.0))
    return frame.message


@pytest.mark.parametrize("cls", [DeviceCore, CDeviceCore])
def test_a_frame_of_an_unknown_version_gets_no_reply_and_is_counted(cls):
    core = cls(DeviceConfig())
    core.receive(p.encode(p.Hello(10), 0, version=1), 0.0)
    dropped_before = _status(core, 1).crc_errors
    for version in (p.PROTOCOL_VERSION + 1, 255):
        assert core.receive(p.encode(p.Heartbeat(9), 2, version=version), 0.0) == b""
    # the dropped frames took no sequence number: the next frame is 2, no hole (no Missing)
    assert _status(core, 2).crc_errors == dropped_before + 2
