"""Accuracy of a rendering: the mu'(t) a finger got against the mu'*(t) it should have got.

The reference mu'* is the scene evaluated on the finger's *true* path (``truth`` of
``rendering.input.trace_synth``, sampled at a high rate, no noise); the rendered mu' is what the
pipeline produced from the *sampled* trace, held between its output samples (the
microcontroller plays each sample until the next one) and read on the reference's time
grid. All three metrics use only the reference's contact time.

Which metric matters for which layer
------------------------------------
- ``time_error`` (normalised RMS of mu' - mu'*): the strictest, phase and all. It is
  what matters for objects and edges, whose friction must follow the finger exactly.
  For fine textures it mostly measures spatial phase, which a finger cannot feel
  (seed 003 section 6: participants did not notice a grating's phase once two periods
  fit under the fingerpad, P < ~5 mm); there a renderer that gives up and outputs the
  mean scores 1.0 and one with the right texture at a random phase scores ~1.4.
- ``spectral_error`` (distance between short-time third-octave spectra, 10 Hz - 1 kHz):
  what a texture feels like, phase ignored for textures of ``PHASE_BLIND_HZ`` (16 Hz)
  and above, not below (see :func:`spectral_error`). It is the one that matters for fine
  gratings and waveforms (P below ~5 mm): it catches aliasing (seed 003 section 4.4.1:
  a 50 Hz touch screen reproduces a grating only up to 25 Hz; our example, derived from
  sampling, not from seed 003: plain SHO at 50 Hz folds a 66.7 Hz grating to
  66.7 - 50 = 16.7 Hz), lost bandwidth and smearing.
- ``alignment_error_mm`` (distance along the path between matching friction steps):
  what the eye checks, an edge felt where it is drawn. It matters for objects and coarse
  gratings (P above ~5 mm), where plain SHT's accumulated phase error shows (seed 003
  section 4.4.2). On fine gratings it is bounded by a quarter period and says little.

Definitions (the functions below give the details): time error
``rms(mu - mu*) / std(mu*)``; spectral error
``||B - B*|| / ||B*||`` with B the magnitude per third-octave band and STFT frame;
alignment error the mean, over steps of mu'* and over steps of mu', of the distance in mm
of arc length to the nearest place where the other signal crosses the step's half-way
level going the same way (capped at ``cap_mm``): symmetric, so a renderer that misses
an edge and one that adds spurious edges (chatter) both pay.

Chatter (:func:`chatter`, for a periodic layer: a grating's axis and period) counts
edges felt twice: a friction step of mu' undone by the next step (the other way, back
across the first one's half-way level) within ``CHATTER_S``, while the finger, along
the layer's axis, stayed within a quarter period (the same edge, not the next one half
a period on) and did not itself turn back (a reversal: the finger moved back at least
``hysteresis_mm`` from its furthest point, within ``CHATTER_S`` of the pair). An edge
crossed three times (early, back, again) counts 2. Against the true path
(:func:`accuracy` with ``layer``) the finger's motion is the true one, and the ideal
mu'* never chatters (a finger crosses an edge back only by turning back); on a
recording (``app.measure.report_real``) it is the tracker's (reversals: in the measured
samples).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import stft

from frictex.device.jit import njit
from frictex.rendering.compose import ideal_mu
from frictex.rendering.input.trace_file import UP, Trace, TraceError

#: tactile band (Hz) of the spectral error: from the lowest vibration frequency skin
#: resolves as texture to the ~1 kHz where the Pacinian channel's sensitivity ends
TACTILE_BAND_HZ = (10.0, 1000.0)
#: STFT window (s): 10 Hz resolution, the band's lower edge
SPECTRAL_WINDOW_S = 0.1
#: texture frequency (Hz) from which the spectral error ignores phase: a spatial shift
#: of a grating costs at most 0.11 there; below, up to 1.34 (:func:`spectral_error`)
PHASE_BLIND_HZ = 16.0
#: spectra are compared in bands this fine (third octaves, ~26 % wide)
BANDS_PER_OCTAVE = 3
#: a friction step is a monotone change of at least this much mu' ...
MIN_STEP = 0.05
#: ... over at most this much path (mm): sharp edges and the soft edges of texture files
MAX_STEP_WIDTH_MM = 2.0
#: no step is matched to one further away than this (mm) along the path
ALIGNMENT_CAP_MM = 10.0
#: a step undone within this (s) is chatter (see the module docstring): at 50 Hz touch a
#: lock correction comes at most one touch interval and one 5 ms block after the step
#: it undoes (25 ms)
CHATTER_S = 0.03
#: a finger's motion reverses when it moves back this far (mm) from its furthest point:
#: on a true path (no noise) any turn; measured positions need ``REVERSAL_MEASURED_MM``
REVERSAL_TRUE_MM = 1e-3
#: ... four times a touch screen's 0.05 mm noise (standard deviation)
REVERSAL_MEASURED_MM = 0.2
#: chatter is counted on layers of at least this period (mm), whose edges are felt as
#: events (the hybrid's coarse layers, ``rendering.layers.hybrid.COARSE_MM``); on finer
#: ones successive edges are texture
CHATTER_PERIOD_MM = 2.0


class MetricError(TraceError):
    """Inputs an accuracy metric cannot be computed from (the message says which and why)."""


@dataclass(frozen=True, eq=False)
class Reference:
    """The ideal rendering on the true path, on the true path's time grid (n samples).

    t_s : (n,) s. x_mm, y_mm : (n,) true position. contact : (n,) bool.
    s_mm : (n,) arc length along the true path (mm). mu : (n,) mu'* (1 out of contact).
    rate_hz : the grid's sampling rate (Hz).
    """

    t_s: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    contact: np.ndarray
    s_mm: np.ndarray
    mu: np.ndarray
    rate_hz: float


@dataclass(frozen=True)
class Accuracy:
    """The three metrics of one rendering (see the module docstring), and the step counts."""

    time_error: float
    spectral_error: float
    alignment_error_mm: float | None
    ideal_steps: int
    rendered_steps: int
    chatter: int | None = None


def reference(scene, truth: Trace) -> Reference:
    """mu'* of ``scene`` along the true path ``truth`` (one finger, uniform time grid).

    Contact runs from the first sample up to, not including, the finger's ``up``
    sample (as in the tracker).
    """
    if len(truth) < 2 or len(truth.fingers) != 1:
        raise MetricError(f"true path: {len(truth)} samples of fingers {truth.fingers}; "
                          "expected at least 2 samples of exactly one finger")
    t = truth.t_s
    steps = np.diff(t)
    rate = 1.0 / float(np.median(steps))
    if np.abs(steps * rate - 1.0).max() > 1e-6:
        raise MetricError(f"true path: sample spacing varies from {steps.min():.3g} s to "
                          f"{steps.max():.3g} s; expected a uniform grid")
    contact = np.cumsum(truth.event == UP) == 0
    s = np.concatenate(([0.0], np.cumsum(np.hypot(np.diff(truth.x_mm), np.diff(truth.y_mm)))))
    mu = np.where(contact, ideal_mu(scene, truth.x_mm, truth.y_mm), 1.0)
    return Reference(t, truth.x_mm, truth.y_mm, contact, s, mu, rate)


def hold(t_out: np.ndarray, values: np.ndarray, t_query: np.ndarray, rate_hz: float) -> np.ndarray:
    """Zero-order hold: ``values`` (n,) output at ``t_out`` (n,), uniform at ``rate_hz``,
    read at times ``t_query`` (m,) s. Before the first output sample: mu' = 1 (plate at
    rest); after the last: the last value."""
    k = np.floor((np.asarray(t_query) - t_out[0]) * rate_hz + 1e-6).astype(np.int64)
    held = np.asarray(values, dtype=np.float64)[np.clip(k, 0, t_out.size - 1)]
    return np.where(k < 0, 1.0, held)


def time_error(mu: np.ndarray, mu_ideal: np.ndarray, contact: np.ndarray) -> float:
    """Normalised RMS error over contact time: ``rms(mu - mu*) / std(mu*)``.

    Parameters
    ----------
    mu, mu_ideal : (n,) rendered and ideal mu'.
    contact : (n,) bool, samples that count.

    Returns
    -------
    float, dimensionless: 0 for a perfect rendering, 1 for a constant at the mean of
    mu'*, ~sqrt(2) for the right signal at an unrelated phase.
    """
    a, b = mu[contact], mu_ideal[contact]
    if b.size == 0 or np.ptp(b) == 0.0:
        raise MetricError(f"ideal mu' is constant ({b[:1]}) over the {b.size} contact samples: "
                          "the time error is undefined; expected a path that crosses the scene")
    return float(np.sqrt(np.mean((a - b) ** 2)) / np.std(b))


def _band_spectrogram(mu, contact, rate_hz, band_hz, window_s):
    """Magnitude per third-octave band (rows) and STFT frame (columns)."""
    x = np.where(contact, mu, 1.0)
    nper = int(round(window_s * rate_hz))
    if x.size < nper:
        raise MetricError(f"{x.size} samples at {rate_hz:g} Hz are shorter than one "
                          f"{window_s:g} s spectral window")
    freq, _, z = stft(x, fs=rate_hz, window="hann", nperseg=nper, noverlap=nper // 2,
                      detrend="constant", boundary=None, padded=False)
    inside = (freq >= band_hz[0]) & (freq <= band_hz[1])
    band = np.floor(BANDS_PER_OCTAVE * np.log2(freq[inside] / band_hz[0]) + 1e-9).astype(np.intp)
    power = np.zeros((band.max() + 1, z.shape[1]))
    np.add.at(power, band, np.abs(z[inside]) ** 2)
    return np.sqrt(power)


def spectral_error(mu: np.ndarray, mu_ideal: np.ndarray, contact: np.ndarray, rate_hz: float,
                   band_hz: tuple[float, float] = TACTILE_BAND_HZ,
                   window_s: float = SPECTRAL_WINDOW_S) -> float:
    """Relative distance between the short-time band spectra of mu' and mu'*.

    Both signals are set to 1 out of contact, cut into Hann windows of ``window_s`` (half
    overlap, mean removed per window); each window's magnitude spectrum is summed (power)
    into third-octave bands over ``band_hz``, about the finger's frequency resolution
    (vibrotactile Weber fraction ~0.2-0.3), so a texture 5 % off in frequency is not
    penalised as if it were a different texture. The error is
    ``sqrt(sum (B - B*)^2) / sqrt(sum B*^2)`` over bands and windows. A missing texture
    costs 1; energy in the wrong bands costs up to ~1.4.

    Phase is ignored only where a window holds a few of the texture's cycles: for a
    texture (v / P) of ``PHASE_BLIND_HZ`` and above a texture shifted in space by any
    fraction of its period costs at most 0.11 (0.105 at 25 Hz, 2.5 cycles a window;
    under 0.06 from 26 Hz on). Below it a window holds one or two edges and their place
    in the window sets the band magnitudes: a shift of a quarter period costs 0.09-0.18
    at 11-15 Hz, 0.30 at 10 Hz, 0.45 at 8 Hz, 0.87 at 6 Hz and 1.34 at 4 Hz (a 5 mm
    grating at 20 mm/s), more than a missing texture. Measured on a 0.6/1.0 square
    grating, 4 s at 60 mm/s on a 20 kHz grid, shifts of 1/16 to 8/16 of a period
    (tests/test_fidelity_spectral_phase.py). A half-period shift of a square grating
    costs 0 at any frequency (it only flips the sign, which the magnitudes ignore).

    Parameters
    ----------
    mu, mu_ideal : (n,) rendered and ideal mu' on a uniform grid at ``rate_hz`` (Hz).
    contact : (n,) bool.
    band_hz : (low, high) Hz, inclusive; high must not exceed rate_hz / 2.
    window_s : STFT window length (s).
    """
    if band_hz[1] > rate_hz / 2:
        raise MetricError(f"band up to {band_hz[1]:g} Hz needs a grid above {2 * band_hz[1]:g} Hz; "
                          f"got {rate_hz:g} Hz")
    got = _band_spectrogram(mu, contact, rate_hz, band_hz, window_s)
    want = _band_spectrogram(mu_ideal, contact, rate_hz, band_hz, window_s)
    norm = float(np.sqrt(np.sum(want ** 2)))
    if norm == 0.0:
        raise MetricError(f"ideal mu' has no energy in {band_hz[0]:g}-{band_hz[1]:g} Hz: the "
                          "spectral error is undefined; expected a path that crosses the scene")
    return float(np.sqrt(np.sum((got - want) ** 2)) / norm)


def find_steps(mu: np.ndarray, s_mm: np.ndarray, contact: np.ndarray, min_step: float = MIN_STEP,
               max_width_mm: float = MAX_STEP_WIDTH_MM) -> tuple[np.ndarray, np.ndarray]:
    """Friction steps of ``mu`` along the path (see :func:`_steps`): their positions
    (mm of arc length) and directions (+1 friction rising, -1 falling)."""
    pos, direction, _ = _steps(mu, s_mm, contact, min_step, max_width_mm)
    return pos, direction


def _steps(mu: np.ndarray, s_mm: np.ndarray, contact: np.ndarray, min_step: float = MIN_STEP,
           max_width_mm: float = MAX_STEP_WIDTH_MM, tol: float = 1e-9
           ) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """Friction steps of ``mu`` along the path: monotone runs (within one contact
    interval; samples held equal, as between the output samples of a slower renderer,
    do not end a run) that change mu' by at least ``min_step`` over at most
    ``max_width_mm`` of path.

    Parameters
    ----------
    mu : (n,) mu'. s_mm : (n,) arc length (mm), non-decreasing. contact : (n,) bool.
    tol : changes smaller than this are no change (rounding).

    Returns
    -------
    position_mm : (k,) arc length of each step's centre of change (the |d mu'|-weighted
        mean of the positions where mu' changes; the midpoint of a sharp step).
    direction : (k,) +1 for friction rising, -1 falling.
    level : (k,) mu' half way through each step.
    """
    d = np.diff(mu)
    both = contact[1:] & contact[:-1]
    moving = np.flatnonzero((np.abs(d) > tol) & both)  # samples held equal do not break a run
    if moving.size == 0:
        return np.empty(0), np.empty(0), np.empty(0)
    sign = np.sign(d[moving])
    interval = np.cumsum(~both)[moving]  # runs never span a lift
    new = np.concatenate(([True], (sign[1:] != sign[:-1]) | (interval[1:] != interval[:-1])))
    first = np.flatnonzero(new)
    last = np.concatenate((first[1:], [moving.size])) - 1
    start, end = moving[first], moving[last]
    change = mu[end + 1] - mu[start]
    width = s_mm[end + 1] - s_mm[start]
    weight = np.abs(d[moving])
    mid = 0.5 * (s_mm[moving] + s_mm[moving + 1])
    centre = np.add.reduceat(weight * mid, first) / np.add.reduceat(weight, first)
    keep = (np.abs(change) >= min_step) & (width <= max_width_mm)
    level = 0.5 * (mu[start] + mu[end + 1])
    return centre[keep], np.sign(change[keep]), level[keep]


def _to_crossings(pos, direction, level, other, s_mm, contact, cap_mm):
    """Distance (mm of path) from each step to the nearest place, within ``cap_mm``,
    where ``other`` crosses the step's level going the same way (else ``cap_mm``)."""
    out = np.full(pos.size, cap_mm)
    lo = np.searchsorted(s_mm, pos - cap_mm)
    hi = np.searchsorted(s_mm, pos + cap_mm, side="right")
    for k in range(pos.size):
        a, b = max(lo[k] - 1, 0), min(hi[k] + 1, s_mm.size)
        x0, x1 = other[a:b - 1], other[a + 1:b]
        if direction[k] > 0:
            hit = (x0 < level[k]) & (x1 >= level[k])
        else:
            hit = (x0 > level[k]) & (x1 <= level[k])
        hit &= contact[a:b - 1] & contact[a + 1:b]
        i = np.flatnonzero(hit)
        if i.size:
            frac = (level[k] - x0[i]) / (x1[i] - x0[i])
            where = s_mm[a + i] + frac * (s_mm[a + i + 1] - s_mm[a + i])
            out[k] = min(float(np.abs(where - pos[k]).min()), cap_mm)
    return out


