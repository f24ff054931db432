"""The hybrid renderer: SHT's synthesis, phase-locked to the finger filter's position.

Seed 003 (section 6) leaves as future work "a joint control strategy unifying the
advantages of SHO and SHT". SHO (section 4.4.1) is aligned with what the screen shows
but, read at the touch rate, cannot render texture frequencies above half that rate;
SHT (section 4.4.2) synthesises the texture at the finger's speed with full bandwidth,
but its spatial phase starts anywhere at touch-down and drifts with every velocity
error, which the eye sees on coarse gratings.

The hybrid's phase (cycles) is a velocity integral plus an offset::

    phase(t) = phase_v(t) + offset(t),   phase_v = integral of v_s / period dt

(``rendering.layers.sht.integrate_phase``, restarted at each touch), with ``v_s`` the
finger's velocity along the texture's axis, and the offset locked to the finger's
position along that axis, both estimated by the finger model between touch samples
(``rendering.layers.finger_filter``: a steady and a manoeuvring constant-velocity
Kalman filter, weighed by how well each predicts the touch samples). The tracker's
velocity (a line through the last two or three 50 Hz samples) both jitters (1.8-3.5
mm/s rms through 0.05 mm touch noise: SHT's frequency jitters with it) and lags an
accelerating finger by one sample interval; the filter averages the noise out where
the finger moves steadily and follows an acceleration within a sample or two. Against
the velocity smoothing it replaced (estimate-to-estimate changes under 6 mm/s averaged
in with weight 0.5, larger ones taken at once), on the report's draws (16 of each,
50 Hz; ``rendering/RENDERERS.md``): human-like strokes, 5 mm grating time / spectral
error 0.382 / 0.245 -> 0.354 / 0.213 (SHO-predicted 0.371 / 0.245), edges felt twice
47 -> 26; 15 mm 0.199 / 0.162 -> 0.185 / 0.134; 0.6 mm spectral 0.524 -> 0.460 (SHT
0.527; before the lost-lock gate below: 0.447 with it); slow swipes, 5 mm 0.272 / 0.111
-> 0.259 / 0.100.

Coarse layers (period at least ``COARSE_MM``) are position-locked: at each new
measurement of a moving finger any error ahead, in the finger's direction, and an error
up to ``BACK_MM`` behind are taken at once; synthesis fills in between samples. There
the touch noise and the 50 Hz prediction error (0.05-0.3 mm) are a few per cent of a
period at most, so a jump is a small shift of an edge, while slewing it off left the
rendered phase 0.2-0.6 mm behind the finger through every acceleration of a 60 mm/s
stroke: over 16 human-like draws the 15 mm grating's time error was 0.213 slewed and
0.174 locked (SHO-predicted: 0.171). ``BACK_MM`` is 2 mm because a flick leaves the
prediction millimetres behind: on 16 draws of ``human-varied`` strokes (flicks,
creeping, arcs) the 15 mm grating's time error was 0.218 with 1 mm, 0.213 with 2 mm,
0.212 with 4 mm (SHO-predicted 0.208; these with the velocity smoothing of the time).

No chatter (the hold). A jump ahead never adds an edge (the phase skips forward); a
jump back can cross a line the phase passed a moment early, and the finger then feels
that edge three times within a few ms (early, back, and again when it gets there):
*chatter*, ``rendering.metrics.chatter``. SHO-predicted does this at every touch sample
of a finger slower than predicted; on the refdata tablet two-finger drag the hybrid did
it 10 times in 1.5 s on the 15 mm grating. The model behind the rule: a finger moving
one way goes on moving that way between two touch samples (minimum-jerk strokes turn
back only through a stop, ``rendering/RENDERERS.md``), so a measurement a little behind
the rendered phase says the phase is early, not that the finger went back. Such an
error, one the finger's own motion covers within ``HOLD_S`` (20 ms, one 50 Hz touch
interval: at the filtered phase rate, ``|error| <= |rate| HOLD_S``), is *held*: the
offset works it off at exactly the finger's phase rate, so the phase stands still until
the finger has caught up and then moves on with it; an edge crossed early stays crossed
(felt up to 20 ms early instead of three times). Corrections never run the phase
backwards except on a lost lock: a larger error behind (the finger stopped short of
where the velocity fit carried the phase, crawls, or turned back: a reversal is the
error growing faster than the finger's own speed can cover) is taken at once up to
``BACK_MM`` or worked off at the relock speed below, because there the finger will not
get to the phase soon. Taken at once is the part beyond what the finger covers within
``HOLD_S``; that part is held as above, so the phase goes back only to where the finger
will be one touch interval on. Taking all of it made the rule jump at the hold's edge:
an error 5 um beyond it undid the edge the finger was 0.2 mm from (the out-and-back
stroke of ``tests/test_fidelity_motion.py``, draw 4: at 0.52 s the filter's velocity
fell from 31 to 14.6 mm/s, 0.292 mm in 20 ms, against an error of 0.297 mm; the line
at 45 mm was felt early, undone and felt again 15 ms later). On the report's
human-like draws (16) this took the 5 mm grating's edges felt twice from 26 to 17,
time / spectral error 0.354 / 0.213 -> 0.356 / 0.212; nothing else changed. Measured
on the report's draws (8 of each, 50 Hz, 0.05 mm noise; without the hold -> with it):
edges felt twice on a 20 mm/s swipe, 15 mm 20 -> 0, 5 mm 46 -> 0; on human-like strokes
15 mm 4 -> 0, 5 mm 59 -> 19 (the rest at flick stops,
where the error outgrows 20 ms of the lagging velocity fit; SHO-predicted 4 and 58); the
slow swipe's alignment error 0.35 -> 0.035 mm (15 mm) and 0.15 -> 0.07 mm (5 mm). The
price is the time the early band is felt: human-like time error 0.188 -> 0.189 (15 mm)
and 0.362 -> 0.373 (5 mm; SHO-predicted 0.358), which is why ``HOLD_S`` is one touch
interval and not more (50 ms: 0.195 and 0.381). Leaving errors within the touch noise
(under 0.06-0.15 mm, whatever the speed) to a hold or a slew instead removed less chatter
and cost more (0.15 mm: 5 mm time error 0.376, 44 edges felt twice). On a fine layer
the same jumps would be a third of a period: there the slew below stays (locking them
doubled the 0.6 mm grating's spectral error on a constant-speed swipe, 0.12 to 0.24).
``rendering/RENDERERS.md`` states the finger model behind the prediction.

At touch-down, and at the first measurement after the tracker knew no velocity (the
start of a swipe, before two samples exist; a finger that rested past the prediction
horizon), the offset puts the phase at the spatial phase of the measured position: the
finger has just started from rest, and synthesis starts where it is. At every other
new touch measurement the *error* between the spatial phase of the filter's position
along the layer's axis (``s_mm``) and ``phase`` is taken
(the shorter way round the cycle; on coarse layers less the part the position lock
above takes at once) and the offset works it off, in general never faster
than ``SLIP`` times the phase rate of the finger's own motion, i.e. the texture slides
over the glass at most 0.9 times as fast as the finger moves, so the phase does not run
backwards (no spurious edges from prediction errors, which SHO-predicted shows as
chatter):

- an error larger than ``LOCK_MM`` and than ``GATE_SIGMAS`` standard deviations of the
  finger filter's own position correction at that measurement (``finger_filter``'s
  ``sd``: the textbook 99 % validation gate, |innovation| > 2.576 sqrt(P + r), stated
  for the correction P / (P + r) x innovation) is a lost lock (a reversal the velocity
  fit has not caught up with, or a stop it overshot: a 50 ms line fit lags a
  decelerating finger). A smaller one is what the filter's own noise explains (its
  estimate moves by as much from sample to sample while the lock holds): correcting it
  at up to 0.9 times the phase rate frequency-modulates a fine texture (a burst near
  twice its frequency early in every touch, where the gate is widest) for a phase the
  finger does not feel. A lost lock is worked off down to that threshold whatever the
  texture, and at no less than ``SLIP * RELOCK_MM_S`` (18 mm/s) while the finger moves
  at all. Below that speed the
  phase may run backwards: a finger that crawls or rests (the screen still reporting
  it) 0.5 mm past a 15 mm grating's line would otherwise feel the wrong band for as
  long as it stays (0.6 s in one of the report's seed-scatter draws), the error the eye
  catches first;
- within that threshold the error is worked off only where the lines pass slower than
  ``EVENT_HZ`` (coarse gratings, slow strokes, the ends of strokes): there each edge is
  felt as an event and its place is what matters. Where the texture is a vibration in
  the tactile band, a residual error under the threshold is left alone, because correcting it
  would frequency-modulate the texture, while its phase cannot be felt (seed 003 section
  6: phase goes unnoticed once two periods fit under the fingerpad);
- a resting finger gets no correction at all: no texture appears under a still finger.

The gate is 0.2 mm on a steady 50 Hz swipe, 0.35-0.48 mm in its first samples, and on
human-like strokes 0.26 mm typically, up to 0.65, so on a 0.6 mm grating (no error
exceeds 0.3 mm the shorter way round) a lock is seldom found lost: on the report's
draws its spectral error fell on every kind of motion (fast swipes 0.131 -> 0.122, SHT
0.133), and its phase, which no finger feels there, wandered further (time error 1.20
-> 1.29 on human-like strokes, 0.61 -> 0.89 on slow swipes; alignment 0.15 -> 0.17 and
0.03 -> 0.06 mm). Coarse layers take or hold their errors by the position lock above
before this rule is reached: their figures did not change (``rendering/RENDERERS.md``).

So the hybrid has SHT's bandwidth on fine textures and SHO's alignment on coarse ones.
As SHT does, each sample plays the profile's mean over the phase interval from the
previous sample's phase to its own, and above the output's Nyquist frequency the
texture's mean instead of an alias, counted in ``clipped`` (``rendering.layers.band_limit``).

The error is taken once per measurement and the offset ramps towards it at the bounded
rate, computed in closed form per measurement. The whole per-finger recurrence
(phase integration, measurements, slew; the filter is a pass of its own) is one compiled pass over the block
(numba, ``_hybrid_row``): a Python loop per measurement, or some sixty numpy passes,
cost several times more at 10 kHz and dominated a 5 ms live block.

What it cannot do (``frictex report`` and ``rendering/RENDERERS.md``, 50 Hz touch,
human-like motion): get the 0.6 mm grating's phase right while the finger moves. There
the time error measures a phase the finger cannot feel (seed 003 section 6): 50 Hz
samples with 0.05 mm noise, extrapolated over up to 20 ms of a minimum-jerk stroke, are
0.1-0.3 mm off, a third of a period or more. On that grating the hybrid's spectrum is
below SHT's (0.447 against 0.527 over 16 human-like draws, with the lost-lock gate), far below SHO's 0.94; on
the 15 and 5 mm gratings its mean time and spectral errors are below SHO-predicted's
(over 16 draws: -4.6 % and -18 % at 15 mm, -4.0 % and -13 % at 5 mm), far below plain
SHO's and SHT's, and it feels far fewer edges twice than SHO-predicted (0 against 16 at
15 mm, 17 against 107 at 5 mm).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from frictex.device.jit import njit
from frictex.rendering.layers.band_limit import BandLimit
from frictex.rendering.layers.finger_filter import filter_axis
from frictex.rendering.tracking.tracks import FingerBlock

#: fastest correction, as a fraction of the finger's own phase rate (below 1: the phase
#: does not run backwards), but see RELOCK_MM_S
SLIP = 0.9
#: a phase error beyond this (mm) is a lost lock, corrected whatever the texture, if it
#: is also beyond what the finger filter's own uncertainty explains (see GATE_SIGMAS)
LOCK_MM = 0.1
#: ... that is, beyond this many standard deviations of the filter's position correction
#: at the measurement (``rendering.layers.finger_filter.filter_axis``, ``sd``): the 99 %
#: point of a normal error either way, sqrt of chi-square's with one degree of freedom
#: (6.635), the usual validation gate of a tracking filter
GATE_SIGMAS = 2.576
#: a lost lock is worked off at least at SLIP times this speed (mm/s) while the finger
#: moves, however slowly
RELOCK_MM_S = 20.0
#: temporal frequency (Hz) below which lines are events, not vibration: the tactile band's
#: lower edge (rendering.metrics.TACTILE_BAND_HZ)
EVENT_HZ = 10.0
#: layers of at least this period (mm) are position-locked (see the module docstring) ...
COARSE_MM = 2.0
#: ... where an error against the finger's direction up to this (mm) is taken at once,
BACK_MM = 2.0
#: ... unless the finger's own motion covers it within this (s): then the phase holds
#: still until the finger has caught up (no edge crossed back, see the module docstring)
HOLD_S = 0.02


@dataclass(frozen=True)
class _Finger:
    """One finger between calls: its touch, phase_v carry and offset (cycles, in [0, 1)),
    the target offset of its last measurement (cycles), that measurement (held x, held y,
    the tracker's phase rate) to tell whether the next call starts with a new one,
    |vx| + |vy| (mm/s) at the last sample (only ever compared with 0: at rest or
    moving), 1.0 if the last measurement's error is being held (see ``HOLD_S``), else
    0.0, and the finger filter's state (``rendering.layers.finger_filter.filter_axis``)."""

    touch: int
    phase: float
    offset: float
    target: float
    measured: tuple[float, float, float]
    speed: float
    held: float
    filter: tuple


@dataclass(frozen=True)
class HybridState:
    """Per finger id of the last block's tracks (``FingerBlock.ids``: the fingers
    touching, and those that lifted in it): its :class:`_Finger` record; and the touching
    samples played as the texture's mean so far (``rendering.layers.band_limit``)."""

    fingers: dict[int, _Finger]
    clipped: int = 0


def slew_offset(bounds: np.ndarray, target: np.ndarray, restart: np.ndarray, snap: np.ndarray,
                fast: np.ndarray, slow: np.ndarray, start: float, lock: float | np.ndarray,
                jump: np.ndarray | None = None, back: float = 0.0,
                hold: np.ndarray | None = None, travel: np.ndarray | None = None
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
    lock : error (cycles) down to which the ``fast`` allowance applies: one for every
        bound, or (k,) one per bound.
    jump : (k,) the position lock (see the module docstring) at each bound: +1 or -1, the
        direction (phase rate's sign) the finger moves in, 0 where it does not apply; an
        error that way is taken at once, one the other way if at most ``back``.
        None: nowhere.
    back : largest error (cycles) against the finger's direction taken at once.
    hold : (k,) at each bound the largest error (cycles) against the finger's direction
        that is held instead: the offset follows the ``travel`` allowance, so that the
        phase stands still until the finger has caught up; of a larger one up to
        ``back`` the part beyond ``hold`` is taken at once and the rest held.
        None: nowhere.
    travel : (n + 1,) the finger's own phase travel (cycles) accumulated before each
        sample and, last, after the last one; needed with ``hold``.

    Returns
    -------
    offset : (n,) offset at each sample (cycles, not wrapped).
    end : offset after the last sample, wrapped to [0, 1).
    """
    fast = np.ascontiguousarray(fast, dtype=np.float64)
    offset = np.empty(fast.size - 1)
    end = _slew_kernel(np.ascontiguousarray(bounds, dtype=np.int64),
                       np.ascontiguousarray(target, dtype=np.float64),
                       np.ascontiguousarray(restart, dtype=np.bool_),
                       np.ascontiguousarray(snap, dtype=np.bool_), fast,
                       np.ascontiguousarray(slow, dtype=np.float64), float(start),
                       np.ascontiguousarray(np.broadcast_to(np.asarray(lock, dtype=np.float64),
                                                            (len(bounds),))),
                       np.zeros(len(bounds)) if jump is None
                       else np.ascontiguousarray(jump, dtype=np.float64), float(back),
                       np.zeros(len(bounds)) if hold is None
                       else np.ascontiguousarray(hold, dtype=np.float64),
                       np.zeros(fast.size) if travel is None
                       else np.ascontiguousarray(travel, dtype=np.float64), False, offset,
                       np.empty(offset.size))
    return offset, end[0]


@njit(cache=True, nogil=True)
def _slew_kernel(bounds, target, restart, snap, fast, slow, start, lock, jump, back, hold,
                 travel, held_before, offset, reach):
    """:func:`slew_offset` in one pass: writes ``offset`` (n,) and ``reach`` (n,), where
    each sample's correction takes the offset by the next sample (before anything decided
    there), returns the wrapped end and whether the last segment is held.

    Per segment (bounds[k] to the next bound) the error ``gap`` to its target is taken at
    its first sample, less at once the part of one behind beyond ``hold`` (up to ``back``);
    a held gap is worked off at the ``travel`` allowance; otherwise
    ``far = |gap| - lock`` of it (if positive) at the ``fast`` allowance, the rest at the
    ``slow`` one from index ``switch`` on, the first allowance index where the fast part
    is done; ``lock`` (k,) is the segment's. ``held_before``: the first segment continues
    a held one (the previous call's last; its ``jump`` is 0, so nothing is decided again).
    """
    k_n = bounds.size
    n = fast.size - 1
    base = gap = far = 0.0
    b = switch = 0
    held = False
    value = start
    for k in range(k_n):
        d = target[k]
        if restart[k]:
            value = d
        elif k > 0:  # where the previous segment got to by this bound
            value = base + math.copysign(
                _worked_off(fast, slow, travel, b, bounds[k], far, gap, held), gap)
        g = (d - value + 0.5) % 1.0 - 0.5
        held = held_before and k == 0 and not restart[k]
        if (snap[k] and abs(g) > lock[k]) or (jump[k] != 0.0 and g * jump[k] > 0.0):
            value, g = d, 0.0
        elif jump[k] != 0.0 and abs(g) <= max(hold[k], back):  # behind: beyond the hold at once
            excess = math.copysign(max(abs(g) - hold[k], 0.0), g)
            value, g, held = value + excess, g - excess, True
        base, gap, b = value, g, bounds[k]
        far = 0.0 if held else max(abs(g) - lock[k], 0.0)
        switch = min(np.searchsorted(fast, fast[b] + far), n)
        rest = abs(g) - far
        for i in range(b, bounds[k + 1] if k + 1 < k_n else n):
            offset[i] = base + math.copysign(
                _segment_worked(fast, slow, travel, b, i, far, rest, switch, held), g)
            reach[i] = base + math.copysign(
                _segment_worked(fast, slow, travel, b, i + 1, far, rest, switch, held), g)
    wrapped = (base + math.copysign(_worked_off(fast, slow, travel, b, n, far, gap, held), gap)) % 1.0
    return wrapped, held


@njit(cache=True, nogil=True)
def _segment_worked(fast, slow, travel, b, i, far, rest, switch, held):
    """Correction (cycles, >= 0) of the segment starting at ``b`` by allowance index ``i``:
    a held one at the ``travel`` allowance up to ``rest``, otherwise ``far`` at the
    ``fast`` one and then ``rest`` at the ``slow`` one from index ``switch`` on."""
    if held:
        return min(travel[i] - travel[b], rest)
    return min(fast[i] - fast[b], far) + min(max(slow[i] - slow[switch], 0.0), rest)


@njit(cache=True, nogil=True)
def _worked_off(fast, slow, travel, b, i, far, gap, held):
    """Correction (cycles, >= 0) of the segment starting at ``b`` by allowance index ``i``."""
    if held:
        return min(travel[i] - travel[b], abs(gap))
    quick = fast[i] - fast[b]
    if quick < far:
        return quick
    switch = b if far == 0.0 else min(np.searchsorted(fast, fast[b] + far), fast.size - 1)
    return far + min(max(slow[i] - slow[switch], 0.0), abs(gap) - far)


# The phase accumulator of SHT (rendering.layers.sht) as well: it lives beside
# _hybrid_row, which compiles it in, because numba's cache sees changes to the cached
# kernel's own file only (tests/test_numba_cache.py).
def integrate_phase(rate_cycles: np.ndarray, dt_s: float, touch_id: np.ndarray,
                    start: tuple[int, float] | None, steps: np.ndarray | None = None
                    ) -> tuple[np.ndarray, float]:
    """Phase (cycles, in [0, 1)) at each sample, and the carry.

    Parameters
    ----------
    rate_cycles : (n,) phase rate (cycles/s) in effect from each sample to the next; a
        non-finite one is taken as 0 (the phase holds).
    dt_s : output sample period (s).
    touch_id : (n,) touch identifier; the phase restarts at 0 where it changes.
    start : (touch_id, phase) carried from the previous call, or None.
    steps : (n,) array to receive each sample's own phase increment (cycles, unwrapped:
        the stretch the finger crosses while the sample is held), or None.

    Returns
    -------
    phase : (n,) phase at each sample, in [0, 1). carry : phase after the last sample, in
    [0, 1).
    """
    rate = np.ascontiguousarray(rate_cycles, dtype=np.float64)
    phase = np.empty(rate.size)
    prev_id, prev_phase = start if start is not None else (0, 0.0)
    carry = phase_kernel(rate, float(dt_s), np.ascontiguousarray(touch_id, dtype=np.int64),
                         start is not None, int(prev_id), float(prev_phase), phase,
                         np.empty(rate.size) if steps is None else steps)
    return phase, carry


@njit(cache=True, nogil=True)
def phase_kernel(rate, dt_s, touch, has_start, prev_id, prev_phase, phase, steps):
    """:func:`integrate_phase`'s loop, writing ``phase`` (n,) and each sample's phase
    increment ``steps`` (n,, cycles), and returning the carry.

    The phase is a running sum of ``rate * dt_s`` from 0 at the touch's first sample (a
    touch carried in from the previous call, ``has_start`` and the same ``prev_id``,
    goes on from ``prev_phase``), wrapped to [0, 1) after each step. Each sample's phase
    then comes from the same operations however the samples are split into calls, so a
    replay's result does not depend on its chunk size (a sum restarted at each call and
    wrapped only at its end flipped 19 of 20,050 samples at a 5 mm grating's edges
    between one block per call and the default), and the sum never leaves [0, 1), where
    a step's rounding is at most 5.6e-17 cycles however long the touch. A non-finite
    rate steps 0: one NaN must not spoil the rest of the touch through the carry.
    """
    n = rate.size
    acc = prev_phase if has_start and n > 0 and touch[0] == prev_id else 0.0
    for k in range(n):
        if k > 0 and touch[k] != touch[k - 1]:
            acc = 0.0
        phase[k] = acc
        steps[k] = rate[k] * dt_s if math.isfinite(rate[k]) else 0.0
        acc += steps[k]
        acc -= math.floor(acc)
        if acc >= 1.0:  # a step just below 0 wraps to 1 - 1e-17, which rounds to 1.0
            acc = 0.0
    return acc


@njit(cache=True, nogil=True)
def _hybrid_row(touch, vx, vy, x_held, y_held, x_pred, y_pred, s_mm, v_mm_s, sd_mm,
                has_before, before, axis, layer_phase, limits, phase, steps):
    """One finger's phase (cycles) for :meth:`HybridRenderer.render`, written to ``phase``,
    and each sample's own phase travel (cycles: synthesis and correction until the next
    sample, not a jump there) to ``steps``.

    touch : (n,) int64; vx, vy, x_held, y_held, x_pred, y_pred : (n,) float64, the
    finger's tracks. s_mm, v_mm_s : (n,) its filtered position (mm) and velocity (mm/s)
    along ``axis`` (``rendering.layers.finger_filter``), and the standard deviation (mm)
    of its last position correction (its ``sd``). before : the carried
    :class:`_Finger` fields (touch, phase, offset, target, measured x, measured y,
    measured rate, speed, held), used if ``has_before``. axis : (ax, ay). layer_phase :
    (offset_mm, period_mm), so that ``(ax x + ay y - offset_mm) / period_mm`` is
    ``layer.phase_at(x, y)``. limits : (dt_s, slip, lock (cycles), event_hz, relock rate
    (cycles/s), position-locked (bool), largest jump back (cycles), hold (s), gate
    (standard deviations of ``sd_mm``)); a measurement's lost-lock threshold is the
    larger of lock and the gate.

    Returns the new carried fields in ``before``'s order.
    """
    n = touch.size
    ax, ay = axis
    offset_mm, period = layer_phase
    dt_s, slip, lock, event_hz, relock, locked, back, hold_s, gate = limits
    b_touch, b_phase, b_offset, b_target, b_x, b_y, b_rate, b_speed, b_held = before
    restart = np.empty(n, dtype=np.bool_)
    measured = np.empty(n)  # the tracker's phase rate (cycles/s): tells new measurements
    rate = np.empty(n)  # the filter's (cycles/s): what is synthesised
    for k in range(n):
        restart[k] = touch[k] != (b_touch if k == 0 else touch[k - 1]) or (k == 0 and not has_before)
        measured[k] = (vx[k] * ax + vy[k] * ay) / period
        rate[k] = v_mm_s[k] / period
    carry = phase_kernel(rate, dt_s, touch, has_before, int(b_touch), b_phase, phase, steps)
    # a new measurement: a new touch, or the tracker's held sample or velocity changes;
    # synthesis starts where the finger is at touch-down and when it starts from rest
    bounds = np.empty(n + 1, dtype=np.int64)
    target = np.empty(n + 1)
    flags = np.zeros(n + 1, dtype=np.bool_)
    starts = np.zeros(n + 1, dtype=np.bool_)
    jump = np.zeros(n + 1)
    hold = np.zeros(n + 1)
    locks = np.empty(n + 1)
    k_n = 0
    if not has_before:
        new0 = True
    else:
        new0 = restart[0] or x_held[0] != b_x or y_held[0] != b_y or measured[0] != b_rate
    if not new0:  # the previous call's measurement holds, and what was decided at it
        bounds[0], target[0] = 0, b_target
        locks[0] = max(lock, gate * sd_mm[0] / period)
        k_n = 1
    speed_before = b_speed if has_before else 0.0
    for k in range(n):
        speed = abs(vx[k]) + abs(vy[k])  # only compared with 0: zero exactly when the speed is
        if k == 0:
            new = new0
        else:
            new = (restart[k] or x_held[k] != x_held[k - 1] or y_held[k] != y_held[k - 1]
                   or measured[k] != measured[k - 1])
        if new:
            bounds[k_n] = k
            target[k_n] = (s_mm[k] - offset_mm) / period - phase[k]
            flags[k_n] = restart[k]
            starts[k_n] = speed_before == 0.0 and speed > 0.0
            jump[k_n] = math.copysign(1.0, rate[k]) if locked and speed > 0.0 else 0.0
            hold[k_n] = abs(rate[k]) * hold_s if locked and speed > 0.0 else 0.0
            locks[k_n] = max(lock, gate * sd_mm[k] / period)
            k_n += 1
        speed_before = speed
    # correction allowances: SLIP times the distance travelled (cycles; beyond the lock,
    # at least SLIP times relock cycles/s while the finger moves), the part of it where
    # the lines pass slower than event_hz, and the distance travelled itself (a hold)
    fast = np.empty(n + 1)
    slow = np.empty(n + 1)
    travel = np.empty(n + 1)
    scale = slip * dt_s
    fast[0] = slow[0] = travel[0] = 0.0
    acc_fast = acc_slow = acc_travel = 0.0
    for k in range(n):
        r = abs(rate[k])
        acc_fast += max(r, relock) if r > 0.0 else 0.0
        acc_slow += r * (1.0 if r < event_hz else 0.0)
        acc_travel += r
        fast[k + 1] = acc_fast * scale
        slow[k + 1] = acc_slow * scale
        travel[k + 1] = acc_travel * dt_s
    offset = np.empty(n)
    reach = np.empty(n)
    end, held = _slew_kernel(bounds[:k_n], target[:k_n], flags[:k_n], starts[:k_n], fast, slow,
                             b_offset if has_before else 0.0, locks[:k_n], jump[:k_n], back,
                             hold[:k_n], travel, not new0 and b_held != 0.0, offset, reach)
    for k in range(n):
        phase[k] += offset[k]
        # a jump at the next measurement is where the finger is then, not crossed here
        steps[k] += reach[k] - offset[k]
    return (touch[n - 1], carry, end, target[k_n - 1] % 1.0, x_held[n - 1], y_held[n - 1],
            measured[n - 1], speed_before, 1.0 if held else 0.0)


#: the carried fields of :func:`_hybrid_row` for a finger seen for the first time
_NO_FINGER = (0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0, 0.0)


class HybridRenderer:
    """Phase-locked period synthesis of one periodic layer (grating or waveform)."""

    #: what it makes of a period finer than the touch samples can place
    #: (``rendering.perception``)
    fine_period = ("SHO alone (the map read at the touch samples) would alias it; the hybrid "
                   "renderer plays it from the finger's velocity, so it is felt, registered "
                   "with the drawing only as closely as the touch samples allow")
    #: plays its texture from the tracker's velocity between touch samples
    #: (``rendering.renderers.from_velocity``)
    from_velocity = True

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
        self.locked = layer.period_mm >= COARSE_MM
        self.event_hz = float(event_hz)
        self.band_limit = BandLimit(layer)

    def initial_state(self) -> HybridState:
        return HybridState(fingers={})

    def render(self, block: FingerBlock, state: HybridState):
        """mu' (F, n) and coverage (F, n) under each finger (mu' 1 where the layer does
        not cover), and the new state."""
        phase = np.empty((len(block.ids), block.n))
        steps = np.empty_like(phase)
        # only the block's fingers are carried on: one that lifted and left the tracks
        # is forgotten (its id, if it comes back, is a new touch that restarts it
        # anyway), so the state follows the fingers touching, not every id ever used
        carried: dict[int, _Finger] = {}
        layer_phase = (float(self.layer.offset_mm), float(self.layer.period_mm))
        limits = (self.dt_s, self.slip, self.lock, self.event_hz,
                  RELOCK_MM_S / self.layer.period_mm, self.locked,
                  BACK_MM / self.layer.period_mm, HOLD_S, GATE_SIGMAS)
        rows = [np.ascontiguousarray(getattr(block, name), dtype=np.float64)
                for name in ("vx", "vy", "x_held", "y_held", "x_pred", "y_pred")]
        touch = np.ascontiguousarray(block.touch_id, dtype=np.int64)
        for row, fid in enumerate(block.ids):
            before = state.fingers.get(fid)
            fields = _NO_FINGER if before is None else (
                before.touch, before.phase, before.offset, before.target, *before.measured,
                before.speed, before.held)
            s_mm, v_mm_s, sd_mm, filtered = filter_axis(
                block.t_s, touch[row], *(a[row] for a in rows), self.axis,
                None if before is None else before.filter)
            end = _hybrid_row(touch[row], *(a[row] for a in rows), s_mm, v_mm_s, sd_mm,
                              before is not None, fields, self.axis, layer_phase, limits,
                              phase[row], steps[row])
            carried[fid] = _Finger(touch=int(end[0]), phase=end[1], offset=end[2], target=end[3],
                                   measured=end[4:7], speed=end[7], held=end[8],
                                   filter=filtered)
        covers = self.layer.covers(block.x_pred, block.y_pred)
        mu = self.band_limit.play_forward(phase, covers, steps)
        limited = self.band_limit.apply(mu, covers, block, steps)
        return mu, covers, HybridState(fingers=carried, clipped=state.clipped + limited)
