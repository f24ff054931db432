"""Online adaptation of the inverse model: recursive least squares on seed 003's (b, k).

Seed 003, eq 2 is linearised around the current estimate at each update (an extended
RLS): with the Jacobian J of mu' with respect to (b, k) (``device.calibration_fit.
model_jacobian``) and the residual r = measured mu' - model mu' (the caller passes both
through the sensor chain), one block's points update the estimate in information form::

    P^-1 <- lam P^-1 + (1 - lam) P0^-1 + J^T J / s^2,   theta <- theta + P J^T r / s^2

``lam`` forgets old blocks with the time constant ``memory_s``; ``s`` is the measurement's
standard deviation (mu'). The prior (``P0``) is the population's spread, so a direction
the points do not excite (a grating asks for one amplitude only) stays near the prior.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property

import numpy as np

from frictex.device.calibration_fit import B_BOUNDS, K_BOUNDS
from frictex.device.profile import FrictionParams


@dataclass(frozen=True)
class RlsState:
    """Estimate theta = (b 1/um, k 1/N) and its information matrix (2 x 2)."""

    theta: tuple[float, float]
    info: tuple[tuple[float, float], tuple[float, float]]

    @property
    def params(self) -> FrictionParams:
        return FrictionParams(b_per_um=self.theta[0], asymptote_per_n=self.theta[1])


@dataclass(frozen=True)
class Rls:
    """The adaptation's constants: prior spread of b and k, measurement noise (mu'),
    memory (s) and block length (s)."""

    prior_sd: tuple[float, float] = (0.5, 0.25)
    noise_sd: float = 0.02
    memory_s: float = 20.0
    block_s: float = 0.005

    def initial_state(self, start: FrictionParams) -> RlsState:
        i0 = 1.0 / np.square(self.prior_sd)
        return RlsState(theta=(start.b_per_um, start.asymptote_per_n),
                        info=((float(i0[0]), 0.0), (0.0, float(i0[1]))))

    @cached_property
    def _forgetting(self) -> float:
        """lam, the weight of the information so far after one block (module docstring)."""
        return float(np.exp(-self.block_s / self.memory_s))

    def update(self, state: RlsState, jac: np.ndarray, resid: np.ndarray) -> RlsState:
        """One block's points: Jacobian (m, 2) of mu' in (b, k) and residual (m,)
        measured - model (m may be 0); returns the state after them.

        The 2 x 2 system is solved in closed form (:func:`_solve_spd`): the information
        matrix is symmetric positive definite, its eigenvalues at least the prior's
        smallest, 1 / max(``prior_sd``)^2 (4 with the defaults), since forgetting mixes
        it with the prior's and the points only add J^T J / s^2.
        """
        lam = self._forgetting
        # forgetting toward the prior's information keeps P bounded when points stop
        (i00, i01), (_, i11) = state.info  # symmetric
        sb, sk = self.prior_sd
        i00 = lam * i00 + (1.0 - lam) * (1.0 / (sb * sb))
        i01 = lam * i01
        i11 = lam * i11 + (1.0 - lam) * (1.0 / (sk * sk))
        b, k = state.theta
        if resid.size:
            s2 = self.noise_sd ** 2
            (j00, j01), (_, j11) = (jac.T @ jac).tolist()
            i00, i01, i11 = i00 + j00 / s2, i01 + j01 / s2, i11 + j11 / s2
            r0, r1 = (jac.T @ resid).tolist()
            db, dk = _solve_spd(i00, i01, i11, r0 / s2, r1 / s2)
            b, k = b + db, k + dk
        return RlsState(theta=(min(max(b, B_BOUNDS[0]), B_BOUNDS[1]),
                               min(max(k, K_BOUNDS[0]), K_BOUNDS[1])),
                        info=((i00, i01), (i01, i11)))


def _solve_spd(a: float, b: float, d: float, r0: float, r1: float) -> tuple[float, float]:
    """x of [[a, b], [b, d]] x = (r0, r1) for a symmetric positive definite matrix:
    Gaussian elimination without pivoting, i.e. its LDL^T factors, whose pivots a and
    d - b^2 / a (the Schur complement) are positive: an SPD matrix needs no pivoting
    (Golub and Van Loan, *Matrix Computations*, 4th ed., section 4.2). It agrees with
    LAPACK's pivoted LU (``np.linalg.solve``) to rounding, without its call overhead."""
    el = b / a
    x1 = (r1 - el * r0) / (d - el * b)
    return (r0 - b * x1) / a, x1
