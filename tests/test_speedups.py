"""The fast paths of the haptic pipeline (issue 4) against the computations they replace.

Each fast path must give what the straightforward computation gives: bit for bit where
the operations are the same ones reordered, to a stated tolerance where the arithmetic
differs (closed-form 2 x 2 solves against LAPACK's SVD, sqrt(a^2 + b^2) against hypot).
"""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from numpy.testing import assert_allclose, assert_array_equal

from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.device.actuation.base import SingleModeActuation, primary_finger
from frictex.device.actuation.modal import _gains_2x2, _gains_svd, forward, solve
from frictex.rendering.compose import compose
from frictex.device.friction import make_friction_model
from frictex.rendering.layers.sht import integrate_phase
from frictex.rendering.tracking.tracks import BLOCK_FIELDS, FingerBlock, TrackerConfig, TrackerState, track
from frictex.device.profile import DeviceProfile
from frictex.textures.model import DiscRegion, Grating, RectRegion, Shape, VisualHints, Waveform, _smoothstep_inside, _wrap

SETTINGS = settings(derandomize=True, max_examples=60, deadline=None)


# --- device.actuation.modal: closed-form 2 x 2 against the batched SVD ------------------------------

def _both(phi, wanted, method, rcond=0.1):
    regularised = method == "regularised"
    threshold = rcond if regularised else 1e-12
    return (_gains_2x2(phi, wanted, threshold, regularised),
            _gains_svd(phi, wanted, threshold, regularised))


@pytest.mark.parametrize("method", ["exact", "regularised"])
def test_closed_form_equals_svd_on_random_well_conditioned_matrices(method):
    rng = np.random.default_rng(0)
    phi = rng.uniform(-1, 1, (20_000, 2, 2))
    wanted = rng.uniform(-1, 1, (20_000, 2)) + 1j * rng.uniform(-1, 1, (20_000, 2))
    (m2, c2, r2), (ms, cs, rs) = _both(phi, wanted, method)
    s = np.linalg.svd(phi, compute_uv=False)
    ok = s[:, 1] > 1e-3 * s[:, 0]  # condition number under 1e3: both accurate to 1e-12
    assert ok.mean() > 0.99
    scale = np.abs(ms[ok]).max(axis=-1, keepdims=True)
    assert_allclose(m2[ok] / scale, ms[ok] / scale, rtol=0, atol=1e-12)
    assert_array_equal(c2, cs)
    assert_allclose(r2, rs, rtol=0, atol=1e-14)


def test_regularised_closed_form_equals_svd_through_the_singular_locus():
    """Seed 000's beam with finger b swept through finger a's position (det = 0 there):
    the regularised gains are continuous, so the two computations agree everywhere."""
    from frictex.device.structures.beam import FreeFreeBeam
    beam = FreeFreeBeam(350, 6, 6, 57, 2561)
    xb = np.linspace(100.0, 140.0, 40_001)  # passes x_a = 120 mm exactly
    phi = np.stack([np.broadcast_to(beam.phi((16, 17), np.array([120.0])), (xb.size, 2)),
                    beam.phi((16, 17), xb)], axis=-2)
    wanted = np.broadcast_to(np.array([0.4, 0.1], complex), (xb.size, 2))
    (m2, c2, r2), (ms, cs, rs) = _both(phi, wanted, "regularised")
    assert_allclose(m2, ms, rtol=0, atol=1e-12 * np.abs(ms).max())
    assert_array_equal(c2, cs)
    assert c2.any() and not c2.all()  # the sweep crosses the regularised zone
    assert r2.min() < 1e-9  # and the singular locus itself


@pytest.mark.parametrize("method", ["exact", "regularised"])
def test_one_finger_padding_and_no_finger(method):
    """A zero row (one finger) gives the minimum-norm solution of the 1 x 2 system; an
    all-zero matrix (no finger) gives 0, as with the SVD. Regularised, the closed form
    cancels up to a factor 1/rcond^2 = 100 (see ``_gains_2x2``): 1e-13 relative."""
    row = np.array([0.7, -0.3])
    phi = np.array([[row, [0.0, 0.0]], [[0.0, 0.0], [0.0, 0.0]]])
    wanted = np.array([[0.5, 0.0], [0.2, 0.3]], dtype=complex)
    (m2, c2, r2), (ms, cs, rs) = _both(phi, wanted, method)
    assert_allclose(m2[0], row * 0.5 / (row @ row), rtol=1e-13)  # pinv of one row
    assert_allclose(m2, ms, rtol=0, atol=1e-13)
    assert_array_equal(m2[1], 0.0)
    assert_array_equal(c2, [True, True]) and assert_array_equal(cs, c2)
    assert_array_equal(r2, [0.0, 0.0])


