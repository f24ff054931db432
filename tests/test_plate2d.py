"""Seed 001's 2D plate: X and Y modes (eq 6), the loci of eq 8, the V_AC / V_BD wiring."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.device.structures.beam import ModesError
from frictex.device.actuation.modal import solve
from frictex.device.structures.plate2d import ACTUATORS, Plate2D

# seed 001 section 4.1: 140 x 140 x 4 mm, k = 8; aluminium assumed (the paper names no material)
PLATE = Plate2D(140, 140, 4, 69, 2700, poisson=0.33, order=8)
LAM = 17 * math.pi / 2


def test_shapes_follow_eq6():
    x, y = np.array([35.0, 10.0]), np.array([70.0, 140.0])
    assert_allclose(PLATE.phi(x, y), np.stack([np.sin(LAM * x / 140), np.sin(LAM * y / 140)], -1),
                    rtol=1e-15)


def test_det_is_eq8_and_vanishes_on_its_loci():
    rng = np.random.default_rng(0)
    pts = rng.uniform(0, 140, (100, 4))
    full = np.stack([PLATE.phi(pts[:, 0], pts[:, 1]), PLATE.phi(pts[:, 2], pts[:, 3])], -2)
    assert_allclose(PLATE.det(*pts.T), np.linalg.det(full), atol=1e-14)
    # Fig. 1's first finger at (0.25, 0.5) of the side; with y2 = y1 the locus is
    # sin(lam x2) = sin(lam x1), e.g. x2 mirrored about the crest at pi / (2 lam)
    x1, y1 = 0.25 * 140, 0.5 * 140
    x2 = (2 * math.pi * 2 + math.pi - LAM * x1 / 140) * 140 / LAM
    assert abs(PLATE.det(x1, y1, x2, y1)) < 1e-13
    assert abs(PLATE.det(x1, y1, x2 + 3, y1)) > 0.1


def test_nodes_and_wavelength():
    nodes = PLATE.nodes_mm("x")
    assert nodes.size == 9
    assert_allclose(PLATE.phi(nodes, 20.0)[..., 0], 0, atol=1e-14)
    assert_allclose(PLATE.wavelength_mm("y"), 140 * 4 / 17, rtol=1e-15)


def test_frequency_from_plate_equation():
    d = 69e9 * 0.004 ** 3 / (12 * (1 - 0.33 ** 2))  # seed 001, eq 2
    beta = LAM / 0.14
    assert_allclose(PLATE.frequency_hz("x"), beta ** 2 * math.sqrt(d / (2700 * 0.004)) / (2 * math.pi),
                    rtol=1e-14)
    # seed 001 measured f_x = 33010 Hz; the strip estimate lands within 10 %
    assert abs(PLATE.frequency_hz("x") / 33010 - 1) < 0.1


def test_vac_vbd_wiring():
    # V_AC alone: modes X and Y in phase; V_BD alone: in opposition (seed 001 section 4.1)
    to_modes = np.linalg.inv(ACTUATORS)
    assert_allclose(to_modes @ [1.0, 0.0], [1.0, 1.0])
    assert_allclose(to_modes @ [0.0, 1.0], [1.0, -1.0])


def test_fig7_node_becomes_antinode():
    # a point with sin(lam x) = -sin(lam y) is a node for W_X = W_Y and an antinode for W_X = -W_Y
    x, y = 140 / LAM * math.pi / 2, 140 / LAM * 3 * math.pi / 2
    phi = PLATE.phi(x, y)
    assert abs(phi @ [1.0, 1.0]) < 1e-14
    assert_allclose(abs(phi @ [1.0, -1.0]), 2.0, rtol=1e-14)


def test_two_fingers_on_the_plate_through_vac_vbd():
    phi = np.stack([PLATE.phi(30.0, 40.0), PLATE.phi(100.0, 90.0)])
    wanted = np.array([0.5, 0.1j])
    sol = solve(phi, wanted, "bounded", actuators=ACTUATORS, limits_um=2.0)
    assert_allclose(sol.achieved_um, wanted, atol=1e-12)
    v_ac, v_bd = sol.commands_um
    assert_allclose(sol.modal_um, [v_ac + v_bd, v_ac - v_bd], atol=1e-14)


def test_regularised_continuous_across_eq8_locus():
    x1, y1 = 35.0, 70.0
    x2_locus = (2 * math.pi * 2 + math.pi - LAM * x1 / 140) * 140 / LAM
    x2 = np.linspace(x2_locus - 2, x2_locus + 2, 4001)
    phi = np.stack(np.broadcast_arrays(PLATE.phi(x1, y1), PLATE.phi(x2, y1)), -2)
    sol = solve(phi, [0.5, 0.0], "regularised", actuators=ACTUATORS, limits_um=2.0)
    assert np.all(np.abs(sol.commands_um) <= 2.0 + 1e-12)
    assert np.max(np.abs(np.diff(sol.commands_um, axis=0))) < 5e-3
    assert sol.capped.any()


@pytest.mark.parametrize("kwargs, match", [
    (dict(order=0), "order k must be an integer >= 1, got 0"),
    (dict(thickness_mm=-4), "thickness_mm must be a finite number > 0, got -4"),
    (dict(poisson=0.5), "poisson must be in"),
])
def test_bad_plates(kwargs, match):
    with pytest.raises(ModesError, match=match):
        Plate2D(**{**dict(width_mm=140, height_mm=140, thickness_mm=4, youngs_gpa=69,
                          density_kg_m3=2700), **kwargs})


def test_bad_axis():
    with pytest.raises(ModesError, match="axis must be 'x' or 'y', got 'z'"):
        PLATE.nodes_mm("z")
