"""The finger model between touch samples: a two-model (steady / manoeuvring)
interacting-multiple-model filter of the finger's position along one axis, run on the
tracker's touch measurements. The hybrid renderer (``rendering.layers.hybrid``) reads
its phase rate and its position lock from it.

Each model is a constant-velocity Kalman filter (one axis: the layer's, across its
lines; position s in mm, velocity v in mm/s)::

    s' = v,   v' = w(t),   w white acceleration noise of spectral density q

so between two measurements d seconds apart the state moves as F = [[1, d], [0, 1]]
with process covariance Q = q [[d^3/3, d^2/2], [d^2/2, d]] (Bar-Shalom, Li and
Kirubarajan 2001, section 6.2.2, the discretised continuous white-noise acceleration
model). The two models differ only in q:

- *steady*, ``Q_STEADY`` = 1e2 mm^2/s^3: the finger keeps its speed (a swipe, the
  middle of a stroke); over one 20 ms touch interval its velocity may wander by
  sqrt(q d) = 1.4 mm/s, so the filter averages the touch noise out of the velocity over
  many samples (velocity noise ~0.9 mm/s at 0.05 mm touch noise, against the tracker's
  1.8-3.5 mm/s from a two- or three-sample line fit);
- *manoeuvring*, ``Q_MANOEUVRE`` = 1e4 mm^2/s^3: the finger speeds up or slows down as
  a minimum-jerk stroke does. Over a stroke of length D and duration T the
  acceleration is (D / T^2)(60 u - 180 u^2 + 120 u^3), u = t / T, of mean square
  (120 / 7)(D / T^2)^2; as white noise over its correlation time (about T / 3, it
  changes sign once) that is q = (40 / 7) D^2 / T^3: 1.9e3 for a 40 mm stroke in 1.25 s
  (peak 60 mm/s), 1.3e4 for 20 mm in 0.4 s (peak 94 mm/s), 2.3e5 for a 30 mm flick in
  0.11 s. 1e4 is the brisk stroke's.

The interacting multiple model estimator (Blom and Bar-Shalom 1988; Bar-Shalom et al.
2001, section 11.6) runs both and weighs them by how well each predicted the
measurements: at each measurement each model starts from a mixture of the two
(Markov switching, ``STAY`` = 0.95 the chance that the finger keeps its state over one
touch interval: a state lasts some 0.4 s, about a third of a stroke), is updated, and
its weight becomes its prior times the likelihood of the measurement. The output is the
weighted mean. So the velocity is averaged while the finger moves steadily and follows
an acceleration within a sample or two, where a fixed q must give up one for the other
(one model with q = 1e4: human-like strokes better than the tracker, swipes worse;
q = 1e2: the reverse; see ``rendering/RENDERERS.md``).

A measurement is the tracker's predicted position at the output sample where a new
touch sample takes effect (``FingerBlock.x_pred``, ``y_pred`` projected on the axis:
the sample's smoothed position carried to that output sample at its velocity, so it
refers to a known time whatever the sample's own timestamp), with the touch noise's
variance ``R_MM2``. Between measurements the filter predicts at constant velocity:
s(t) = s_k + v_k (t - t_k) (``rendering/RENDERERS.md``: why that holds over 20 ms).

What a measurement may move the estimate by, by the filter's own account: the
correction (updated less predicted position) of a Kalman filter with predicted
position variance P has variance P - P r / (P + r) = P^2 / (P + r) (its gain is
P / (P + r) and the innovation's variance P + r). ``filter_axis`` returns its standard
deviation for the two models' mixture; the hybrid tells a lost lock from the filter's
own noise by it (``rendering.layers.hybrid.GATE_SIGMAS``). At 50 Hz with 0.05 mm
noise (eight draws each): early in a touch, the velocity known from two samples and
both models equally likely, 0.14 mm at the third sample and 0.19 at the fourth; on a
steady swipe (20 or 120 mm/s) it falls to 0.08 mm after 0.3 s; on human-like strokes,
which keep the manoeuvring model up, 0.10 mm typically and up to 0.25.

Restarts: at a new touch, and wherever the tracker knows no velocity (the first sample
of a touch, a finger resting past the prediction horizon: ``vx = vy = 0``; then the
position is the tracker's and the velocity 0), the filter starts again at the
measurement with the tracker's velocity and a velocity standard deviation ``V0_MM_S``,
a two-sample velocity's through the touch noise, both models equally likely.
"""

from __future__ import annotations

import math

import numpy as np

from frictex.device.jit import njit