def test_exact_near_singular_is_finite_and_solves_the_system():
    """Condition numbers up to ~1e11: both computations lose digits (to eps x cond); the
    closed form is finite, caps the same samples, stays within 10 eps x cond of LAPACK and
    is backward stable (Phi W_M reproduces the wanted amplitudes to 1e-14 ||Phi|| ||W_M||)."""
    rng = np.random.default_rng(1)
    base = rng.uniform(-1, 1, (200, 2))
    eps = np.logspace(-6, -10, 200)
    phi = np.stack([base, base + eps[:, None] * rng.uniform(-1, 1, (200, 2))], axis=-2)
    wanted = rng.uniform(-1, 1, (200, 2)).astype(complex)
    (m2, c2, _), (ms, cs, _) = _both(phi, wanted, "exact")
    assert np.isfinite(m2).all()
    assert_array_equal(c2, cs)
    s = np.linalg.svd(phi, compute_uv=False)
    size = np.abs(ms).max(axis=-1)
    assert (np.abs(m2 - ms).max(axis=-1) <= 10 * np.finfo(float).eps * s[:, 0] / s[:, 1] * size).all()
    backward = np.abs(forward(phi, m2) - wanted).max(axis=-1) / (s[:, 0] * np.abs(m2).max(axis=-1))
    assert backward.max() < 1e-14


def test_solve_dispatch_keeps_the_svd_for_bounded_and_complex_shapes():
    """`solve` uses the closed form for real 2 x 2 exact/regularised only; a complex Phi
    (any shape) gives the same as its real part when the imaginary part is 0."""
    rng = np.random.default_rng(2)
    phi = rng.uniform(-1, 1, (50, 2, 2))
    wanted = rng.uniform(-0.3, 0.3, (50, 2))
    real = solve(phi, wanted, "regularised")
    cplx = solve(phi.astype(complex), wanted, "regularised")  # goes through LAPACK
    assert_allclose(real.modal_um, cplx.modal_um, rtol=0, atol=1e-12)


def test_forward_equals_einsum():
    rng = np.random.default_rng(4)
    phi = rng.uniform(-1, 1, (3, 7, 2, 5))
    modal = rng.uniform(-1, 1, (7, 5)) + 1j * rng.uniform(-1, 1, (7, 5))
    assert_allclose(forward(phi, modal), np.einsum("...ij,...j->...i", phi, modal),
                    rtol=1e-14, atol=1e-15)


# --- textures.model: shared distances, wrapped phase, raised-cosine ramp ---------------

@SETTINGS
@given(st.lists(st.floats(-1e15, 1e15, allow_nan=False), min_size=1, max_size=50))
def test_wrap_is_np_mod_bit_for_bit(values):
    p = np.array(values + [-1e-300, -0.0, -1.0, 0.9999999999999999, -1e-17])
    assert_array_equal(np.signbit(_wrap(p)), np.signbit(np.mod(p, 1.0)))
    assert_array_equal(_wrap(p), np.mod(p, 1.0))


def test_smoothstep_only_evaluates_the_cosine_on_the_ramp_and_equals_the_formula():
    d = np.concatenate((np.linspace(-3, 3, 10_001), [-0.5, 0.5, 0.0]))
    s = np.clip(0.5 - d / 1.0, 0.0, 1.0)
    assert_array_equal(_smoothstep_inside(d, 1.0), 0.5 - 0.5 * np.cos(np.pi * s))


def _layers():
    hints = VisualHints()
    rect = RectRegion(10.0, 20.0, 30.0, 15.0)
    tilted = RectRegion(10.0, 20.0, 30.0, 15.0, angle_deg=25.0)
    disc = DiscRegion(30.0, 30.0, 12.0)
    return [Shape("r", "sho", None, "multiply", hints, geometry=rect, mu=0.7, edge_mm=2.0),
            Shape("t", "sho", disc, "multiply", hints, geometry=tilted, mu=0.7, edge_mm=1.0),
            Shape("d", "sho", None, "replace", hints, geometry=disc, mu=0.5),
            Grating("g", "sho", disc, "multiply", hints, period_mm=5.0, angle_deg=30.0),
            Waveform("w", "sht", rect, "multiply", hints, period_mm=0.8)]


