"""The closed loop's arithmetic on one block's samples, compiled (numba).

``rendering.control.loop`` computes each block it sends through these kernels (the mu'
asked of the inverse, :func:`feed_forward`, and what it keeps of the block,
:func:`sent_rows` and :func:`touch_downs`) and reads each block's force report through them: its peak
(:func:`report_peak`), the references it passes through the sensor chain
(:func:`chain_input`), the friction at rest (:func:`rest_stats`) and the feedback's and
the adaptation's points (:func:`feedback_stats`). They compute what numpy computed
there, in the same order of operations, so that the loop's figures are the same to the
bit; one call per step instead of tens of numpy calls on 50 samples (1-2 us each). Two
parts stay in numpy because their bits depend on numpy's code: the exponential (numpy's
own vectorised ``exp``, not the C library's) and the adaptation's matrix products (BLAS).
Units: mu' and force ratios dimensionless, forces N, amplitudes um, speeds mm/s.
"""

from __future__ import annotations

import numpy as np

from frictex.device.jit import njit


@njit(cache=True, nogil=True)
def feed_forward(mu_target, c):
    """The mu' asked of the inverse (F, n) for the target mu' (F, n): 1 - c (1 - mu')
    where the target is below 1, else the target (loop docstring, 2; the caller gives
    gain ``c`` = 1 unless one finger touches)."""
    asked = np.empty(mu_target.shape)
    for f in range(mu_target.shape[0]):
        for i in range(mu_target.shape[1]):
            mu = mu_target[f, i]
            asked[f, i] = 1.0 - c * (1.0 - mu) if mu < 1.0 else mu
    return asked


@njit(cache=True, nogil=True)
def report_peak(lateral_n, normal_n):
    """The largest |force| (N) of a report's samples (0 for none), inf if any is not
    finite (nan or inf)."""
    peak = 0.0
    for x in (lateral_n, normal_n):
        for v in x:
            if not np.isfinite(v):
                return np.inf
            peak = max(peak, abs(v))
    return peak


@njit(cache=True, nogil=True)
def sent_rows(wanted, contact, asked, mu_target, row, cut_um):
    """What the loop keeps of a block sent: ``wanted`` (F, n, um) zeroed where
    ``contact`` is False (a new array), and for finger ``row`` (-1: none touching) the
    target mu' the feedback compares with (1 where ``asked`` >= 1: the probe held the
    plate still) and where the amplitude limit cut the command (wanted >= ``cut_um``
    with a reduction asked); returns (wanted, target (n,), cut (n,))."""
    out = np.empty(wanted.shape)
    for f in range(wanted.shape[0]):
        for i in range(wanted.shape[1]):
            out[f, i] = wanted[f, i] if contact[f, i] else 0.0
    n = wanted.shape[1]
    target = np.ones(n)
    cut = np.zeros(n, dtype=np.bool_)
    if row >= 0:
        for i in range(n):
            target[i] = 1.0 if asked[row, i] >= 1.0 else mu_target[row, i]
            cut[i] = out[row, i] >= cut_um and target[i] < 1.0
    return out, target, cut


@njit(cache=True, nogil=True)
def touch_downs(contact, down_at, index0, row):
    """The output index finger ``row`` (-1: none) touched down at, for each sample
    (n,) int64 (-1 where lifted, or none), and each finger's at the block's last sample
    (F,); ``contact`` (F, n), ``down_at`` (F,): the same at the block before's last
    sample, ``index0``: the block's first output index."""
    fingers, n = contact.shape
    down = np.full(n, -1, dtype=np.int64)
    after = np.empty(fingers, dtype=np.int64)
    for f in range(fingers):
        d = down_at[f]
        for i in range(n):
            if not contact[f, i]:
                d = -1
            elif d < 0:
                d = index0 + i
            if f == row:
                down[i] = d
        after[f] = d
    return down, after


@njit(cache=True, nogil=True)
def chain_input(target, w_um, still_um, normal_n, e, k_per_n, edge):
    """Rows (k, n) the loop passes through the chain: the reduction asked (1 - target
    where target < 1, else 0), the plate moving (1 where ``w_um`` > ``still_um``, else 0)
    and, when ``e`` (n,) = exp(-b w) is given (adaptive; else size 0), seed 003's mu'
    (``device.friction.forward_mu``: its asymptote k F_n at most ``edge``) and its
    Jacobian in (b, k) (``device.calibration_fit.model_jacobian``) at ``normal_n``."""
    n = w_um.size
    rows = np.empty((2 if e.size == 0 else 5, n))
    for i in range(n):
        rows[0, i] = 1.0 - target[i] if target[i] < 1.0 else 0.0
        rows[1, i] = 1.0 if w_um[i] > still_um else 0.0
        if e.size:
            kf = k_per_n * normal_n[i]
            a = edge if kf >= edge else kf  # np.minimum: a nan stays nan
            rows[2, i] = (1.0 - a) * e[i] + a
            rows[3, i] = -(1.0 - kf) * w_um[i] * e[i]
            rows[4, i] = normal_n[i] * (1.0 - e[i])
    return rows


