"""The table-driven inversion the report compares with the exact one: its error bound,
the same guards and counts, and the pipeline option."""

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.device.friction import SeedFrictionModel, make_friction_model
from frictex.rendering.inversion_lut import LutFrictionModel
from frictex.rendering.pipeline import build_pipeline
from scenes import grating_scene
from frictex.device.profile import Calibration, DeviceProfile


def test_error_is_within_the_interpolation_bound():
    """Linear interpolation of w(r) = -ln(1 - r) / b on N points: error at most
    h^2 / (8 b (1 - r_max)^2); measured on 200 001 targets at three forces."""
    device = DeviceProfile()
    lut = LutFrictionModel(make_friction_model(device))
    b = device.friction.b_per_um
    h = lut.r_max / 4095
    bound = h * h / (8 * b * (1 - lut.r_max) ** 2)
    for force in (0.1, 0.5, 0.8):
        err = lut.max_error_um(normal_force_n=force)
        assert 0.0 < err <= bound * (1 + 1e-6)
    assert bound < 3e-5  # about 1e-5 of the 2.5 um range


def test_hard_cases_are_guarded_and_counted_like_the_exact_inversion():
    exact = make_friction_model(DeviceProfile())
    lut = LutFrictionModel(exact)
    # at 0.5 N the floor is 0.572 (A = 0.565, 2.5 um): 0.4 and 0.05 are unreachable
    mu = np.array([1.2, 1.0, 0.9, 0.6, 0.4, 0.05])
    force = np.full(mu.size, 0.5)
    w_exact, c_exact = exact.invert(mu, force)
    w_lut, c_lut = lut.invert(mu, force)
    assert c_lut == c_exact and c_lut.above_one == 1 and c_lut.unreachable == 2
    assert_allclose(w_lut, w_exact, atol=3e-5)
    # forces that differ per sample, and one beyond the model's range
    f2 = np.array([0.1, 0.3, 0.5, 0.7, 0.9, 0.2])
    assert lut.invert(mu, f2)[1] == exact.invert(mu, f2)[1]
    assert_allclose(lut.invert(mu, f2)[0], exact.invert(mu, f2)[0], atol=3e-5)
    # non-finite targets or forces take the exact path, counted there
    bad = np.array([np.nan, 0.8, np.inf])
    assert lut.invert(bad, [0.5, -1.0, 0.5])[1] == exact.invert(bad, [0.5, -1.0, 0.5])[1]


def test_pipeline_option_and_refusal_for_a_calibration_table():
    scene = grating_scene(5.0)
    p = build_pipeline(scene, inversion="lut")
    assert isinstance(p.friction, LutFrictionModel)
    cal = Calibration(amplitudes_um=(0.0, 1.0, 2.0), forces_n=(0.5,), mu=((1.0, 0.8, 0.7),))
    with pytest.raises(ValueError, match="lut inversion: the device has a CalibratedFrictionModel"):
        build_pipeline(grating_scene(5.0, device=DeviceProfile(calibration=cal)), inversion="lut")
    with pytest.raises(ValueError, match="unknown inversion 'fast'"):
        build_pipeline(scene, inversion="fast")
    assert isinstance(build_pipeline(scene).friction, SeedFrictionModel)
