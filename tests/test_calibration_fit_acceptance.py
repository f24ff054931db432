"""When seed 003's eq 2 is not accepted whatever the runs test says: a residual RMS above
the ceiling, a solver that did not converge; and a constant the points do not determine
(standard error above its value) is said, not written as an estimate."""

import math

import numpy as np
import pytest
from scipy.optimize import least_squares

from frictex.device import calibration_fit
from frictex.device.calibration_fit import (MODEL_CEILING, MODEL_TOLERANCE, device_toml,
                                            fit_points)
from frictex.device.errors import InputError, RunFailed
from frictex.device.friction import forward_mu
from frictex.device.profile import FrictionParams

LEVELS_UM = np.round(np.linspace(0.2, 2.4, 12), 3)
FORCE_N = np.full(12, 0.5)
SEED = forward_mu(LEVELS_UM, FORCE_N, FrictionParams(1.67, 1.13))


def test_points_shuffled_out_of_their_fall_are_not_accepted():
    """The runs test keeps the model (the shuffled residuals change sign often), but an
    RMS 4.6 times the tolerance is no fit: a table instead."""
    fit = fit_points(LEVELS_UM, FORCE_N, np.random.default_rng(0).permutation(SEED))
    assert fit.residual_rms > MODEL_CEILING > MODEL_TOLERANCE
    assert not fit.fits and fit.judged_by == "RMS ceiling"
    assert fit.calibration is not None
    assert fit.misfit_reason.startswith(f"residual RMS {fit.residual_rms:.3f} above the ceiling")


def test_a_fit_the_solver_did_not_finish_is_not_accepted(monkeypatch):
    monkeypatch.setattr(calibration_fit, "least_squares",
                        lambda *args, **kwargs: least_squares(*args, **kwargs, max_nfev=1))
    fit = fit_points(LEVELS_UM, FORCE_N, forward_mu(LEVELS_UM, FORCE_N, FrictionParams(3.0, 0.5)))
    assert fit.solver_status == 0
    assert not fit.fits and fit.calibration is not None
    assert fit.misfit_reason.startswith("the fit did not converge: ")


def test_amplitudes_in_nm_say_b_is_not_determined():
    fit = fit_points(LEVELS_UM * 1000, FORCE_N, SEED)
    assert fit.b_se > fit.params.b_per_um
    assert [note for note in fit.notes if note.startswith("b = ")] == [
        f"b = {fit.params.b_per_um:.4g} /um with a standard error of {fit.b_se:.2g} /um, more "
        f"than its value: the points do not determine b (are the amplitudes in um and the "
        f"forces in N?)"]
    assert not fit.fits


def test_a_determined_fit_has_no_notes():
    noisy = SEED + np.random.default_rng(4).normal(0.0, 0.01, 12)
    assert fit_points(LEVELS_UM, FORCE_N, noisy).notes == []


@pytest.mark.parametrize("force_n, hint", [
    (1.5, "the finger pressed 1.5 N, too hard: k F_n reaches 1 near 0.88 N"),
    (0.5, "is the plate vibrating and the finger pressing?")])
def test_a_flat_curve_is_a_failed_run_naming_a_press_too_hard(force_n, hint):
    with pytest.raises(RunFailed, match="did not fall with vibration") as refused:
        fit_points(LEVELS_UM, np.full(12, force_n), np.ones(12))
    assert hint in str(refused.value)


@pytest.mark.parametrize("top", [3000.0, 4000.0])
def test_a_singular_fit_of_amplitudes_in_nm_has_an_infinite_standard_error(top):
    """Exact points at 0 to 3000 or 4000 'um' (nm by mistake): J^T J inverted to -inf or
    nan, not an error, and its variance was clipped to a standard error of 0, no note."""
    w = np.linspace(0.0, top, 13)
    fit = fit_points(w, np.full(13, 0.5), forward_mu(w, np.full(13, 0.5), FrictionParams()))
    assert fit.b_se == math.inf
    assert any(note.startswith("b = 1.67 /um with a standard error of inf /um")
               for note in fit.notes)
    assert "b_per_um = 1.67        # standard error inf" in device_toml(fit, 3.0, 0.5)


def test_exact_points_the_model_cannot_tell_apart_keep_a_large_standard_error():
    """Exact points up to 2500 'um' leave residuals of exactly 0: 0 times b's huge
    variance was a standard error of 0."""
    w = np.linspace(0.0, 2500.0, 13)
    fit = fit_points(w, np.full(13, 0.5), forward_mu(w, np.full(13, 0.5), FrictionParams()))
    assert fit.b_se > 1e100 and "b" in fit.undetermined


@pytest.mark.parametrize("w", [[2.0, 2.0 + 1e-12, 2.0 + 2e-12], np.linspace(1.999, 2.001, 30)])
def test_amplitudes_within_a_nanometre_are_one_amplitude(w):
    with pytest.raises(InputError, match=r"at 1 distinct amplitudes above 0 um \(within 1 nm "
                                         r"count as one\)"):
        fit_points(w, np.full(len(w), 0.5), np.full(len(w), 0.6))


def test_jittered_amplitudes_that_do_not_determine_b_get_a_table_not_the_model():
    """30 noisy points at 2 +- 0.01 um: several amplitudes 1 nm apart, but b = 9.7 /um
    with a standard error of 3e7 /um was accepted and written as the model."""
    rng = np.random.default_rng(5)
    w = 2.0 + rng.uniform(-0.01, 0.01, 30)
    force = np.full(30, 0.5)
    fit = fit_points(w, force, forward_mu(w, force, FrictionParams()) + rng.normal(0, 0.03, 30))
    assert not fit.fits and fit.judged_by == "b undetermined"
    assert fit.misfit_reason.startswith("the points do not determine b: b = ")
    assert fit.calibration is not None
    assert "[device.calibration]     # the model does not fit (the points do not determine b" \
        in device_toml(fit, 2.5, 0.5)


def test_points_of_mismatched_lengths_are_bad_input():
    with pytest.raises(InputError, match="13 amplitudes, 5 normal forces and 13 values of mu'"):
        fit_points(np.linspace(0.2, 2.4, 13), np.full(5, 0.5), np.full(13, 0.6))
