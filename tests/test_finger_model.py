"""The simulated finger (device/finger.py) against independent computations."""

import math

import numpy as np
from hypothesis import given, settings, strategies as st

from frictex.device.finger import (RANGES, FingerParams, FingerPlant, SensorParams, draw_finger,
                           moisture, rest_mu, true_amplitude, true_mu)


def test_true_mu_is_seed_003_eq_2_without_drift_or_speed():
    finger = FingerParams(b_per_um=1.67, k_per_n=1.13)
    w = np.array([0.0, 0.5, 1.0, 2.5])
    a = 1.13 * 0.5
    expected = [(1 - a) * math.exp(-1.67 * x) + a for x in w]
    np.testing.assert_allclose(true_mu(w, 0.5, 0.0, 0.0, finger), expected, rtol=1e-12)


def test_speed_weakens_the_reduction_and_moisture_raises_friction():
    finger = FingerParams(v_c_mm_s=200.0, mu0_drift=0.4, k_drift=0.2, tau_s=60.0)
    slow, fast = true_mu(1.0, 0.5, 10.0, 0.0, finger), true_mu(1.0, 0.5, 200.0, 0.0, finger)
    assert fast > slow
    # at v = v_c, b is halved
    a = finger.k_per_n * 0.5
    assert math.isclose(fast, (1 - a) * math.exp(-finger.b_per_um / 2) + a, rel_tol=1e-12)
    assert math.isclose(rest_mu(60.0, finger), finger.mu0 * (1 + 0.4 * (1 - math.exp(-1))),
                        rel_tol=1e-12)
    assert moisture(600.0, finger) > moisture(60.0, finger) > moisture(0.0, finger) == 0.0


def test_population_draws_stay_in_their_ranges_and_differ():
    fingers = [draw_finger(k) for k in range(1, 21)]
    for f in fingers:
        for name, (lo, hi, _) in RANGES.items():
            assert lo <= getattr(f, name) <= hi
    assert len({f.mu0 for f in fingers}) == 20
    assert draw_finger(5) == draw_finger(5)


def test_plate_loop_is_first_order_at_400_hz():
    rate = 10_000.0
    plant = FingerPlant(FingerParams(), rate, 2.5, SensorParams(lateral_noise_n=0.0,
                                                                 normal_noise_n=0.0))
    out, _ = plant.step(0, np.full(40, 1.0), np.full(40, 50.0), np.full(40, 0.5),
                        plant.initial_state())
    p = math.exp(-2 * math.pi * 400.0 / rate)
    np.testing.assert_allclose(out.amplitude_um, 1.0 - p ** np.arange(1, 41), rtol=1e-12)


def test_commands_beyond_the_limit_are_cut():
    plant = FingerPlant(FingerParams(), 10_000.0, 2.5)
    out, _ = plant.step(0, np.full(2000, 9.0), np.full(2000, 50.0), np.full(2000, 0.5),
                        plant.initial_state())
    assert out.amplitude_um.max() <= 2.5


def test_a_finger_at_rest_reads_no_friction():
    plant = FingerPlant(FingerParams(), 10_000.0, 2.5, SensorParams(lateral_noise_n=0.0))
    out, _ = plant.step(0, np.zeros(500), np.zeros(500), np.full(500, 0.5), plant.initial_state())
    assert np.all(out.lateral_n == 0.0)


@settings(max_examples=25, derandomize=True, deadline=None)
@given(st.lists(st.integers(1, 299), max_size=4, unique=True))
def test_split_blocks_equal_one_block(cuts):
    """Noise-free: any split of a run into blocks, state carried, equals one block."""
    rng = np.random.default_rng(3)
    n = 300
    cmd, speed, force = rng.uniform(0, 3, n), rng.uniform(0, 100, n), rng.uniform(0.2, 0.8, n)
    plant = FingerPlant(draw_finger(2), 10_000.0, 2.5,
                        SensorParams(lateral_noise_n=0.0, normal_noise_n=0.0))
    whole, _ = plant.step(0, cmd, speed, force, plant.initial_state())
    state, parts = plant.initial_state(), []
    edges = [0, *sorted(cuts), n]
    for a, b in zip(edges[:-1], edges[1:]):
        out, state = plant.step(a, cmd[a:b], speed[a:b], force[a:b], state)
        parts.append(out)
    for name in ("amplitude_um", "delivered_mu", "lateral_n", "normal_n"):
        np.testing.assert_allclose(np.concatenate([getattr(p, name) for p in parts]),
                                   getattr(whole, name), rtol=1e-10, atol=1e-15)


def test_true_amplitude_inverts_true_mu():
    finger = draw_finger(6)
    w = np.array([0.0, 0.3, 1.1, 2.0])
    mu = true_mu(w, 0.5, 40.0, 3.0, finger)
    np.testing.assert_allclose(true_amplitude(mu, 0.5, 40.0, 3.0, finger, 2.5), w, atol=1e-9)
    # below this finger's floor: the limit
    assert true_amplitude(0.0, 0.5, 40.0, 3.0, finger, 2.5) == 2.5
