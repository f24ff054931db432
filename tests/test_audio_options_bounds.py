"""The audio device's rate and carrier bounds (``device.audio.options``): what sound
cards offer, one-line errors naming the bounds, exit 2 from the command line."""

from __future__ import annotations

import re
import subprocess
import sys

import pytest

from frictex.device.audio.options import (MAX_CARRIER_SHARE, MAX_RATE_HZ, MIN_RATE_HZ,
                                          make_plan, parse_arg)
from frictex.device.errors import InputError

RATE = 10_000.0


@pytest.mark.parametrize("rate", [MIN_RATE_HZ, 44_100, MAX_RATE_HZ])
def test_the_rates_sound_cards_offer_are_taken(rate):
    assert make_plan(parse_arg(f"envelope,rate={rate}"), 1, 1_000.0).audio_rate == rate


@pytest.mark.parametrize("rate", [MIN_RATE_HZ - 1, MAX_RATE_HZ + 1, 3e9, 1e300])
def test_a_rate_outside_them_names_them(rate):
    with pytest.raises(InputError, match=re.escape(f"rate={rate:g}: expected {MIN_RATE_HZ} "
                                                   f"to {MAX_RATE_HZ} Hz")):
        make_plan(parse_arg(f"envelope,rate={rate:.17g}"), 1, RATE)


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
    assert done.stderr == (f"frictex: error: audio device rate=3e+09: expected {MIN_RATE_HZ} "
                           f"to {MAX_RATE_HZ} Hz, the rates sound cards offer\n")
    assert not (tmp_path / "q.wav").exists()
