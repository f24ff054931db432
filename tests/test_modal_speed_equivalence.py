"""ModalActuation.command's compiled passes (positions of the fingers touching, their
shapes only, one pass for two modes) against the numpy chain they replaced, written out
here: np.clip, shapes at every sample, the padded systems filled with numpy, ``solve``,
np.minimum, np.angle. Bit for bit: the replay outputs must stay byte-identical."""

from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st
from hypothesis.extra.numpy import arrays

from frictex.device.actuation.modal import magnitude, solve
from frictex.device.actuation.modal_actuation import beam_actuation, plate_actuation
from frictex.device.profile import BeamStructure, PlateStructure
from frictex.device.structures.beam import ModesError
from test_modal_kernels import assert_same_bits, numpy_forward, numpy_touch_rank

SETTINGS = settings(derandomize=True, max_examples=60, deadline=None)

#: limits low enough that about half the samples are scaled or constrained
ACTUATIONS = {
    **{f"beam {m}": beam_actuation(BeamStructure(method=m, channel_limit_um=0.3), 0.7)
       for m in ("exact", "regularised", "bounded")},
    "beam three modes": beam_actuation(BeamStructure(orders=(15, 16, 17), actuators_mm=(60.0, 170.0, 290.0),
                                                     channel_limit_um=0.3), 0.7),
    "plate": plate_actuation(PlateStructure(channel_limit_um=0.4), 1.0),
    "plate exact": plate_actuation(PlateStructure(channel_limit_um=0.4, method="exact"), 1.0),
}


def numpy_command(act, wanted_um, fingers):
    """What ModalActuation.command computed before its compiled passes."""
    contact = fingers.contact
    (x_lo, x_hi), (y_lo, y_hi) = act.bounds
    x, y = fingers.x_pred - act.offset_mm[0], fingers.y_pred - act.offset_mm[1]
    xc, yc = np.clip(x, x_lo, x_hi), np.clip(y, y_lo, y_hi)
    phi_all = np.asarray(act.shapes(xc, yc), dtype=np.float64)      # (F, n, p)
    p = phi_all.shape[-1]
    rank = numpy_touch_rank(contact, fingers.touch_start)
    phi, wanted = np.zeros((contact.shape[1], p, p)), np.zeros((contact.shape[1], p))
    for f in range(contact.shape[0]):
        for row in range(p):
            at = contact[f] & (rank[f] == row)
            np.copyto(phi[:, row, :], phi_all[f], where=at[:, None])
            np.copyto(wanted[:, row], wanted_um[f], where=at)
    sol = solve(phi, wanted, act.method, actuators=act.actuators, limits_um=act.limits_um, rcond=act.rcond)
    z = numpy_forward(np.swapaxes(phi_all, 0, 1), sol.modal_um)    # (n, F)
    achieved = np.where(contact, np.sqrt(z.real * z.real + z.imag * z.imag).T, 0.0)
    return (np.minimum(magnitude(sol.commands_um), act.limits_um), np.angle(sol.commands_um + 0.0),
            achieved, int(np.count_nonzero(sol.limited)),
            int(np.count_nonzero(((xc != x) | (yc != y)) & contact)))


@st.composite
def blocks(draw, width_mm, height_mm):
    """Up to four fingers over up to 40 samples: touching or not, touch-down times with
    ties, positions on and off the structure (its edges, -0.0 next to 0.0), still
    fingers (one position held), wanted amplitudes up to 1 um with zeros."""
    f, n = draw(st.integers(0, 4)), draw(st.integers(0, 40))
    contact = draw(arrays(np.bool_, (f, n), elements=st.booleans()))
    start = draw(arrays(np.float64, (f, n), elements=st.sampled_from([0.0, 0.5, 1.0, 2.0])))

    def positions(size):
        edge = st.sampled_from([0.0, -0.0, size, -1.0, size + 1.0])
        return draw(arrays(np.float64, (f, n), elements=st.one_of(edge, st.floats(-5.0, size + 5.0))))
    x, y = positions(width_mm), positions(height_mm)
    if f and n and draw(st.booleans()):
        x[0], y[0] = x[0, 0], y[0, 0]
    wanted = draw(arrays(np.float64, (f, n), elements=st.one_of(st.just(0.0), st.floats(0.0, 1.0))))
    return wanted, SimpleNamespace(contact=contact, touch_start=start, x_pred=x, y_pred=y)


