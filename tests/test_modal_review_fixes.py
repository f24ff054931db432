"""Singular loci, near-singular conditioning and the modal solver's edge cases."""

import re
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.app.engine.summary import Totals, warnings_of
from frictex.device.actuation.modal import NEAR_SINGULAR, solve
from frictex.device.actuation.modal_actuation import beam_actuation, plate_actuation
from frictex.device.profile import BeamStructure, PlateStructure
from frictex.device.structures.beam import FreeFreeBeam, ModesError

#: seed 000's beam, modes 16 and 17 (the worked example)
BEAM = FreeFreeBeam(350, 6, 6, 57, 2561)
MODES = (16, 17)


def _capped_warning() -> str:
    totals = Totals()
    totals.modal_capped = 3
    pipeline = SimpleNamespace(forces=None, scene=SimpleNamespace(layers=()))
    tracker = SimpleNamespace(jumps=0, out_of_order=0)
    return next(w for w in warnings_of(pipeline, tracker, totals) if w.startswith("3 samples:"))


def test_singular_loci_are_half_a_wavelength_apart_as_the_warning_says():
    # det Phi_f (seed 001, eq 8) with finger 1 at 120 mm, finger 2 swept past it
    x2 = np.linspace(125.0, 190.0, 65001)
    first, second = BEAM.phi(MODES, np.array([120.0])), BEAM.phi(MODES, x2)
    det = first[0, 0] * second[:, 1] - second[:, 0] * first[0, 1]
    zeros = x2[np.flatnonzero(np.signbit(det[:-1]) != np.signbit(det[1:]))]
    gaps = np.diff(np.concatenate([[120.0], zeros]))
    # independently: the mean flexural wavelength 2 pi / beta of the two modes
    wavelength = np.mean([BEAM.wavelength_mm(order) for order in MODES])
    assert len(zeros) == 3
    np.testing.assert_allclose(gaps, wavelength / 2, rtol=0.03)
    assert "a multiple of half a wavelength apart" in _capped_warning()


def test_the_warning_names_the_singular_matrix_and_half_wavelengths_only_on_a_beam():
    # on seed 001's plate the loci are sin(lambda x2/a) = sin(lambda x1/a) (eq 8), not
    # half a wavelength apart: the warning says what they are on any structure
    warning = _capped_warning()
    assert "mode-shape matrix is singular (det ~ 0" in warning
    assert "on a beam e.g. fingers a multiple of half a wavelength apart" in warning


def _block(positions, wanted):
    """Every finger touching at (x, y) for one sample, finger 0 first down."""
    pts = np.array(positions, dtype=float).reshape(len(positions), -1)
    y = pts[:, 1:] if pts.shape[1] > 1 else np.zeros((len(pts), 1))
    fingers = SimpleNamespace(contact=np.ones((len(pts), 1), bool), x_pred=pts[:, :1], y_pred=y,
                              touch_start=np.arange(len(pts), dtype=float)[:, None])
    return fingers, np.array(wanted, dtype=float)[:, None]


def _beam(method):
    return beam_actuation(BeamStructure(method=method), 1.0)


def _plate(method):
    return plate_actuation(PlateStructure(method=method), 1.0)


@pytest.mark.parametrize("method", ["exact", "bounded", "regularised"])
@pytest.mark.parametrize("make, positions, wanted", [
    (_beam, [[120.0], [120.0001]], [0.4, 0.0]),
    (_plate, [(35.0, 70.0), (35.001, 70.0)], [0.5, 0.2]),
])
def test_near_singular_fingers_are_capped_under_every_method(method, make, positions, wanted):
    fingers, wanted_um = _block(positions, wanted)
    assert make(method).command(wanted_um, fingers).capped == 1


def test_solve_counts_near_singular_systems_as_capped():
    phi = BEAM.phi(MODES, np.array([120.0, 120.0001]))
    assert 0 < np.linalg.cond(phi) ** -1 < NEAR_SINGULAR
    for method in ("exact", "bounded"):
        assert solve(phi, [0.4, 0.0], method, actuators=np.eye(2), limits_um=0.75).capped
    assert not solve(BEAM.phi(MODES, np.array([120.0, 250.0])), [0.4, 0.0], "exact").capped


@pytest.mark.parametrize("make, positions, wanted", [
    (_beam, [[120.0], [120.0001]], [0.4, 0.0]),
    (_plate, [(35.0, 70.0), (35.001, 70.0)], [0.5, 0.2]),
])
def test_bounded_spends_no_limit_on_a_near_singular_direction(make, positions, wanted):
    fingers, wanted_um = _block(positions, wanted)
    bounded = make("bounded").command(wanted_um, fingers)
    regularised = make("regularised").command(wanted_um, fingers)
    # the same amplitudes under the fingers as the regularised method, every channel
    # well within its limit (before: beam [0.197, 0.75] um, plate V_BD at 1.0)
    np.testing.assert_allclose(bounded.achieved_um, regularised.achieved_um, atol=1e-3)
    assert np.all(bounded.commands_um < 0.5 * make("bounded").limits_um)


def test_bounded_counts_limited_only_where_a_command_reaches_its_limit():
    node = BEAM.nodes_mm(16)[3]  # 68.939 mm, a node of mode 16
    fingers, wanted_um = _block([[node], [node + 1e-9]], [0.4, 0.1])
    at_node = _beam("bounded").command(wanted_um, fingers)
    assert np.all(at_node.commands_um < _beam("bounded").limits_um)  # [0.3047, 0.3047] < 0.75
    assert at_node.limited == 0
    fingers, wanted_um = _block([[120.0], [250.0]], [5.0, 0.0])
    assert _beam("bounded").command(wanted_um, fingers).limited == 1


def test_timoshenko_refusal_names_the_order_and_the_cutoff_frequency():
    beam = FreeFreeBeam(350, 6, 6, 57, 2561, theory="timoshenko")
    with pytest.raises(ModesError) as refused:
        beam.frequency_hz(80)
    # before: "beta = 664.222 1/m is above the Timoshenko cutoff 245187 Hz", then a
    # frequency that was the root search's end, not a mode's
    found = re.fullmatch(r"mode order 80 is above the Timoshenko cutoff ([0-9.e+]+) Hz of "
                         r"this beam: .*", str(refused.value))
    assert found and float(found[1]) == pytest.approx(beam.cutoff_hz, rel=1e-5)


@pytest.mark.parametrize("make", [_beam, _plate])
def test_a_negative_wanted_amplitude_is_refused(make):
    # before: -0.4 um was served as +0.4 um (commands of the opposite sign)
    positions = [[120.0], [250.0]] if make is _beam else [(35.0, 70.0), (105.0, 70.0)]
    fingers, wanted_um = _block(positions, [-0.4, 0.0])
    with pytest.raises(ModesError, match=r"^wanted amplitude -0.4 um of finger 0 at sample 0 is "
                                         r"negative; amplitudes are zero-to-peak, 0 or more$"):
        make("bounded").command(wanted_um, fingers)


@pytest.mark.parametrize("method", ["exact", "bounded"])
def test_a_finger_at_a_nan_position_is_named(method):
    fingers, wanted_um = _block([[120.0], [np.nan]], [0.4, 0.0])
    with pytest.raises(ModesError, match=r"^finger 1 at sample 0 is touching at a position that "
                                         r"is not finite \(x, y = nan, "):
        _beam(method).command(wanted_um, fingers)
