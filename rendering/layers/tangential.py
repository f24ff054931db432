"""Tangential force of a travelling wave on a sliding finger, and its inversion.

Seed 002 (eqs 7-10) splits the tangential force into a friction force F_f, opposing the
finger's motion and equal to that of a standing wave of the same amplitude, and a
driving force F_p pushing the finger against the wave's direction of travel. With
F_t positive when it resists the finger (seed 002's convention)::

    F_t = F_f(w) + s F_p(w),      s = m d                         (seed 002, eqs 7-8)

where m = +1/-1 is the finger's direction of motion along the wave axis and d = +1/-1
the wave's (d = 0: a standing wave, W_B = 0). s = +1 (finger moving with the wave) is
eq 8, F_f + F_p; s = -1 is eq 7, F_f - F_p.

- F_f = mu0 F_n mu'(w), mu' from seed 003, eq 2 (``device.friction.forward_mu``).
- F_p = k_p F_n max(0, tau w - w_th): seed 004, Fig. 3c's linear fit (slope
  0.13 N/um at F_n = 1 N, so k_p = 0.13 /um; no force below about 1 um). tau is the
  local travelling-wave ratio (``device.actuation.travelling``): a wave of envelope w with ratio
  tau is a pure travelling wave of amplitude tau w plus a standing wave, and only the
  travelling part drives. seed 004 quotes amplitudes as "+-1 um": zero-to-peak already.

Inversion: for a wanted F_t on a finger moving at v (mm/s), the amplitude w in
[0, limit] and the direction d. The branch s = -1 is strictly decreasing in w, from
F0 = mu0 F_n at w = 0 to its floor at the limit, so every target in [floor, F0] has
one solution, found in closed form (seed 003, eq 3 below the drive threshold, Lambert W
above it).

Zero and negative net force (seed 002, sec 4.1) lie in that range only at light
presses. The floor at w = limit, tau = 1 is
F_n [mu0 ((1 - k F_n) e^{-b w} + k F_n) - k_p (w - w_th)], at most 0 only for
F_n <= (k_p (w - w_th) / mu0 - e^{-b w}) / (k (1 - e^{-b w})): with the default
constants (mu0 0.5, k 1.13 /N, b 1.67 /um, k_p 0.13 /um, w_th 1 um) F_n <= 0.457 N at
3 um (the ring), 0.356 N at the 2.58 um seed 002's beam gives mid-span. At the paper's
0.5 N the floor is +0.012 N at 3 um (+0.11 N at 1.6 um); zero would need 3.18 um.
Lower targets get the floor (w at the limit) and are counted ``unreachable``.

Targets above F0 need s = +1, whose force is convex past the threshold and is reachable
up to its value at the limit (Lambert W, the branch where the force rises). Targets
outside are clamped to the nearest reachable force and marked ``unreachable`` (never
silently).

Direction hysteresis (no chatter): m follows sign(v) only once |v| >= ``v_hold_mm_s``;
below it (and at a finger at rest) the last direction holds. d is changed only on a
sample that needs drive; while F_p = 0 (w tau <= w_th) the last d holds, since either
direction gives the same force there. Both are carried between blocks in
:class:`TangentialState`, so any split of a trace into blocks gives the same result.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.special import lambertw

from frictex.device.actuation.travelling import driving_force
from frictex.device.friction import asymptote, forward_mu
from frictex.device.profile import DrivingForceParams, FrictionParams


@dataclass(frozen=True)
class TangentialState:
    """What one block hands to the next: the held motion and wave directions (+1/-1)."""

    motion: int = 1
    direction: int = 1


@dataclass(frozen=True, eq=False)
class TangentialCommand:
    """The inversion's result for a block of n samples.

    amplitude_um : float64 (n,) wave amplitude w (um zero-to-peak), in [0, limit].
    direction : int8 (n,) wave direction d (+1 / -1 along the axis).
    motion : int8 (n,) the finger direction m used (held through slow samples).
    achieved_n : float64 (n,) F_t of the commands (forward model), N.
    unreachable : bool (n,) targets outside the reachable range, clamped to its nearest end.
    nonfinite : bool (n,) targets that were NaN/inf (w = 0 there).
    beyond_model : bool (n,) samples given an amplitude (w > 0) at a normal force beyond
        seed 003's friction model (``device.friction.asymptote``), where F_f was taken at
        the model's edge; counted as ``force_beyond_model`` like the friction inversion's.
    """

    amplitude_um: np.ndarray
    direction: np.ndarray
    motion: np.ndarray
    achieved_n: np.ndarray
    unreachable: np.ndarray
    nonfinite: np.ndarray
    beyond_model: np.ndarray


def _forces(w_um, normal_force_n, twr, friction: FrictionParams, params: DrivingForceParams):
    """(F_f, F_p) in N at amplitude w (um), force F_n (N) and travelling-wave ratio tau."""
    fn = np.asarray(normal_force_n, dtype=np.float64)
    f_f = params.mu0 * fn * forward_mu(w_um, fn, friction)
    return f_f, driving_force(np.asarray(twr, dtype=np.float64) * w_um, fn, params)


def tangential_force(w_um, direction, motion, normal_force_n, twr, friction: FrictionParams,
                     params: DrivingForceParams) -> np.ndarray:
    """F_t (N, positive resisting the finger) of seed 002, eqs 7-8.

    Parameters
    ----------
    w_um : array_like, wave amplitude (um zero-to-peak), >= 0.
    direction : array_like of -1, 0, +1, wave direction d (0: standing wave).
    motion : array_like of -1, +1, finger direction of motion m.
    normal_force_n : array_like, F_n (N), >= 0.
    twr : array_like, local travelling-wave ratio tau in [0, 1].
    All broadcast together; the result has their broadcast shape.
    """
    f_f, f_p = _forces(np.asarray(w_um, dtype=np.float64), normal_force_n, twr, friction, params)
    return f_f + np.asarray(motion) * np.asarray(direction) * f_p


def _lambert_amplitude(c1, b, c2, c3, resist: bool):
    """The w solving c1 exp(-b w) -+ c2 w = c3 where the drive term wins (Lambert W_0).

    assist (``resist`` False): c1 e^{-bw} - c2 w = c3, decreasing, one root:
    b (w + c3/c2) = W_0((b c1 / c2) e^{b c3 / c2}).
    resist: c1 e^{-bw} + c2 w = c3, convex, the larger root:
    b (w - c3/c2) = W_0(-(b c1 / c2) e^{-b c3 / c2}).
    Elsewhere (no root, or c2 = 0) the value is meaningless and the caller discards it.
    """
    with np.errstate(divide="ignore", invalid="ignore", over="ignore"):
        shift = c3 / c2
        if resist:
            return shift + np.real(lambertw(-(b * c1 / c2) * np.exp(-b * shift))) / b
        return np.real(lambertw((b * c1 / c2) * np.exp(b * shift))) / b - shift


def invert_tangential(target_n, velocity_mm_s, normal_force_n, twr, limit_um,
                      friction: FrictionParams, params: DrivingForceParams,
                      state: TangentialState | None = None
                      ) -> tuple[TangentialCommand, TangentialState]:
    """Amplitude and direction giving the wanted F_t, for one block of samples.

    Parameters
    ----------
    target_n : (n,) wanted F_t (N, positive resisting the finger; 0 and negative allowed).
    velocity_mm_s : (n,) finger velocity along the wave axis (mm/s); NaN/inf holds the
        last direction like a slow sample.
    normal_force_n : (n,) or scalar, normal force (N), finite and >= 0.
    twr : (n,) or scalar, local travelling-wave ratio in [0, 1] at the finger.
    limit_um : scalar or (n,), the largest w reachable at each sample (um zero-to-peak).
    state : from the previous block (default: motion +1, direction +1).

    Returns
    -------
    (TangentialCommand, TangentialState)
    """
    state = state or TangentialState()
    target = np.asarray(target_n, dtype=np.float64)
    n = target.shape[0]
    fn = np.broadcast_to(np.asarray(normal_force_n, dtype=np.float64), (n,))
    tau = np.broadcast_to(np.asarray(twr, dtype=np.float64), (n,))
    _, motion = finger_motion(velocity_mm_s, params.v_hold_mm_s, state.motion)

    nonfinite = ~np.isfinite(target)
    goal = np.where(nonfinite, params.mu0 * fn, target)
    a, beyond = asymptote(fn, friction)
    b = friction.b_per_um
    f0 = params.mu0 * fn
    c1, ca = f0 * (1.0 - a), f0 * a           # F_f = c1 exp(-b w) + ca
    c2 = params.slope_per_um * fn             # F_p = c2 (tau w - w_th) past the threshold
    with np.errstate(divide="ignore", over="ignore"):
        w_th = np.where(tau > 0, params.threshold_um / tau, np.inf)
    low = tangential_force(limit_um, 1, -1, fn, tau, friction, params)    # s = -1 at the limit
    high_drive = tangential_force(limit_um, 1, 1, fn, tau, friction, params)
    high = np.maximum(f0, high_drive)

    # s = -1 branch, below the threshold: seed 003, eq 3 on F_f alone
    with np.errstate(divide="ignore", invalid="ignore"):
        w_friction = -np.log1p(-np.minimum((f0 - goal) / (f0 - ca), 1.0)) / b
    # above it: c1 e^{-bw} + ca - c2 (tau w - w_th) = goal
    w_assist = _lambert_amplitude(c1, b, c2 * tau, goal - ca - c2 * params.threshold_um, False)
    # s = +1 branch: c1 e^{-bw} + ca + c2 (tau w - w_th) = goal
    w_resist = _lambert_amplitude(c1, b, c2 * tau, goal - ca + c2 * params.threshold_um, True)

    below = goal < low
    above = goal > high
    resist = (goal > f0) & ~above
    w = np.where(w_friction <= np.minimum(w_th, limit_um), w_friction, w_assist)
    w = np.where(resist, w_resist, w)
    w = np.where(below, limit_um, w)
    w = np.where(above, np.where(high_drive > f0, limit_um, 0.0), w)
    # no normal force, no force of any kind (each is F_n times something): rest, and a
    # goal other than 0 stays counted unreachable
    w = np.where(nonfinite | (fn == 0.0), 0.0, np.clip(w, 0.0, limit_um))
    s = np.where(resist | above & (w > 0), 1, -1)

    driving = tau * w > params.threshold_um
    direction = _hold(np.where(driving, s * motion, 0), state.direction)
    achieved = tangential_force(w, direction, motion, fn, tau, friction, params)
    command = TangentialCommand(w, direction.astype(np.int8), motion.astype(np.int8), achieved,
                                (below | above) & ~nonfinite, nonfinite, beyond & (w > 0.0))
    new_state = TangentialState(int(motion[-1]), int(direction[-1])) if n else state
    return command, new_state


def finger_motion(velocity_mm_s, v_hold_mm_s: float, initial: int) -> tuple[np.ndarray, np.ndarray]:
    """Which samples move, and the held direction of motion m (+1/-1) at each.

    Parameters
    ----------
    velocity_mm_s : (n,) velocity along the wave axis (mm/s); NaN/inf counts as still.
    v_hold_mm_s : speed below which the finger is still and m holds its last value.
    initial : m before the first sample (+1 or -1).

    Returns
    -------
    moving : bool (n,). motion : int64 (n,) of +1/-1.
    """
    v = np.asarray(velocity_mm_s, dtype=np.float64)
    moving = np.isfinite(v) & (np.abs(v) >= v_hold_mm_s)
    return moving, _hold(np.where(moving, np.sign(v), 0), initial)


def _hold(values: np.ndarray, initial: int) -> np.ndarray:
    """Forward-fill the non-zero entries of ``values`` (int), starting from ``initial``."""
    values = np.asarray(values).astype(np.int64)
    idx = np.where(values != 0, np.arange(values.size), -1)
    last = np.maximum.accumulate(idx) if values.size else idx
    return np.where(last >= 0, values[np.maximum(last, 0)], initial)
