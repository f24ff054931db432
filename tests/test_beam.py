"""Free-free beams (seed 000, eq 2, Table I): roots, frequencies, shapes, nodes, both theories."""

import math

import numpy as np
import pytest
from numpy.polynomial import chebyshev as cheb
from numpy.testing import assert_allclose

from frictex.device.structures.beam import FreeFreeBeam, ModesError

# seed 000, Table I
TABLE_I = dict(length_mm=350, width_mm=6, thickness_mm=6, youngs_gpa=57, density_kg_m3=2561)
EB = FreeFreeBeam(**TABLE_I)
TIMO = FreeFreeBeam(**TABLE_I, theory="timoshenko", poisson=0.33)
L = 350.0


def test_first_roots_match_published_table():
    # roots of cos(bL) cosh(bL) = 1 as tabulated (e.g. Blevins, Formulas for natural frequency)
    published = [4.730040745, 7.853204624, 10.995607838, 14.137165491, 17.278759657]
    beta_l = [2 * math.pi / EB.wavelength_mm(n) * L for n in range(1, 6)]
    assert_allclose(beta_l, published, rtol=2e-10)


@pytest.mark.parametrize("order", [16, 17, 60])
def test_euler_bernoulli_frequency_from_dimensions_alone(order):
    # at high order bL = (2n+1) pi / 2 to within e^{-bL}; omega = beta^2 sqrt(E h^2 / (12 rho))
    beta = (2 * order + 1) * math.pi / 2 / 0.35
    expected = beta ** 2 * math.sqrt(57e9 * 0.006 ** 2 / 12 / 2561) / (2 * math.pi)
    assert_allclose(EB.frequency_hz(order), expected, rtol=1e-13)


@pytest.mark.parametrize("order", range(1, 5))
def test_low_orders_match_textbook_cosh_sinh_form(order):
    # the textbook form is accurate while e^{bL} is small (it is off by 2e-8 at order 6)
    bl = 2 * math.pi / EB.wavelength_mm(order) * L
    sigma = (math.cosh(bl) - math.cos(bl)) / (math.sinh(bl) - math.sin(bl))
    u = np.linspace(0, 1, 301) * bl
    textbook = np.cosh(u) + np.cos(u) - sigma * (np.sinh(u) + np.sin(u))
    assert_allclose(EB.shape(order, np.linspace(0, L, 301)), textbook, atol=1e-10)


def test_orthonormal_to_1e9_up_to_order_100():
    # composite Gauss-Legendre, 3000 panels of 16 points (independent of the module's)
    gx, gw = np.polynomial.legendre.leggauss(16)
    edges = np.linspace(0, L, 3001)
    half = np.diff(edges)[:, None] / 2
    x = (edges[:-1, None] + half * (1 + gx)).ravel()
    w = (half * gw).ravel() / L
    phi = EB.phi(range(1, 101), x)
    gram = phi.T @ (w[:, None] * phi)
    assert_allclose(gram, np.eye(100), atol=1e-9)


@pytest.mark.parametrize("order", [1, 16, 17, 55, 100])
def test_free_ends_and_symmetry(order):
    # unit-RMS free-free modes have |W| = 2 at both free ends; mode n is (anti)symmetric
    x = np.linspace(0, L, 97)
    w = EB.shape(order, x)
    assert_allclose([w[0], abs(w[-1])], [2.0, 2.0], rtol=1e-12)
    assert_allclose(EB.shape(order, L - x), (-1) ** (order + 1) * w, atol=1e-11)


@pytest.mark.parametrize("beam", [EB, TIMO], ids=["euler-bernoulli", "timoshenko"])
@pytest.mark.parametrize("order", [1, 2, 16, 17, 40])
def test_nodes_count_position_and_symmetry(beam, order):
    nodes = beam.nodes_mm(order)
    assert nodes.shape == (order + 1,)
    assert np.all(np.diff(nodes) > 0) and 0 < nodes[0] and nodes[-1] < L
    assert_allclose(beam.shape(order, nodes), 0, atol=1e-12)
    assert_allclose(nodes + nodes[::-1], L, atol=1e-9)


def test_order_100_has_101_nodes():
    nodes = EB.nodes_mm(100)
    assert nodes.size == 101
    # interior nodes sit half a wavelength apart
    assert_allclose(np.diff(nodes[10:-10]), EB.wavelength_mm(100) / 2, rtol=1e-9)


