"""What a paced replay's counts leave out is said in summary.json's warnings (printed on
stderr with the others, except with --quiet): a
protocol-1 device's watchdog trips (it does not count what they dropped: the run read
0 unplayed and passed), and underruns (sim:buffer=200 ran dry 101 times, exit 0, no
word). A device buffer under two of the pipeline's blocks is refused (sim:buffer=2 lost
96 % as overflow; buffer=50 ran dry 400 times)."""

from __future__ import annotations

import json
import subprocess
import sys

import pytest

SCENE, TRACE = "grating-5mm", "swipe-40mms-50hz"


def replay(tmp_path, *device_args):
    """(exit status, stderr, summary or None) of a replay to ``device_args``."""
    out = tmp_path / "out"
    done = subprocess.run([sys.executable, "-m", "frictex", "replay", SCENE, TRACE, "--out",
                           str(out), "--quiet", *device_args],
                          capture_output=True, text=True, timeout=120)
    summary = json.loads((out / "summary.json").read_text()) if out.exists() else None
    return done.returncode, done.stderr, summary


def test_watchdog_trips_of_a_version_1_device_are_said_uncountable(tmp_path):
    """The injected trip is counted and said; a loaded machine may starve the link into
    more (a newest-versions run beside two busy processes counted 2), said with their
    number."""
    code, err, summary = replay(tmp_path, "--device", "sim:protocol=1",
                                "--faults", "trip@1")
    trips = summary["device"]["watchdog_trips_in_run"]
    assert trips >= 1
    assert summary["device"]["unplayed_known"] is False
    said = (f"the device tripped its watchdog {trips} time(s) (the plate stopped) and, speaking "
            "protocol version 1, does not count the samples it dropped: unplayed_samples "
            "counts only the known causes and --max-unplayed cannot be checked")
    assert said in summary["warnings"]


def test_a_version_1_device_without_trips_says_nothing(tmp_path):
    """No fault injected: nothing said unless the watchdog really tripped (a loaded
    machine may starve the link that long: then it is said, as above)."""
    code, err, summary = replay(tmp_path, "--device", "sim:protocol=1")
    said = any("watchdog" in w for w in summary["warnings"])
    assert code == 0 and said == (summary["device"]["watchdog_trips_in_run"] > 0)


def test_underruns_of_a_paced_replay_are_said(tmp_path):
    code, err, summary = replay(tmp_path, "--device", "sim:buffer=200")
    runs = summary["device"]["underruns_in_run"]
    assert runs > 0
    said = (f"the device's buffer (200 samples) ran empty {runs} time(s) during the paced "
            "replay (underruns): the plate fell silent until the next block came")
    assert said in summary["warnings"]


@pytest.mark.parametrize("buffer", [2, 50, 99])
def test_a_buffer_under_two_blocks_is_refused(tmp_path, capfd, buffer):
    code, err, summary = replay(tmp_path, "--device", f"sim:buffer={buffer}")
    assert code == 1 and summary is None
    assert (f"sim:// (frictex sim-device) buffers {buffer} samples, less than two of the "
            "pipeline's 50-sample blocks: it would overflow or run dry between them") in err
