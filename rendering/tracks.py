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

from rendering.trace_file import DOWN, MOVE, UP, Trace


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


#: the per-sample arrays of a :class:`FingerBlock`, each (F, n)
BLOCK_FIELDS = ("contact", "touch_id", "x_held", "y_held", "x_pred", "y_pred", "vx", "vy",
                "force", "touch_start")


class FingerBlock:
    """Tracks for ``n`` output samples; per-finger arrays have shape (F, n), F = len(ids).

    t_s : (n,) output times (s). index0 : output index of the first sample.
    contact : bool. touch_id : int64, changes at every new touch (down or jump).
    x_held, y_held : last measured position (mm). x_pred, y_pred : predicted position (mm).
    vx, vy : velocity estimate (mm/s), 0 when not touching or resting.
    force : normal force (N). touch_start : time (s) the current touch began.

    Built with every array given as a keyword, or by :meth:`lazy` with a function that
    makes an array from its name on first access: a stage that never reads a field
    (SHO never reads the velocity, plain SHT never the held position) never pays for it.
    Read-only.
    """

    def __init__(self, index0: int, t_s: np.ndarray, ids: tuple[int, ...], **arrays):
        if set(arrays) != set(BLOCK_FIELDS):
            raise TypeError(f"FingerBlock needs the arrays {', '.join(BLOCK_FIELDS)}; got "
                            f"{', '.join(sorted(arrays)) or 'none'}")
        self._init(index0, t_s, ids, arrays, None)

    @classmethod
    def lazy(cls, index0: int, t_s: np.ndarray, ids: tuple[int, ...], make) -> "FingerBlock":
        """A block whose arrays are made by ``make(name)`` when first read."""
        block = cls.__new__(cls)
        block._init(index0, t_s, ids, {}, make)
        return block

    def _init(self, index0, t_s, ids, arrays, make):
        self.__dict__.update(arrays, index0=index0, t_s=t_s, ids=ids, _make=make)

    def __getattr__(self, name):  # only called for arrays not made yet
        make = self.__dict__.get("_make")
        if make is None or name not in BLOCK_FIELDS:
            raise AttributeError(f"FingerBlock has no attribute {name!r}")
        value = self.__dict__[name] = make(name)
        return value

    def __setattr__(self, name, value):
        raise AttributeError(f"FingerBlock is read-only (tried to set {name!r})")

    @property
    def n(self) -> int:
        return int(self.t_s.size)

    def with_force(self, force: np.ndarray) -> "FingerBlock":
        """The same tracks with the normal force (F, n) replaced, e.g. by what a device's
        force sensors measured."""
        made = {k: v for k, v in self.__dict__.items() if k in BLOCK_FIELDS}
        made["force"] = force
        block = FingerBlock.__new__(FingerBlock)
        block._init(self.index0, self.t_s, self.ids, made, self.__dict__.get("_make"))
        return block


def apply_index(t_s: np.ndarray, config: TrackerConfig) -> np.ndarray:
    """Output index from which each sample is used: the next block boundary at or after it."""
    pos = (np.asarray(t_s, dtype=np.float64) - config.t0_s) * config.rate_hz / config.quantum
    return (np.ceil(pos - 1e-9).astype(np.int64)) * config.quantum


def _line_fits(t, x, y, first):
    """Least-squares lines through each sample's window: velocity and fitted position.

    ``t, x, y`` (N,) hold a finger's samples; sample k's window is ``first[k] .. k``.
    Windows are gathered into a padded (N, J) table, J the longest window, and summed
    relative to the sample's own time, so nothing large cancels. Returns
    ``(vx, vy, xf, yf, ok)``; ``ok`` is False where the window has one distinct time.
    """
    k = np.arange(t.size)
    span = k - first
    j = np.arange(int(span.max(initial=0)) + 1)
    member = j[None, :] <= span[:, None]
    g = np.where(member, k[:, None] - j[None, :], k[:, None])
    dt = np.where(member, t[g] - t[:, None], 0.0)
    wx = np.where(member, x[g], 0.0)
    wy = np.where(member, y[g], 0.0)
    n = member.sum(axis=1).astype(np.float64)
    st, stt = dt.sum(axis=1), (dt * dt).sum(axis=1)
    sx, sy = wx.sum(axis=1), wy.sum(axis=1)
    stx, sty = (dt * wx).sum(axis=1), (dt * wy).sum(axis=1)
    denom = n * stt - st * st
    ok = denom > 1e-18
    safe = np.where(ok, denom, 1.0)
    vx = np.where(ok, (n * stx - st * sx) / safe, 0.0)
    vy = np.where(ok, (n * sty - st * sy) / safe, 0.0)
    return vx, vy, np.where(ok, (sx - vx * st) / n, x), np.where(ok, (sy - vy * st) / n, y), ok


