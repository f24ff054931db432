"""The simulated device's played-sample and plate logs reach the file while it runs.

A reader of ``sim-device --log`` saw 19,713 of 20,050 rows until the device exited, and
30 rows stayed missing for 10 s after a replay: rows were flushed only when a later row
came. Now a flusher writes them out at most ``LOG_FLUSH_S`` after they are written, the
device idle or not. Every wait here is bounded polling (30 s), never a timing assertion.
A log FIFO with no reader, or an empty log path, is refused in one line; one with a
reader is written as a stream.
"""

import os
import select
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

from frictex.app.commands.sim_device import HANG_S
from frictex.device.link import protocol as p
from frictex.device.link.simdevice import (CsvLog, DeviceConfig, DeviceCore, plate_log,
                                           plate_log_growth, played_log)

BOUND_S = 30.0


def eventually(read, expected):
    """``read()`` once it equals ``expected``, polled for at most :data:`BOUND_S`; the
    last value read otherwise."""
    deadline = time.monotonic() + BOUND_S
    value = read()
    while value != expected and time.monotonic() < deadline:
        time.sleep(0.01)
        value = read()
    return value


def data_lines(path):
    return path.read_text().splitlines()[1:]


def test_rows_reach_the_file_with_no_row_after_them(tmp_path):
    path = tmp_path / "played.csv"
    log = CsvLog(path, ["index", "ch0_um"])
    try:
        log.rows([np.arange(3), np.full(3, 1.5)], ["%d", "%.9f"])
        assert eventually(lambda: data_lines(path), ["0,1.500000000", "1,1.500000000",
                                                     "2,1.500000000"]) == [
            "0,1.500000000", "1,1.500000000", "2,1.500000000"]
    finally:
        log.close()
    log.close()  # idempotent
    assert path.read_text().splitlines()[0] == "index,ch0_um"


def test_a_device_gone_idle_has_its_played_and_plate_rows_on_disk(tmp_path):
    """A host plays 120 samples and stops talking; the device goes on (idle, no more
    played rows): every played row and every tick so far is in the files while they
    are still open."""
    config = DeviceConfig()
    played_path, plate_path = tmp_path / "played.csv", tmp_path / "plate.csv"
    core = DeviceCore(config)
    core.log, played_csv = played_log(played_path, config.channels, config.phases)
    core.plate_log, plate_csv = plate_log(plate_path, config.channels)
    try:
        core.receive(p.encode(p.Hello(0), 0), 0.0)
        wire = p.amplitude_to_wire(np.full((120, 1), 1.5))[0]
        core.receive(p.encode(p.Block(0, wire), 1), 0.0)
        core.advance_to(0.1)  # 1000 ticks: the 120 samples play, the device then idles
        assert core.counters.played_samples == 120
        played = eventually(lambda: len(data_lines(played_path)), 120)
        ticks = eventually(lambda: len(data_lines(plate_path)), core.tick)
        assert (played, ticks) == (120, 1000)
        assert data_lines(played_path)[-1] == "119,1.500000000"
    finally:
        played_csv.close()
        plate_csv.close()


def test_the_plate_log_growth_is_one_row_per_tick():
    rows, mb_hour = plate_log_growth(1, 10_000.0)
    assert rows == 10_000.0
    assert 1_200 < mb_hour < 1_500  # measured: 35-38 bytes a row, 126 MB in 6 minutes
    assert plate_log_growth(2, 10_000.0)[1] > mb_hour


def test_sim_device_says_how_fast_the_plate_log_grows_and_it_is_read_while_running(tmp_path):
    """No host: the plate log grows anyway; its rows are in the file while the device
    runs, and the device said the rate on stderr at start."""
    path = tmp_path / "plate.csv"
    proc = subprocess.Popen([sys.executable, "-m", "frictex", "sim-device", "--plate-log",
                             str(path)], stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, text=True)
    try:
        assert select.select([proc.stdout], [], [], BOUND_S)[0], "sim-device did not start"
        assert proc.stdout.readline().startswith("/")
        deadline = time.monotonic() + BOUND_S
        while (not path.exists() or len(data_lines(path)) < 100) and time.monotonic() < deadline:
            time.sleep(0.05)
        assert len(data_lines(path)) >= 100  # read while the device runs
        assert proc.poll() is None
    finally:
        os.kill(proc.pid, signal.SIGTERM)
        _, err = proc.communicate(timeout=BOUND_S)
    mb_hour = plate_log_growth(1, 10_000.0)[1]
    assert err.splitlines()[0] == (f"frictex sim-device: --plate-log {path} grows by 10,000 "
                                   f"rows a second, about {mb_hour:,.0f} MB an hour, until "
                                   "the device exits")


def test_the_plate_log_help_gives_its_growth():
    done = subprocess.run([sys.executable, "-m", "frictex", "sim-device", "--help"],
                          capture_output=True, text=True, timeout=BOUND_S)
    text = " ".join(done.stdout.split())
    mb_hour = plate_log_growth(1, 10_000.0)[1]
    assert f"10,000 rows a second, about {mb_hour:,.0f} MB an hour" in text


def _sim_device(*args: str) -> subprocess.CompletedProcess:
    """``frictex sim-device --once ARGS`` in a process of its own, waited for at most
    ``HANG_S``: a refusal must come before it serves anything."""
    return subprocess.run([sys.executable, "-m", "frictex", "sim-device", "--once", *args],
                          capture_output=True, text=True, stdin=subprocess.DEVNULL,
                          timeout=HANG_S)


@pytest.mark.parametrize("option", ["--log", "--plate-log"])
def test_a_log_fifo_with_no_reader_is_refused_not_waited_for(tmp_path, option):
    fifo = tmp_path / "log.fifo"
    os.mkfifo(fifo)
    done = _sim_device(option, str(fifo))
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"frictex: error: cannot write the log file {fifo}: a FIFO with no reader; start "
        "its reader first"]


@pytest.mark.parametrize("option", ["--log", "--plate-log"])
def test_an_empty_log_path_is_refused(option):
    done = _sim_device(option, "")
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"frictex: error: sim-device: argument {option}: an empty path; give a file to "
        "write, or leave the option out for no log"]


def test_a_log_fifo_with_a_reader_is_written_blocking(tmp_path):
    fifo = tmp_path / "log.fifo"
    os.mkfifo(fifo)
    reader = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)
    try:
        csv = CsvLog(fifo, ["index", "ch0_um"])
        try:
            assert os.get_blocking(csv._fh.fileno())  # writes wait for a slow reader
            csv.flush()
            assert select.select([reader], [], [], BOUND_S)[0]
            assert os.read(reader, 100) == b"index,ch0_um\n"
        finally:
            csv.close()
    finally:
        os.close(reader)
