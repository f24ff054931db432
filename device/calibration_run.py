"""The calibration protocol on a plate, through its link: the finger slides while the
plate steps through amplitudes, and the points (w, F_n, mu') come out for
``device.calibration_fit``.

The plate alternates rest and each of ``levels`` amplitudes, ``step_s`` each; the first
``settle_share`` of a step is discarded (plate loop, fingertip and sensor settling). The
forces are the device's own force reports (PROTOCOL.md 4.9) over each step's kept
samples, read through ``device.link.host.CommandSink.force_report``: the same code
calibrates the simulated device (``frictex sim-device --finger N``) and a plate that
announces a lateral force sensor. A step's ratio is the median of F_t / F_n over its
kept samples, so a short gap in the stream (an underrun: the plate at rest meanwhile)
moves it little. The friction at rest mu0 is the mean ratio of the rest steps on each
side of an amplitude step, so the slow moisture drift cancels; mu' = F_t / (F_n mu0)
(seed 003, eq 1).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from device.link.host import LinkStalled

#: samples per block sent (5 ms at 10 kHz)
BLOCK_SAMPLES = 50
#: how long (s) a step's reports may take beyond the time the device needs to play what
#: is queued before it (the link's queue and the device's buffer: under 1 s)
REPORT_WAIT_S = 2.0
#: smallest normal force (N) a finger on the plate gives
MIN_NORMAL_N = 0.05


@dataclass(frozen=True)
class Sweep:
    """The protocol: amplitudes (um), time per step (s), share of each step discarded,
    and the finger's speed (mm/s) and normal force (N) asked of the user (the simulated
    device's finger slides and presses so)."""

    levels: tuple[float, ...] = tuple(np.round(np.linspace(0.2, 2.4, 12), 3))
    step_s: float = 0.5
    settle_share: float = 0.4
    speed_mm_s: float = 60.0
    force_n: float = 0.5

    @property
    def duration_s(self) -> float:
        return (2 * len(self.levels) + 1) * self.step_s

    def amplitudes(self) -> list[float]:
        """Each step's amplitude (um): rest, then each level followed by rest."""
        steps = [0.0]
        for level in self.levels:
            steps += [float(level), 0.0]
        return steps


def run_sweep(link, sweep: Sweep, on_step=None):
    """Stream the protocol to ``link`` (a paced ``CommandSink``, one channel) from sample
    0 on and read the forces back; returns the points (w_um, normal_n, mu) as arrays.

    ``on_step(done, total)`` is called as each step's forces have come (progress).
    Raises ValueError for a device that cannot be calibrated (no force reports, a limit
    below the sweep's levels) and ``LinkStalled`` when a step's reports do not come.
    """
    info = link.info
    if info is None or not info.has_force_reports:
        raise ValueError(f"{link.label}: the device sends no force reports (PROTOCOL.md "
                         f"4.9: a version 3 device with a lateral force sensor); it cannot "
                         f"be calibrated")
    if max(sweep.levels) > min(info.limits_um):
        raise ValueError(f"{link.label}: the device's amplitude limit {min(info.limits_um):g} "
                         f"um is below the sweep's {max(sweep.levels):g} um")
    per = int(round(sweep.step_s * link.rate_hz))
    kept = per - int(per * sweep.settle_share)
    steps = sweep.amplitudes()
    ratios, normals = [], []

    def window(k: int) -> tuple[int, int]:
        return (k + 1) * per - kept, kept

    def take(k: int, report) -> None:
        normal = float(np.median(report.normal_n))
        if not normal >= MIN_NORMAL_N:
            raise ValueError(f"{link.label}: normal force {normal:.3g} N during step {k + 1}: "
                             f"no finger on the plate (slide a finger through the whole sweep)")
        ratios.append(float(np.median(report.lateral_n / report.normal_n)))
        normals.append(normal)
        if on_step is not None:
            on_step(k + 1, len(steps))

    # a step's reports are read as soon as they have come, between the blocks sent: the
    # link keeps the last second of them
    for k, w in enumerate(steps):
        for lo in range(0, per, BLOCK_SAMPLES):
            link.send(k * per + lo, np.full((min(BLOCK_SAMPLES, per - lo), 1), w))
            while len(ratios) < k:
                report = link.force_report(*window(len(ratios)))
                if report is None:
                    break
                take(len(ratios), report)
    link.send(len(steps) * per, np.zeros((BLOCK_SAMPLES, 1)))  # the plate back at rest
    while len(ratios) < len(steps):
        take(len(ratios), _wait_report(link, *window(len(ratios)), sweep.step_s))
    ratios, normals = np.array(ratios), np.array(normals)
    rest = 0.5 * (ratios[0:-1:2] + ratios[2::2])
    return np.array(sweep.levels), normals[1::2], ratios[1::2] / rest


def _wait_report(link, index0: int, n: int, step_s: float):
    """The forces over samples ``index0 .. index0 + n - 1``, waiting for their reports at
    most the time to play a step and the queue before it plus ``REPORT_WAIT_S``."""
    deadline = time.monotonic() + 2 * step_s + REPORT_WAIT_S
    while (report := link.force_report(index0, n)) is None:
        if time.monotonic() > deadline:
            raise LinkStalled(f"{link.label}: no force reports for samples {index0} to "
                              f"{index0 + n - 1} after {2 * step_s + REPORT_WAIT_S:g} s; "
                              f"the device stopped taking data or reporting")
        time.sleep(0.005)
    return report
