"""A started stream that PortAudio reports no longer active (its JACK server gone) is let
go without a stop or close: they wait 10 minutes for the server, or, in Debian's
PortAudio, a close asserts that the stream's ports were unregistered from the server
that has gone and aborts the process (a CI run: exit -6 instead of the one line)."""

from __future__ import annotations

import pytest
from test_audio_jack import FS, RATE, jack_device, send_for  # noqa: F401 - the fixture

from frictex.device.audio.options import AudioArgs, make_plan
from frictex.device.audio.stream import StreamOutput
from frictex.device.errors import DeviceError


class GoneStream:
    """What PortAudio's stream looks like once its server has gone: not active; a stop
    or close is recorded (the real ones would block or abort)."""

    active = False

    def __init__(self, calls: list):
        self.calls = calls

    def stop(self):
        self.calls.append("stop")

    def close(self):
        self.calls.append("close")


def test_a_stream_whose_server_went_away_is_abandoned_without_a_stop_or_close(jack_device):
    plan = make_plan(AudioArgs(), 1, RATE)
    out = StreamOutput(plan, str(jack_device), blocksize=256, buffer_frames=FS // 10,
                       phases=False, paced=True, wait_s=10.0)
    send_for(out, 0.5, 0)  # past half the ring: started
    real, calls = out.stream, []
    out.stream = GoneStream(calls)
    try:
        with pytest.raises(DeviceError, match=r"^audio:.*; PortAudio reports the stream no "
                                              r"longer active, so it was abandoned without a "
                                              r"stop or close$"):
            out.close()
    finally:
        real.stop()
        real.close()
    assert calls == [] and out.player.estop  # should its callback run again: a ramp to 0


def test_a_stream_gone_while_sending_says_why_once(jack_device):
    plan = make_plan(AudioArgs(), 1, RATE)
    out = StreamOutput(plan, str(jack_device), blocksize=256, buffer_frames=FS // 10,
                       phases=False, paced=True, wait_s=10.0)
    start = send_for(out, 0.5, 0)  # past half the ring: started
    real, calls = out.stream, []
    out.stream = GoneStream(calls)
    try:
        with pytest.raises(DeviceError) as gone:
            send_for(out, 1.0, start)  # more than the ring holds: it waits for room
    finally:
        real.stop()
        real.close()
    said = str(gone.value)
    assert said.endswith(": the audio device went away; PortAudio reports the stream no "
                         "longer active, so it was abandoned without a stop or close"), said
    assert said.count("no longer active") == 1 and calls == []