def alignment_error(mu: np.ndarray, mu_ideal: np.ndarray, s_mm: np.ndarray, contact: np.ndarray,
                    cap_mm: float = ALIGNMENT_CAP_MM, **step_options) -> tuple[float, int, int]:
    """Symmetric step alignment error (mm) along the path.

    Every step of mu'* is matched to the nearest place where mu' crosses the step's
    half-way level going the same way, and every step of mu' to the nearest such
    crossing of mu'*; distances are arc length (mm), capped at ``cap_mm`` (also the cost
    of a step with no such crossing). Crossings, not detected steps, are the partners, so
    a soft edge rendered in fragments (a ramp read along a jittery prediction) is matched
    fragment by fragment. The error is the mean of the two sides' mean distances (a side
    without steps is left out), so missed and spurious steps both count.

    Parameters
    ----------
    mu, mu_ideal, s_mm, contact : (n,) as in :func:`find_steps`.
    step_options : ``min_step``, ``max_width_mm`` for :func:`find_steps`.

    Returns
    -------
    (error_mm, ideal_steps, rendered_steps); error_mm is None when neither signal has a
    step: there is nothing to align, and 0 would read as a perfect score.
    """
    ideal = _steps(mu_ideal, s_mm, contact, **step_options)
    rendered = _steps(mu, s_mm, contact, **step_options)
    if ideal[0].size == 0 and rendered[0].size == 0:
        return None, 0, 0
    to_rendered = _to_crossings(*ideal, mu, s_mm, contact, cap_mm)
    to_ideal = _to_crossings(*rendered, mu_ideal, s_mm, contact, cap_mm)
    means = [float(m.mean()) for m in (to_rendered, to_ideal) if m.size]
    return float(np.mean(means)), int(ideal[0].size), int(rendered[0].size)


