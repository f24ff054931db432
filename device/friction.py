"""The friction model and its inversion: relative friction mu' <-> vibration amplitude w.

Seed 003, eq 2 (written for mu' = mu(w)/mu(0), eq 1)::

    mu'(w) = (1 - A) exp(-b w) + A,        A = k F_n  (k = 1.13 /N, b = 1.67 /um)

and its inversion, eq 3::

    w = -(1/b) ln((mu' - A) / (1 - A))

computed here as ``-log1p(-(1 - mu') / (1 - A)) / b``, which keeps full relative
precision for the small reductions textures mostly ask for.

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
        reduction = (1.0 - mu) / (1.0 - a)  # in [0, 1) where reachable
        # unreachable targets get eq 3's log1p(-1) = -inf without numpy's log1p, which takes
        # 10x as long over -1 as over a finite result
        unreachable = reduction >= 1.0
        with np.errstate(divide="ignore", invalid="ignore"):
            log = np.where(unreachable, -np.inf, np.log1p(-np.where(unreachable, 0.0, reduction)))
            w = -log / self.params.b_per_um
        if beyond.any():  # asks for a reduction where the model does not hold
            out = beyond & (mu < 1.0)
            counts.force_beyond_model += int(np.count_nonzero(out))
            w = np.where(out, self.limit_um, w)
        return w  # may be inf exactly at the asymptote; the caller clamps

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
    passes about numpy's log1p (so every result is the same to the bit as the general
    path's, which :func:`_guarded_invert` takes for the rest): finite targets and one
    force for all, within the model's range. None (``counts`` untouched) for any other
    block."""
    mu_flat, force_flat = mu.ravel(), force.ravel()
    params = model.params
    edge = 1.0 - ASYMPTOTE_MARGIN
    arg, above_one = _seed_reductions(mu_flat, force_flat, params.asymptote_per_n, edge)
    if above_one < 0:
        return None
    np.log1p(arg, out=arg)
    a = params.asymptote_per_n * force_flat[0]
    counts.above_one = above_one
    counts.unreachable = _seed_amplitudes(arg, mu_flat, 1.0 - a, params.b_per_um,
                                          model.limit_um, model.limit_um * (1.0 + 1e-12))
    return arg.reshape(mu.shape)


@njit(cache=True, nogil=True, error_model="numpy")
def _seed_reductions(mu, force, k_per_n, edge):
    """log1p's argument -(1 - min(mu', 1)) / (1 - A) (m,) of eq 3 at targets ``mu``
    (m,), with A = k F_n, 0 where the target is unreachable ((1 - mu') / (1 - A) >= 1),
    and how many targets are above 1; that count is -1 (nothing else computed) unless
    every target is finite and every force is the same, finite, >= 0, with
    A < ``edge``."""
    arg = np.empty(mu.size)
    f = force[0]
    a = k_per_n * f
    if not (0.0 <= f < np.inf and a < edge):
        return arg, -1
    span = 1.0 - a
    above = 0
    for i in range(mu.size):
        m = mu[i]
        if force[i] != f or not abs(m) < np.inf:
            return arg, -1
        if m > 1.0:
            above += 1
            m = 1.0
        r = (1.0 - m) / span
        arg[i] = 0.0 if r >= 1.0 else -r
    return arg, above


@njit(cache=True, nogil=True, error_model="numpy")
def _seed_amplitudes(log, mu, span, b, limit, top):
    """Eq 3's w = -log / b in place over ``log`` (m,), log1p of :func:`_seed_reductions`'s
    arguments, at the limit where the target ``mu`` is unreachable or w is beyond ``top``
    (returns how many), else clipped to [0, limit]."""
    over = 0
    for i in range(mu.size):
        m = mu[i] if mu[i] <= 1.0 else 1.0
        w = -log[i] / b
        if (1.0 - m) / span >= 1.0 or not w <= top:
            over += 1
            w = limit
        log[i] = limit if w > limit else (0.0 if w < 0.0 else w)
    return over


def make_friction_model(device: DeviceProfile) -> FrictionModel:
    """The device's friction model: its calibration table if it has one, else seed 003's."""
    if device.calibration is not None:
        return CalibratedFrictionModel(device)
    return SeedFrictionModel(device)


def mu_floor(device: DeviceProfile, normal_force_n: float) -> float:
    """Lowest mu' the device can reach at ``normal_force_n`` (N) within its amplitude limit."""
    return float(make_friction_model(device).floor(normal_force_n))