def test_seed000_wavelength_near_41mm():
    # seed 000 section III.C: "wavelength of 41.5 mm" between modes 16 and 17
    assert 39.9 < EB.wavelength_mm(17) < 41.5 < EB.wavelength_mm(16) < 43


E, RHO, R2 = 57e9, 2561.0, 0.006 ** 2 / 12
KG = 10 * 1.33 / (12 + 11 * 0.33) * E / (2 * 1.33)  # Cowper's kappa times G, nu = 0.33


def _fit(beam, order, a_m, b_m, deg=40):
    """Chebyshev fit of the shape against x in metres (derivatives in SI units)."""
    x = np.linspace(a_m, b_m, 400)
    return cheb.Chebyshev.fit(x, beam.shape(order, x * 1e3), deg)


@pytest.mark.parametrize("order", [3, 16, 17])
def test_timoshenko_shape_solves_the_timoshenko_equation(order):
    # W'''' + w^2 rho (1/E + 1/kG) W'' + (rho w^2 / (E r^2)) (rho r^2 w^2 / kG - 1) W = 0
    w2 = (2 * math.pi * TIMO.frequency_hz(order)) ** 2
    fit = _fit(TIMO, order, 0.100, 0.130)
    x = np.linspace(0.102, 0.128, 50)
    residual = (fit.deriv(4)(x) + w2 * RHO * (1 / E + 1 / KG) * fit.deriv(2)(x)
                + RHO * w2 / (E * R2) * (RHO * R2 * w2 / KG - 1) * fit(x))
    assert np.max(np.abs(residual)) < 1e-6 * np.max(np.abs(fit.deriv(4)(x)))


@pytest.mark.parametrize("order", [2, 16, 17])
def test_timoshenko_free_end_conditions(order):
    # no moment: W'' + q W = 0; no shear: W''' + (q + rho w^2 / E) W' = 0, q = rho w^2 / kG
    w2 = (2 * math.pi * TIMO.frequency_hz(order)) ** 2
    q = RHO * w2 / KG
    fit = _fit(TIMO, order, 0.0, TIMO.wavelength_mm(order) * 1e-3 / 3, deg=24)
    d0, d1, d2, d3 = (fit.deriv(k)(0.0) for k in range(4))
    scale = (2 * math.pi / TIMO.wavelength_mm(order) * 1e3) ** 3 * abs(d0)
    assert abs(d2 + q * d0) < 1e-6 * scale
    assert abs(d3 + (q + RHO * w2 / E) * d1) < 1e-6 * scale


def test_timoshenko_tends_to_euler_bernoulli_for_slender_beams():
    # first-order correction: w_T / w_EB = 1 - (beta r)^2 (1 + E / kG) / 2 + O((beta r)^4)
    slender = dict(TABLE_I, thickness_mm=0.06)
    eb = FreeFreeBeam(**slender)
    timo = FreeFreeBeam(**slender, theory="timoshenko")
    beta_r = 2 * math.pi / eb.wavelength_mm(20) * 0.06 / math.sqrt(12)
    expected = 1 - beta_r ** 2 * (1 + E / KG) / 2
    assert_allclose(timo.frequency_hz(20) / eb.frequency_hz(20), expected, atol=5 * beta_r ** 4)


def test_timoshenko_lowers_seed000_frequencies_towards_measured():
    # seed 000 Fig. 10: measured 26373 Hz (mode 16) and 29369 Hz (mode 17)
    for order, measured in ((16, 26373.0), (17, 29369.0)):
        assert abs(TIMO.frequency_hz(order) - measured) < abs(EB.frequency_hz(order) - measured)
    ratio = lambda b: b.frequency_hz(17) / b.frequency_hz(16)  # noqa: E731
    assert abs(ratio(TIMO) - 29369 / 26373) < abs(ratio(EB) - 29369 / 26373)


def test_order_above_timoshenko_cutoff_is_refused():
    with pytest.raises(ModesError, match="cutoff"):
        TIMO.frequency_hz(90)


