"""The friction model and its inversion: relative friction mu' <-> vibration amplitude w.

Seed 003, eq 2 (written for mu' = mu(w)/mu(0), eq 1)::

    mu'(w) = (1 - A) exp(-b w) + A,        A = k F_n  (k = 1.13 /N, b = 1.67 /um)

and its inversion, eq 3::

    w = -(1/b) ln((mu' - A) / (1 - A))

computed here from r = (1 - mu') / (1 - A) as ``-log1p(-r) / b`` where r <= 1/2 (full
relative precision for the small reductions textures mostly ask for), and from
q = (mu' - A) / (1 - A) = 1 - r as ``-log(q) / b`` above that: near the floor q is tiny and
1 - mu' rounded would leave it few correct digits (4.8e-4 um off at mu' = 1e-14, 0 N),
while mu' - A, with A's own rounding of k F_n taken back out, keeps them all.

Where the model stops being usable, frictex decides as follows (each case counted in
:class:`ClampCounts`, never silent):

- target >= 1: w = 0 (the plate at rest gives mu' = 1; above 1 is counted as ``above_one``).
- target at or below the lowest reachable mu' (the asymptote A, or mu'(limit) if the
  amplifier limit comes first, including targets within 1e-12 of A where eq 3 diverges):
  w = limit, counted as ``unreachable``.
- A within ``ASYMPTOTE_MARGIN`` of 1 or beyond (F_n >= 0.885 N with seed 003's k): the
  model predicts no modulation at all (A = 1) or friction *rising* with amplitude
  (A > 1), which no ultrasonic plate shows. Below that the model is used as it stands
  (at 0.85 N, A = 0.9605, target 0.99 gives eq 3's 0.175 um). At and beyond it frictex
  evaluates the model at its edge, A = 1 - ``ASYMPTOTE_MARGIN``, the limit the valid
  model tends to: every target below 1 is out of reach and gets the full amplitude (a
  heavy press still gets the strongest reduction, never a sign flip), and each such
  sample is counted as ``force_beyond_model`` (not also as ``unreachable``; a target
  of 1 there is w = 0, exact whatever A, and not counted). The margin is where eq 3 stops being
  computable: a target's rounding (eps = 1.1e-16) moves w by eps / (b (mu' - A)), with
  mu' - A <= 1 - A, i.e. up to 7e-8 um at 1 - A = 1e-9.
- normal force NaN/inf or negative: the nominal force of the device is used, counted as
  ``bad_force``. A force near 0 is fine: A -> 0 and the model is regular.
- target NaN/inf: w = 0 (the safe side), counted as ``nonfinite_target``.

A device may instead carry a measured calibration table (``device.profile.Calibration``):
mu' against amplitude at one or more normal forces. Each row is inverted by monotone
cubic (PCHIP) interpolation; between two measured forces the *amplitudes* for the same
mu' are interpolated linearly in force. Outside the measured forces the nearest row is
used, and each such sample with a target below 1 is counted as ``force_beyond_model``
(not also as ``unreachable``: one out of that row's reach gets the limit). The forward
model of a calibration is defined as the inverse of that map, so forward(invert(mu)) ==
mu on the reachable range.
"""

from __future__ import annotations

from dataclasses import dataclass, fields

import numpy as np

from frictex.device.jit import njit
from frictex.device.profile import Calibration, DeviceProfile, FrictionParams

#: a finger touching with a normal force below this (N) is not pressing: seed 003's plate
#: reads a finger at 0.3-0.75 N (``report_closed_loop.population_slopes``); the closed
#: loop, calibration and a trace's force check share it
MIN_NORMAL_N = 0.05



@dataclass
class ClampCounts:
    """How many output samples each guard changed (see the module docstring)."""

    above_one: int = 0
    unreachable: int = 0
    force_beyond_model: int = 0
    bad_force: int = 0
    nonfinite_target: int = 0

    def add(self, other: "ClampCounts") -> None:
        for f in fields(self):
            setattr(self, f.name, getattr(self, f.name) + getattr(other, f.name))

    def as_dict(self) -> dict[str, int]:
        return {f.name: int(getattr(self, f.name)) for f in fields(self)}

    @property
    def total(self) -> int:
        return sum(self.as_dict().values())