def turns(along_mm: np.ndarray, contact: np.ndarray, hysteresis_mm: float) -> np.ndarray:
    """Indices where the motion along an axis turns back: the furthest point before the
    position has come back at least ``hysteresis_mm`` (mm) from it, within one contact
    interval (a zigzag with that threshold; a new contact starts without a direction)."""
    return _turns_kernel(np.ascontiguousarray(along_mm, dtype=np.float64),
                         np.ascontiguousarray(contact, dtype=np.bool_), float(hysteresis_mm))


@njit(cache=True)
def _turns_kernel(x, contact, h):
    out = np.empty(x.size, dtype=np.int64)
    count = 0
    direction = 0
    hi = lo = 0.0
    i_hi = i_lo = 0
    for i in range(x.size):
        if not contact[i]:
            direction = 0
            continue
        if direction == 0 and (i == 0 or not contact[i - 1]):
            hi = lo = x[i]
            i_hi = i_lo = i
            continue
        if direction >= 0 and x[i] > hi:
            hi, i_hi = x[i], i
        if direction <= 0 and x[i] < lo:
            lo, i_lo = x[i], i
        if direction >= 0 and x[i] <= hi - h:
            if direction > 0:
                out[count] = i_hi
                count += 1
            direction, lo, i_lo = -1, x[i], i
        elif direction <= 0 and x[i] >= lo + h:
            if direction < 0:
                out[count] = i_lo
                count += 1
            direction, hi, i_hi = 1, x[i], i
    return out[:count]


