"""A device whose lateral force reads 0 while the finger slides on the plate at rest
(a lateral sensor unplugged), or next to nothing: the sweep stops at the first rest step with
one line saying so, instead of dividing by that friction."""

import warnings

import numpy as np
import pytest

from frictex.device.calibration_run import Sweep, run_sweep
from frictex.device.errors import DeviceError
from test_calibrate import ModelLink


class NoLateralLink(ModelLink):
    """Seed 003's plate whose lateral force reads ``lateral_n`` (N) throughout."""

    def __init__(self, lateral_n):
        super().__init__(1.4, 0.8)
        self.lateral_n = lateral_n

    def _forces(self, index0, n):
        _, normal, reported = super()._forces(index0, n)
        return np.full(n, self.lateral_n), normal, reported


class NegatedLink(ModelLink):
    """Seed 003's plate whose sensor counts the slide's direction negative."""

    def _forces(self, index0, n):
        lateral, normal, reported = super()._forces(index0, n)
        return -lateral, normal, reported


@pytest.mark.parametrize("lateral_n", [0.0, 0.001])  # 0.001 N: 0.002 of the normal force
def test_no_friction_at_rest_is_one_device_error_without_a_numpy_warning(lateral_n):
    with warnings.catch_warnings():
        warnings.simplefilter("error")
        with pytest.raises(DeviceError) as refused:
            run_sweep(NoLateralLink(lateral_n), Sweep())
    message = str(refused.value)
    assert message.startswith("model: the device reported no friction at rest: lateral "
                              f"force {lateral_n:g} N with the plate still (step 1)")
    assert "\n" not in message


def test_a_sensor_of_the_other_sign_still_calibrates():
    """Friction is the ratio of two lateral forces: a sensor counting the slide's direction
    negative gives the same points."""
    w, _, mu = run_sweep(NegatedLink(1.4, 0.8, drift_per_s=0.0), Sweep())
    kf = 0.8 * 0.5
    np.testing.assert_allclose(mu, (1 - kf) * np.exp(-1.4 * w) + kf, rtol=1e-12)
