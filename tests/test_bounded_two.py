"""The exact two-actuator bounded solver (device.actuation.bounded_two) against the projected-gradient
solver it replaces and an independent constrained optimiser, on random and hard problems."""

import numpy as np
from hypothesis import example, given, settings, strategies as st
from scipy.optimize import minimize

from frictex.device.actuation.bounded_two import bounded_two
from frictex.device.actuation.modal import _bounded_commands

SETTINGS = settings(derandomize=True, max_examples=80, deadline=None)


def residual(m, w, c):
    return float(np.sum(np.abs(m @ c - w) ** 2))


def problem(seed, fingers, kind):
    """(m, w, limits): random complex, real (the beam's modes), one column zero, two equal
    columns (fingers on a singular locus), or nearly equal."""
    rng = np.random.default_rng(seed)
    m = rng.standard_normal((fingers, 2)) + (1j * rng.standard_normal((fingers, 2))
                                             if kind == "complex" else 0.0)
    if kind == "zero-column":
        m[:, 1] = 0.0
    elif kind == "equal-columns":
        m[:, 1] = m[:, 0]
    elif kind == "nearly-equal":
        m[:, 1] = m[:, 0] * (1 + 1e-7)
    w = (rng.standard_normal(fingers) + 1j * rng.standard_normal(fingers)) * rng.uniform(0.1, 3.0)
    limits = rng.uniform(0.05, 1.0, 2)
    return m, w, limits


def slsqp(m, w, limits):
    """The same problem in real variables (re c1, im c1, re c2, im c2) for SLSQP."""
    def f(x):
        return residual(m, w, x[0::2] + 1j * x[1::2])
    cons = [{"type": "ineq", "fun": lambda x, j=j: limits[j] ** 2 - x[2 * j] ** 2 - x[2 * j + 1] ** 2}
            for j in range(2)]
    best = np.inf
    for start in np.random.default_rng(0).uniform(-0.5, 0.5, (4, 4)) * limits.repeat(2):
        r = minimize(f, start, method="SLSQP", constraints=cons,
                     options=dict(ftol=1e-14, maxiter=500))
        # SLSQP may stop slightly outside the limits: its point scaled back inside them is
        # a residual any feasible solver can reach
        c = r.x[0::2] + 1j * r.x[1::2]
        c *= np.minimum(1.0, limits / np.maximum(np.abs(c), 1e-300))
        best = min(best, residual(m, w, c))
    return best


@SETTINGS
@given(st.integers(0, 2**32 - 1), st.sampled_from([1, 2, 3]),
       st.sampled_from(["complex", "real", "zero-column", "equal-columns", "nearly-equal"]))
@example(7869, 3, "nearly-equal")
def test_optimal_and_feasible(seed, fingers, kind):
    m, w, limits = problem(seed, fingers, kind)
    c = bounded_two(m[None], w[None], limits)[0]
    assert np.all(np.isfinite(c))
    assert np.all(np.abs(c) <= limits * (1 + 1e-9))
    got = residual(m, w, c)
    scale = float(np.sum(np.abs(w) ** 2))
    # columns this close (det M^H M <= 1e-12 trace^2) are solved as rank 1 on purpose,
    # like the modal solver's rcond: that may cost up to ~1e-8 of |w|^2 in optimality
    tolerance = 1e-8 if kind == "nearly-equal" else 1e-9
    assert got <= slsqp(m, w, limits) + tolerance * scale
    start = np.clip(np.abs(np.linalg.lstsq(m, w, rcond=None)[0]), 1e-300, None)
    fista = _bounded_commands(m[None], w[None], (np.linalg.lstsq(m, w, rcond=None)[0]
                                                 * np.minimum(1, limits / start))[None], limits)[0]
    assert got <= residual(m, w, fista) + 1e-9 * scale


def test_reachable_wanted_amplitudes_are_met_exactly():
    """Commands within the limits that give ``w`` exactly: residual zero, any solver."""
    m = np.array([[0.9436, 0.6809], [0.9715, -0.7388]])
    c_true = np.array([0.2 + 0.1j, -0.3j])
    c = bounded_two(m[None], (m @ c_true)[None], np.array([0.5, 0.5]))[0]
    np.testing.assert_allclose(c, c_true, atol=1e-12)


def test_both_limits_active_on_a_hard_case():
    """Wanted far beyond reach of either actuator alone: both commands at their limits,
    and no phase pair on the limits' torus does better (dense scan)."""
    m = np.array([[1.0, 0.3j], [-0.2, 1.0]])
    w = np.array([3.0, -3.0 + 1j])
    limits = np.array([0.4, 0.7])
    c = bounded_two(m[None], w[None], limits)[0]
    np.testing.assert_allclose(np.abs(c), limits, rtol=1e-12)
    theta = np.linspace(0, 2 * np.pi, 721)
    grid = (limits[0] * np.exp(1j * theta))[:, None, None] * m[:, 0] \
        + (limits[1] * np.exp(1j * theta))[None, :, None] * m[:, 1] - w
    assert residual(m, w, c) <= np.min(np.sum(np.abs(grid) ** 2, axis=-1)) + 1e-12
