"""Fit seed 003's friction model to measured points, or tabulate them where it does not fit.

A point is (w, F_n, mu'): plate amplitude (um), normal force (N), measured relative
friction. Seed 003, eq 2: ``mu'(w) = (1 - k F_n) exp(-b w) + k F_n``; the fit finds
(b, k) by bounded least squares, with standard errors from its Jacobian (the points'
scatter only: they leave out the sweep's systematic errors, so sixteen simulated sweeps,
fingers 0-15, landed 0.5 to 16 of them from the true b, 0.04 to 4.2 % of it: the finger's
moisture drifts over the sweep, which eq 2 does not model). Points that are not finite, at a negative amplitude
or without a normal force (F_n <= 0) are left out and counted (:attr:`Fit.n_dropped`). The model is not accepted where the solver did not converge or
its residual RMS is above ``MODEL_CEILING``, whatever the residuals' pattern; otherwise it
is said not to fit this plate and finger only when its residual RMS is above
``MODEL_TOLERANCE`` *and* the residuals are not noise: their signs, in order of amplitude,
form fewer runs than independent noise would (Wald-Wolfowitz runs test, p below
``LACK_OF_FIT_P``). Noise alone (sd 0.03 on exact eq-2 points) raises the RMS above the
tolerance in most sweeps, and a table then fits the noise worse than the model does. With
few amplitudes the runs test cannot reach ``LACK_OF_FIT_P`` whatever the residuals (its
smallest p is 0.2 at 5 amplitudes, 0.057 at 7): there the RMS alone judges the fit
(:attr:`Fit.judged_by`), so a clear misfit at 3 to 7 amplitudes still gets a table. Where
the model is not accepted, :func:`fit_points` also builds a calibration table
(``device.profile.Calibration``) from the points: one column per measured amplitude (the
protocol's levels, however few points each has), or bins of neighbouring amplitudes where
there are more than ``TABLE_BINS`` of them; one row at the points' median force, the
decreasing (isotonic) regression of the columns' means, so no single noisy point pulls
the columns after it down.

A fit that stops on a bound of b or k, or whose standard error of a constant exceeds the
constant (:attr:`Fit.notes`), does not determine that constant: points of b = 30 /um give
b = 20 /um, the upper bound, with a residual of 0.005; amplitudes given in nm leave b at
its start with a standard error of 1e133 or more (infinite where J^T J is singular to
rounding). k = 0 is the exception: friction that does not depend on the normal force, a
physical value the fit can reach, not a limit of the fit. A b the points do not determine
(off its bounds) is not accepted as the model (:attr:`Fit.judged_by` ``"b undetermined"``):
noisy points jittered a few nm about one amplitude get a table, not an exponent fitted to
the jitter. Amplitudes within ``AMPLITUDE_RESOLUTION_UM`` (1 nm) of each other count as one.

A fitted curve that does not fall is a failed run (exit 1), not bad input: the plate did
not vibrate, or the finger pressed so hard that k F_n reached 1, where eq 2 is flat. The
fit starts from seed 003's k, or from a smaller k where that puts k F_n above
``START_ASYMPTOTE`` at the points' largest force: a start where eq 2 is flat left the
solver where it began, so a firm press (1.15 N or more) whose friction fell was refused.

:func:`device_toml` writes the result as the ``[device]`` section of a texture file
(the grammar of ``textures.loader``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np
from scipy.optimize import isotonic_regression, least_squares
from scipy.special import gammaln, logsumexp

from frictex.device.errors import InputError, RunFailed
from frictex.device.friction import forward_mu
from frictex.device.calibration_identity import B_BOUNDS, K_BOUNDS, toml_lines
from frictex.device.profile import DEFAULT_PROFILE, Calibration, FittedOn, FrictionParams

#: residual RMS (mu') at or below which the model fits, whatever its residuals' pattern
MODEL_TOLERANCE = 0.02
#: residual RMS (mu') above which the model is not accepted, whatever its residuals'
#: pattern: above the RMS that a sensor's noise of sd 0.03 leaves on 12 amplitudes (0.026
#: median, 0.048 the most in 500 sweeps); points shuffled out of their fall give 0.093
MODEL_CEILING = 0.06
#: runs-test p-value below which residuals above the tolerance are taken for a misfit
LACK_OF_FIT_P = 0.05
#: most amplitude columns of a calibration table, besides amplitude 0
TABLE_BINS = 12
#: least distinct amplitudes above 0 a fit takes: two determine (b, k) at one normal
#: force, a third checks that the model fits (by the residual RMS alone below 8
#: amplitudes, where the runs test cannot reach ``LACK_OF_FIT_P``)
MIN_AMPLITUDES = 3
#: amplitudes (um) closer than this count as one: eq 2's slope |d mu'/dw| is at most b, and
#: b at most ``B_BOUNDS``' 20 /um, so across 1 nm mu' changes by less than
#: ``MODEL_TOLERANCE`` whatever b; four counts of the wire's amplitude (``AMPLITUDE_STEP_UM``)
AMPLITUDE_RESOLUTION_UM = MODEL_TOLERANCE / B_BOUNDS[1]
#: least fall of the fitted mu' from 0 um to the largest amplitude that determines b:
#: below it the curve is within a few times the model's tolerance of flat, so any b fits
MIN_FALL = 2.5 * MODEL_TOLERANCE
#: largest k F_n the fit starts from: a start k whose k F_n reaches 1 at some point puts eq 2
#: at its edge there, flat in b and k, and the solver does not move (seed 003's k 1.13 /N
#: does so from 0.885 N); the fit starts from k = this / the points' largest force where
#: the given start's k F_n is above it
START_ASYMPTOTE = 0.9
#: median normal force (N) above which a flat curve is put down to a press too hard: at
#: seed 003's k (1.13 /N) k F_n is 0.9 at 0.8 N, leaving eq 2 a fall of 0.1 at most
HARD_PRESS_N = 0.8


def model_jacobian(w_um, normal_n, b_per_um: float, k_per_n: float) -> np.ndarray:
    """d mu' / d(b, k) of seed 003, eq 2, shape (n, 2); arrays (n,)."""
    e = np.exp(-b_per_um * w_um)
    return np.stack([-(1.0 - k_per_n * normal_n) * w_um * e, normal_n * (1.0 - e)], axis=1)


