"""A table-driven friction inversion: seed 003's eq 3 read from a table built at scene load.

Not a faster one: the exact inversion (``device.friction``, compiled) is quicker at every
block size. Measured per call on a 2-core machine under load (best of 5 runs of
interleaved 0.6 / 1.0 targets at 0.5 N): 50 samples (one 5 ms block at 10 kHz) 6.3 us
exact against 45 us here, 1,000 samples 15 against 61 us, 100,000 samples 1.3 against
3.7 ms (the table uniform in r this one replaced, below: 23 us, 29 us, 1.7 ms, measured
when the exact path took 3.6 us, 8.6 us and 0.52 ms, before it took eq 3's log near the floor);
``frictex report``'s Inversion table compares the two per second of output. What it is
for: it is how a controller without a fast logarithm would invert eq 3, and
``frictex report`` and the Python API's ``inversion="lut"`` (``build_pipeline``) show
what such a table costs in accuracy (at most 5e-9 um of amplitude at any allowed limit,
nothing the friction errors show).

Eq 3, ``w = -(1/b) ln(q)`` with ``q = (mu' - A) / (1 - A) = 1 - r``,
``r = (1 - mu') / (1 - A)``, depends on the target and the force only through q, taken
as the exact inversion takes it (``device.friction.eq3_arguments``: 1 - r near 1, the
first form near the floor, where 1 - r would keep few of its digits). q in (0, 1] is split into a mantissa and an
octave, ``q = m 2^e`` with m in [0.5, 1) (``frexp``: a controller reads them off the
float's bits), so ``w = -ln(m) / b - e ln(2) / b``: one table of ``-ln(m) / b`` uniform
in m over one octave serves every force and every amplitude limit, and a block is
inverted with a ``frexp``, a truncation and one linear interpolation instead of a
``log1p`` (in numpy: several array passes, which cost more than the exact path's one
compiled loop). A table uniform in r, as this one was, cannot: w(r) steepens as
1/(1 - r) toward the limit, and its last of 4096 cells spanned about 5 um at an 8 um
limit (1.47 um off at mu' = 0.565, 12.5 um at 20 um; 100 um, allowed, is r = 1 to
the last bit).

Error (linear interpolation, step h = 0.5 / (N - 1)): at most
``h^2 / 8 * max |d^2/dm^2 ln(m)| / b = h^2 / (2 b)`` whatever the limit or the force;
for seed 003's device (b = 1.67/um) and N = 4096 that is 4.5e-9 um, plus the rounding of
e ln(2) / b (below 1e-14 um). :meth:`LutFrictionModel.max_error_um` measures it
against the exact inversion on a dense grid; ``frictex report`` reports the resulting
friction error beside the exact one.

Same guards and counts as ``device.friction`` (targets above 1, unreachable targets);
a block with a non-finite target, a bad force or a force beyond the model takes the
exact path, which handles and counts those.
"""

from __future__ import annotations

import numpy as np

from frictex.device.errors import InputError
from frictex.device.friction import (ClampCounts, SeedFrictionModel, asymptote,
                                     asymptote_rounding, eq3_arguments)

#: table size: 4096 points over one octave keep the interpolation error below 5e-9 um
TABLE_SIZE = 4096


