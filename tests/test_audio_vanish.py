"""An audio device that goes away or freezes mid-replay ends the run, within a bound, with
exit 1 and one line (``device.audio.stream``, ``device.audio.bounded``).

The device is JACK's dummy backend in a private jackd (Debian's jackd2, installed by
.ci/setup-firmware), which the test ends with SIGTERM (the server gone: PortAudio's stop
and close then block for 10 minutes) or stops with SIGSTOP (the device frozen) while
``frictex replay --device audio`` plays into it, in a process of its own."""

from __future__ import annotations

import os
import shutil
import signal
import subprocess
import sys
import time
from contextlib import contextmanager

import pytest

JACKD = shutil.which("jackd")
pytestmark = pytest.mark.skipif(
    JACKD is None, reason="jackd is not installed (Debian package jackd2, see .ci/setup-firmware)")
START_S = 30.0  # bound on the server's start and on the replay's stream opening
#: generous bound on the run once its device is gone: the producer's 5 s wait plus the
#: 3 s bound on PortAudio's stop, on a busy machine (it hung for 10 minutes before)
END_S = 60.0


@contextmanager
def dummy_jack(tmp_path):
    """A private jackd (dummy backend, 192 kHz, 256 frames); yields (Popen, the
    environment that makes PortAudio use it). Ends it afterwards, frozen or not, with
    SIGTERM: a jackd killed with SIGKILL stays in JACK's server registry in /dev/shm, and
    a few such make every later jackd fail ('Too many servers already active')."""
    name = f"frictex-vanish-{os.getpid()}"
    env = {**os.environ, "JACK_DEFAULT_SERVER": name, "JACK_NO_AUDIO_RESERVATION": "1"}
    with open(tmp_path / "jackd.log", "wb") as log:
        server = subprocess.Popen([JACKD, "--no-realtime", "-n", name, "-d", "dummy",
                                   "-r", "192000", "-p", "256"], stdout=log,
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


def start_replay(tmp_path, env) -> subprocess.Popen:
    """``frictex replay`` of a 5 s trace into the default audio device (JACK's)."""
    return subprocess.Popen([sys.executable, "-m", "frictex", "replay", "grating-15mm",
                             "back-and-forth-60mms-50hz", "--out", str(tmp_path / "out"),
                             "--device", "audio", "--quiet"],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True, env=env)


def wait_until_playing(replay: subprocess.Popen, env) -> None:
    """Until the replay's PortAudio client has its output port on the server."""
    deadline = time.monotonic() + START_S
    while time.monotonic() < deadline and replay.poll() is None:
        ports = subprocess.run(["jack_lsp", "-s", env["JACK_DEFAULT_SERVER"]],
                               capture_output=True, text=True, env=env, timeout=10).stdout
        if "PortAudio:" in ports:
            time.sleep(0.5)  # well into the stream
            return
        time.sleep(0.1)
    pytest.fail(f"the replay's stream did not open within {START_S:g} s (exit "
                f"{replay.poll()}): {replay.stderr.read() if replay.poll() is not None else ''}")


def finish(replay: subprocess.Popen) -> tuple[int, float, str]:
    """Exit status, seconds waited (bounded by END_S, then killed: a failure) and stderr."""
    t0 = time.monotonic()
    try:
        _, err = replay.communicate(timeout=END_S)
    except subprocess.TimeoutExpired:
        replay.kill()
        replay.communicate(timeout=10)
        pytest.fail(f"the replay was still running {END_S:g} s after its device went away")
    return replay.returncode, time.monotonic() - t0, err


def test_a_jack_server_killed_mid_replay_ends_the_run_with_one_line(tmp_path):
    with dummy_jack(tmp_path) as (server, env):
        replay = start_replay(tmp_path, env)
        wait_until_playing(replay, env)
        server.terminate()  # as `kill` does; the server shuts down and is gone
        server.wait(10)
        code, _, err = finish(replay)
    assert code == 1, err
    assert err.count("\n") == 1 and err.startswith("frictex: error: audio: the audio device ")
    assert "went away" in err
    assert not (tmp_path / "out").exists()  # an aborted run leaves no outputs


def test_a_frozen_audio_device_ends_the_run_with_one_line(tmp_path):
    """The server stopped (SIGSTOP): the stream takes no frames, and PortAudio's stop
    does not return."""
    with dummy_jack(tmp_path) as (server, env):
        replay = start_replay(tmp_path, env)
        wait_until_playing(replay, env)
        server.send_signal(signal.SIGSTOP)
        code, _, err = finish(replay)
    assert code == 1, err
    assert err.count("\n") == 1 and "the audio device took no frames for 5 s" in err
    assert err.rstrip().endswith("did not return within 3 s, so the stream was abandoned")


def test_sigterm_ends_a_run_whose_audio_device_froze(tmp_path):
    """Two SIGTERMs (the first is held until the step ends; the second raises) while the
    producer waits for a frozen device: the run still ends within the bound, and says
    what became of the device (its stream left to PortAudio) rather than only that it
    was terminated."""
    with dummy_jack(tmp_path) as (server, env):
        replay = start_replay(tmp_path, env)
        wait_until_playing(replay, env)
        server.send_signal(signal.SIGSTOP)
        time.sleep(0.5)
        replay.send_signal(signal.SIGTERM)
        time.sleep(0.2)  # two signals pending at once would be one
        replay.send_signal(signal.SIGTERM)
        code, _, err = finish(replay)
    assert code == 1, err
    assert err.count("\n") == 1 and err.startswith("frictex: error: audio: the audio device ")
    assert err.rstrip().endswith("so the stream was abandoned")
