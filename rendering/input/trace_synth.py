"""Synthetic finger motions: continuous paths, sampled like a touch screen would.

Each motion is a continuous path p(t) (mm) over [0, duration]; ``sample`` reads it at
a touch screen's rate with optional timestamp jitter and position noise (what the
pipeline sees), ``truth`` reads it at a high rate without noise (what accuracy checks
compare against). A finger touches at t = 0 and lifts at the end.

Motions:
- ``swipe``: constant speed along a straight line.
- ``back-and-forth``: constant speed between two ends, reversing instantly.
- ``circle``: constant speed around a circle.
Human motions (``human``, ``human-varied``) wander inside an area (``area_mm``, from
(0, 0); the demo's display by default), starting 30 % and 50 % across it unless told
where; the others start where told (14, 32.4 mm by default).

- ``human``: strokes between random waypoints with a minimum-jerk speed profile
  (Flash & Hogan 1985, the standard model of human reaching), random peak speeds and
  pauses with the finger resting.
- ``human-varied``: the ways people explore a texture, drawn one after another:
  strokes whose speed varies within the stroke (a minimum-jerk profile with a ripple,
  still never backwards), slow creeping (2-5 mm/s), fast flicks (200-500 mm/s peaks),
  reversals (a stroke straight back, no pause), circular arcs, and pauses. Each part
  starts and ends at rest, as minimum-jerk movements do.

``sample`` can add what real controllers do to the timing: samples taken off the
regular grid (``jitter_s``; each position is the finger's at its own timestamp, so the
stamps are irregular but true: a controller whose stamps differ from the times it
scanned is not modelled) and dropped samples (``drop``, the share of samples the screen
never reports).
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from frictex.device.errors import InputError
from frictex.rendering.input.trace_file import DOWN, MAX_COORD_MM, MOVE, UP, Trace, make_trace

MOTIONS = ("swipe", "back-and-forth", "circle", "human", "human-varied")
#: segment kinds of ``human-varied`` and their draw probabilities
#: where a swipe, back-and-forth or circle starts unless told (mm)
START_MM = (14.0, 32.4)
#: the area human motions wander in unless told (mm): the demo's display
HUMAN_AREA_MM = (108.0, 64.8)
#: how near a human motion's waypoints come to its area's edges (mm)
HUMAN_MARGIN_MM = 8.0
SEGMENTS = {"stroke": 0.3, "varying": 0.2, "creep": 0.1, "flick": 0.1, "reversal": 0.1,
            "arc": 0.1, "pause": 0.1}


@dataclass(frozen=True)
class Motion:
    """A continuous path: knots of a piecewise definition and the duration (s)."""

    kind: str
    duration_s: float
    params: dict

    def position(self, t) -> tuple[np.ndarray, np.ndarray]:
        """Position (mm) at times ``t`` (s), clamped to [0, duration]."""
        t = np.clip(np.asarray(t, dtype=np.float64), 0.0, self.duration_s)
        p = self.params
        if self.kind == "swipe":
            return p["x0"] + p["vx"] * t, p["y0"] + p["vy"] * t
        if self.kind == "back-and-forth":
            period = 2.0 * p["length"] / p["speed"]
            u = np.mod(t, period) / period
            s = p["length"] * (1.0 - np.abs(1.0 - 2.0 * u))  # triangle wave 0..length..0
            return p["x0"] + p["ux"] * s, p["y0"] + p["uy"] * s
        if self.kind == "circle":
            a = p["a0"] + p["speed"] / p["radius"] * t
            return p["cx"] + p["radius"] * np.cos(a), p["cy"] + p["radius"] * np.sin(a)
        if self.kind == "human-varied":
            return _segments(t, p["segments"])
        return _min_jerk(t, p["knots_t"], p["knots_x"], p["knots_y"])


def _min_jerk(t, knots_t, knots_x, knots_y):
    """Piecewise minimum-jerk interpolation between rest points (zero speed at knots)."""
    kt = np.asarray(knots_t)
    seg = np.clip(np.searchsorted(kt, t, side="right") - 1, 0, kt.size - 2)
    span = kt[seg + 1] - kt[seg]
    tau = np.where(span > 0, (t - kt[seg]) / np.where(span > 0, span, 1.0), 1.0)
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    kx, ky = np.asarray(knots_x), np.asarray(knots_y)
    return kx[seg] + (kx[seg + 1] - kx[seg]) * s, ky[seg] + (ky[seg + 1] - ky[seg]) * s


def _progress(tau, ripple: float, cycles: float):
    """Minimum-jerk progress 0 -> 1 over tau in [0, 1], plus ``ripple`` times
    sin(2 pi cycles tau) tau^3 (1 - tau)^3, whose slope is at most
    ripple (pi cycles / 2 + 3) tau^2 (1 - tau)^2: below the minimum-jerk slope
    30 tau^2 (1 - tau)^2 while ``ripple < 30 / (pi cycles / 2 + 3)``, so it never runs back."""
    s = 10 * tau**3 - 15 * tau**4 + 6 * tau**5
    return s + ripple * np.sin(2 * np.pi * cycles * tau) * (tau * (1 - tau)) ** 3


def _segments(t, segments):
    """Position (mm) at times ``t`` of a list of segments ``(t0, t1, kind, params)``,
    ``kind`` "line" (x0, y0, x1, y1, ripple, cycles) or "arc" (cx, cy, radius, a0, a1)."""
    x, y = np.empty(t.shape), np.empty(t.shape)
    for i, (t0, t1, kind, q) in enumerate(segments):
        sel = (t >= t0) & ((t < t1) | (i == len(segments) - 1))
        tau = np.clip((t[sel] - t0) / (t1 - t0), 0.0, 1.0)
        if kind == "line":
            u = _progress(tau, q[4], q[5])
            x[sel], y[sel] = q[0] + (q[2] - q[0]) * u, q[1] + (q[3] - q[1]) * u
        else:
            a = q[3] + (q[4] - q[3]) * _progress(tau, 0.0, 0.0)
            x[sel], y[sel] = q[0] + q[2] * np.cos(a), q[1] + q[2] * np.sin(a)
    return x, y


def make_motion(kind: str, *, speed_mm_s: float = 40.0, duration_s: float = 2.0,
                x0_mm: float | None = None, y0_mm: float | None = None,
                angle_deg: float = 0.0, length_mm: float = 80.0, radius_mm: float = 20.0,
                area_mm: tuple[float, float] = HUMAN_AREA_MM, seed: int = 0) -> Motion:
    """A motion of the given kind (see the module docstring); units mm, s, mm/s. The start
    (``x0_mm``, ``y0_mm``; None: the kind's default) of a human motion must lie in its
    ``area_mm`` (InputError otherwise)."""
    if kind not in MOTIONS:
        raise InputError(f"unknown motion {kind!r}; expected one of {', '.join(MOTIONS)}")
    if speed_mm_s <= 0 or duration_s <= 0:
        raise InputError(f"speed {speed_mm_s} mm/s and duration {duration_s} s must be > 0")
    if kind in ("human", "human-varied"):
        start = _human_start(x0_mm, y0_mm, area_mm)
        if kind == "human":
            return _human_motion(speed_mm_s, duration_s, area_mm, start, seed)
        return _varied_motion(speed_mm_s, duration_s, area_mm, start, seed)
    x0_mm = START_MM[0] if x0_mm is None else x0_mm
    y0_mm = START_MM[1] if y0_mm is None else y0_mm
    a = np.radians(angle_deg)
    ux, uy = float(np.cos(a)), float(np.sin(a))
    start = dict(x0_mm=x0_mm, y0_mm=y0_mm)
    if kind == "swipe":
        return _within_reach(Motion(kind, duration_s, dict(x0=x0_mm, y0=y0_mm,
                                                           vx=speed_mm_s * ux,
                                                           vy=speed_mm_s * uy)),
                             dict(start, speed_mm_s=speed_mm_s, duration_s=duration_s,
                                  angle_deg=angle_deg))
    if kind == "back-and-forth":
        return _within_reach(Motion(kind, duration_s, dict(x0=x0_mm, y0=y0_mm, ux=ux, uy=uy,
                                                           length=length_mm,
                                                           speed=speed_mm_s)),
                             dict(start, length_mm=length_mm, angle_deg=angle_deg))
    return _within_reach(Motion(kind, duration_s, dict(cx=x0_mm + radius_mm, cy=y0_mm,
                                                       radius=radius_mm, speed=speed_mm_s,
                                                       a0=np.pi)),
                         dict(start, radius_mm=radius_mm))


def _within_reach(motion: Motion, arguments: dict[str, float]) -> Motion:
    """``motion`` (a swipe, back-and-forth or circle) if its path stays within
    +-MAX_COORD_MM (mm) on both axes, as a trace's positions must; else an InputError
    naming ``arguments``, those of :func:`make_motion` that set how far it reaches."""
    extremes = np.array(_extremes(motion))  # (points, 2) mm
    point, axis = np.unravel_index(np.argmax(np.abs(extremes)), extremes.shape)
    if abs(extremes[point, axis]) <= MAX_COORD_MM:
        return motion
    given = ", ".join(f"{name}={value:g}" for name, value in arguments.items())
    raise InputError(f"a {motion.kind} with {given} reaches {'xy'[axis]}_mm = "
                     f"{extremes[point, axis]:g}; a trace's positions stay within "
                     f"+-{MAX_COORD_MM:g} mm")


def _extremes(motion: Motion) -> list[tuple[float, float]]:
    """Points (mm) whose box holds the path of ``motion``: a swipe's ends, a
    back-and-forth's start and far end (reached at length / speed, or not at all), the
    box of a circle's whole circle."""
    p = motion.params
    if motion.kind == "circle":
        return [(p["cx"] - p["radius"], p["cy"] - p["radius"]),
                (p["cx"] + p["radius"], p["cy"] + p["radius"])]
    farthest_s = (motion.duration_s if motion.kind == "swipe"
                  else min(motion.duration_s, p["length"] / p["speed"]))
    return [tuple(map(float, motion.position(0.0))),
            tuple(map(float, motion.position(farthest_s)))]


def _human_start(x0_mm: float | None, y0_mm: float | None, area_mm) -> tuple[float, float]:
    """Where a human motion in ``area_mm`` (width, height) starts: (``x0_mm``, ``y0_mm``),
    each 30 % and 50 % across the area where None."""
    if not all(size > 2 * HUMAN_MARGIN_MM for size in area_mm):
        raise InputError(f"area {area_mm[0]:g} x {area_mm[1]:g} mm: a human motion keeps "
                         f"{HUMAN_MARGIN_MM:g} mm from the area's edges; give more than "
                         f"{2 * HUMAN_MARGIN_MM:g} mm each way")
    x0 = area_mm[0] * 0.3 if x0_mm is None else float(x0_mm)
    y0 = area_mm[1] * 0.5 if y0_mm is None else float(y0_mm)
    if not (0.0 <= x0 <= area_mm[0] and 0.0 <= y0 <= area_mm[1]):
        raise InputError(f"start ({x0:g}, {y0:g}) mm: outside the {area_mm[0]:g} x "
                         f"{area_mm[1]:g} mm area (from 0, 0) a human motion wanders in; "
                         "give a start inside it, or a larger area")
    return x0, y0


def _human_motion(speed_mm_s: float, duration_s: float, area_mm, start, seed: int) -> Motion:
    """Strokes of 15-60 mm at peak speeds around ``speed_mm_s`` (x0.5-x1.8), with pauses,
    from ``start`` (x, y mm)."""
    rng = np.random.default_rng(seed)
    w, h = area_mm
    margin = HUMAN_MARGIN_MM
    knots_t, knots_x, knots_y = [0.0], [start[0]], [start[1]]
    while knots_t[-1] < duration_s:
        angle = rng.uniform(-np.pi, np.pi) if rng.random() < 0.3 else rng.choice([0.0, np.pi])
        dist = rng.uniform(15.0, 60.0)
        x = float(np.clip(knots_x[-1] + dist * np.cos(angle), margin, w - margin))
        y = float(np.clip(knots_y[-1] + dist * np.sin(angle), margin, h - margin))
        length = float(np.hypot(x - knots_x[-1], y - knots_y[-1]))
        peak = speed_mm_s * rng.uniform(0.5, 1.8)
        move_s = max(1.875 * length / peak, 0.05)  # min-jerk peak speed = 1.875 * mean speed
        knots_t.append(knots_t[-1] + move_s)
        knots_x.append(x)
        knots_y.append(y)
        if rng.random() < 0.4:  # pause, finger resting
            knots_t.append(knots_t[-1] + rng.uniform(0.1, 0.5))
            knots_x.append(x)
            knots_y.append(y)
    return Motion("human", duration_s, dict(knots_t=knots_t, knots_x=knots_x, knots_y=knots_y))


def _varied_motion(speed_mm_s: float, duration_s: float, area_mm, start, seed: int) -> Motion:
    """Segments drawn from ``SEGMENTS`` until ``duration_s`` (speeds scale with
    ``speed_mm_s``, the typical stroke's peak; creeping and flicks have their own), from
    ``start`` (x, y mm)."""
    rng = np.random.default_rng(seed)
    w, h = area_mm
    margin = HUMAN_MARGIN_MM
    kinds, weights = zip(*SEGMENTS.items())
    (x, y), t = start, 0.0
    segments = []

    def inside(length, angle):
        return (float(np.clip(x + length * np.cos(angle), margin, w - margin)),
                float(np.clip(y + length * np.sin(angle), margin, h - margin)))

    def line(length, peak, angle, ripple=0.0, cycles=0.0):
        nonlocal x, y, t
        x1, y1 = inside(length, angle)
        if np.hypot(x1 - x, y1 - y) < 0.5 * length:  # against an edge: turn round
            x1, y1 = inside(length, angle + np.pi)
        move_s = max(1.875 * float(np.hypot(x1 - x, y1 - y)) / peak, 0.04)
        segments.append((t, t + move_s, "line", (x, y, x1, y1, ripple, cycles)))
        x, y, t = x1, y1, t + move_s

    while t < duration_s:
        kind = kinds[rng.choice(len(kinds), p=np.array(weights) / sum(weights))]
        angle = rng.uniform(-np.pi, np.pi) if rng.random() < 0.3 else rng.choice([0.0, np.pi])
        peak = speed_mm_s * rng.uniform(0.5, 1.8)
        if kind == "stroke":
            line(rng.uniform(15.0, 60.0), peak, angle)
        elif kind == "varying":
            cycles = float(rng.integers(1, 4))
            line(rng.uniform(25.0, 60.0), peak, angle,
                 0.8 * 30.0 / (np.pi * cycles / 2 + 3) * rng.choice([-1.0, 1.0]), cycles)
        elif kind == "creep":
            line(rng.uniform(1.0, 4.0), rng.uniform(2.0, 5.0) * 1.875, angle)
        elif kind == "flick":
            line(rng.uniform(15.0, 40.0), rng.uniform(200.0, 500.0), angle)
        elif kind == "reversal":
            length = rng.uniform(10.0, 40.0)
            x0, y0 = x, y
            line(length, peak, angle)
            line(float(np.hypot(x - x0, y - y0)), peak, float(np.arctan2(y0 - y, x0 - x)))
        elif kind == "arc":
            # at most what fits between the margins (the default area fits every radius)
            radius = min(rng.uniform(8.0, 20.0), (min(w, h) - 2 * margin) / 2)
            sweep = rng.uniform(0.5, 1.5) * 2 * np.pi * rng.choice([-1.0, 1.0])
            a0 = rng.uniform(-np.pi, np.pi)
            cx = float(np.clip(x - radius * np.cos(a0), margin + radius, w - margin - radius))
            cy = float(np.clip(y - radius * np.sin(a0), margin + radius, h - margin - radius))
            # start on the circle (a short line there if the centre had to move in)
            sx, sy = cx + radius * np.cos(a0), cy + radius * np.sin(a0)
            if np.hypot(sx - x, sy - y) > 1e-9:
                line(float(np.hypot(sx - x, sy - y)), peak, float(np.arctan2(sy - y, sx - x)))
            move_s = max(1.875 * radius * abs(sweep) / peak, 0.1)
            segments.append((t, t + move_s, "arc", (cx, cy, radius, a0, a0 + sweep)))
            x, y, t = cx + radius * np.cos(a0 + sweep), cy + radius * np.sin(a0 + sweep), t + move_s
        else:  # pause, finger resting
            rest = rng.uniform(0.1, 0.5)
            segments.append((t, t + rest, "line", (x, y, x, y, 0.0, 0.0)))
            t += rest
    return Motion("human-varied", duration_s, dict(segments=segments))


def sample(motion: Motion, rate_hz: float, *, noise_mm: float = 0.0, jitter_s: float = 0.0,
           drop: float = 0.0, force_n: float = 0.5, seed: int = 0, finger: int = 0) -> Trace:
    """The motion as a touch screen at ``rate_hz`` reports it (down first, up last).

    ``noise_mm``: standard deviation of position noise; ``jitter_s``: standard deviation
    of the sample times about the regular grid (kept strictly increasing,
    :func:`_jittered`; each position is taken at its sample's time); ``drop``: share of
    samples in [0, 1) the screen never reports (drawn independently; the first and the
    last are always kept). The lift lies at the motion's end (:func:`sample_times`).
    """
    if rate_hz <= 0:
        raise InputError(f"sampling rate {rate_hz} Hz must be > 0")
    if not 0.0 <= drop < 1.0:
        raise InputError(f"drop {drop!r}: expected a share of samples in [0, 1)")
    _check_jitter(jitter_s, rate_hz)
    t = sample_times(motion.duration_s, rate_hz)
    n = t.size
    rng = np.random.default_rng(seed + 1)
    if jitter_s > 0:
        t = _jittered(t, rng.normal(0, jitter_s, n), motion.duration_s, rate_hz)
    if drop > 0:
        kept = rng.random(n) >= drop
        kept[0] = kept[-1] = True
        t = t[kept]
        n = t.size
    x, y = motion.position(t)
    if noise_mm > 0:
        x = x + rng.normal(0, noise_mm, n)
        y = y + rng.normal(0, noise_mm, n)
    event = np.full(n, MOVE, dtype=np.int8)
    event[0] = DOWN
    event[-1] = UP
    return make_trace(t, np.full(n, finger), x, y, np.full(n, force_n), event)


#: how close two samples' times are rounded together as a whole number of intervals
COUNT_TOLERANCE = 1e-9
#: least gap between jittered timestamps, in sample intervals
MIN_GAP_INTERVALS = 0.1


def sample_count(duration_s: float, rate_hz: float) -> int:
    """Samples in [0, ``duration_s``] (s) at ``rate_hz`` (Hz) (:func:`sample_times`): one
    every interval from 0, and one at the end itself unless the duration is a whole number
    of intervals, its last sample already there."""
    whole = _whole_intervals(duration_s, rate_hz)
    return whole + 1 if whole is not None else int(np.floor(duration_s * rate_hz)) + 2


def sample_times(duration_s: float, rate_hz: float) -> np.ndarray:
    """Sample times (s): k / ``rate_hz`` from 0, and ``duration_s`` itself last when the
    duration is not a whole number of intervals, so that a stroke or press lasts what was
    asked (1.01 s at 3 Hz ended at 1.0 s; a 1.3 s press at 3 Hz lifted at 1.0 s, at 0.55 N
    instead of its touch force)."""
    t = np.arange(sample_count(duration_s, rate_hz)) / rate_hz
    if _whole_intervals(duration_s, rate_hz) is None:
        t[-1] = duration_s
    return t


def _whole_intervals(duration_s: float, rate_hz: float) -> int | None:
    """The sample intervals in ``duration_s`` (s) at ``rate_hz`` (Hz) when they are a whole
    number to within COUNT_TOLERANCE (0.57 s at 100 Hz is 56.999... intervals in floating
    point: 57), else None."""
    intervals = duration_s * rate_hz
    whole = round(intervals)
    return int(whole) if abs(intervals - whole) < COUNT_TOLERANCE else None


def _jittered(t: np.ndarray, jitter: np.ndarray, duration_s: float, rate_hz: float) -> np.ndarray:
    """Times ``t`` (s) plus ``jitter`` (s), within [0, ``duration_s``] and kept strictly
    increasing: a time less than MIN_GAP_INTERVALS / ``rate_hz`` after the one before is
    moved to that gap (at 100 Hz and 0.004 s, 88 of 2001 timestamps repeated before), so
    the last few may pass ``duration_s`` by as many gaps."""
    t = np.maximum.accumulate(np.clip(t + jitter, 0, duration_s))
    gap = MIN_GAP_INTERVALS / rate_hz
    steps = np.arange(t.size) * gap
    pushed = np.maximum.accumulate(t - steps)  # t_i >= t_j + (i - j) gap for all j < i
    moved = pushed > t - steps
    t[moved] = pushed[moved] + steps[moved]  # the others keep their times bit for bit
    return t


def _check_jitter(jitter_s: float, rate_hz: float) -> None:
    """InputError for a timestamp jitter (s, standard deviation) of half the sample interval
    at ``rate_hz`` (Hz) or more: kept monotonic, such timestamps repeat (45 of 100 at 50 Hz
    and 0.05 s) and bunch before the end, shortening the trace."""
    half_interval_s = 0.5 / rate_hz
    if jitter_s >= half_interval_s:
        raise InputError(f"jitter {jitter_s:g} s: expected less than half the sample interval, "
                         f"{half_interval_s:g} s at {rate_hz:g} Hz (timestamps would repeat)")


def truth(motion: Motion, rate_hz: float = 10_000.0, force_n: float = 0.5) -> Trace:
    """The motion's true path at a high rate, no noise, on a uniform grid (for accuracy
    checks, whose reference needs one: ``rendering.metrics.reference``): up to its last
    whole interval, less than 1 / ``rate_hz`` s before its end, whose own sample
    (:func:`sample_times`) would break the grid."""
    whole = _whole_intervals(motion.duration_s, rate_hz)
    if whole is None:
        whole = int(np.floor(motion.duration_s * rate_hz))
        motion = replace(motion, duration_s=whole / rate_hz)
    return sample(motion, rate_hz, force_n=force_n)