#: touch noise variance (mm^2): 0.05 mm standard deviation, a good capacitive controller
#: (``app.measure.report_matrix.TOUCH_NOISE_MM``)
R_MM2 = 0.05 ** 2
#: white acceleration noise densities (mm^2/s^3) of the steady and manoeuvring models
Q_STEADY = 1.0e2
Q_MANOEUVRE = 1.0e4
#: chance that the finger keeps its motion state from one touch sample to the next
STAY = 0.95
#: velocity standard deviation (mm/s) at a (re)start: sqrt(2) 0.05 mm over 20 ms
V0_MM_S = math.sqrt(2.0) * 0.05 / 0.02
#: the carried filter state of a finger seen for the first time: per model (s mm,
#: v mm/s, P00 mm^2, P01 mm^2/s, P11 mm^2/s^2), the steady model's weight, the time of
#: the last measurement (s), 1.0 while the finger moves, the standard deviation of the
#: last measurement's position correction (mm)
NO_FILTER = (0.0,) * 14


def filter_axis(t_s, touch, vx, vy, x_held, y_held, x_pred, y_pred, axis, before=None,
                q=(Q_STEADY, Q_MANOEUVRE), stay=STAY, r=R_MM2):
    """Filtered position (mm) and velocity (mm/s) along ``axis`` at every output sample,
    and how far the last measurement may move the position by the filter's own account.

    Parameters
    ----------
    t_s : (n,) output times (s).
    touch, vx, vy, x_held, y_held, x_pred, y_pred : (n,) one finger's tracks
        (``rendering.tracking.tracks.FingerBlock`` rows; mm, mm/s).
    axis : (ax, ay), unit vector across the layer's lines.
    before : the ``end`` of the previous call for this finger, or None.
    q : (steady, manoeuvring) white acceleration noise densities (mm^2/s^3).
    stay : chance that the finger keeps its motion state over one measurement.
    r : measurement variance (mm^2).

    Returns
    -------
    s : (n,) mm. v : (n,) mm/s.
    sd : (n,) mm, the standard deviation of the position correction (updated less
        predicted position) of the last measurement at or before each sample, under the
        filter's own model: P / sqrt(P + r), P the predicted position variance (mm^2) of
        the mixture of both models (their variances weighted by their prior chances plus
        the spread of their means, as the IMM combines estimates). 0 from a (re)start
        on, where nothing was predicted.
    end : the state to carry (the filter's 14 values as in ``NO_FILTER``, then the last
        measurement's touch, held x, held y and the tracker's velocity along the axis).
    """
    n = len(t_s)
    s, v, sd = np.empty(n), np.empty(n), np.empty(n)
    start = before if before is not None else (np.array(NO_FILTER), 0, 0.0, 0.0, 0.0)
    end = filter_kernel(np.ascontiguousarray(t_s, dtype=np.float64),
                        np.ascontiguousarray(touch, dtype=np.int64),
                        *(np.ascontiguousarray(a, dtype=np.float64)
                          for a in (vx, vy, x_held, y_held, x_pred, y_pred)),
                        (float(axis[0]), float(axis[1])), before is not None,
                        np.ascontiguousarray(start[0], dtype=np.float64), int(start[1]),
                        (float(start[2]), float(start[3]), float(start[4])),
                        (float(q[0]), float(q[1]), float(stay)), float(r), s, v, sd)
    return s, v, sd, end


@njit(cache=True, nogil=True)
def _cv_step(x, d, q, z, r):
    """One constant-velocity Kalman predict (``d`` s, white acceleration density ``q``)
    and update with the position ``z`` (mm, variance ``r``): ``x`` = (s, v, P00, P01,
    P11) in place; returns the likelihood of ``z`` under the prediction (1/mm), the
    predicted position (mm) and its variance (mm^2)."""
    s, v, p00, p01, p11 = x[0], x[1], x[2], x[3], x[4]
    s += v * d
    p00 += d * (2.0 * p01 + d * p11) + q * d * d * d / 3.0
    p01 += d * p11 + q * d * d / 2.0
    p11 += q * d
    var = p00 + r
    innovation = z - s
    k0, k1 = p00 / var, p01 / var
    x[0], x[1] = s + k0 * innovation, v + k1 * innovation
    x[2], x[3], x[4] = p00 - k0 * p00, p01 - k1 * p00, p11 - k1 * p01
    like = math.exp(-0.5 * innovation * innovation / var) / math.sqrt(2.0 * math.pi * var)
    return like, s, p00


