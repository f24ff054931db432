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
``max_gap_s``), the latest ``fit_samples`` of them at most; its slope is the velocity, its
value at the sample time the smoothed position. The cap bounds the cost: each sample's fit
sums at most ``fit_samples`` rows, so a block costs time linear in its samples however
closely they crowd (100,000 samples within 0.1 ms once summed all 5e9 pairs). A screen
reporting 1 kHz puts 50 samples in the default 50 ms window, one at 5 kHz 250: the cap
(256) changes no fit of a screen's trace. A line fit, not a finite difference, because real controllers re-report a
finger unmoved 0.6 ms after another one moves (refdata phone-two-finger-drag): a
difference quotient there swings between 0 and twice the true speed.

A fit spanning less than ``min_fit_span_s`` gives no velocity (the touch's last one is
carried, 0 on a new touch): it cannot tell motion from a re-reported position. A
controller reports a touch down at 20.0 mm and its refined position, 20.3 mm, 0.6 ms
later: a line through those two is 500 mm/s, and the prediction ran 10 mm past a still
finger within 20 ms. 0.3 mm of position noise over 10 ms is 30 mm/s at most (0.6 mm over
20 ms of prediction); a 50 Hz screen's first fit spans 20 ms anyway, a 1 kHz screen's
touch starts with 10 ms at velocity 0.

