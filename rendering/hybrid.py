"""The hybrid renderer: SHT's synthesis, phase-locked to the measured position.

Seed 003 (section 6) leaves as future work "a joint control strategy unifying the
advantages of SHO and SHT". SHO (section 4.4.1) is aligned with what the screen shows
but, read at the touch rate, cannot render texture frequencies above half that rate;
SHT (section 4.4.2) synthesises the texture at the finger's speed with full bandwidth,
but its spatial phase starts anywhere at touch-down and drifts with every velocity
error, which the eye sees on coarse gratings.

The hybrid's phase (cycles) is a velocity integral plus an offset::

    phase(t) = phase_v(t) + offset(t),   phase_v = integral of v_s / period dt

(``rendering.sht.integrate_phase``, restarted at each touch), with ``v_s`` the
tracker's velocity along the texture's axis, smoothed (:func:`smooth_rate`): a new
estimate that differs from the current one by less than ``VELOCITY_NOISE_MM_S`` (the
scatter a 50 ms line fit through 0.05 mm touch noise gives between successive 50 Hz
samples, ~2.5 mm/s rms, times three) is noise and is averaged in with weight
``SMOOTH``; a larger change is a real acceleration and is taken at once. SHT's
frequency jitters with every estimate (9 % rms at 20 mm/s); the hybrid's less, so on
constant-speed strokes its spectrum is cleaner than SHT's, and the lag the averaging
could add is the phase lock's to remove.

At touch-down, and at the first measurement after the tracker knew no velocity (the
start of a swipe, before two samples exist; a finger that rested past the prediction
horizon), the offset puts the phase at the spatial phase of the measured position: the
finger has just started from rest, and synthesis starts where it is. At every other
new touch measurement the *error* ``layer.phase_at(x_pred, y_pred) - phase`` is taken
(the shorter way round the cycle) and the offset works it off, never faster than
``SLIP`` times the phase rate of the finger's own motion, i.e. the texture slides over
the glass at most 0.9 times as fast as the finger moves, so the phase never runs
backwards (no spurious edges from prediction errors, which SHO-predicted shows as
chatter):

- an error larger than ``LOCK_MM`` is a lost lock (a reversal the velocity fit has not
  caught up with): it is worked off down to ``LOCK_MM`` whatever the texture;
- within ``LOCK_MM`` the error is worked off only where the lines pass slower than
  ``EVENT_HZ`` (coarse gratings, slow strokes, the ends of strokes): there each edge is
  felt as an event and its place is what matters. Where the texture is a vibration in
  the tactile band, a residual error under ``LOCK_MM`` is left alone, because correcting it
  would frequency-modulate the texture, while its phase cannot be felt (seed 003 section
  6: phase goes unnoticed once two periods fit under the fingerpad);
- a resting finger gets no correction at all: no texture appears under a still finger.

So the hybrid has SHT's bandwidth on fine textures and SHO's alignment on coarse ones.

The error is taken once per measurement and the offset ramps towards it at the bounded
rate, computed in closed form per measurement (one scalar step per touch sample, not
per output sample) and filled in vectorised.

What it cannot do (measured by ``frictex report --quick``, 50 Hz touch, human-like
motion): beat plain SHO's time error on the 0.6 mm grating (1.23 against 1.16; SHT
1.27). There the time error measures a phase the finger cannot feel. While the finger
moves, every renderer's phase is as good as random there: 0.2 s windows score 1.3-1.6
(sqrt(2) = 1.41 for the right texture at an unrelated phase) for SHO, SHT and the
hybrid alike, because 50 Hz samples with 0.05 mm noise, extrapolated over up to 20 ms
of a minimum-jerk stroke, are 0.1-0.3 mm off: a third of a period or more. SHO-held
gains only during the pauses, where it reads the resting position (time error 0 there)
while a synthesis, which renders no texture under a still finger, keeps the phase the
stroke ended with. Following each measurement as SHO-predicted does reaches 0.92 and
is still above the 30 % target (0.89) while its jumps would cost the hybrid the clean
spectrum the 0.6 mm grating is about (spectral error 0.54 against the hybrid's 0.5).
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
#: velocity changes (mm/s) smaller than this between two estimates are touch noise ...
VELOCITY_NOISE_MM_S = 8.0
#: ... and are averaged in with this weight (1 would be SHT's unsmoothed velocity)
SMOOTH = 0.5


@dataclass(frozen=True)
class _Finger:
    """One finger between calls: its touch, phase_v carry and offset (cycles, in [0, 1)),
    the target offset of its last measurement (cycles), that measurement (held x, held y,
    the tracker's phase rate) to tell whether the next call starts with a new one, the
    smoothed phase rate (cycles/s) and |vx| + |vy| (mm/s) at the last sample (only ever
    compared with 0: at rest or moving)."""

    touch: int
    phase: float
    offset: float
    target: float
    measured: tuple[float, float, float]
    smoothed: float
    speed: float


@dataclass(frozen=True)
class HybridState:
    """Per finger id: its :class:`_Finger` record."""

    fingers: dict[int, _Finger]


def slew_offset(bounds: np.ndarray, target: np.ndarray, restart: np.ndarray, snap: np.ndarray,
                fast: np.ndarray, slow: np.ndarray, start: float, lock: float
                ) -> tuple[np.ndarray, float]:
    """Offset (cycles) following a piecewise-constant target at a bounded rate.

    Parameters
    ----------
    bounds : (k,) increasing sample indices, the first 0, where the target takes a new value.
    target : (k,) target offset (cycles) from each bound on; only its value mod 1 matters.
    restart : (k,) bool, bounds where the offset jumps to the target (touch-down).
    snap : (k,) bool, bounds where it jumps to the target if the error exceeds ``lock``
        (the finger starts from rest: nothing slides under it to slew against).
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
    for k, (d, reset, jump) in enumerate(zip(target.tolist(), restart.tolist(), snap.tolist())):
        if reset:
            offset = d
        elif k > 0:
            offset = base[k - 1] + math.copysign(done(k - 1, b_list[k]), gap[k - 1])
        g = (d - offset + 0.5) % 1.0 - 0.5
        if jump and abs(g) > lock:
            offset, g = d, 0.0
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


def smooth_rate(rate: np.ndarray, restart: np.ndarray, period_mm: float,
                start: tuple[float, float] | None, noise_mm_s: float = VELOCITY_NOISE_MM_S,
                weight: float = SMOOTH) -> tuple[np.ndarray, float]:
    """The tracker's phase rate with its estimate-to-estimate noise averaged out.

    At every new estimate (a sample where ``rate`` changes) the smoothed rate moves
    ``weight`` of the way to it if the two differ by less than ``noise_mm_s`` (along the
    texture's axis), else takes it: a real acceleration is followed at once. A new touch
    and a rate of 0 (no velocity known, finger resting) start afresh.

    Parameters
    ----------
    rate : (n,) the tracker's phase rate (cycles/s).
    restart : (n,) bool, samples where a new touch starts.
    period_mm : the texture's period (mm), to compare rates as speeds.
    start : (last tracker rate, smoothed rate) carried from the previous call, or None.
    noise_mm_s : speed difference (mm/s) below which a change is noise.
    weight : weight of a new estimate that is noise, in (0, 1].

    Returns
    -------
    smoothed : (n,) cycles/s. end : smoothed rate after the last sample.
    """
    last, value = start if start is not None else (0.0, 0.0)
    change = np.empty(rate.size, dtype=bool)
    change[0] = start is None or rate[0] != last or restart[0]
    change[1:] = (rate[1:] != rate[:-1]) | restart[1:]
    at = np.flatnonzero(change)
    values = [value]
    limit = noise_mm_s / period_mm
    for r, fresh in zip(rate[at].tolist(), restart[at].tolist()):
        if fresh or r == 0.0 or value == 0.0 or abs(r - value) >= limit:
            value = r
        else:
            value += weight * (r - value)
        values.append(value)
    runs = np.diff(np.concatenate(([0], at, [rate.size])))
    return np.repeat(np.array(values), runs), value


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
            measured_rate = (block.vx[row] * ax + block.vy[row] * ay) / self.layer.period_mm
            rate, smoothed = smooth_rate(measured_rate, restart, self.layer.period_mm,
                                         None if before is None else (before.measured[2], before.smoothed))
            phase_v, carry = integrate_phase(rate, self.dt_s, touch,
                                             None if before is None else (before.touch, before.phase))
            # a new measurement: a new touch, or the tracker's held sample or velocity changes
            measured = (block.x_held[row], block.y_held[row], measured_rate)
            new = restart.copy()
            for m in measured:
                new[1:] |= m[1:] != m[:-1]
            new[0] |= before is None or tuple(float(m[0]) for m in measured) != before.measured
            bounds = np.flatnonzero(new)
            target = (self.layer.phase_at(block.x_pred[row, bounds], block.y_pred[row, bounds])
                      - phase_v[bounds])
            # synthesis starts where the finger is: at touch-down and when it starts from rest
            # only ever compared with 0: |vx| + |vy| is zero exactly when the speed is
            speed = np.abs(block.vx[row]) + np.abs(block.vy[row])
            was_still = np.concatenate(([0.0 if before is None else before.speed], speed[:-1])) == 0.0
            flags = restart[bounds]
            starts = was_still[bounds] & (speed[bounds] > 0.0)
            if bounds.size == 0 or bounds[0] != 0:  # the previous call's measurement holds
                bounds = np.concatenate(([0], bounds))
                target = np.concatenate(([before.target], target))
                flags = np.concatenate(([False], flags))
                starts = np.concatenate(([False], starts))
            travel = np.concatenate(([0.0], np.cumsum(np.abs(rate)))) * (self.slip * self.dt_s)
            as_event = np.abs(rate) < self.event_hz
            slow = np.concatenate(([0.0], np.cumsum(np.abs(rate) * as_event))) * (self.slip * self.dt_s)
            offset, end = slew_offset(bounds, target, flags, starts, travel, slow,
                                      0.0 if before is None else before.offset, self.lock)
            carried[fid] = _Finger(touch=int(touch[-1]), phase=carry, offset=end,
                                   target=float(np.mod(target[-1], 1.0)),
                                   measured=tuple(float(m[-1]) for m in measured),
                                   smoothed=smoothed, speed=float(speed[-1]))
            mu[row] = self.layer.profile(phase_v + offset)
        covers = self.layer.covers(block.x_pred, block.y_pred)
        return mu, covers, HybridState(fingers=carried)
