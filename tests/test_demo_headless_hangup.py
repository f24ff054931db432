"""A terminal's SIGHUP to the headless demo's process group (the demo, its haptic
process, ``multiprocessing``'s resource tracker) ends it with its one line: the resource
tracker, started with SIGHUP ignored, lives on to clean up the queues' semaphores
(it died with the group and its replacement printed a warning and 17 KeyErrors).
Each step waits for the demo to confirm it, within generous bounds."""

import os
import signal
import subprocess
import sys
import time

from conftest import signals_as_a_terminal_gives

BOUND_S = 120


def wait_first_frame(proc, out, err) -> None:
    """Wait until the demo's staging folder beside ``out`` says its first frame was drawn."""
    deadline = time.monotonic() + BOUND_S
    while True:
        assert proc.poll() is None, err.read_text()
        assert time.monotonic() < deadline, "no first frame"
        for folder in out.parent.glob(f".{out.name}.frictex-*"):
            events = folder / "events.csv"
            if events.exists() and ",first-frame," in events.read_text():
                return
        time.sleep(0.02)


def test_a_hangup_to_the_headless_demos_group_is_its_one_line(tmp_path):
    out, err = tmp_path / "out", tmp_path / "stderr.txt"
    with open(err, "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-m", "frictex", "demo", "grating-5mm", "--headless",
             "--duration", "300", "--device", "sim", "--out", str(out)],
            stdout=subprocess.DEVNULL, stderr=fh, start_new_session=True,
            preexec_fn=signals_as_a_terminal_gives)
    try:
        wait_first_frame(proc, out, err)
        os.killpg(proc.pid, signal.SIGHUP)
        assert proc.wait(timeout=BOUND_S) == 128 + signal.SIGHUP
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    deadline = time.monotonic() + BOUND_S  # the tracker writes after the demo has ended
    while subprocess.run(["pgrep", "-g", str(proc.pid)], capture_output=True).returncode == 0:
        assert time.monotonic() < deadline, "the process group did not end"
        time.sleep(0.05)
    # the device's verdict may come first on a loaded machine (more than half the samples
    # skipped to catch up, say): its own line, no part of this test
    said = [line for line in err.read_text().strip().splitlines()
            if not line.startswith("frictex demo: error: ")]
    # the headless demo's tables are its recording (--out): said being written, then the signal
    assert said == ["frictex demo: stopping the plate and writing the recording (another "
                    "signal ends the demo at once, without it)", "frictex: terminated by SIGHUP"]
