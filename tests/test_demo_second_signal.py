"""Ctrl-C twice in the demo: the first ends it as Q does and says the recording is being
written; a second while that runs ends it at once, and says the recording was not
written (it went without a word: the same exit 130 and 'frictex: interrupted' as one
Ctrl-C that wrote it). Whichever the second signal meets, the recording is never lost
without a line saying so. Each step waits for the demo to confirm it."""

import os
import signal
import subprocess
import sys
import time

from conftest import signals_as_a_terminal_gives
from test_demo_headless_hangup import BOUND_S, wait_first_frame

WRITING = "frictex demo: stopping the plate and writing the recording"
NOT_WRITTEN = "frictex demo: a second signal: the recording in"


def test_a_second_ctrl_c_says_the_recording_was_not_written(tmp_path):
    out, rec, err = tmp_path / "out", tmp_path / "rec", tmp_path / "stderr.txt"
    with open(err, "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-m", "frictex", "demo", "grating-5mm", "--headless",
             "--duration", "300", "--device", "sim", "--out", str(out), "--record", str(rec)],
            stdout=subprocess.DEVNULL, stderr=fh, start_new_session=True,
            preexec_fn=signals_as_a_terminal_gives)
    try:
        wait_first_frame(proc, rec, err)
        proc.send_signal(signal.SIGINT)
        deadline = time.monotonic() + BOUND_S
        while WRITING not in err.read_text():
            assert proc.poll() is None and time.monotonic() < deadline, err.read_text()
            time.sleep(0.005)
        proc.send_signal(signal.SIGINT)
        assert proc.wait(timeout=BOUND_S) == 130
    finally:
        if proc.poll() is None:
            os.killpg(proc.pid, signal.SIGKILL)
            proc.wait()
    said = err.read_text()
    assert said.count(WRITING) == 1 and "Traceback" not in said
    if (rec / "summary.json").exists():  # the second signal came once it was written
        assert NOT_WRITTEN not in said
    else:
        assert f"{NOT_WRITTEN} {rec} was not written (nothing was written)" in said