#: the model holds for A < 1 (seed 003, eq 2); within this of 1 eq 3 is not computable
#: (see the module docstring)
ASYMPTOTE_MARGIN = 1e-9


def asymptote(normal_force_n, params: FrictionParams) -> tuple[np.ndarray, np.ndarray]:
    """The model's asymptote A = k F_n (seed 003, eq 2), at most 1 - ``ASYMPTOTE_MARGIN``.

    Returns ``(A, beyond)`` where ``beyond`` marks forces where the model does not hold
    (A = k F_n >= 1 - ``ASYMPTOTE_MARGIN``).
    """
    a = params.asymptote_per_n * np.asarray(normal_force_n, dtype=np.float64)
    edge = 1.0 - ASYMPTOTE_MARGIN
    beyond = a >= edge
    return np.minimum(a, edge), beyond


def _split(x):
    """x as hi + lo, each of at most 26 significant bits (Veltkamp's split; |x| < 1e300)."""
    c = 134217729.0 * x  # 2^27 + 1
    hi = c - (c - x)
    return hi, x - hi


def asymptote_rounding(k_per_n, normal_force_n):
    """k F_n less its rounded product: A's rounding (seed 003, eq 2), exactly (Dekker's
    product), for eq 3 near the asymptote, where mu' - A is a few of A's roundings.

    Plain arithmetic, for floats or arrays (NaN where k or F_n is beyond 1e300).
    """
    a = k_per_n * normal_force_n
    k_hi, k_lo = _split(k_per_n)
    f_hi, f_lo = _split(normal_force_n)
    return ((k_hi * f_hi - a) + k_hi * f_lo + k_lo * f_hi) + k_lo * f_lo


def eq3_arguments(mu, a, low):
    """Eq 3's arguments at targets ``mu`` with asymptote ``a`` (``low``: its
    :func:`asymptote_rounding`, 0 at the model's edge), as ``(x, q, tail)``: where
    r = (1 - mu') / (1 - A) <= 1/2, x = -r for ``log1p`` (and q = 1); above (``tail``),
    q = (mu' - A) / (1 - A) for ``log``, NaN where q <= 0 (unreachable: at or below the
    asymptote), and x = 0."""
    span = 1.0 - a
    with np.errstate(invalid="ignore"):
        r = (1.0 - mu) / span
        tail = r > 0.5
        gap = (mu - a) - low
        q = np.where(tail, np.where(gap > 0.0, gap / span, np.nan), 1.0)
    return np.where(tail, 0.0, -r), q, tail


def eq3_logs(x, q, tails: int) -> None:
    """log1p over ``x`` and log over ``q``, in place (:func:`eq3_arguments`; ``tails``: how
    many targets take q). Whole arrays, not masked ones: numpy's masked logarithms cost
    10x as much over mixed targets."""
    if tails < x.size:
        np.log1p(x, out=x)
    if tails:
        np.log(q, out=q)


def forward_mu(w_um, normal_force_n, params: FrictionParams) -> np.ndarray:
    """mu'(w) of seed 003, eq 2 (beyond the model's force range, at its edge: see above).

    Parameters
    ----------
    w_um : array_like, zero-to-peak vibration amplitude (um), >= 0.
    normal_force_n : array_like, normal force (N), broadcast against ``w_um``.
    params : the model constants.
    """
    a, _ = asymptote(normal_force_n, params)
    return (1.0 - a) * np.exp(-params.b_per_um * np.asarray(w_um, dtype=np.float64)) + a


