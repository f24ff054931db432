"""A table-driven friction inversion: seed 003's eq 3 read from a table built at scene load.

Not a faster one: the exact inversion (``device.friction``, compiled) is quicker at every
block size. Measured per call on a 2-core machine under load (best of 3 runs of
interleaved 0.6 / 1.0 targets at 0.5 N): 50 samples (one 5 ms block at 10 kHz) 2.7 us
exact against 18 us here, 1,000 samples 4.7 against 20 us, 100,000 samples 0.36 against
0.78 ms; ``frictex report``'s Inversion table shows the same (33 against 92 us per second
of output in one report). What it is for: it is how a controller without a fast
logarithm would invert eq 3, and ``--inversion lut`` and the report show what such a
table costs in accuracy (2e-5 um of amplitude, nothing the friction errors show).

Eq 3, ``w = -(1/b) ln(1 - r)`` with ``r = (1 - mu') / (1 - A)``, depends on the target
and the force only through r, and the amplifier limit is the fixed point
``r_max = 1 - exp(-b w_limit)`` whatever the force. So one uniform table of w over
r in [0, r_max] serves every force; a block is inverted with a multiply, a truncation
and one linear interpolation instead of a ``log1p`` (in numpy: several array passes,
which cost more than the exact path's one compiled loop).

Error (linear interpolation, step h = r_max / (N - 1)): at most
``h^2 / 8 * max w''(r) = h^2 / (8 b (1 - r_max)^2)``; for seed 003's device (b = 1.67/um,
2.5 um limit) and N = 4096 that is 2e-5 um, 1e-5 of the amplitude range.
:meth:`LutFrictionModel.max_error_um` measures it against the exact inversion on a
dense grid; ``frictex report`` reports the resulting friction error beside the exact one.

Same guards and counts as ``device.friction`` (targets above 1, unreachable targets);
a block with a non-finite target, a bad force or a force beyond the model takes the
exact path, which handles and counts those.
"""

from __future__ import annotations

import numpy as np

from frictex.device.errors import InputError
from frictex.device.friction import ClampCounts, SeedFrictionModel, asymptote

#: table size: 4096 points keep the interpolation error near 1e-5 of the range
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
        self.r_max = -np.expm1(-b * self.limit_um)
        r = np.linspace(0.0, self.r_max, size)
        w = -np.log1p(-r) / b
        w[-1] = self.limit_um  # exact at the limit, not a rounding off
        self._scale = (size - 1) / self.r_max
        self._w = w
        self._slope = np.append(np.diff(w), 0.0)

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
        x = (1.0 - mu) * (self._scale / (1.0 - a))  # r in table steps
        top = self._w.size - 1
        counts.above_one = int(np.count_nonzero(x < 0.0))
        counts.unreachable = int(np.count_nonzero(x > top * (1.0 + 1e-12)))
        np.clip(x, 0.0, top, out=x)
        k = x.astype(np.intp)
        x -= k
        return self._w[k] + x * self._slope[k], counts

    def max_error_um(self, points: int = 200_001, normal_force_n: float | None = None) -> float:
        """Largest |w_lut - w_exact| (um) over ``points`` targets spanning the reachable
        range at ``normal_force_n`` (default: the device's nominal force)."""
        force = self.nominal_force_n if normal_force_n is None else normal_force_n
        mu = np.linspace(float(self.floor(force)), 1.0, points)
        exact, _ = self.exact.invert(mu, force)
        fast, _ = self.invert(mu, np.full(points, force))
        return float(np.abs(fast - exact).max())
