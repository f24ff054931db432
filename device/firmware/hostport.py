"""Start the firmware's host port (``frictex-fw-host``) the way ``frictex sim-device`` is
started, and link to it with frictex's own host link.

    proc, path = start(channels=1, rate_hz=10_000.0, extra=("--log", "played.csv"))
    sink = CommandSink(lambda: open_port(path), 1, 10_000.0, paced=True, process=proc)
"""

from __future__ import annotations

import os
import select
import subprocess
import time

from frictex.device.firmware.build import host_port
from frictex.device.link.protocol import LinkError

#: longest a port that neither prints nor exits is waited for (s): a hang, not a busy
#: machine (it prints its pty path as it starts, in milliseconds when idle)
HANG_S = 120.0


def start(channels: int = 1, rate_hz: float = 10_000.0, *, binary=None,
          extra: tuple[str, ...] = ()) -> tuple[subprocess.Popen, str]:
    """Start the host port on a new pty with ``--once`` (it exits when the host's Stop has
    played out, as ``start_sim_device`` does); returns (process, pty path).

    ``binary``: another build of it (the sanitizer build); default: built if needed.
    ``extra``: more flags (the same as ``frictex sim-device``'s, plus ``--rx-log``).
    """
    exe = os.fspath(binary or host_port())
    cmd = [exe, "--once", "--channels", str(channels), "--rate", repr(float(rate_hz)),
           "--parent-pid", str(os.getpid()), *extra]
    proc = subprocess.Popen(cmd, stdout=subprocess.PIPE, stdin=subprocess.DEVNULL,
                            stderr=subprocess.PIPE, text=True)
    line = _first_line(proc)
    if not line.startswith("/"):
        proc.kill()
        _, err = proc.communicate()
        raise LinkError(f"the firmware host port did not start (printed {line!r}; exit code "
                        f"{proc.returncode}; stderr {err.strip()!r})")
    return proc, line


def _first_line(proc: subprocess.Popen) -> str:
    """The process's first line: waited for as long as it runs (a busy machine only
    delays it), at most :data:`HANG_S`; "" if it exits or hangs first."""
    deadline = time.monotonic() + HANG_S
    while time.monotonic() < deadline:
        ready, _, _ = select.select([proc.stdout], [], [], 0.5)
        if ready:
            return proc.stdout.readline().strip()
        if proc.poll() is not None:
            return ""
    return ""
