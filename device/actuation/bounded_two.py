"""Exact bounded least squares for two actuators: min ||M c - w||^2 subject to |c_j| <= L_j.

``device.actuation.modal``'s ``"bounded"`` method for the devices frictex drives (two channels: the
seed 000 beam's two actuators, seed 001's V_AC / V_BD plate wiring). M is (m, 2)
complex, c (2,) complex commands, L (2,) limits (um zero-to-peak).

The problem is convex, so its optimum is the feasible point of least residual among the
optima of each possible active set, and each of those has a closed form or a 1-D search:

- no limit active: the least-squares solution (the minimum-norm one where M is singular);
- limit j active, the other command k free: for fixed c_j the best c_k is
  ``m_k^H (w - m_j c_j) / |m_k|^2``, which leaves the residual ``P (w - m_j c_j)`` with P
  the projection off m_k; with |c_j| = L_j that is least at
  ``c_j = L_j z / |z|``, ``z = (P m_j)^H (P w)``;
- both active: c_j = L_j exp(i theta_j). For a given theta_2 the best theta_1 is the
  argument of ``m_1^H (w - m_2 c_2)``; the residual as a function of theta_2 alone is a
  smooth periodic function with few extrema (a square root of one harmonic plus one
  harmonic), located on a grid of ``GRID`` points and refined by golden-section search
  to ``THETA_TOL`` rad.

The candidates are taken in that order; the first that keeps the other limit and
whose active limit really holds its command back (a non-negative multiplier: the
unconstrained optimum along it lies beyond the limit) satisfies the KKT conditions and
is returned at once. Otherwise those that break a limit are dropped (up to a relative
1e-12) and the one of least residual among them and the both-active optimum is
returned. One compiled pass per sample, a few microseconds, where projected-gradient
iterations took 1-3 ms on flat (near-singular) problems.
"""

from __future__ import annotations

import math

import numpy as np

from frictex.device.jit import njit

#: grid points over [0, 2 pi) bracketing the minimum over the second command's phase
GRID = 64
#: golden-section tolerance on that phase (rad)
THETA_TOL = 1e-12
_FEASIBLE = 1.0 + 1e-12
_GOLDEN = (math.sqrt(5.0) - 1.0) / 2.0


def bounded_two(m_cmd: np.ndarray, wanted: np.ndarray, limits: np.ndarray) -> np.ndarray:
    """Optimal commands (k, 2) complex for k problems.

    Parameters
    ----------
    m_cmd : (k, m, 2) complex or real, commands -> amplitudes under the m fingers.
    wanted : (k, m) complex, wanted amplitudes (um).
    limits : (2,) largest |command| of each actuator (um), > 0.
    """
    m_cmd = np.ascontiguousarray(m_cmd, dtype=np.complex128)
    wanted = np.ascontiguousarray(wanted, dtype=np.complex128)
    out = np.empty((m_cmd.shape[0], 2), dtype=np.complex128)
    _solve_all(m_cmd, wanted, np.ascontiguousarray(limits, dtype=np.float64), out)
    return out


@njit(cache=True)
def _solve_all(m_cmd, wanted, limits, out):
    for k in range(m_cmd.shape[0]):
        _solve_one(m_cmd[k], wanted[k], limits, out[k])


@njit(cache=True)
def _residual(m, w, c0, c1):
    total = 0.0
    for i in range(w.size):
        r = m[i, 0] * c0 + m[i, 1] * c1 - w[i]
        total += r.real * r.real + r.imag * r.imag
    return total


@njit(cache=True)
def _dot(a, b):
    """a^H b."""
    total = 0j
    for i in range(a.size):
        total += a[i].conjugate() * b[i]
    return total


@njit(cache=True)
def _on_circle(z, radius):
    """radius * z / |z| (phase 0 where z is 0)."""
    mag = abs(z)
    return complex(radius, 0.0) if mag == 0.0 else z * (radius / mag)


