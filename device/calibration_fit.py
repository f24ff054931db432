"""Fit seed 003's friction model to measured points, or tabulate them where it does not fit.

A point is (w, F_n, mu'): plate amplitude (um), normal force (N), measured relative
friction. Seed 003, eq 2: ``mu'(w) = (1 - k F_n) exp(-b w) + k F_n``; the fit finds
(b, k) by bounded least squares. If its residual RMS stays above ``MODEL_TOLERANCE``
the model does not describe this plate and finger, and :func:`fit_points` also builds a
calibration table (``device.profile.Calibration``) from the points: one column per
measured amplitude (the protocol's levels, however few points each has), or bins of
neighbouring amplitudes where there are more than ``TABLE_BINS`` of them; one row at the
points' median force, made strictly decreasing.

:func:`device_toml` writes the result as the ``[device]`` section of a texture file
(the grammar of ``textures.loader``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.optimize import least_squares

from frictex.device.errors import InputError
from frictex.device.friction import forward_mu
from frictex.device.calibration_identity import toml_lines
from frictex.device.profile import DEFAULT_PROFILE, Calibration, FittedOn, FrictionParams

#: residual RMS (mu') above which the closed-form model is said not to fit
MODEL_TOLERANCE = 0.02
#: bounds of the fit: b (1/um), k (1/N)
B_BOUNDS = (0.05, 20.0)
K_BOUNDS = (0.0, 5.0)
#: most amplitude columns of a calibration table, besides amplitude 0
TABLE_BINS = 12
#: least distinct amplitudes above 0 a fit takes: two determine (b, k) at one normal
#: force, a third checks that the model fits
MIN_AMPLITUDES = 3
#: least fall of the fitted mu' from 0 um to the largest amplitude that determines b:
#: below it the curve is within a few times the model's tolerance of flat, so any b fits
MIN_FALL = 2.5 * MODEL_TOLERANCE


def model_jacobian(w_um, normal_n, b_per_um: float, k_per_n: float) -> np.ndarray:
    """d mu' / d(b, k) of seed 003, eq 2, shape (n, 2); arrays (n,)."""
    e = np.exp(-b_per_um * w_um)
    return np.stack([-(1.0 - k_per_n * normal_n) * w_um * e, normal_n * (1.0 - e)], axis=1)


@dataclass(frozen=True)
class Fit:
    """A fit's outcome: the constants, the residual RMS (mu') and the point count;
    ``calibration`` is a table when the model does not fit (else None)."""

    params: FrictionParams
    residual_rms: float
    n_points: int
    calibration: Calibration | None = None

    @property
    def fits(self) -> bool:
        return self.residual_rms <= MODEL_TOLERANCE


