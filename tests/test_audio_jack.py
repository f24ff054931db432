"""The audio output through a real audio server: JACK's dummy backend (Debian's jackd2,
installed by .ci/setup-firmware) at 192 kHz, 256-frame periods, as the device PortAudio
plays into. The output is read back from the callback's own buffer (``Player.tap``)."""

from __future__ import annotations

import os
import time

import numpy as np
import pytest

from frictex.device.audio.options import AudioArgs, make_plan
from frictex.device.audio.stream import StreamOutput
from frictex.device.link.host import open_sink
from jack_server import FS, JACKD, NO_JACKD, START_S, private_jackd

RATE = 10_000.0
LEVEL_UM = 1.5  # 0.5 of full scale on the default profile (0.02 um/V, 150 V)


def _jack_output(sd) -> int | None:
    """The JACK host API's first output device, or None."""
    for api in sd.query_hostapis():
        if "JACK" in api["name"]:
            for index in api["devices"]:
                if sd.query_devices(index)["max_output_channels"] > 0:
                    return index
    return None


@pytest.fixture
def jack_device(monkeypatch, tmp_path):
    """A private jackd (``jack_server.private_jackd``) and PortAudio rescanned to see it;
    yields the PortAudio device index. Stops the server afterwards."""
    if JACKD is None:
        pytest.skip(NO_JACKD)
    import sounddevice as sd

    with private_jackd(tmp_path, f"frictex-test-{os.getpid()}") as (server, env):
        for key in ("JACK_DEFAULT_SERVER", "JACK_NO_AUDIO_RESERVATION"):
            monkeypatch.setenv(key, env[key])
        try:
            deadline = time.monotonic() + START_S
            index = None
            while index is None:
                if server.poll() is not None or time.monotonic() > deadline:
                    pytest.fail(f"PortAudio did not list the JACK server within {START_S:g} "
                                f"s: {(tmp_path / 'jackd.log').read_text()[-800:]}")
                sd._terminate()  # PortAudio lists host APIs when initialised: rescan
                sd._initialize()
                index = _jack_output(sd)
                if index is None:
                    time.sleep(0.2)
            yield index
        finally:
            sd._terminate()  # PortAudio's JACK client goes before its server
    sd._initialize()


def send_for(out, seconds: float, start: int) -> int:
    """Send ``seconds`` of constant commands in 50-sample blocks from ``start``; the
    next start index."""
    block = np.full((50, 1), LEVEL_UM)
    for _ in range(round(seconds * RATE / 50)):
        out.send(start, block)
        start += 50
    return start


def test_starved_producer_ramps_to_zero_and_every_frame_is_accounted_for(jack_device):
    plan = make_plan(AudioArgs(), 1, RATE)
    out = StreamOutput(plan, str(jack_device), blocksize=256, buffer_frames=FS // 10,
                       phases=False, paced=True, wait_s=10.0, tap_frames=6 * FS)
    with out:
        assert out.output_latency_s > 0
        index = send_for(out, 1.5, 0)
        time.sleep(0.6)  # the producer stops: the ring's 100 ms run dry
        send_for(out, 1.0, index)
    p, status = out.player, out.status()
    audio = status["audio"]
    # every frame handed to the device either played or is counted, by cause
    assert audio["commanded_frames"] == p.played + sum(audio["unplayed_frames"].values())
    assert 0 < p.late <= p.underrun_frames
    assert audio["unplayed_frames"]["late"] == p.late
    assert status["unplayed_samples"] > 0 and status["underruns"] == p.underruns >= 1
    # the deliberate starvation: the longest from an underrun to the frames' return
    gaps = [(p.resumes[i] - p.marks[i], p.marks[i], p.resumes[i])
            for i in range(min(p.mark_count, p.resume_count))]
    _, start, back = max(gaps)
    assert back - start > 0.05 * FS  # well past the 5 ms looked at below
    tap = p.tap[:p.tap_len, 0]
    before = np.abs(tap[start - 2000:start])
    assert before.max() > 0.45  # it was playing at 0.5 of full scale
    settle = round(5e-3 * FS)
    assert np.abs(tap[start + settle:back]).max() < 0.01  # below 1 % within 5 ms
    slope = 0.5 * 2 * np.pi * plan.carrier_hz / FS  # the carrier's own largest step
    assert np.abs(np.diff(tap[start - 2000:start + settle])).max() <= slope * 1.01
    assert np.abs(np.diff(tap[back - 10:back + 2000])).max() <= slope * 1.01


