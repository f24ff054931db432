"""The compiled kernels of the modal actuation (issue 13) against the numpy formulas they
replaced, written out here: bit for bit, signed zeros included (the replay outputs must
stay byte-identical), on random, near-singular and degenerate inputs."""

import numpy as np
from hypothesis import example, given, settings, strategies as st
from hypothesis.extra.numpy import arrays

from frictex.device.actuation.base import touch_rank
from frictex.device.actuation.modal import _gains_2x2, _gains_svd, _scale_to_limits, forward, magnitude, solve
from frictex.device.actuation.modal import NEAR_SINGULAR, NODE_FLOOR, achieved_magnitude
from frictex.device.actuation.modal_actuation import _serve_rows, _served_fingers
from frictex.device.structures.beam import FreeFreeBeam, _mode

SETTINGS = settings(derandomize=True, max_examples=80, deadline=None)
SEED000 = FreeFreeBeam(350, 6, 6, 57, 2561)


def assert_same_bits(got, want):
    """Bit for bit, but for the sign of a zero: a real actuator row times a complex gain
    is a complex product in the kernel, whose extra +0 term turns an underflowed -0
    (subnormal actuators) into +0 where numpy's real-by-complex product keeps -0."""
    got, want = np.asarray(got), np.asarray(want)
    if got.dtype.kind in "fc":
        got, want = got + got.dtype.type(0), want + want.dtype.type(0)  # -0 + 0 is +0
    assert got.shape == want.shape and got.dtype == want.dtype, (got.shape, got.dtype, want.shape, want.dtype)
    size = want.dtype.itemsize
    bad = np.ascontiguousarray(got).view(np.uint8).reshape(got.shape + (size,)) \
        != np.ascontiguousarray(want).view(np.uint8).reshape(want.shape + (size,))
    assert not bad.any(), f"{np.count_nonzero(bad.any(axis=-1))} values differ, first {np.argwhere(bad.any(axis=-1))[0]}"


# --- beam mode shapes ------------------------------------------------------------------

def numpy_deflection(beam, order, x_mm):
    mode, length, x = _mode(beam, order), beam.length_mm * 1e-3, np.asarray(x_mm, float) * 1e-3
    a, b, c, d = mode.coef
    bx = mode.beta * x
    return (a * np.exp(-mode.alpha * x) + b * np.exp(-mode.alpha * (length - x))
            + c * np.cos(bx) + d * np.sin(bx))


positions = arrays(np.float64, st.integers(1, 300), elements=st.floats(0, 350))


@SETTINGS
@given(x=positions, theory=st.sampled_from(["euler-bernoulli", "timoshenko"]),
       orders=st.lists(st.integers(1, 20), min_size=1, max_size=3))
def test_beam_shapes_are_numpys_bit_for_bit(x, theory, orders):
    beam = FreeFreeBeam(350, 6, 6, 57, 2561, theory=theory)
    want = np.stack([numpy_deflection(beam, o, x) for o in orders], axis=-1)
    assert_same_bits(beam.phi(orders, x), want)


def test_beam_shapes_at_nodes_ends_and_many_positions():
    """The nodes (W = 0 to round-off, where a finger cannot be controlled), the ends, a
    (k, F) array and a scalar; 1e5 random positions cover exp's SIMD path; runs of a held
    position (copied, not recomputed) and -0.0 next to 0.0 (equal, not the same bits)."""
    rng = np.random.default_rng(5)
    x = np.concatenate([SEED000.nodes_mm(16), SEED000.nodes_mm(17), [0.0, 350.0, -0.0, 0.0, -0.0],
                        np.repeat(rng.uniform(0, 350, 1000), rng.integers(1, 5, 1000)),
                        rng.uniform(0, 350, 100_000)])
    for orders in ((16, 17), (17,)):
        want = np.stack([numpy_deflection(SEED000, o, x) for o in orders], axis=-1)
        assert_same_bits(SEED000.phi(orders, x), want)
        even = x.size // 2 * 2
        assert_same_bits(SEED000.phi(orders, x[:even].reshape(-1, 2)), want[:even].reshape(-1, 2, len(orders)))
    assert_same_bits(SEED000.shape(16, 120.0), numpy_deflection(SEED000, 16, 120.0))
    assert np.abs(SEED000.phi((16,), SEED000.nodes_mm(16))).max() < 1e-12


