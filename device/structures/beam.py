"""Free-free beams: natural frequencies, wavelengths, mode shapes and nodes.

Seed 000 (eq 2, Table I) drives the 16th and 17th flexural modes of a free-free
aluminium beam, 350 x 6 x 6 mm. Two theories are offered:

- ``"euler-bernoulli"`` (seed 000, eq 2, the default): EI w'''' + rho A w_tt = 0.
- ``"timoshenko"``: adds shear deformation and rotary inertia, which matter once the
  wavelength is only a few thicknesses (seed 000: about 41 mm on a 6 mm beam)::

      rho A w_tt   = kappa G A (w'' - psi')
      rho I psi_tt = E I psi'' + kappa G A (w' - psi)

  with G = E / (2 (1 + nu)) and Cowper's shear coefficient for a rectangle,
  kappa = 10 (1 + nu) / (12 + 11 nu).

Both are solved the same way. At angular frequency omega the deflection is

    W(x) = a exp(-alpha x) + b exp(-alpha (L - x)) + c cos(beta x) + d sin(beta x)

with beta the propagating and alpha the evanescent wavenumber (alpha = beta for
Euler-Bernoulli). The textbook cosh/sinh form subtracts numbers of size e^{beta L}
(about 1e22 at mode 16) and loses every digit; in the exponential form every term is
bounded by 1, so the four free-end conditions (no moment, no shear at x = 0 and L) give
a 4 x 4 matrix with O(1) entries whose determinant is found to full precision by a
bracketed root search in beta L, one root in each interval [n pi, (n + 1) pi], and whose
null vector gives (a, b, c, d). For Euler-Bernoulli the roots are those of
cos(beta L) cosh(beta L) = 1.

Orders count flexural modes from the first bending mode (order 1: beta L = 4.730);
the two rigid-body modes are not counted. Mode n has n + 1 nodes.

Shapes are normalised to unit RMS over the length, (1/L) int_0^L W^2 dx = 1, with
W(0) > 0. Euler-Bernoulli modes are then orthonormal with weight 1/L (and |W| = 2 at
the free ends). Timoshenko modes are orthogonal only under the inner product
rho A W W + rho I Psi Psi, so their plain overlap is small but not zero.

Above the Timoshenko cutoff omega_c = sqrt(kappa G A / (rho I)) a second wave
propagates (the second spectrum); it is not modelled. The root search of an order stops
at the cutoff's wavenumber, so an order whose root lies below the cutoff is found even
when its interval [n pi, (n + 1) pi] reaches past it; an order with no root below the
cutoff raises :class:`ModesError`.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from frictex.device.errors import InputError
from frictex.device.jit import njit
from frictex.device.profile import THEORIES


#: Gauss-Legendre panels per wavelength for norms (20 nodes each: exact to round-off)
_PANELS_PER_WAVELENGTH = 8
_GAUSS_X, _GAUSS_W = np.polynomial.legendre.leggauss(20)
#: node search samples per wavelength before refinement
_NODE_SAMPLES_PER_WAVELENGTH = 40


#: Most modes one structure drives or one mode table holds: the modal inversion builds
#: (p, p) matrices, and 26 is the bound on a scene's ``orders`` too.
MAX_MODES = 26


#: Shortest flexural wavelength, in thicknesses, at which each theory holds. Theories
#: without shear (Euler-Bernoulli, and Kirchhoff for plates) read high as the wavelength
#: nears the thickness: on seed 000's beam, Euler-Bernoulli is 13.7 % above Timoshenko at
#: 6.7 thicknesses (mode 17) and 18 % at 5.7 (mode 20); Timoshenko follows the exact
#: elastic solution down to about 2.
VALID_WAVELENGTH_IN_THICKNESSES = {"euler-bernoulli": 6.0, "timoshenko": 2.0}
#: Below one thickness no bending theory holds: the wave no longer bends the section
#: but runs along the surfaces (Rayleigh-Lamb waves).
MIN_WAVELENGTH_IN_THICKNESSES = 1.0


class ModesError(InputError):
    """A structure, mode order or mode table that cannot be used; says which value and why.

    The one exception root of frictex's structures, modes and modal inversion
    (``device.structures.beam``, ``device.structures.plate2d``, ``device.structures.measured_modes``, ``device.actuation.modal``).
    """


def check_positive(name: str, value: float) -> float:
    """Return ``value`` as float if finite and > 0, else raise :class:`ModesError`."""
    v = float(value)
    if not (math.isfinite(v) and v > 0):
        raise ModesError(f"{name} must be a finite number > 0, got {value!r}")
    return v


def check_order(order) -> int:
    """Return ``order`` as int if it is an integer >= 1, else raise :class:`ModesError`."""
    if isinstance(order, bool) or int(order) != order or order < 1:
        raise ModesError(f"mode order must be an integer >= 1 (1 = first bending mode), "
                         f"got {order!r}")
    return int(order)


@dataclass(frozen=True)
class _Mode:
    beta: float       # propagating wavenumber (1/m)
    alpha: float      # evanescent wavenumber (1/m)
    omega: float      # angular frequency (rad/s)
    coef: tuple[float, float, float, float]  # (a, b, c, d), unit RMS


@dataclass(frozen=True)
class FreeFreeBeam:
    """A uniform free-free beam of rectangular cross-section.

    Parameters
    ----------
    length_mm, width_mm, thickness_mm : float
        Length L, width b and thickness h (mm); bending is across the thickness.
    youngs_gpa : float
        Young's modulus E (GPa).
    density_kg_m3 : float
        Density rho (kg/m^3).
    theory : {"euler-bernoulli", "timoshenko"}
        Beam theory (see the module docstring).
    poisson : float
        Poisson's ratio nu (used by Timoshenko's shear modulus), in (-1, 0.5).

    Examples
    --------
    Seed 000, Table I:

    >>> beam = FreeFreeBeam(350, 6, 6, 57, 2561)
    >>> round(beam.frequency_hz(16))
    28526
    """

    length_mm: float
    width_mm: float
    thickness_mm: float
    youngs_gpa: float
    density_kg_m3: float
    theory: str = "euler-bernoulli"
    poisson: float = 0.33

    def __post_init__(self):
        for name in ("length_mm", "width_mm", "thickness_mm", "youngs_gpa", "density_kg_m3"):
            object.__setattr__(self, name, check_positive(name, getattr(self, name)))
        if self.theory not in THEORIES:
            raise ModesError(f"beam theory must be one of {', '.join(THEORIES)}, "
                             f"got {self.theory!r}")
        nu = float(self.poisson)
        if not (math.isfinite(nu) and -1.0 < nu < 0.5):
            raise ModesError(f"poisson must be in (-1, 0.5), got {self.poisson!r}")
        object.__setattr__(self, "poisson", nu)

    # -- public API ---------------------------------------------------------

    def frequency_hz(self, order: int) -> float:
        """Natural frequency (Hz) of flexural mode ``order`` (1 = first bending mode)."""
        return _mode(self, check_order(order)).omega / (2 * math.pi)

    def wavelength_mm(self, order: int) -> float:
        """Flexural wavelength 2 pi / beta (mm) of mode ``order``."""
        return 2e3 * math.pi / _mode(self, check_order(order)).beta

    def shape(self, order: int, x_mm) -> np.ndarray:
        """Mode shape of ``order`` at positions ``x_mm``.

        Parameters
        ----------
        order : int
            Flexural mode order, >= 1.
        x_mm : array_like, any shape
            Positions along the beam (mm), 0 <= x <= L (not checked: outside the beam
            the formula extrapolates).

        Returns
        -------
        ndarray of float64, shape of ``x_mm``
            Deflection, unit RMS over the length ((1/L) int W^2 dx = 1), W(0) > 0.
        """
        return self.phi((order,), x_mm)[..., 0]

    def phi(self, orders, x_mm) -> np.ndarray:
        """Modal matrix: shapes of ``orders`` (p,) at ``x_mm`` (any shape) -> (..., p) float64."""
        modes = [_mode(self, check_order(o)) for o in orders]
        return _deflections(modes, np.asarray(x_mm, dtype=np.float64) * 1e-3, self.length_mm * 1e-3)

    def nodes_mm(self, order: int) -> np.ndarray:
        """All n + 1 node positions (mm, increasing) of mode ``order`` = n."""
        order = check_order(order)
        mode = _mode(self, order)
        length = self.length_mm * 1e-3
        n_samples = int(math.ceil(length * mode.beta / (2 * math.pi) * _NODE_SAMPLES_PER_WAVELENGTH)) + 2
        xs = np.linspace(0.0, length, n_samples)
        ws = _deflection(mode, xs, length)
        change = np.flatnonzero(np.signbit(ws[:-1]) != np.signbit(ws[1:]))
        from scipy.optimize import brentq  # beam scenes only: scipy's import is 0.3-0.6 s
        nodes = [brentq(lambda x: float(_deflection(mode, np.float64(x), length)),
                        xs[i], xs[i + 1], xtol=1e-15, rtol=4 * np.finfo(float).eps)
                 for i in change]
        return np.array(nodes) * 1e3

    @property
    def cutoff_hz(self) -> float:
        """Timoshenko cutoff frequency sqrt(kappa G A / (rho I)) / 2 pi (Hz); inf for Euler-Bernoulli."""
        if self.theory == "euler-bernoulli":
            return math.inf
        e, kg, rho, r2 = self._constants()
        return math.sqrt(kg / (rho * r2)) / (2 * math.pi)

    # -- internals ----------------------------------------------------------

    def _constants(self) -> tuple[float, float, float, float]:
        """(E, kappa G, rho, r^2 = I/A) in SI units; kappa G = inf for Euler-Bernoulli."""
        e = self.youngs_gpa * 1e9
        h = self.thickness_mm * 1e-3
        if self.theory == "euler-bernoulli":
            kg = math.inf
        else:
            nu = self.poisson
            kappa = 10 * (1 + nu) / (12 + 11 * nu)
            kg = kappa * e / (2 * (1 + nu))
        return e, kg, self.density_kg_m3, h * h / 12

    def _cutoff_beta(self) -> float:
        """Propagating wavenumber (1/m) at which the flexural branch reaches the cutoff
        omega_c; inf for Euler-Bernoulli.

        omega_c^2 = kappa G / (rho r^2) is the lower root of the dispersion quadratic
        (:meth:`_dispersion`) where beta^2 = (1 + kappa G / E) / r^2.
        """
        e, kg, _, r2 = self._constants()
        return math.sqrt((1 + kg / e) / r2)

    def _dispersion(self, beta: float) -> tuple[float, float, float]:
        """(omega, alpha, q) of the flexural branch with propagating wavenumber ``beta``
        (1/m, below :meth:`_cutoff_beta`).

        q = rho omega^2 / (kappa G) (0 for Euler-Bernoulli) enters the end conditions.
        """
        e, kg, rho, r2 = self._constants()
        if math.isinf(kg):
            return beta * beta * math.sqrt(e * r2 / rho), beta, 0.0
        # omega^2 solves (rho^2/(E kG)) W^2 - a1 W + beta^4 = 0; the lower root, written
        # without cancellation.
        a1 = beta * beta * rho * (1 / e + 1 / kg) + rho / (e * r2)
        a2 = rho * rho / (e * kg)
        w2 = 2 * beta ** 4 / (a1 + math.sqrt(a1 * a1 - 4 * a2 * beta ** 4))
        below_cutoff = 1 - rho * r2 * w2 / kg
        alpha = math.sqrt(rho * w2 * below_cutoff / (e * r2)) / beta
        return math.sqrt(w2), alpha, rho * w2 / kg

    def _end_matrix(self, beta: float) -> np.ndarray:
        """Free-end conditions (moment, shear at 0 and L) on (a, b, c, d), entries O(1)."""
        _, alpha, q = self._dispersion(beta)
        length = self.length_mm * 1e-3
        ea = math.exp(-alpha * length)
        cl, sl = math.cos(beta * length), math.sin(beta * length)
        # moment ~ (k^2 + q) and shear ~ -1/k per exp(k x); rows scaled by 1/beta^2 and beta
        m_e = (alpha * alpha + q) / (beta * beta)
        m_t = (q - beta * beta) / (beta * beta)
        v_e = beta / alpha
        return np.array([
            [m_e, m_e * ea, m_t, 0.0],
            [v_e, -v_e * ea, 0.0, 1.0],
            [m_e * ea, m_e, m_t * cl, m_t * sl],
            [v_e * ea, -v_e, -sl, cl],
        ])


def _deflection(mode: _Mode, x_m: np.ndarray, length_m: float) -> np.ndarray:
    """W(x) of one mode at ``x_m`` (m, any shape; module docstring)."""
    return _deflections((mode,), x_m, length_m)[..., 0]


def _deflections(modes, x_m, length_m: float) -> np.ndarray:
    """W(x) of each of ``modes`` (p) at ``x_m`` (m, any shape) -> (..., p).

    Two compiled passes around one ``np.exp`` of every exponent: numpy's SIMD exp
    differs from libm's in the last bit for a few % of arguments, and these are the
    values numpy has always given here. numpy's float64 sin and cos are libm's, which
    the compiled pass calls too (tests/test_modal_kernels.py checks both bit for bit).
    """
    x = np.asarray(x_m, dtype=np.float64)
    flat = x.reshape(-1)
    exps = np.exp(_exponents(flat, np.array([m.alpha for m in modes]), length_m))
    out = _combine(flat, np.array([m.beta for m in modes]), np.array([m.coef for m in modes]), exps)
    return out.reshape(x.shape + (len(modes),))


@njit(cache=True, nogil=True)
def _exponents(x, alpha, length):
    """(2p, N): -alpha x and -alpha (L - x) of each mode."""
    out = np.empty((2 * alpha.size, x.size))
    for k in range(alpha.size):
        neg = -alpha[k]
        for i in range(x.size):
            out[2 * k, i] = neg * x[i]
            out[2 * k + 1, i] = neg * (length - x[i])
    return out


@njit(cache=True, nogil=True)
def _combine(x, beta, coef, exps):
    """(N, p): a e^(-alpha x) + b e^(-alpha (L - x)) + c cos(beta x) + d sin(beta x),
    summed in that order, from the exponentials ``exps`` of :func:`_exponents`; a
    position equal to the one before (same bits) copies its row."""
    out = np.empty((x.size, beta.size))
    for k in range(beta.size):
        a, b, c, d = coef[k, 0], coef[k, 1], coef[k, 2], coef[k, 3]
        for i in range(x.size):
            if i > 0 and x[i] == x[i - 1] and math.copysign(1.0, x[i]) == math.copysign(1.0, x[i - 1]):
                out[i, k] = out[i - 1, k]  # a finger held still: sin and cos are most of the cost
                continue
            bx = beta[k] * x[i]
            out[i, k] = (a * exps[2 * k, i] + b * exps[2 * k + 1, i]
                         + c * math.cos(bx) + d * math.sin(bx))
    return out


@lru_cache(maxsize=4096)
def _mode(beam: FreeFreeBeam, order: int) -> _Mode:
    length = beam.length_mm * 1e-3
    # one root of the end-condition determinant in each beta L interval [n pi, (n+1) pi]
    lo, hi = order * math.pi * (1 + 1e-12), (order + 1) * math.pi * (1 - 1e-12)

    def det(beta_l: float) -> float:
        return float(np.linalg.det(beam._end_matrix(beta_l / length)))

    cutoff_l = beam._cutoff_beta() * length * (1 - 1e-12)
    if cutoff_l < hi:  # the branch ends inside the interval: search below the cutoff only
        hi = cutoff_l
        if not (lo < hi and np.signbit(det(lo)) != np.signbit(det(hi))):
            raise ModesError(f"mode order {order} is above the Timoshenko cutoff "
                             f"{beam.cutoff_hz:.6g} Hz of this beam: it has no flexural mode "
                             "of that order below it (second spectrum not modelled); use a "
                             "lower order or --theory euler-bernoulli")
    from scipy.optimize import brentq  # beam scenes only: scipy's import is 0.3-0.6 s
    beta_l = brentq(det, lo, hi, xtol=1e-14, rtol=4 * np.finfo(float).eps)
    beta = beta_l / length
    omega, alpha, _ = beam._dispersion(beta)
    coef = np.linalg.svd(beam._end_matrix(beta))[2][-1]
    raw = _Mode(beta, alpha, omega, tuple(coef))
    # unit RMS by composite Gauss-Legendre; panels short against both 1/alpha and 1/beta
    n_panels = int(math.ceil(length * max(beta, alpha) / (2 * math.pi) * _PANELS_PER_WAVELENGTH))
    edges = np.linspace(0.0, length, n_panels + 1)
    half = np.diff(edges)[:, None] / 2
    xs = (edges[:-1, None] + half * (1 + _GAUSS_X)).ravel()
    ws = (half * _GAUSS_W).ravel()
    rms = math.sqrt(float(np.sum(ws * _deflection(raw, xs, length) ** 2)) / length)
    scale = math.copysign(1.0 / rms, float(_deflection(raw, np.float64(0.0), length)))
    return _Mode(beta, alpha, omega, tuple(float(v) * scale for v in coef))