def chatter(mu: np.ndarray, t_s: np.ndarray, along_mm: np.ndarray, contact: np.ndarray,
            period_mm: float, hysteresis_mm: float, window_s: float = CHATTER_S,
            min_step: float = MIN_STEP, tol: float = 1e-9,
            turning_mm: np.ndarray | None = None) -> int:
    """Edges felt twice (see the module docstring): the number of friction steps of
    ``mu`` that undo the step before them.

    Parameters
    ----------
    mu : (n,) rendered mu'. t_s : (n,) s, increasing. contact : (n,) bool.
    along_mm : (n,) the finger's position along the layer's axis (mm), where the two
        steps are compared: the true path against a reference; on a recording the
        tracker's prediction (samples 10-20 ms apart may straddle two edges).
    turning_mm : (n,) the positions its reversals are found in (default ``along_mm``):
        on a recording the measured ones (a prediction overshoots and comes back at
        every sample of a finger that slows down).
    period_mm : the layer's period (mm); the same edge is within a quarter of it.
    hysteresis_mm : how far back (mm) the finger must move for a reversal (:func:`turns`).
    window_s : a step undone within this (s) counts. min_step : smallest step (mu').
    tol : changes smaller than this are no change (rounding).
    """
    d = np.diff(mu)
    both = contact[1:] & contact[:-1]
    moving = np.flatnonzero((np.abs(d) > tol) & both)
    if moving.size < 2:
        return 0
    sign = np.sign(d[moving])
    interval = np.cumsum(~both)[moving]
    new = np.concatenate(([True], (sign[1:] != sign[:-1]) | (interval[1:] != interval[:-1])))
    first = np.flatnonzero(new)
    last = np.concatenate((first[1:], [moving.size])) - 1
    start, end = moving[first], moving[last] + 1
    keep = np.abs(mu[end] - mu[start]) >= min_step
    start, end, interval = start[keep], end[keep], interval[first][keep]
    weight = np.abs(d[moving])
    centre = np.add.reduceat(weight * moving, first)[keep] / np.add.reduceat(weight, first)[keep]
    at = np.clip(np.rint(centre).astype(np.int64), 0, mu.size - 1)
    when, where = t_s[at], along_mm[at]
    level = 0.5 * (mu[start] + mu[end])
    lo, hi = np.minimum(mu[start], mu[end]), np.maximum(mu[start], mu[end])
    turn_t = t_s[turns(along_mm if turning_mm is None else turning_mm, contact, hysteresis_mm)]
    count = 0
    for k in range(1, when.size):
        if (interval[k] != interval[k - 1] or when[k] - when[k - 1] > window_s
                or np.sign(mu[end[k]] - mu[start[k]]) == np.sign(mu[end[k - 1]] - mu[start[k - 1]])
                or not lo[k] < level[k - 1] < hi[k]
                or abs(where[k] - where[k - 1]) >= period_mm / 4):
            continue
        a, b = np.searchsorted(turn_t, [when[k - 1] - window_s, when[k] + window_s])
        count += int(b == a)
    return count