# --- the 2 x 2 gains ---------------------------------------------------------------------

def numpy_gains_2x2(phi, wanted, rcond, regularised):
    # scaled by the power of two nearest the largest entry, unscaled at the end
    exponent = np.frexp(np.abs(phi).max(axis=(1, 2)))[1]
    phi = np.ldexp(phi, -exponent[:, None, None])
    a, b, c, d = phi[:, 0, 0], phi[:, 0, 1], phi[:, 1, 0], phi[:, 1, 1]
    q = np.sqrt(((a + d) / 2) ** 2 + ((c - b) / 2) ** 2)
    r = np.sqrt(((a - d) / 2) ** 2 + ((c + b) / 2) ** 2)
    s1, s2 = q + r, np.abs(q - r)
    threshold = rcond * s1
    full = ((s2 >= threshold) if regularised else (s2 > threshold)) & (s2 > 0)
    ratio = np.divide(s2, s1, out=np.zeros(s1.shape), where=s1 > 0)
    inv_det = np.divide(1.0, a * d - b * c, out=np.zeros(a.shape), where=full)
    g = [[d * inv_det, -b * inv_det], [-c * inv_det, a * inv_det]]
    rest = ~full & (s1 > 0)
    b00, b01, b11 = a * a + b * b, a * c + b * d, c * c + d * d
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        lam1 = s1 * s1
        h2 = 1.0 / (threshold * threshold) if regularised else 0.0
        beta = (1.0 / lam1 - h2) / (4.0 * q * r)
        alpha = 1.0 / lam1 - beta * lam1
        for i, (x0, x1) in enumerate(((a, c), (b, d))):
            g[i][0] = np.where(rest, alpha * x0 + beta * (x0 * b00 + x1 * b01), g[i][0])
            g[i][1] = np.where(rest, alpha * x1 + beta * (x0 * b01 + x1 * b11), g[i][1])
    w0, w1 = wanted[:, 0], wanted[:, 1]
    modal = np.stack((g[0][0] * w0 + g[0][1] * w1, g[1][0] * w0 + g[1][1] * w1), axis=-1)
    modal.real, modal.imag = np.ldexp(modal.real, -exponent[:, None]), np.ldexp(modal.imag, -exponent[:, None])
    return modal, ~full, ratio


#: 0 or 1e-100 <= |x| <= 10: no product underflows. Where one does (below 1e-308, which
#: amplitudes in um never reach), numpy's SIMD complex product, which fuses its roundings,
#: can give the resulting zero the other sign.
finite = st.one_of(st.just(0.0), st.floats(1e-100, 10), st.floats(-10, -1e-100))


@st.composite
def systems(draw):
    """(k, 2, 2) Phi and (k, 2) complex wanted: random rows, nearly parallel rows (a
    relative gap down to 1e-16), a zero row (one finger lifted), zero entries (fingers
    on nodes) and the zero matrix."""
    k = draw(st.integers(1, 40))
    phi = draw(arrays(np.float64, (k, 2, 2), elements=finite))
    gap = draw(arrays(np.float64, (k, 1), elements=st.floats(-1, 1))) * \
        10.0 ** -draw(arrays(np.float64, (k, 1), elements=st.floats(0, 16)))
    kind = draw(arrays(np.int64, k, elements=st.integers(0, 4)))
    phi[kind == 1, 1] = phi[kind == 1, 0] * (1 + gap[kind == 1])
    phi[kind == 2, 1] = 0.0
    phi[kind == 3, :, draw(st.integers(0, 1))] = 0.0
    phi[kind == 4] = 0.0
    wanted = draw(arrays(np.float64, (k, 2), elements=finite)) \
        + 1j * draw(arrays(np.float64, (k, 2), elements=finite))
    return phi, wanted


