"""frictex sim-device on Ctrl-C: the port closed and the counts printed, then the line
every command prints, ``frictex: interrupted``, exit 130."""

import signal
import subprocess
import sys

#: longest the device is waited for at each stage (s): a hang, not a busy machine
HANG_S = 120.0


def test_ctrl_c_says_interrupted_and_exits_130():
    proc = subprocess.Popen([sys.executable, "-m", "frictex", "sim-device", "--tcp", "0"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                            stdin=subprocess.DEVNULL, text=True)
    try:
        where = proc.stdout.readline().strip()  # the readiness line: where a host connects
        assert where.startswith("socket://"), where
        proc.send_signal(signal.SIGINT)
        _, err = proc.communicate(timeout=HANG_S)
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait()
    assert proc.returncode == 130, err
    lines = err.strip().splitlines()
    assert lines[-1] == "frictex: interrupted", err
    assert lines[-2].startswith("frictex sim-device: played 0 samples"), err
    assert "Traceback" not in err
