"""Travelling waves (seed 002, eqs 4-6; seed 004, eq 1 and Fig. 4): actuator references,
direction, local travelling-wave ratio on a finite beam, phase-shift control on the ring."""

import math

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.device.structures.beam import FreeFreeBeam, ModesError
from frictex.device.structures.ring import RingResonator
from frictex.device.actuation.travelling import (BeamActuation, beam_wave, phase_shift_response, ring_wave,
                               surface_speed_mm_s)
from frictex.rendering.layers.tangential import DrivingForceParams

# seed 002's beam: 600 x 6 x 6 mm aluminium, wavelength about 41 mm (orders 28-29 here)
BEAM = FreeFreeBeam(600, 6, 6, 69, 2700)
WAVE = beam_wave(BEAM, 28)
ACT = BeamActuation(WAVE, (19.0, 581.0))
RING_WAVE = ring_wave(RingResonator(140, 50, 2.75, 30, 69, 2680), 24)


def test_eq_6_surface_speed_holds_for_zero_to_peak_and_angular_frequency():
    # seed 002: "W = 1 um gives a tangential speed of 80 mm/s" (h 6 mm, lambda 41 mm, 28.3 kHz)
    speed = surface_speed_mm_s(1.0, 6.0, 41.0, 28_300.0)
    # independently: surface h/2 from the neutral line, slope amplitude k W, times omega
    assert_allclose(speed, 3.0 * (2 * math.pi / 41.0) * 1e-3 * 2 * math.pi * 28_300, rtol=1e-14)
    assert_allclose(speed, 80.0, rtol=0.025)           # the paper rounds 81.7 to 80
    assert abs(surface_speed_mm_s(0.5, 6.0, 41.0, 28_300.0) - 80.0) > 30  # peak-to-peak: no


def test_eq_5_references_are_the_two_shapes_at_the_actuators():
    refs = ACT.references(np.array([1.0, 2.0, 1.0]), np.array([1, -1, 0]))
    phi = BEAM.phi((28, 29), np.array([19.0, 581.0]))              # (2 actuators, 2 modes)
    mid = 300.0
    scale = [math.hypot(BEAM.shape(o, mid), BEAM.shape(o, mid + BEAM.wavelength_mm(o) / 4))
             for o in (28, 29)]
    psi = phi / np.array(scale)
    s = WAVE.sign
    assert_allclose(refs[0], s * 1j * psi[:, 0] + psi[:, 1], rtol=1e-12)      # W_A = +j W_B
    assert_allclose(refs[1], 2 * (-s * 1j * psi[:, 0] + psi[:, 1]), rtol=1e-12)
    assert_allclose(refs[2], psi[:, 0], rtol=1e-12)                             # W_B = 0
    # the references need neither equal amplitudes nor a 90 degree shift (seed 002)
    assert not np.isclose(abs(np.angle(refs[0, 0] / refs[0, 1])), math.pi / 2, atol=1e-2)


@pytest.mark.parametrize("direction", [1, -1])
def test_direction_is_the_direction_of_travel(direction):
    # Re[W(x) e^{j w t}] = |W| cos(w t + arg W(x)): a point of constant phase moves at
    # dx/dt = -w / (d arg W / dx), so travel towards +x needs arg W falling with x
    x = np.linspace(300 - WAVE.wavelength_mm, 300 + WAVE.wavelength_mm, 2001)
    slope = np.diff(np.unwrap(np.angle(WAVE.field(WAVE.modal(1.0, direction), x)))) / np.diff(x)
    assert np.all(np.sign(slope) == -direction)
    assert_allclose(np.mean(slope), -direction * 2 * math.pi / WAVE.wavelength_mm, rtol=0.02)


def test_envelope_is_the_time_domain_peak_and_ratio_falls_towards_the_ends():
    modal = WAVE.modal(1.0, 1)
    field = WAVE.field(modal)
    wt = np.linspace(0, 2 * math.pi, 721)[:, None]
    assert_allclose(np.abs(np.real(field * np.exp(1j * wt))).max(axis=0), np.abs(field),
                    rtol=1e-4)
    x = np.array([5.0, 75.0, 150.0, 225.0, 300.0])
    ratio = ACT.ratio_at(x)
    assert ratio[-1] > 0.98                       # pure travelling wave at mid-span
    assert np.all(np.diff(ratio) > 0) and ratio[0] < 0.1
    assert_allclose(ACT.ratio_at(600 - x), ratio, atol=0.02)        # symmetric about mid-span
    # against the two-wave model: drift delta = (beta_B - beta_A)(x - L/2) between the modes
    dbeta = 2 * math.pi * (1 / BEAM.wavelength_mm(29) - 1 / BEAM.wavelength_mm(28))
    sd = np.abs(np.sin(dbeta * (x[1:4] - 300)))
    assert_allclose(ratio[1:4], np.sqrt((1 - sd) / (1 + sd)), atol=0.05)
    # the standing wave (W_B = 0) of the same device is not travelling anywhere
    assert WAVE.local_ratio(WAVE.modal(1.0, 0)).max() < 0.05
    assert_allclose(ACT.gain_at(300.0), 1.0, atol=0.01)