@dataclass(frozen=True)
class Fit:
    """A fit's outcome: the constants, their standard errors (``b_se`` 1/um, ``k_se``
    1/N), the residual RMS (mu'), the point count and the count of points left out (not
    finite, a negative amplitude or no normal force: ``n_dropped``), the solver's status and message (``least_squares``: above 0
    where it converged), the runs test's p-value of the
    residuals (:func:`few_runs_p`) and the smallest p-value it could have given with the
    residuals' counts of signs (``runs_least_p``), and the bounds the fit stopped on
    (``at_bound``: e.g. ``("b", "upper")``); ``calibration`` is a table when the model
    does not fit (else None)."""

    params: FrictionParams
    residual_rms: float
    n_points: int
    calibration: Calibration | None = None
    b_se: float = 0.0
    k_se: float = 0.0
    runs_p: float = 1.0
    runs_least_p: float = 0.0
    at_bound: tuple[tuple[str, str], ...] = ()
    n_dropped: int = 0
    solver_status: int = 1
    solver_message: str = ""

    @property
    def judged_by(self) -> str:
        """The rule that judged the fit: ``"solver"`` where it did not converge, ``"RMS
        ceiling"`` where the residual RMS is above ``MODEL_CEILING``, ``"b undetermined"``
        where the points do not determine b (:attr:`undetermined`), ``"RMS"`` where it is
        within ``MODEL_TOLERANCE`` or the runs test could not reach ``LACK_OF_FIT_P`` (too
        few amplitudes), else ``"runs test"``."""
        if self.solver_status <= 0:
            return "solver"
        if not self.residual_rms <= MODEL_CEILING:
            return "RMS ceiling"
        if "b" in self.undetermined:
            return "b undetermined"
        runs_can_reject = self.runs_least_p < LACK_OF_FIT_P
        return "runs test" if self.residual_rms > MODEL_TOLERANCE and runs_can_reject else "RMS"

    @property
    def fits(self) -> bool:
        judge = self.judged_by
        if judge == "RMS":
            return self.residual_rms <= MODEL_TOLERANCE
        if judge == "runs test":
            return self.runs_p >= LACK_OF_FIT_P
        return False

    @property
    def misfit_reason(self) -> str:
        """Why the model does not fit, by the rule that judged it (one clause)."""
        if self.judged_by == "solver":
            return f"the fit did not converge: {self.solver_message}"
        if self.judged_by == "b undetermined":
            return (f"the points do not determine b: b = {self.params.b_per_um:.4g} /um with "
                    f"a standard error of {self.b_se:.2g} /um")
        if self.judged_by == "RMS ceiling":
            return (f"residual RMS {self.residual_rms:.3f} above the ceiling "
                    f"{MODEL_CEILING:g}, beyond noise whatever its pattern")
        if self.judged_by == "runs test":
            return (f"its residuals run in long stretches on one side of the curve, runs "
                    f"test p {self.runs_p:.3f}")
        return (f"residual RMS {self.residual_rms:.3f} above the tolerance "
                f"{MODEL_TOLERANCE:g}; too few amplitudes for the runs test, whose smallest "
                f"p here is {self.runs_least_p:.2g}")

    @property
    def bound_notes(self) -> list[str]:
        """One line per constant the fit stopped on a bound of: what the points say of it."""
        limits = {"b": (B_BOUNDS, "/um"), "k": (K_BOUNDS, "/N")}
        notes = []
        for name, side in self.at_bound:
            (low, high), unit = limits[name]
            value = high if side == "upper" else low
            if (name, side) == ("k", "lower"):
                notes.append(f"k is {value:g} /N, its physical limit: the finger's friction "
                             f"does not depend on the normal force, to within k's standard "
                             f"error {self.k_se:.2g} /N")
                continue
            notes.append(f"{name} stopped on its {side} bound {value:g} {unit}: the best fit "
                         f"lies beyond it, so the points do not determine {name} (its value "
                         f"and standard error are not estimates)")
        return notes

    @property
    def undetermined(self) -> tuple[str, ...]:
        """The constants, of those the fit did not stop on a bound of, whose standard error
        exceeds their value: the points do not determine them."""
        on_bound = {name for name, _ in self.at_bound}
        return tuple(name for name, (value, se, _) in self._estimates.items()
                     if name not in on_bound and not se <= abs(value))

    @property
    def _estimates(self) -> dict[str, tuple[float, float, str]]:
        """Each constant's value, standard error and unit."""
        return {"b": (self.params.b_per_um, self.b_se, "/um"),
                "k": (self.params.asymptote_per_n, self.k_se, "/N")}

    @property
    def notes(self) -> list[str]:
        """:attr:`bound_notes`, then one line per constant in :attr:`undetermined`."""
        estimates = self._estimates
        return self.bound_notes + [
            f"{name} = {value:.4g} {unit} with a standard error of {se:.2g} {unit}, more than "
            f"its value: the points do not determine {name} (are the amplitudes in um and "
            f"the forces in N?)"
            for name in self.undetermined for value, se, unit in [estimates[name]]]