class LutFrictionModel:
    """Table-driven inversion of a :class:`~device.friction.SeedFrictionModel`."""

    def __init__(self, exact, size: int = TABLE_SIZE):
        if not isinstance(exact, SeedFrictionModel):
            raise InputError(f"lut inversion: the device has a {type(exact).__name__}; "
                             "expected seed 003's closed-form model (use the exact inversion "
                             "with a calibration table)")
        self.exact = exact
        self.params = exact.params
        self.limit_um = exact.limit_um
        self.nominal_force_n = exact.nominal_force_n
        b = self.params.b_per_um
        # q at the limit; below it a target is unreachable: beyond the limit (a rounding
        # off it, as the exact inversion allows, is not)
        self._q_low = np.exp(-b * self.limit_um * (1.0 + 1e-12))
        m = np.linspace(0.5, 1.0, size)
        self._w = -np.log(m) / b  # w of the mantissa m (um)
        self._w[0] = np.log(2.0) / b  # so that q = 1 (m = 0.5, e = 1) is w = 0 exactly
        self._scale = (size - 1) / 0.5  # table steps per unit of m
        self._slope = np.append(np.diff(self._w), 0.0)
        self._octave_um = self._w[0]  # w of a factor 2 in q

    def forward(self, w_um, normal_force_n) -> np.ndarray:
        """mu' at amplitude ``w_um`` (um) and force ``normal_force_n`` (N): the exact model."""
        return self.exact.forward(w_um, normal_force_n)

    def floor(self, normal_force_n) -> np.ndarray:
        return self.exact.floor(normal_force_n)

    def beyond_model(self, forces: bool = False) -> str:
        return self.exact.beyond_model(forces)

    def invert(self, mu_target, normal_force_n) -> tuple[np.ndarray, ClampCounts]:
        """Amplitude (um, in [0, limit]) for ``mu_target`` at ``normal_force_n``; see
        ``device.friction.SeedFrictionModel.invert`` for the guards and counts."""
        mu, force = np.broadcast_arrays(np.asarray(mu_target, dtype=np.float64),
                                        np.asarray(normal_force_n, dtype=np.float64))
        f_lo, f_hi = force.min(initial=np.inf), force.max(initial=-np.inf)
        # one cheap pass: the sum of finite targets is finite (else the exact path decides)
        if mu.size == 0 or not (np.isfinite(mu.sum()) and f_lo >= 0.0 and np.isfinite(f_hi)):
            return self.exact.invert(mu, force)
        # one force for the block (the usual case): a scalar asymptote
        a, beyond = asymptote(f_lo if f_lo == f_hi else force, self.params)
        if np.any(beyond):  # a heavy press: the exact path decides and counts
            return self.exact.invert(mu, force)
        counts = ClampCounts()
        # q as the exact path computes it (1 - r or q itself, NaN where unreachable);
        # flat, so that a single target (0-d) is an array to write into too
        low = asymptote_rounding(self.params.asymptote_per_n, f_lo if f_lo == f_hi else force)
        x, q, tail = eq3_arguments(mu, a, low)
        x = x.reshape(-1)
        counts.above_one = int(np.count_nonzero(x > 0.0))  # r < 0: mu' > 1
        q = np.where(tail, q, 1.0 + x).reshape(-1)
        over = ~(q >= self._q_low)
        counts.unreachable = int(np.count_nonzero(over))
        q[over] = 1.0  # w = limit below
        x, e = np.frexp(np.minimum(q, 1.0, out=q))  # q = x 2^e, x in [0.5, 1), e <= 1
        x *= self._scale
        x -= self._scale / 2  # x in table steps from m = 0.5
        k = x.astype(np.intp)
        x -= k
        w = self._slope[k]
        w *= x
        w += self._w[k]
        w -= e * self._octave_um  # seed 003, eq 3: w = -(ln(m) + e ln(2)) / b
        if counts.unreachable:
            w[over] = self.limit_um
        return np.clip(w, 0.0, self.limit_um, out=w).reshape(mu.shape), counts

    def max_error_um(self, points: int = 200_001, normal_force_n: float | None = None) -> float:
        """Largest |w_lut - w_exact| (um) over ``points`` targets spanning the reachable
        range at ``normal_force_n`` (default: the device's nominal force)."""
        force = self.nominal_force_n if normal_force_n is None else normal_force_n
        mu = np.linspace(float(self.floor(force)), 1.0, points)
        exact, _ = self.exact.invert(mu, force)
        fast, _ = self.invert(mu, np.full(points, force))
        return float(np.abs(fast - exact).max())
