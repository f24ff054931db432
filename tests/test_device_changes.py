"""What an output device changed of what was commanded (``app.engine.device_changes``):
values clamped to its limit and audio output underflows, said as warnings, and the
replay's printed clamp count giving the device's part.

The clamps are checked against the commands table itself: the samples it holds above the
device's limit are the ones the device clamped."""

from __future__ import annotations

import csv
import json
import struct

import numpy as np

from frictex.app.commands.cli import main
from frictex.app.commands.replay import inversion_clamps
from frictex.app.engine.device_changes import device_clamped, device_warnings
from frictex.textures.library import LIBRARY_DIR


def commands_um(folder) -> np.ndarray:
    """The commands table's one channel (um)."""
    with open(folder / "commands.csv", newline="") as f:
        return np.array([float(row["ch0_um"]) for row in csv.DictReader(f)])


def replay(tmp_path, capsys, scene: str, device: str, *options: str) -> tuple[dict, str]:
    """``frictex replay SCENE swipe-40mms-50hz --device DEVICE OPTIONS``: summary.json and
    the printed line; every warning in the summary is printed too."""
    out = tmp_path / "out"
    assert main(["replay", scene, "swipe-40mms-50hz", "--out", str(out),
                 "--device", device, *options]) == 0
    doc = json.loads((out / "summary.json").read_text())
    printed = capsys.readouterr()
    assert printed.err == "".join(f"frictex: warning: {w}\n" for w in doc["warnings"])
    return doc, printed.out


def test_a_device_limit_below_the_commands_is_said(tmp_path, capsys):
    # the simulated device plays in real time: on a busy machine it may run dry, which
    # this test is not about (its samples are clamped on sending, played or not)
    doc, printed = replay(tmp_path, capsys, "grating-15mm", "sim:limit=1", "--max-unplayed", "1")
    device, commands = doc["device"], commands_um(tmp_path / "out")
    over = int(np.count_nonzero(commands > 1.0))
    assert over > 0 and device["clamped_samples"] == over  # the table keeps the command
    assert doc["clamps"]["unreachable"] == 0  # the pipeline itself clamped nothing
    (warning,) = [w for w in device_warnings(device, doc["counts"]["max_amplitude_um"])
                  if "were clamped" in w]
    share = over / device["commanded_samples"]
    assert warning.startswith(f"{over} of {device['commanded_samples']} commanded samples "
                              f"({share:.1%}) were clamped to the device's 1 um limit")
    assert warning.endswith(f"up to {commands.max():.4g} um")
    assert warning in doc["warnings"]  # in summary.json, and printed with the others
    # the printed count no longer says 0 clamped
    assert f"; 0 clamped by the friction inversion, {over} samples by the device's limit; " \
        in printed


def test_an_audio_outputs_voltage_limit_is_said(tmp_path, capsys):
    """A scene allowed 100 um on a profile whose 150 V drive reaches 3 um (0.02 um/V)."""
    text = (LIBRARY_DIR / "grating-15mm.toml").read_text()
    scene = tmp_path / "wide.toml"
    scene.write_text(text.replace("amplitude_limit_um = 2.5", "amplitude_limit_um = 100")
                     .replace("mu_low = 0.6 ", "mu_low = 0.1 "))
    wav = tmp_path / "drive.wav"
    doc, printed = replay(tmp_path, capsys, str(scene), f"audio:wav:{wav}")
    device, commands = doc["device"], commands_um(tmp_path / "out")
    over = int(np.count_nonzero(commands > 3.0 + 1e-9))
    assert over > 0 and device["clamped_samples"] == over
    (warning,) = device_warnings(device, doc["counts"]["max_amplitude_um"])
    assert f"{over} of {device['commanded_samples']} commanded samples" in warning
    assert "the audio output's 150 V limit (3 um at 0.02 um/V)" in warning
    assert warning in doc["warnings"]
    inversion = sum(doc["clamps"].values())  # its own clamp to the scene's 100 um, too
    assert doc["clamps"]["unreachable"] == inversion > 0  # the only guard it took
    assert (f"; {inversion} clamped by the friction inversion (unreachable {inversion}), "
            f"{over} samples by the device's limit; ") in printed
    frames = np.frombuffer(wav.read_bytes()[58:], dtype="<f4")  # after the header
    assert np.abs(frames).max() <= 1.0 + 1e-6  # full scale: 150 V, what the plate got
    assert struct.unpack("<I", wav.read_bytes()[24:28])[0] == 192_000


def test_audio_underflows_are_said_with_what_they_cost():
    status = {"clamped_samples": 0, "commanded_samples": 50_050,
              "audio": {"xruns": 30, "blocksize": 256, "rate_hz": 192_000}}
    (warning,) = device_warnings(status, 1.5)
    assert warning.startswith("30 audio callbacks were flagged with an output underflow")
    assert "up to one 256-frame period, 1.33 ms," in warning
    assert "unplayed_samples and underruns count only frictex's own buffer" in warning
    status["audio"]["xruns"] = 0
    assert device_warnings(status, 1.5) == []


def test_several_channels_count_values_and_name_each_limit():
    status = {"clamped_samples": 5, "commanded_samples": 10,
              "device": {"limits_um": [1.0, 2.0]}}
    (warning,) = device_warnings(status, 3.0)
    assert warning.startswith("5 of 20 commanded values (samples x 2 channels, 25.0%) were "
                              "clamped to the device's limits (1, 2 um by channel)")


def test_a_device_clamp_counts_samples_on_one_channel_and_values_on_more():
    """A two-channel device counts each channel's clamped value: 79,563 of them against
    44,050 samples were printed as if samples (the warning already said values)."""
    one = {"clamped_samples": 7, "device": {"limits_um": [1.0]}}
    two = {"clamped_samples": 79_563, "device": {"limits_um": [0.1, 0.1]}}
    assert device_clamped(one) == (7, "samples")
    assert device_clamped(two) == (79_563, "values")
    assert device_clamped({}) == (0, "samples")


def test_the_replay_line_names_each_guard_that_clamped():
    """Each guard's count is said (a sample can be in two: a bad force and then an
    unreachable target), not only their sum."""
    clamps = {"above_one": 0, "unreachable": 10, "force_beyond_model": 0, "bad_force": 2,
              "nonfinite_target": 0}
    assert inversion_clamps(clamps) == ("12 clamped by the friction inversion "
                                        "(unreachable 10, bad force 2)")
    assert inversion_clamps(dict.fromkeys(clamps, 0)) == "0 clamped by the friction inversion"
