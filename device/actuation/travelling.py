"""Travelling waves from two modes in quadrature, on a finite beam or on the ring.

Seed 002 (eqs 1-5): with complex modal amplitudes W_A, W_B (um, time factor e^{j omega t},
physical motion Re[W(x) e^{j omega t}]) the surface moves as
W(x) = W_A psi_A(x) + W_B psi_B(x); W_A = +-j W_B makes a travelling wave (eq 4) and the
actuators' references are the field at their positions (eq 5). A standing wave of the
same device is W_B = 0. Here each mode shape is scaled to unit *propagating* amplitude
(for a beam, the shape's cos/sin part away from the ends), so an amplitude W gives a
surface amplitude W (um zero-to-peak) where the wave is purely travelling, and W_A = W
alone gives a standing wave of the same peak amplitude (seed 002, section 5).
``direction`` +1 is a wave travelling towards +x, -1 towards -x, 0 the standing wave.

Two adjacent modes of a finite beam have different wavenumbers, so they stay in
quadrature only near mid-span: the field is a pure travelling wave there and turns into
a standing wave towards the ends. The local travelling-wave ratio is seed 004's
(Fig. 4): the minimum over the maximum of the vibration envelope. A field
F e^{-jkx} + B e^{jkx} has envelope between ||F| - |B|| and |F| + |B|, so ratio
tau = ||F| - |B|| / (|F| + |B|): a pure travelling wave of amplitude ||F| - |B|| on top of
a standing wave. F and B are read pointwise from the two modes' complex amplitudes
(:meth:`TwoModeWave.travelling_parts`). Each mode shape is locally a propagating cosine,
psi_n = cos(k_n x + theta_n) = (e^{-j(k_n x + theta_n)} + e^{j(k_n x + theta_n)}) / 2,
whose parts travelling towards +x and -x are (psi_n + j psi_n' / k_n) / 2 and
(psi_n - j psi_n' / k_n) / 2; summed over the modes with their amplitudes (eq 1)::

    F(x) = 1/2 sum_n W_n (psi_n(x) + j psi_n'(x) / k_n)
    B(x) = 1/2 sum_n W_n (psi_n(x) - j psi_n'(x) / k_n)

With eq 4 (W_A = +-j W_B) and two modes in spatial quadrature (psi_A = cos, psi_B = sin
at one k) one part vanishes: tau = 1, the pure travelling wave. Where the beam's modes
drift out of quadrature by delta = (k_B - k_A)(x - L/2), tau = (1 - |sin delta|) / |cos delta|.
(A min/max of |W| over a half-wavelength window, used before, read 0.984 at mid-span
where tau is exactly 1: the window spans envelope that belongs to neighbouring points.)
The end (evanescent) terms of the beam's shapes, below e^{-beta x} away from the ends,
are read as if propagating; there tau is near 0 anyway.

Seed 004 (eq 1, Fig. 4): on the ring the two degenerate modes are driven with a phase
shift phi (W_A = e^{j phi} W_B); +-90 degrees gives a pure travelling wave, 0 or 180 a
standing wave, and the force on a still finger follows the ratio and reverses with the
sign of phi (:func:`phase_shift_response`).

Seed 004, Fig. 3c: the driving force of a travelling amplitude on a finger
(:func:`driving_force`; here, not in ``rendering``, so that ``device`` never imports
``rendering``).

Seed 002, eq 6: the surface points' horizontal speed, S_h = pi W h omega / lambda
(:func:`surface_speed_mm_s`).
"""

from __future__ import annotations

import math
from collections.abc import Callable
from dataclasses import dataclass

import numpy as np

from frictex.device.structures.beam import FreeFreeBeam, ModesError
from frictex.device.structures.ring import RingMode, RingResonator
from frictex.device.profile import DrivingForceParams

#: grid samples per wavelength (ratio and gain tables are read between them linearly)
_SAMPLES_PER_WAVELENGTH = 512
#: step of the slopes' five-point difference, in wavelengths (error ~ (2 pi h)^4 / 30 ~ 5e-11)
_SLOPE_STEP = 1e-3


def driving_force(travelling_um, normal_force_n, params: DrivingForceParams) -> np.ndarray:
    """F_p (N) = k_p F_n max(0, w_t - w_th) for a travelling amplitude w_t (um, zero-to-peak).

    Seed 004, section IV.B and Fig. 3c, gives the slope (0.13 N/um) only at f_z = 1 N, as
    a line fitted through its points, and says the force is insignificant below about 1
    um and weaker than the line below 1.3 um; it is larger at 1 N than at 0.5 N. The
    threshold ``w_th`` (1 um) and the force's proportion to F_n are this model's own
    reading of those statements, not the paper's equation: at 3 um and 1 N it gives 0.26
    N, where a line through the origin would give 0.39 N. Arguments broadcast together.
    """
    drive = np.maximum(np.asarray(travelling_um, dtype=np.float64) - params.threshold_um, 0.0)
    return params.slope_per_um * np.asarray(normal_force_n, dtype=np.float64) * drive


