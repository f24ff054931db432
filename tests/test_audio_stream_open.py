"""``device.audio.stream`` without a sound card: PortAudio's initialisation and open,
bounded where the audio server does not answer; the device a number names; the ramp
written in place of a dropped block; the fade published with each part of a block longer
than the ring; a live ring that takes the blocks whatever ``buffer_ms``.
python-sounddevice is stood in for (``fake_sd``), and a hanging import by a module of that
name in a process of its own."""

from __future__ import annotations

import math
import os
import subprocess
import sys
import threading
import types

import numpy as np
import pytest

from frictex.device.audio import stream
from frictex.device.audio.options import AudioArgs, make_plan
from frictex.device.audio.stream import StreamOutput
from frictex.device.errors import DeviceError, InputError

RATE = 10_000.0
#: PortAudio's devices in the stand-in: an input only, then an output
DEVICES = [{"index": 0, "name": "mic", "max_output_channels": 0},
           {"index": 1, "name": "card", "max_output_channels": 2}]
#: bound on the command whose PortAudio does not answer (s): 3 s, on a busy machine
END_S = 60.0


class FakeStream:
    """A PortAudio output stream that opens and never calls back."""
    latency = 0.005
    active = True

    def __init__(self, **kwargs):
        self.kwargs = kwargs
        self.blocksize = kwargs["blocksize"]

    def start(self):
        pass

    def stop(self):
        pass

    def close(self):
        pass


@pytest.fixture
def fake_sd(monkeypatch):
    """python-sounddevice stood in for in ``device.audio.stream``."""
    sd = types.SimpleNamespace(PortAudioError=type("PortAudioError", (Exception,), {}),
                               OutputStream=FakeStream, query_devices=lambda: DEVICES)
    monkeypatch.setattr(stream, "import_sounddevice", lambda label="audio": sd)
    return sd


def open_output(device: str | None, *, paced: bool = True, blocksize: int = 256,
                buffer_frames: int = 0) -> StreamOutput:
    return StreamOutput(make_plan(AudioArgs(), 1, RATE), device, blocksize=blocksize,
                        buffer_frames=buffer_frames, phases=False, paced=paced, wait_s=5.0)


# ----------------------------------------------------------------- a server that does not answer
HANGING_IMPORT = """
import atexit, os, threading
def _exit_handler():  # sounddevice's: PortAudio's end, which would wait for the server too
    print("exit handler ran")
atexit.register(_exit_handler)
os.dup2(os.open(os.devnull, os.O_WRONLY), 2)  # as sounddevice does while PortAudio initialises
threading.Event().wait()  # Pa_Initialize waiting for a stopped jackd
"""


def test_an_initialisation_that_does_not_return_ends_the_run_with_one_line(tmp_path):
    (tmp_path / "sounddevice.py").write_text(HANGING_IMPORT)
    replay = subprocess.Popen(
        [sys.executable, "-m", "frictex", "replay", "grating-15mm",
         "back-and-forth-60mms-50hz", "--device", "audio", "--quiet",
         "--out", str(tmp_path / "out")],
        stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
        env={**os.environ, "PYTHONPATH": str(tmp_path)})
    try:
        out, err = replay.communicate(timeout=END_S)
    except subprocess.TimeoutExpired:
        replay.kill()
        replay.communicate(timeout=10)
        pytest.fail(f"the replay was still running after {END_S:g} s")
    assert replay.returncode == 1, err
    assert err.count("\n") == 1
    assert err.startswith("frictex: error: audio: the audio server is not answering: "
                          "PortAudio's initialisation (which connects to the JACK server) "
                          "did not return within 3 s")
    assert "exit handler ran" not in out  # unregistered: the process could end
    assert not (tmp_path / "out").exists()


def test_an_open_that_does_not_return_is_abandoned(fake_sd, monkeypatch):
    release = threading.Event()
    abandoned = []
    fake_sd.OutputStream = lambda **kwargs: release.wait(END_S)  # bounded too
    monkeypatch.setattr(stream, "PA_CALL_LIMIT_S", 0.2)
    monkeypatch.setattr(stream, "abandon_portaudio", abandoned.append)
    try:
        with pytest.raises(DeviceError, match=r"^audio:1: the audio server is not answering: "
                           r"PortAudio's open of the stream .* within 0\.2 s"):
            open_output("1")
    finally:
        release.set()  # let the abandoned thread end
    assert abandoned == [fake_sd]  # its exit handler would wait for the server again


# ----------------------------------------------------------------- the device a number names
@pytest.mark.parametrize("device", ["0", "7"])
def test_a_number_that_is_no_output_device_is_bad_input(fake_sd, device):
    with pytest.raises(InputError, match=rf"^audio device '{device}': No output device "
                       rf"number {device}; output devices: 1: card \(2 ch\)$"):
        open_output(device)


def test_a_digit_int_cannot_read_is_a_name(fake_sd):
    """'²' is a digit to str.isdigit, not to int(): handed to PortAudio as a name (one
    line if none matches), not read as a number (a traceback)."""
    assert open_output("²").stream.kwargs["device"] == "²"


def test_a_number_that_is_an_output_device_opens_it(fake_sd):
    assert open_output("1").stream.kwargs["device"] == 1


