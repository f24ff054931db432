"""A held signal (Ctrl-C, SIGTERM: ``device.link.waits``) ends an audio output's waits at
once, and ``abort`` ramps the plate's drive to 0 before releasing the device; through
JACK's dummy backend (the fixture of tests/test_audio_jack.py)."""

from __future__ import annotations

import numpy as np
import pytest
from test_audio_jack import FS, RATE, jack_device, send_for  # noqa: F401 - the fixture

from frictex.device.audio.options import AudioArgs, make_plan
from frictex.device.audio.stream import StreamOutput
from frictex.device.link.waits import interruptible


def test_a_held_signal_ends_a_paced_wait_and_abort_ramps_to_zero(jack_device):
    plan = make_plan(AudioArgs(), 1, RATE)
    out = StreamOutput(plan, str(jack_device), blocksize=256, buffer_frames=FS // 10,
                       phases=False, paced=True, wait_s=10.0, tap_frames=4 * FS)
    held = []

    def check():  # what the run's check does once a signal is held
        if held:
            raise KeyboardInterrupt

    with interruptible(check):
        index = send_for(out, 1.0, 0)  # the ring full: each send waits for room
        held.append("SIGINT")
        with pytest.raises(KeyboardInterrupt):
            send_for(out, 1.0, index)
    out.abort()
    p, audio = out.player, out.status()["audio"]
    assert out.closed and p.stopped > 0  # the queued frames were dropped, not played out
    assert p.silent  # the ramp to 0 played before the device was let go
    assert audio["commanded_frames"] == p.played + sum(audio["unplayed_frames"].values())
    tap = p.tap[:p.tap_len, 0]
    loud = np.flatnonzero(np.abs(tap) > 0.01)
    last = loud[-1]
    assert np.abs(tap[last - 2000:last]).max() > 0.45  # it was playing at 0.5 full scale
    assert np.abs(tap[last + 1:]).max(initial=0.0) < 0.01  # and then silence
    slope = 0.5 * 2 * np.pi * plan.carrier_hz / FS  # the carrier's own largest step
    assert np.abs(np.diff(tap[last - 2 * plan.ramp_frames:])).max() <= slope * 1.01


def test_an_abort_before_the_stream_started_plays_nothing(jack_device):
    plan = make_plan(AudioArgs(), 1, RATE)
    out = StreamOutput(plan, str(jack_device), blocksize=256, buffer_frames=FS // 10,
                       phases=False, paced=True, wait_s=10.0, tap_frames=FS)
    send_for(out, 0.02, 0)  # less than half the ring: a paced stream has not started yet
    out.abort()
    p, audio = out.player, out.status()["audio"]
    assert out.closed and p.played == 0 and p.tap_len == 0
    assert audio["commanded_frames"] == p.stopped > 0  # every frame counted, as stopped
