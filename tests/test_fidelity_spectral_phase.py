"""Where the spectral error ignores a texture's spatial phase, and where it does not, and
that the report's spectral claims below that frequency say so."""

import numpy as np
import pytest

from frictex.app.measure.report_claims import phase_note
from frictex.rendering.metrics import PHASE_BLIND_HZ, spectral_error

RATE_HZ, SPEED_MM_S = 20_000.0, 60.0


def _shift_cost(texture_hz: float, shift_periods: float) -> float:
    """Spectral error of a 0.6/1.0 square grating at ``texture_hz`` (4 s at 60 mm/s)
    shifted in space by ``shift_periods`` of its period."""
    period = SPEED_MM_S / texture_hz
    s = SPEED_MM_S * np.arange(0, 4.0, 1 / RATE_HZ)
    grating = lambda x: np.where(np.mod(x, period) / period < 0.5, 0.6, 1.0)  # noqa: E731
    return spectral_error(grating(s - shift_periods * period), grating(s),
                          np.ones(s.size, bool), RATE_HZ)


@pytest.mark.parametrize("texture_hz", [PHASE_BLIND_HZ, 18.0, 25.0, 40.0, 100.0])
def test_from_phase_blind_hz_a_shift_costs_little(texture_hz):
    assert max(_shift_cost(texture_hz, k / 8) for k in (1, 2, 3)) <= 0.11


@pytest.mark.parametrize("texture_hz, at_least", [(4.0, 1.3), (8.0, 0.4), (10.0, 0.25)])
def test_below_it_a_quarter_period_shift_costs_as_much_as_a_wrong_texture(texture_hz, at_least):
    assert _shift_cost(texture_hz, 0.25) > at_least


def test_spectral_claims_on_slow_textures_say_they_count_phase():
    # 15 mm at the human-like strokes' 60 mm/s: 4 Hz; 5 mm at 120 mm/s: 24 Hz
    assert "4 Hz texture" in phase_note("grating-15mm", "human", "spectral_error")
    assert "4 Hz texture" in phase_note("grating-5mm", "slow", "spectral_error")
    assert phase_note("grating-5mm", "fast", "spectral_error") == ""
    assert phase_note("grating-0.6mm", "slow", "spectral_error") == ""
    assert phase_note("grating-15mm", "human", "time_error") == ""
