"""Stability margins of the friction loop (``rendering.control.loop``).

In the log domain the loop is an integrator with ``D`` blocks of delay between the block
a gain acts on and the update that uses its measurement::

    x[k+1] = x[k] - ki (x[k-D] + log G),      L(z) = ki z^-D / (z - 1)

with x = log c and G the finger's local slope against the model's (1 for a model that
fits; ``rendering.control.adapt`` drives it there). The phase of L(e^jw) is
-(pi/2 + w/2 + w D), so it crosses -180 deg at w = pi / (2 D + 1), where
|L| = ki / (2 sin(w / 2)); the gain crossover is at 2 sin(w_c / 2) = ki. The sensor's
and the plate loop's lags are shorter than a block (``Chain.lag_samples``) and are
applied to the reference too, so they enter as at most one block of ``D``.
"""

from __future__ import annotations

import math

#: the integrator's gain per block (``LoopConfig.ki``)
KI = 0.3
#: delays stated: the simulated device (report before the next block) and a live link
#: whose report arrives two blocks later
DELAYS = (0, 2)


def gain_phase_margins(ki: float, delay_blocks: int) -> tuple[float, float]:
    """(gain margin as a factor, phase margin in degrees) of L(z) = ki z^-D / (z - 1)."""
    w180 = math.pi / (2 * delay_blocks + 1)
    gain_margin = 2.0 * math.sin(w180 / 2.0) / ki
    wc = 2.0 * math.asin(min(ki / 2.0, 1.0))
    phase_margin = math.degrees(math.pi / 2.0 - wc * (delay_blocks + 0.5))
    return gain_margin, phase_margin


def margins(ki: float = KI) -> dict:
    """The margins at each delay of :data:`DELAYS` (the first is the simulated device's)."""
    rows = [{"delay_blocks": d, **dict(zip(("gain_margin", "phase_margin_deg"),
                                           gain_phase_margins(ki, d)))} for d in DELAYS]
    return {"ki": ki, **rows[0], "live": rows[1:]}
