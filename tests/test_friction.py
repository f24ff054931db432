"""Seed 003 friction model (eqs 2-3) and its inversion, including every hard case."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from frictex.device.friction import (CalibratedFrictionModel, ClampCounts, SeedFrictionModel, forward_mu,
                                make_friction_model, mu_floor)
from frictex.device.profile import Calibration, DeviceProfile, FrictionParams

DEVICE = DeviceProfile(amplitude_limit_um=2.5, normal_force_n=0.5)
MODEL = SeedFrictionModel(DEVICE)


def test_forward_matches_seed_equation_2():
    # eq 2 by hand: (1 - 1.13 F) exp(-1.67 w) + 1.13 F at F = 0.5 N, w = 1 um
    expected = (1 - 0.565) * np.exp(-1.67) + 0.565
    assert_allclose(forward_mu(1.0, 0.5, FrictionParams()), expected, rtol=1e-15)


def test_inversion_matches_seed_equation_3():
    mu = 0.7
    expected = -1 / 1.67 * np.log((mu - 0.565) / (1 - 0.565))
    w, counts = MODEL.invert(mu, 0.5)
    assert_allclose(w, expected, rtol=1e-13)
    assert counts.total == 0


@settings(max_examples=300, derandomize=True, deadline=None)
@given(w=st.floats(0.0, 2.5), force=st.floats(0.0, 0.8))
def test_round_trip_on_reachable_range(w, force):
    mu = MODEL.forward(w, force)
    w_back, counts = MODEL.invert(mu, force)
    assert abs(float(w_back) - w) <= 1e-9
    assert counts.unreachable == 0


def test_target_at_or_above_one_gives_zero():
    w, counts = MODEL.invert(np.array([1.0, 1.0 + 1e-12, 1.7]), 0.5)
    assert_allclose(w, 0.0, atol=0)
    assert counts.above_one == 2  # exactly 1 is the plate at rest, not a clamp


def test_target_below_asymptote_is_unreachable_and_counted():
    w, counts = MODEL.invert(np.array([0.565, 0.3, 1e-9]), 0.5)
    assert_allclose(w, 2.5)
    assert counts.unreachable == 3


def test_target_within_1e_12_of_asymptote_is_finite_and_clamped():
    w, counts = MODEL.invert(np.array([0.565 + 1e-12, 0.565 + 1e-15]), 0.5)
    assert np.all(np.isfinite(w)) and np.all(w == 2.5)
    assert counts.unreachable == 2


def test_target_between_limit_floor_and_asymptote_clamps_to_limit():
    floor = float(MODEL.floor(0.5))
    assert floor > 0.565
    w, counts = MODEL.invert(np.array([floor + 1e-6, (floor + 0.565) / 2]), 0.5)
    assert w[0] < 2.5 and w[1] == 2.5
    assert counts.unreachable == 1


def test_normal_force_near_zero_is_regular():
    w, counts = MODEL.invert(0.5, np.array([0.0, 1e-300, 1e-9]))
    expected = -np.log(0.5) / 1.67
    assert_allclose(w, expected, rtol=1e-8)
    assert counts.total == 0


@pytest.mark.parametrize("force, mu", [(0.85, 0.99), (0.8407, 0.99), (0.88, 0.999)])
def test_model_holds_up_to_its_asymptote_reaching_one(force, mu):
    """Seed 003's model holds for A = 1.13 F_n < 1 (F_n < 0.885 N): eq 3 there, no clamp.
    At 0.85 N a target of 0.99 is 0.175 um (a cap at A = 0.95 gave 0.134 um)."""
    a = 1.13 * force
    expected = -np.log((mu - a) / (1 - a)) / 1.67  # eq 3
    w, counts = MODEL.invert(np.array([mu]), force)
    assert_allclose(w, expected, rtol=1e-12)
    assert counts.total == 0
    assert_allclose(MODEL.forward(w, force), mu, rtol=1e-13)
    if force == 0.85:
        assert abs(float(w[0]) - 0.175) < 5e-4


def test_model_holds_within_a_nanometre_of_its_bound():
    """1 - A = 2e-9, inside the model (margin 1e-9): a target half way down its tiny range
    is ln 2 / b, to the rounding eq 3 has there (eps / (b (mu' - A)) ~ 7e-8 um)."""
    force = (1 - 2e-9) / 1.13
    a = 1.13 * force
    mu = 1 - (1 - a) / 2
    w, counts = MODEL.invert(np.array([mu]), force)
    assert_allclose(w, np.log(2) / 1.67, atol=1e-6)
    assert counts.total == 0


@pytest.mark.parametrize("force", [1 / 1.13, 0.9, 3.0, 1e6])
def test_force_where_asymptote_reaches_one_is_beyond_the_model_and_counted(force):
    """A >= 1: no reduction is reachable; targets below 1 get the full amplitude (the
    limit the valid model tends to, never a sign flip), counted as beyond the model
    only; a target of 1 is w = 0 and no clamp."""
    w, counts = MODEL.invert(np.array([1.0, 0.97, 0.5]), force)
    assert_array_equal(w, [0.0, 2.5, 2.5])
    assert counts.force_beyond_model == 2 and counts.total == 2


def test_nan_and_inf_in():
    w, counts = MODEL.invert(np.array([np.nan, np.inf, -np.inf, 0.8]),
                             np.array([0.5, 0.5, 0.5, np.nan]))
    assert np.all(np.isfinite(w)) and np.all((0 <= w) & (w <= 2.5))
    assert w[0] == 0 and w[1] == 0 and w[2] == 0  # non-finite targets: plate off
    assert counts.nonfinite_target == 3 and counts.bad_force == 1
    assert_allclose(w[3], MODEL.invert(0.8, 0.5)[0])  # bad force -> nominal force


def test_mu_floor_at_half_newton():
    # seed 003: asymptote 1.13 * 0.5 = 0.565; the 2.5 um limit stops a little above it
    assert mu_floor(DEVICE, 0.5) == pytest.approx(0.565 + 0.435 * np.exp(-1.67 * 2.5), rel=1e-12)


CAL = Calibration(amplitudes_um=(0, 0.5, 1, 2, 3), forces_n=(0.3, 0.6),
                  mu=((1, 0.8, 0.6, 0.45, 0.4), (1, 0.85, 0.7, 0.6, 0.58)))
CAL_DEVICE = DeviceProfile(amplitude_limit_um=2.5, calibration=CAL)


def test_calibration_interpolates_measured_points_exactly():
    model = make_friction_model(CAL_DEVICE)
    assert isinstance(model, CalibratedFrictionModel)
    w, counts = model.invert(np.array([0.8, 0.6, 0.45, 0.85, 0.7]),
                             np.array([0.3, 0.3, 0.3, 0.6, 0.6]))
    assert_allclose(w, [0.5, 1.0, 2.0, 0.5, 1.0], atol=1e-12)
    assert counts.total == 0


@settings(max_examples=60, derandomize=True, deadline=None)
@given(mu=st.floats(0.6, 1.0), force=st.floats(0.3, 0.6))
def test_calibration_round_trip_and_monotone(mu, force):
    model = make_friction_model(CAL_DEVICE)
    w, counts = model.invert(mu, force)
    assert 0 <= w <= 2.5
    if counts.unreachable == 0:
        assert_allclose(model.forward(w, force), mu, atol=1e-9)
    w2, _ = model.invert(mu - 0.01, force)
    assert w2 >= w


def test_calibration_outside_measured_forces_is_counted():
    model = make_friction_model(CAL_DEVICE)
    w, counts = model.invert(np.array([0.8, 0.8]), np.array([0.1, 2.0]))
    assert counts.force_beyond_model == 2
    assert_allclose(w, [0.5, model.invert(0.8, 0.6)[0]], atol=1e-12)


def test_a_force_outside_the_calibration_counts_once_and_only_below_one():
    """A target of 1 is w = 0 whatever the force: not counted. One out of the nearest
    row's reach gets the limit, counted as beyond the table only (the clamp total is the
    samples changed, each once). The warning names the table's forces, not seed 003."""
    model = make_friction_model(CAL_DEVICE)
    w, counts = model.invert(np.array([1.0, 1.0, 0.8, 0.05]), np.array([0.1, 2.0, 2.0, 2.0]))
    assert_allclose(w, [0.0, 0.0, model.invert(0.8, 0.6)[0], 2.5], atol=1e-12)
    assert counts.as_dict() == {**ClampCounts().as_dict(), "force_beyond_model": 2}
    assert model.beyond_model() == ("outside the calibration's measured forces (0.3 to 0.6 N): "
                                    "the nearest measured force's row was used")


def test_the_seed_models_warning_gives_its_own_asymptote():
    model = SeedFrictionModel(DeviceProfile(friction=FrictionParams(asymptote_per_n=0.5)))
    assert "asymptote 0.5 F_n reaches 1" in model.beyond_model()


def test_amplitude_is_equation_3_bit_for_bit_with_unreachable_targets_among_them():
    """Eq 3 as log1p(-r) for r = (1 - mu') / (1 - A) <= 1/2, as log(q), q = (mu' - A) /
    (1 - A), above (A = 0.565 is 1.13 F_n exactly at 0.5 N); unreachable targets skip
    log(0) (slow in numpy) and give NaN, which the guards clamp."""
    mu = np.concatenate([np.linspace(-0.5, 1.0, 3001), [0.565, np.nextafter(0.565, 1.0),
                                                          np.nan, -0.0]])
    force = np.concatenate([np.full(mu.size - 4, 0.5), [0.5, 0.5, 0.5, 0.9]])
    params = DEVICE.friction
    a = np.minimum(params.asymptote_per_n * force, 1.0 - 1e-9)
    r, q = (1.0 - mu) / (1.0 - a), (mu - a) / (1.0 - a)
    with np.errstate(divide="ignore", invalid="ignore"):
        eq3 = np.where(r > 0.5, np.where(q > 0.0, -np.log(q), np.nan),
                       -np.log1p(-r)) / params.b_per_um
    eq3 = np.where((a == 1.0 - 1e-9) & (mu < 1.0), DEVICE.amplitude_limit_um, eq3)  # beyond
    cases = ((mu, force, eq3), (mu[:2000], 0.5, eq3[:2000]), (mu[:500], 0.5, eq3[:500]),
             (mu[2800:2810], 0.5, eq3[2800:2810]), (mu[-4], 0.5, eq3[-4]),
             (mu[1600], 0.5, eq3[1600]))
    assert np.isnan(eq3).sum() > 1000 and np.isfinite(eq3[mu > 0.565]).all()
    for m, f, expected in cases:  # some, all and none unreachable
        w = MODEL._amplitude(m, f, ClampCounts())
        w = np.where(np.isnan(w), np.nan, w)  # a NaN's sign is no result
        assert w.tobytes() == np.asarray(expected).tobytes()


class _GeneralPath(SeedFrictionModel):
    """Seed 003's model, taken through the general guards (the compiled path is for
    ``SeedFrictionModel`` itself only)."""


@pytest.mark.parametrize("force", [0.5, 0.0, 0.3, 0.884, 0.9, np.nan, -1.0, "mixed"])
def test_compiled_inversion_is_the_general_path_bit_for_bit(force):
    """The usual block's two compiled passes about numpy's log1p give the general path's
    amplitudes (signed zeros too) and counts: targets above 1, at 1, reachable, near the
    floor and the asymptote, unreachable; and blocks it hands back (a force that is not
    one finite value >= 0 within the model, targets that are not finite)."""
    rng = np.random.default_rng(11)
    a = 1.13 * 0.5
    mu = np.concatenate([rng.uniform(0.0, 1.2, 3000), [1.0, 1.0 + 1e-16, 0.999999999999, a,
                                                       a + 1e-13, a - 1e-13, 0.58, 0.5801, 0.0]])
    for targets in (mu, mu[mu < 1.0], np.full(50, 1.0), np.append(mu, np.nan),
                    np.append(mu, np.inf)):
        if force == "mixed":
            forces = np.where(np.arange(targets.size) % 2, 0.5, 0.4)
        else:
            forces = np.full(targets.size, force)
        for shape in ((targets.size,), (1, targets.size)):
            m, f = targets.reshape(shape), forces.reshape(shape)
            w, counts = MODEL.invert(m, f)
            w_ref, counts_ref = _GeneralPath(DEVICE).invert(m, f)
            assert w.shape == w_ref.shape and w.dtype == w_ref.dtype
            assert w.tobytes() == w_ref.tobytes()
            assert counts == counts_ref
    # the usual block does reach the limit and the clip to it, and counts both
    w, counts = MODEL.invert(mu, np.full(mu.size, 0.5))
    assert counts.unreachable > 100 and counts.above_one > 100 and (w == 2.5).sum() > 100
