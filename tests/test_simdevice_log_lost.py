"""A simulated device's log that cannot be written (``sim-device --log /dev/full``) crashed
the session: a thread traceback ('Exception in thread frictex-log-flush ... OSError:
[Errno 28]'), then 'frictex: error: [Errno 28] No space left on device' naming no file.
Now one line names the log and what happened, once; logging stops and the device goes on
serving the host, its watchdog and clamps as before."""

from __future__ import annotations

import os

import numpy as np
import pytest

from frictex.device.link.host import open_sink
from frictex.device.link.simdevice import CsvLog

pytestmark = pytest.mark.skipif(not os.path.exists("/dev/full"), reason="no /dev/full")

LOST = ("frictex: warning: cannot write the log file /dev/full: No space left on device; "
        "logging stopped, the simulated device goes on")


def test_a_log_that_cannot_be_written_is_said_once_and_dropped(capsys):
    log = CsvLog("/dev/full", ["index", "ch0_um"])
    for start in range(0, 40_000, 2_000):  # past any buffer: the writes themselves fail
        log.rows([np.arange(start, start + 2_000), np.full(2_000, 1.5)], ["%d", "%.9f"])
        log.flush()
    log.close()
    assert capsys.readouterr().err.splitlines() == [LOST]
    assert log.lost


def test_a_replay_on_a_simulated_device_outlives_its_lost_log(capsys):
    with open_sink("sim", channels=1, rate_hz=10_000.0, paced=True,
                   log_path="/dev/full") as sink:
        for start in range(0, 20_000, 500):
            sink.send(start, np.full((500, 1), 1.0))
    assert sink.status()["commanded_samples"] == 20_000
    err = capsys.readouterr().err
    assert err.splitlines() == [LOST] and "Traceback" not in err



def test_sim_device_ends_with_exit_1_when_its_log_was_lost():
    """As the C host port does: the device serves its host to the end, then says the log
    ended early and exits 1 (a run whose output is incomplete says so)."""
    import subprocess
    import sys

    proc = subprocess.Popen([sys.executable, "-m", "frictex", "sim-device", "--once", "--tcp",
                             "0", "--log", "/dev/full"], stdout=subprocess.PIPE,
                            stderr=subprocess.PIPE, text=True)
    try:
        url = proc.stdout.readline().strip()
        assert url.startswith("socket://"), url
        with open_sink(url, channels=1, rate_hz=10_000.0, paced=True) as sink:
            for start in range(0, 20_000, 500):
                sink.send(start, np.full((500, 1), 1.0))
        _, err = proc.communicate(timeout=120)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()
    assert proc.returncode == 1, err
    assert LOST in err and "Traceback" not in err
    assert err.strip().splitlines()[-1] == (
        "frictex: error: --log: logging stopped early (said above)"), err
