"""A private JACK server for the audio tests: jackd's dummy backend (Debian's jackd2,
installed by .ci/setup-firmware) at 192 kHz with 256-frame periods, as the device
PortAudio plays into."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
from contextlib import contextmanager

import pytest

JACKD = shutil.which("jackd")
#: why an audio server test is skipped where jackd is missing
NO_JACKD = "jackd is not installed (Debian package jackd2, see .ci/setup-firmware)"
FS = 192_000
#: bound on the server's start (s)
START_S = 30.0


@contextmanager
def private_jackd(tmp_path, name: str):
    """Start jackd as the server ``name``, its log in ``tmp_path``; yields (its Popen, the
    environment that makes PortAudio and JACK's tools use it) once it answers. Ends it
    afterwards, frozen or not, with SIGTERM: a jackd killed with SIGKILL stays in JACK's
    server registry in /dev/shm, and a few such make every later jackd fail ('Too many
    servers already active')."""
    env = {**os.environ, "JACK_DEFAULT_SERVER": name, "JACK_NO_AUDIO_RESERVATION": "1"}
    with open(tmp_path / "jackd.log", "wb") as log:
        server = subprocess.Popen([JACKD, "--no-realtime", "-n", name, "-d", "dummy",
                                   "-r", str(FS), "-p", "256"], stdout=log,
                                  stderr=subprocess.STDOUT, env=env, start_new_session=True)
    try:
        up = subprocess.run(["jack_wait", "-s", name, "-w", "-t", str(int(START_S))],
                            capture_output=True, env=env, timeout=START_S + 10)
        if up.returncode != 0:
            pytest.fail(f"jackd did not come up within {START_S:g} s: "
                        f"{(tmp_path / 'jackd.log').read_text()[-800:]}")
        yield server, env
    finally:
        if server.poll() is None:
            server.send_signal(signal.SIGCONT)
            server.terminate()
            try:
                server.wait(10)
            except subprocess.TimeoutExpired:
                server.kill()
        server.wait(10)