def _last_true(mask: np.ndarray) -> np.ndarray:
    """For each position, the index of the last True at or before it (-1 if none)."""
    return np.maximum.accumulate(np.where(mask, np.arange(mask.size), -1))


def _finger_steps(fs: FingerState, t, x, y, force, event, cfg: TrackerConfig, counters: dict):
    """One finger's samples (in time order) applied to its state, all at once.

    Returns the per-sample state after each kept sample (dict of arrays named as
    ``_FIELDS``), the mask of kept samples, and the finger's state after the last one.
    """
    previous_t = np.maximum.accumulate(np.concatenate(([fs.t_sample], t[:-1])))
    keep = t >= previous_t  # older than the finger's last sample: dropped
    counters["out_of_order"] += int(np.count_nonzero(~keep))
    t, x, y, force, event = t[keep], x[keep], y[keep], force[keep], event[keep]
    if t.size == 0:
        return None, keep, fs
    contact_after = event != UP
    t_prev = np.concatenate(([fs.t_sample], t[:-1]))
    x_prev = np.concatenate(([fs.x], x[:-1]))
    y_prev = np.concatenate(([fs.y], y[:-1]))
    contact_prev = np.concatenate(([fs.contact], contact_after[:-1]))
    dist = np.hypot(x - x_prev, y - y_prev)
    jump = (contact_prev & (event == MOVE) & (dist > cfg.jump_min_mm)
            & (dist > cfg.jump_speed_mm_s * (t - t_prev)))
    counters["jumps"] += int(np.count_nonzero(jump))
    new_touch = (event == DOWN) | ~contact_prev | jump
    last_new = _last_true(new_touch)
    touch_id = fs.touch_id + np.cumsum(new_touch)
    t_down = np.where(last_new >= 0, t[np.maximum(last_new, 0)], fs.t_down)

    # velocity windows over the touch's earlier samples (kept in the state) and these
    h = len(fs.history) if fs.contact else 0
    ht = np.array([s[0] for s in fs.history[:h]] + t.tolist())
    hx = np.array([s[1] for s in fs.history[:h]] + x.tolist())
    hy = np.array([s[2] for s in fs.history[:h]] + y.tolist())
    g = h + np.arange(t.size)
    touch_first = np.where(last_new >= 0, h + last_new, 0)
    first = np.maximum(np.searchsorted(ht, t - cfg.velocity_window_s, side="left"), touch_first)
    # one distinct time in the window: the previous sample of the touch, if recent enough
    lone = ht[first] == t
    prev_ok = (g - 1 >= touch_first) & (t - ht[np.maximum(g - 1, 0)] <= cfg.max_gap_s)
    first = np.where(lone & prev_ok, g - 1, first)
    vx, vy, xf, yf, ok = _line_fits(ht, hx, hy, np.concatenate((np.zeros(h, np.int64), first)))
    vx, vy, xf, yf, ok = vx[h:], vy[h:], xf[h:], yf[h:], ok[h:]
    # no fit: keep the touch's last velocity (0 from its first sample on)
    source = _last_true(ok | new_touch)
    carried = source >= 0
    src = np.maximum(source, 0)
    vx = np.where(carried, np.where(new_touch[src] & ~ok[src], 0.0, vx[src]), fs.vx)
    vy = np.where(carried, np.where(new_touch[src] & ~ok[src], 0.0, vy[src]), fs.vy)
    up = ~contact_after
    steps = {"contact": contact_after.astype(np.float64), "touch_id": touch_id.astype(np.float64),
             "t_sample": t, "x": x, "y": y, "xf": np.where(up, x, xf), "yf": np.where(up, y, yf),
             "vx": np.where(up, 0.0, vx), "vy": np.where(up, 0.0, vy), "force": force,
             "t_down": t_down}
    last = t.size - 1
    if up[last]:
        history = ()
    else:
        lo = max(int(np.searchsorted(ht, t[last] - cfg.velocity_window_s)), int(touch_first[last]))
        history = tuple(zip(ht[lo:].tolist(), hx[lo:].tolist(), hy[lo:].tolist()))
    end = FingerState(bool(contact_after[last]), int(touch_id[last]), float(t[last]),
                      float(x[last]), float(y[last]), float(steps["xf"][last]),
                      float(steps["yf"][last]), float(steps["vx"][last]), float(steps["vy"][last]),
                      float(force[last]), float(t_down[last]), history)
    return steps, keep, end


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
    # per finger: (apply indices, state columns after each of its samples)
    updates: dict[int, tuple[np.ndarray, dict]] = {}
    if samples is not None and len(samples):
        applied = np.clip(apply_index(samples.t_s, config), index0, index0 + n - 1)
        for fid in np.unique(samples.finger).tolist():
            sel = samples.finger == fid
            steps, keep, fingers[fid] = _finger_steps(
                fingers.get(fid, FingerState()), samples.t_s[sel], samples.x_mm[sel],
                samples.y_mm[sel], samples.force_n[sel], samples.event[sel], config, counters)
            if steps is not None:
                updates[fid] = (applied[sel][keep], steps)
    ids = tuple(sorted(fingers))
    rows = []
    for fid in ids:
        before = np.array(_GET_FIELDS(state.fingers.get(fid, FingerState())), dtype=np.float64)
        at, steps = updates.get(fid, (np.zeros(0, np.int64), None))
        table = before[:, None] if steps is None else np.column_stack(
            (before, np.array([steps[name] for name in _FIELDS])))
        # step j holds from its apply index to the next step's (a later step applied at
        # the same index overrides it: a run of length 0)
        rows.append((table, np.diff(np.concatenate(([0], at - index0, [n])))))
    block = FingerBlock.lazy(index0, t_out, ids, _BlockArrays(t_out, rows, config).make)
    return block, TrackerState(fingers=fingers, **counters)


