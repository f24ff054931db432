"""Modal inversion (seed 000, eqs 7-10 and 12-14; seed 001, eqs 4-5)."""

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from numpy.testing import assert_allclose
from scipy.optimize import minimize

from frictex.device.structures.beam import MAX_MODES, FreeFreeBeam, ModesError
from frictex.device.actuation.modal import METHODS, forward, solve

# seed 000, eq 12 (shapes at the actuators) and eq 13 (at x_a = 120, x_b = 250 mm)
PHI_ACT = np.array([[-0.9680, -0.6949], [1.0, -0.7447]])
PHI_FINGERS = np.array([[0.9436, 0.6809], [0.9715, -0.7388]])

BEAM = FreeFreeBeam(350, 6, 6, 57, 2561)
ORDERS = (16, 17)
BEAM_ACT = BEAM.phi(ORDERS, np.array([60.0, 290.0]))  # actuators 60 mm from each end
LIMIT_UM = 1.0


def beam_phi(xa, xb):
    xa, xb = np.broadcast_arrays(np.asarray(xa, float), np.asarray(xb, float))
    return np.stack([BEAM.phi(ORDERS, np.asarray(xa, float)),
                     BEAM.phi(ORDERS, np.asarray(xb, float))], axis=-2)


@pytest.mark.parametrize("method", METHODS)
def test_seed000_worked_example_eq14(method):
    # 0.8 um peak-to-peak under finger a, 0 under b; frictex works zero-to-peak: 0.4 um
    wanted = np.array([0.8 / 2, 0.0])
    sol = solve(PHI_FINGERS, wanted, method, actuators=PHI_ACT, limits_um=LIMIT_UM)
    assert_allclose(sol.commands_um.real, [-0.4093, 0.0045], atol=5e-5)  # eq 14, 4 decimals
    assert_allclose(sol.commands_um.imag, 0, atol=1e-15)
    assert_allclose(sol.achieved_um, wanted, atol=1e-14)
    assert sol.counts() == {"limited": 0, "capped": 0}


amplitude = st.builds(complex, st.floats(-0.5, 0.5), st.floats(-0.5, 0.5))
position = st.floats(0.0, 350.0)


@settings(max_examples=60, derandomize=True, deadline=None)
@given(xa=position, xb=position, wa=amplitude, wb=amplitude)
def test_well_conditioned_pairs_are_met_to_1e9(xa, xb, wa, wb):
    phi = beam_phi(xa, xb)
    s = np.linalg.svd(phi, compute_uv=False)
    assume(s[-1] > 0.2 * s[0])  # well conditioned (and above the regularisation threshold)
    wanted = np.array([wa, wb])
    for method in METHODS:
        sol = solve(phi, wanted, method, actuators=BEAM_ACT, limits_um=1e3)
        assert_allclose(forward(phi, sol.modal_um), wanted, rtol=0, atol=1e-9)
        assert_allclose(sol.commands_um, BEAM_ACT @ sol.modal_um, rtol=1e-13, atol=1e-15)
        assert np.max(sol.error_um) <= 1e-9
        assert not sol.limited


special = st.sampled_from([0.0, 350.0, 120.0, *BEAM.nodes_mm(16)[:3], *BEAM.nodes_mm(17)[-2:]])


@settings(max_examples=80, derandomize=True, deadline=None)
@given(xa=st.one_of(special, position), xb=st.one_of(special, position),
       wa=amplitude, wb=amplitude, coincide=st.booleans())
def test_any_pair_gives_finite_commands_within_limits(xa, xb, wa, wb, coincide):
    phi = beam_phi(xa, xa if coincide else xb)
    for method in METHODS:
        sol = solve(phi, [wa, wb], method, actuators=BEAM_ACT, limits_um=LIMIT_UM)
        for arr in (sol.modal_um, sol.commands_um, sol.achieved_um, sol.error_um):
            assert np.all(np.isfinite(arr))
        assert np.max(np.abs(sol.commands_um)) <= LIMIT_UM * (1 + 1e-12)
        assert_allclose(sol.error_um, np.abs(forward(phi, sol.modal_um) - [wa, wb]), atol=1e-15)


def _sweep(method, xa, xb):
    return solve(beam_phi(xa, xb), [0.4, 0.0], method, actuators=BEAM_ACT, limits_um=LIMIT_UM)