def surface_speed_mm_s(w_um, thickness_mm: float, wavelength_mm: float, frequency_hz: float):
    """Peak horizontal speed (mm/s) of the surface under a travelling wave: seed 002, eq 6.

    S_h = pi W h omega / lambda, with W the zero-to-peak amplitude, h the full thickness
    (the surface is h/2 from the neutral line, whose slope amplitude is 2 pi W / lambda)
    and omega = 2 pi f in rad/s. This is the convention under which the paper's "1 um
    gives 80 mm/s" holds (81.7 mm/s for its 6 mm beam, lambda 41 mm, 28.3 kHz).
    """
    return (math.pi * np.asarray(w_um, dtype=np.float64) * 1e-3 * thickness_mm
            * 2 * math.pi * frequency_hz / wavelength_mm)


@dataclass(frozen=True, eq=False)
class TwoModeWave:
    """Two mode shapes sampled on the touch surface, scaled to unit propagating amplitude.

    shapes_at : x_mm (any shape) -> float64 (..., 2), psi_A and psi_B at x.
    x_mm : float64 (g,) uniform grid along the surface (mm); shapes : (g, 2) on it;
    slopes : (g, 2) d psi / dx on it (1/mm).
    wavelength_mm : the waves' (mean) wavelength.
    wavenumbers : (k_A, k_B), each mode's wavenumber 2 pi / lambda_n (rad/mm).
    sign : +1 or -1, the sign s for which W_A = s j W_B travels towards +x.
    """

    shapes_at: Callable[[np.ndarray], np.ndarray]
    x_mm: np.ndarray
    shapes: np.ndarray
    slopes: np.ndarray
    wavelength_mm: float
    wavenumbers: tuple[float, float]
    sign: int

    @classmethod
    def from_shapes(cls, shapes_at: Callable[[np.ndarray], np.ndarray], x_mm: np.ndarray,
                    wavelengths_mm: tuple[float, float]) -> "TwoModeWave":
        """Sample ``shapes_at`` and its slope on ``x_mm``; the direction sign is read at
        the grid's middle point from the parts of W_A = j W_B travelling each way, so a
        grid shorter than a wavelength has it too."""
        wavelength = 0.5 * (wavelengths_mm[0] + wavelengths_mm[1])
        h = _SLOPE_STEP * wavelength
        slopes = (8 * (shapes_at(x_mm + h) - shapes_at(x_mm - h))
                  - (shapes_at(x_mm + 2 * h) - shapes_at(x_mm - 2 * h))) / (12 * h)
        k = (2 * math.pi / wavelengths_mm[0], 2 * math.pi / wavelengths_mm[1])
        wave = cls(shapes_at, x_mm, shapes_at(x_mm), slopes, wavelength, k, 1)
        mid = x_mm.size // 2
        forward, backward = wave.travelling_parts(wave.modal(1.0, 1))
        sign = 1 if abs(forward[mid]) >= abs(backward[mid]) else -1
        return cls(shapes_at, x_mm, wave.shapes, slopes, wavelength, k, sign)

    def modal(self, amplitude_um, direction) -> np.ndarray:
        """Modal amplitudes (..., 2) complex (um) for amplitude W and direction (-1, 0, +1).

        Seed 002, eq 4: W_A = +-j W_B for a travelling wave; direction 0 is W_B = 0.
        """
        w = np.asarray(amplitude_um, dtype=np.float64)
        d = np.asarray(direction)
        w_a = np.where(d == 0, w, d * self.sign * 1j * w)
        return np.stack(np.broadcast_arrays(w_a, np.where(d == 0, 0.0, w) + 0j), axis=-1)

    def field(self, modal: np.ndarray, x_mm=None) -> np.ndarray:
        """Complex amplitude W(x) (um) of ``modal`` (..., 2) at ``x_mm`` (default: the grid)."""
        shapes = self.shapes if x_mm is None else self.shapes_at(np.asarray(x_mm, dtype=np.float64))
        return np.tensordot(np.asarray(modal), shapes, axes=([-1], [-1]))

    def travelling_parts(self, modal: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
        """Complex amplitudes (um) of the parts travelling towards +x (F) and -x (B) at
        each grid point, ``(F, B)`` each (..., g), from ``modal`` (..., 2) (see the module
        docstring: F, B = 1/2 sum_n W_n (psi_n +- j psi_n' / k_n))."""
        k = np.asarray(self.wavenumbers)
        turned = 1j * self.slopes / k  # j psi_n' / k_n, (g, 2)
        forward = 0.5 * np.tensordot(np.asarray(modal), self.shapes + turned, axes=([-1], [-1]))
        backward = 0.5 * np.tensordot(np.asarray(modal), self.shapes - turned, axes=([-1], [-1]))
        return forward, backward

    def local_ratio(self, modal: np.ndarray) -> np.ndarray:
        """Local travelling-wave ratio on the grid (g,): ||F| - |B|| / (|F| + |B|) (0 where
        the field vanishes)."""
        forward, backward = (np.abs(p) for p in self.travelling_parts(modal))
        total = forward + backward
        return np.divide(np.abs(forward - backward), total, out=np.zeros_like(total),
                         where=total > 0)

    def local_max(self, modal: np.ndarray) -> np.ndarray:
        """Local envelope maximum on the grid (g,), um: |F| + |B|."""
        forward, backward = (np.abs(p) for p in self.travelling_parts(modal))
        return forward + backward


def beam_wave(beam: FreeFreeBeam, order_a: int) -> TwoModeWave:
    """Modes ``order_a`` and ``order_a + 1`` of a free-free beam (seed 002, Fig. 1) on the beam.

    Each shape is divided by its propagating amplitude, sqrt(W(x)^2 + W(x + lambda/4)^2)
    at mid-span, where the end (evanescent) terms are below e^{-beta L/2}.
    """
    orders = (order_a, order_a + 1)
    wavelengths = (beam.wavelength_mm(orders[0]), beam.wavelength_mm(orders[1]))
    n = int(math.ceil(beam.length_mm / min(wavelengths) * _SAMPLES_PER_WAVELENGTH)) + 1
    x = np.linspace(0.0, beam.length_mm, n)
    mid = beam.length_mm / 2
    scale = np.array([math.hypot(float(beam.shape(o, mid)),
                                 float(beam.shape(o, mid + beam.wavelength_mm(o) / 4)))
                      for o in orders])
    return TwoModeWave.from_shapes(lambda xs: beam.phi(orders, xs) / scale, x, wavelengths)


def ring_wave(ring: RingResonator, order: int) -> TwoModeWave:
    """The symmetric (A) and asymmetric (B) modes of ``order`` on a straight part (seed 004)."""
    modes: tuple[RingMode, RingMode] = ring.pair(order)
    wavelengths = (modes[0].wavelength_mm, modes[1].wavelength_mm)
    n = int(math.ceil(ring.length_mm / min(wavelengths) * _SAMPLES_PER_WAVELENGTH)) + 1
    x = np.linspace(-ring.length_mm / 2, ring.length_mm / 2, n)
    return TwoModeWave.from_shapes(
        lambda xs: np.stack([ring.straight_shape(m, xs) for m in modes], axis=-1), x, wavelengths)


@dataclass(frozen=True, eq=False)
class BeamActuation:
    """Seed 002's two-actuator travelling-wave beam: references (eq 5) and the wave they make.

    wave : the two modes on the beam (:func:`beam_wave`).
    actuators_mm : positions x_1, x_2 of the two actuators (mm from the end).
    """

    wave: TwoModeWave
    actuators_mm: tuple[float, float]

    def __post_init__(self):
        x0, x1 = self.wave.x_mm[0], self.wave.x_mm[-1]
        for x in self.actuators_mm:
            if not (x0 <= x <= x1):
                raise ModesError(f"actuator position {x!r} mm is off the beam "
                                 f"(expected {x0:g} <= x <= {x1:g} mm)")

    def references(self, amplitude_um, direction) -> np.ndarray:
        """Actuator references (..., 2) complex (um zero-to-peak, phase rad): seed 002, eq 5.

        ``amplitude_um`` and ``direction`` (-1, 0, +1) broadcast (e.g. over a block).
        """
        return self.wave.field(self.wave.modal(amplitude_um, direction), self.actuators_mm)

    def ratio_at(self, x_mm) -> np.ndarray:
        """Local travelling-wave ratio at positions ``x_mm`` (the same for both directions)."""
        return np.interp(x_mm, self.wave.x_mm, self.wave.local_ratio(self.wave.modal(1.0, 1)))

    def gain_at(self, x_mm) -> np.ndarray:
        """Local envelope maximum |F| + |B| per unit W at positions ``x_mm``."""
        return np.interp(x_mm, self.wave.x_mm, self.wave.local_max(self.wave.modal(1.0, 1)))


def phase_shift_response(wave: TwoModeWave, phase_rad, amplitude_um: float,
                         normal_force_n: float, params: DrivingForceParams):
    """Travelling-wave ratio and force on a still finger against phase shift (seed 004, Fig. 4).

    Parameters
    ----------
    wave : the two modes (e.g. :func:`ring_wave`).
    phase_rad : (k,) phase shift phi of mode A over mode B (W_A = e^{j phi} W_B), rad.
    amplitude_um : W (um zero-to-peak).
    normal_force_n : F_n (N).
    params : the driving-force model.

    Returns
    -------
    ratio : (k,) min / max of the envelope across the surface.
    force_n : (k,) lateral force along +x (N) on a still finger, -d F_p(min |W|): the
        travelling part of the field (the envelope minimum) pushes against its direction
        of travel d = sign * sign(sin phi).
    """
    phi = np.asarray(phase_rad, dtype=np.float64)
    w_b = np.full(phi.shape, float(amplitude_um)) + 0j
    modal = np.stack([np.exp(1j * phi) * w_b, w_b], axis=-1)
    env = np.abs(wave.field(modal))
    ratio = env.min(axis=-1) / env.max(axis=-1)
    direction = wave.sign * np.sign(np.sin(phi))
    return ratio, -direction * driving_force(env.min(axis=-1), normal_force_n, params)
