"""The TCP simulated device: a silent connection cannot hold it, refusals are rate-limited.

serve() runs in a thread on a clock the test moves: no sleeps decide a result, every
wait is bounded.
"""

import socket
import threading
import time

from frictex.device.link import protocol as p
from frictex.device.link.simdevice import (HELLO_TIMEOUT_S, REFUSAL_REPORT_S, DeviceConfig,
                                           DeviceCore, open_listener, serve)


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


def started(**kwargs):
    listener = open_listener()
    clock, quit_event, calls = Clock(), threading.Event(), {"refused": [], "dropped": []}
    core = DeviceCore(DeviceConfig())
    thread = threading.Thread(target=serve, args=(core,), kwargs=dict(
        listener=listener, clock=clock, quit_event=quit_event,
        on_refused=lambda a, n: calls["refused"].append(n),
        on_dropped=lambda a: calls["dropped"].append(a), **kwargs), daemon=True)
    thread.start()
    return listener, clock, quit_event, calls, thread, core


def connect(listener):
    sock = socket.create_connection(listener.getsockname()[:2], timeout=30)
    return sock


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
        host = connect(listener)
        host.sendall(p.encode(p.Hello(prefill=10), 0, 1))
        until(lambda: core.hellos == 1, "the next host's Hello handled")
        clock.now += 2 * HELLO_TIMEOUT_S  # said Hello: not dropped before SILENT_HOST_S
        time.sleep(0.05)
        assert len(calls["dropped"]) == 1 and calls["refused"] == [1]
        host.close()
        silent.close()
    finally:
        quit_event.set()
        thread.join(30)
        listener.close()


def test_a_flood_of_refused_connections_is_reported_once_a_second_with_a_count():
    listener, clock, quit_event, calls, thread, core = started()
    try:
        host = connect(listener)
        host.sendall(p.encode(p.Hello(prefill=10), 0, 1))
        until(lambda: core.hellos == 1, "the host served")
        for _ in range(40):  # all within one second of the device's clock
            connect(listener).close()
        until(lambda: calls["refused"], "the first report")
        time.sleep(0.1)
        assert len(calls["refused"]) == 1  # the clock has not moved a second

        def all_counted():
            # a second more at each look: refusals the device had not accepted yet at the
            # first report are told at a later one
            clock.now += REFUSAL_REPORT_S
            return sum(calls["refused"]) == 40 or not thread.is_alive()
        until(all_counted, "all counted")
    finally:
        quit_event.set()
        thread.join(30)
        listener.close()
    assert sum(calls["refused"]) == 40 and len(calls["refused"]) <= 2
    host.close()
