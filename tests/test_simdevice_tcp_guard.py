"""The TCP simulated device: a silent connection cannot hold it (before its Hello or after
it), an idle host is never dropped, refusals are rate-limited.

serve() runs in a thread on a clock the test moves: no sleeps decide a result, every
wait is bounded; the last test connects the host's own link over loopback and lets it
idle in real time.
"""

import io
import socket
import threading
import time

from frictex.device.link import protocol as p
from frictex.device.link.host import open_sink
from frictex.device.link.simdevice import (HELLO_TIMEOUT_S, REFUSAL_REPORT_S, SILENT_HOST_S,
                                           DeviceConfig, DeviceCore, open_listener, serve,
                                           socket_url)


class Clock:
    def __init__(self):
        self.now = 0.0

    def __call__(self):
        return self.now


def until(condition, what):
    deadline = time.monotonic() + 30.0
    while not condition():
        assert time.monotonic() < deadline, what
        time.sleep(0.002)


def started(clock=None, **kwargs):
    """serve() in a thread on a fresh core, on ``clock`` (a Clock the test moves unless
    given); what it reports in ``calls``: refused (counts), dropped before a Hello,
    silent after one (s)."""
    listener = open_listener()
    clock, quit_event = clock or Clock(), threading.Event()
    calls = {"refused": [], "dropped": [], "silent": []}
    core = DeviceCore(DeviceConfig())
    thread = threading.Thread(target=serve, args=(core,), kwargs=dict(
        listener=listener, clock=clock, quit_event=quit_event,
        on_refused=lambda a, n: calls["refused"].append(n),
        on_dropped=lambda a: calls["dropped"].append(a),
        on_silent=lambda a, silent_s: calls["silent"].append(silent_s), **kwargs), daemon=True)
    thread.start()
    return listener, clock, quit_event, calls, thread, core


def stopped(listener, quit_event, thread):
    quit_event.set()
    thread.join(30)
    listener.close()


def connect(listener):
    sock = socket.create_connection(listener.getsockname()[:2], timeout=30)
    return sock


def hello(listener, core, version: int = 1):
    """A host connected that has said Hello (protocol ``version``) and been heard."""
    host = connect(listener)
    heard = core.hellos
    host.sendall(p.encode(p.Hello(prefill=10), 0, version))
    until(lambda: core.hellos > heard, "the host's Hello handled")
    return host


def closed(sock) -> bool:
    """True once the device closed ``sock`` (EOF or reset)."""
    sock.setblocking(False)
    try:
        return sock.recv(4096) == b""
    except BlockingIOError:
        return False
    except ConnectionError:
        return True


def test_a_host_without_hello_is_dropped_and_the_next_is_served():
    listener, clock, quit_event, calls, thread, core = started()
    try:
        silent = connect(listener)
        connect(listener).close()  # refused once the silent one is taken: the sync point
        until(lambda: calls["refused"], "the silent host taken at clock 0")
        clock.now = HELLO_TIMEOUT_S / 2  # within the time: kept
        time.sleep(0.05)
        assert not closed(silent) and calls["dropped"] == []
        clock.now = HELLO_TIMEOUT_S + 0.1
        until(lambda: calls["dropped"], "the silent host dropped")
        until(lambda: closed(silent), "its socket closed")
        host = hello(listener, core)
        clock.now += 2 * HELLO_TIMEOUT_S  # said Hello: not dropped before SILENT_HOST_S
        time.sleep(0.05)
        assert len(calls["dropped"]) == 1 and calls["refused"] == [1]
        host.close()
        silent.close()
    finally:
        stopped(listener, quit_event, thread)


def test_a_flood_of_refused_connections_is_reported_once_a_second_with_a_count():
    # the Hello'd host stays silent however far the clock moves: it is never dropped
    listener, clock, quit_event, calls, thread, core = started(silent_host_s=1e9)
    try:
        host = hello(listener, core)
        for _ in range(40):  # all within one second of the device's clock
            connect(listener).close()
        until(lambda: calls["refused"], "the first report")
        time.sleep(0.1)
        assert len(calls["refused"]) == 1  # the clock has not moved a second
        bumps = 0
        while sum(calls["refused"]) < 40 and thread.is_alive():
            # refusals the device had not accepted yet at the last report are told at the
            # next one, a second later: the clock moves once each report is out
            reports = len(calls["refused"])
            clock.now += REFUSAL_REPORT_S
            bumps += 1
            until(lambda: len(calls["refused"]) > reports or not thread.is_alive(),
                  "a report a second while refusals wait")
    finally:
        stopped(listener, quit_event, thread)
    assert sum(calls["refused"]) == 40 and len(calls["refused"]) <= bumps + 1
    host.close()