Guards, all counted: a sample older than the finger's last one is dropped
(``out_of_order``); a sample that the touch's recent motion does not explain is a lift
and a touch elsewhere (``jumps``: velocity and SHT phase restart). Recent motion: the
chord over the velocity window, i.e. the mean velocity over its span S (at least
``min_fit_span_s``). A finger whose acceleration stays within ``accel_max_mm_s2`` lands,
dt after the last sample, within ``accel_max * dt * (dt + S) / 2`` of where that chord
leads (its velocity differs from the chord's mean by at most ``accel_max`` times the
time since the chord's midpoint; integrated over dt). A sample off by more than that
plus ``jump_min_mm`` (what touch noise and a rolling fingerpad move a reported position)
is a jump. 20 m/s^2 is 1.5 times the peak acceleration of the fastest stroke the human
motion model makes (a 30 mm flick in 0.11 s, 13.7 m/s^2: RENDERERS.md); at 50 Hz
(dt = 20 ms, S = 40 ms) the bound is 12 mm, so a finger teleported 30 mm within one
sample is a new touch, where a bound of 2 m/s times dt (40 mm) took it for motion and
SHT played 12 edges of a 5 mm grating in 100 ms. With no velocity known (the touch's
first samples), the bound is ``jump_speed_mm_s`` (a finger's top speed) times dt.
A swipe at any steady speed is no jump; a long gap's bound (0.5 s: 2.7 m) is no jump on
any display. After
``predict_horizon_s`` without a new sample the finger is taken as resting (prediction
stops, velocity 0), so a screen that stops reporting a still finger does not leave SHT
synthesising forever. A touch sample past the display's edge (``area_mm``) is taken at
the edge as it comes in, so every renderer plays it there: with only the prediction held
there, SHO-held and SHT went on playing a grating from the raw position and velocity (a
tablet's two-finger drag on grating-5mm, 108 mm wide: mu' changed 156 and 170 times at
x = 108 mm; now 4 and 10, as the velocity fit slows to the still finger at the edge, as
anywhere a finger stops). A prediction stays on the display too: a
finger touching the screen is on it, and a fit running on past where a finger stopped at the edge (a
phone's two-finger drag to the edge, silent for 86 ms before the lift: 12.7 mm past the
140 mm plate) would render, and count as off the structure, a place nobody touched.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, field
from operator import attrgetter
from typing import TYPE_CHECKING

import numpy as np
import numpy.typing as npt

from frictex.device.jit import njit
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, Trace


#: the largest acceleration of a finger (mm/s^2) and the shortest span of samples a
#: velocity is fitted over (s): module docstring
ACCEL_MAX_MM_S2, MIN_FIT_SPAN_S = 20_000.0, 0.01


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
    accel_max_mm_s2: float = ACCEL_MAX_MM_S2
    min_fit_span_s: float = MIN_FIT_SPAN_S
    fit_samples: int = 256
    #: the display's (width, height) (mm): touch samples and predictions stay within it;
    #: None: unbounded
    area_mm: tuple[float, float] | None = None


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
    """The fingers touching (a lifted finger is forgotten), the guards' counts, and the
    largest touch id issued: a finger the tracker does not know starts from it, so a
    touch id is never reused by the same finger id (layers key their state on both)."""

    fingers: dict[int, FingerState] = field(default_factory=dict)
    jumps: int = 0
    out_of_order: int = 0
    touches: int = 0


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

    Built with every array given as a keyword; ``track`` makes all of them in one
    compiled pass (``_expand``), a few microseconds per 5 ms block, which is less than
    making only the ones a stage reads with numpy would cost. Read-only.
    """

    index0: int
    t_s: npt.NDArray[np.float64]
    ids: tuple[int, ...]
    contact: npt.NDArray[np.bool_]
    touch_id: npt.NDArray[np.int64]
    x_held: npt.NDArray[np.float64]
    y_held: npt.NDArray[np.float64]
    x_pred: npt.NDArray[np.float64]
    y_pred: npt.NDArray[np.float64]
    vx: npt.NDArray[np.float64]
    vy: npt.NDArray[np.float64]
    force: npt.NDArray[np.float64]
    touch_start: npt.NDArray[np.float64]

    def __init__(self, index0: int, t_s: np.ndarray, ids: tuple[int, ...], **arrays):
        if set(arrays) != set(BLOCK_FIELDS):
            raise TypeError(f"FingerBlock needs the arrays {', '.join(BLOCK_FIELDS)}; got "
                            f"{', '.join(sorted(arrays)) or 'none'}")
        self.__dict__.update(arrays, index0=index0, t_s=t_s, ids=ids)

    if not TYPE_CHECKING:  # a type checker sees the fields above, so a misspelt one fails it
        def __getattr__(self, name):  # only called for names that are not there
            raise AttributeError(f"FingerBlock has no attribute {name!r}")

        def __setattr__(self, name, value):
            raise AttributeError(f"FingerBlock is read-only (tried to set {name!r})")

    @property
    def n(self) -> int:
        return int(self.t_s.size)

    def with_force(self, force: np.ndarray) -> "FingerBlock":
        """The same tracks with the normal force (F, n) replaced, e.g. by what a device's
        force sensors measured."""
        arrays = {name: getattr(self, name) for name in BLOCK_FIELDS}
        arrays["force"] = force
        return FingerBlock(self.index0, self.t_s, self.ids, **arrays)

    def read_only(self) -> "FingerBlock":
        """The same tracks as views numpy refuses to write into, for code frictex does not
        own (another package's renderer): a write into one would change what every later
        layer, the composition and the outputs read."""
        def view(array: np.ndarray) -> np.ndarray:
            frozen = array.view()
            frozen.flags.writeable = False
            return frozen
        arrays = {name: view(getattr(self, name)) for name in BLOCK_FIELDS}
        return FingerBlock(self.index0, view(self.t_s), self.ids, **arrays)


def apply_index(t_s: np.ndarray, config: TrackerConfig) -> np.ndarray:
    """Output index from which each sample is used: the next block boundary at or after it.

    A sample meant to fall on a boundary is off it by the rounding of its time and of its
    position in blocks, both of which grow with the clock's reading: a log whose clock
    reads 1e9 s holds its times to 1.2e-7 s (2.4e-5 of a 5 ms block). Within four such
    roundings of a boundary (and 1e-9 block) a sample is on it, so that where the clock
    starts changes no block a sample is used from."""
    t = np.asarray(t_s, dtype=np.float64)
    per_s = config.rate_hz / config.quantum  # blocks per second
    pos = (t - config.t0_s) * per_s
    slack = 4.0 * (np.spacing(np.abs(t)) * per_s + np.spacing(np.abs(pos))) + 1e-9
    return (np.ceil(pos - slack).astype(np.int64)) * config.quantum


def _finger_steps(fs: FingerState, t, x, y, force, event, cfg: TrackerConfig, counters: dict):
    """One finger's samples (in time order) applied to its state, all at once.

    Returns the state after each kept sample ((len(_FIELDS), m) float64, rows named by
    ``_FIELDS``), the mask of kept samples, and the finger's state after the last one.
    """
    h = len(fs.history) if fs.contact else 0
    history = np.array(fs.history[:h], dtype=np.float64).reshape(h, 3)
    keep, table, dropped, jumps, lo, window = _steps_kernel(
        (fs.contact, fs.touch_id, fs.t_sample, fs.x, fs.y, fs.vx, fs.vy, fs.t_down), history,
        np.ascontiguousarray(t, dtype=np.float64), np.ascontiguousarray(x, dtype=np.float64),
        np.ascontiguousarray(y, dtype=np.float64), np.ascontiguousarray(force, dtype=np.float64),
        np.ascontiguousarray(event, dtype=np.int8),
        (cfg.velocity_window_s, cfg.max_gap_s, cfg.jump_speed_mm_s, cfg.jump_min_mm),
        max(int(cfg.fit_samples), 2), (cfg.accel_max_mm_s2, cfg.min_fit_span_s))
    counters["out_of_order"] += dropped
    counters["jumps"] += jumps
    if table.shape[1] == 0:
        return None, keep, fs
    last = table[:, -1].tolist()
    end = FingerState(last[0] > 0.5, int(last[1]), *last[2:],
                      tuple(map(tuple, window[lo:].tolist())) if lo >= 0 else ())
    return table, keep, end


@njit(cache=True, nogil=True)
def _steps_kernel(fs, history, t, x, y, force, event, cfg, cap,
                  motion=(ACCEL_MAX_MM_S2, MIN_FIT_SPAN_S)):
    """:func:`_finger_steps` in one compiled pass.

    fs : the finger's (contact, touch_id, t_sample, x, y, vx, vy, t_down) before the
    samples; history : (h, 3) its touch's (t, x, y) within the velocity window (h = 0 if
    not touching); t, x, y, force, event : its samples (s, mm, mm, N, event code);
    cfg : (velocity_window_s, max_gap_s, jump_speed_mm_s, jump_min_mm); cap : most rows
    of a fit (``fit_samples``, at least 2); motion : (accel_max_mm_s2, min_fit_span_s).

    Returns ``(keep, table, dropped, jumps, lo, window)``: the kept samples, the state
    after each kept sample (len(_FIELDS), m), the counts of dropped (out of order)
    samples and of jumps, and the rows ``window[lo:]`` ((t, x, y), history then kept
    samples) to carry as the touch's history (lo = -1: the finger lifted).

    Velocity: a least-squares line through each sample's window (the touch's samples of
    the last ``velocity_window_s``, at least the previous sample of the touch if it is
    recent enough), summed relative to the sample's own time and position so nothing
    large cancels: a finger at rest has all position terms exactly 0, so its velocity is
    exactly 0 and its fitted position exactly its own (uncentred sums of x = 50 mm left
    +-7.4e-13 mm/s, and SHT's phase stepped back across a grating edge).
    The sums are those of a padded (rows, J) table summed along its rows by numpy
    (:func:`_pairwise`; J the longest window among the history and the samples, at most
    ``cap``): the work is about 12 J per sample, linear in the samples.
    """
    fs_contact, fs_touch, fs_t, fs_x, fs_y, fs_vx, fs_vy, fs_t_down = fs
    window_s, max_gap, jump_speed, jump_min = cfg
    accel_max, min_span = motion
    m_all = t.size
    keep = np.empty(m_all, dtype=np.bool_)
    latest = fs_t
    for i in range(m_all):  # older than the finger's last sample: dropped
        keep[i] = t[i] >= latest
        latest = max(latest, t[i])
    idx = np.flatnonzero(keep)
    m, h = idx.size, history.shape[0]
    table = np.empty((11, m))
    if m == 0:
        return keep, table, m_all, 0, -1, np.empty((0, 3))
    # (t, x, y) of the touch's earlier samples and of these
    win = np.empty((h + m, 3))
    win[:h] = history
    new_touch = np.empty(m, dtype=np.bool_)
    touch_first = np.empty(m, dtype=np.int64)
    jumps = 0
    t_prev, x_prev, y_prev, contact_prev = fs_t, fs_x, fs_y, fs_contact
    touch, t_down, last_new = fs_touch, fs_t_down, -1
    for k in range(m):
        i = idx[k]
        g = h + k
        win[g, 0], win[g, 1], win[g, 2] = t[i], x[i], y[i]
        # a jump: a move the touch's recent motion does not explain (module docstring).
        # That motion: the chord over the rows a next call keeps as history (the
        # velocity window), not the last step: a screen re-reports a finger unmoved
        # 0.6 ms after another one moves
        jump = False
        if contact_prev and event[i] == MOVE:
            last = g - 1
            f = max(np.searchsorted(win[:g, 0], win[last, 0] - window_s),
                    touch_first[k - 1] if k > 0 else 0, last - cap + 1)
            span_s = win[last, 0] - win[f, 0]
            dt = t[i] - t_prev
            vx_recent = vy_recent = 0.0
            bound = jump_speed * dt  # no velocity known: a finger's top speed
            if span_s > 0.0 and span_s >= min_span:
                vx_recent = (win[last, 1] - win[f, 1]) / span_s
                vy_recent = (win[last, 2] - win[f, 2]) / span_s
                bound = accel_max * dt * (dt + span_s) / 2
            off = np.hypot(x[i] - x_prev - vx_recent * dt, y[i] - y_prev - vy_recent * dt)
            jump = off > jump_min + bound
        if jump:
            jumps += 1
        new_touch[k] = event[i] == DOWN or not contact_prev or jump
        if new_touch[k]:
            touch += 1
            t_down, last_new = t[i], k
        touch_first[k] = h + last_new if last_new >= 0 else 0
        contact_prev = event[i] != UP
        t_prev, x_prev, y_prev = t[i], x[i], y[i]
        table[0, k], table[1, k], table[2, k] = 1.0 if contact_prev else 0.0, touch, t[i]
        table[3, k], table[4, k], table[9, k], table[10, k] = x[i], y[i], force[i], t_down
    # each kept sample's window first[k] .. h + k
    first = np.empty(m, dtype=np.int64)
    longest = min(h, cap) - 1  # history rows' windows (their fits are not used) pad the table too
    for k in range(m):
        g = h + k
        tk = win[g, 0]
        f = max(np.searchsorted(win[:, 0], tk - window_s), touch_first[k], g - cap + 1)
        # one distinct time in the window: the previous sample of the touch, if recent enough
        if win[f, 0] == tk and g - 1 >= touch_first[k] and tk - win[max(g - 1, 0), 0] <= max_gap:
            f = g - 1
        first[k] = f
        longest = max(longest, g - f)
    width = max(longest, 0) + 1
    pad = np.zeros((6, width))
    source_v = np.empty(2)  # the velocity carried where no fit is possible
    source_v[0], source_v[1] = fs_vx, fs_vy
    for k in range(m):
        g = h + k
        span = g - first[k]
        pad[:] = 0.0
        for j in range(span + 1):
            dt = win[g - j, 0] - win[g, 0]
            pad[0, j], pad[1, j] = dt, dt * dt
            dx, dy = win[g - j, 1] - win[g, 1], win[g - j, 2] - win[g, 2]
            pad[2, j], pad[3, j] = dx, dy
            pad[4, j], pad[5, j] = dt * dx, dt * dy
        n = float(span + 1)
        st, stt = _pairwise(pad[0], 0, width), _pairwise(pad[1], 0, width)
        sx, sy = _pairwise(pad[2], 0, width), _pairwise(pad[3], 0, width)
        stx, sty = _pairwise(pad[4], 0, width), _pairwise(pad[5], 0, width)
        denom = n * stt - st * st
        ok = denom > 1e-18 and win[g, 0] - win[first[k], 0] >= min_span
        vx = (n * stx - st * sx) / denom if ok else 0.0
        vy = (n * sty - st * sy) / denom if ok else 0.0
        xf = win[g, 1] + (sx - vx * st) / n if ok else win[g, 1]
        yf = win[g, 2] + (sy - vy * st) / n if ok else win[g, 2]
        # no fit (or one too short to tell motion from noise): keep the touch's last
        # velocity (0 from its first sample on)
        if ok:
            source_v[0], source_v[1] = vx, vy
        elif new_touch[k]:
            source_v[0], source_v[1] = 0.0, 0.0
        up = table[0, k] == 0.0
        table[5, k] = win[g, 1] if up else xf
        table[6, k] = win[g, 2] if up else yf
        table[7, k] = 0.0 if up else source_v[0]
        table[8, k] = 0.0 if up else source_v[1]
    lo = -1
    if table[0, m - 1] != 0.0:
        last_t = win[h + m - 1, 0]
        lo = max(np.searchsorted(win[:, 0], last_t - window_s), touch_first[m - 1],
                 h + m - cap + 1)
    return keep, table, m_all - m, jumps, lo, win


@njit(cache=True, nogil=True)
def _pairwise(a, lo, n):
    """Sum of ``a[lo:lo + n]`` in the order numpy's ``sum`` adds a contiguous row
    (pairwise: 8 running sums for up to 128 values, halves above), so that the sums
    are those of the table summation this kernel replaced, to the last bit. The halving
    runs on an explicit stack: numba's cache does not keep recursive functions safely."""
    if n <= 128:
        return _block_sum(a, lo, n)
    frames = np.empty((64, 3), dtype=np.int64)  # (lo, n, children summed); depth ~log2(n)
    sums = np.empty(64)
    top, count = 1, 0
    frames[0, 0], frames[0, 1], frames[0, 2] = lo, n, 0
    while top > 0:
        top -= 1
        f_lo, f_n, done = frames[top, 0], frames[top, 1], frames[top, 2]
        if f_n <= 128:
            sums[count] = _block_sum(a, f_lo, f_n)
            count += 1
        elif done:
            sums[count - 2] += sums[count - 1]
            count -= 1
        else:
            half = f_n // 2
            half -= half % 8
            frames[top, 2] = 1
            frames[top + 1, 0], frames[top + 1, 1], frames[top + 1, 2] = f_lo, half, 0
            frames[top + 2, 0], frames[top + 2, 1], frames[top + 2, 2] = f_lo + half, f_n - half, 0
            top += 3
    return sums[0]


@njit(cache=True, nogil=True)
def _block_sum(a, lo, n):
    """numpy's pairwise sum of up to 128 contiguous values (see :func:`_pairwise`)."""
    if n < 8:
        res = -0.0
        for i in range(lo, lo + n):
            res += a[i]
        return res
    r0, r1, r2, r3 = a[lo], a[lo + 1], a[lo + 2], a[lo + 3]
    r4, r5, r6, r7 = a[lo + 4], a[lo + 5], a[lo + 6], a[lo + 7]
    i = 8
    while i < n - n % 8:
        r0 += a[lo + i]
        r1 += a[lo + i + 1]
        r2 += a[lo + i + 2]
        r3 += a[lo + i + 3]
        r4 += a[lo + i + 4]
        r5 += a[lo + i + 5]
        r6 += a[lo + i + 6]
        r7 += a[lo + i + 7]
        i += 8
    res = ((r0 + r1) + (r2 + r3)) + ((r4 + r5) + (r6 + r7))
    while i < n:
        res += a[lo + i]
        i += 1
    return res


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
    updates: dict[int, tuple[np.ndarray, np.ndarray]] = {}
    sampled = sorted(set(samples.finger.tolist())) if samples is not None else []
    if sampled:
        applied = np.minimum(np.maximum(apply_index(samples.t_s, config), index0), index0 + n - 1)
        x_mm, y_mm = _on_display(samples.x_mm, samples.y_mm, config.area_mm)
        # each finger's samples in file order, found by one sort (a mask per finger would
        # cost fingers x samples: a block of 50,000 short touches)
        order = np.argsort(samples.finger, kind="stable")
        bounds = np.searchsorted(samples.finger[order], sampled + [sampled[-1] + 1]).tolist()
        for k, fid in enumerate(sampled):
            sel = slice(None) if len(sampled) == 1 else order[bounds[k]:bounds[k + 1]]
            steps, keep, fingers[fid] = _finger_steps(
                fingers.get(fid, FingerState(touch_id=state.touches)), samples.t_s[sel], x_mm[sel],
                y_mm[sel], samples.force_n[sel], samples.event[sel], config, counters)
            if steps is not None:
                updates[fid] = (applied[sel][keep], steps)
    # the fingers touching when the block starts and those sampled in it; a finger that
    # lifted is forgotten once its lift is out, so the cost follows the fingers touching
    # at once, not every id a recording ever used
    ids = tuple(sorted(set(sampled) | set(state.fingers)))
    table, runs, steps = _step_table(ids, state, updates, index0, n)
    (x_lo, y_lo), (x_hi, y_hi) = ((0.0, 0.0), config.area_mm) if config.area_mm else (
        (-math.inf, -math.inf), (math.inf, math.inf))
    arrays = _expand(table, runs, steps, t_out, float(config.predict_horizon_s),
                     np.array([x_lo, x_hi, y_lo, y_hi], dtype=np.float64))
    block = FingerBlock(index0, t_out, ids, **dict(zip(BLOCK_FIELDS, arrays)))
    touching = {fid: s for fid, s in fingers.items() if s.contact}
    touches = max([state.touches, *(s.touch_id for s in fingers.values())])
    return block, TrackerState(fingers=touching, touches=touches, **counters)


def _on_display(x_mm: np.ndarray, y_mm: np.ndarray, area_mm) -> tuple[np.ndarray, np.ndarray]:
    """Touch positions (mm) held within the display's ``area_mm`` (width, height from
    (0, 0); None: as they are): a sample past the edge is taken at the edge, so the held
    position, the fit and its velocity (what SHO-held and SHT play from) agree with the
    prediction, which stays within it too."""
    if area_mm is None:
        return x_mm, y_mm
    return np.clip(x_mm, 0.0, area_mm[0]), np.clip(y_mm, 0.0, area_mm[1])


def _step_table(ids, state: TrackerState, updates: dict, index0: int, n: int):
    """:func:`_expand`'s ``table``, ``runs`` and ``steps`` for the fingers ``ids``: each
    finger's state when the block starts, then its ``updates`` (apply indices, state
    columns) if any."""
    counts = [1 + (updates[fid][1].shape[1] if fid in updates else 0) for fid in ids]
    table = np.empty((len(_FIELDS), sum(counts)))
    runs = np.empty(sum(counts), dtype=np.int64)
    col = 0
    for fid, count in zip(ids, counts):
        known = state.fingers.get(fid)
        table[:, col] = _GET_FIELDS(FingerState(touch_id=state.touches) if known is None else known)
        if count == 1:
            runs[col] = n
        else:
            at, steps = updates[fid]
            table[:, col + 1:col + count] = steps
            # step j holds from its apply index to the next step's (a later step applied at
            # the same index overrides it: a run of length 0)
            edges = at - index0
            runs[col] = edges[0]
            runs[col + 1:col + count - 1] = edges[1:] - edges[:-1]
            runs[col + count - 1] = n - edges[-1]
        col += count
    return table, runs, np.array(counts, dtype=np.int64)


@njit(cache=True, nogil=True)
def _expand(table, runs, steps, t_out, horizon, area):
    """The arrays of a :class:`FingerBlock` (in ``BLOCK_FIELDS`` order, each (F, n)) from
    each finger's piecewise-constant state columns.

    table : (len(_FIELDS), k) float64, the state after each step, the fingers' steps one
    after the other; runs : (k,) number of output samples each step holds for;
    steps : (F,) number of steps of each finger; t_out : (n,) output times (s);
    horizon : ``predict_horizon_s``. Velocity and prediction: a finger sampled within
    the horizon moves at its fitted velocity from its fitted position; past it, it rests
    where it was predicted at the horizon (velocity 0). area : (x_lo, x_hi, y_lo, y_hi)
    (mm; infinite: unbounded): a prediction is held within it, its velocity 0 on an axis
    where it is held (SHT's periods would go on past the edge otherwise).
    """
    f_n, n = steps.size, t_out.size
    contact = np.empty((f_n, n), dtype=np.bool_)
    touch_id = np.empty((f_n, n), dtype=np.int64)
    x_held, y_held = np.empty((f_n, n)), np.empty((f_n, n))
    x_pred, y_pred = np.empty((f_n, n)), np.empty((f_n, n))
    vx, vy = np.empty((f_n, n)), np.empty((f_n, n))
    force, touch_start = np.empty((f_n, n)), np.empty((f_n, n))
    s = 0
    for f in range(f_n):
        start = 0
        for _ in range(steps[f]):
            touching = table[0, s] > 0.5
            touch, t_sample, x, y = np.int64(table[1, s]), table[2, s], table[3, s], table[4, s]
            xf, yf, vxs, vys = table[5, s], table[6, s], table[7, s], table[8, s]
            for k in range(start, start + runs[s]):
                since = t_out[k] - t_sample
                ahead = min(max(since, 0.0), horizon)
                moving = touching and since <= horizon
                contact[f, k] = touching
                touch_id[f, k] = touch
                x_held[f, k], y_held[f, k] = x, y
                px, py = xf + vxs * ahead, yf + vys * ahead
                x_pred[f, k] = min(max(px, area[0]), area[1]) if touching else x
                y_pred[f, k] = min(max(py, area[2]), area[3]) if touching else y
                # held at the area's edge, the prediction rests there on that axis
                vx[f, k] = vxs if moving and area[0] <= px <= area[1] else 0.0
                vy[f, k] = vys if moving and area[2] <= py <= area[3] else 0.0
                force[f, k], touch_start[f, k] = table[9, s], table[10, s]
            start += runs[s]
            s += 1
    return contact, touch_id, x_held, y_held, x_pred, y_pred, vx, vy, force, touch_start
