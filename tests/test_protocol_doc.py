"""device/PROTOCOL.md says what the code does: the version it documents, the host's
handshake bounds, and the versions in which a device sends Flushed and ForceReports.

It said version "1, 2 or 3" and protocol_version "3 for this document" while both
devices answer 4; that the host gives up the handshake after 1 s in 4.1 and 10 s in 6.2
(the code: 10 s); and that Flushed and ForceReports follow version 2 or 3 and version 3
frames only, while both devices send them after version 4 frames too.
"""

import re
from pathlib import Path

import numpy as np
import pytest

from frictex.device.link import protocol as p
from frictex.device.link.host import HANDSHAKE_TOTAL_S
from frictex.device.link.session import HELLO_FIRST_S, HELLO_MAX_S, RESYNC_TIMEOUT_S
from frictex.device.link.simdevice import DeviceConfig
from link_checks import CORES, core_class

TEXT = (Path(p.__file__).parents[1] / "PROTOCOL.md").read_text(encoding="utf-8")
FLAT = " ".join(TEXT.split())


def section(number: str) -> str:
    """The text of section ``number`` (``"4.1"``), whitespace collapsed."""
    start = re.search(rf"^#+ {re.escape(number)}\b", TEXT, re.M).end()
    end = re.search(r"^#+ ", TEXT[start:], re.M)
    return " ".join(TEXT[start:start + (end.start() if end else len(TEXT))].split())


def test_the_document_is_of_the_version_the_code_speaks():
    newest = p.PROTOCOL_VERSION
    assert TEXT.startswith(f"# frictex device protocol, version {newest}\n")
    listed = ", ".join(str(v) for v in range(1, newest)) + f" or {newest}"
    assert f"`version` selects the payload layouts: {listed} (section 2.1)" in FLAT
    assert f"newest version the device speaks ({newest} for this document" in section("4.2")
    assert DeviceConfig().info().protocol_version == newest


def hellos_within(total_s: float) -> int:
    """Hellos the host sends in ``total_s``: one at once, then after waits of
    HELLO_FIRST_S doubling up to HELLO_MAX_S."""
    at, wait, sent = 0.0, HELLO_FIRST_S, 1
    while at + wait < total_s:
        at, wait, sent = at + wait, min(2 * wait, HELLO_MAX_S), sent + 1
    return sent


def test_the_handshake_bounds_are_the_hosts():
    hello = section("4.1")
    assert (f"first after {HELLO_FIRST_S:g} s, the wait doubling up to {HELLO_MAX_S:g} s"
            in hello)
    assert (f"gives up after {HANDSHAKE_TOTAL_S:g} s in all on the first handshake "
            f"({hellos_within(HANDSHAKE_TOTAL_S)} Hellos), {RESYNC_TIMEOUT_S:g} s on a "
            "recovery or a reconnect (6.2)") in hello
    bounds = section("6.2")
    assert (f"| first handshake | {HANDSHAKE_TOTAL_S:g} s in total (Hello resent after "
            f"{HELLO_FIRST_S:g} s, the wait doubling to {HELLO_MAX_S:g} s)") in bounds
    assert f"| handshake of a recovery or a reconnect | {RESYNC_TIMEOUT_S:g} s" in bounds


@pytest.fixture(params=CORES)
def device_class(request):
    return core_class(request.param)


@pytest.mark.parametrize("version", [2, 3, 4])
def test_flushed_and_force_reports_follow_every_version_that_has_them(device_class, version):
    """A host of ``version`` streams, then falls silent: the device's ForceReports
    (version 3 on) and its Flushed after the watchdog trip (version 2 on) come in
    ``version`` frames, as 4.8 and 4.9 say."""
    core = device_class(DeviceConfig(lateral_n=0.25, protocol_version=p.PROTOCOL_VERSION))
    core.receive(p.encode(p.Hello(10), 0, version=1), 0.0)
    wire = p.amplitude_to_wire(np.full((200, 1), 1.0))[0]
    core.receive(p.encode(p.Block(0, wire), 1, version=version), 0.0)
    frames = p.Decoder().feed(core.advance_to(0.1))  # 15 ms played, then silence
    kinds = {type(f.message): f.version for f in frames}
    assert kinds.get(p.Flushed) == version
    assert kinds.get(p.ForceReport) == (version if version >= 3 else None)
    assert ("was version 2 or later (2, 3 or 4), in that version" in section("4.8")
            and "was version 3 or later (3 or 4), in that version" in section("4.9"))
