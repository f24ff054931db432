"""Run the firmware's QEMU port (``sf2/``: Emcraft's SmartFusion2 SOM, a Cortex-M3) in
``qemu-system-arm`` with its link UART on a pty, and link to it with frictex's own host
link, as :mod:`hostport` does for the host port.

    with QemuDevice(log_path="played.bin") as dev:
        sink = CommandSink(lambda: open_port(dev.path), 1, 10_000.0, paced=True,
                           process=dev.proc)

QEMU's clock is the host's (no ``-icount``): the firmware's sample interrupt comes late
while the host runs something else, and it plays the ticks its free-running counter says
it missed, so it samples at 10 kHz of wall time while QEMU gets the CPU it needs.
"""

from __future__ import annotations

import ctypes
import os
import re
import select
import shutil
import signal
import subprocess
import tempfile
import threading
import time
from pathlib import Path

import numpy as np

from frictex.device.firmware.build import BUILD, make, require
from frictex.device.link.protocol import LinkError

QEMU = "qemu-system-arm"
BOARD = "emcraft-sf2"
#: the samples per second, channels and per-channel limit (counts) of sf2/board.h
RATE_HZ = 10_000.0
CHANNELS = 1
# QEMU's clock is the host's. Held to instruction counts instead (``-icount
# shift=5,sleep=on,align=on``: 32 ns per instruction, sleeping in real time while the
# guest idles) this port did not answer a handshake within 10 s, and an LM3S6965 port
# tried before it played about 5,400 samples a second, not 10,000, on an idle machine.
_PTY = re.compile(r"char device redirected to (/dev/\S+) \(label link\)")


def firmware() -> Path:
    """The QEMU port's ELF, built if needed (needs the Arm cross compiler)."""
    make("sf2")
    return BUILD / "sf2" / "frictex-fw-sf2.elf"


def _die_with_parent() -> None:
    ctypes.CDLL(None, use_errno=True).prctl(1, signal.SIGTERM)  # PR_SET_PDEATHSIG


def command(elf: Path) -> list[str]:
    """The QEMU command line: UART0 (the link) on a new pty; semihosting for the
    played-sample log (``played.bin`` in QEMU's working folder) and for the exit; QEMU's
    clock the host's (module docstring)."""
    return [QEMU, "-M", BOARD, "-display", "none", "-monitor", "none",
            "-chardev", "pty,id=link", "-serial", "chardev:link",
            "-semihosting-config", "enable=on,target=native",
            "-kernel", os.fspath(elf)]


class QemuDevice:
    """The QEMU port running; ``path`` is its link's pty, ``proc`` the QEMU process.

    The played-sample log the firmware writes (:func:`played_log`'s records) goes to
    ``log_path`` (None: nowhere) and, as it arrives, to ``on_log(chunk, t)`` (``t``:
    ``time.perf_counter()`` at its arrival), from a thread that reads QEMU's output.
    It exits by itself (status 0) once a host's Stop has played out; :meth:`close` ends
    it otherwise. The pty's slave is held open here, so QEMU sees its port connected from
    the start and never discards a reply while the host opens it.
    """

    def __init__(self, log_path: os.PathLike | None = None, *, elf: Path | None = None,
                 on_log=None, start_timeout_s: float = 30.0):
        require(QEMU)
        self._slave = self._reader = None
        self._log = open(log_path, "wb") if log_path is not None else None
        self._on_log = on_log
        self.stderr = tempfile.TemporaryFile("w+b")  # QEMU's messages, for errors
        self._folder = tempfile.TemporaryDirectory(prefix="frictex-qemu-")
        fifo = os.path.join(self._folder.name, "played.bin")  # sf2/board.h BOARD_PLAYED_LOG
        os.mkfifo(fifo)
        self._fifo = os.open(fifo, os.O_RDONLY | os.O_NONBLOCK)  # so QEMU's open returns
        self.proc = subprocess.Popen(command(elf or firmware()), cwd=self._folder.name,
                                     stdin=subprocess.DEVNULL, stdout=subprocess.PIPE,
                                     stderr=self.stderr, preexec_fn=_die_with_parent)
        ready, _, _ = select.select([self.proc.stdout], [], [], start_timeout_s)
        line = self.proc.stdout.readline().decode("ascii", "replace") if ready else ""
        found = _PTY.search(line)
        if not found:
            self.close()
            self.stderr.seek(0)
            raise LinkError(f"{QEMU} did not start the firmware (printed {line.strip()!r}; "
                            f"exit code {self.proc.returncode}; "
                            f"{self.stderr.read()[-500:].decode(errors='replace')!r})")
        self.path = found.group(1)
        self._slave = os.open(self.path, os.O_RDWR | os.O_NOCTTY)
        self._reader = threading.Thread(target=self._read_log, name="frictex-qemu-log",
                                        daemon=True)
        self._reader.start()
        # what QEMU prints later must not fill the pipe
        threading.Thread(target=shutil.copyfileobj, args=(self.proc.stdout, self.stderr),
                         name="frictex-qemu-out", daemon=True).start()

    def _read_log(self) -> None:
        while True:
            select.select([self._fifo], [], [], 1.0)
            try:
                chunk = os.read(self._fifo, 1 << 16)
            except BlockingIOError:  # no writer yet, or nothing written
                continue
            if not chunk:  # QEMU closed it: exited
                if self.proc.poll() is not None:
                    return
                time.sleep(0.01)  # not opened yet
                continue
            t = time.perf_counter()
            if self._log is not None:
                self._log.write(chunk)
                self._log.flush()
            if self._on_log is not None:
                self._on_log(chunk, t)

    def wait(self, timeout_s: float) -> int:
        """QEMU's exit status once it has exited by itself (within ``timeout_s``), its
        log complete."""
        code = self.proc.wait(timeout=timeout_s)
        self._reader.join(timeout=timeout_s)
        return code

    def close(self) -> None:
        """End QEMU if it still runs, and release the pty and the log."""
        if self.proc.poll() is None:
            self.proc.terminate()
            try:
                self.proc.wait(timeout=5.0)
            except subprocess.TimeoutExpired:
                self.proc.kill()
                self.proc.wait(timeout=5.0)
        if self._reader is not None:
            self._reader.join(timeout=5.0)
        if self._slave is not None:
            os.close(self._slave)
            self._slave = None
        os.close(self._fifo)
        self._folder.cleanup()
        if self._log is not None:
            self._log.close()

    def __enter__(self) -> QemuDevice:
        return self

    def __exit__(self, *exc) -> None:
        self.close()


def played_log(path: os.PathLike, channels: int = CHANNELS) -> tuple[np.ndarray, np.ndarray]:
    """The played-sample log the firmware wrote: (sample numbers, setpoints in counts of
    1/4096 um, shape (n, channels)). A record is the number (u32) and a u16 per channel,
    little-endian; a partial record at the end (QEMU still writing) is left out."""
    return records(Path(path).read_bytes(), channels)


def records(raw: bytes, channels: int = CHANNELS) -> tuple[np.ndarray, np.ndarray]:
    """:func:`played_log` of bytes ``raw``."""
    rec = np.dtype([("index", "<u4"), ("amp", "<u2", (channels,))])
    data = np.frombuffer(raw[: len(raw) // rec.itemsize * rec.itemsize], rec)
    return data["index"].astype(np.int64), data["amp"].astype(np.int64)

