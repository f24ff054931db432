"""The ring resonator of seed 004 (Ultraloop): degenerate flexural modes of an oblong ring.

The ring is two straight beams of length L joined by two semicircles of radius R, of
uniform width w and thickness h (seed 004, Fig. 2a). The straight part is a Rayleigh
beam (seed 004, eq 2), the curved part an inextensional ring (eq 3, v_c = -du_c/dtheta).
A mode has a straight-part shape V_s(x) = A_s cos(k_s x) or A_s sin(k_s x) on
x in [-L/2, L/2] and a curved-part shape U_c = A_c sin(k_c theta) or A_c cos(k_c theta) on
theta in [-pi/2, pi/2], the two meeting at x = L/2, theta = -pi/2. Four families:

==============  ============  ============  ==========  =========================
family          V_s           U_c           orders      ``kind`` here
==============  ============  ============  ==========  =========================
solution 1      cos(k_s x)    sin(k_c th)   even        "symmetric"
solution 1      sin(k_s x)    cos(k_c th)   even        "asymmetric"
solution 2      cos(k_s x)    cos(k_c th)   odd         "symmetric" (paper: y-axis)
solution 2      sin(k_s x)    sin(k_c th)   odd         "asymmetric" (paper: x-axis)
==============  ============  ============  ==========  =========================

``kind`` is the parity of the straight-part shape about the straight's centre, which
is the paper's naming for the even orders it uses; for odd orders the paper says
"y-axis symmetric" and "x-axis symmetric".

Dispersion (the modes' only free parameter is k_c, the curved part's wavenumber per
radian, as in the paper):

- eq 7 solved for omega: omega^2 = K (K - 1)^2 / (gamma_c (K - 1)^2 + alpha_c (K + 1)),
  K = k_c^2, alpha_c = rho A R^4 / (E I), gamma_c = rho R^2 / E;
- eq 6 solved for k_s: k_s^2 = (alpha_s omega^2 + sqrt(alpha_s^2 omega^4 + 4 gamma_s omega^2)) / 2,
  alpha_s = rho / E, gamma_s = rho A / (E I).

Continuity of displacement and slope at the junction (eqs 4-5, for solution 1
symmetric: eqs 8-9) is a 2 x 2 homogeneous system in (A_s, A_c). The paper solves it
through the cost g = (Gamma_1 - Gamma_2)^2 (eqs 10-11), which has poles wherever
cos(k_s L/2) or sin(k_s L/2) vanishes, and between poles local minima that are not
zeros. Here the modes are the sign changes of the system's determinant, divided by
k_c k_s R so that it is O(1) and free of poles (a = k_s L/2, b = k_c pi/2,
r = k_c / (R k_s))::

    symmetric, even:   cos b sin a + r sin b cos a
    asymmetric, even:  sin b cos a + r cos b sin a
    symmetric, odd:    sin a sin b - r cos a cos b
    asymmetric, odd:   r sin a sin b - cos a cos b

It is sampled on a grid fine against the spacing of its roots, each sign change is
refined by Brent's method, and the order of each root is counted from the total phase
around the ring, k_s L + k_c pi = n pi (exact at r = 1, within 0.01 here). The cost g
itself is :meth:`RingResonator.cost` (its zeros are the same modes).

Degenerate crossings: the symmetric and asymmetric determinants differ by
(1 - r) sin(a - b) (even) or (1 - r) cos(a - b) (odd), so both vanish at one k_c only
when k_c is an integer j and a + b = n pi / 2, i.e. at L = (n - j) pi / k_s(j) for
j = 2 .. n - 1 (:meth:`RingResonator.crossings`). These are the coincidences of
seed 004, Fig. 2c.
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import brentq

from frictex.device.structures.beam import ModesError, check_positive

KINDS = ("symmetric", "asymmetric")
#: thickness over radius up to which the thin curved beam of eq 3 holds well (seed 004's
#: ring: 2.75 / 50 = 0.055); at h >= R the "ring" is a thick annulus (inner radius <= R/2)
THIN_RING_H_OVER_R = 0.1
#: determinant samples per pi of total phase around the ring (roots are 2 pi apart per family)
_SAMPLES_PER_PI = 16
_MAX_REFINEMENTS = 4


@dataclass(frozen=True)
class RingMode:
    """One flexural mode of the ring.

    order : number of wavelengths around the ring (even: solution 1, odd: solution 2).
    kind : "symmetric" (V_s = cos k_s x) or "asymmetric" (V_s = sin k_s x).
    k_c : curved-part wavenumber (1/rad); k_s_per_m : straight-part wavenumber (1/m).
    frequency_hz : natural frequency (Hz).
    """

    order: int
    kind: str
    k_c: float
    k_s_per_m: float
    frequency_hz: float

    @property
    def wavelength_mm(self) -> float:
        """Wavelength on the straight part, 2 pi / k_s (mm)."""
        return 2e3 * math.pi / self.k_s_per_m


@dataclass(frozen=True)
class RingResonator:
    """An oblong ring (seed 004, Fig. 2a): straights of length L, semicircles of radius R.

    Parameters
    ----------
    length_mm : float
        Length L of each straight part (mm).
    radius_mm : float
        Radius R of the semicircles (mm), measured to the neutral line.
    thickness_mm, width_mm : float
        Thickness h (bending across it) and width w (mm).
    youngs_gpa : float
        Young's modulus E (GPa).
    density_kg_m3 : float
        Density rho (kg/m^3).

    Examples
    --------
    Seed 004's design (aluminium 5052), its 24th-order pair:

    >>> ring = RingResonator(140, 50, 2.75, 30, 69, 2680)
    >>> [round(m.frequency_hz) for m in ring.pair(24)]
    [40287, 40294]
    """

    length_mm: float
    radius_mm: float
    thickness_mm: float
    width_mm: float
    youngs_gpa: float
    density_kg_m3: float

    def __post_init__(self):
        for name in ("length_mm", "radius_mm", "thickness_mm", "width_mm", "youngs_gpa",
                     "density_kg_m3"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))

    # -- dispersion (eqs 6-7) ----------------------------------------------

    def _constants(self) -> tuple[float, float, float, float]:
        """(alpha_s, gamma_s, alpha_c, gamma_c) of eqs 6-7, SI units."""
        e, rho = self.youngs_gpa * 1e9, self.density_kg_m3
        h, w, r = self.thickness_mm * 1e-3, self.width_mm * 1e-3, self.radius_mm * 1e-3
        area, inertia = w * h, w * h ** 3 / 12
        return rho / e, rho * area / (e * inertia), rho * area * r ** 4 / (e * inertia), rho * r * r / e

    def omega(self, k_c) -> np.ndarray:
        """Angular frequency (rad/s) of curved-part wavenumber ``k_c`` (1/rad, > 1): seed 004, eq 7."""
        _, _, alpha_c, gamma_c = self._constants()
        k2 = np.asarray(k_c, dtype=np.float64) ** 2
        return np.sqrt(k2 * (k2 - 1) ** 2 / (gamma_c * (k2 - 1) ** 2 + alpha_c * (k2 + 1)))

    def k_s(self, omega) -> np.ndarray:
        """Straight-part wavenumber (1/m) at angular frequency ``omega`` (rad/s): seed 004, eq 6."""
        alpha_s, gamma_s, _, _ = self._constants()
        w2 = np.asarray(omega, dtype=np.float64) ** 2
        return np.sqrt((alpha_s * w2 + np.sqrt(alpha_s ** 2 * w2 * w2 + 4 * gamma_s * w2)) / 2)

    def _angles(self, k_c):
        """(a, b, r) = (k_s L/2, k_c pi/2, k_c / (R k_s)) at ``k_c`` (> 1)."""
        k_c = np.asarray(k_c, dtype=np.float64)
        ks = self.k_s(self.omega(k_c))
        return ks * self.length_mm * 5e-4, k_c * math.pi / 2, k_c / (self.radius_mm * 1e-3 * ks)

    # -- the mode conditions (eqs 8-11) ------------------------------------

    def residual(self, k_c, kind: str, odd: bool) -> np.ndarray:
        """Pole-free determinant of the junction conditions (see the module docstring).

        Parameters
        ----------
        k_c : array_like, curved-part wavenumber (1/rad), > 1.
        kind : "symmetric" or "asymmetric".
        odd : False for solution 1 (even orders), True for solution 2 (odd orders).
        """
        a, b, r = self._angles(k_c)
        sa, ca, sb, cb = np.sin(a), np.cos(a), np.sin(b), np.cos(b)
        if kind == "symmetric":
            return sa * sb - r * ca * cb if odd else cb * sa + r * sb * ca
        return r * sa * sb - ca * cb if odd else sb * ca + r * cb * sa

    def cost(self, k_c, kind: str = "symmetric") -> np.ndarray:
        """The paper's cost g = (Gamma_1 - Gamma_2)^2 for solution 1 (seed 004, eqs 10-11).

        inf at its poles (where a Gamma's denominator vanishes). ``kind="asymmetric"`` uses
        the same construction on the asymmetric mode's junction conditions.
        """
        a, b, r = self._angles(k_c)
        with np.errstate(divide="ignore", invalid="ignore"):
            if kind == "symmetric":  # eq 10 as printed: Gamma = A_s / (A_c k_c)
                g1 = -np.cos(-b) / np.cos(a)
                g2 = -r * np.sin(-b) / np.sin(a)
            else:
                g1 = np.sin(-b) / np.sin(a)
                g2 = r * np.cos(-b) / np.cos(a)
            g = (g1 - g2) ** 2
        return np.where(np.isfinite(g), g, np.inf)

    def total_phase(self, k_c) -> np.ndarray:
        """k_s L + k_c pi (rad): pi times the order of a mode at ``k_c``."""
        k_c = np.asarray(k_c, dtype=np.float64)
        return self.k_s(self.omega(k_c)) * self.length_mm * 1e-3 + k_c * math.pi

    # -- mode finding ------------------------------------------------------

    def _k_c_at(self, frequency_hz: float) -> float:
        """The k_c > 1 whose eq 7 frequency is ``frequency_hz`` (omega(k_c) is increasing)."""
        target = 2 * math.pi * frequency_hz
        hi = 2.0
        while float(self.omega(hi)) < target:
            hi *= 2
        return brentq(lambda k: float(self.omega(k)) - target, 1.0, hi, xtol=1e-13, rtol=1e-15)

    def order_at(self, frequency_hz: float) -> float:
        """Total phase around the ring over pi at ``frequency_hz`` (> 0): the (fractional)
        order of a mode there."""
        return float(self.total_phase(self._k_c_at(frequency_hz))) / math.pi

    def modes_in_band(self, f_min_hz: float, f_max_hz: float) -> list[RingMode]:
        """Every mode (all four families) with f_min_hz <= frequency <= f_max_hz, by frequency.

        Raises :class:`ModesError` if the band is empty or malformed, or if the roots of a
        family cannot be separated (an order missing after refining the grid).
        """
        f_min_hz, f_max_hz = float(f_min_hz), float(f_max_hz)
        if not (math.isfinite(f_min_hz) and math.isfinite(f_max_hz) and 0 < f_min_hz < f_max_hz):
            raise ModesError(f"frequency band must satisfy 0 < min < max (Hz), got "
                             f"{f_min_hz!r} .. {f_max_hz!r}")
        k_lo, k_hi = self._k_c_at(f_min_hz), self._k_c_at(f_max_hz)
        span = float(self.total_phase(k_hi) - self.total_phase(k_lo)) / math.pi
        n = int(math.ceil(span * _SAMPLES_PER_PI)) + 2
        for _ in range(_MAX_REFINEMENTS):
            grid = np.linspace(k_lo, k_hi, n)
            families = [self._roots(kind, odd, grid) for kind in KINDS for odd in (False, True)]
            if all(_consecutive(modes, odd) for modes, odd in zip(families, (False, True) * 2)):
                found = [m for modes in families for m in modes]
                return sorted(found, key=lambda m: m.frequency_hz)
            n *= 4
        raise ModesError(f"ring modes between {f_min_hz:g} and {f_max_hz:g} Hz: could not "
                         f"separate the roots (orders found "
                         f"{[[m.order for m in modes] for modes in families]}); expected each "
                         f"family's orders to step by 2")

    def _roots(self, kind: str, odd: bool, grid: np.ndarray) -> list[RingMode]:
        values = self.residual(grid, kind, odd)
        change = np.flatnonzero(np.signbit(values[:-1]) != np.signbit(values[1:]))
        modes = []
        for i in change:
            k_c = brentq(lambda k: float(self.residual(k, kind, odd)), grid[i], grid[i + 1],
                         xtol=1e-14, rtol=4 * np.finfo(float).eps)
            order = int(round(float(self.total_phase(k_c)) / math.pi))
            omega = float(self.omega(k_c))
            modes.append(RingMode(order, kind, k_c, float(self.k_s(omega)), omega / (2 * math.pi)))
        return modes

    def pair(self, order: int) -> tuple[RingMode, RingMode]:
        """The (symmetric, asymmetric) modes of ``order`` (>= 2)."""
        order = _check_order(order)
        # order n has total phase n pi; search the k_c interval of phases (n -/+ 1/2) pi
        lo = self._k_c_at_phase((order - 0.5) * math.pi)
        hi = self._k_c_at_phase((order + 0.5) * math.pi)
        f_lo, f_hi = (float(self.omega(k)) / (2 * math.pi) for k in (lo, hi))
        if not 0 < f_lo < f_hi:  # k_c within rounding of 1, where omega is 0
            raise ModesError(
                f"ring order {order}: its frequency is 0 Hz to double precision at this "
                f"geometry (L {self.length_mm:g} mm, R {self.radius_mm:g} mm, h "
                f"{self.thickness_mm:g} mm); use a higher order, shorter straights or a "
                f"larger radius")
        found = {m.kind: m for m in self.modes_in_band(f_lo, f_hi) if m.order == order}
        missing = [k for k in KINDS if k not in found]
        if missing:
            raise ModesError(f"ring order {order}: no {' or '.join(missing)} mode found "
                             f"between {f_lo:.6g} and {f_hi:.6g} Hz")
        return found["symmetric"], found["asymmetric"]

    def _k_c_at_phase(self, phase: float) -> float:
        hi = 2.0
        while float(self.total_phase(hi)) < phase:
            hi *= 2
        return brentq(lambda k: float(self.total_phase(k)) - phase, 1.0, hi, xtol=1e-13)

    def crossings(self, order: int) -> list[float]:
        """Length-to-radius ratios L/R (R fixed) where the pair of ``order`` is exactly degenerate.

        L_j = (n - j) pi / k_s(omega(j)) for integer k_c = j in 2 .. n - 1 (module
        docstring); returned in increasing order.
        """
        _check_order(order)
        j = np.arange(2, int(order), dtype=np.float64)
        length_m = (order - j) * math.pi / self.k_s(self.omega(j))
        return sorted((length_m / (self.radius_mm * 1e-3)).tolist())

    def with_length(self, length_mm: float) -> "RingResonator":
        """The same ring with straights of ``length_mm``."""
        return replace(self, length_mm=length_mm)

    # -- shapes on the touch surface ---------------------------------------

    def straight_shape(self, mode: RingMode, x_mm) -> np.ndarray:
        """Transverse shape of ``mode`` on a straight part, unit amplitude (seed 004, Solution 1/2).

        Parameters
        ----------
        mode : a mode of this ring.
        x_mm : array_like, any shape; position from the straight's centre (mm), |x| <= L/2.

        Returns
        -------
        float64, shape of ``x_mm``: cos(k_s x) (symmetric) or sin(k_s x) (asymmetric).
        """
        kx = mode.k_s_per_m * 1e-3 * np.asarray(x_mm, dtype=np.float64)
        return np.cos(kx) if mode.kind == "symmetric" else np.sin(kx)


def _check_order(order) -> int:
    if isinstance(order, bool) or int(order) != order or order < 2:
        raise ModesError(f"ring mode order must be an integer >= 2 (wavelengths around the "
                         f"ring), got {order!r}")
    return int(order)


def _consecutive(modes: list[RingMode], odd: bool) -> bool:
    """True if a family's orders have its parity and step by 2 (no root missed or doubled)."""
    orders = [m.order for m in modes]
    return (all(o % 2 == int(odd) for o in orders)
            and all(b - a == 2 for a, b in zip(orders, orders[1:])))
