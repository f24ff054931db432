"""The audio output's stream, written by ``audio:wav:PATH`` from real replays and checked
against a demodulation written here (its own carrier estimate, mixer and filter)."""

from __future__ import annotations

import numpy as np
import pytest
from scipy.io import wavfile

import frictex
from frictex.device.errors import InputError
from frictex.device.link.devices import OutputDevice
from frictex.device.link.host import open_sink
from frictex.device.profile import PROFILES

FS = 192_000
RATE = 10_000.0


def replay_to_wav(tmp_path, scene, trace, options=""):
    path = tmp_path / "stream.wav"
    run = frictex.replay(scene, trace, device=f"audio:wav:{path}{options}")
    fs, frames = wavfile.read(path)
    assert fs == FS and frames.dtype == np.float32
    commands = {name: np.asarray(run.commands[name]) for name in run.commands.column_names}
    return frames.astype(np.float64).reshape(len(frames), -1), commands, run.summary


def carrier_estimate(x: np.ndarray) -> float:
    """The strongest spectral line (Hz), refined by a parabola through the three bins
    around the peak of the Hann-windowed spectrum."""
    spec = np.abs(np.fft.rfft(x * np.hanning(x.size)))
    k = int(np.argmax(spec[1:])) + 1
    a, b, c = np.log(spec[k - 1:k + 2])
    return (k + 0.5 * (a - c) / (a - 2 * b + c)) * FS / x.size


def window(f: float) -> int:
    """Frames L (8-199) of a moving average that holds the closest to a whole number of
    periods of the 2f image."""
    return min(range(8, 200), key=lambda m: abs(2 * f * m / FS - round(2 * f * m / FS)))


def smooth(x: np.ndarray, ell: int) -> np.ndarray:
    """Centred moving average of L frames, twice (a triangle of 2L - 1 frames: the 2f
    image leaks far less at a fast change of amplitude than through one average)."""
    box = np.ones(ell) / ell
    return np.convolve(np.convolve(x, box, mode="same"), box, mode="same")


def demodulate(x: np.ndarray, f: float) -> tuple[np.ndarray, int]:
    """Complex envelope: x mixed down by exp(-i 2 pi f t), times 2, then :func:`smooth`
    over :func:`window` frames (the expected envelope goes through the same filter)."""
    n = np.arange(x.size)
    ell = window(f)
    return smooth(2.0 * x * np.exp(-2j * np.pi * f * n / FS), ell), ell


def commanded_envelope(command: np.ndarray, frames: int, scale: float) -> np.ndarray:
    """The documented timeline: frame n carries the commands at n * RATE / FS - 1 (one
    command sample late), linearly interpolated; in full-scale units."""
    q = np.arange(frames) * RATE / FS - 1.0
    k = np.arange(-1, command.size)
    return np.interp(q, k, np.concatenate([[0.0], command]), right=0.0) * scale


def test_grating_10s_carrier_and_envelope(tmp_path):
    trace = frictex.synth_trace("back-and-forth", duration_s=10.0, speed_mm_s=60.0)
    frames, commands, summary = replay_to_wav(tmp_path, "grating-5mm", trace)
    spec = PROFILES.get("plate-seed003")
    x = frames[:, 0]
    assert summary.device["unplayed_samples"] == 0
    assert commands["t_s"][-1] > 9.9
    f = carrier_estimate(x)
    assert abs(f - spec.carrier_hz) <= 1e-4 * spec.carrier_hz, f
    z, ell = demodulate(x, f)
    want = smooth(commanded_envelope(commands["ch0_um"], x.size,
                                     1.0 / spec.um_per_volt / spec.voltage_limit_v), ell)
    assert want.max() > 0.2  # the grating drives the plate well into the scale
    first_block = int(50 * FS / RATE)  # the replay's first block (50 commands)
    inside = slice(first_block, int(commands["ch0_um"].size * FS / RATE) - 2 * ell)
    err = np.abs(np.abs(z[inside]) - want[inside])
    assert err.max() < 0.01, (err.max(), int(np.argmax(err)))
    assert np.abs(x).max() <= 1.0


