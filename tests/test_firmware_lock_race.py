"""The C core with the sample interrupt preempting fw_receive at each of its locks in turn
(tests/firmware_lock_race.c, built here with the system cc): what a tick can change
between two critical sections of a frame must not let the frame undo it."""

import shutil
import subprocess
from pathlib import Path

import numpy as np
import pytest

from frictex.device.firmware.build import FIRMWARE
from frictex.device.link import protocol as p

HARNESS = Path(__file__).resolve().parent / "firmware_lock_race.c"
FLAGS = ("-std=c11", "-D_GNU_SOURCE", "-O1", "-Wall", "-Wextra", "-Werror")


@pytest.fixture(scope="module")
def lock_race(tmp_path_factory):
    """The harness binary, built from the core's sources."""
    if shutil.which("cc") is None:
        pytest.skip("cc not found: install the Debian package gcc to build the C core")
    binary = tmp_path_factory.mktemp("lock_race") / "lock_race"
    sources = sorted(str(s) for s in (FIRMWARE / "core").glob("*.c"))
    proc = subprocess.run(["cc", *FLAGS, "-I", str(FIRMWARE / "core"), "-o", str(binary),
                           *sources, str(HARNESS)], capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    return binary


def frames(*messages, seq=0) -> bytes:
    return b"".join(p.encode(m, seq + i) for i, m in enumerate(messages))


def amplitudes(n, counts):
    return np.full((n, 1), counts, np.uint16)


def test_a_block_racing_a_drain_that_runs_dry_never_restarts_the_plate(lock_race):
    """Hello(10), Block(0, 10 samples), Stop(drain=1), the 10 samples played; then
    Block(10, 400 samples at the 16384-count limit) with the tick that runs the drain dry
    preempting it at each lock. The Block's readiness check ran outside the lock that left
    SILENT: preempted at that lock, the Block found SILENT and played (PLAYING with the
    Stop completed; 249 samples at the limit before the watchdog ended it). Now a Block
    that finds the Stop completed is refused (NOT_READY), and none plays after it; one
    taken before the drain ran dry is drained with the rest."""
    setup = frames(p.Hello(10), p.Block(0, amplitudes(10, 4096)), p.Stop(drain=True))
    race = frames(p.Block(10, amplitudes(400, 16384)), seq=3)
    proc = subprocess.run([str(lock_race)], input=f"{setup.hex()}\n{race.hex()}\n",
                          capture_output=True, text=True, timeout=120)
    assert proc.returncode == 0, proc.stderr
    runs = [line.split() for line in proc.stdout.splitlines()]
    assert len(runs) > 400, "the Block took fewer locks than it has samples"
    refused = flushed_runs = 0
    for _, k, _, played_after_stop, _, restarted, _, held, _, flushed, _, *reply in runs:
        assert (played_after_stop, restarted) == ("0", "0"), f"interrupt at lock {k}"
        # a drain that ran dry while the Block was stored: the samples stored after it
        # were kept while SILENT (Status level 400, nothing to play); now flushed, counted
        assert held == "0", f"interrupt at lock {k}"
        flushed_runs += flushed != "0"
        codes = [f.message.code for f in p.Decoder().feed(bytes.fromhex("".join(reply)))
                 if isinstance(f.message, p.ErrorReport)]
        refused += codes == [p.ErrorCode.NOT_READY]
    # preempted at any lock up to the one that reads readiness (three in this core): refused
    assert refused >= 3
    assert flushed_runs >= 1  # preempted after the Block was taken, before its first sample
