"""What a periodic layer's output sample plays: the texture's mean over the stretch the
finger crosses while the sample is held, and the texture's mean beyond the Nyquist
frequency.

The box mean. The plate holds each output sample for 1 / rate_hz, and the finger crosses
a stretch of the texture meanwhile, so each sample of a periodic layer (grating or
waveform) plays the mean of the layer's profile over that stretch of phase, not the
profile at one point: SHT and the hybrid from the sample's phase by its own step (the
``travel`` they synthesise), SHO, which cannot know the next sample's phase, from the
previous sample's phase to its own (at the finger's position). Point sampling folded a square
grating's harmonics above Nyquist back into the plate's band (seed 003: ~400 Hz
amplitude-loop bandwidth): at 10 kHz a 0.6 mm, duty 0.4 grating under a 980 mm/s swipe
(1633 Hz) played its 6th harmonic (9800 Hz) as a 200 Hz line at 0.168 of the fundamental;
the box mean weights harmonic f by sinc(f / rate_hz), which took that line to 0.003. It
also places an edge within a sample: a sample straddling one plays the two sides in
proportion, where a point sample played either by chance. The mean over [phi0, phi1] is
exact from the profile's running integral C over one period, tabulated at ``MEAN_PHASES``
phases (midpoint rule) less the mean's share, D (periodic, and small, so that differences
of it round less)::

    C(phi) = phi * mean + D(frac(phi)),   box mean = (C(phi1) - C(phi0)) / (phi1 - phi0)

A sample that moves the phase by less than ``MIN_TRAVEL`` (a finger at rest, or slower
than one table cell per sample) plays the point value at its own phase, exactly as
before: below one cell the table cannot place an edge inside the interval any better. So
does SHO's first sample of a touch (it has no previous phase); SHO's first sample of a
call starts at the previous call's last phase (``last``, carried in the renderer's
state), and SHT's and the hybrid's stretch is each sample's own, so the output does not
depend on how a run is split into calls.

Beyond Nyquist. SHT and the hybrid play a texture whose phase moves by their ``travel``
each sample. Where it moves by more than half a cycle (a texture beyond the output's
Nyquist frequency, half the output rate; for the hybrid the synthesis at the filtered
velocity plus its correction, which can exceed what the tracker's velocity says) the
texture's mean mu' over one period is played, which is what the texture is to a plate
that cannot play it, and those touching samples are counted (``summary.json``'s
``layer_clipped``, with a warning). At the default 10 kHz output it takes a finger beyond
3 m/s on a 0.6 mm grating. SHO does the same where its stretch from the previous
sample's phase moves by more than half a cycle while the tracker's velocity also moves
the phase by more than half a cycle a sample: its box mean weakens a fundamental above
Nyquist only by sinc(f / rate_hz) and played it folded into the band (0.6 mm, 560 mm/s,
933 Hz at 1 kHz output: a 67 Hz square wave 0.786-0.814, uncounted). A longer stretch
under a slower finger is the jump to a new touch sample (SHO-held's at each one), a step
and not a texture beyond Nyquist: it keeps its mean over the jump, uncounted.
"""

from __future__ import annotations

import math

import numpy as np

from frictex.device.jit import njit

#: phases over one period the profile's running integral (and its mean) is tabulated at:
#: a cell is 9 nm of a 0.6 mm grating, so an edge's place within a sample is off by at
#: most (mu_high - mu_low) * cell / (sample's phase travel)
MEAN_PHASES = 65536

#: phase travel (cycles) in one sample below which the sample plays the profile's point
#: value: one table cell (a finger slower than 0.09 mm/s on a 0.6 mm grating at 10 kHz)
MIN_TRAVEL = 1.0 / MEAN_PHASES

#: a box mean this close to the sample's point value is the point value: rounding, not
#: texture (see ``_box_row``)
SNAP = 1e-9