def assert_command_is_the_numpy_chain(act, block):
    wanted, fingers = block
    got = act.command(wanted, fingers)
    amplitude, phases, achieved, limited, off = numpy_command(act, wanted, fingers)
    assert_same_bits(got.commands_um, amplitude)
    assert_same_bits(got.phases_rad, phases)
    assert_same_bits(got.achieved_um, achieved)
    assert (got.limited, got.off_structure) == (limited, off)


@SETTINGS
@given(block=blocks(350.0, 6.0), name=st.sampled_from([k for k in ACTUATIONS if k.startswith("beam")]))
def test_beam_commands_are_the_numpy_chain_bit_for_bit(block, name):
    assert_command_is_the_numpy_chain(ACTUATIONS[name], block)


@SETTINGS
@given(block=blocks(140.0, 140.0), name=st.sampled_from(["plate", "plate exact"]))
def test_plate_commands_are_the_numpy_chain_bit_for_bit(block, name):
    assert_command_is_the_numpy_chain(ACTUATIONS[name], block)


def test_a_long_block_of_two_fingers_crossing_is_the_numpy_chain():
    """25000 samples (a replay's batch of blocks): finger b sweeps across finger a and
    the singular loci on the way, both lift for a while; about a quarter of the samples
    meet a limit (as in the bundled two-finger replay)."""
    n = 25_000
    t = np.linspace(0.0, 1.0, n)
    contact = np.ones((2, n), bool)
    contact[:, 9000:9500] = False
    contact[1, 20000:] = False
    fingers = SimpleNamespace(contact=contact, touch_start=np.array([[0.0], [0.2]]) * np.ones((2, n)),
                              x_pred=np.stack([100.0 + 20 * t, 260.0 - 160 * t]), y_pred=np.full((2, n), 3.0))
    wanted = np.stack([np.full(n, 0.15), 0.1 + 0.1 * np.sin(40 * t)])
    act = ACTUATIONS["beam regularised"]
    assert_command_is_the_numpy_chain(act, (wanted, fingers))
    assert 0.2 * n < act.command(wanted, fingers).limited < 0.4 * n


@SETTINGS
@given(x=arrays(np.float64, st.integers(0, 30), elements=st.one_of(
    st.sampled_from([0.0, -0.0, 140.0, np.nan, np.inf, -np.inf]), st.floats(-10.0, 150.0))))
def test_structure_position_is_np_clip(x):
    act = ACTUATIONS["plate"]
    y = x[::-1].copy()
    got = act.structure_position(x, y)
    want_x, want_y = np.clip(x, 0.0, 140.0), np.clip(y, 0.0, 140.0)
    for g, w in zip(got, (want_x, want_y, (want_x != x) | (want_y != y))):
        assert_same_bits(g, w)
    assert_same_bits(act.structure_position(x[:, None], 70.0)[1], np.full((x.size, 1), 70.0))


def test_a_non_finite_wanted_amplitude_is_refused_as_solve_refuses_it():
    """The compiled pass hands a system it cannot take back to solve, whose error names it."""
    fingers = SimpleNamespace(contact=np.ones((2, 3), bool), touch_start=np.zeros((2, 3)),
                              x_pred=np.array([[120.0] * 3, [250.0] * 3]), y_pred=np.full((2, 3), 3.0))
    wanted = np.array([[0.1, np.nan, 0.1], [0.1, 0.1, 0.1]])
    with pytest.raises(ModesError, match=r"wanted_um has non-finite values \(first at index \[1, 0\]\)"):
        ACTUATIONS["beam regularised"].command(wanted, fingers)
