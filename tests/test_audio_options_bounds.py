"""The audio device's rate, carrier, block, buffer and ramp bounds
(``device.audio.options``): what sound cards offer, a plate still within 50 ms of a stop,
one-line errors naming the option as typed and the bounds, exit 2 from the command line."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from frictex.device.audio.options import (MAX_BLOCKSIZE, MAX_BUFFER_MS, MAX_CARRIER_SHARE,
                                          MAX_RATE_HZ, MAX_STOP_MS, MIN_RATE_HZ, make_plan,
                                          parse_arg)
from frictex.device.errors import InputError

RATE = 10_000.0


@pytest.mark.parametrize("rate", [MIN_RATE_HZ, 44_100, MAX_RATE_HZ])
def test_the_rates_sound_cards_offer_are_taken(rate):
    assert make_plan(parse_arg(f"envelope,rate={rate}"), 1, 1_000.0).audio_rate == rate


@pytest.mark.parametrize("rate", ["7999", "768001", "3e9", "1e300", "768000.5"])
def test_a_rate_outside_them_names_them_as_typed(rate):
    with pytest.raises(InputError, match=re.escape(f"rate={rate}: expected {MIN_RATE_HZ} "
                                                   f"to {MAX_RATE_HZ} Hz")):
        make_plan(parse_arg(f"envelope,rate={rate}"), 1, RATE)


def test_a_rate_not_whole_is_quoted_as_typed_not_rounded():
    """It said "rate=192000: expected a whole number of Hz" for rate=192000.5."""
    with pytest.raises(InputError, match=re.escape("rate=192000.5: expected a whole number")):
        parse_arg("wav:t.wav,rate=192000.5")


@pytest.mark.parametrize("option, text, bound", [
    ("ramp_ms", "1000", f"more than 0 to {MAX_STOP_MS:g} ms: the plate must be still within"),
    ("ramp_ms", "1e9", f"more than 0 to {MAX_STOP_MS:g} ms"),
    ("blocksize", str(MAX_BLOCKSIZE + 1), f"1 to {MAX_BLOCKSIZE} frames"),
    ("buffer_ms", "1e9", f"1 to {MAX_BUFFER_MS:g} ms"),
    ("buffer_ms", "0.5", f"1 to {MAX_BUFFER_MS:g} ms"),
])
def test_an_option_sizing_a_buffer_or_a_time_is_bounded(option, text, bound):
    with pytest.raises(InputError, match=re.escape(f"{option}={text}: expected {bound}")):
        parse_arg(f"wav:t.wav,{option}={text}")


def test_the_ramp_and_one_block_stop_the_plate_within_50_ms():
    fs = 192_000
    top = MAX_STOP_MS - 256 * 1e3 / fs  # the default block, 1.33 ms
    plan = make_plan(parse_arg(f"envelope,rate={fs},ramp_ms={top}"), 1, RATE)
    assert plan.ramp_frames * 1e3 / fs + 256 * 1e3 / fs <= MAX_STOP_MS + 1e3 / fs
    with pytest.raises(InputError, match=r"ramp_ms=48\.7 at rate=192000 Hz: one block "
                                         r"\(1\.333 ms\) plus the ramp must not exceed 50 ms "
                                         r"\(ramp_ms up to 48\.67 ms\)"):
        make_plan(parse_arg(f"envelope,rate={fs},ramp_ms=48.7"), 1, RATE)
    with pytest.raises(InputError, match=r"blocksize=8192 and ramp_ms=2 at rate=8000 Hz: one "
                                         r"block \(1024 ms\).*\(blocksize up to 384\)"):
        make_plan(parse_arg("envelope,rate=8000,blocksize=8192"), 1, 1_000.0)
    assert make_plan(parse_arg("envelope,rate=8000,blocksize=384"), 1, 1_000.0).audio_rate


@pytest.mark.parametrize("text, line", [
    ("ramp_ms=1000", f"ramp_ms=1000: expected more than 0 to {MAX_STOP_MS:g} ms: the plate "
                     f"must be still within {MAX_STOP_MS:g} ms of a stop (PROTOCOL.md 5.3)"),
    ("ramp_ms=1e9", f"ramp_ms=1e9: expected more than 0 to {MAX_STOP_MS:g} ms: the plate "
                    f"must be still within {MAX_STOP_MS:g} ms of a stop (PROTOCOL.md 5.3)"),
    ("rate=192000.5", "rate=192000.5: expected a whole number of Hz"),
])
def test_a_long_ramp_is_one_line_and_exit_2(tmp_path, text, line):
    """ramp_ms=1000 was taken (a 1 s stop ramp); ramp_ms=1e9 was a 1.4 TiB numpy
    allocation in the stop ramp, "internal error", exit 70."""
    done = subprocess.run(
        [sys.executable, "-m", "frictex", "replay", "grating-5mm", "swipe-40mms-50hz",
         "--out", str(tmp_path / "out"), "--device", f"audio:wav:{tmp_path / 'x.wav'},{text}"],
        capture_output=True, text=True, timeout=120)
    assert (done.returncode, done.stderr) == (2, f"frictex: error: audio device {line}\n")
    assert not (tmp_path / "x.wav").exists()


def test_the_highest_carrier_is_what_the_highest_rate_carries():
    top = MAX_CARRIER_SHARE * MAX_RATE_HZ
    plan = make_plan(parse_arg(f"carrier={top - 1:g},rate={MAX_RATE_HZ}"), 1, RATE)
    assert plan.carrier_hz == top - 1
    for carrier in (top, 1e9):  # no rate to suggest: above what any rate carries
        with pytest.raises(InputError, match=f"expected below {top:g} Hz") as refused:
            make_plan(parse_arg(f"carrier={carrier:g}"), 1, RATE)
        assert "use rate=" not in str(refused.value)
    with pytest.raises(InputError, match=r"use rate=750001 or more"):  # one that fits
        make_plan(parse_arg("carrier=300000"), 1, RATE)


def test_an_absurd_rate_is_one_line_and_exit_2(tmp_path):
    """It was a struct.error traceback from the WAV header, exit 70."""
    done = subprocess.run(
        [sys.executable, "-m", "frictex", "replay", "grating-15mm", "swipe-40mms-50hz",
         "--out", str(tmp_path / "out"), "--device",
         f"audio:wav:{tmp_path / 'q.wav'},carrier=1e9,rate=3e9"],
        capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr == (f"frictex: error: audio device rate=3e9: expected {MIN_RATE_HZ} "
                           f"to {MAX_RATE_HZ} Hz, the rates sound cards offer\n")
    assert not (tmp_path / "q.wav").exists()