@SETTINGS
@given(system=systems(), regularised=st.booleans(), rcond=st.sampled_from([1e-12, 0.1, 0.3]))
def test_gains_2x2_are_the_numpy_formula_bit_for_bit(system, regularised, rcond):
    phi, wanted = system
    for got, want in zip(_gains_2x2(phi, wanted, rcond, regularised),
                         numpy_gains_2x2(phi, wanted, rcond, regularised)):
        assert_same_bits(got, want)


# --- forward, magnitude, limits -------------------------------------------------------------

def numpy_forward(phi, modal):
    out = phi[..., 0] * modal[..., None, 0]
    for j in range(1, phi.shape[-1]):
        out = out + phi[..., j] * modal[..., None, j]
    return out


@SETTINGS
@given(system=systems(), real_phi=st.booleans(), shared=st.booleans())
def test_forward_and_magnitude_are_the_numpy_formulas_bit_for_bit(system, real_phi, shared):
    phi, modal = system
    if not real_phi:
        phi = phi + 1j * phi[:, ::-1]
    if shared:  # one matrix for the whole batch, as c = A W_M
        phi = phi[0]
    assert_same_bits(forward(phi, modal), numpy_forward(phi, modal))
    assert_same_bits(forward(phi, modal.real), numpy_forward(phi, modal.real))
    z = numpy_forward(phi, modal)
    assert_same_bits(magnitude(z), np.sqrt(z.real * z.real + z.imag * z.imag))
    # real: np.abs, the same bits as sqrt(x^2) wherever x^2 neither under- nor overflows
    # (the others: test_magnitude_of_real_amplitudes_is_exact_where_squares_underflow_...)
    x = z.real
    normal = (np.abs(x) > 1.5e-154) & (np.abs(x) < 1.3e154)
    assert_same_bits(magnitude(x)[normal], np.sqrt(x * x)[normal])
    swapped = np.swapaxes(np.stack([phi, phi * 2]) if shared else phi[None], 0, 1)  # a strided view
    assert_same_bits(forward(swapped, modal[:swapped.shape[0]]), numpy_forward(swapped, modal[:swapped.shape[0]]))


def test_magnitude_of_real_amplitudes_is_exact_where_squares_underflow_or_overflow():
    x = np.array([1e-160, -3e-200, 5e-324, -0.0, 2e200, -np.inf, 7])
    assert_same_bits(magnitude(x), np.array([1e-160, 3e-200, 5e-324, 0.0, 2e200, np.inf, 7.0]))
    assert_same_bits(magnitude(np.array([-3, 4])), np.array([3.0, 4.0]))


def numpy_scale(commands, modal, limits):
    ratios = np.sqrt(commands.real * commands.real + commands.imag * commands.imag) / limits
    over = ratios[..., 0]
    for j in range(1, ratios.shape[-1]):
        over = np.maximum(over, ratios[..., j])
    scale = 1 / np.maximum(over, 1)
    return commands * scale[..., None], modal * scale[..., None], over > 1


@SETTINGS
@given(system=systems(), limits=arrays(np.float64, 2, elements=st.floats(1e-3, 10)))
def test_scaling_to_the_limits_is_the_numpy_formula_bit_for_bit(system, limits):
    phi, modal = system
    commands = numpy_forward(phi, modal)
    for got, want in zip(_scale_to_limits(commands, modal, limits), numpy_scale(commands, modal, limits)):
        assert_same_bits(got, want)


def test_scaling_keeps_the_nan_rule_of_np_maximum():
    """A NaN ratio (an infinite command over an infinite limit cannot occur in solve, so
    the kernel is driven directly) keeps NaN as np.maximum does, wherever it is."""
    commands = np.array([[np.inf, 1.0], [1.0, np.inf], [0.5, 0.2]], complex)
    limits = np.array([np.inf, np.inf])
    with np.errstate(invalid="ignore"):
        want_all = numpy_scale(commands, commands, limits)
    for got, want in zip(_scale_to_limits(commands, commands, limits), want_all):
        assert_same_bits(got, want)


# --- touch order and the padded systems -----------------------------------------------------

def numpy_touch_rank(contact, touch_start):
    f = contact.shape[0]
    key = np.where(contact, touch_start, np.inf)
    before = key[None, :, :] < key[:, None, :]
    lower_row = np.arange(f)[None, :] < np.arange(f)[:, None]
    before |= (key[None, :, :] == key[:, None, :]) & lower_row[:, :, None]
    rank = np.count_nonzero(before & contact[None, :, :], axis=1)
    return np.where(contact, rank, -1)


