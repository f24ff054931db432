"""The closed-form 2 x 2 modal gains on systems whose entries span many decades."""

import numpy as np
import pytest

from frictex.device.actuation import modal


@pytest.mark.parametrize("regularised", [False, True])
@pytest.mark.parametrize("phi", [
    [[1e200, 0.0], [0.0, 1e-200]],      # e*e overflowed: NaN modal amplitudes
    [[1e-200, 0.0], [0.0, 1e-200]],     # the determinant underflowed to 0 (solve: at rest)
    [[1e300, 1e300], [1e300, -1e300]],
])
def test_extreme_scales_match_the_svd_and_stay_finite(phi, regularised):
    phi, wanted = np.array(phi)[None], np.array([0.4, 0.1], complex)[None]
    threshold = modal.gain_threshold("regularised" if regularised else "exact", modal.DEFAULT_RCOND)
    closed, _, _ = modal._gains_2x2(phi, wanted, threshold, regularised)
    with np.errstate(over="ignore", invalid="ignore"):
        svd, _, _ = modal._gains_svd(phi, wanted, threshold, regularised)
    assert np.all(np.isfinite(closed))
    np.testing.assert_allclose(closed, svd, rtol=1e-12)


def test_scaling_leaves_ordinary_systems_bit_for_bit():
    rng = np.random.default_rng(3)
    phi = rng.normal(size=(200, 2, 2))
    wanted = rng.normal(size=(200, 2)) + 0j
    plain = modal.solve(phi, wanted, "exact").modal_um
    scaled = modal.solve(phi * 2.0 ** 40, wanted, "exact").modal_um * 2.0 ** 40
    assert np.array_equal(plain, scaled)


@pytest.mark.parametrize("method", ["exact", "regularised", "bounded"])
@pytest.mark.parametrize("phi", [
    [[1e-310, 2e-310], [3e-310, 1e-311]],           # the closed form's gains overflowed
    [[1e-310, 2e-310, 0.0], [3e-310, 1e-311, 1e-312]],  # the SVD's: inf, then NaN
    [[3e-308, 0.0], [0.0, 3e-308]],                 # 10 um / 3e-308 is past the largest float
])
def test_shapes_too_small_to_reach_the_fingers_give_no_command(phi, method):
    """Mode shapes below about 1e-308 under every finger need amplitudes no float holds:
    the sample gets none (the plate at rest), counted as capped, never inf or NaN."""
    wanted = np.array([10.0, 0.5])
    with np.errstate(over="raise", divide="raise", invalid="raise"):  # none left to warnings
        got = modal.solve(phi, wanted, method, limits_um=3.0, actuators=np.eye(len(phi[0])))
    assert np.array_equal(got.commands_um, np.zeros(len(phi[0])))
    assert got.capped and not got.limited
    np.testing.assert_array_equal(got.error_um, np.abs(wanted))


@pytest.mark.parametrize("modes", [2, 3])
def test_bounded_commands_do_not_depend_on_the_shapes_scale(modes):
    """min ||M c - w|| within |c_j| <= L has the same c for (M s, w s): shapes of 5e-91
    (the determinant of their M^H M underflowed to 0: the two-actuator solver took the
    system for rank 1, the other divided by zero) give the commands of the same system
    at unit scale (s a power of two). solve itself gives shapes that small no command
    (NODE_FLOOR), so the bounded solver is asked directly."""
    rng = np.random.default_rng(modes)
    phi = rng.normal(size=(50, 2, modes))
    wanted = rng.normal(size=(50, 2)) * 4 + 0j  # most beyond the 1 um limits
    limits = np.ones(modes)
    start = modal.solve(phi, wanted, "exact", actuators=np.eye(modes)).commands_um
    scale = 2.0 ** -300  # 4.9e-91: within reach (1 um of command gives the fingers 1e-90 um)
    plain, _ = modal._bounded(phi, wanted, start, limits)
    tiny, unreached = modal._bounded(phi * scale, wanted * scale, start, limits)
    assert np.count_nonzero(np.abs(plain).max(axis=-1) >= 1 - 1e-12) > 25 and not unreached.any()
    np.testing.assert_allclose(plain, tiny, rtol=0, atol=1e-9)


def test_no_scale_of_the_shapes_gives_inf_nan_or_a_command_past_its_limit():
    """Shapes from 1e-325 to 1 (entries spread over 20 decades within a system, as near
    nodes), every method: finite results, commands within the limits."""
    rng = np.random.default_rng(2)
    for _ in range(600):
        modes = int(rng.integers(2, 4))
        fingers = int(rng.integers(1, modes + 1))
        phi = (rng.standard_normal((fingers, modes)) * 10.0 ** rng.uniform(-20, 0, (fingers, modes))
               * 10.0 ** rng.uniform(-325, 0))
        wanted = rng.standard_normal(fingers) * 10.0 ** rng.uniform(-3, 1)
        for method in ("exact", "regularised", "bounded"):
            got = modal.solve(phi, wanted, method, limits_um=3.0, actuators=np.eye(modes))
            for values in (got.modal_um, got.commands_um, got.achieved_um, got.error_um):
                assert np.all(np.isfinite(values)), (phi, wanted, method)
            assert np.all(np.abs(got.commands_um) <= 3.0 * (1 + 1e-12))


@pytest.mark.parametrize("modes", [2, 3])
def test_bounded_commands_too_weak_to_reach_the_fingers_are_counted_capped(modes):
    """Limits of 1e-105 um: every command within them moves the fingers by under
    1e-100 um; 'bounded' gives none, and counts the sample as capped (it was neither
    capped nor limited, unlike an overflow)."""
    rng = np.random.default_rng(modes)
    phi = rng.normal(size=(2, modes))
    got = modal.solve(phi, [0.5, 0.3], "bounded", limits_um=1e-105, actuators=np.eye(modes))
    assert np.array_equal(got.commands_um, np.zeros(modes)) and got.capped
    batch = modal.solve(np.stack([phi, phi * 1e10]), [[0.5, 0.3]] * 2, "bounded",
                        limits_um=1e-105, actuators=np.eye(modes))
    assert batch.capped[0] and np.any(batch.commands_um[1] != 0)
