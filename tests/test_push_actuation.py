"""Travelling-wave actuation of the force profiles: seed 002 eq 5 references on the beam,
seed 004 phase-shift control on the ring, local ratio and envelope under the fingers."""

import math
from types import SimpleNamespace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.device.actuation.factory import make_actuation
from frictex.device.structures.beam import FreeFreeBeam
from frictex.device.actuation.push_actuation import travelling_beam, travelling_ring
from frictex.device.actuation.travelling import BeamActuation, beam_wave
from frictex.device.profile import DeviceProfile
from frictex.device.registry import UnknownName

BEAM = travelling_beam(1e9)  # limits tested on their own
RING = travelling_ring(1e9)


def fingers(x):
    x = np.atleast_2d(np.asarray(x, dtype=np.float64))
    return SimpleNamespace(contact=np.ones(x.shape, bool), x_pred=x)


def test_beam_commands_are_the_eq_5_references_scaled_by_the_amplitude():
    reference = BeamActuation(beam_wave(FreeFreeBeam(600, 6, 6, 69, 2700), 28), (19.0, 581.0))
    w = np.array([0.0, 1.0, 2.5, 2.5])
    d = np.array([1, 1, 1, -1])
    act = BEAM.drive(w, d, fingers(np.full(4, 300.0)))
    refs = reference.references(w, d)
    assert_allclose(act.commands_um, np.abs(refs), rtol=1e-12, atol=1e-15)
    nonzero = w > 0
    assert_allclose(np.exp(1j * act.phases_rad[nonzero]), np.exp(1j * np.angle(refs[nonzero])),
                    atol=1e-12)
    # reversing the wave conjugates the references (W_A = +j W_B -> -j W_B, real shapes)
    assert_allclose(act.phases_rad[2], -act.phases_rad[3], atol=1e-12)


def test_ring_channels_are_the_two_modes_ninety_degrees_apart_sign_set_by_direction():
    act = RING.drive(np.array([2.0, 2.0]), np.array([1, -1]), fingers(np.array([70.0, 70.0])))
    assert_allclose(act.commands_um, 2.0, rtol=1e-15)      # same modal amplitude (seed 004, eq 1)
    shift = act.phases_rad[:, 0] - act.phases_rad[:, 1]
    assert_allclose(np.abs(shift), math.pi / 2, rtol=1e-12)
    assert np.sign(shift[0]) == -np.sign(shift[1])         # direction reverses with the shift
    # direction +1 travels towards +x: phase falling with x along the straight
    x = np.linspace(60.0, 62.0, 5) - 70.0
    field = RING.wave.field(RING.wave.modal(1.0, 1), x)
    assert np.all(np.diff(np.unwrap(np.angle(field))) < 0)


def test_ratio_and_envelope_under_fingers_follow_the_beam_and_the_display_offset():
    x = np.array([[2.0, 100.0, 300.0]])
    assert_allclose(BEAM.ratio_at(x), BEAM.wave.local_ratio(BEAM.wave.modal(1.0, 1))[
        np.searchsorted(BEAM.wave.x_mm, x)], atol=0.01)
    ratio = BEAM.ratio_at(x)[0]
    assert ratio[0] < 0.05 and ratio[2] > 0.97                # standing near the end
    act = BEAM.drive(np.array([1.5]), np.array([1]), fingers(np.array([[300.0], [2.0]])))
    assert_allclose(act.achieved_um[:, 0], 1.5 * BEAM.gain_at(np.array([300.0, 2.0])), rtol=1e-12)
    assert_allclose(act.achieved_um[0, 0], 1.5, rtol=0.01)   # unit propagating amplitude mid-span
    # the ring's straight is centred on display x = 70 mm and the wave is travelling throughout
    assert RING.ratio_at(np.array([0.0, 70.0, 140.0])).min() > 0.99
    assert_allclose(RING.x0_mm, -70.0)


def test_make_actuation_dispatches_the_force_profiles():
    act = make_actuation(DeviceProfile(profile="ring-seed004"))
    assert act.channels == ("mode_sym", "mode_asym") and act.has_phases
    with pytest.raises(UnknownName, match="unknown device profile 'ring'; expected one of "
                                          "plate-seed003, .*ring-seed004"):
        make_actuation(DeviceProfile(profile="ring"))


def test_channel_commands_never_pass_the_limit_and_keep_the_wave_shape():
    beam = travelling_beam(3.0)
    w = np.linspace(0.0, 5.0, 101)
    d = np.ones(w.size, dtype=np.int8)
    wave, limited = beam.within_limit(w, d)
    fingers = SimpleNamespace(contact=np.zeros((0, w.size), bool), x_pred=np.zeros((0, w.size)))
    act = beam.drive(wave, d, fingers, limited)
    assert act.commands_um.max() <= 3.0 and np.isclose(act.commands_um.max(), 3.0)
    assert act.limited == limited == int(np.count_nonzero(wave < w))
    unit = np.abs(beam.unit_refs[2])
    np.testing.assert_allclose(act.commands_um[1:] / wave[1:, None], np.broadcast_to(unit, (100, 2)),
                               rtol=1e-12)  # scaled together: the same travelling wave


def test_the_envelope_limit_is_what_the_channels_give_under_the_finger():
    beam = travelling_beam(3.0)
    x = np.array([300.0, 100.0, 20.0])
    limit = beam.envelope_limit_at(x)
    assert_allclose(limit[0], 3.0 / 1.16405249, rtol=1e-6)   # g = 1 mid-span
    # a wave planned there, divided back by g, is within every channel: not limited
    for d in (-1, 1):
        wave, limited = beam.within_limit(limit / beam.gain_at(x), np.full(3, d))
        assert limited == 0
        assert_allclose(np.abs(beam.unit_refs[d + 1]).max() * wave, 3.0, rtol=1e-12)
    assert_allclose(travelling_ring(3.0).envelope_limit_at(70.0), 3.0, rtol=1e-3)