def test_ratio_is_pointwise_exact_against_the_two_wave_model():
    """Seed 002, eq 4 on the beam's modes 28-29: at mid-span the symmetric and the
    antisymmetric mode are in exact spatial quadrature, so the wave is purely travelling
    (tau = 1, where a half-wavelength min/max window read 0.984). Away from it they drift
    by delta = (beta_B - beta_A)(x - L/2); splitting each mode's cosine into its two
    travelling halves gives |F| ~ sqrt(1 + cos delta), |B| ~ sqrt(1 - cos delta), so
    tau = (|F| - |B|) / (|F| + |B|) = (1 - |sin delta|) / |cos delta| (while cos delta > 0)."""
    assert abs(float(ACT.ratio_at(300.0)) - 1.0) < 1e-9
    dbeta = 2 * math.pi * (1 / BEAM.wavelength_mm(29) - 1 / BEAM.wavelength_mm(28))
    x = np.linspace(100.0, 500.0, 81)  # clear of the end terms (below e^{-beta 100 mm} = 2e-7)
    delta = dbeta * (x - 300.0)
    assert np.all(np.cos(delta) > 0)
    expected = (1 - np.abs(np.sin(delta))) / np.abs(np.cos(delta))
    assert_allclose(ACT.ratio_at(x), expected, atol=5e-5)  # the table's linear interpolation
    on = (WAVE.x_mm >= 100.0) & (WAVE.x_mm <= 500.0)  # on the grid itself, no interpolation
    d = dbeta * (WAVE.x_mm[on] - 300.0)
    assert_allclose(WAVE.local_ratio(WAVE.modal(1.0, 1))[on],
                    (1 - np.abs(np.sin(d))) / np.abs(np.cos(d)), atol=1e-6)


def test_ring_ratio_from_its_cos_and_sin_modes():
    """On the ring's straight part psi_A = cos(k_A x), psi_B = sin(k_B x) (seed 004); with
    W_A = s j, W_B = 1 the parts towards +x and -x are, by hand,
    F = (s j e^{-j k_A x} + j e^{-j k_B x}) / 2 and B = (s j e^{j k_A x} - j e^{j k_B x}) / 2
    (cos = (e^{jkx} + e^{-jkx}) / 2, sin = (e^{jkx} - e^{-jkx}) / 2j)."""
    k_a, k_b = RING_WAVE.wavenumbers
    s = RING_WAVE.sign
    x = RING_WAVE.x_mm
    forward = (s * 1j * np.exp(-1j * k_a * x) + 1j * np.exp(-1j * k_b * x)) / 2
    backward = (s * 1j * np.exp(1j * k_a * x) - 1j * np.exp(1j * k_b * x)) / 2
    got_f, got_b = RING_WAVE.travelling_parts(RING_WAVE.modal(1.0, 1))
    assert_allclose(np.abs(got_f), np.abs(forward), atol=1e-9)
    assert_allclose(np.abs(got_b), np.abs(backward), atol=1e-9)
    tau = np.abs(np.abs(forward) - np.abs(backward)) / (np.abs(forward) + np.abs(backward))
    assert_allclose(RING_WAVE.local_ratio(RING_WAVE.modal(1.0, 1)), tau, atol=1e-9)


def test_phase_shift_sets_ratio_and_force_direction_on_the_ring():
    phase = np.radians([-180, -135, -90, -45, 0, 45, 90, 135, 180])
    ratio, force = phase_shift_response(RING_WAVE, phase, 3.0, 1.0, DrivingForceParams())
    # degenerate cos/sin modes: envelope^2 = 1 +- cos(phi), ratio = tan(min(|phi|, pi-|phi|)/2)
    folded = np.minimum(np.abs(phase), math.pi - np.abs(phase))
    assert_allclose(ratio, np.tan(folded / 2), atol=0.01)
    assert_allclose(force, -force[::-1], atol=1e-15)           # reverses with the sign of phi
    assert np.all(force[[0, 4, 8]] == 0) and np.argmax(np.abs(force)) in (2, 6)
    # at +-90 degrees a pure 3 um wave: 0.13 N/um at 1 N above 1 um (seed 004, Fig. 3c)
    assert_allclose(abs(force[6]), 0.13 * (3.0 - 1.0), rtol=0.01)


def test_actuator_off_the_beam_raises():
    with pytest.raises(ModesError, match="actuator position 700.0 mm is off the beam"):
        BeamActuation(WAVE, (19.0, 700.0))


@pytest.mark.parametrize("length_mm", [1.0, 2.0, 140.0])
def test_direction_holds_on_a_straight_shorter_than_a_wavelength(length_mm):
    # a 1 mm straight holds under a tenth of the 11 mm wavelength: no sample an eighth of a
    # wavelength past its middle, yet W_A = +j s W_B still travels towards +x there
    wave = ring_wave(RingResonator(length_mm, 50, 2.75, 30, 69, 2680), 24)
    assert wave.x_mm[-1] - wave.x_mm[0] == pytest.approx(length_mm)
    for direction in (1, -1):
        field = wave.field(wave.modal(1.0, direction))
        slope = np.diff(np.unwrap(np.angle(field))) / np.diff(wave.x_mm)
        assert np.all(np.sign(slope) == -direction)