@st.composite
def fingers(draw):
    f, n = draw(st.integers(0, 4)), draw(st.integers(0, 30))
    contact = draw(arrays(np.bool_, (f, n)))
    start = draw(arrays(np.float64, (f, n), elements=st.sampled_from([0.0, 0.5, 1.0, 2.0, np.nan])))
    return contact, start


@SETTINGS
@given(fingers())
def test_touch_rank_is_the_numpy_formula(fing):
    contact, start = fing
    assert_same_bits(touch_rank(contact, start), numpy_touch_rank(contact, start))
    assert_same_bits(touch_rank(contact.T.copy().T, start.T.copy().T), numpy_touch_rank(contact, start))


def touching_rows(contact):
    """Row of each finger sample in the (k, p) shapes of the samples touching, -1 elsewhere."""
    return np.where(contact, np.cumsum(contact.ravel()).reshape(contact.shape) - 1, -1)


@SETTINGS
@given(fing=fingers(), p=st.integers(1, 3))
def test_padded_systems_are_the_numpy_fill(fing, p):
    """Finger f fills row rank[f] where served; a lifted finger leaves its row zero."""
    contact, start = fing
    f, n = contact.shape
    rng = np.random.default_rng(f * 100 + n)
    phi_all, wanted_um = rng.normal(size=(f, n, p)), rng.uniform(0, 1, (f, n))
    rank = numpy_touch_rank(contact, start)
    phi, wanted = np.zeros((n, p, p)), np.zeros((n, p))
    served = contact & (rank < p)
    for i in range(f):
        for row in range(p):
            at = served[i] & (rank[i] == row)
            np.copyto(phi[:, row, :], phi_all[i], where=at[:, None])
            np.copyto(wanted[:, row], wanted_um[i], where=at)
    got = _serve_rows(phi_all[contact], touching_rows(contact), _served_fingers(touch_rank(contact, start), p),
                      wanted_um)
    assert_same_bits(got[0], phi)
    assert_same_bits(got[1], wanted)


def test_solve_on_seed000_fingers_crossing_keeps_its_answers():
    """Two fingers on seed 000's beam, one crossing the other (a singular locus) and then
    lifted (a zero row): solve's closed form gives the numpy formula's amplitudes."""
    xb = np.linspace(100.0, 140.0, 4001)
    phi = np.stack([np.broadcast_to(SEED000.phi((16, 17), np.array([120.0])), (xb.size, 2)),
                    SEED000.phi((16, 17), xb)], axis=-2)
    phi[::3, 1] = 0.0
    wanted = np.where(np.arange(xb.size)[:, None] % 3 == 0, [0.4, 0.0], [0.4, 0.1]).astype(complex)
    sol = solve(phi, wanted, "regularised", limits_um=0.75)
    modal, capped, ratio = numpy_gains_2x2(phi, wanted, 0.1, True)
    commands, modal, limited = numpy_scale(modal, modal, np.array([0.75, 0.75]))
    assert_same_bits(sol.modal_um, modal)
    assert_same_bits(sol.commands_um, commands)
    assert_same_bits(sol.limited, limited)
    assert_same_bits(sol.capped, capped)
    assert_same_bits(sol.achieved_um, numpy_forward(phi, modal))


def on_nodes_at_rest(phi, modal, capped):
    """solve's rule: no modal amplitude, counted capped, where every shape is below NODE_FLOOR."""
    rest = np.abs(phi).max(axis=(-2, -1)) < NODE_FLOOR
    return np.where(rest[:, None], 0j, modal), capped | rest


@SETTINGS
@given(system=systems(), method=st.sampled_from(["exact", "regularised"]),
       actuators=arrays(np.float64, (2, 2), elements=st.floats(-2, 2)).filter(lambda a: np.linalg.cond(a) < 1e6),
       limits=st.none() | arrays(np.float64, 2, elements=st.floats(1e-3, 10)))
