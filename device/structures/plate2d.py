"""The 2D two-finger plate of seed 001: an X mode and a Y mode, four actuators.

Seed 001, eq 6 approximates the two modes of order k (the 8th in its 140 x 140 x 4 mm
prototype) by

    phi_X(x, y) = sin(lambda_k x / a),   phi_Y(x, y) = sin(lambda_k y / b),
    lambda_k = (2k + 1) pi / 2

with x, y in mm and a, b the plate's width and height (seed 001 writes x, y as fractions
of the side). Both shapes are unit-peak. Two fingers cannot be controlled where

    sin(lambda_k x1/a) sin(lambda_k y2/b) - sin(lambda_k x2/a) sin(lambda_k y1/b) = 0

(seed 001, eq 8: the determinant of the 2 x 2 modal matrix).

Frequencies follow from the plate equation (seed 001, eqs 1-2) at the wavenumber of
eq 6, beta = lambda_k / a: omega = beta^2 sqrt(D / (rho h)), D = E h^3 / (12 (1 - nu^2)).
This is the straight-crested (strip) estimate that eq 6 implies, not an exact eigenvalue
of the free plate.

Actuators (seed 001, section 4.1): A and C share the supply V_AC, B and D share V_BD;
mode X follows V_AC + V_BD and mode Y follows V_AC - V_BD. With unit gain,
W_X = V_AC + V_BD and W_Y = V_AC - V_BD, so the commands are
(V_AC, V_BD) = ((W_X + W_Y) / 2, (W_X - W_Y) / 2): :data:`ACTUATORS` is that matrix, in
the form ``device.actuation.modal.solve(..., actuators=...)`` takes.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from frictex.device.structures.beam import ModesError, check_positive

AXES = ("x", "y")
#: modal amplitudes (W_X, W_Y) -> commands (V_AC, V_BD), unit gain (seed 001, section 4.1)
ACTUATORS = np.array([[0.5, 0.5], [0.5, -0.5]])
ACTUATOR_NAMES = ("V_AC", "V_BD")


@dataclass(frozen=True)
class Plate2D:
    """A rectangular plate with seed 001's X and Y modes of order ``order``.

    Parameters
    ----------
    width_mm, height_mm, thickness_mm : float
        Sides a (along x), b (along y) and thickness h (mm).
    youngs_gpa, density_kg_m3, poisson : float
        E (GPa), rho (kg/m^3), nu.
    order : int
        k of eq 6 (>= 1); seed 001's prototype uses k = 8.
    """

    width_mm: float
    height_mm: float
    thickness_mm: float
    youngs_gpa: float
    density_kg_m3: float
    poisson: float = 0.33
    order: int = 8

    def __post_init__(self):
        for name in ("width_mm", "height_mm", "thickness_mm", "youngs_gpa", "density_kg_m3"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        if not (math.isfinite(self.poisson) and -1 < self.poisson < 0.5):
            raise ModesError(f"poisson must be in (-1, 0.5), got {self.poisson!r}")
        if isinstance(self.order, bool) or int(self.order) != self.order or self.order < 1:
            raise ModesError(f"plate mode order k must be an integer >= 1, got {self.order!r}")

    @property
    def lambda_k(self) -> float:
        """(2k + 1) pi / 2 (seed 001, eq 6)."""
        return (2 * self.order + 1) * math.pi / 2

    def _side_mm(self, axis: str) -> float:
        if axis not in AXES:
            raise ModesError(f"plate axis must be 'x' or 'y', got {axis!r}")
        return self.width_mm if axis == "x" else self.height_mm

    def wavelength_mm(self, axis: str) -> float:
        """Wavelength 2 pi a / lambda_k (mm) of the mode along ``axis``."""
        return 2 * math.pi * self._side_mm(axis) / self.lambda_k

    def frequency_hz(self, axis: str) -> float:
        """Plate-equation frequency (Hz) at the wavenumber of eq 6 (see the module docstring)."""
        h = self.thickness_mm * 1e-3
        e = self.youngs_gpa * 1e9
        d = e * h ** 3 / (12 * (1 - self.poisson ** 2))  # seed 001, eq 2
        beta = self.lambda_k / (self._side_mm(axis) * 1e-3)
        return beta * beta * math.sqrt(d / (self.density_kg_m3 * h)) / (2 * math.pi)

    def nodes_mm(self, axis: str) -> np.ndarray:
        """Positions (mm) of the k + 1 nodal lines of the mode along ``axis`` (x = const for X)."""
        side = self._side_mm(axis)
        return 2 * np.arange(self.order + 1) * side / (2 * self.order + 1)

    def phi(self, x_mm, y_mm) -> np.ndarray:
        """Modal matrix rows at (x, y): float64 (..., 2) = (phi_X, phi_Y) (seed 001, eq 6).

        ``x_mm``, ``y_mm`` broadcast together; positions in mm from the plate's corner.
        """
        x, y = np.broadcast_arrays(np.asarray(x_mm, dtype=np.float64),
                                   np.asarray(y_mm, dtype=np.float64))
        return np.stack([np.sin(self.lambda_k * x / self.width_mm),
                         np.sin(self.lambda_k * y / self.height_mm)], axis=-1)

    def det(self, x1_mm, y1_mm, x2_mm, y2_mm) -> np.ndarray:
        """det Phi for fingers at (x1, y1) and (x2, y2), broadcast (seed 001, eq 8)."""
        p1, p2 = self.phi(x1_mm, y1_mm), self.phi(x2_mm, y2_mm)
        return p1[..., 0] * p2[..., 1] - p2[..., 0] * p1[..., 1]
