"""The C host port with a log that cannot be written (``frictex-fw-host --log /dev/full
--once``) exited 0 without a word, the log lost: its writes, flushes and close went
unchecked. Now one line names the log and what happened, the device goes on serving the
host, and the port exits 1."""

from __future__ import annotations

import os

import numpy as np
import pytest

from frictex.device.firmware import hostport
from frictex.device.link.host import CommandSink, open_port

RATE = 10_000.0


@pytest.fixture(scope="module")
def binary(firmware_host_port):
    return firmware_host_port


@pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")
def test_a_log_lost_to_a_full_disk_is_said_and_is_exit_1(binary):
    proc, path = hostport.start(binary=binary, extra=("--log", "/dev/full"))
    sink = CommandSink(lambda: open_port(path), 1, RATE, paced=True, process=proc)
    for start in range(0, 6000, 50):
        sink.send(start, np.full((50, 1), 1.0), None)
    sink.close()
    causes = sink.status()["unplayed_by_cause"]  # the device went on: nothing unplayed
    # but what its watchdog flushed when a starved host went quiet (95 in a loaded CI run)
    assert all(n == 0 for cause, n in causes.items() if cause != "flushed"), causes
    assert proc.wait(timeout=30) == 1
    err = proc.stderr.read().splitlines()
    lost = [line for line in err if "/dev/full" in line]
    assert lost == ["frictex-fw-host: cannot write the log file /dev/full: No space left on "
                    "device; logging stopped, the device goes on"], err