def test_regularised_is_continuous_across_coincident_fingers_exact_is_not():
    # finger b crosses finger a (det Phi = 0 where they coincide); steps of 1 um
    xb = np.linspace(115.0, 125.0, 10001)
    steps = {m: np.max(np.abs(np.diff(_sweep(m, 120.0, xb).commands_um, axis=0)))
             for m in METHODS}
    assert steps["regularised"] < 2e-3  # about 1 um/mm at most: Lipschitz, no jump
    assert steps["exact"] > 0.5 and steps["bounded"] > 0.5  # sign flip at the locus


def test_regularised_is_continuous_across_a_beam_end():
    xb = np.linspace(0.0, 10.0, 5001)
    sol = _sweep("regularised", 0.0, xb)
    assert np.max(np.abs(np.diff(sol.commands_um, axis=0))) < 1e-2


def test_near_singular_bounded_is_closest_achievable():
    # coincident fingers asking 0.4 and 0: the best any method can do is 0.2 under each
    sol = solve(beam_phi(120.0, 120.0), [0.4, 0.0], "bounded", actuators=BEAM_ACT,
                limits_um=LIMIT_UM)
    assert_allclose(sol.error_um, [0.2, 0.2], atol=1e-6)
    assert sol.capped


def test_bounded_matches_independent_constrained_optimiser():
    # real case with active limits: compare with SLSQP on the same problem
    phi = beam_phi(118.0, 121.0)
    wanted = np.array([0.45, -0.1])
    sol = solve(phi, wanted, "bounded", actuators=BEAM_ACT, limits_um=0.3)
    m_cmd = phi @ np.linalg.inv(BEAM_ACT)
    ref = minimize(lambda c: np.sum((m_cmd @ c - wanted) ** 2), np.zeros(2), method="SLSQP",
                   bounds=[(-0.3, 0.3)] * 2, options=dict(ftol=1e-15, maxiter=500))
    assert sol.limited
    assert np.sum(np.abs(forward(phi, sol.modal_um) - wanted) ** 2) <= ref.fun + 1e-10


def test_more_modes_than_fingers_gives_minimum_norm_solution():
    phi = np.stack([BEAM.phi((15, 16, 17), np.array(100.0)),
                    BEAM.phi((15, 16, 17), np.array(230.0))])
    wanted = np.array([0.3 + 0.1j, -0.2])
    sol = solve(phi, wanted, "exact")
    assert_allclose(sol.modal_um, np.linalg.lstsq(phi, wanted, rcond=None)[0], rtol=1e-12)
    assert_allclose(sol.achieved_um, wanted, atol=1e-14)


def test_batch_equals_one_call_per_sample():
    rng = np.random.default_rng(3)
    xa, xb = rng.uniform(0, 350, 50), rng.uniform(0, 350, 50)
    wanted = rng.uniform(-0.5, 0.5, (50, 2)) + 1j * rng.uniform(-0.5, 0.5, (50, 2))
    for method in METHODS:
        batch = solve(beam_phi(xa, xb), wanted, method, actuators=BEAM_ACT, limits_um=LIMIT_UM)
        for i in range(0, 50, 7):
            one = solve(beam_phi(xa[i], xb[i]), wanted[i], method, actuators=BEAM_ACT,
                        limits_um=LIMIT_UM)
            assert_allclose(batch.commands_um[i], one.commands_um, rtol=1e-9, atol=1e-12)


def test_limited_commands_keep_their_ratio():
    sol = solve(PHI_FINGERS, [4.0, 0.0], "exact", actuators=PHI_ACT, limits_um=0.2)
    eq10 = PHI_ACT @ np.linalg.solve(PHI_FINGERS, [4.0, 0.0])
    assert_allclose(sol.commands_um, eq10 * 0.2 / np.max(np.abs(eq10)), rtol=1e-12)
    assert sol.counts()["limited"] == 1


def test_all_zero_shapes_give_zero_not_nan():
    for method in METHODS:
        sol = solve(np.zeros((2, 2)), [0.4, 0.1], method, limits_um=1.0)
        assert_allclose(sol.commands_um, 0)
        assert_allclose(sol.error_um, [0.4, 0.1])


