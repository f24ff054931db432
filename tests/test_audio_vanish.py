"""An audio device that goes away or freezes mid-replay, or is frozen when the replay
opens it, ends the run, within a bound, with exit 1 and one line (``device.audio.stream``,
``device.audio.bounded``).

The device is JACK's dummy backend in a private jackd (Debian's jackd2, installed by
.ci/setup-firmware), which the test ends with SIGTERM (the server gone: PortAudio's stop
and close then block for 10 minutes) or stops with SIGSTOP (the device frozen) while
``frictex replay --device audio`` plays into it, in a process of its own."""

from __future__ import annotations

import os
import signal
import subprocess
import sys
import time

import pytest
from jack_server import JACKD, NO_JACKD, START_S, private_jackd

pytestmark = pytest.mark.skipif(JACKD is None, reason=NO_JACKD)
#: generous bound on the run once its device is gone: the producer's 5 s wait plus the
#: 3 s bound on PortAudio's stop, on a busy machine (it hung for 10 minutes before)
END_S = 60.0


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
    with private_jackd(tmp_path, f"frictex-vanish-{os.getpid()}") as (server, env):
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
    with private_jackd(tmp_path, f"frictex-vanish-{os.getpid()}") as (server, env):
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
    with private_jackd(tmp_path, f"frictex-vanish-{os.getpid()}") as (server, env):
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


def test_a_replay_opening_a_frozen_audio_server_ends_with_one_line(tmp_path):
    """The server stopped (SIGSTOP) before the replay starts: PortAudio's initialisation
    waits for its answer without a bound (it hung with no output before)."""
    with private_jackd(tmp_path, f"frictex-vanish-{os.getpid()}") as (server, env):
        server.send_signal(signal.SIGSTOP)
        code, _, err = finish(start_replay(tmp_path, env))
    assert code == 1, err
    assert err.count("\n") == 1 and err.startswith(
        "frictex: error: audio: the audio server is not answering: PortAudio's initialisation")
    assert not (tmp_path / "out").exists()