def test_emergency_stop_ramps_through_jack(jack_device):
    plan = make_plan(AudioArgs(), 1, RATE)
    out = StreamOutput(plan, str(jack_device), blocksize=256, buffer_frames=FS // 10,
                       phases=False, paced=True, wait_s=10.0, tap_frames=4 * FS)
    send_for(out, 1.0, 0)
    out.emergency_stop()
    # JACK's thread plays the ramp and then silence when it next runs: waited for (a busy
    # machine may hold it), not assumed to take 0.1 s
    deadline = time.monotonic() + 10.0
    while time.monotonic() < deadline and not _quiet_after_stop(out.player, FS // 20):
        time.sleep(0.01)
    out.close()
    p, audio = out.player, out.status()["audio"]
    assert p.stopped > 0
    assert audio["commanded_frames"] == p.played + sum(audio["unplayed_frames"].values())
    tap = p.tap[:p.tap_len, 0]
    loud = np.flatnonzero(np.abs(tap) > 0.01)
    last = loud[-1]
    assert np.abs(tap[last + 1:]).max(initial=0.0) < 0.01 and tap.size - last > 0.05 * FS
    slope = 0.5 * 2 * np.pi * plan.carrier_hz / FS
    assert np.abs(np.diff(tap[last - 2 * plan.ramp_frames:])).max() <= slope * 1.01


def _quiet_after_stop(player, frames: int) -> bool:
    """Whether ``player`` has stopped and played ``frames`` quiet frames since."""
    tap = player.tap[:player.tap_len, 0]
    loud = np.flatnonzero(np.abs(tap) > 0.01)
    return player.stopped > 0 and loud.size > 0 and tap.size - loud[-1] > frames


def test_audio_device_by_name_through_the_registry(jack_device):
    with open_sink(f"audio:{jack_device},blocksize=256", 1, RATE, paced=True) as sink:
        assert sink.label == f"audio:{jack_device}"
        send_for(sink, 0.5, 0)
    status = sink.status()
    audio = status["audio"]
    assert status["state"] == "closed" and status["commanded_samples"] == 5000
    assert audio["commanded_frames"] == audio["played_frames"] + sum(
        audio["unplayed_frames"].values())
    # all of it played, but for frames that a producer descheduled past the ring's 100 ms
    # (a loaded machine) handed over after their time: dropped, counted late, and only
    # after the stream ran dry; with no underrun, that is played > 0.9 * 0.5 * FS
    late = audio["unplayed_frames"]["late"]
    assert audio["played_frames"] + late > 0.9 * 0.5 * FS
    assert late <= audio["underrun_frames"]


def test_an_unknown_audio_device_lists_the_output_devices_there_are(jack_device):
    """The help promises that an unknown name lists every device installed."""
    import sounddevice as sd
    from frictex.device.errors import InputError
    name = sd.query_devices(jack_device)["name"]
    with pytest.raises(InputError) as refused:
        open_sink("audio:no-such-card", 1, RATE, paced=True)
    message = str(refused.value)
    assert message.startswith("audio device 'no-such-card': ")
    assert "output devices: " in message and f"{jack_device}: {name} (" in message


def test_touch_to_dac_latency_through_jack(jack_device):
    from frictex.device.audio.latency import audio_latency

    result = audio_latency(f"{jack_device},blocksize=256", events=20)
    latency = result["latency_s"]
    assert latency.size + result["missed"] == 20 and latency.size >= 1
    # the first frame of an event's block reaches the DAC after the event arrived, and
    # no earlier than the callback that plays it plus what PortAudio reports downstream
    assert np.all(latency > 0) and np.all(np.isfinite(latency))
    assert result["output_latency_s"] > 0 and result["audio_rate"] == FS
