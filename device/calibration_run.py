"""The calibration protocol on a simulated plate: the finger slides while the plate steps
through amplitudes, and the points (w, F_n, mu') come out for ``device.calibration_fit``.

The plate alternates rest and each of ``levels`` amplitudes, ``step_s`` each; the first
``settle_share`` of a step is discarded (plate loop, fingertip and sensor settling). The
friction at rest mu0 is the mean F_t / F_n of the rest steps on each side of an amplitude
step, so the slow moisture drift cancels; mu' = F_t / (F_n mu0) (seed 003, eq 1).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from device.finger import FingerPlant


@dataclass(frozen=True)
class Sweep:
    """The protocol: amplitudes (um), time per step (s), share of each step discarded,
    finger speed (mm/s) and normal force (N) of the simulated user."""

    levels: tuple[float, ...] = tuple(np.round(np.linspace(0.2, 2.4, 12), 3))
    step_s: float = 0.5
    settle_share: float = 0.4
    speed_mm_s: float = 60.0
    force_n: float = 0.5

    @property
    def duration_s(self) -> float:
        return (2 * len(self.levels) + 1) * self.step_s


def run_sweep(plant: FingerPlant, sweep: Sweep, on_step=None):
    """Run the protocol on ``plant``; returns the points (w_um, normal_n, mu) as arrays.

    ``on_step(done, total)`` is called after each step (progress).
    """
    rate = plant.rate_hz
    per = int(round(sweep.step_s * rate))
    keep = slice(int(per * sweep.settle_share), per)
    steps = [0.0]
    for level in sweep.levels:
        steps += [level, 0.0]
    state = plant.initial_state()
    ratios, normals = [], []
    for k, w in enumerate(steps):
        cmd = np.full(per, w)
        block, state = plant.step(k * per, cmd, np.full(per, sweep.speed_mm_s),
                                  np.full(per, sweep.force_n), state)
        ratios.append(float(np.mean(block.lateral_n[keep] / block.normal_n[keep])))
        normals.append(float(np.mean(block.normal_n[keep])))
        if on_step is not None:
            on_step(k + 1, len(steps))
    ratios, normals = np.array(ratios), np.array(normals)
    rest = 0.5 * (ratios[0:-1:2] + ratios[2::2])
    return np.array(sweep.levels), normals[1::2], ratios[1::2] / rest
