"""``sim-device --tcp '[::1]:0'`` listens on IPv6 loopback and prints a URL the host
opens (``socket://[::1]:PORT``): ::1 was said to be no address of this machine ('Name or
service not known'), as the listener took only IPv4 and the brackets as part of the name."""

import argparse
import io
import socket
import threading

import pytest

from frictex.app.commands.sim_device import _tcp_address
from frictex.device.link.host import open_sink
from frictex.device.link.simdevice import (DeviceConfig, DeviceCore, host_port, open_listener,
                                           serve, socket_url)


def _ipv6_loopback() -> bool:
    """Whether this machine can listen on ::1 at all (a container may have no IPv6)."""
    try:
        socket.create_server(("::1", 0), family=socket.AF_INET6).close()
    except OSError:
        return False
    return True


def test_an_ipv6_host_is_given_in_brackets_and_taken_without():
    assert _tcp_address("[::1]:0") == ("::1", 0)
    assert _tcp_address("127.0.0.1:5000") == ("127.0.0.1", 5000)
    assert _tcp_address("5000") == ("127.0.0.1", 5000)
    assert host_port("::1", 5000) == "[::1]:5000" and host_port("h", 1) == "h:1"
    with pytest.raises(argparse.ArgumentTypeError, match=r"written in brackets, \[ADDRESS\]"):
        _tcp_address("::1:0")


@pytest.mark.skipif(not _ipv6_loopback(), reason="no IPv6 loopback on this machine")
def test_a_host_reaches_the_device_listening_on_ipv6_loopback():
    listener = open_listener("::1", 0)
    url = socket_url(listener)
    assert url.startswith("socket://[::1]:")
    core, quit_event = DeviceCore(DeviceConfig()), threading.Event()
    thread = threading.Thread(target=serve, args=(core,), daemon=True,
                              kwargs=dict(listener=listener, quit_event=quit_event))
    thread.start()
    try:
        sink = open_sink(url, 1, 10_000.0, paced=True, stderr=io.StringIO())
        sink.close()
        assert core.decoder.counts.frames_ok >= 1  # its Hello, answered before open returned
    finally:
        quit_event.set()
        thread.join(30)
        listener.close()
