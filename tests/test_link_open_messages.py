"""The link's opening errors say each thing once and blame the right party: a missing
serial port said '[Errno 2]' twice ("cannot open device port '/dev/ttyACM9': [Errno 2]
could not open port /dev/ttyACM9: [Errno 2] No such file or directory: '/dev/ttyACM9'"),
and a handshake spoiled by the user's own ``--faults corrupt=0.05`` asked "is it a
frictex device?"."""

from __future__ import annotations

import socket

import pytest

from frictex.device.link.faults import parse_faults
from frictex.device.link.host import LinkError, open_port, open_sink


def test_a_missing_port_gives_the_reason_once(tmp_path):
    missing = tmp_path / "ttyACM9"
    with pytest.raises(LinkError) as refused:
        open_port(str(missing))
    assert str(refused.value) == (f"cannot open device port {str(missing)!r}: "
                                  "No such file or directory")


@pytest.mark.parametrize("kind", ["regular file", "folder"])
def test_a_path_that_is_no_serial_port_is_said_so(tmp_path, kind):
    """pyserial said "Could not configure port: (25, 'Inappropriate ioctl for device')"
    of --device /etc/passwd."""
    path = tmp_path / "port"
    path.mkdir() if kind == "folder" else path.write_text("not a port\n")
    with pytest.raises(LinkError) as refused:
        open_port(str(path))
    assert str(refused.value) == (f"cannot open device port {str(path)!r}: not a serial port "
                                  f"(a {kind}); expected a serial device such as /dev/ttyACM0")


def test_a_refused_socket_gives_the_reason_once():
    with socket.socket() as closed:  # a port no one listens on
        closed.bind(("127.0.0.1", 0))
        url = "socket://127.0.0.1:%d" % closed.getsockname()[1]
    with pytest.raises(LinkError) as refused:
        open_port(url)
    assert str(refused.value) == f"cannot open device port {url!r}: Connection refused"


@pytest.mark.parametrize("spec", ["corrupt=0.05", "drop=0.1,garbage=0.2,seed=3",
                                  "stall=0.2@1.5,trip@3,unplug=2@4"])
def test_a_fault_plan_reads_back_as_its_spec(spec):
    assert str(parse_faults(spec)) == spec


def test_a_handshake_lost_to_injected_faults_says_so():
    """Every byte damaged: no Info gets through in the handshake's 10 s."""
    with pytest.raises(LinkError) as failed:
        open_sink("sim", 1, 10_000.0, paced=True, faults=parse_faults("corrupt=0.9"))
    message = str(failed.value)
    assert message.startswith("sim://: no answer to the handshake within ")
    assert message.endswith("; the faults injected (--faults corrupt=0.9) may have kept it "
                            "from answering"), message
    assert "is it a frictex device" not in message
