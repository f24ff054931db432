"""The closed-form 2 x 2 modal gains on systems whose entries span many decades."""

import numpy as np
import pytest

from frictex.device.actuation import modal


@pytest.mark.parametrize("method", ["exact", "regularised"])
@pytest.mark.parametrize("phi", [
    [[1e200, 0.0], [0.0, 1e-200]],      # e*e overflowed: NaN modal amplitudes
    [[1e-200, 0.0], [0.0, 1e-200]],     # the determinant underflowed to 0
    [[1e300, 1e300], [1e300, -1e300]],
])
def test_extreme_scales_match_the_svd_and_stay_finite(phi, method):
    wanted = [0.4, 0.1]
    closed = modal.solve(phi, wanted, method)
    with np.errstate(over="ignore", invalid="ignore"):
        svd, _, _ = modal._gains_svd(np.array(phi)[None], np.array(wanted, complex)[None],
                                     modal.gain_threshold(method, modal.DEFAULT_RCOND),
                                     regularised=method == "regularised")
    assert np.all(np.isfinite(closed.modal_um)) and np.all(np.isfinite(closed.achieved_um))
    np.testing.assert_allclose(closed.modal_um, svd[0], rtol=1e-12)


def test_scaling_leaves_ordinary_systems_bit_for_bit():
    rng = np.random.default_rng(3)
    phi = rng.normal(size=(200, 2, 2))
    wanted = rng.normal(size=(200, 2)) + 0j
    plain = modal.solve(phi, wanted, "exact").modal_um
    scaled = modal.solve(phi * 2.0 ** 40, wanted, "exact").modal_um * 2.0 ** 40
    assert np.array_equal(plain, scaled)
