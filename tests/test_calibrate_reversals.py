"""A finger sliding back and forth: the lateral force (PROTOCOL.md 4.9, positive when the
finger drags the plate towards +x) changes sign at each reversal, within a step. Friction
opposes the slide whichever way it goes, so its size |F_t| / F_n is seed 003's mu; the
points are eq 2's, not a median of ratios of both signs (about 0, or of either sign)."""

import numpy as np

from frictex.device.calibration_fit import fit_points
from frictex.device.calibration_run import Sweep, run_sweep
from test_calibrate import ModelLink


class ReversingLink(ModelLink):
    """Seed 003's plate where the finger reverses every ``stroke`` samples (0.13 s at 10
    kHz: several times in each step's 3000 kept samples, so about half of them negative)."""

    stroke = 1300

    def _forces(self, index0, n):
        lateral, normal, reported = super()._forces(index0, n)
        direction = np.where((index0 + np.arange(n)) // self.stroke % 2 == 0, 1.0, -1.0)
        return direction * lateral, normal, reported


def test_a_finger_sliding_back_and_forth_gives_eq_2s_points():
    w, _, mu = run_sweep(ReversingLink(1.4, 0.8), Sweep())
    kf = 0.8 * 0.5
    np.testing.assert_allclose(mu, (1 - kf) * np.exp(-1.4 * w) + kf, rtol=1e-3)


def test_points_that_are_not_finite_are_counted_not_dropped_silently():
    w = np.round(np.linspace(0.2, 2.4, 12), 3)
    mu = 0.6 * np.exp(-1.4 * w) + 0.4
    mu[[3, 7]] = [np.inf, np.nan]
    fit = fit_points(w, np.full(12, 0.5), mu)
    assert (fit.n_points, fit.n_dropped) == (10, 2)


def test_points_at_a_negative_amplitude_or_without_a_normal_force_are_counted_too():
    w = np.round(np.linspace(0.2, 2.4, 12), 3)
    mu = 0.6 * np.exp(-1.4 * w) + 0.4
    fit = fit_points(np.append(w, [-1.0, -1.0, 0.5]), np.append(np.full(12, 0.5), [0.5, 0.5, 0.0]),
                     np.append(mu, [0.9, 0.9, 0.7]))
    assert (fit.n_points, fit.n_dropped) == (12, 3)
