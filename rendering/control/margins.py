"""Stability margins of the friction loop (``rendering.control.loop``) from its open-loop
transfer function at the block rate.

The loop, linearised in the log domain (x = log c; a finger whose reduction of friction
changes ``s`` times as fast as the model's with the reduction asked, s = 1 for a model
that fits, multiplies the loop gain by s): block k commands x_k, held over its N
samples. The plate's amplitude loop (seed 003, Fig. 3b: 400 Hz), the fingertip's
tangential compliance (seed 003, section 3: 3.84 ms rise, about 90 Hz) and the force
sensor (1 kHz, 0.5 ms transport delay) smooth and delay it: ``rendering.control.chain``,
the same chain the loop applies to its reference, so that the ratio measured / reference
is the chain's output for a held x. The loop measures that ratio's median over a block
(here its mean): m_k = sum_j h_j x_{k-j}, h_j the mean over a block of the chain's
response to one block of ones j blocks earlier (sum_j h_j = 1). The report reaches the
loop D blocks after its block, and the integrator steps x_{k+1} = x_k - ki m_{k-D}::

    L(z) = ki z^-D H(z) / (z - 1),     H(z) = sum_j h_j z^-j

Margins of L(e^jw), w in (0, pi] rad per block: the gain margin 1 / |L| where the phase
crosses -180 deg (how much larger ``s ki`` may be before the loop oscillates), the phase
margin 180 deg + arg L where |L| = 1 (at w_c), and the delay margin PM / w_c (how many
more blocks of delay it tolerates).

The gain margin is inversely proportional to ki, so the loop's gain is scheduled on the
delay D it measures (:func:`scheduled_ki`): the largest ki whose gain margin is at least
:data:`COVER_SLOPE`, the steepest s the loop must tolerate, and at most :data:`KI_MAX`.
A report that comes back later makes the loop slower, never unstable.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass
from functools import lru_cache

import numpy as np

from frictex.device.finger import SensorParams
from frictex.rendering.control.chain import Chain

#: the integrator's gain per block, at most: the cover asks for less at every delay with
#: 5 ms blocks (0.296 at 5 kHz, 0.269 at 10 kHz with the report before the next block);
#: the cap binds only for a faster chain of blocks
KI_MAX = 0.3
#: the loop-gain factor s every scheduled gain tolerates: the steepest finger of the
#: report's population reaches s = 7.37 (``app.measure.report_closed_loop``'s
#: ``population_slopes``), so it keeps a gain margin of 1.09 at its worst operating point
COVER_SLOPE = 8.0
#: the frequency grid (points over (0, pi]) on which the crossings are found
GRID = 1 << 16


@dataclass(frozen=True)
class Margins:
    """Margins of one loop (module docstring): gain margin (factor, inf if the phase
    never reaches -180 deg), phase margin (deg), gain crossover w_c (rad per block),
    delay margin (blocks), at ``delay_blocks`` of report delay and gain ``ki``."""

    ki: float
    delay_blocks: int
    gain_margin: float
    phase_margin_deg: float
    crossover_rad_per_block: float
    delay_margin_blocks: float


def block_response(sensor: SensorParams, rate_hz: float, block: int) -> np.ndarray:
    """h_j, j = 0, 1, ...: the mean over block j of the chain's response to one block of
    ones in block 0 (until what is left is below 1e-12); sums to 1."""
    chain = Chain(sensor, rate_hz)
    slowest = float(np.abs(np.roots(chain.a)).max())
    samples = chain.delay + block + int(math.ceil(math.log(1e-12) / math.log(slowest)))
    blocks = -(-samples // block)
    x = np.zeros((1, blocks * block))
    x[0, :block] = 1.0
    y, _ = chain.run(x, chain.initial_state([0.0]))
    return y[0].reshape(blocks, block).mean(axis=1)


def open_loop(w: np.ndarray, ki: float, h: np.ndarray, delay_blocks: int) -> np.ndarray:
    """L(e^jw) at ``w`` (rad per block), see the module docstring."""
    z = np.exp(1j * np.asarray(w, dtype=np.float64))
    taps = np.polyval(h[::-1], 1.0 / z)  # sum_j h_j z^-j, by Horner's rule
    return ki * z ** -delay_blocks * taps / (z - 1.0)


def _crossing(w: np.ndarray, f: np.ndarray) -> float | None:
    """The first w where f (sampled on w) falls through 0, linearly interpolated."""
    below = np.flatnonzero(f <= 0.0)
    if below.size == 0:
        return None
    k = int(below[0])
    if k == 0:
        return float(w[0])
    return float(w[k - 1] + (w[k] - w[k - 1]) * f[k - 1] / (f[k - 1] - f[k]))


def loop_margins(ki: float, h: np.ndarray, delay_blocks: int) -> Margins:
    """The margins of L(z) = ki z^-D H(z) / (z - 1) (module docstring)."""
    w = np.linspace(math.pi / GRID, math.pi, GRID)
    loop = open_loop(w, ki, h, delay_blocks)
    phase = np.unwrap(np.angle(loop))
    w180 = _crossing(w, phase + math.pi - 1e-9)  # reached at w = pi exactly when D = 0
    gain_margin = math.inf if w180 is None else 1.0 / float(
        np.abs(open_loop(np.array([w180]), ki, h, delay_blocks))[0])
    wc = _crossing(w, np.abs(loop) - 1.0)
    if wc is None:  # |L| < 1 everywhere: nothing to cross
        return Margins(ki, delay_blocks, gain_margin, 180.0, 0.0, math.inf)
    pm = math.pi + float(np.interp(wc, w, phase))
    return Margins(ki, delay_blocks, gain_margin, math.degrees(pm), wc, pm / wc)


@lru_cache(maxsize=256)
def scheduled_ki(delay_blocks: int, sensor: SensorParams = SensorParams(),
                 rate_hz: float = 10_000.0, block: int = 50,
                 cover: float = COVER_SLOPE) -> float:
    """The integrator's gain for reports ``delay_blocks`` late (module docstring): the
    gain margin at ki = 1 divided by ``cover``, at most :data:`KI_MAX`. About 5 ms the
    first time for each set of arguments (kept)."""
    h = block_response(sensor, rate_hz, block)
    return min(KI_MAX, loop_margins(1.0, h, int(delay_blocks)).gain_margin / cover)


def margins(delays, sensor: SensorParams = SensorParams(), rate_hz: float = 10_000.0,
            block: int = 50, cover: float = COVER_SLOPE) -> dict:
    """The margins at the scheduled gain for each report delay in ``delays`` (blocks)
    for blocks of ``block`` samples at ``rate_hz``, as a dict for the report: ``rows``
    (:class:`Margins` as dicts), ``block_s``, ``block_response`` (h_j), ``cover``."""
    h = block_response(sensor, rate_hz, block)
    rows = [asdict(loop_margins(scheduled_ki(d, sensor, rate_hz, block, cover), h, d))
            for d in delays]
    return {"rows": rows, "block_s": block / rate_hz, "block_response": h.tolist(),
            "cover": cover}