# ----------------------------------------------------------------- a dropped block
def test_the_ramp_after_a_dropped_block_continues_the_last_frame_written(fake_sd):
    """A live stream whose device takes no frames: blocks of 25 commands at 2 um fill the
    ring, and the first that does not fit is dropped and the ramp to 0 written instead.
    The ramp's frames are the carrier going on from the last frame written, frame by
    frame, at its level times (1 - k/ramp), k = 1, 2, ..."""
    out = open_output(None, paced=False)
    plan, ring = out.plan, out.ring
    start = 0
    while out.ring_full == 0:
        written = ring.tail
        out.send(start, np.full((25, 1), 2.0))
        start += 25
    assert out.ring_full == 480  # the dropped block's frames
    assert ring.tail == written + plan.ramp_frames

    def carrier(n: int) -> float:  # frame n, at 2 um on the default profile's full scale
        level = 2.0 / plan.um_per_volt / plan.full_scale_v
        return level * math.cos(2 * math.pi * math.fmod(n * plan.carrier_hz / plan.audio_rate, 1.0))

    # no frame has played: ring position n is frame n
    assert float(ring.frames[written - 1, 0]) == pytest.approx(carrier(written - 1), abs=1e-6)
    ramp = ring.frames[written:written + 8, 0].astype(np.float64)
    expected = [carrier(written + k) * (1 - (k + 1) / plan.ramp_frames) for k in range(8)]
    np.testing.assert_allclose(ramp, expected, rtol=0, atol=1e-6)


def test_the_fade_after_a_block_within_the_ramp_in_starts_from_its_ramped_level(fake_sd):
    """After a dropped block the next block ramps in from 0 over ramp_frames (384); one of
    5 commands (96 frames) ends a quarter of the way up. The fade published with it, which
    a callback running dry plays next, started from the synthesis's full level: a step up
    from 0.25 to 1 of the level, then the fall. It starts where the ramp in was going."""
    out = open_output(None, paced=False)
    plan, ring = out.plan, out.ring
    start = 0
    while out.ring_full == 0:
        out.send(start, np.full((25, 1), 2.0))
        start += 25
    drained = np.zeros((ring.tail - ring.head, 1), dtype=np.float32)
    out.player.fill(drained)  # the device plays all it was given, the ramp to 0 last
    assert drained[-1, 0] == pytest.approx(0.0, abs=1e-3)
    out.send(start, np.full((5, 1), 2.0))
    assert out.ring_full == 480 and ring.tail - ring.head == 96
    played = np.zeros((96 + plan.ramp_frames + 16, 1), dtype=np.float32)
    out.player.fill(played)  # the callback runs dry after the short block
    frames = played[:, 0].astype(np.float64)
    level = 2.0 / plan.um_per_volt / plan.full_scale_v
    carrier_step = 2 * level * math.sin(math.pi * plan.carrier_hz / plan.audio_rate)
    steps = np.abs(np.diff(frames[:96 + plan.ramp_frames + 1]))
    assert np.max(np.abs(frames[96:106])) < 0.3 * level  # the ramped level: 97/384 of it
    assert np.max(steps) <= 1.05 * carrier_step + level / plan.ramp_frames
    assert np.all(frames[96 + plan.ramp_frames:] == 0.0)


# ----------------------------------------------------------------- a block longer than the ring
class RanDry(Exception):
    """Ends a ``send`` once the callback has played the ring out."""


@pytest.mark.parametrize("blocksize, buffer_frames, amplitudes_um", [
    (256, 0, np.linspace(0.0, 3.0, 3000)),  # parts of 1024 frames, a ramp up to 3 um
    (1, 192, np.full(100, 2.0)),  # parts of 192 frames, within the stream's start ramp
])
def test_the_fade_after_each_part_of_a_long_block_starts_from_that_part(
        fake_sd, monkeypatch, blocksize, buffer_frames, amplitudes_um):
    """Paced, a block longer than the ring goes in parts. The producer waits for room after
    the first part, and the callback plays the ring out meanwhile and runs dry: the fade
    it plays continues the part's last frames (level and carrier), no step. (The fade
    after the whole block, 3 um or full scale, followed 0.02 full scale: a step of 1.6 full
    scale, 150 V.)"""
    out = open_output(None, blocksize=blocksize, buffer_frames=buffer_frames)
    plan, played = out.plan, []

    def callback_runs_dry() -> None:
        queued = out.ring.tail - out.ring.head
        buffer = np.zeros((queued + plan.ramp_frames + 16, 1), dtype=np.float32)
        out.player.fill(buffer)
        played.append((queued, buffer[:, 0].astype(np.float64)))
        raise RanDry

    monkeypatch.setattr(stream, "check_interrupt", callback_runs_dry)
    with pytest.raises(RanDry):
        out.send(0, amplitudes_um[:, None])
    [(part, frames)] = played
    assert part == out.ring.capacity - plan.ramp_frames
    assert out.player.underruns == 1
    # the part's last carrier peaks (the samples' peak: within 5 % of the level's)
    level = float(np.max(np.abs(frames[part - 40:part])))
    carrier_step = 2 * level * math.sin(math.pi * plan.carrier_hz / plan.audio_rate)
    assert 0 < level < 0.6
    steps = np.abs(np.diff(frames[part - 40:]))  # into the fade, through it, then zeros
    assert np.max(steps) <= 1.05 * carrier_step + level / plan.ramp_frames
    assert np.all(frames[part + plan.ramp_frames:] == 0.0)


# ----------------------------------------------------------------- a live ring
def test_a_live_ring_takes_two_blocks_whatever_the_buffer(fake_sd):
    """buffer_ms=1 and blocksize=1 (192 frames and 1 at 192 kHz; 192 usable beside the
    384-frame ramp) against the live demo's 2.5 ms blocks, 480 frames: the ring takes two
    of them, though the callback has played none (it dropped every block, silent)."""
    out = open_output(None, paced=False, blocksize=1, buffer_frames=192)
    for start in (0, 25):
        out.send(start, np.full((25, 1), 2.0))
    assert out.ring_full == 0
    assert out.ring.tail == 2 * 480
    assert out.ring.capacity == 2 * 480 + out.plan.ramp_frames
