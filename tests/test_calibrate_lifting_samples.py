"""A step whose finger leaves the plate for a few samples (0 N) while its median normal
force is a press: those samples have no friction ratio. The step's ratio is the median over
the pressed samples, without dividing by 0 N (numpy's divide warning)."""

import warnings

import numpy as np

from frictex.device.calibration_run import Sweep, run_sweep
from test_calibrate import ModelLink


class LiftingLink(ModelLink):
    """Seed 003's plate where every 50th sample reads 0 N normal and 0 N lateral."""

    def _forces(self, index0, n):
        lateral, normal, reported = super()._forces(index0, n)
        lifted = (index0 + np.arange(n)) % 50 == 0
        return np.where(lifted, 0.0, lateral), np.where(lifted, 0.0, normal), reported


def test_samples_at_zero_newtons_are_left_out_of_a_steps_ratio():
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        w, _, mu = run_sweep(LiftingLink(1.4, 0.8, drift_per_s=0.0), Sweep())
    kf = 0.8 * 0.5
    np.testing.assert_allclose(mu, (1 - kf) * np.exp(-1.4 * w) + kf, rtol=1e-12)