def accuracy(ref: Reference, t_out: np.ndarray, mu_out: np.ndarray, out_rate_hz: float,
             layer=None) -> Accuracy:
    """All three metrics of a rendering ``mu_out`` (n,) output at ``t_out`` (n,) s, uniform
    at ``out_rate_hz``, against ``ref`` (see the module docstring); with ``layer`` (a
    periodic layer: ``axis``, ``period_mm``) also its chatter along the true path.
    Raises :class:`MetricError` where ``mu_out`` holds a NaN or an infinity (every metric
    of it would be NaN)."""
    bad = np.count_nonzero(~np.isfinite(mu_out))
    if bad:
        raise MetricError(f"rendered mu' has {bad} non-finite sample(s) of {np.size(mu_out)}: "
                          "its accuracy is undefined; expected finite values")
    mu = hold(t_out, mu_out, ref.t_s, out_rate_hz)
    mu = np.where(ref.contact, mu, 1.0)
    align, n_ideal, n_rendered = alignment_error(mu, ref.mu, ref.s_mm, ref.contact)
    doubled = None
    if layer is not None:
        along = layer.axis[0] * ref.x_mm + layer.axis[1] * ref.y_mm
        doubled = chatter(mu, ref.t_s, along, ref.contact, layer.period_mm, REVERSAL_TRUE_MM)
    return Accuracy(time_error=time_error(mu, ref.mu, ref.contact),
                    spectral_error=spectral_error(mu, ref.mu, ref.contact, ref.rate_hz),
                    alignment_error_mm=align, ideal_steps=n_ideal, rendered_steps=n_rendered,
                    chatter=doubled)
