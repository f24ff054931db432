"""SHT, the surface haptic texture (seed 003, section 4.4.2): one spatial period
replayed at the rate the finger's velocity sets.

The spatial phase (cycles) advances by (v . axis) / period per second: the velocity
projected on the texture's axis (across its lines) over the period. It is integrated
sample by sample (a cumulative sum of phase increments), wrapped to [0, 1) and carried
to the next call, so its error does not grow with time: float64 increments of at most
a few hundredths of a cycle keep a one-hour integral within ~1e-9 cycle (see
tests/test_sht.py). A new touch (down, or a jump) restarts the phase at 0: plain SHT
does not know where the finger landed (the seed's stated drawback; the hybrid renderer
fixes it). The layer's region gates the output at the predicted finger position.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from numba import njit

from rendering.tracking.tracks import FingerBlock


@dataclass(frozen=True)
class ShtState:
    """Per finger: the touch the phase belongs to and the wrapped phase (cycles)."""

    phase: dict[int, tuple[int, float]]


def integrate_phase(rate_cycles: np.ndarray, dt_s: float, touch_id: np.ndarray,
                    start: tuple[int, float] | None) -> tuple[np.ndarray, float]:
    """Phase (cycles, unwrapped within the call) at each sample, and the wrapped carry.

    Parameters
    ----------
    rate_cycles : (n,) phase rate (cycles/s) in effect from each sample to the next.
    dt_s : output sample period (s).
    touch_id : (n,) touch identifier; the phase restarts at 0 where it changes.
    start : (touch_id, phase) carried from the previous call, or None.

    Returns
    -------
    phase : (n,) phase at each sample. carry : phase after the last sample, in [0, 1).
    """
    rate = np.ascontiguousarray(rate_cycles, dtype=np.float64)
    phase = np.empty(rate.size)
    prev_id, prev_phase = start if start is not None else (0, 0.0)
    carry = phase_kernel(rate, float(dt_s), np.ascontiguousarray(touch_id, dtype=np.int64),
                         start is not None, int(prev_id), float(prev_phase), phase)
    return phase, carry


@njit(cache=True, nogil=True)
def phase_kernel(rate, dt_s, touch, has_start, prev_id, prev_phase, phase):
    """:func:`integrate_phase`'s loop, writing ``phase`` (n,) and returning the carry.

    The phase before sample k is the running sum of ``rate * dt_s`` over the samples
    before it (the same sums, in the same order, as ``np.cumsum``) minus the sum at the
    touch's first sample in this call; a touch carried in from the previous call
    (``has_start`` and the same ``prev_id``) starts at ``prev_phase`` instead.
    """
    n = rate.size
    base = -prev_phase if has_start and n > 0 and touch[0] == prev_id else 0.0
    acc = 0.0  # sum of rate * dt before sample k
    for k in range(n):
        if k > 0 and touch[k] != touch[k - 1]:
            base = acc
        phase[k] = acc - base
        acc += rate[k] * dt_s
    return (acc - base) % 1.0


class ShtRenderer:
    """Period synthesis of one periodic layer (grating or waveform)."""

    def __init__(self, layer, rate_hz: float):
        self.layer = layer
        self.dt_s = 1.0 / rate_hz
        self.axis = np.array(layer.axis)

    def initial_state(self) -> ShtState:
        return ShtState(phase={})

    def render(self, block: FingerBlock, state: ShtState):
        """mu' (F, n) and coverage (F, n) under each finger, and the new state."""
        mu = np.empty((len(block.ids), block.n))
        carried = {fid: state.phase[fid] for fid in block.ids if fid in state.phase}
        ax, ay = self.axis
        for row, fid in enumerate(block.ids):
            rate = (block.vx[row] * ax + block.vy[row] * ay) / self.layer.period_mm
            phase, carry = integrate_phase(rate, self.dt_s, block.touch_id[row], carried.get(fid))
            carried[fid] = (int(block.touch_id[row, -1]), carry)
            mu[row] = self.layer.profile(phase)
        covers = self.layer.covers(block.x_pred, block.y_pred)
        return mu, covers, ShtState(phase=carried)
