"""A host process that was stopped (SIGSTOP, a suspended laptop) while it waited for room
on a paced link is said to have been stopped, and its block kept: the device did nothing
wrong. Before, a 1.5 s stop ran out the 1 s wait, and the link warned "device took no
blocks for 1 s; dropped a block of 50 samples, stream goes on (said again when it ends)",
booked the block as stalled, and never said anything again.

The stop is played by the host's clock: the caller's wait comes back 1.5 s later than it
asked, with the lock held all along, so that nothing moved meanwhile, as in a stopped
process whose caller wakes before its link thread.
"""

import io
import threading
import time
import types

import numpy as np

from frictex.device.link import host
from frictex.device.link.host import open_sink

RATE = 10_000.0
STOP_S = 1.5


class StoppingClock:
    """``time`` for the host module: the monotonic clock, jumped by :data:`STOP_S` by
    the first wait on the link's condition after :meth:`arm`."""

    def __init__(self, cond: threading.Condition):
        self.offset = 0.0
        self.armed = False
        self._wait = cond.wait
        cond.wait = self.wait

    def monotonic(self) -> float:
        return time.monotonic() + self.offset

    def arm(self) -> None:
        self.armed = True

    def wait(self, timeout=None) -> bool:
        if not self.armed:
            return self._wait(timeout)
        self.armed = False
        self.offset += STOP_S  # the whole process stood still: the lock never let go
        return False


def test_a_stopped_host_is_said_stopped_and_its_block_kept(monkeypatch):
    err = io.StringIO()
    sink = open_sink("sim", 1, RATE, paced=True, queue_blocks=2, stderr=err)
    clock = StoppingClock(sink._cond)
    monkeypatch.setattr(host, "time", types.SimpleNamespace(monotonic=clock.monotonic))
    block = np.full((50, 1), 1.0)
    t0 = time.monotonic()
    try:
        for start in range(0, 40 * 50, 50):
            if start == 20 * 50:
                clock.arm()
            sink.send(start, block)
        assert not clock.armed, "no send waited for room after the clock was armed"
    finally:
        sink.close()
    assert time.monotonic() - t0 < 60.0
    said = err.getvalue()
    assert f"this host was stopped for {STOP_S:.1f} s (not the device)" in said, said
    assert "device took no blocks" not in said, said
    status = sink.status()
    assert status["stalls"] == 0
    assert status["dropped_blocks"] == 0
    assert status["stalled_s"] < 0.5 * STOP_S  # the stop is not the device's lag either


def test_a_single_stall_is_said_again_when_it_ends():
    """The first stall's warning promises it is said again when it ends: it is, for one
    stall as for several."""
    err = io.StringIO()
    sink = open_sink("sim", 1, RATE, paced=True, queue_blocks=2, stderr=err)
    try:
        for start in range(0, 10_000 * 50, 50):  # blocks outrun the device: the queue fills
            sink.send(start, np.full((50, 1), 1.0))
            if not sink.wait_for_room(0.001):
                break
        assert sink.status()["stalls"] == 1
        assert sink.wait_for_room(60.0)
    finally:
        sink.close()
    lines = err.getvalue().splitlines()
    assert sum("said again when it ends" in line for line in lines) == 1, lines
    ended = [line for line in lines if " in all, until it took blocks again: 1 stall, 0 " in line]
    assert len(ended) == 1, lines


def test_the_stall_policy_leaves_a_stop_out_of_its_lag():
    """2 s waited with nothing played, 1.5 s of it the host stopped: 0.5 s of lag."""
    from frictex.device.link.stall import StallPolicy
    policy = StallPolicy(RATE, give_up_s=5.0)
    policy.account(10.0, 0, waiting=True)
    policy.skip(STOP_S)
    policy.account(12.0, 0, waiting=True)
    assert abs(policy.lag_s - 0.5) < 1e-12
