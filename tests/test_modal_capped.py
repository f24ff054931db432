"""Two-finger control lost on a singular locus (seed 001, eq 8) is counted and warned about."""

from types import SimpleNamespace

import numpy as np
import pytest

from frictex.app.engine.summary import Totals, warnings_of
from frictex.device.actuation.modal_actuation import ModalActuation
from frictex.device.structures.plate2d import ACTUATOR_NAMES, ACTUATORS, Plate2D

PLATE = Plate2D(140, 140, 4, 57, 2561, order=8)  # seed 001, section 4
#: finger 2 one wavelength (32.94 mm) from finger 1 along x and y: eq 8's determinant is 0
SINGULAR = ((20.0, 70.0), (52.9412, 102.9412))
#: coincident fingers: singular to the last bit, for every method's threshold
SAME = ((20.0, 70.0), (20.0, 70.0))
#: a well-conditioned pair (the determinant far from 0)
APART = ((20.0, 70.0), (60.0, 60.0))


def plate_actuation(method):
    return ModalActuation(PLATE.phi, ((0, 140), (0, 140)), (0, 0), ACTUATORS, ACTUATOR_NAMES, 1.0,
                          method, 0.1)


def fingers_at(positions, n=5):
    """Every finger touching at its fixed position for n samples, finger 0 first down."""
    f = len(positions)
    x = np.array([[p[0]] * n for p in positions])
    y = np.array([[p[1]] * n for p in positions])
    return SimpleNamespace(contact=np.ones((f, n), bool), x_pred=x, y_pred=y,
                           touch_start=np.arange(f, dtype=float)[:, None] * np.ones((1, n)))


@pytest.mark.parametrize("method, positions", [("regularised", SINGULAR), ("regularised", SAME),
                                               ("exact", SAME), ("bounded", SAME)])
def test_fingers_on_a_singular_locus_are_counted_capped(method, positions):
    """The fingers ask for 0.3 and 0.5 um and cannot be told apart: every sample is
    counted (closed form for regularised and exact, SVD for bounded). Near, not on, the
    locus "exact" does not cap its gain: its commands grow and are counted as limited."""
    result = plate_actuation(method).command(np.array([[0.3] * 5, [0.5] * 5]), fingers_at(positions))
    assert result.capped == 5


@pytest.mark.parametrize("method", ["regularised", "exact", "bounded"])
@pytest.mark.parametrize("positions", [APART, SINGULAR[:1]], ids=["apart", "one finger"])
def test_independent_or_single_fingers_are_not_counted(method, positions):
    """A well-conditioned pair, or one finger alone (its padded zero row caps the gain
    but there is nothing to tell apart), counts 0."""
    wanted = np.full((len(positions), 5), 0.3)
    assert plate_actuation(method).command(wanted, fingers_at(positions)).capped == 0


def test_capped_samples_are_warned_about():
    totals = Totals()
    totals.modal_capped = 12
    pipeline = SimpleNamespace(forces=None, scene=SimpleNamespace(layers=()))
    tracker = SimpleNamespace(jumps=0, out_of_order=0)
    warnings = warnings_of(pipeline, tracker, totals)
    assert [w for w in warnings if w.startswith("12 samples: the fingers could not be given "
                                                "independent amplitudes (seed 001 eq 8")]
