"""Effect clips: mu' against time, started by touch events (``rendering.layers.clips``).

A clip is a list of events on its own time axis (s, 0 = the first output sample after
the trigger), each contributing a level in [0, 1] at every output sample; the levels add,
and mu' = 1 - depth * min(1, sum) (samples where the sum passed 1 are marked; a replay
counts those played in ``summary.json``'s ``layer_clipped``).

- ``transient`` (a tick): a Hann pulse sin^2(pi t / T) of peak ``intensity``, T from
  sharpness: T = 30 ms at sharpness 0 down to 5 ms at sharpness 1 (sharper, shorter,
  more high-frequency content).
- ``continuous`` (envelopes, ramps): ``intensity`` times an envelope, piecewise linear
  through (t, level) breakpoints relative to the event's start, times a carrier
  c = (1 + cos(2 pi phi)) / 2 whose frequency follows sharpness: f = 250 Hz * sharpness
  (0: a smooth drop with no vibration; 1: 250 Hz, near the skin's most sensitive band);
  phi is integrated sample by sample so the carrier never jumps when f changes.

Clip-wide curves (AHAP's dynamic parameters): ``intensity_curve`` multiplies every
event's intensity, ``sharpness_curve`` is added to every event's sharpness (then clipped
to [0, 1]; a transient takes the curve's value where it starts, for its whole pulse);
both are piecewise linear through (t, value) points (two points at one time: a step),
neutral before their first point (a gain of 1, a shift of 0: a control changes nothing
before its time) and held at their last value after it.
"""

from __future__ import annotations

import functools
import math
from dataclasses import dataclass
import numpy as np

from frictex.device.jit import njit
from frictex.textures.dynamic import OUTPUT_RATE_HZ, DynamicLayer

CLIP_TRIGGERS = ("down", "lift", "edge", "force")
EVENT_KINDS = ("transient", "continuous")
TRANSIENT_S = (0.030, 0.005)  # pulse length at sharpness 0 and at sharpness 1
CARRIER_MAX_HZ = 250.0
#: longest clip (s): its samples are computed once, at the pipeline's output rate
MAX_CLIP_S = 60.0
#: how near a sample (in samples) an event's start or end counts as on it: times written
#: in decimal land there only within rounding (0.1 + 0.2 is 3000.0000000000005 samples
#: at 10 kHz), and an event ending where the next starts must not share its sample
ON_SAMPLE = 1e-6

Points = tuple[tuple[float, float], ...]


@dataclass(frozen=True)
class ClipEvent:
    """One event of a clip. Times in s from the clip's start; intensity and sharpness
    in [0, 1]; ``envelope`` (continuous only) as (t from the event's start, level in
    [0, 1]) breakpoints, default flat at 1 over ``duration_s``."""

    kind: str
    time_s: float
    intensity: float = 1.0
    sharpness: float = 0.5
    duration_s: float = 0.0
    envelope: Points = ()


def _transient_length(sharpness: float) -> float:
    return TRANSIENT_S[0] + (TRANSIENT_S[1] - TRANSIENT_S[0]) * sharpness


def _curve(points: Points, t: np.ndarray, default: float) -> np.ndarray:
    """A clip-wide curve at times ``t`` (s): ``default`` before its first point (or
    everywhere if it has none), linear between points, its last value after them."""
    if not points:
        return np.full(np.shape(t), default)
    ts, vs = zip(*points)
    return np.interp(t, ts, vs, left=default)


def _first_sample_from(time_s: float, rate_hz: float) -> int:
    """The index of the first sample at or after ``time_s`` (>= 0), one within
    :data:`ON_SAMPLE` of a sample counting as on it."""
    return max(0, math.ceil(time_s * rate_hz - ON_SAMPLE))


@dataclass(frozen=True)
class Clip:
    """A clip of mu' against time; see the module docstring. ``depth``: the drop in mu'
    at full level, in (0, 1)."""

    events: tuple[ClipEvent, ...]
    depth: float = 0.5
    intensity_curve: Points = ()
    sharpness_curve: Points = ()

    def event_length_s(self, e: ClipEvent) -> float:
        """How long event ``e`` plays (s): a continuous event its duration, a transient its
        pulse at its sharpness plus the sharpness curve's value where it starts."""
        if e.kind != "transient":
            return e.duration_s
        shift = float(_curve(self.sharpness_curve, np.array(e.time_s), 0.0))
        return _transient_length(min(max(e.sharpness + shift, 0.0), 1.0))

    @property
    def duration_s(self) -> float:
        return max((e.time_s + self.event_length_s(e) for e in self.events), default=0.0)

    @functools.cached_property
    def deepest_mu(self) -> float:
        """The lowest mu' the clip plays at a replay's default output rate
        (``textures.dynamic.OUTPUT_RATE_HZ``): 1 - depth where its levels reach 1, higher
        where they never do (a tick of intensity 0.64 at depth 0.5: 0.68)."""
        return float(self.sample(OUTPUT_RATE_HZ)[0].min())

    def sample(self, rate_hz: float) -> tuple[np.ndarray, np.ndarray]:
        """mu' at t = k / rate_hz, k = 0 .. ceil(duration * rate), and the samples where the
        level sum passed 1 and was clipped there (bool, the same shape). An event plays on
        the samples with time_s <= t < time_s + its length (within :data:`ON_SAMPLE`), so
        the last sample is back at 1 and an event ending where the next begins shares no
        sample with it. Each event is computed over its own samples only: the cost is the
        events' total length, not their number times the clip's."""
        n = int(math.ceil(self.duration_s * rate_hz)) + 1
        if (n - 1) / rate_hz < self.duration_s:  # the product rounded down past an integer
            n += 1
        t = np.arange(n) / rate_hz
        gain = _curve(self.intensity_curve, t, 1.0)
        shift = _curve(self.sharpness_curve, t, 0.0)
        total = np.zeros(n)
        for e in self.events:
            length = self.event_length_s(e)
            lo = _first_sample_from(e.time_s, rate_hz)
            hi = min(n, _first_sample_from(e.time_s + length, rate_hz))
            rel = np.clip(t[lo:hi] - e.time_s, 0.0, length)
            if e.kind == "transient":
                level = np.sin(np.pi * rel / length) ** 2
            else:
                env = e.envelope or ((0.0, 1.0), (e.duration_s, 1.0))
                step = CARRIER_MAX_HZ * np.clip(e.sharpness + shift[lo:hi], 0.0, 1.0) / rate_hz
                phase = np.cumsum(step) - step  # cycles before each sample: 0 on the first
                level = _curve(env, rel, 0.0) * (0.5 + 0.5 * np.cos(2.0 * np.pi * phase))
            total[lo:hi] += e.intensity * gain[lo:hi] * level
        return 1.0 - self.depth * np.minimum(total, 1.0), total > 1.0


