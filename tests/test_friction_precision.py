"""Seed 003's eq 3 near the floor: the inversion against the equation itself, evaluated
at 50 significant digits (``decimal``), at every amplitude limit and force that matter."""

from decimal import Decimal, localcontext

import numpy as np
import pytest

from frictex.device.friction import SeedFrictionModel
from frictex.device.profile import DeviceProfile
from frictex.rendering.inversion_lut import TABLE_SIZE, LutFrictionModel

#: the exact inversion: a few roundings of q (relative) and of the logarithm (of w)
EXACT_BOUND_UM = 1e-12


def _eq3_um(mu: float, force: float, device: DeviceProfile) -> float:
    """Seed 003, eq 3, w = -(1/b) ln((mu' - A) / (1 - A)) with A = k F_n, at 50 digits
    from the doubles given (the model's constants as the device holds them), clamped to
    the amplitude limit where mu' is below its reach. A and mu' - A are exact (a product
    of two doubles has at most 107 digits)."""
    with localcontext() as ctx:
        ctx.prec = 120
        k, b = Decimal(device.friction.asymptote_per_n), Decimal(device.friction.b_per_um)
        a = k * Decimal(force)
        gap, span = Decimal(mu) - a, 1 - a
        ctx.prec = 50
        q = gap / span
        limit = Decimal(device.amplitude_limit_um)
        return float(limit if q <= 0 else min(-q.ln() / b, limit))


def _floor(force: float, device: DeviceProfile) -> float:
    """Seed 003, eq 2, at the limit: (1 - A) exp(-b w_max) + A, at 50 digits."""
    with localcontext() as ctx:
        ctx.prec = 120
        a = Decimal(device.friction.asymptote_per_n) * Decimal(force)
        w = Decimal(device.amplitude_limit_um)
        return float((1 - a) * (-Decimal(device.friction.b_per_um) * w).exp() + a)


def _targets(force: float, device: DeviceProfile) -> np.ndarray:
    """From the doubles just above the floor, through tiny and large reductions, to 1."""
    floor = _floor(force, device)
    above = [floor]
    for _ in range(8):
        above.append(np.nextafter(above[-1], 2.0))
    offsets = floor + (1.0 - floor) * np.logspace(-15, 0, 61)
    return np.unique(np.clip(np.concatenate([above, offsets, np.linspace(floor, 1.0, 41),
                                             1.0 - np.logspace(-16, -1, 16)]), floor, 1.0))


@pytest.mark.parametrize("limit_um", [2.5, 20.0, 100.0])
@pytest.mark.parametrize("force", [0.0, 0.05, 0.5])
def test_inversion_is_equation_3_to_its_last_digits_down_to_the_floor(limit_um, force):
    """Before, 1 - mu' rounded left q = 1 - r few correct digits near the floor: at 20 um,
    0 N, mu' = 1e-14 gave 19.303587 um for eq 3's 19.303109, and errors reached 0.018 um.
    Now the exact inversion is within 1e-12 um of eq 3 and the table within its
    interpolation bound h^2 / (2 b) (4.5e-9 um) of it, from the floor to 1."""
    device = DeviceProfile(amplitude_limit_um=limit_um)
    exact = SeedFrictionModel(device)
    lut = LutFrictionModel(exact)
    mu = _targets(force, device)
    expected = np.array([_eq3_um(m, force, device) for m in mu])
    forces = np.full(mu.size, force)
    w_exact, _ = exact.invert(mu, forces)
    w_lut, _ = lut.invert(mu, forces)
    h = 0.5 / (TABLE_SIZE - 1)
    lut_bound = h * h / (2 * device.friction.b_per_um) * (1 + 1e-6) + EXACT_BOUND_UM
    assert np.abs(w_exact - expected).max() <= EXACT_BOUND_UM
    assert np.abs(w_lut - expected).max() <= lut_bound
    assert expected.min() == 0.0 and expected.max() > limit_um - 0.1  # the whole range


def test_the_reported_case():
    device = DeviceProfile(amplitude_limit_um=20.0)
    w, counts = SeedFrictionModel(device).invert([1e-14], [0.0])
    assert abs(w[0] - (-np.log(1e-14) / 1.67)) < 1e-12 and counts.total == 0