def test_mu_and_covers_equals_mu_at_and_covers():
    """Where the layer covers (all that is composed) mu' is mu_at's; outside, mu_at's or
    1 (not computed)."""
    rng = np.random.default_rng(5)
    x, y = rng.uniform(0, 60, (2, 3, 4000))
    for layer in _layers():
        mu, covers = layer.mu_and_covers(x, y)
        assert_array_equal(covers, layer.covers(x, y))
        assert 0 < covers.sum() < covers.size
        assert_array_equal(mu[covers], layer.mu_at(x, y)[covers])
        assert np.all((mu == layer.mu_at(x, y)) | (mu == 1.0))


def test_distances_against_hypot_and_the_rotation_formula():
    """sqrt(a^2 + b^2) is within 2 ulp of np.hypot; angle 0 skips a rotation by exactly
    (c, s) = (1, 0)."""
    rng = np.random.default_rng(6)
    x, y = rng.uniform(-50, 150, (2, 20_000))
    exact = np.hypot(x - 30.0, y - 30.0)
    centre = DiscRegion(30.0, 30.0, 0.0).signed_distance(x, y)  # the distance to the centre
    assert np.all(np.abs(centre - exact) <= 2 * np.spacing(exact))
    on_axis = DiscRegion(30.0, 30.0, 0.0).signed_distance(x, np.full(x.size, 30.0))
    assert_array_equal(on_axis, np.abs(x - 30.0))
    rect = RectRegion(10.0, 20.0, 30.0, 15.0)
    u, v = 1.0 * (x - 25.0) + 0.0 * (y - 27.5), -0.0 * (x - 25.0) + 1.0 * (y - 27.5)
    qx, qy = np.abs(u) - 15.0, np.abs(v) - 7.5
    expected = (np.hypot(np.maximum(qx, 0), np.maximum(qy, 0))
                + np.minimum(np.maximum(qx, qy), 0.0))
    assert_allclose(rect.signed_distance(x, y), expected, rtol=4.5e-16, atol=1e-15)


# --- rendering: phase integration, composition, inversion, tracks ---------------------------

def _phase_loop(rate, dt, touch, start):
    """Sample by sample: the definition integrate_phase vectorises."""
    prev_id, phase = start if start is not None else (None, 0.0)
    out = np.empty(rate.size)
    for k in range(rate.size):
        if touch[k] != prev_id:
            phase, prev_id = 0.0, touch[k]
        out[k] = phase
        phase += rate[k] * dt
    return out, phase % 1.0


@SETTINGS
@given(st.lists(st.tuples(st.integers(1, 40), st.integers(0, 2), st.floats(-300, 300)),
                min_size=1, max_size=8),
       st.one_of(st.none(), st.tuples(st.integers(0, 2), st.floats(0, 0.999))))
def test_integrate_phase_equals_a_sample_by_sample_loop(runs, start):
    rate = np.concatenate([np.full(n, r) for n, _, r in runs])
    touch = np.concatenate([np.full(n, t) for n, t, _ in runs])
    phase, carry = integrate_phase(rate, 1e-4, touch, start)
    expected, expected_carry = _phase_loop(rate, 1e-4, touch, start)
    assert np.all((phase >= 0.0) & (phase < 1.0))
    assert_allclose((phase - expected + 0.5) % 1.0 - 0.5, 0.0, rtol=0, atol=1e-12)
    assert abs((carry - expected_carry + 0.5) % 1.0 - 0.5) < 1e-12


@pytest.mark.parametrize("touching", [0.8, 1.0])
def test_compose_in_place_equals_the_where_formula(touching):
    """Layers covering some samples, all of them (a plain product) or none (skipped)."""
    rng = np.random.default_rng(7)
    shape = (3, 500)
    covering = [1.0, 0.6, 0.6, 1.0, 0.6, 0.6, 0.0, 0.0, 0.02]
    outputs = [(rng.uniform(0.3, 1.0, shape), rng.random(shape) < f) for f in covering]
    blends = ["replace", "multiply", "replace", "multiply", "multiply", "replace", "multiply",
              "replace", "multiply"]
    masks = [None, None, rng.random(shape) < 0.5, None, None, rng.random(shape) < 0.5, None,
             None, None]
    contact = rng.random(shape) < touching
    mu = np.ones(shape)
    for (m, c), blend, mask in zip(outputs, blends, masks):
        c = c if mask is None else c & mask
        mu = np.where(c, m, mu) if blend == "replace" else np.where(c, mu * m, mu)
    composed = compose(outputs, blends, contact, masks)
    assert composed.tobytes() == np.where(contact, mu, 1.0).tobytes()


