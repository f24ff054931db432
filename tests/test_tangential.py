"""Tangential force of a travelling wave (seed 002, eqs 7-10; seed 004, Fig. 3c) and its
inversion: round trip, reachable set against brute force, hysteresis, block splits."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from frictex.device.friction import forward_mu
from frictex.rendering.layers.tangential import (DrivingForceParams, TangentialState, invert_tangential,
                                  tangential_force)
from frictex.device.profile import FrictionParams

FRICTION = FrictionParams()
PARAMS = DrivingForceParams()
LIMIT = 3.0


def test_eqs_9_10_recover_the_standing_wave_friction_and_seed_004_drive():
    w = np.linspace(0, 3, 31)
    f_plus = tangential_force(w, 1, -1, 1.0, 1.0, FRICTION, PARAMS)   # eq 7: against the wave
    f_minus = tangential_force(w, 1, 1, 1.0, 1.0, FRICTION, PARAMS)   # eq 8: with the wave
    standing = tangential_force(w, 0, 1, 1.0, 1.0, FRICTION, PARAMS)  # W_B = 0
    # eq 10: F_f is the standing wave of the same amplitude (seed 003, eq 2 times mu0 F_n)
    assert_allclose((f_minus + f_plus) / 2, standing, rtol=1e-15)
    assert_allclose(standing, 0.5 * 1.0 * forward_mu(w, 1.0, FRICTION), rtol=1e-15)
    # eq 9: F_p, seed 004 Fig. 3c: nothing below 1 um, then 0.13 N/um at 1 N
    assert_allclose((f_minus - f_plus) / 2, 0.13 * np.maximum(w - 1.0, 0.0), atol=1e-15)
    # a partial travelling wave drives only with its travelling part tau w
    assert_allclose(tangential_force(3.0, 1, 1, 1.0, 0.5, FRICTION, PARAMS)
                    - tangential_force(3.0, 0, 1, 1.0, 0.5, FRICTION, PARAMS), 0.13 * 0.5)


def _brute_range(fn, tau, params=PARAMS):
    w = np.linspace(0, LIMIT, 200_001)
    both = np.concatenate([tangential_force(w, 1, s, fn, tau, FRICTION, params) for s in (-1, 1)])
    return both.min(), both.max()


STRONG = DrivingForceParams(mu0=0.3, slope_per_um=0.3)


@settings(derandomize=True, max_examples=40, deadline=None)
@given(fn=st.floats(0.05, 1.5), tau=st.floats(0.0, 1.0), strong=st.booleans(),
       targets=st.lists(st.floats(-0.6, 0.8), min_size=1, max_size=20),
       speed=st.floats(-80, 80))
def test_round_trip_and_reachable_set_against_brute_force(fn, tau, strong, targets, speed):
    params = STRONG if strong else PARAMS
    target = np.array(targets)
    cmd, _ = invert_tangential(target, np.full(target.size, speed), fn, tau, LIMIT, FRICTION,
                               params)
    lo, hi = _brute_range(fn, tau, params)
    inside = (target > lo + 1e-7) & (target < hi - 1e-7)
    outside = (target < lo - 1e-7) | (target > hi + 1e-7)
    assert not cmd.unreachable[inside].any()
    assert cmd.unreachable[outside].all()
    # forward model of the commands, recomputed here, gives the target where reachable
    forward = tangential_force(cmd.amplitude_um, cmd.direction, cmd.motion, fn, tau, FRICTION, params)
    assert_allclose(forward, cmd.achieved_n, rtol=0, atol=1e-15)
    assert_allclose(forward[~cmd.unreachable], target[~cmd.unreachable], rtol=0, atol=1e-9)
    # where not, the clamp gives the nearest reachable end
    nearest = np.where(target < lo, lo, hi)
    assert_allclose(forward[cmd.unreachable], nearest[cmd.unreachable], atol=1e-6)
    assert np.all((cmd.amplitude_um >= 0) & (cmd.amplitude_um <= LIMIT))


def test_zero_and_negative_net_force_and_more_than_rest():
    target = np.array([0.0, -0.05, 0.3 * 0.5, 0.30])  # F0 = mu0 F_n = 0.15 N
    cmd, _ = invert_tangential(target, np.full(4, 25.8), 0.5, 1.0, LIMIT, FRICTION, STRONG)
    assert not cmd.unreachable.any()
    assert_allclose(cmd.achieved_n, target, atol=1e-12)
    # zero and negative: the wave travels against the finger (d = -m); above rest: with it
    assert_array_equal(cmd.direction[[0, 1, 3]], [-1, -1, 1])
    assert cmd.amplitude_um[2] == pytest.approx(0.0, abs=1e-12)


def test_unreachable_and_nonfinite_are_marked_not_silent():
    target = np.array([-5.0, 5.0, np.nan, 0.1])
    cmd, _ = invert_tangential(target, np.full(4, 10.0), 0.5, 1.0, LIMIT, FRICTION, PARAMS)
    assert_array_equal(cmd.unreachable, [True, True, False, False])
    assert_array_equal(cmd.nonfinite, [False, False, True, False])
    assert cmd.amplitude_um[2] == 0.0 and cmd.amplitude_um[0] == LIMIT
    assert np.all(np.isfinite(cmd.achieved_n))


def test_no_force_and_no_travelling_wave_stay_finite():
    cmd, _ = invert_tangential(np.array([0.0, 0.1, 0.2]), np.array([5.0, 5.0, 5.0]),
                               np.array([0.0, 0.0, 0.5]), 0.0, LIMIT, FRICTION, PARAMS)
    assert np.all(np.isfinite(cmd.amplitude_um)) and np.all(np.isfinite(cmd.achieved_n))
    assert_array_equal(cmd.unreachable, [False, True, False])


def test_without_normal_force_the_plate_rests_and_says_the_goal_unreachable():
    """With F_n = 0 every force is 0 whatever the amplitude: a negative goal commanded the
    amplitude limit for 0 N achieved."""
    cmd, _ = invert_tangential(np.array([-0.1, 0.0, 0.1]), np.full(3, 20.0), 0.0, 1.0,
                               LIMIT, FRICTION, PARAMS)
    assert_array_equal(cmd.amplitude_um, [0.0, 0.0, 0.0])
    assert_array_equal(cmd.unreachable, [True, False, True])
    assert_array_equal(cmd.achieved_n, [0.0, 0.0, 0.0])


def test_direction_has_hysteresis_at_rest_and_flips_once_at_a_reversal():
    n = 400
    jitter = np.where(np.arange(n) % 2, 1.5, -1.5)           # a finger at rest, noisy velocity
    v = np.concatenate([np.full(n, 30.0), jitter, np.full(n, -30.0)])
    target = np.full(v.size, 0.05)                            # needs drive: w above threshold
    cmd, state = invert_tangential(target, v, 0.5, 1.0, LIMIT, FRICTION, PARAMS)
    assert np.count_nonzero(np.diff(cmd.motion)) == 1
    assert np.count_nonzero(np.diff(cmd.direction)) == 1
    assert_array_equal(cmd.motion[n:2 * n], 1)                # held through the jitter
    assert state == TangentialState(motion=-1, direction=1)
    # a target hovering just below the force at rest (0.25 N) needs no drive: d holds
    hover = 0.2499 + 5e-5 * np.where(np.arange(n) % 2, 1.0, -1.0)
    cmd, _ = invert_tangential(hover, np.full(n, 30.0), 0.5, 1.0, LIMIT, FRICTION, PARAMS,
                               TangentialState(1, -1))
    assert_array_equal(cmd.direction, -1)


@settings(derandomize=True, max_examples=25, deadline=None)
@given(cuts=st.lists(st.integers(0, 300), max_size=5))
def test_blocks_with_carried_state_equal_one_call(cuts):
    t = np.linspace(0, 1, 300)
    v = 40 * np.sin(2 * np.pi * 3 * t) + 3 * np.sin(2 * np.pi * 70 * t)
    target = 0.2 * np.cos(2 * np.pi * 2 * t)
    fn = 0.5 + 0.3 * t
    whole, _ = invert_tangential(target, v, fn, 0.8, LIMIT, FRICTION, PARAMS)
    state, parts = TangentialState(), []
    edges = [0, *sorted(cuts), 300]
    for a, b in zip(edges, edges[1:]):
        part, state = invert_tangential(target[a:b], v[a:b], fn[a:b], 0.8, LIMIT, FRICTION,
                                        PARAMS, state)
        parts.append(part)
    for name in ("amplitude_um", "direction", "motion", "achieved_n", "unreachable"):
        assert_array_equal(np.concatenate([getattr(p, name) for p in parts]), getattr(whole, name))


def test_a_still_push_without_normal_force_or_wave_rests():
    """A still finger asked to be pushed: with F_n = 0 or no travelling wave (tau = 0) no
    amplitude pushes, so the plate rests (it drove the limit) and the push is counted
    unreachable; with both, the drive the push needs."""
    from frictex.rendering.pipeline import build_pipeline
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene

    stage = build_pipeline(load_scene(resolve_scene("directional-beam"))).forces
    fn, tau = np.array([0.0, 0.5, 0.5]), np.array([1.0, 0.0, 1.0])
    w, _, unreachable, _, _, _ = stage._invert(np.zeros(3), np.full(3, 0.05), np.zeros(3, bool),
                                           np.zeros(3), fn, tau, np.full(3, 2.5), None)
    assert_array_equal(w[:2], [0.0, 0.0])
    assert 0.0 < w[2] < stage.device.amplitude_limit_um
    assert_array_equal(unreachable, [True, True, False])


@pytest.mark.parametrize("limit, light", [(3.0, 0.457), (3.0 / 1.16405249, 0.356)])
def test_zero_net_force_is_reachable_only_at_the_light_presses_the_docstring_states(limit, light):
    # the module docstring: with the default constants, F_t <= 0 needs F_n <= 0.457 N at
    # 3 um (0.356 N at the beam's 2.58 um); at 0.5 N the floor is +0.012 N at 3 um
    for fn, reachable in ((light - 0.001, True), (light + 0.001, False), (0.5, False)):
        cmd, _ = invert_tangential(np.zeros(1), np.full(1, 25.0), fn, 1.0, limit, FRICTION, PARAMS)
        assert cmd.unreachable[0] != reachable
    floor = tangential_force(3.0, 1, -1, 0.5, 1.0, FRICTION, PARAMS)
    assert floor == pytest.approx(0.012, abs=5e-4)
    assert tangential_force(1.6, 1, -1, 0.5, 1.0, FRICTION, PARAMS) == pytest.approx(0.11, abs=5e-3)