class BandLimit:
    """What one periodic layer (grating or waveform) plays, sample by sample (the box
    mean does not depend on the output rate: each sample brings its stretch)."""

    def __init__(self, layer):
        self.layer = layer
        self.period_mm = float(layer.period_mm)
        middles = (np.arange(MEAN_PHASES) + 0.5)[None, :] / MEAN_PHASES
        values = layer.profile_where(middles, np.ones(middles.shape, bool))[0]
        #: the profile's least and greatest mu' (at the table's phases): a box mean lies
        #: between them
        self._range = float(values.min()), float(values.max())
        # summed in extended precision, so that each entry is rounded once: a float64
        # running sum drifts by up to 65536 roundings, 4e-12 of a 10 mm grating's box mean
        running = np.cumsum(values.astype(np.longdouble))
        mean = running[-1] / MEAN_PHASES
        #: mu' averaged over one period: what is played above the Nyquist frequency
        self.mean_mu = float(mean)
        #: D at MEAN_PHASES + 1 even steps over one period: the running integral of mu' less mean x phase (cycles x mu'),
        #: periodic (0 at both ends), and small, so a difference of it rounds less than C's
        deviation = (running - mean * np.arange(1, MEAN_PHASES + 1)) / MEAN_PHASES
        self._table = np.concatenate(([0.0], deviation[:-1].astype(np.float64), [0.0]))

    def play_since(self, phase: np.ndarray, covers: np.ndarray, block, last: dict,
                   step: np.ndarray) -> tuple[np.ndarray, int, dict]:
        """mu' (F, n) each sample plays (1 where the layer does not cover): the profile's
        mean over the stretch from the previous sample's phase to its own ``phase``
        (cycles, unwrapped; SHO, which knows no sample's phase before it comes; ``last``:
        the previous call's), or the texture's mean where both that stretch and ``step``
        (F, n; cycles the finger's velocity moves the phase in one sample) exceed half a
        cycle (:meth:`apply`); the number of such touching samples; and the (touch id,
        last phase) of each finger of ``block`` to pass back as ``last`` next call."""
        touch = np.ascontiguousarray(block.touch_id, dtype=np.int64)
        phase = np.ascontiguousarray(phase, dtype=np.float64)
        point = self.layer.profile_where(phase, covers)
        mu = np.empty_like(point)
        travel = np.empty_like(phase)
        for row, fid in enumerate(block.ids):
            start, travel[row] = _since_previous(phase[row], touch[row], last.get(fid))
            self._box(start, travel[row], covers[row], point[row], mu[row])
        # a stretch past half a cycle under a finger slower than that is a jump to a new
        # touch sample, not a texture beyond Nyquist: it keeps its mean over the jump
        limited = self.apply(mu, covers, block, np.where(np.abs(step) > 0.5, travel, 0.0))
        if phase.shape[1] == 0:
            return mu, limited, last
        return mu, limited, {fid: (int(touch[row, -1]), float(phase[row, -1]))
                             for row, fid in enumerate(block.ids)}

    def play_forward(self, phase: np.ndarray, covers: np.ndarray, travel: np.ndarray
                     ) -> np.ndarray:
        """mu' (F, n) each sample plays (1 where the layer does not cover): the profile's
        mean over [phase, phase + travel] (cycles; ``travel`` (F, n): each sample's own
        phase increment, the stretch the finger crosses while the sample is held; SHT,
        the hybrid)."""
        phase = np.ascontiguousarray(phase, dtype=np.float64)
        point = self.layer.profile_where(phase, covers)
        mu = np.empty_like(point)
        for row in range(phase.shape[0]):
            self._box(phase[row], np.ascontiguousarray(travel[row], dtype=np.float64),
                      covers[row], point[row], mu[row])
        return mu

    def _box(self, start, span, covers, point, out) -> None:
        """One finger's row (``_box_row``) into ``out``."""
        _box_row(start, span, np.ascontiguousarray(covers), point, self._table, self.mean_mu,
                 *self._range, out)

    def apply(self, mu: np.ndarray, covers: np.ndarray, block, travel: np.ndarray) -> int:
        """Set ``mu`` (F, n) to the mean where a touching finger on the layer (``covers``)
        moves the phase by more than half a cycle in one sample (``travel``, cycles,
        (F, n): the texture beyond the Nyquist frequency); the number of such samples."""
        above = (np.abs(travel) > 0.5) & covers & block.contact
        mu[above] = self.mean_mu
        return int(np.count_nonzero(above))


def _since_previous(phase: np.ndarray, touch: np.ndarray, before: tuple[int, float] | None
                    ) -> tuple[np.ndarray, np.ndarray]:
    """Each sample's stretch (start, travel; cycles, (n,)) from the previous sample's
    phase to its own (``before``: the previous call's last touch and phase); travel 0
    where the sample starts a touch (it plays its point value)."""
    start = np.empty_like(phase)
    start[1:] = phase[:-1]
    joined = np.empty(phase.size, dtype=bool)
    joined[1:] = touch[1:] == touch[:-1]
    if phase.size:
        start[0] = before[1] if before is not None else phase[0]
        joined[0] = before is not None and touch[0] == before[0]
    return start, np.where(joined, phase - start, 0.0)


@njit(cache=True, nogil=True)
def _deviation(phase, table):
    """D(phase) (cycles, any real) from ``table`` (D at MEAN_PHASES + 1 even steps over one
    period), linearly interpolated, as np.interp on that grid."""
    cells = table.size - 1
    at = (phase - math.floor(phase)) * cells
    i = min(int(at), cells - 1)
    w = at - i
    return table[i] + (table[i + 1] - table[i]) * w


@njit(cache=True, nogil=True)
def _box_row(start, travel, covers, point, table, mean_mu, lo, hi, mu):
    """One finger's row of :meth:`BandLimit.play_since` and
    :meth:`BandLimit.play_forward`, written to ``mu``: each covered sample whose stretch
    [start, start + travel] (cycles) is at least ``MIN_TRAVEL`` long, the
    box mean over it, within the profile's range [lo, hi]; the others ``point``, the
    profile at the sample's own phase."""
    for k in range(start.size):
        span = travel[k]
        if not (covers[k] and abs(span) >= MIN_TRAVEL):  # NaN fails too
            mu[k] = point[k]
            continue
        a = start[k] - math.floor(start[k])
        mean = mean_mu + (_deviation(a + span, table) - _deviation(a, table)) / span
        # within one band (a grating's, or any flat stretch) the difference rounds to the
        # band's level +- 1e-11 (|D| < 0.25 over |travel| >= 1/65536): play the level
        # a stretch starting on an edge has the lower band's point value and rounds to the
        # upper band's level +- 1e-16, which past 1 the inversion would count as a clamp
        mu[k] = point[k] if abs(mean - point[k]) < SNAP else min(max(mean, lo), hi)
