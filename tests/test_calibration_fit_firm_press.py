"""A firm press whose friction falls is fitted, not refused: the fit started from seed 003's
k (1.13 /N), whose k F_n passes 1 from 0.885 N, where eq 2 is flat in b and k, so the
solver stayed at its start and the run was refused as a curve that did not fall. Points
that really do not fall are still refused."""

import numpy as np
import pytest

from frictex.device.calibration_fit import fit_points
from frictex.device.errors import RunFailed
from frictex.device.friction import forward_mu
from frictex.device.profile import FrictionParams

AMPLITUDES_UM = np.linspace(0.0, 2.5, 13)
B_PER_UM = 1.67


def exact_points(force_n, k_per_n: float) -> np.ndarray:
    """mu' of seed 003, eq 2 at ``AMPLITUDES_UM`` and ``force_n`` (N, scalar or (13,))."""
    force = np.broadcast_to(np.asarray(force_n, dtype=np.float64), AMPLITUDES_UM.shape)
    return forward_mu(AMPLITUDES_UM, force, FrictionParams(B_PER_UM, k_per_n))


@pytest.mark.parametrize("force_n", [1.15, 1.2, 2.0, 3.0])
@pytest.mark.parametrize("asymptote", [0.2, 0.6, 0.85])
def test_exact_points_of_a_firm_press_give_back_b_and_k(force_n, asymptote):
    """At 1.2 N with k F_n = 0.6 (mu' falling 1.000 to 0.606) the run was refused: 'the
    fitted mu' falls by only 0.000'."""
    k = asymptote / force_n
    force = np.full(AMPLITUDES_UM.size, force_n)
    fit = fit_points(AMPLITUDES_UM, force, exact_points(force_n, k))
    assert fit.params.b_per_um == pytest.approx(B_PER_UM, rel=1e-6)
    assert fit.params.asymptote_per_n == pytest.approx(k, rel=1e-6)
    assert fit.fits and fit.calibration is None and fit.notes == []


def test_forces_from_light_to_firm_give_back_b_and_k():
    """Points pressed 0.5 to 3 N, k F_n up to 0.9: every point of seed 003's k was past 1
    from 0.885 N."""
    force = np.linspace(0.5, 3.0, AMPLITUDES_UM.size)[::-1]
    fit = fit_points(AMPLITUDES_UM, force, exact_points(force, 0.3))
    assert fit.params.b_per_um == pytest.approx(B_PER_UM, rel=1e-6)
    assert fit.params.asymptote_per_n == pytest.approx(0.3, rel=1e-6)


def test_noisy_points_of_a_firm_press_have_honest_standard_errors():
    """Noise sd 0.01 at 2 N, k = 0.3 /N: b +- 1.96 standard errors covers the true b in
    about 95 % of sweeps, as at a light press."""
    force = np.full(AMPLITUDES_UM.size, 2.0)
    rng = np.random.default_rng(3)
    fits = [fit_points(AMPLITUDES_UM, force,
                       exact_points(2.0, 0.3) + rng.normal(0.0, 0.01, AMPLITUDES_UM.size))
            for _ in range(100)]
    b = np.array([fit.params.b_per_um for fit in fits])
    b_se = np.array([fit.b_se for fit in fits])
    k = np.array([fit.params.asymptote_per_n for fit in fits])
    k_se = np.array([fit.k_se for fit in fits])
    assert 0.85 < np.mean(abs(b - B_PER_UM) < 1.96 * b_se) <= 1.0
    assert 0.85 < np.mean(abs(k - 0.3) < 1.96 * k_se) <= 1.0
    assert abs(np.median(b) - B_PER_UM) < 0.05 and np.median(b_se) < 0.2
    assert sum(fit.calibration is None for fit in fits) >= 90


@pytest.mark.parametrize("force_n", [1.2, 2.0, 3.0])
@pytest.mark.parametrize("noise_sd", [0.0, 0.01])
def test_points_that_do_not_fall_are_still_refused_at_a_firm_press(force_n, noise_sd):
    force = np.full(AMPLITUDES_UM.size, force_n)
    mu = 1.0 + np.random.default_rng(0).normal(0.0, noise_sd, AMPLITUDES_UM.size)
    with pytest.raises(RunFailed, match="did not fall with vibration") as refused:
        fit_points(AMPLITUDES_UM, force, mu)
    assert f"the finger pressed {force_n:.2g} N, too hard" in str(refused.value)


def test_a_fall_below_the_least_is_still_refused_at_a_firm_press():
    """k F_n = 0.98 at 2 N: eq 2 falls by 0.020 over 2.5 um, too little to determine b."""
    force = np.full(AMPLITUDES_UM.size, 2.0)
    with pytest.raises(RunFailed, match="the fitted mu' falls by only 0.020 from 0 to 2.5 um"):
        fit_points(AMPLITUDES_UM, force, exact_points(2.0, 0.49))
