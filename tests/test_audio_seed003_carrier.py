"""The default plate (seed 003) drives its audio output at its own resonance, 60.75 kHz,
and a rate that cannot carry it is refused in one line naming the carrier and the rate
it needs."""

from __future__ import annotations

import pytest

from frictex.device.audio.options import make_plan, parse_arg
from frictex.device.errors import InputError
from frictex.device.profile import DEFAULT_PROFILE, PROFILES

RATE = 10_000.0


def test_seed003_plate_resonates_at_60750_hz():
    """Seed 003, section 4.2: 'a glass plate ... resonating at 60750 Hz' (was 30 kHz)."""
    assert DEFAULT_PROFILE == "plate-seed003"
    assert PROFILES.get("plate-seed003").carrier_hz == 60_750.0
    assert make_plan(parse_arg(""), 1, RATE).carrier_hz == 60_750.0


@pytest.mark.parametrize("rate", [48_000, 96_000])
def test_rates_below_its_nyquist_share_are_refused_naming_carrier_and_rate(rate):
    with pytest.raises(InputError) as caught:
        make_plan(parse_arg(f"rate={rate}"), 1, RATE)
    assert str(caught.value) == (
        f"audio device: carrier 60750 Hz (profile plate-seed003) at rate={rate} Hz: the "
        f"carrier must stay below 0.4 of the rate (use rate=151876 or more)")


def test_the_default_rate_carries_it():
    assert make_plan(parse_arg("rate=192000"), 1, RATE).audio_rate == 192_000
    assert make_plan(parse_arg("rate=151876"), 1, RATE).audio_rate == 151_876
