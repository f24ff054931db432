"""What a stream to a device on the wall clock can be held to however the scheduler runs.

A device plays on its own clock and trips its watchdog when the host falls silent for
longer than ``watchdog_ms`` (PROTOCOL.md 5.3). On a busy machine the host's link thread
can be descheduled that long: the trip then flushes what the device held, and those
samples never play. That is the safety design, not a fault of the link, so tests of
streaming assert what holds for any timing: every commanded sample is played exactly as
commanded or counted unplayed by its cause, and nothing is unplayed without a trip.
"""

from __future__ import annotations

import os
import threading
import time

import numpy as np
import pytest

from frictex.device.firmware.build import FirmwareBuildError
from frictex.device.firmware.ccore import built_core_class
from frictex.device.link.simdevice import DeviceCore, open_pty, serve

#: the device logic a link test runs against: the Python reference, the C firmware's core
CORES = ["python", "c-firmware"]


def core_class(kind: str):
    """The device core class of ``kind`` (one of :data:`CORES`), the firmware built; a
    firmware that does not build fails the test, with the compiler's message."""
    if kind == "python":
        return DeviceCore
    try:
        return built_core_class()
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


def accounted(status: dict, played_index: np.ndarray | None, commanded: int) -> None:
    """Every commanded sample is played or counted unplayed, and the device's own log
    (``played_index``: the sample numbers it played, None when it kept no log) agrees:
    what the host says played did play, and nothing that did not play is missing from
    the unplayed count."""
    assert status["commanded_samples"] == commanded, status
    assert status["played_samples"] + status["unplayed_samples"] == commanded, status
    assert sum(status["unplayed_by_cause"].values()) == status["unplayed_samples"], status
    if played_index is None:
        return
    lost = status["unplayed_by_cause"]["lost"]
    assert status["played_samples"] <= len(played_index) <= status["played_samples"] + lost
    assert commanded - len(played_index) <= status["unplayed_samples"]


def all_played_unless_tripped(status: dict, played_index: np.ndarray | None,
                              commanded: int, trips: int | None = None) -> None:
    """:func:`accounted`, and with no watchdog trip every sample played: a clean stream
    loses nothing, a starved host loses only on the device's side what its trips
    flushed (and counts it), never on the host's, and the stream goes on. ``trips``: the
    device's trips during this stream, when not the Status's count since power-up.
    (A device silent for half a second, so starved itself, is handshaken again, which
    restarts its buffer: a recovery, counted like a trip; so is a port that a starved
    device's pty made fail, 'returned no data', whether reconnected or lost while the
    stream closed: what was in flight or queued is lost, counted.)"""
    accounted(status, played_index, commanded)
    trips = status["watchdog_trips"] if trips is None else trips
    restarted = status["recoveries"] + status["reconnects"] + status["disconnects"]
    if trips == 0 and restarted == 0:
        assert status["unplayed_samples"] == 0, status["unplayed_by_cause"]
    else:
        assert status["played_samples"] > 0, "nothing played"
        if restarted == 0:
            by_cause = status["unplayed_by_cause"]
            assert by_cause["disconnected"] == by_cause["queue_full"] == by_cause["stalled"] == 0


def clean_unless_starved(status: dict, blocks: int) -> bool:
    """With no watchdog trip, no recovery and no reconnect (a device or host starved of
    CPU for half a second is handshaken again, which drops what waited, counted), every one of
    ``blocks`` went out once and nothing was damaged on the wire; returns whether the
    stream was so clean (for the caller's further checks of a clean stream)."""
    if status["recoveries"] or status["reconnects"] or status["watchdog_trips"]:
        return False
    assert status["blocks_sent"] == blocks and status["dropped_blocks"] == 0, status
    assert status["resyncs"] == 0 and status["device_crc_errors"] == 0, status
    return True


def in_order_within(played_index: np.ndarray, commanded_index: np.ndarray) -> None:
    """The samples that played are commanded ones, each once, in the order commanded."""
    where = np.searchsorted(commanded_index, played_index)
    assert np.all(where < len(commanded_index))
    assert np.array_equal(commanded_index[where], played_index)
    assert np.all(np.diff(where) > 0)


def until(predicate, what: str, timeout_s: float = 20.0) -> None:
    """Wait for ``predicate()`` (polled every 5 ms); fail naming ``what`` after
    ``timeout_s``. For a state that follows from the test's own actions once the threads
    involved have run, however late the scheduler runs them."""
    deadline = time.monotonic() + timeout_s
    while not predicate():
        assert time.monotonic() < deadline, f"{what}: not within {timeout_s:g} s"
        time.sleep(0.005)


def start_sim_device(channels: int, rate_hz: float, *, phases: bool = False, log_path=None,
                     tcp: bool = False, extra: tuple[str, ...] = ()):
    """``frictex sim-device`` in a process of its own, as an external tool would run it
    (``app.commands.sim_device.spawn``); returns (process, pty path or ``socket://``
    URL). The in-process ``sim`` device needs none of this."""
    import os

    from frictex.app.commands.sim_device import spawn
    flags = (*(["--phases"] if phases else []),
             *(["--log", os.fspath(log_path)] if log_path is not None else []), *extra)
    return spawn(channels, rate_hz, tcp=tcp, extra=tuple(flags))


def serve_on_pty(core):
    """Serve the simulated device ``core`` on a new pty from a thread of this process (so
    the test can look inside it); returns (the pty's path, stop(keep_pty=False)).

    The device is gone when ``stop`` returns (its thread has ended), and its pty with it
    unless ``keep_pty``: then the path stays openable and nothing answers. A closed pty's
    number goes to the next pty any process opens: a host reopening the path then reaches
    that one (another test's device), so a test that stops the device either keeps its
    pty or unplugs the host's port first. Calling ``stop`` again closes a kept pty."""
    master, slave, path = open_pty()
    quit_event = threading.Event()
    thread = threading.Thread(target=serve, args=(core, master),
                              kwargs={"quit_event": quit_event}, daemon=True)
    thread.start()
    open_fds = [master, slave]

    def stop(keep_pty: bool = False):
        if not quit_event.is_set():
            quit_event.set()
            thread.join(timeout=30.0)
            assert not thread.is_alive(), "the simulated device did not stop within 30 s"
        while open_fds and not keep_pty:
            os.close(open_fds.pop())
    return path, stop