def _timoshenko_free_free_det(beam: FreeFreeBeam, frequency_hz: float) -> float:
    """Determinant of the free ends' conditions (E I psi' = 0, kappa G A (w' - psi) = 0 at
    0 and L) written from the equations of motion at ``frequency_hz``, below the cutoff:
    w = e^{s x}, psi = P e^{s x} with rho w_tt = kG (w'' - psi') giving P = (kG s^2 +
    rho w^2) / (kG s), and s^2 a root of (kG s^2 + rho w^2)(E r2 s^2 - kG + rho r2 w^2)
    + kG^2 s^2 = 0."""
    nu, e, rho, length = beam.poisson, beam.youngs_gpa * 1e9, beam.density_kg_m3, beam.length_mm * 1e-3
    kg = 10 * (1 + nu) / (12 + 11 * nu) * e / (2 * (1 + nu))
    r2 = (beam.thickness_mm * 1e-3) ** 2 / 12
    w2 = (2 * math.pi * frequency_hz) ** 2
    squares = np.roots([kg * e * r2, kg * rho * r2 * w2 + rho * w2 * e * r2,
                        rho * w2 * (rho * r2 * w2 - kg)])
    alpha, beta = math.sqrt(max(squares.real)), math.sqrt(-min(squares.real))
    columns = []
    # e^{-alpha x}, e^{alpha (x - L)} (each at most 1 on the beam), e^{j beta x} (re, im)
    for s, shift in ((-alpha, 0.0), (alpha, length), (1j * beta, 0.0)):
        p = (kg * s * s + rho * w2) / (kg * s)
        ends = [np.exp(s * (x - shift)) for x in (0.0, length)]
        column = np.array([s * p * ends[0] / beta ** 2, (s - p) * ends[0] / beta,
                           s * p * ends[1] / beta ** 2, (s - p) * ends[1] / beta])
        columns += [column.real, column.imag] if s.imag else [column.real]
    return float(np.linalg.det(np.array(columns).T))


@pytest.mark.parametrize("length_mm, order", [(350, 73), (60, 12)])
def test_timoshenko_order_below_the_cutoff_in_an_interval_reaching_past_it_is_found(
        length_mm, order):
    # before: refused, quoting the end of the root search (beta L = 74 pi, 245605 Hz)
    beam = FreeFreeBeam(**dict(TABLE_I, length_mm=length_mm), theory="timoshenko")
    f = beam.frequency_hz(order)
    assert f < beam.cutoff_hz
    from scipy.optimize import brentq
    below = beam.frequency_hz(order - 1)
    grid = np.linspace(below + 1.0, beam.cutoff_hz * (1 - 1e-9), 400)
    dets = [_timoshenko_free_free_det(beam, g) for g in grid]
    change = np.flatnonzero(np.signbit(dets[:-1]) != np.signbit(dets[1:]))
    assert change.size == 1  # one mode between order - 1 and the cutoff
    root = brentq(lambda g: _timoshenko_free_free_det(beam, g), grid[change[0]],
                  grid[change[0] + 1], xtol=1e-9)
    assert_allclose(f, root, rtol=1e-9)


@pytest.mark.parametrize("length_mm, order", [(350, 74), (60, 13)])
def test_timoshenko_order_with_no_root_below_the_cutoff_is_refused(length_mm, order):
    beam = FreeFreeBeam(**dict(TABLE_I, length_mm=length_mm), theory="timoshenko")
    with pytest.raises(ModesError, match=rf"^mode order {order} is above the Timoshenko cutoff "
                                         r"245187 Hz of this beam: it has no flexural mode"):
        beam.frequency_hz(order)


@pytest.mark.parametrize("kwargs, match", [
    (dict(TABLE_I, length_mm=0), "length_mm must be a finite number > 0, got 0"),
    (dict(TABLE_I, youngs_gpa=float("nan")), "youngs_gpa"),
    (dict(TABLE_I, theory="rayleigh"), "theory must be one of"),
    (dict(TABLE_I, poisson=0.7), "poisson must be in"),
])
def test_bad_beam_parameters(kwargs, match):
    with pytest.raises(ModesError, match=match):
        FreeFreeBeam(**kwargs)


@pytest.mark.parametrize("order", [0, -3, 2.5, True])
def test_bad_orders(order):
    with pytest.raises(ModesError, match="mode order must be an integer >= 1"):
        EB.frequency_hz(order)