@njit(cache=True)
def _solve_one(m, w, limits, out):
    best = math.inf
    # no limit active: least squares, minimum norm where M^H M is singular
    g00 = _dot(m[:, 0], m[:, 0]).real
    g11 = _dot(m[:, 1], m[:, 1]).real
    g01 = _dot(m[:, 0], m[:, 1])
    h0, h1 = _dot(m[:, 0], w), _dot(m[:, 1], w)
    trace = g00 + g11
    det = g00 * g11 - (g01.real * g01.real + g01.imag * g01.imag)
    if det > 1e-12 * trace * trace:
        c0 = (g11 * h0 - g01 * h1) / det
        c1 = (g00 * h1 - g01.conjugate() * h0) / det
    elif trace > 0.0:  # rank 1: pinv(G) = G / trace^2
        c0 = (g00 * h0 + g01 * h1) / (trace * trace)
        c1 = (g01.conjugate() * h0 + g11 * h1) / (trace * trace)
    else:
        c0 = c1 = 0j
    if abs(c0) <= limits[0] * _FEASIBLE and abs(c1) <= limits[1] * _FEASIBLE:
        out[0], out[1] = c0, c1
        return  # an unconstrained optimum within the limits
    # one limit active (j), the other command (o) free; with G = M^H M and h = M^H w:
    # z = (P m_j)^H (P w) = h_j - G_jo h_o / G_oo, |P m_j|^2 = G_jj - |G_jo|^2 / G_oo
    for j in range(2):
        o = 1 - j
        if j == 0:
            g_jj, norm_o, g_jo, h_j, h_o = g00, g11, g01, h0, h1
        else:
            g_jj, norm_o, g_jo, h_j, h_o = g11, g00, g01.conjugate(), h1, h0
        if norm_o > 0.0:
            z = h_j - g_jo * h_o / norm_o
            weight = g_jj - (g_jo.real * g_jo.real + g_jo.imag * g_jo.imag) / norm_o
        else:
            z, weight = h_j, g_jj
        cj = _on_circle(z, limits[j])
        co = (h_o - g_jo.conjugate() * cj) / norm_o if norm_o > 0.0 else 0j
        if abs(co) <= limits[o] * _FEASIBLE:
            c = (cj, co) if j == 0 else (co, cj)
            if abs(z) >= limits[j] * weight:
                # the limit holds c_j back (multiplier >= 0): the KKT point, optimal
                out[0], out[1] = c[0], c[1]
                return
            value = _residual(m, w, c[0], c[1])
            if value < best:
                best = value
                out[0], out[1] = c[0], c[1]
    # both limits active: search the second command's phase
    theta = _best_phase(m, w, limits, h0, g01)
    c1 = complex(math.cos(theta), math.sin(theta)) * limits[1]
    c0 = _on_circle(h0 - g01 * c1, limits[0])
    value = _residual(m, w, c0, c1)
    if value < best:
        out[0], out[1] = c0, c1


@njit(cache=True)
def _torus(m, w, limits, h0, g01, theta):
    """Residual with |c_2| = L_2 at phase theta and c_1 = L_1 at its best phase, the
    argument of m_1^H (w - m_2 c_2) = h_0 - G_01 c_2."""
    c1 = complex(math.cos(theta), math.sin(theta)) * limits[1]
    c0 = _on_circle(h0 - g01 * c1, limits[0])
    return _residual(m, w, c0, c1)


@njit(cache=True)
def _best_phase(m, w, limits, h0, g01):
    step = 2.0 * math.pi / GRID
    best_i, best = 0, math.inf
    for i in range(GRID):
        value = _torus(m, w, limits, h0, g01, i * step)
        if value < best:
            best_i, best = i, value
    lo, hi = (best_i - 1) * step, (best_i + 1) * step
    a = hi - _GOLDEN * (hi - lo)
    b = lo + _GOLDEN * (hi - lo)
    fa, fb = _torus(m, w, limits, h0, g01, a), _torus(m, w, limits, h0, g01, b)
    while hi - lo > THETA_TOL:
        if fa < fb:
            hi, b, fb = b, a, fa
            a = hi - _GOLDEN * (hi - lo)
            fa = _torus(m, w, limits, h0, g01, a)
        else:
            lo, a, fa = a, b, fb
            b = lo + _GOLDEN * (hi - lo)
            fb = _torus(m, w, limits, h0, g01, b)
    return 0.5 * (lo + hi)
