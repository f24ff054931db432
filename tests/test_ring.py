"""Ring resonator (seed 004, eqs 6-11): the paper's 24th-order pair, the mode conditions
checked by substitution, the circle limit, every mode in a band, and the L/R crossings."""

import argparse
import json
import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.app.commands import modes_ring
from frictex.app.commands.cli import main
from frictex.device.structures.beam import ModesError
from frictex.device.structures.ring import RingResonator

# seed 004, section II-B: L 140 mm, R 50 mm, h 2.75 mm, w 30 mm, aluminium 5052
DESIGN = dict(length_mm=140, radius_mm=50, thickness_mm=2.75, width_mm=30, youngs_gpa=69,
              density_kg_m3=2680)
RING = RingResonator(**DESIGN)
E, RHO, H, W, R = 69e9, 2680.0, 2.75e-3, 30e-3, 50e-3
AREA, INERTIA = W * H, W * H ** 3 / 12


def test_24th_pair_matches_the_paper():
    sym, asym = RING.pair(24)
    # the paper: "40287 Hz and 40294 Hz" (rounded to 1 Hz)
    assert_allclose([sym.frequency_hz, asym.frequency_hz], [40287, 40294], atol=0.5)
    assert (sym.kind, asym.kind) == ("symmetric", "asymmetric")


def test_found_mode_satisfies_eqs_6_to_9_by_substitution():
    for mode in RING.pair(24):
        omega = 2 * math.pi * mode.frequency_hz
        ks, kc = mode.k_s_per_m, mode.k_c
        # eq 6 and eq 7 exactly as printed
        eq6 = ks ** 4 - (RHO / E) * ks ** 2 * omega ** 2 - (RHO * AREA / (E * INERTIA)) * omega ** 2
        a_c, g_c = RHO * AREA * R ** 4 / (E * INERTIA), RHO * R ** 2 / E
        eq7 = omega ** 2 * (g_c * kc ** 4 - 2 * g_c * kc ** 2 + a_c * kc ** 2 + a_c + g_c) \
            - kc ** 6 + 2 * kc ** 4 - kc ** 2
        assert abs(eq6) < 1e-12 * ks ** 4
        assert abs(eq7) < 1e-12 * kc ** 6
        # eqs 8-9 (symmetric) or their asymmetric counterparts: A_c = 1, A_s from the first,
        # the second must then hold
        a, b = ks * 0.140 / 2, kc * math.pi / 2
        if mode.kind == "symmetric":
            a_s = -kc * math.cos(-b) / math.cos(a)
            lhs, rhs = -a_s * ks * math.sin(a), kc ** 2 / R * math.sin(-b)
        else:  # V_s = sin(k_s x), v_c = -dU_c/dtheta = k_c sin(k_c theta)
            a_s = kc * math.sin(-b) / math.sin(a)
            lhs, rhs = a_s * ks * math.cos(a), kc ** 2 / R * math.cos(-b)
        assert_allclose(lhs, rhs, rtol=1e-9)
        assert RING.cost(kc, mode.kind) < 1e-20  # eq 11 at its zero


def test_circle_limit_gives_the_classical_inextensional_ring():
    # L -> 0: a circle, whose modes have exactly k_c = n (n waves around 2 pi)
    circle = RingResonator(**{**DESIGN, "length_mm": 1e-6})
    a_c, g_c = RHO * AREA * R ** 4 / (E * INERTIA), RHO * R ** 2 / E
    for n in (4, 5, 24):
        expected = math.sqrt(n ** 2 * (n ** 2 - 1) ** 2 / (g_c * (n ** 2 - 1) ** 2 + a_c * (n ** 2 + 1)))
        for mode in circle.pair(n):
            assert_allclose(2 * math.pi * mode.frequency_hz, expected, rtol=1e-6)


def test_the_paper_cost_is_a_needle_the_residual_is_not():
    # near the circle limit the zero of g (eq 11) is as narrow as k_s L: a grid over g
    # misses it, while the pole-free residual changes sign across it
    ring = RingResonator(**{**DESIGN, "length_mm": 1e-3})
    sym = ring.pair(24)[0]
    grid = sym.k_c + np.linspace(-0.05, 0.05, 1001) + 3.7e-5
    assert np.min(ring.cost(grid)) > 1e-3
    res = ring.residual(grid, "symmetric", odd=False)
    assert np.all(np.isfinite(res)) and res.min() < 0 < res.max()
    # and at the design g has poles (inf) between modes, the residual stays O(1)
    k = np.linspace(10, 15, 4001)
    a = RING.k_s(RING.omega(k)) * 0.070
    pole = int(np.argmin(np.abs(np.cos(a))))
    assert RING.cost(k[pole - 1:pole + 2]).max() > 1e6
    assert np.abs(RING.residual(k, "symmetric", odd=False)).max() < 2