@njit(cache=True, nogil=True)
def median(x):
    """``np.median`` of a non-empty finite 1-d array, to the bit: the middle of the
    sorted values, or the mean of the middle two."""
    s = np.sort(x)
    half = s.size // 2
    return s[half] if s.size % 2 else (s[half - 1] + s[half]) / 2.0


@njit(cache=True, nogil=True)
def rest_stats(lateral_n, normal_n, speed, plate_seen, min_normal_n, creep_mm_s,
               slide_mm_s, still_seen, min_rest_mu, half_min, first):
    """The friction at rest's samples (``rendering.control.loop``, docstring 1) in a
    finite report: returns (ratio F_t / F_n (n,), a, b, c).

    ``first`` (no mu0 yet): among samples where the plate is seen still
    (``plate_seen`` < ``still_seen``) reading a ratio of at least ``min_rest_mu``
    (quiet) and the finger pressed (F_n >= ``min_normal_n``) and moving
    (>= ``creep_mm_s``), a and b are the ratio's medians over the first and second half
    of the block (nan unless both halves have ``half_min`` such samples), c the count of
    quiet samples in the second half. Otherwise: a = 1 if any sample is pressed and
    moving (else 0), b the count of quiet samples pressed and sliding (>=
    ``slide_mm_s``), c their ratio's median (nan if none)."""
    n = lateral_n.size
    ratio = np.empty(n)
    quiet = np.empty(n, dtype=np.bool_)
    moving = np.empty(n, dtype=np.bool_)
    sliding = np.empty(n, dtype=np.bool_)
    for i in range(n):
        pressed = normal_n[i] >= min_normal_n
        ratio[i] = lateral_n[i] / (normal_n[i] if normal_n[i] > min_normal_n else min_normal_n)
        quiet[i] = plate_seen[i] < still_seen and ratio[i] >= min_rest_mu
        moving[i] = speed[i] >= creep_mm_s and pressed
        sliding[i] = speed[i] >= slide_mm_s and pressed
    if first:
        late = n // 2
        early_still = ratio[:late][quiet[:late] & moving[:late]]
        late_still = ratio[late:][quiet[late:] & moving[late:]]
        ma = mb = np.nan
        if min(early_still.size, late_still.size) >= half_min:
            ma, mb = median(early_still), median(late_still)
        return ratio, ma, mb, float(np.count_nonzero(quiet[late:]))
    still = ratio[quiet & sliding]
    m = median(still) if still.size else np.nan
    return ratio, 1.0 if moving.any() else 0.0, float(still.size), m


@njit(cache=True, nogil=True)
def feedback_stats(ratio, mu0, normal_n, speed, seen, min_normal_n, creep_mm_s,
                   slide_mm_s, min_mu, min_reduction, min_count, decimate):
    """The feedback's and the adaptation's points (``rendering.control.loop``,
    docstring 2, 3) from a report's ``ratio`` and the friction at rest ``mu0``: the
    measured mu'_m = ratio / mu0 gripping (>= ``min_mu``) where the finger is pressed.

    ``seen``'s last row is the reduction asked where the amplitude limit cut the command
    (0 elsewhere) through the same chain as the whole reduction asked (``seen[0]``), so
    that a cut lines up with the reduction it cut.

    Returns (asked, g, cut, jac, resid): ``asked`` the count of samples moving with a
    reduction asked (``seen[0]`` >= ``min_reduction``), ``g`` the median of their
    delivered / asked reduction (nan unless ``asked`` >= ``min_count``), ``cut`` the
    count of those asked samples whose reduction the limit mostly cut (the last row at
    least half of ``seen[0]``); with
    the model's rows in ``seen`` (6 rows, adaptive), every
    ``decimate``-th sample sliding: ``jac`` (m, 2) (``seen[3:]`` there; C-ordered, the
    layout numpy's ``seen[3:, pick].T`` has) and ``resid`` (m,) = mu'_m - ``seen[2]``
    there; else both of size 0."""
    n = ratio.size
    measured = ratio / mu0
    asked = np.empty(n, dtype=np.bool_)
    picked = np.empty(n, dtype=np.int64)
    m = 0
    for i in range(n):
        pressed = normal_n[i] >= min_normal_n
        grip = measured[i] >= min_mu
        asked[i] = speed[i] >= creep_mm_s and pressed and grip and seen[0, i] >= min_reduction
        if speed[i] >= slide_mm_s and pressed and grip:
            picked[m] = i
            m += 1
    count = np.count_nonzero(asked)
    cut = np.count_nonzero(seen[seen.shape[0] - 1][asked] >= 0.5 * seen[0][asked])
    g = np.nan
    if count >= min_count:
        g = median((1.0 - measured[asked]) / seen[0][asked])
    rows = seen.shape[0] == 6
    pick = picked[:m:decimate] if rows else picked[:0]
    jac = np.empty((pick.size, 2))
    resid = np.empty(pick.size)
    for j in range(pick.size):
        i = pick[j]
        jac[j, 0], jac[j, 1] = seen[3, i], seen[4, i]
        resid[j] = measured[i] - seen[2, i]
    return count, g, cut, jac, resid
