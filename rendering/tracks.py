"""Finger tracks: from timestamped touch samples to position and velocity at every output sample.

Touch screens report a finger 50 to 1000 times a second; the haptic output runs at
kHz. For each output sample this stage says, per finger: whether it touches, where
it was last measured (what plain SHO uses, seed 003 section 4.4.1), where it probably
is now (constant-velocity prediction from a smoothed fit), its velocity (what SHT
integrates, section 4.4.2) and its normal force.

When a sample takes effect. The live haptic thread drains its input queue at the
start of each block, so a touch sample is used from the first block boundary at or
after its timestamp. Replay applies the same rule to the sample times (block size
``quantum`` output samples), which makes replay reproduce live timing exactly and
makes the output independent of how many blocks one call processes.

Velocity. At each sample a least-squares line is fitted to the finger's samples of the
last ``velocity_window_s`` (at least the last two distinct times no further apart than
``max_gap_s``); its slope is the velocity, its value at the sample time the smoothed
position. A line fit, not a finite difference, because real controllers re-report a
finger unmoved 0.6 ms after another one moves (refdata phone-two-finger-drag): a
difference quotient there swings between 0 and twice the true speed.

Guards, all counted: a sample older than the finger's last one is dropped
(``out_of_order``); a sample whose implied speed exceeds ``jump_speed_mm_s`` over more
than ``jump_min_mm`` is a lift and a touch elsewhere (``jumps``: velocity and SHT phase
restart); after ``predict_horizon_s`` without a new sample the finger is taken as
resting (prediction stops, velocity 0), so a screen that stops reporting a still
finger does not leave SHT synthesising forever.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from operator import attrgetter

import numpy as np

from rendering.trace_file import DOWN, UP, Trace


@dataclass(frozen=True)
class TrackerConfig:
    """Tracking parameters (times in s, distances in mm, speeds in mm/s)."""

    rate_hz: float = 10_000.0
    quantum: int = 50
    t0_s: float = 0.0
    velocity_window_s: float = 0.05
    max_gap_s: float = 0.1
    predict_horizon_s: float = 0.06
    jump_speed_mm_s: float = 2000.0
    jump_min_mm: float = 10.0


@dataclass(frozen=True)
class FingerState:
    """One finger between two calls: its last sample and its velocity fit window."""

    contact: bool = False
    touch_id: int = 0
    t_sample: float = -math.inf
    x: float = 0.0
    y: float = 0.0
    xf: float = 0.0
    yf: float = 0.0
    vx: float = 0.0
    vy: float = 0.0
    force: float = 0.0
    t_down: float = math.inf
    history: tuple[tuple[float, float, float], ...] = ()  # (t, x, y) within the window


@dataclass(frozen=True)
class TrackerState:
    fingers: dict[int, FingerState] = field(default_factory=dict)
    jumps: int = 0
    out_of_order: int = 0


@dataclass(frozen=True, eq=False)
class FingerBlock:
    """Tracks for ``n`` output samples; per-finger arrays have shape (F, n), F = len(ids).

    t_s : (n,) output times (s). index0 : output index of the first sample.
    contact : bool. touch_id : int64, changes at every new touch (down or jump).
    x_held, y_held : last measured position (mm). x_pred, y_pred : predicted position (mm).
    vx, vy : velocity estimate (mm/s), 0 when not touching or resting.
    force : normal force (N). touch_start : time (s) the current touch began.
    """

    index0: int
    t_s: np.ndarray
    ids: tuple[int, ...]
    contact: np.ndarray
    touch_id: np.ndarray
    x_held: np.ndarray
    y_held: np.ndarray
    x_pred: np.ndarray
    y_pred: np.ndarray
    vx: np.ndarray
    vy: np.ndarray
    force: np.ndarray
    touch_start: np.ndarray

    @property
    def n(self) -> int:
        return int(self.t_s.size)


def apply_index(t_s: np.ndarray, config: TrackerConfig) -> np.ndarray:
    """Output index from which each sample is used: the next block boundary at or after it."""
    pos = (np.asarray(t_s, dtype=np.float64) - config.t0_s) * config.rate_hz / config.quantum
    return (np.ceil(pos - 1e-9).astype(np.int64)) * config.quantum


def _fit(history, t_now: float, x_now: float, y_now: float):
    """Least-squares line through (t, x) and (t, y): velocity and position at t_now."""
    n = len(history)
    if n < 2:
        return x_now, y_now, None
    st = sx = sy = stt = stx = sty = 0.0
    for t, x, y in history:
        dt = t - t_now
        st += dt
        sx += x
        sy += y
        stt += dt * dt
        stx += dt * x
        sty += dt * y
    denom = n * stt - st * st
    if denom <= 1e-18:
        return x_now, y_now, None
    vx = (n * stx - st * sx) / denom
    vy = (n * sty - st * sy) / denom
    return (sx - vx * st) / n, (sy - vy * st) / n, (vx, vy)


def _update_finger(fs: FingerState, t: float, x: float, y: float, force: float, event: int,
                   cfg: TrackerConfig, counters: dict) -> FingerState:
    """The finger's state after one sample (events already normalised)."""
    if fs.contact and t < fs.t_sample:
        counters["out_of_order"] += 1
        return fs
    new_touch = event == DOWN or not fs.contact
    if not new_touch and event != UP:
        dist = math.hypot(x - fs.x, y - fs.y)
        if dist > cfg.jump_min_mm and dist > cfg.jump_speed_mm_s * (t - fs.t_sample):
            counters["jumps"] += 1
            new_touch = True
    if new_touch:
        return FingerState(contact=event != UP, touch_id=fs.touch_id + 1, t_sample=t, x=x, y=y,
                           xf=x, yf=y, vx=0.0, vy=0.0, force=force, t_down=t,
                           history=((t, x, y),))
    history = tuple(h for h in fs.history if h[0] >= t - cfg.velocity_window_s) + ((t, x, y),)
    if history[0][0] == t:  # one distinct time (times in the window never decrease)
        # too few samples in the window: the last two, if close enough in time
        recent = tuple(h for h in fs.history[-1:] if t - h[0] <= cfg.max_gap_s)
        history = recent + ((t, x, y),)
    xf, yf, vel = _fit(history, t, x, y)
    vx, vy = vel if vel is not None else (fs.vx, fs.vy)
    if event == UP:
        return FingerState(False, fs.touch_id, t, x, y, x, y, 0.0, 0.0, force, fs.t_down, ())
    return FingerState(fs.contact, fs.touch_id, t, x, y, xf, yf, vx, vy, force, fs.t_down, history)