def usable_points(w_um: np.ndarray, normal_n: np.ndarray, mu: np.ndarray) -> np.ndarray:
    """bool, the calibration points :func:`fit_points` fits (the others it leaves out):
    every value finite, an amplitude (um) of at least 0 and a normal force (N) above 0."""
    finite = np.isfinite(w_um) & np.isfinite(normal_n) & np.isfinite(mu)
    return finite & (w_um >= 0) & (normal_n > 0)


def fit_points(w_um, normal_n, mu, start: FrictionParams = FrictionParams()) -> Fit:
    """Least-squares (b, k) of seed 003, eq 2 on the points; arrays (n,), at least
    ``MIN_AMPLITUDES`` distinct amplitudes above 0 um among them.

    Points that are not finite, at an amplitude below 0 or a normal force of 0 or less
    are left out, counted in :attr:`Fit.n_dropped`. Raises
    InputError (a ValueError) when the arrays' lengths differ, or when the usable points
    have fewer distinct amplitudes above 0, amplitudes within ``AMPLITUDE_RESOLUTION_UM``
    counting as one (they cannot determine both b and k and check the fit), and RunFailed
    when the
    fitted mu' falls by less than ``MIN_FALL`` (a flat curve: every b fits it).
    ``start`` is the solver's first (b, k), its k lowered to ``START_ASYMPTOTE`` over the
    points' largest force (N) where it is above that.
    """
    w, f, m = (np.asarray(a, dtype=np.float64).ravel() for a in (w_um, normal_n, mu))
    if not w.size == f.size == m.size:
        raise InputError(f"calibration points: {w.size} amplitudes, {f.size} normal forces "
                         f"and {m.size} values of mu': expected one of each per point")
    good = usable_points(w, f, m)
    w, f, m = w[good], f[good], m[good]
    amplitudes = np.unique(_levels(w[w > 0])).size
    if amplitudes < MIN_AMPLITUDES:
        raise InputError(f"{w.size} usable calibration points at {amplitudes} distinct "
                         f"amplitudes above 0 um (within {AMPLITUDE_RESOLUTION_UM * 1e3:g} nm "
                         f"count as one): expected at least {MIN_AMPLITUDES} (two determine "
                         f"b and k, a third checks the fit)")

    def residual(theta):
        return forward_mu(w, f, FrictionParams(theta[0], theta[1])) - m

    def jac(theta):
        return model_jacobian(w, f, theta[0], theta[1])

    lower, upper = [B_BOUNDS[0], K_BOUNDS[0]], [B_BOUNDS[1], K_BOUNDS[1]]
    start_k = min(start.asymptote_per_n, START_ASYMPTOTE / f.max())
    x0 = np.clip([start.b_per_um, start_k], lower, upper)
    sol = least_squares(residual, x0, jac=jac, bounds=(lower, upper))
    # the solver stays strictly inside its bounds (k 6.8e-10 for k = 0): one it stopped
    # on is the bound itself
    theta = np.where(sol.active_mask < 0, lower, np.where(sol.active_mask > 0, upper, sol.x))
    params = FrictionParams(b_per_um=float(theta[0]), asymptote_per_n=float(theta[1]))
    rms = float(np.sqrt(np.mean(sol.fun ** 2)))
    _check_fall(w, f, params)
    b_se, k_se = standard_errors(sol.jac, sol.fun)
    at_bound = tuple((name, "lower" if side < 0 else "upper")
                     for name, side in zip("bk", sol.active_mask) if side != 0)
    signs = _residual_signs(w, sol.fun)
    fit = Fit(params=params, residual_rms=rms, n_points=int(w.size), b_se=b_se, k_se=k_se,
              runs_p=few_runs_p(signs), runs_least_p=few_runs_p(np.sort(signs)),
              at_bound=at_bound, n_dropped=int(np.count_nonzero(~good)),
              solver_status=int(sol.status), solver_message=str(sol.message))
    if fit.fits:
        return fit
    return replace(fit, calibration=_table(w, f, m))


