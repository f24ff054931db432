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

import numpy as np

from device.calibration_fit import B_BOUNDS, K_BOUNDS
from device.profile import FrictionParams


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

    def update(self, state: RlsState, jac: np.ndarray, resid: np.ndarray) -> RlsState:
        """One block's points: Jacobian (m, 2) of mu' in (b, k) and residual (m,)
        measured - model (m may be 0); returns the state after them."""
        lam = float(np.exp(-self.block_s / self.memory_s))
        # forgetting toward the prior's information keeps P bounded when points stop
        info = lam * np.array(state.info) + (1.0 - lam) * np.diag(1.0 / np.square(self.prior_sd))
        theta = np.array(state.theta)
        if resid.size:
            s2 = self.noise_sd ** 2
            info = info + jac.T @ jac / s2
            theta = theta + np.linalg.solve(info, jac.T @ resid / s2)
        theta = np.clip(theta, [B_BOUNDS[0], K_BOUNDS[0]], [B_BOUNDS[1], K_BOUNDS[1]])
        return RlsState(theta=(float(theta[0]), float(theta[1])),
                        info=((float(info[0, 0]), float(info[0, 1])),
                              (float(info[1, 0]), float(info[1, 1]))))