class SeedFrictionModel:
    """Seed 003's closed-form model (eqs 2-3) for one device, with its constants or
    ``params`` in their place (an online estimate of them)."""

    def __init__(self, device: DeviceProfile, params: FrictionParams | None = None):
        self.params = device.friction if params is None else params
        self.limit_um = float(device.amplitude_limit_um)
        self.nominal_force_n = float(device.normal_force_n)

    def forward(self, w_um, normal_force_n) -> np.ndarray:
        """mu' at amplitude ``w_um`` (um) and force ``normal_force_n`` (N)."""
        return forward_mu(w_um, normal_force_n, self.params)

    def floor(self, normal_force_n) -> np.ndarray:
        """Lowest mu' reachable at that force within the amplitude limit."""
        return self.forward(self.limit_um, normal_force_n)

    def beyond_model(self, forces: bool = False) -> str:
        """What a sample counted ``force_beyond_model`` met, for a warning; ``forces``:
        the samples of a travelling-wave scene, whose force inversion takes the friction
        at the model's edge (a friction target gets full amplitude instead)."""
        done = ("its force inversion took the friction at the model's edge" if forces
                else "full amplitude was commanded")
        return (f"beyond seed 003's friction model, whose asymptote "
                f"{self.params.asymptote_per_n:g} F_n reaches 1 there ({done})")

    def _amplitude(self, mu, force, counts: ClampCounts) -> np.ndarray:
        a, beyond = asymptote(force, self.params)  # force may be one value for all of mu
        with np.errstate(over="ignore", invalid="ignore"):
            low = np.where(beyond, 0.0, asymptote_rounding(self.params.asymptote_per_n, force))
        # unreachable targets get NaN, not eq 3's log(0) = -inf: numpy's logarithms take
        # 10x as long over 0 as over a finite result
        x, q, tail = eq3_arguments(mu, a, low)
        eq3_logs(x, q, int(np.count_nonzero(tail)))
        w = -np.where(tail, q, x) / self.params.b_per_um
        if beyond.any():  # asks for a reduction where the model does not hold
            out = beyond & (mu < 1.0)
            counts.force_beyond_model += int(np.count_nonzero(out))
            w = np.where(out, self.limit_um, w)
        return w  # NaN where unreachable, maybe beyond the limit; the caller clamps

    def invert(self, mu_target, normal_force_n) -> tuple[np.ndarray, ClampCounts]:
        """Amplitude (um, in [0, limit]) giving mu' = ``mu_target`` at ``normal_force_n``.

        Both arguments broadcast to one shape. Returns ``(w_um, counts)``; ``w_um`` is
        always finite.
        """
        return _guarded_invert(self, mu_target, normal_force_n)