#: FingerBlock arrays read straight from a state column (the column's name)
_HELD = {"x_held": "x", "y_held": "y", "force": "force", "touch_start": "t_down"}


class _BlockArrays:
    """The arrays of a :class:`FingerBlock`, made on demand from each finger's
    piecewise-constant state columns (one ``np.repeat`` per column and finger)."""

    def __init__(self, t_out: np.ndarray, rows, config: TrackerConfig):
        self.t_out = t_out
        self.rows = rows  # per finger: (state table (len(_FIELDS), k), run lengths (k,))
        self.config = config
        self.cache: dict[str, np.ndarray] = {}

    def column(self, name: str) -> np.ndarray:
        """State column ``name`` at every output sample, float64 (F, n)."""
        if name not in self.cache:
            k = _FIELDS.index(name)
            out = np.empty((len(self.rows), self.t_out.size))
            for row, (table, runs) in enumerate(self.rows):
                out[row] = np.repeat(table[k], runs)
            self.cache[name] = out
        return self.cache[name]

    def motion(self):
        """(contact, moving, ahead): touching; touching and sampled within the prediction
        horizon; time (s) since the sample, clipped to [0, horizon]."""
        if "ahead" not in self.cache:
            horizon = self.config.predict_horizon_s
            contact = self.column("contact") > 0.5
            since = self.t_out[None, :] - self.column("t_sample")
            self.cache["contact_bool"] = contact
            self.cache["moving"] = contact & (since <= horizon)
            self.cache["ahead"] = np.clip(since, 0.0, horizon, out=since)
        return self.cache["contact_bool"], self.cache["moving"], self.cache["ahead"]

    def make(self, name: str) -> np.ndarray:
        if name in _HELD:
            return self.column(_HELD[name])
        if name == "touch_id":
            return self.column("touch_id").astype(np.int64)
        if name == "contact":
            return self.column("contact") > 0.5
        contact, moving, ahead = self.motion()
        if name in ("vx", "vy"):
            return np.where(moving, self.column(name), 0.0)
        axis = name[0]  # x_pred, y_pred
        return np.where(contact, self.column(axis + "f") + self.column("v" + axis) * ahead,
                        self.column(axis))
