"""``profile=`` on ``--device audio`` names the plate wired to the output; the drive still
never passes the scene's profile's voltage limit (device/audio/options.py)."""

from __future__ import annotations

import io

import numpy as np
from scipy.io import wavfile

from frictex.device.audio.open import open_audio
from frictex.device.audio.options import make_plan, parse_arg
from frictex.device.link.devices import DeviceRequest

RATE = 10_000.0


def test_typed_profile_gives_the_figures_and_the_scene_caps_the_voltage():
    # the ring's scene (80 V) played on the beam (150 V, 0.005125 um/V)
    plan = make_plan(parse_arg("profile=beam-seed000"), 2, RATE, "ring-seed004")
    assert (plan.profile, plan.carrier_hz, plan.um_per_volt) == ("beam-seed000", 28_000.0,
                                                                  0.41 / 80.0)
    assert (plan.limit_v, plan.full_scale_v) == (80.0, 150.0)
    # the other way round: the beam's scene on the ring keeps the ring's own 80 V
    assert make_plan(parse_arg("profile=ring-seed004"), 2, RATE, "beam-seed000").limit_v == 80.0
    # no scene profile: the typed profile's limit alone
    assert make_plan(parse_arg("profile=beam-seed000"), 2, RATE).limit_v == 150.0


def test_wav_peaks_at_the_scene_limit_and_one_line_names_both_profiles(tmp_path):
    stderr = io.StringIO()
    request = DeviceRequest(channels=2, rate_hz=RATE, paced=True, stderr=stderr,
                            profile="ring-seed004")
    path = tmp_path / "out.wav"
    with open_audio(f"wav:{path},profile=beam-seed000", request) as out:
        out.send(0, np.full((2_000, 2), 100.0))  # far above either limit
    _, frames = wavfile.read(path)
    assert abs(np.abs(frames).max() - 80.0 / 150.0) < 1e-3
    lines = [line for line in stderr.getvalue().splitlines() if "profile" in line]
    assert len(lines) == 1
    assert all(s in lines[0] for s in ("beam-seed000 (150 V", "ring-seed004 (80 V", "80 V"))


def test_same_profile_twice_says_nothing(tmp_path):
    stderr = io.StringIO()
    request = DeviceRequest(channels=2, rate_hz=RATE, paced=True, stderr=stderr,
                            profile="ring-seed004")
    with open_audio(f"wav:{tmp_path / 'o.wav'},profile=ring-seed004", request):
        pass
    assert "profile" not in stderr.getvalue()