_FIELDS = ("contact", "touch_id", "t_sample", "x", "y", "xf", "yf", "vx", "vy", "force", "t_down")
_GET_FIELDS = attrgetter(*_FIELDS)


def track(index0: int, n: int, samples: Trace | None, state: TrackerState,
          config: TrackerConfig) -> tuple[FingerBlock, TrackerState]:
    """Tracks for output samples ``index0 .. index0 + n - 1``.

    Parameters
    ----------
    index0, n : first output index and number of output samples.
    samples : touch samples taking effect in this range (their apply index, see
        :func:`apply_index`, is clamped into it), or None.
    state : the tracker state after the previous call.
    config : tracking parameters.

    Returns
    -------
    (FingerBlock, TrackerState)
    """
    idx = index0 + np.arange(n, dtype=np.int64)
    t_out = config.t0_s + idx / config.rate_hz
    fingers = dict(state.fingers)
    counters = {"jumps": state.jumps, "out_of_order": state.out_of_order}
    # per finger: list of (apply index, FingerState after the sample)
    updates: dict[int, list[tuple[int, FingerState]]] = {}
    if samples is not None and len(samples):
        applied = np.clip(apply_index(samples.t_s, config), index0, index0 + n - 1)
        columns = (applied, samples.finger, samples.t_s, samples.x_mm, samples.y_mm,
                   samples.force_n, samples.event)
        # plain Python numbers: indexing numpy arrays one sample at a time is the slow part
        for at, fid, t, x, y, force, event in zip(*(c.tolist() for c in columns)):
            fs = fingers.get(fid, FingerState())
            fs = _update_finger(fs, t, x, y, force, event, config, counters)
            fingers[fid] = fs
            updates.setdefault(fid, []).append((at, fs))
    ids = tuple(sorted(fingers))
    values = np.empty((len(_FIELDS), len(ids), n))
    for row, fid in enumerate(ids):
        before = state.fingers.get(fid, FingerState())
        steps = [(index0 - 1, before)] + updates.get(fid, [])
        # step j holds from its apply index to the next step's (a later step applied at
        # the same index overrides it: a run of length 0)
        starts = np.array([max(s[0] - index0, 0) for s in steps] + [n], dtype=np.int64)
        table = np.array([_GET_FIELDS(s[1]) for s in steps], dtype=np.float64).T
        values[:, row, :] = np.repeat(table, np.diff(starts), axis=1)
    arrays = dict(zip(_FIELDS, values))
    contact = arrays["contact"] > 0.5
    since = t_out[None, :] - arrays["t_sample"]
    moving = contact & (since <= config.predict_horizon_s)
    ahead = np.clip(since, 0.0, config.predict_horizon_s)
    vx = np.where(moving, arrays["vx"], 0.0)
    vy = np.where(moving, arrays["vy"], 0.0)
    block = FingerBlock(
        index0=index0, t_s=t_out, ids=ids, contact=contact,
        touch_id=arrays["touch_id"].astype(np.int64),
        x_held=arrays["x"], y_held=arrays["y"],
        x_pred=np.where(contact, arrays["xf"] + arrays["vx"] * ahead, arrays["x"]),
        y_pred=np.where(contact, arrays["yf"] + arrays["vy"] * ahead, arrays["y"]),
        vx=vx, vy=vy, force=arrays["force"], touch_start=arrays["t_down"])
    return block, TrackerState(fingers=fingers, **counters)
