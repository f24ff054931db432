"""Singular loci, near-singular conditioning and the modal solver's edge cases."""

from types import SimpleNamespace

import numpy as np

from frictex.app.engine.summary import Totals, warnings_of
from frictex.device.structures.beam import FreeFreeBeam

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