@dataclass(frozen=True)
class ClipLayer(DynamicLayer):
    """A clip played under every touching finger when its trigger fires.

    ``trigger``: ``down`` / ``lift`` (a touch begins / ends inside the layer's region),
    ``edge`` (a touching finger crosses the line through (x_mm, y_mm) whose normal is at
    ``angle_deg`` from +x, either way, inside the region; only reaching it is no crossing), ``force`` (a touching
    finger's normal force rises through ``force_n``, inside the region, having fallen
    below :data:`FORCE_REARM` x ``force_n`` since it last did). The clip starts
    on the output sample after the event; a new event restarts it. A one-channel plate
    vibrates under every finger at once, so the clip is felt by all fingers touching.
    Statically (drawn, or for a finger with nothing playing) the layer is mu' = 1.
    """

    renderer_kind = "clip"
    FILE_TYPE = "clip"

    clip: Clip = None  # type: ignore[assignment]
    trigger: str = "down"
    x_mm: float = 0.0
    y_mm: float = 0.0
    angle_deg: float = 0.0
    force_n: float = 1.0

    @property
    def mu_range(self) -> tuple[float, float]:
        return self.clip.deepest_mu, 1.0

    @property
    def rest_mu(self) -> float:
        return 1.0

    def side(self, x, y) -> np.ndarray:
        """int8, the side of the edge line (``edge`` trigger) at positions x, y (mm,
        broadcast together): +1 on the side the normal points to, -1 on the other, 0 on
        the line, within :data:`ON_LINE_MM` of it (a finger there has crossed nothing
        yet; the tolerance takes up the rounding of the normal, cos 90 deg being 6e-17)."""
        a = math.radians(self.angle_deg)
        x, y = np.asarray(x, dtype=np.float64), np.asarray(y, dtype=np.float64)
        if x.shape != y.shape:
            x, y = np.broadcast_arrays(x, y)
        line = (self.x_mm, self.y_mm, math.cos(a), math.sin(a))
        return _side(x.ravel(), y.ravel(), line).reshape(x.shape)

    def force_level(self, force_n) -> np.ndarray:
        """int8, where a normal force (N) stands for the ``force`` trigger: +1 at or above
        ``force_n``, -1 below :data:`FORCE_REARM` x ``force_n`` (re-armed), 0 between
        (and NaN): as the finger's last sample stood, so that a force's noise about
        ``force_n`` fires once (a press held at the threshold with 0.03 N of noise fired
        again on each crossing)."""
        force = np.asarray(force_n, dtype=np.float64)
        with np.errstate(invalid="ignore"):
            return ((force >= self.force_n).astype(np.int8)
                    - (force < FORCE_REARM * self.force_n).astype(np.int8))


#: the fraction of a clip's ``force_n`` the force must fall below before it can trigger
#: again: 20 % of hysteresis, as force-sensing buttons release below their press level
FORCE_REARM = 0.8


#: distance (mm) from an edge line within which a position is on it: a picometre, far
#: under any touch screen's resolution and far over the rounding of a position's distance
ON_LINE_MM = 1e-9


@njit(cache=True, nogil=True)
def _side(x, y, line):
    """(m,) int8: the sign (+1, 0, -1) of nx (x - x0) + ny (y - y0) at positions (x, y)
    (mm, (m,)) for the line through (x0, y0) with unit normal (nx, ny), ``line``, 0 within
    :data:`ON_LINE_MM`; one pass."""
    x0, y0, nx, ny = line
    out = np.empty(x.size, dtype=np.int8)
    for i in range(x.size):
        d = nx * (x[i] - x0) + ny * (y[i] - y0)
        out[i] = 1 if d > ON_LINE_MM else (-1 if d < -ON_LINE_MM else 0)
    return out