class CalibratedFrictionModel:
    """A measured calibration table, inverted by monotone (PCHIP) interpolation."""

    def __init__(self, device: DeviceProfile):
        # scipy only for scenes with a calibration table (importing it costs 0.3-0.6 s)
        from scipy.interpolate import PchipInterpolator
        from scipy.optimize import brentq
        cal: Calibration = device.calibration
        self.limit_um = float(device.amplitude_limit_um)
        self.nominal_force_n = float(device.normal_force_n)
        self.forces = np.asarray(cal.forces_n, dtype=np.float64)
        amps = np.asarray(cal.amplitudes_um, dtype=np.float64)
        mu = np.asarray(cal.mu, dtype=np.float64)
        # w as a function of mu' per row: mu decreases with w, so reverse to increasing
        self._inverse_rows = [PchipInterpolator(row[::-1], amps[::-1], extrapolate=False)
                              for row in mu]
        # each row's lowest mu' within the amplitude limit (or the table's last amplitude)
        w_max = min(self.limit_um, amps[-1])
        self._row_floor = np.array([
            brentq(lambda m, inv=inverse: float(inv(m)) - w_max, row.min(), 1.0, xtol=1e-15)
            for inverse, row in zip(self._inverse_rows, mu)])

    def _blend(self, force: np.ndarray):
        """Row indices and weights for each force (linear in force, clamped to the table)."""
        f = np.asarray(force, dtype=np.float64)
        if self.forces.size == 1:
            zeros = np.zeros(f.shape, dtype=np.intp)
            return zeros, zeros, np.zeros(f.shape)
        fc = np.clip(f, self.forces[0], self.forces[-1])
        hi = np.clip(np.searchsorted(self.forces, fc, side="right"), 1, self.forces.size - 1)
        lo = hi - 1
        weight = (fc - self.forces[lo]) / (self.forces[hi] - self.forces[lo])
        return lo, hi, weight

    def _amplitude(self, mu, force, counts: ClampCounts) -> np.ndarray:
        force = np.broadcast_to(force, mu.shape)
        lo, hi, weight = self._blend(force)
        per_row = np.stack([inverse(mu) for inverse in self._inverse_rows])
        per_row = np.where(np.isnan(per_row), np.inf, per_row)  # below a row's range: unreachable
        w_lo = np.take_along_axis(per_row, lo[None], 0)[0]
        w_hi = np.take_along_axis(per_row, hi[None], 0)[0]
        with np.errstate(invalid="ignore"):
            blended = (1.0 - weight) * w_lo + weight * w_hi
        w = np.where(weight == 0.0, w_lo, np.where(weight == 1.0, w_hi, blended))
        # a force outside the table: its nearest row, counted (a target of 1 is w = 0
        # whatever the force); out of that row's reach, it gets the limit as counted here
        out = ((force < self.forces[0]) | (force > self.forces[-1])) & (mu < 1.0)
        if out.any():
            counts.force_beyond_model += int(np.count_nonzero(out))
            w = np.where(out & ~(w <= self.limit_um), self.limit_um, w)
        return w

    def beyond_model(self, forces: bool = False) -> str:
        """What a sample counted ``force_beyond_model`` met, for a warning (the same for
        a travelling-wave scene's ``forces``)."""
        return (f"outside the calibration's measured forces ({self.forces[0]:g} to "
                f"{self.forces[-1]:g} N): the nearest measured force's row was used")

    def floor(self, normal_force_n) -> np.ndarray:
        lo, hi, weight = self._blend(normal_force_n)
        both = np.maximum(self._row_floor[lo], self._row_floor[hi])
        return np.where(weight == 0.0, self._row_floor[lo],
                        np.where(weight == 1.0, self._row_floor[hi], both))

    def forward(self, w_um, normal_force_n) -> np.ndarray:
        """mu' at ``w_um``: the inverse of :meth:`invert` (solved per element; not for hot paths)."""
        from scipy.optimize import brentq
        w_b, f_b = np.broadcast_arrays(np.asarray(w_um, dtype=np.float64),
                                       np.asarray(normal_force_n, dtype=np.float64))
        out = np.empty(w_b.shape)
        for idx in np.ndindex(w_b.shape):
            w, f = float(w_b[idx]), float(f_b[idx])
            fl = float(self.floor(f))
            if w <= 0.0:
                out[idx] = 1.0
                continue
            amp = lambda m: float(self._amplitude(np.array([m]), np.array([f]), ClampCounts())[0])
            if amp(fl) <= w:
                out[idx] = fl
                continue
            out[idx] = brentq(lambda m: amp(m) - w, fl, 1.0, xtol=1e-15, rtol=1e-14)
        return out

    def invert(self, mu_target, normal_force_n) -> tuple[np.ndarray, ClampCounts]:
        return _guarded_invert(self, mu_target, normal_force_n)


FrictionModel = SeedFrictionModel | CalibratedFrictionModel


def _guarded_invert(model: FrictionModel, mu_target, normal_force_n) -> tuple[np.ndarray, ClampCounts]:
    """The hard-case guards shared by every model (see the module docstring)."""
    counts = ClampCounts()
    mu = np.asarray(mu_target, dtype=np.float64)
    force = np.asarray(normal_force_n, dtype=np.float64)
    if mu.shape != force.shape:  # broadcast_arrays costs microseconds even when they match
        mu, force = np.broadcast_arrays(mu, force)
    if type(model) is SeedFrictionModel and mu.size:
        w = _seed_invert(model, mu, force, counts)
        if w is not None:
            return w, counts
    f_lo, f_hi = force.min(initial=np.inf), force.max(initial=-np.inf)
    # the usual block: finite targets (their sum is finite) and one good force for all
    if np.isfinite(mu.sum()) and f_lo == f_hi and 0.0 <= f_lo < np.inf:
        bad_mu = None
        force = f_lo
    else:
        bad_mu = ~np.isfinite(mu)
        bad_force = ~np.isfinite(force) | (force < 0.0)
        counts.nonfinite_target = int(np.count_nonzero(bad_mu))
        counts.bad_force = int(np.count_nonzero(bad_force))
        force = np.where(bad_force, model.nominal_force_n, force)
        mu = np.where(bad_mu, 1.0, mu)
    counts.above_one = int(np.count_nonzero(mu > 1.0))
    mu = np.minimum(mu, 1.0)
    w = model._amplitude(mu, force, counts)
    # unreachable: beyond the asymptote (nan/inf from eq 3) or beyond the amplifier limit;
    # a target computed from w = limit may come back a rounding error above it: not a clamp
    top = model.limit_um * (1.0 + 1e-12)
    if not w.max(initial=0.0) <= top:  # some w is nan, inf or beyond the limit
        over = ~np.isfinite(w) | (w > top)
        counts.unreachable = int(np.count_nonzero(over if bad_mu is None else over & ~bad_mu))
        w = np.where(over, model.limit_um, w)
    return np.clip(w, 0.0, model.limit_um), counts