def _check_fall(w: np.ndarray, f: np.ndarray, params: FrictionParams) -> None:
    """Raise RunFailed when the fitted mu' falls by less than ``MIN_FALL`` from 0 um to
    the largest amplitude, at the points' median force."""
    force = np.array([np.median(f)])
    fall = float((forward_mu(np.zeros(1), force, params)
                  - forward_mu(np.array([w.max()]), force, params))[0])
    if fall < MIN_FALL:
        raise RunFailed(f"the fitted mu' falls by only {fall:.3f} from 0 to {w.max():.3g} um "
                        f"({w.size} calibration points): the finger's friction did not fall "
                        f"with vibration, so no b fits better than another; "
                        f"{_flat_hint(float(force[0]))} (a fit needs a fall of "
                        f"{MIN_FALL:.2f} or more)")


def _flat_hint(force_n: float) -> str:
    """What to try when the fitted curve is flat at median normal force ``force_n`` (N)."""
    if force_n > HARD_PRESS_N:
        k = FrictionParams().asymptote_per_n
        return (f"the finger pressed {force_n:.2g} N, too hard: k F_n reaches 1 near "
                f"{1 / k:.2g} N at seed 003's k {k:g} /N, where eq 2 is flat; press lighter, "
                f"about 0.5 N")
    return "is the plate vibrating and the finger pressing?"