def fit_points(w_um, normal_n, mu, start: FrictionParams = FrictionParams()) -> Fit:
    """Least-squares (b, k) of seed 003, eq 2 on the points; arrays (n,), at least
    ``MIN_AMPLITUDES`` distinct amplitudes above 0 um among them.

    Raises InputError (a ValueError) when the usable (finite) points have fewer distinct
    amplitudes above 0 (they cannot determine both b and k and check the fit), or when
    the fitted mu' falls by less than ``MIN_FALL`` (a flat curve: every b fits it).
    """
    w, f, m = (np.asarray(a, dtype=np.float64).ravel() for a in (w_um, normal_n, mu))
    good = np.isfinite(w) & np.isfinite(f) & np.isfinite(m) & (w >= 0) & (f > 0)
    w, f, m = w[good], f[good], m[good]
    amplitudes = np.unique(w[w > 0]).size
    if amplitudes < MIN_AMPLITUDES:
        raise InputError(f"{w.size} usable calibration points at {amplitudes} distinct "
                         f"amplitudes above 0 um: expected at least {MIN_AMPLITUDES} (two "
                         f"determine b and k, a third checks the fit)")

    def residual(theta):
        return forward_mu(w, f, FrictionParams(theta[0], theta[1])) - m

    def jac(theta):
        return model_jacobian(w, f, theta[0], theta[1])

    x0 = np.clip([start.b_per_um, start.asymptote_per_n],
                 [B_BOUNDS[0], K_BOUNDS[0]], [B_BOUNDS[1], K_BOUNDS[1]])
    sol = least_squares(residual, x0, jac=jac, bounds=([B_BOUNDS[0], K_BOUNDS[0]],
                                                       [B_BOUNDS[1], K_BOUNDS[1]]))
    params = FrictionParams(b_per_um=float(sol.x[0]), asymptote_per_n=float(sol.x[1]))
    rms = float(np.sqrt(np.mean(sol.fun ** 2)))
    force = np.array([np.median(f)])
    fall = float((forward_mu(np.zeros(1), force, params)
                  - forward_mu(np.array([w.max()]), force, params))[0])
    if fall < MIN_FALL:
        raise InputError(f"the fitted mu' falls by only {fall:.3f} from 0 to {w.max():.3g} um "
                         f"({w.size} calibration points): the finger's friction did not "
                         f"fall with vibration, so no b fits better than another; is the "
                         f"plate vibrating and the finger pressing? (a fit needs a fall of "
                         f"{MIN_FALL:.2f} or more)")
    table = None if rms <= MODEL_TOLERANCE else _table(w, f, m)
    return Fit(params=params, residual_rms=rms, n_points=int(w.size), calibration=table)


def _table(w: np.ndarray, f: np.ndarray, m: np.ndarray) -> Calibration:
    """One-row table at the median force: mean mu' per amplitude column, strictly
    decreasing; a column per distinct amplitude above 0 (um), or per run of neighbouring
    amplitudes where there are more than ``TABLE_BINS`` of them."""
    vibrating = w > 0
    levels, level_of = np.unique(w[vibrating], return_inverse=True)
    centres, means = [0.0], [1.0]
    for run in np.array_split(np.arange(levels.size), min(TABLE_BINS, levels.size)):
        inside = np.isin(level_of, run)
        centres.append(float(w[vibrating][inside].mean()))
        means.append(float(m[vibrating][inside].mean()))
    mu = np.minimum.accumulate(np.clip(means, 1e-3, 1.0))
    mu = mu - 1e-6 * np.arange(mu.size)  # strictly decreasing, as the table format asks
    return Calibration(amplitudes_um=tuple(centres), forces_n=(float(np.median(f)),),
                       mu=(tuple(float(x) for x in mu),))


def device_toml(fit: Fit, amplitude_limit_um: float, normal_force_n: float,
                profile: str = DEFAULT_PROFILE, fitted: FittedOn | None = None) -> str:
    """The ``[device]`` section (text) a texture file can use for this calibration, with
    what it was ``fitted`` on (``[device.fitted]``: ``device.calibration_identity``)."""
    lines = ["[device]", f'profile = "{profile}"',
             f"amplitude_limit_um = {amplitude_limit_um:.6g}",
             f"normal_force_n = {normal_force_n:.6g}",
             f"[device.friction]        # seed 003 eq 2, fitted: residual RMS {fit.residual_rms:.4f} "
             f"over {fit.n_points} points",
             f"b_per_um = {fit.params.b_per_um:.6g}",
             f"asymptote_per_n = {fit.params.asymptote_per_n:.6g}"]
    if fitted is not None:
        lines += toml_lines(fitted)
    if fit.calibration is not None:
        cal = fit.calibration
        lines += ["[device.calibration]     # the model does not fit: measured table",
                  "amplitudes_um = [" + ", ".join(f"{a:.6g}" for a in cal.amplitudes_um) + "]",
                  "forces_n = [" + ", ".join(f"{x:.6g}" for x in cal.forces_n) + "]",
                  "mu = [" + ", ".join("[" + ", ".join(f"{x:.8g}" for x in row) + "]"
                                       for row in cal.mu) + "]"]
    return "\n".join(lines) + "\n"