@pytest.mark.parametrize("force", [0.5, 0.87, 1.2])
def test_inversion_with_one_force_equals_per_sample_forces(force):
    """A block with one good force and finite targets takes the scalar path; the same
    block plus a sample at another force (mu' = 1: no clamp) takes the per-sample path."""
    model = make_friction_model(DeviceProfile())
    mu = np.linspace(0.0, 1.2, 2001)
    w1, c1 = model.invert(mu, force)
    w2, c2 = model.invert(np.append(mu, 1.0), np.append(np.full(mu.size, force), 0.3))
    assert_array_equal(w1, w2[:-1])
    assert w2[-1] == 0.0
    assert c1.as_dict() == c2.as_dict()
    assert c1.above_one > 0
    if 1.13 * force >= 1.0 - 1e-9:  # seed 003's model does not hold (A >= 1)
        assert c1.force_beyond_model == np.count_nonzero(mu < 1.0) and c1.unreachable == 0
    else:  # within it (0.87 N: A = 0.983), targets below the floor are out of reach
        assert c1.force_beyond_model == 0 and c1.unreachable > 0


def test_single_finger_actuation_equals_the_primary_finger_rule():
    rng = np.random.default_rng(8)
    contact = rng.random((1, 300)) < 0.7
    wanted = rng.uniform(0, 2, (1, 300))
    block = FingerBlock(0, np.arange(300) / 1e4, (0,), contact=contact,
                        touch_id=np.ones((1, 300), np.int64), x_held=wanted, y_held=wanted,
                        x_pred=wanted, y_pred=wanted, vx=wanted, vy=wanted, force=wanted,
                        touch_start=np.zeros((1, 300)))
    act = SingleModeActuation().command(wanted, block)
    primary = primary_finger(contact, np.zeros((1, 300)))
    assert_array_equal(act.commands_um[:, 0], np.where(primary == 0, wanted[0], 0.0))


def test_finger_block_holds_every_array_once_and_is_read_only():
    trace = sample(make_motion("human", speed_mm_s=60.0, duration_s=0.5, seed=3), 120.0,
                   noise_mm=0.05, seed=1)
    block, _ = track(0, 5000, trace, TrackerState(), TrackerConfig())
    assert block.x_pred is block.x_pred
    eager = FingerBlock(block.index0, block.t_s, block.ids,
                        **{name: getattr(block, name) for name in BLOCK_FIELDS})
    for name in BLOCK_FIELDS:
        assert getattr(eager, name) is getattr(block, name)
        assert getattr(block, name).shape == (1, 5000)
    with pytest.raises(AttributeError, match="read-only"):
        block.x_pred = None
    with pytest.raises(AttributeError, match="no attribute 'speed'"):
        block.speed
    with pytest.raises(TypeError, match="x_pred"):
        FingerBlock(0, block.t_s, block.ids, contact=block.contact)


@SETTINGS
@given(st.integers(1, 400), st.integers(1, 300), st.integers(0, 2**32 - 1))
def test_tracker_window_sums_are_numpys_row_sums(width, used, seed):
    """The tracker's compiled line fits add each window in the order numpy's ``sum``
    adds a padded table row (pairwise), so velocities keep every bit of the table
    summation: values of mixed sign and size, rows padded with zeros."""
    from frictex.rendering.tracking.tracks import _pairwise
    rng = np.random.default_rng(seed)
    row = np.zeros(width)
    k = min(used, width)
    row[:k] = rng.standard_normal(k) * 10.0 ** rng.integers(-6, 6, k)
    table = np.stack([row, row[::-1]])
    assert [_pairwise(r, 0, width) for r in table] == table.sum(axis=1).tolist()


def test_a_periodic_profile_where_covered_is_the_profile_there_and_1_elsewhere():
    rng = np.random.default_rng(7)
    phase = rng.uniform(-50, 50, (2, 3000))
    for layer in [lay for lay in _layers() if lay.is_periodic]:
        for covers in (rng.uniform(size=phase.shape) < 0.3, np.ones(phase.shape, bool),
                       np.zeros(phase.shape, bool)):
            mu = layer.profile_where(phase, covers)
            assert_array_equal(mu, np.where(covers, layer.profile(phase), 1.0))