def standard_errors(jacobian: np.ndarray, residuals: np.ndarray) -> tuple[float, float]:
    """Standard errors of (b, k) (1/um, 1/N): the square roots of the diagonal of
    s^2 (J^T J)^-1, s^2 the residual variance over n - 2 degrees of freedom; inf where
    J^T J is singular (a constant the points do not determine) or where there are 2
    points or fewer (they fit exactly, leaving no residual to measure the noise by). A
    J^T J singular to rounding may invert to infinite, not-a-number or negative entries
    instead of raising: those variances give inf too."""
    dof = residuals.size - 2
    if dof < 1:
        return math.inf, math.inf
    # mu' (about 1) is known to within its rounding: exact points leave that, not 0, so a
    # constant they do not determine keeps its huge variance instead of 0 times it
    s2 = max(float(residuals @ residuals) / dof, np.finfo(np.float64).eps ** 2)
    try:
        inverse = np.linalg.inv(jacobian.T @ jacobian)
    except np.linalg.LinAlgError:
        return math.inf, math.inf
    b_var, k_var = s2 * np.diag(inverse)
    return tuple(math.sqrt(var) if 0.0 < var < math.inf else math.inf for var in (b_var, k_var))


def _levels(w: np.ndarray) -> np.ndarray:
    """Each amplitude's level, 0, 1, ... in order of amplitude: one within
    ``AMPLITUDE_RESOLUTION_UM`` of the next smaller amplitude shares its level."""
    order = np.argsort(w, kind="stable")
    level_of = np.empty(w.size, dtype=np.intp)
    level_of[order] = np.cumsum(np.diff(w[order], prepend=w[order][:1])
                                >= AMPLITUDE_RESOLUTION_UM)
    return level_of


def _residual_signs(w: np.ndarray, residuals: np.ndarray) -> np.ndarray:
    """Signs (+1/-1) of the mean residual at each distinct amplitude (:func:`_levels`), in
    order of amplitude; amplitudes whose mean residual is 0 are left out."""
    level_of = _levels(w)
    means = np.bincount(level_of, weights=residuals) / np.bincount(level_of)
    signs = np.sign(means)
    return signs[signs != 0]


def few_runs_p(signs: np.ndarray) -> float:
    """P(as few runs or fewer) of a sequence of signs whose order is random, given its
    counts of + and - (the exact Wald-Wolfowitz distribution): small when the residuals
    of a fit stay on one side of the curve for long stretches, as a misfit's do. With one
    sign throughout, the chance of that many equal signs, 0.5^(n-1). The counts of
    arrangements are summed as logarithms: as numbers they overflow past about 1000
    signs."""
    n_pos, n_neg = int(np.sum(signs > 0)), int(np.sum(signs < 0))
    if n_pos == 0 or n_neg == 0:
        return 1.0 if n_pos + n_neg < 2 else 0.5 ** (n_pos + n_neg - 1)
    runs = 1 + int(np.count_nonzero(signs[1:] != signs[:-1]))
    half = np.arange(2, runs + 1) // 2  # runs of each sign: r = 2 half or 2 half + 1
    odd = np.arange(2, runs + 1) % 2 == 1
    even_ways = np.log(2.0) + _log_comb(n_pos - 1, half - 1) + _log_comb(n_neg - 1, half - 1)
    odd_ways = np.logaddexp(_log_comb(n_pos - 1, half) + _log_comb(n_neg - 1, half - 1),
                            _log_comb(n_pos - 1, half - 1) + _log_comb(n_neg - 1, half))
    log_ways = logsumexp(np.where(odd, odd_ways, even_ways))
    return float(min(1.0, np.exp(log_ways - _log_comb(n_pos + n_neg, n_pos))))