@pytest.mark.parametrize("kwargs, match", [
    (dict(phi_fingers=np.ones((3, 2)), wanted_um=np.ones(3)), r"p >= m >= 1.*got \(3, 2\)"),
    (dict(phi_fingers=np.eye(2), wanted_um=np.ones(3)), r"m = 2 fingers, got \(3,\)"),
    (dict(phi_fingers=[[np.nan, 0], [0, 1]], wanted_um=[1, 1]), r"non-finite.*\[0, 0\]"),
    # past about 1e155 um the solvers' squares overflowed: commands over the limits
    (dict(phi_fingers=np.eye(2), wanted_um=[[1, 1], [1e160, 0]], method="bounded",
          limits_um=0.75), r"wanted_um has 1e\+160 um at index \[1, 0\]: expected at most 1e\+06 um"),
    (dict(phi_fingers=np.eye(2), wanted_um=[0, 2e6j]), r"2e\+06 um at index \[1\]"),
    (dict(phi_fingers=np.eye(2), wanted_um=[1, 1], method="lstsq"), "method must be one of"),
    (dict(phi_fingers=np.eye(2), wanted_um=[1, 1], method="bounded"), "needs limits_um"),
    (dict(phi_fingers=np.eye(2), wanted_um=[1, 1], limits_um=[1, -1]), r"limits_um .*\[1, -1\]"),
    (dict(phi_fingers=np.eye(2), wanted_um=[1, 1], actuators=np.eye(3)), r"got shape \(3, 3\)"),
    (dict(phi_fingers=np.eye(2), wanted_um=[1, 1], rcond=0.0), "rcond must be in"),
])
def test_bad_inputs(kwargs, match):
    with pytest.raises(ModesError, match=match):
        solve(**kwargs)


@pytest.mark.parametrize("method", ["exact", "regularised", "bounded"])
@pytest.mark.parametrize("real_phi", [True, False])
def test_complex_and_integer_actuator_matrices(method, real_phi):
    """A complex actuator matrix (a phased drive) on real or complex Phi_f: c = A W_M to
    round-off, within the limits, and the same answer whatever the dtype of Phi_f; an
    integer matrix is the float64 one (the compiled real-Phi_f end once failed on both)."""
    phi = PHI_FINGERS if real_phi else PHI_FINGERS + 0j
    act = np.array([[1, 1j], [0, 1]])
    sol = solve(phi, [0.4, 0.1], method, actuators=act, limits_um=0.3)
    assert_allclose(sol.commands_um, sol.modal_um @ act.T, atol=1e-15)
    assert np.abs(sol.commands_um).max() <= 0.3 * (1 + 1e-12)
    other = solve(PHI_FINGERS + 0j if real_phi else PHI_FINGERS, [0.4, 0.1], method,
                  actuators=act, limits_um=0.3)
    assert_allclose(sol.commands_um, other.commands_um, atol=1e-15)
    ints = solve(phi, [0.4, 0.1], method, actuators=[[1, 0], [1, 2]], limits_um=2)
    floats = solve(phi, [0.4, 0.1], method, actuators=[[1.0, 0.0], [1.0, 2.0]], limits_um=2)
    assert_allclose(ints.commands_um, floats.commands_um, rtol=0, atol=0)


def test_modes_over_the_bound_are_refused_before_any_p_by_p_matrix():
    """p = 3000 modes: refused with no (p, p) allocation (np.eye(3000) alone is 72 MB)."""
    import tracemalloc
    phi = np.ones((1, 3000))
    tracemalloc.start()
    try:
        with pytest.raises(ModesError, match=f"1 to {MAX_MODES} modes, got 3000"):
            solve(phi, [1.0])
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak < 4 << 20


def test_bad_limits_are_shown_on_one_short_escaped_line():
    """A long limits array is shown as a cut flat list, never numpy's multi-line repr."""
    with pytest.raises(ModesError) as info:
        solve(np.eye(2), [1, 1], limits_um=np.full(200, 0.75))
    message = str(info.value)
    assert "\n" not in message and "got 200 values [0.75, " in message and len(message) < 200
    with pytest.raises(ModesError) as info:
        solve(np.eye(2), [1, 1], method="\x1b]0;title\x07")
    assert "\x1b" not in str(info.value) and "\\x1b" in str(info.value)
