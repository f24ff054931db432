"""The TCP simulated device drops a host gone silent after its Hello, never an idle one.

The first two tests run serve() in a thread on a clock the test moves (no sleep decides
a result, every wait is bounded); the last connects the host's own link over loopback
and lets it idle in real time.
"""

import io
import socket
import threading
import time

from frictex.device.link import protocol as p
from frictex.device.link.host import open_sink
from frictex.device.link.simdevice import (SILENT_HOST_S, DeviceConfig, DeviceCore,
                                           open_listener, serve, socket_url)


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def until(condition, what, limit_s=30.0):
    deadline = time.monotonic() + limit_s
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.002)


def started(clock, **kwargs):
    """serve() in a thread on a fresh core; (listener, quit_event, silent calls, thread, core)."""
    listener = open_listener()
    quit_event, silent = threading.Event(), []
    core = DeviceCore(DeviceConfig())
    thread = threading.Thread(target=serve, args=(core,), kwargs=dict(
        listener=listener, clock=clock, quit_event=quit_event,
        on_silent=lambda address, silent_s: silent.append(silent_s), **kwargs), daemon=True)
    thread.start()
    return listener, quit_event, silent, thread, core


def connect(listener):
    return socket.create_connection(listener.getsockname()[:2], timeout=30)


def closed(sock) -> bool:
    """True once the device closed ``sock`` (EOF or reset); reads what it sent."""
    sock.setblocking(False)
    try:
        return sock.recv(4096) == b""
    except BlockingIOError:
        return False
    except ConnectionError:
        return True


def answers(sock) -> list:
    """The messages in the device's next packet on ``sock``."""
    sock.settimeout(30)
    return [frame.message for frame in p.Decoder().feed(sock.recv(4096))]


def stopped(listener, quit_event, thread):
    quit_event.set()
    thread.join(30)
    listener.close()


def test_a_host_silent_after_its_hello_is_dropped_and_the_next_is_served():
    clock = Clock()
    listener, quit_event, silent, thread, core = started(clock)
    try:
        quiet = connect(listener)
        quiet.sendall(b"\x00" + p.encode(p.Hello(100), 0, 4))
        until(lambda: core.hellos == 1, "the quiet host's Hello handled")
        clock.now = SILENT_HOST_S - 0.5  # within the bound: kept
        time.sleep(0.05)
        assert not closed(quiet) and silent == []
        clock.now = SILENT_HOST_S + 0.1
        until(lambda: silent, "the quiet host dropped")
        until(lambda: closed(quiet), "its socket closed")
        assert silent[0] > SILENT_HOST_S
        host = connect(listener)
        host.sendall(p.encode(p.Hello(prefill=10), 0, 4))
        assert isinstance(answers(host)[0], p.Info)  # served, not refused busy
        host.close()
        quiet.close()
    finally:
        stopped(listener, quit_event, thread)
    assert len(silent) == 1


def test_a_host_that_heartbeats_is_never_dropped():
    """Heartbeats a second apart on the device's clock (a real host's are 5 ms apart)."""
    clock = Clock()
    listener, quit_event, silent, thread, core = started(clock)
    try:
        host = connect(listener)
        host.sendall(p.encode(p.Hello(prefill=10), 0, 4))
        until(lambda: core.hellos == 1, "the Hello handled")
        for seq in range(1, 4 * int(SILENT_HOST_S) + 1):
            clock.now += 1.0
            frames = core.decoder.counts.frames_ok
            host.sendall(p.encode(p.Heartbeat(seq), seq, 4))
            until(lambda: core.decoder.counts.frames_ok > frames, "the Heartbeat handled")
        assert silent == [] and not closed(host)
        host.close()
    finally:
        stopped(listener, quit_event, thread)


def test_the_hosts_own_link_idling_on_tcp_is_not_dropped():
    """A replay's link that has nothing to send still heartbeats: 3 s idle against a
    2 s bound (the real bound is 5 s; the host heartbeats every watchdog_ms / 5)."""
    listener, quit_event, silent, thread, core = started(time.monotonic, silent_host_s=2.0)
    try:
        sink = open_sink(socket_url(listener), 1, 10_000.0, paced=True, stderr=io.StringIO())
        try:
            frames = core.decoder.counts.frames_ok
            time.sleep(3.0)
            heard = core.decoder.counts.frames_ok - frames
            assert silent == [] and sink.status()["reconnects"] == 0
        finally:
            sink.close()
    finally:
        stopped(listener, quit_event, thread)
    assert heard >= 3  # it did speak while idle, at least once a second