@njit(cache=True, nogil=True)
def filter_kernel(t_s, touch, vx, vy, x_held, y_held, x_pred, y_pred, axis, has_before,
                  kf, b_touch, b_meas, q, r, s_out, v_out, sd_out):
    """:func:`filter_axis`'s loop: writes ``s_out``, ``v_out`` and ``sd_out`` (n,),
    returns the carried fields; ``q`` = (steady q, manoeuvring q, stay).

    A measurement is an output sample where a new touch starts or the tracker's held
    position or velocity changes (a touch sample took effect). At each: mixing (model j
    starts from sum_i w_ij x_i, w_ij the chance it was model i given it is j now, and the
    covariance of that mixture), then each model's Kalman step, then the weights
    mu_j = c_j L_j / sum (c_j the prior chance of model j, L_j the likelihood of the
    measurement), then the weighted mean, and the correction's standard deviation from
    the models' predictions weighted by c_j. Between measurements: constant velocity."""
    ax, ay = axis
    models = np.empty((2, 5))
    for j in range(2):
        for i in range(5):
            models[j, i] = kf[5 * j + i]
    mu = np.array([kf[10], 1.0 - kf[10]])
    t_k, moving, sd = kf[11], kf[12], kf[13]
    qs = np.array([q[0], q[1]])
    stay = q[2]
    mixed = np.empty((2, 5))
    like = np.empty(2)
    prior = np.empty(2)
    s_pred = np.empty(2)
    p_pred = np.empty(2)
    last_touch = b_touch
    last_x, last_y, last_v = b_meas
    s = v = 0.0
    n = t_s.size
    for k in range(n):
        v_tr = vx[k] * ax + vy[k] * ay
        fresh = k == 0 and not has_before
        new = (fresh or touch[k] != last_touch or x_held[k] != last_x or y_held[k] != last_y
               or v_tr != last_v)
        if new:
            z = ax * x_pred[k] + ay * y_pred[k]
            still = vx[k] == 0.0 and vy[k] == 0.0
            if fresh or touch[k] != last_touch or still or moving == 0.0:
                for j in range(2):
                    models[j, 0], models[j, 1] = z, v_tr
                    models[j, 2], models[j, 3], models[j, 4] = r, 0.0, V0_MM_S * V0_MM_S
                mu[0], mu[1] = 0.5, 0.5
                sd = 0.0
            else:
                d = t_s[k] - t_k
                # interaction: each model starts from the mixture of both
                for j in range(2):
                    c = mu[j] * stay + mu[1 - j] * (1.0 - stay)
                    w_same = mu[j] * stay / c
                    w_other = 1.0 - w_same
                    for i in range(5):
                        mixed[j, i] = w_same * models[j, i] + w_other * models[1 - j, i]
                    ds = models[j, 0] - mixed[j, 0]
                    dv = models[j, 1] - mixed[j, 1]
                    es = models[1 - j, 0] - mixed[j, 0]
                    ev = models[1 - j, 1] - mixed[j, 1]
                    mixed[j, 2] += w_same * ds * ds + w_other * es * es
                    mixed[j, 3] += w_same * ds * dv + w_other * es * ev
                    mixed[j, 4] += w_same * dv * dv + w_other * ev * ev
                    like[j] = c
                for j in range(2):
                    prior[j] = like[j]
                    for i in range(5):
                        models[j, i] = mixed[j, i]
                    fit, s_pred[j], p_pred[j] = _cv_step(models[j], d, qs[j], z, r)
                    like[j] = prior[j] * fit
                mean = prior[0] * s_pred[0] + prior[1] * s_pred[1]
                p_mix = 0.0
                for j in range(2):
                    p_mix += prior[j] * (p_pred[j] + (s_pred[j] - mean) ** 2)
                sd = p_mix / math.sqrt(p_mix + r)
                total = like[0] + like[1]
                if total > 0.0:
                    mu[0], mu[1] = like[0] / total, like[1] / total
            t_k = t_s[k]
            moving = 0.0 if still else 1.0
            s = mu[0] * models[0, 0] + mu[1] * models[1, 0]
            v = mu[0] * models[0, 1] + mu[1] * models[1, 1]
            last_touch, last_x, last_y, last_v = touch[k], x_held[k], y_held[k], v_tr
        elif k == 0:
            s = mu[0] * models[0, 0] + mu[1] * models[1, 0]
            v = mu[0] * models[0, 1] + mu[1] * models[1, 1]
        if moving != 0.0:
            s_out[k] = s + v * (t_s[k] - t_k)
            v_out[k] = v
        else:
            s_out[k] = ax * x_pred[k] + ay * y_pred[k]
            v_out[k] = 0.0
        sd_out[k] = sd
    out = np.empty(14)
    for j in range(2):
        for i in range(5):
            out[5 * j + i] = models[j, i]
    out[10], out[11], out[12], out[13] = mu[0], t_k, moving, sd
    return (out, last_touch, last_x, last_y, last_v)
