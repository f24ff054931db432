"""d' of a same-different task under the differencing model, with a bootstrap interval.

The differencing model (Macmillan & Creelman 2005, *Detection theory: a user's guide*,
2nd ed., ch. 9): each interval gives one observation, Gaussian with unit variance and
mean 0 for the reference (A) or d' for the comparison (B); the observer says "different"
when the two observations differ by more than a criterion k. Their difference has
variance 2, so

    F = P("different" | AA or BB) = 2 Phi(-k / sqrt 2)
    H = P("different" | AB or BA) = Phi((d' - k) / sqrt 2) + Phi((-d' - k) / sqrt 2)

The first gives k from F; the second increases with d' (H = F at d' = 0) and is solved
for d' by bisection. H <= F gives d' = 0. The yes-no formula z(H) - z(F) underestimates
this d' (M&C ch. 9). Rates of 0 or 1 are kept finite by the log-linear correction,
(k + 0.5) / (n + 1) (:data:`CORRECTION`); the analysis gives the raw counts beside.
"""

from __future__ import annotations

import math

import numpy as np
from scipy.special import ndtr, ndtri

from frictex.app.experiment.psychometric import data_seed

#: the model, as the analysis names it
MODEL = "differencing model (Macmillan & Creelman 2005, ch. 9)"
#: the interval, as the analysis names it
INTERVAL = ("bootstrap over trials (the different and the same trials resampled apart, "
            "each at its corrected rate), 95 % percentile interval")
#: how the hit and false-alarm rates are taken, as the analysis names it
CORRECTION = ("log-linear correction, (count + 0.5) / (trials + 1) (Hautus 1995), which "
              "keeps rates of 0 and 1 finite")
#: what d' 0 means where the hits are not above the false alarms
NO_DISCRIMINATION = ("hits not above false alarms: d' set to 0, no discrimination shown "
                     "(the model has no d' below 0)")
_ROOT2 = math.sqrt(2.0)
#: bisection halvings: the bracket's width (< 12 for rates within (1e-32, 1 - 1e-16))
#: shrinks below 1e-15
_HALVINGS = 60


def rate(k, n):
    """The rate (k + 0.5) / (n + 1) (:data:`CORRECTION`): never 0 or 1 (``k`` of ``n``
    trials)."""
    return (np.asarray(k, dtype=np.float64) + 0.5) / (np.asarray(n, dtype=np.float64) + 1.0)


def d_prime(hits, false_alarms):
    """d' under the differencing model (module docstring) for the hit and false-alarm
    rates (each within (0, 1), broadcast); 0 where hits <= false alarms.

    Parameters
    ----------
    hits, false_alarms : array_like
        Proportions of "different" to different (AB, BA) and same (AA, BB) pairs.

    Returns
    -------
    ndarray
        d' (units of the observation's standard deviation).
    """
    h, f = np.broadcast_arrays(np.asarray(hits, dtype=np.float64),
                               np.asarray(false_alarms, dtype=np.float64))
    k = -_ROOT2 * ndtri(f / 2.0)
    low = np.zeros(h.shape)
    # at d' = high the first term alone is h: the root lies below
    high = np.maximum(k + _ROOT2 * ndtri(h), 0.0)
    for _ in range(_HALVINGS):
        mid = 0.5 * (low + high)
        below = ndtr((mid - k) / _ROOT2) + ndtr((-mid - k) / _ROOT2) < h
        low, high = np.where(below, mid, low), np.where(below, high, mid)
    return np.where(h > f, 0.5 * (low + high), 0.0)


def d_prime_interval(hits: int, different: int, false_alarms: int, same: int,
                     bootstrap: int) -> tuple[float, float] | None:
    """The 95 % interval of d' (:data:`INTERVAL`) from ``bootstrap`` resamplings of the
    trials: ``hits`` of ``different`` and ``false_alarms`` of ``same`` trials answered
    "different". None for ``bootstrap`` 0 or a kind of pair never shown."""
    if bootstrap == 0 or different == 0 or same == 0:
        return None
    rng = np.random.default_rng(data_seed([hits, different, false_alarms, same]))
    # drawn at the corrected rates: at a raw rate of 0 or 1 every draw would equal the
    # data and the interval would have zero width
    h = rng.binomial(different, rate(hits, different), bootstrap)
    f = rng.binomial(same, rate(false_alarms, same), bootstrap)
    low, high = np.percentile(d_prime(rate(h, different), rate(f, same)), [2.5, 97.5])
    return float(low), float(high)


def ceiling(hits: int, different: int, false_alarms: int, same: int) -> str | None:
    """Why d' and its interval rest on the correction rather than the data (every
    different pair called different or no same pair called different, with hits above
    false alarms), else None."""
    if hits / different <= false_alarms / same or (hits < different and false_alarms > 0):
        return None
    return ("unsettled: a raw rate of 0 or 1 (all hits or no false alarms); d' and its "
            "interval are what the log-linear correction allows with these trials, and "
            "the true d' may be higher (a lower bound)")
