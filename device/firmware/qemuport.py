"""Run the firmware's QEMU port (``mps2/``: MPS2-AN385, Cortex-M3) in
``qemu-system-arm`` with its link UART on a pty, and link to it with frictex's own host
link, as :mod:`hostport` does for the host port.

    with QemuDevice(log_path="played.bin") as dev:
        sink = CommandSink(lambda: open_port(dev.path), 1, 10_000.0, paced=True,
                           process=dev.proc)

QEMU's clock follows the instructions it executes, held to the host's (``-icount
shift=5,sleep=on,align=on``, see :data:`ICOUNT`), so the firmware's SysTick samples at
10 kHz of wall time while the host gives QEMU the CPU.
"""

from __future__ import annotations

import ctypes
import os
import re
import select
import signal
import subprocess
import tempfile
import time
from pathlib import Path

import numpy as np

from frictex.device.firmware.build import BUILD, make, require
from frictex.device.link.protocol import LinkError

QEMU = "qemu-system-arm"
#: the samples per second, channels and per-channel limit (counts) of mps2/board.h
RATE_HZ = 10_000.0
CHANNELS = 1
#: QEMU's clock: 2**5 = 32 ns of emulated time per instruction (a 25 MHz Cortex-M3 runs
#: about 31 million instructions a second); an idle guest (``wfi``) sleeps in real time
#: (``sleep=on``), and a guest whose clock ran ahead of the host's while it computed
#: waits for it (``align=on``): so the SysTick samples at 10 kHz of wall time, slower
#: only while the host starves QEMU of CPU. Measured streaming 6,000 samples here:
#: ``shift=auto`` tripped the firmware's watchdog in 2 of 3 streams (it raises the
#: shift while the guest idles, so a Block received then runs at up to 1 us per
#: instruction and the clock races ahead); without ``align=on`` the clock ran ahead of
#: the host's by the time QEMU computed faster than 31 MIPS, and blocks arrived late.
ICOUNT = "shift=5,sleep=on,align=on"
_PTY = re.compile(r"char device redirected to (/dev/\S+) \(label link\)")


def firmware() -> Path:
    """The QEMU port's ELF, built if needed (needs the Arm cross compiler)."""
    make("mps2")
    return BUILD / "mps2" / "frictex-fw-mps2.elf"


def _die_with_parent() -> None:
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def command(elf: Path, log_path: os.PathLike | None, icount: str = ICOUNT) -> list[str]:
    """The QEMU command line: UART0 (the link) on a new pty, UART1 (the played-sample
    log) into ``log_path`` (discarded when None), semihosting for the exit, QEMU's clock
    from ``icount`` (see :data:`ICOUNT`)."""
    played = f"file,id=played,path={os.fspath(log_path)}" if log_path else "null,id=played"
    return [QEMU, "-M", "mps2-an385", "-display", "none", "-monitor", "none",
            "-chardev", "pty,id=link", "-serial", "chardev:link",
            "-chardev", played, "-serial", "chardev:played",
            "-semihosting-config", "enable=on,target=native",
            "-icount", icount, "-kernel", os.fspath(elf)]


class QemuDevice:
    """The QEMU port running; ``path`` is its link's pty, ``proc`` the QEMU process.

    It exits by itself (status 0) once a host's Stop has played out; :meth:`close` ends
    it otherwise. The pty's slave is held open here, so QEMU sees its port connected from
    the start and never discards a reply while the host opens it.
    """

    def __init__(self, log_path: os.PathLike | None = None, *, elf: Path | None = None,
                 icount: str = ICOUNT, start_timeout_s: float = 30.0):
        require(QEMU)
        self._slave = None
        self.stderr = tempfile.TemporaryFile("w+")  # QEMU's complaints, for errors
        self.proc = subprocess.Popen(command(elf or firmware(), log_path, icount),
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=self.stderr, text=True,
                                     preexec_fn=_die_with_parent)
        ready, _, _ = select.select([self.proc.stdout], [], [], start_timeout_s)
        line = self.proc.stdout.readline() if ready else ""
        found = _PTY.search(line)
        if not found:
            self.close()
            self.stderr.seek(0)
            raise LinkError(f"{QEMU} did not start the firmware (printed {line.strip()!r}; "
                            f"exit code {self.proc.returncode}; {self.stderr.read()[-500:]!r})")
        self.path = found.group(1)
        self._slave = os.open(self.path, os.O_RDWR | os.O_NOCTTY)

    def wait(self, timeout_s: float) -> int:
        """QEMU's exit status once it has exited by itself (within ``timeout_s``)."""
        return self.proc.wait(timeout=timeout_s)

    def close(self) -> None:
        """End QEMU if it still runs, and release the pty."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5.0)
        if self._slave is not None:
            os.close(self._slave)
            self._slave = None
        self.proc.stdout.close()

    def __enter__(self) -> QemuDevice:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def played_log(path: os.PathLike, channels: int = CHANNELS) -> tuple[np.ndarray, np.ndarray]:
    """The played-sample log UART1 wrote: (sample numbers, setpoints in counts of
    1/4096 um, shape (n, channels)). A record is the number (u32) and a u16 per channel,
    little-endian; a partial record at the end (QEMU still writing) is left out."""
    rec = np.dtype([("index", "<u4"), ("amp", "<u2", (channels,))])
    raw = Path(path).read_bytes()
    data = np.frombuffer(raw[: len(raw) // rec.itemsize * rec.itemsize], rec)
    return data["index"].astype(np.int64), data["amp"].astype(np.int64)


def wait_for(predicate, timeout_s: float) -> bool:
    """Poll ``predicate()`` every 5 ms for at most ``timeout_s``; its last value."""
    deadline = time.monotonic() + timeout_s
    while not (ok := predicate()) and time.monotonic() < deadline:
        time.sleep(0.005)
    return ok