@example(system=(np.array([[[0.0, 0.0], [0.0, 0.0]], [[-2.0 ** -24, 0.0], [0.0, -1.0]]]),
                 np.zeros((2, 2), complex)),  # exact, smallest / largest 6e-8: capped
         method="exact", actuators=np.array([[0.0, 1.0], [1.0, 1.0]]), limits=None)
@example(system=(np.full((1, 2, 2), -1.0), np.full((1, 2), -3.91885973e-26j)),  # -0 or +0
         method="exact", actuators=np.array([[0.0, -2.2250738585072014e-308],
                                             [-2.2250738585072014e-308, -2.2250738585072014e-308]]),
         limits=None)
def test_solve_is_the_numpy_chain_bit_for_bit(system, method, actuators, limits):
    """solve's compiled end (commands, scaling, achieved, error) against the numpy steps."""
    phi, wanted = system
    regularised = method == "regularised"
    modal, capped, ratio = numpy_gains_2x2(phi, wanted, 0.1 if regularised else 1e-12, regularised)
    capped |= ratio < NEAR_SINGULAR  # solve's rule: near a singular locus whatever the method
    modal, capped = on_nodes_at_rest(phi, modal, capped)
    commands = numpy_forward(actuators, modal)
    limited = np.zeros(len(phi), bool)
    if limits is not None:
        commands, modal, limited = numpy_scale(commands, modal, limits)
    achieved = numpy_forward(phi, modal)
    sol = solve(phi, wanted, method, actuators=actuators, limits_um=limits)
    for got, want in ((sol.modal_um, modal), (sol.commands_um, commands), (sol.achieved_um, achieved),
                      (sol.error_um, np.sqrt((achieved - wanted).real ** 2 + (achieved - wanted).imag ** 2)),
                      (sol.limited, limited), (sol.capped, capped), (sol.sigma_min_ratio, ratio)):
        assert_same_bits(got, want)


@SETTINGS
@given(fing=fingers(), p=st.integers(1, 3), scale=st.sampled_from([0.0, 1e-90, 1.0, 1e90]))
def test_achieved_amplitudes_are_the_numpy_formula(fing, p, scale):
    """|Phi(x_f) W_M| under every finger touching, 0 under a lifted one."""
    contact, _ = fing
    f, n = contact.shape
    rng = np.random.default_rng(f * 10 + n + p)
    phi_all = rng.normal(size=(f, n, p)) * np.where(rng.random((f, n, p)) < 0.2, 0.0, 1.0)
    modal = (rng.normal(size=(n, p)) + 1j * rng.normal(size=(n, p))) * scale
    z = numpy_forward(np.swapaxes(phi_all, 0, 1), modal)
    want = np.where(contact, np.sqrt(z.real * z.real + z.imag * z.imag).T, 0.0)
    assert_same_bits(achieved_magnitude(phi_all[contact], touching_rows(contact), modal), want)


@SETTINGS
@given(phi=arrays(np.float64, (6, 2, 3), elements=finite), wanted=arrays(np.float64, (6, 2), elements=finite),
       actuators=arrays(np.float64, (4, 3), elements=st.floats(-2, 2)).filter(lambda a: np.linalg.matrix_rank(a) == 3),
       limits=st.none() | arrays(np.float64, 4, elements=st.floats(1e-3, 10)))
def test_solve_with_more_modes_than_fingers_is_the_numpy_chain(phi, wanted, actuators, limits):
    """Three modes under two fingers (the SVD path), four channels: the same compiled end."""
    modal, capped, ratio = _gains_svd(phi, wanted.astype(complex), 0.1, True)
    modal, capped = on_nodes_at_rest(phi, modal, capped)
    commands = numpy_forward(actuators, modal)
    limited = np.zeros(len(phi), bool)
    if limits is not None:
        commands, modal, limited = numpy_scale(commands, modal, limits)
    achieved = numpy_forward(phi, modal)
    sol = solve(phi, wanted, "regularised", actuators=actuators, limits_um=limits)
    for got, want in ((sol.modal_um, modal), (sol.commands_um, commands), (sol.achieved_um, achieved),
                      (sol.limited, limited), (sol.capped, capped)):
        assert_same_bits(got, want)