def test_every_mode_in_a_band_once_with_its_order():
    modes = RING.modes_in_band(30_000, 45_000)
    assert sorted((m.order, m.kind) for m in modes) == sorted(
        (n, kind) for n in range(21, 26) for kind in ("symmetric", "asymmetric"))
    freqs = [m.frequency_hz for m in modes]
    assert freqs == sorted(freqs)
    for m in modes:
        assert abs(RING.total_phase(m.k_c) / math.pi - m.order) < 0.01
        assert m.wavelength_mm == pytest.approx(2e3 * math.pi / m.k_s_per_m)


def test_low_orders_are_found_and_ordered():
    modes = RING.modes_in_band(50, 3000)
    assert sorted({m.order for m in modes}) == [2, 3, 4, 5, 6]
    assert len(modes) == 10


def _split(ring: RingResonator, ratio: float) -> float:
    sym, asym = ring.with_length(ratio * 50).pair(24)
    return asym.frequency_hz - sym.frequency_hz


def test_pair_is_continuous_in_l_over_r_and_crosses_where_predicted():
    ratios = np.linspace(2.5, 3.3, 33)
    freqs = np.array([[m.frequency_hz for m in RING.with_length(r * 50).pair(24)] for r in ratios])
    # smooth: second differences tiny against first differences (no jump to another order)
    d1, d2 = np.diff(freqs, axis=0), np.diff(freqs, n=2, axis=0)
    assert np.all(d1 < 0) and np.abs(d2).max() < 0.05 * np.abs(d1).min()
    split = freqs[:, 1] - freqs[:, 0]
    sign_changes = ratios[:-1][np.signbit(split[:-1]) != np.signbit(split[1:])]
    predicted = [c for c in RING.crossings(24) if 2.5 <= c <= 3.3]
    assert len(sign_changes) == len(predicted) == 2
    # the crossing found by root-finding the solver's split equals the closed form
    from scipy.optimize import brentq
    for c in predicted:
        found = brentq(lambda r: _split(RING, r), c - 0.05, c + 0.05, xtol=1e-13)
        assert_allclose(found, c, rtol=1e-9)
    # seed 004's design L/R = 2.8 lies between two crossings, 7.4 Hz from degenerate
    assert predicted[0] < 2.8 < predicted[1]
    assert abs(split[np.argmin(np.abs(ratios - 2.8))]) < 10


@pytest.mark.parametrize("kwargs, match", [
    ({**DESIGN, "radius_mm": 0}, "radius_mm must be a finite number > 0, got 0"),
    ({**DESIGN, "youngs_gpa": float("nan")}, "youngs_gpa"),
])
def test_bad_ring_raises(kwargs, match):
    with pytest.raises(ModesError, match=match):
        RingResonator(**kwargs)


def test_bad_orders_and_bands_raise():
    with pytest.raises(ModesError, match="integer >= 2.*got 1"):
        RING.pair(1)
    with pytest.raises(ModesError, match="got 40000.0 .. 30000.0"):
        RING.modes_in_band(40_000, 30_000)


def _run(argv: list[str]) -> int:
    parser = argparse.ArgumentParser()
    modes_ring.add_arguments(parser)
    return modes_ring.run(parser.parse_args(argv))


def test_command_json_matches_the_issue_example(capsys):
    argv = ["--length-mm", "140", "--radius-mm", "50", "--thickness-mm", "2.75", "--width-mm",
            "30", "--youngs-gpa", "69", "--density", "2680", "--orders", "24", "--json"]
    assert _run(argv) == 0
    out = json.loads(capsys.readouterr().out)
    assert [(m["order"], m["kind"]) for m in out["modes"]] == [(24, "symmetric"), (24, "asymmetric")]
    assert_allclose([m["frequency_hz"] for m in out["modes"]], [40287, 40294], atol=0.5)
    assert out["pairs"][0]["degenerate_l_over_r"] == [
        c for c in RING.crossings(24) if 1.4 <= c <= 5.6]


def test_command_errors_are_one_line(capsys):
    assert main(["modes", "ring", "--orders", "1"]) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: --orders 1: a mode order is at least 2")
    assert err.count("\n") == 1


@pytest.mark.parametrize("order", [2, 3])
def test_an_order_whose_frequency_is_zero_at_the_geometry_is_refused_naming_it(capsys, order):
    # L 100 m, R 2 um: k_c of orders 2 and 3 lies within rounding of 1, where eq 7 gives 0 Hz;
    # before: "frequency band must satisfy 0 < min < max (Hz), got 0.0 .. 0.0", no --band given
    ring = RingResonator(1e5, 0.002, 0.001, 30, 69, 2680)
    with pytest.raises(ModesError, match=rf"^ring order {order}: its frequency is 0 Hz"):
        ring.pair(order)
    assert main(["modes", "ring", "--length-mm", "1e5", "--radius-mm", "0.002",
                 "--thickness-mm", "0.001", "--orders", str(order), "--phase-shift"]) == 2
    captured = capsys.readouterr()
    error = captured.err.splitlines()[-1]
    assert captured.out == ""
    assert error == (f"frictex: error: --orders {order}: ring order {order}: its frequency is 0 "
                     "Hz to double precision at this geometry (L 100000 mm, R 0.002 mm, h 0.001 "
                     "mm); use a higher order, shorter straights or a larger radius")
