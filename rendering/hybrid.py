"""The hybrid renderer: SHT's synthesis, phase-locked to the measured position.

Seed 003 (section 6) leaves as future work "a joint control strategy unifying the
advantages of SHO and SHT". SHO (section 4.4.1) is aligned with what the screen shows
but, read at the touch rate, cannot render texture frequencies above half that rate;
SHT (section 4.4.2) synthesises the texture at the finger's speed with full bandwidth,
but its spatial phase starts anywhere at touch-down and drifts with every velocity
error, which the eye sees on coarse gratings.

The hybrid's phase (cycles) is SHT's velocity integral plus an offset::

    phase(t) = phase_v(t) + offset(t),   phase_v = integral of (v . axis) / period dt

(``rendering.sht.integrate_phase``, restarted at each touch). At touch-down the offset
puts the phase at the spatial phase of the measured position. At every new touch
measurement the *error* ``layer.phase_at(x_pred, y_pred) - phase`` is taken (the shorter
way round the cycle) and the offset works it off, never faster than ``SLIP`` times the
phase rate of the finger's own motion, i.e. the texture slides over the glass at most
0.9 times as fast as the finger moves, so the phase never runs backwards (no spurious
edges from prediction errors, which SHO-predicted shows as chatter):

- an error larger than ``LOCK_MM`` is a lost lock (the first samples of a touch, before
  the velocity is known; a reversal the velocity fit has not caught up with): it is
  worked off down to ``LOCK_MM`` whatever the texture;
- within ``LOCK_MM`` the error is worked off only where the lines pass slower than
  ``EVENT_HZ`` (coarse gratings, slow strokes, the ends of strokes): there each edge is
  felt as an event and its place is what matters. Where the texture is a vibration in
  the tactile band, a residual error under ``LOCK_MM`` is left alone, because correcting it
  would frequency-modulate the texture, while its phase cannot be felt (seed 003 section
  6: phase goes unnoticed once two periods fit under the fingerpad);
- a resting finger gets no correction at all: no texture appears under a still finger.

So the hybrid has SHT's spectrum on fine textures and SHO's alignment on coarse ones.

Between two measurements the error is constant (the prediction and phase_v advance at
the same velocity), so the offset is a ramp towards a constant, computed in closed form
per measurement (one scalar step per touch sample, not per output sample) and filled
in vectorised.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from rendering.sht import integrate_phase
from rendering.tracks import FingerBlock

#: fastest correction, as a fraction of the finger's own phase rate (below 1: the phase
#: never runs backwards)
SLIP = 0.9
#: a phase error beyond this (mm) is a lost lock, corrected whatever the texture
LOCK_MM = 0.1
#: temporal frequency (Hz) below which lines are events, not vibration: the tactile band's
#: lower edge (rendering.metrics.TACTILE_BAND_HZ)
EVENT_HZ = 10.0


@dataclass(frozen=True)
class _Finger:
    """One finger between calls: its touch, phase_v carry and offset (cycles, in [0, 1)),
    the target offset of its last measurement (cycles) and that measurement (held x,
    held y, phase rate) to tell whether the next call starts with a new one."""

    touch: int
    phase: float
    offset: float
    target: float
    measured: tuple[float, float, float]


@dataclass(frozen=True)
class HybridState:
    """Per finger id: its :class:`_Finger` record."""

    fingers: dict[int, _Finger]


def slew_offset(bounds: np.ndarray, target: np.ndarray, restart: np.ndarray, fast: np.ndarray,
                slow: np.ndarray, start: float, lock: float) -> tuple[np.ndarray, float]:
    """Offset (cycles) following a piecewise-constant target at a bounded rate.

    Parameters
    ----------
    bounds : (k,) increasing sample indices, the first 0, where the target takes a new value.
    target : (k,) target offset (cycles) from each bound on; only its value mod 1 matters.
    restart : (k,) bool, bounds where the offset jumps to the target (touch-down).
    fast, slow : (n + 1,) non-decreasing correction allowances (cycles) accumulated before
        each sample and, last, after the last one: while the error exceeds ``lock`` the
        offset may move by ``fast[j] - fast[i]`` between samples i and j, within ``lock``
        by the ``slow`` difference.
    start : offset before the first sample (cycles), used unless ``restart[0]``.
    lock : error (cycles) down to which the ``fast`` allowance applies.

    Returns
    -------
    offset : (n,) offset at each sample (cycles, not wrapped).
    end : offset after the last sample, wrapped to [0, 1).
    """
    k_n = bounds.size
    base, gap, far = [0.0] * k_n, [0.0] * k_n, [0.0] * k_n  # far: part of |gap| done fast
    switch = [0] * k_n  # allowance index from which the slow rate applies
    b_list = bounds.tolist()

    def done(j: int, i: int) -> float:
        """Correction (cycles, >= 0) of segment j by allowance index i."""
        quick = fast[i] - fast[b_list[j]]
        if quick < far[j]:
            return quick
        if switch[j] < 0:  # found lazily: most segments end before the fast part does
            switch[j] = b_list[j] if far[j] == 0.0 else min(
                int(np.searchsorted(fast, fast[b_list[j]] + far[j])), fast.size - 1)
        return far[j] + min(max(slow[i] - slow[switch[j]], 0.0), abs(gap[j]) - far[j])

    offset = start
    for k, (d, reset) in enumerate(zip(target.tolist(), restart.tolist())):
        if reset:
            offset = d
        elif k > 0:
            offset = base[k - 1] + math.copysign(done(k - 1, b_list[k]), gap[k - 1])
        g = (d - offset + 0.5) % 1.0 - 0.5
        base[k], gap[k], far[k], switch[k] = offset, g, max(abs(g) - lock, 0.0), -1
    n = fast.size - 1
    end = base[-1] + math.copysign(done(k_n - 1, n), gap[-1])
    base, gap, far = np.array(base), np.array(gap), np.array(far)
    switch = np.minimum(np.searchsorted(fast, fast[bounds] + far), n)
    first = np.zeros(n, dtype=bool)
    first[bounds] = True
    seg = np.cumsum(first) - 1
    quick = np.minimum(fast[:-1] - fast[bounds][seg], far[seg])
    worked = quick + np.clip(slow[:-1] - slow[switch][seg], 0.0, np.abs(gap[seg]) - far[seg])
    return base[seg] + np.copysign(worked, gap[seg]), float(np.mod(end, 1.0))


class HybridRenderer:
    """Phase-locked period synthesis of one periodic layer (grating or waveform)."""

    def __init__(self, layer, rate_hz: float, slip: float = SLIP, lock_mm: float = LOCK_MM,
                 event_hz: float = EVENT_HZ):
        if not 0.0 < slip < 1.0:
            raise ValueError(f"hybrid slip {slip!r}: expected a fraction in (0, 1) of the "
                             "finger's speed")
        self.layer = layer
        self.dt_s = 1.0 / rate_hz
        self.axis = layer.axis
        self.slip = float(slip)
        self.lock = lock_mm / layer.period_mm
        self.event_hz = float(event_hz)

    def initial_state(self) -> HybridState:
        return HybridState(fingers={})

    def render(self, block: FingerBlock, state: HybridState):
        """mu' (F, n) and coverage (F, n) under each finger, and the new state."""
        mu = np.empty((len(block.ids), block.n))
        carried = dict(state.fingers)
        ax, ay = self.axis
        for row, fid in enumerate(block.ids):
            before = carried.get(fid)
            touch = block.touch_id[row]
            restart = np.empty(block.n, dtype=bool)
            restart[0] = before is None or touch[0] != before.touch
            restart[1:] = touch[1:] != touch[:-1]
            rate = (block.vx[row] * ax + block.vy[row] * ay) / self.layer.period_mm
            phase_v, carry = integrate_phase(rate, self.dt_s, touch,
                                             None if before is None else (before.touch, before.phase))
            # a new measurement: a new touch, or the tracker's held sample or velocity changes
            measured = (block.x_held[row], block.y_held[row], rate)
            new = restart.copy()
            for m in measured:
                new[1:] |= m[1:] != m[:-1]
            new[0] |= before is None or tuple(float(m[0]) for m in measured) != before.measured
            bounds = np.flatnonzero(new)
            target = (self.layer.phase_at(block.x_pred[row, bounds], block.y_pred[row, bounds])
                      - phase_v[bounds])
            flags = restart[bounds]
            if bounds.size == 0 or bounds[0] != 0:  # the previous call's measurement holds
                bounds = np.concatenate(([0], bounds))
                target = np.concatenate(([before.target], target))
                flags = np.concatenate(([False], flags))
            travel = np.concatenate(([0.0], np.cumsum(np.abs(rate)))) * (self.slip * self.dt_s)
            as_event = np.abs(rate) < self.event_hz
            slow = np.concatenate(([0.0], np.cumsum(np.abs(rate) * as_event))) * (self.slip * self.dt_s)
            offset, end = slew_offset(bounds, target, flags, travel, slow,
                                      0.0 if before is None else before.offset, self.lock)
            carried[fid] = _Finger(touch=int(touch[-1]), phase=carry, offset=end,
                                   target=float(np.mod(target[-1], 1.0)),
                                   measured=tuple(float(m[-1]) for m in measured))
            mu[row] = self.layer.profile(phase_v + offset)
        covers = self.layer.covers(block.x_pred, block.y_pred)
        return mu, covers, HybridState(fingers=carried)