def answers(sock) -> list:
    """The messages in the device's next packet on ``sock``."""
    sock.settimeout(30)
    return [frame.message for frame in p.Decoder().feed(sock.recv(4096))]


def test_a_host_silent_after_its_hello_is_dropped_and_the_next_is_served():
    listener, clock, quit_event, calls, thread, core = started()
    try:
        quiet = connect(listener)
        quiet.sendall(b"\x00" + p.encode(p.Hello(100), 0, 4))
        until(lambda: core.hellos == 1, "the quiet host's Hello handled")
        clock.now = SILENT_HOST_S - 0.5  # within the bound: kept
        time.sleep(0.05)
        assert not closed(quiet) and calls["silent"] == []
        clock.now = SILENT_HOST_S + 0.1
        until(lambda: calls["silent"], "the quiet host dropped")
        until(lambda: closed(quiet), "its socket closed")
        assert calls["silent"][0] > SILENT_HOST_S
        host = connect(listener)
        host.sendall(p.encode(p.Hello(prefill=10), 0, 4))
        assert isinstance(answers(host)[0], p.Info)  # served, not refused busy
        host.close()
        quiet.close()
    finally:
        stopped(listener, quit_event, thread)
    assert len(calls["silent"]) == 1 and calls["dropped"] == []


def test_a_host_that_heartbeats_is_never_dropped():
    """Heartbeats a second apart on the device's clock (a real host's are 5 ms apart)."""
    listener, clock, quit_event, calls, thread, core = started()
    try:
        host = hello(listener, core, version=4)
        for seq in range(1, 4 * int(SILENT_HOST_S) + 1):
            clock.now += 1.0
            frames = core.decoder.counts.frames_ok
            host.sendall(p.encode(p.Heartbeat(seq), seq, 4))
            until(lambda: core.decoder.counts.frames_ok > frames, "the Heartbeat handled")
        assert calls["silent"] == [] and not closed(host)
        host.close()
    finally:
        stopped(listener, quit_event, thread)


def test_the_hosts_own_link_idling_on_tcp_is_not_dropped():
    """A replay's link that has nothing to send still heartbeats: 3 s idle against a
    2 s bound (the real bound is 5 s; the host heartbeats every watchdog_ms / 5)."""
    listener, _, quit_event, calls, thread, core = started(time.monotonic, silent_host_s=2.0)
    try:
        sink = open_sink(socket_url(listener), 1, 10_000.0, paced=True, stderr=io.StringIO())
        try:
            frames = core.decoder.counts.frames_ok
            time.sleep(3.0)
            heard = core.decoder.counts.frames_ok - frames
            assert calls["silent"] == [] and sink.status()["reconnects"] == 0
        finally:
            sink.close()
    finally:
        stopped(listener, quit_event, thread)
    assert heard >= 3  # it did speak while idle, at least once a second


def test_a_new_host_does_not_inherit_the_bytes_the_last_one_left_half_sent():
    """PROTOCOL.md 2: a first frame MAY come without a leading 0x00; what the host before
    left unterminated is not the start of it."""
    listener, clock, quit_event, calls, thread, core = started()
    try:
        first = connect(listener)
        first.sendall(b"\x01\x02\x00" + b"\x01" * 10)  # a short frame, then 10 bytes unended
        until(lambda: core.decoder.counts.discarded == 1, "the short frame read")
        clock.now = HELLO_TIMEOUT_S + 0.1
        until(lambda: calls["dropped"], "the first host dropped")
        host = connect(listener)
        host.sendall(p.encode(p.Hello(prefill=10), 0, 4))
        until(lambda: core.hellos or core.decoder.counts.discarded > 1, "the Hello read")
        assert core.hellos == 1 and isinstance(answers(host)[0], p.Info)
        assert core.decoder.counts.discarded == 1  # the count goes on
        host.close()
        first.close()
    finally:
        stopped(listener, quit_event, thread)