def _seed_invert(model: SeedFrictionModel, mu, force, counts: ClampCounts):
    """:func:`_guarded_invert` of seed 003's model for the usual block, in two compiled
    passes about numpy's log1p and log (so every result is the same to the bit as the general
    path's, which :func:`_guarded_invert` takes for the rest): finite targets and one
    force for all, within the model's range. None (``counts`` untouched) for any other
    block."""
    mu_flat, force_flat = mu.ravel(), force.ravel()
    params = model.params
    edge = 1.0 - ASYMPTOTE_MARGIN
    low = asymptote_rounding(params.asymptote_per_n, float(force_flat[0]))  # floats: no warnings
    x, q, tail, above_one, tails = _seed_reductions(mu_flat, force_flat, params.asymptote_per_n,
                                                    low, edge)
    if above_one < 0:
        return None
    eq3_logs(x, q, tails)
    counts.above_one = above_one
    counts.unreachable = _seed_amplitudes(x, q, tail, params.b_per_um, model.limit_um,
                                          model.limit_um * (1.0 + 1e-12))
    return x.reshape(mu.shape)


@njit(cache=True, nogil=True, error_model="numpy")
def _seed_reductions(mu, force, k_per_n, low, edge):
    """:func:`eq3_arguments` at targets ``mu`` (m,) clipped to 1, with A = k F_n (``low``:
    its :func:`asymptote_rounding`), as ``(x, q, tail, above, tails)``: ``above`` counts
    the targets above 1, ``tails`` the ``tail`` marks. ``above`` is -1 (nothing else
    computed) unless every target is finite and every force is the same, finite, >= 0,
    with A < ``edge``."""
    x = np.zeros(mu.size)
    q = np.ones(mu.size)
    tail = np.zeros(mu.size, dtype=np.bool_)
    f = force[0]
    a = k_per_n * f
    if not (0.0 <= f < np.inf and a < edge):
        return x, q, tail, -1, 0
    span = 1.0 - a
    above = 0
    tails = 0
    for i in range(mu.size):
        m = mu[i]
        if force[i] != f or not abs(m) < np.inf:
            return x, q, tail, -1, 0
        if m > 1.0:
            above += 1
            m = 1.0
        r = (1.0 - m) / span
        if r > 0.5:
            tail[i] = True
            tails += 1
            gap = (m - a) - low
            q[i] = gap / span if gap > 0.0 else np.nan
        else:
            x[i] = -r
    return x, q, tail, above, tails


@njit(cache=True, nogil=True, error_model="numpy")
def _seed_amplitudes(log1p, log, tail, b, limit, top):
    """Eq 3's w = -log1p / b, or -log / b where ``tail`` (:func:`eq3_logs` of
    :func:`_seed_reductions`'s arguments, (m,) each), in place over ``log1p``, at the limit
    where the target is unreachable (NaN) or w is beyond ``top`` (returns how many), else
    clipped to [0, limit]."""
    over = 0
    for i in range(log1p.size):
        w = -(log[i] if tail[i] else log1p[i]) / b
        if not w <= top:
            over += 1
            w = limit
        log1p[i] = limit if w > limit else (0.0 if w < 0.0 else w)
    return over


def make_friction_model(device: DeviceProfile) -> FrictionModel:
    """The device's friction model: its calibration table if it has one, else seed 003's."""
    if device.calibration is not None:
        return CalibratedFrictionModel(device)
    return SeedFrictionModel(device)


def mu_floor(device: DeviceProfile, normal_force_n: float) -> float:
    """Lowest mu' the device can reach at ``normal_force_n`` (N) within its amplitude limit."""
    return float(make_friction_model(device).floor(normal_force_n))
