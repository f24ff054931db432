"""The device's counters summed over a run in which the device restarted or reconnected
(PROTOCOL.md 6.4).

A device's Status counters count since it powered up. A demo whose ``frictex sim-device``
was killed and started again mid-run said "the device ran dry 191 times", the second
device's count alone, though the first had counted 182; its status line went from "182
underruns" down to "167 underruns" once the link came back. A device that restarted counts
from 0 again, and the host tells it by ``frames_ok`` going back: its counts add to the
earlier device's. A device that only reconnected goes on counting: nothing is counted
twice.

The device is the Python reference core, called in-process by a host session on a clock
the test advances: no thread, no wall clock.
"""

import io

import numpy as np

from frictex.app.commands.demo import _Ended, _print_lines
from frictex.app.live.demo_loop import starved
from frictex.device.link.ledger import RunCounts
from frictex.device.link.protocol import Status
from frictex.device.link.session import HostSession
from frictex.device.link.simdevice import DeviceConfig, DeviceCore

RATE = 10_000.0
STEP_S = 0.001
BLOCK = 200  # samples: twice the prefill (10 ms), played out in 20 ms


class Wire:
    """A host session and a device core joined by a byte stream, on the test's clock."""

    def __init__(self):
        self.session = HostSession(1, RATE, phases=False, paced=False, label="test",
                                   stderr=io.StringIO())
        self.core = DeviceCore(DeviceConfig(rate_hz=RATE))
        self.t = 0.0
        self.start = 0
        self.session.connection_made(self.t)

    def run(self, seconds: float) -> None:
        """Advance the clock by ``seconds`` in steps of 1 ms, the bytes crossing each way."""
        for _ in range(round(seconds / STEP_S)):
            self.t += STEP_S
            to_device = self.session.poll(self.t)
            back = self.core.receive(to_device, self.t) if to_device else b""
            self.session.data_received(back + self.core.advance_to(self.t), self.t)

    def run_dry(self, times: int) -> None:
        """Play a block ``times`` times, each played out before the next: each runs dry."""
        for _ in range(times):
            with self.session.cond:
                self.session.ledger.command(BLOCK)
                self.session.queue.append((self.start, np.full((BLOCK, 1), 100, np.uint16),
                                           None))
            self.start += BLOCK
            self.run(0.05)

    def reconnect(self, restarted: bool) -> None:
        """The link is lost and comes back: to the same device, or to one that restarted
        (a new core, its counters from 0)."""
        self.session.connection_lost(ConnectionResetError(104, "Connection reset by peer"))
        if restarted:
            self.core = DeviceCore(DeviceConfig(rate_hz=RATE))
        else:
            self.core.new_connection()
        self.session.connection_made(self.t)
        self.run(0.3)
        assert self.session.phase == "session", "the handshake completed"

    def underruns(self) -> int:
        """The underruns over the run, as the host counts them."""
        return self.session.run_counts.totals["underruns"]


def test_a_device_that_restarted_mid_run_adds_its_underruns_to_the_earlier_ones():
    wire = Wire()
    wire.run(0.1)
    wire.run_dry(3)
    first = wire.core.counters.underruns
    assert first >= 3 and wire.underruns() == first
    wire.reconnect(restarted=True)
    assert wire.underruns() == first, "the restart itself counts nothing"
    wire.run_dry(2)
    second = wire.core.counters.underruns
    assert 2 <= second < first, "the new device counts from 0, below the first"
    assert wire.underruns() == first + second
    assert wire.session.status.underruns == second  # the device's own count since power-up


def test_a_device_that_reconnected_without_restarting_is_not_counted_twice():
    wire = Wire()
    wire.run(0.1)
    wire.run_dry(3)
    core = wire.core
    wire.reconnect(restarted=False)
    wire.run_dry(2)
    assert wire.core is core and wire.underruns() == core.counters.underruns >= 5


def test_the_counts_before_the_hosts_first_status_are_not_the_runs():
    wire = Wire()
    wire.core.counters.underruns = wire.core.counters.watchdog_trips = 7  # an earlier host's
    wire.run(0.1)
    wire.run_dry(2)
    assert wire.underruns() == wire.core.counters.underruns - 7 >= 2
    assert wire.session.run_counts.totals["watchdog_trips"] == 0


def status(frames_ok: int, underruns: int) -> Status:
    return Status(0, 2, 0, 0, underruns=underruns, frames_ok=frames_ok)


def test_a_restart_is_told_by_frames_ok_even_when_the_new_count_is_the_higher():
    runs = RunCounts(("underruns",))
    for frames_ok, underruns in [(10, 0), (500, 3), (4, 5), (40, 6), (2**31, 6), (2**32 - 1, 7),
                                (3, 8)]:
        runs.status(status(frames_ok, underruns))
    # 3 on the first device, 8 on the second, whose frames_ok wrapped at 2**32
    assert runs.totals["underruns"] == 3 + 8


def test_the_demo_says_the_runs_underruns_on_its_status_line_and_closing_line(capsys):
    """The figures of the reproduction: the second device counted 191 since it powered
    up, the run 373 (182 on the first)."""
    link = {"state": "closed", "skipped_blocks": 0, "underruns": 191, "underruns_in_run": 373,
            "unplayed_samples": 0, "commanded_samples": 2000, "unplayed_by_cause": {}}
    assert starved(link) == ", 373 underruns"
    summary = {"cpu_steal_pct": None, "blocks": 1, "output_s": 0.0, "deadline_misses": 0,
               "worst_lateness_ms": 0.0, "clamps_total": 0, "frames": 1, "frame_ms_mean": 1.0,
               "input_counts": {}, "control": None, "ended_by": "window",
               "dropped_record_blocks": 0}
    _print_lines(None, summary, _Ended(summary, link, None, None), None, None)
    assert capsys.readouterr().out.splitlines()[1].startswith(
        "demo: link: the device ran dry 373 times and 0 blocks were skipped")


def test_an_output_that_is_not_a_device_link_says_its_own_underruns():
    assert starved({"commanded_samples": 2000, "unplayed_samples": 0, "underruns": 4}) == (
        ", 4 underruns")
    assert starved({"commanded_samples": 0, "unplayed_samples": 0, "underruns": None}) == ""