def test_two_finger_modal_channel_phases(tmp_path):
    frames, commands, summary = replay_to_wav(
        tmp_path, "two-finger-beam-seed000", "two-fingers-crossing-50hz",
        ",profile=beam-seed000")
    spec = PROFILES.get("beam-seed000")
    assert frames.shape[1] == 2
    assert summary.device["audio"]["carrier_hz"] == spec.carrier_hz
    checked = set()
    k = (np.arange(frames.shape[0]) * RATE / FS - 1.0).astype(int)  # command each frame carries
    kk = np.clip(k, 2, commands["xA_um"].size)
    for name, ch in (("xA", 0), ("xB", 1)):
        z, ell = demodulate(frames[:, ch], spec.carrier_hz)  # the carrier's own reference
        amp = np.concatenate([commands[f"{name}_um"], np.zeros(3)])
        phase = np.concatenate([commands[f"{name}_phase_rad"], np.zeros(3)])
        # frames whose neighbourhood (filter window, interpolation) carries one constant
        # commanded complex amplitude, above 5 % of full scale
        steady = (k >= 2) & (k < commands[f"{name}_um"].size - 2)
        for d in range(-2, 3):
            steady &= (amp[kk + d] == amp[kk]) & (phase[kk + d] == phase[kk])
        pick = steady & (amp[kk] / spec.um_per_volt / spec.voltage_limit_v > 0.05)
        pick[:2 * ell] = pick[-2 * ell:] = False
        assert pick.sum() > 10_000, (name, pick.sum())
        err = np.degrees(np.angle(np.exp(1j * (np.angle(z[pick]) - phase[kk][pick]))))
        assert np.abs(err).max() < 0.5, (name, np.abs(err).max())
        checked |= set(np.round(phase[kk][pick], 9))
    assert checked == {0.0, round(np.pi, 9)}  # both signs of the modes were checked


def test_envelope_mode_plays_the_envelope(tmp_path):
    frames, commands, _ = replay_to_wav(tmp_path, "grating-5mm", "swipe-40mms-50hz",
                                        ",envelope")
    spec = PROFILES.get("plate-seed003")
    want = commanded_envelope(commands["ch0_um"], frames.shape[0],
                              1.0 / spec.um_per_volt / spec.voltage_limit_v)
    ramp = round(2e-3 * FS)
    end = int(commands["ch0_um"].size * FS / RATE)
    np.testing.assert_allclose(frames[ramp:end, 0], want[ramp:end], rtol=0, atol=1e-6)
    assert frames.min() >= 0.0


def test_wav_through_the_registry(tmp_path):
    path = tmp_path / "s.wav"
    with open_sink(f"audio:wav:{path},carrier=25000,full_scale=50", 1, RATE,
                   paced=True) as sink:
        assert sink.label.startswith("audio:wav:") and isinstance(sink, OutputDevice)
        sink.send(0, np.full((500, 1), 2.0))  # 100 V asked, 50 V full scale: clamped
        sink.send(600, np.full((100, 1), 0.5))  # a gap of 100 samples: silence
        status = sink.status()
    status = sink.status()
    assert status["clamped_samples"] == 500 and status["gap_samples"] == 100
    assert status["commanded_samples"] == 700 and status["unplayed_samples"] == 0
    fs, frames = wavfile.read(path)
    assert frames.size == status["audio"]["commanded_frames"]
    assert abs(carrier_estimate(frames[: 500 * 19].astype(np.float64)) - 25_000) < 3
    assert np.abs(frames).max() <= 1.0 and abs(frames[-1]) < 1e-6


def test_wav_bad_path_is_an_input_error(tmp_path):
    with pytest.raises(InputError, match="cannot write"):
        open_sink(f"audio:wav:{tmp_path}/missing/x.wav", 1, RATE)


def test_a_stream_is_written_all_or_nothing(tmp_path):
    """The WAV appears only when the stream ends; a failed or refused run removes what it
    wrote and leaves an earlier file as it was (a closed loop is refused: no force
    reports)."""
    path = tmp_path / "s.wav"
    path.write_bytes(b"earlier")
    sink = open_sink(f"audio:wav:{path}", 1, RATE, paced=True)
    sink.send(0, np.full((500, 1), 1.0))
    assert path.read_bytes() == b"earlier" and (tmp_path / "s.wav.partial").exists()
    sink.abort()
    assert path.read_bytes() == b"earlier" and not (tmp_path / "s.wav.partial").exists()
    with pytest.raises(frictex.DeviceError, match="sends no force reports"):
        frictex.replay("grating-5mm", "swipe-40mms-50hz", device=f"audio:wav:{path}",
                       control="closed")
    assert sorted(p.name for p in tmp_path.iterdir()) == ["s.wav"]
    assert path.read_bytes() == b"earlier"
    with open_sink(f"audio:wav:{path}", 1, RATE, paced=True) as sink:
        sink.send(0, np.full((500, 1), 1.0))
    fs, frames = wavfile.read(path)
    assert fs == FS and frames.size == sink.status()["audio"]["commanded_frames"]


def test_a_stream_to_a_character_device_is_written_directly():
    with open_sink("audio:wav:/dev/null", 1, RATE, paced=True) as sink:
        sink.send(0, np.full((100, 1), 1.0))
    assert sink.status()["commanded_samples"] == 100