def _log_comb(n: int, k):
    """log of n choose k, elementwise over k; -inf where k is outside 0..n."""
    k = np.asarray(k, dtype=np.float64)
    inside = (k >= 0) & (k <= n)
    kept = np.where(inside, k, 0.0)
    log_ways = gammaln(n + 1.0) - gammaln(kept + 1.0) - gammaln(n - kept + 1.0)
    return np.where(inside, log_ways, -np.inf)


def _table(w: np.ndarray, f: np.ndarray, m: np.ndarray) -> Calibration:
    """One-row table at the median force: the decreasing (isotonic) regression of the mean
    mu' per amplitude column, weighted by its point count, strictly decreasing; a column
    per distinct amplitude above 0 (um; :func:`_levels`), or per run of neighbouring amplitudes where there
    are more than ``TABLE_BINS`` of them."""
    vibrating = w > 0
    level_of = _levels(w[vibrating])
    levels = int(level_of.max()) + 1
    centres, means, counts = [], [], []
    for run in np.array_split(np.arange(levels), min(TABLE_BINS, levels)):
        inside = np.isin(level_of, run)
        centres.append(float(w[vibrating][inside].mean()))
        means.append(float(m[vibrating][inside].mean()))
        counts.append(float(inside.sum()))
    columns = isotonic_regression(means, weights=counts, increasing=False).x
    mu = np.clip(np.concatenate([[1.0], columns]), 1e-3, 1.0)  # mu' at rest is 1 (eq 1)
    mu = mu - 1e-6 * np.arange(mu.size)  # strictly decreasing, as the table format asks
    return Calibration(amplitudes_um=(0.0, *centres), forces_n=(float(np.median(f)),),
                       mu=(tuple(float(x) for x in mu),))


def device_toml(fit: Fit, amplitude_limit_um: float, normal_force_n: float,
                profile: str = DEFAULT_PROFILE, fitted: FittedOn | None = None,
                speed_mm_s: float | None = None) -> str:
    """The ``[device]`` section (text) a texture file can use for this calibration, with
    what it was ``fitted`` on (``[device.fitted]``: ``device.calibration_identity``) and
    the finger's sliding speed during the sweep (mm/s; b falls as the speed rises)."""
    lines = ["[device]", f'profile = "{profile}"',
             f"amplitude_limit_um = {amplitude_limit_um:.6g}",
             f"normal_force_n = {normal_force_n:.6g}",
             f"[device.friction]        # seed 003 eq 2, fitted: residual RMS {fit.residual_rms:.4f} "
             f"over {fit.n_points} points",
             f"b_per_um = {fit.params.b_per_um:.6g}        # standard error {fit.b_se:.2g} "
             "(the points' scatter only)"
             + ("" if speed_mm_s is None else f"; applies at {speed_mm_s:g} mm/s sliding"),
             f"asymptote_per_n = {fit.params.asymptote_per_n:.6g}        # standard error "
             f"{fit.k_se:.2g}"]
    lines += [f"# {note}" for note in fit.notes]
    if fitted is not None:
        lines += toml_lines(fitted)
    if fit.calibration is not None:
        cal = fit.calibration
        lines += [f"[device.calibration]     # the model does not fit ({fit.misfit_reason}): "
                  "measured table",
                  "amplitudes_um = [" + ", ".join(f"{a:.6g}" for a in cal.amplitudes_um) + "]",
                  "forces_n = [" + ", ".join(f"{x:.6g}" for x in cal.forces_n) + "]",
                  "mu = [" + ", ".join("[" + ", ".join(f"{x:.8g}" for x in row) + "]"
                                       for row in cal.mu) + "]"]
    return "\n".join(lines) + "\n"
