"""The calibration protocol on a plate, through its link: the finger slides while the
plate steps through amplitudes, and the points (w, F_n, mu') come out for
``device.calibration_fit``.

Once a finger presses on the plate (the device's reports show a normal force), the plate
alternates rest and each of ``levels`` amplitudes, ``step_s`` each; the first
``settle_share`` of a step is discarded (plate loop, fingertip and sensor settling). The
forces are the device's own force reports (PROTOCOL.md 4.9) over each step's kept
samples, read through ``device.link.host.CommandSink``: the same code calibrates the
simulated device (``frictex sim-device --finger N``) and a plate that announces a lateral
force sensor. A device drops the report it was building when it underruns, and a host
must not count on every report arriving: a step whose reports cover at least
``MIN_COVERED`` of its kept samples is taken over those, once the reports have gone
``LATE_SAMPLES`` past it. A step's ratio is the median of |F_t| / F_n over its samples
pressed with at least ``MIN_NORMAL_N`` (a sample at 0 N has no ratio). The size, because
the lateral force is signed (PROTOCOL.md 4.9: positive when the finger drags the plate
towards +x) and friction opposes the slide: a finger sliding back and forth (60 mm/s for
12.5 s on a 108 mm screen reverses several times) turns its sign at each reversal, within
a step, while seed 003's mu = F_t / F_n is the friction coefficient, the same size either
way. A signed median of such a step is about 0, or of either sign. The
friction at rest mu0 is the mean ratio of the rest steps on each side of an amplitude
step, so the slow moisture drift cancels; mu' = F_t / (F_n mu0) (seed 003, eq 1).

Reports are read between the blocks sent, so each is read well within the second of
them the link keeps (the link's queue and the device's buffer hold well under a second).
"""

from __future__ import annotations

import time
from dataclasses import dataclass

import numpy as np

from frictex.device.errors import DeviceError
from frictex.device.friction import MIN_NORMAL_N
from frictex.device.link.host import LinkStalled

#: samples per block sent (5 ms at 10 kHz)
BLOCK_SAMPLES = 50
#: how long (s) a step's reports may take beyond the time the device needs to play what
#: is queued before it
REPORT_WAIT_S = 2.0
#: least share of a step's kept samples its reports must cover
MIN_COVERED = 0.8
#: samples the device's reports must have gone past a step before the ones it lacks are
#: given up (a report spans 40 samples on the reference device; they come in order)
LATE_SAMPLES = 200
#: how long (s) the sweep waits for a finger to press on the plate before it starts
TOUCH_WAIT_S = 30.0
#: least friction coefficient |F_t / F_n| of a rest step: a fingertip sliding on glass has
#: 0.3 to 1.5 (``device.finger``), so below a tenth of that the sensor reads no friction
MIN_REST_FRICTION = 0.03


class StepCut(LinkStalled):
    """A step's reports cover less than ``MIN_COVERED`` of it: the device underran or its
    watchdog tripped (a host starved of CPU), and dropped what it was building.
    ``next_index``: the first sample past everything the sweep sent, where another sweep
    on the same link may start."""

    def __init__(self, message: str, next_index: int = 0):
        super().__init__(message)
        self.next_index = next_index


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


def check_calibratable(link, sweep: Sweep) -> None:
    """Raise DeviceError unless the device on ``link`` can run ``sweep``: it sends force
    reports and its amplitude limit reaches the sweep's levels."""
    info = link.info
    if info is None or not info.has_force_reports:
        raise DeviceError(f"{link.label}: the device sends no force reports (PROTOCOL.md "
                         f"4.9: a version 3 device with a lateral force sensor); it cannot "
                         f"be calibrated")
    if max(sweep.levels) > info.limits_um[0]:
        raise DeviceError(f"{link.label}: the device's amplitude limit {info.limits_um[0]:g} "
                         f"um is below the sweep's {max(sweep.levels):g} um")


def run_sweep(link, sweep: Sweep, on_step=None, first_index: int = 0):
    """Wait for a finger, stream the protocol to ``link`` (a paced ``CommandSink``, one
    channel) from sample ``first_index`` on and read the forces back; returns the points
    (w_um, normal_n, mu) as arrays.

    ``on_step(done, total)`` is called as each step's forces have come (progress).
    Raises DeviceError for a device that cannot be calibrated (:func:`check_calibratable`)
    or no finger on the plate, ``LinkStalled`` when a step's
    reports do not come, and :class:`StepCut` (a ``LinkStalled``) when they cover too
    little of it.
    """
    check_calibratable(link, sweep)
    per = int(round(sweep.step_s * link.rate_hz))
    kept = per - int(per * sweep.settle_share)
    steps = sweep.amplitudes()
    start = _wait_for_finger(link, first_index)
    ratios, normals = [], []
    sent = [start]  # one past the last sample sent

    def window(k: int) -> tuple[int, int]:
        return start + (k + 1) * per - kept, kept

    def take(k: int, forces) -> None:
        lateral, normal_n = forces
        normal = float(np.median(normal_n))
        if not normal >= MIN_NORMAL_N:
            raise DeviceError(f"{link.label}: normal force {normal:.3g} N during step {k + 1}: "
                             f"the finger lifted (slide it through the whole sweep)")
        pressed = normal_n >= MIN_NORMAL_N  # a sample of a lifting finger has no ratio
        ratio = float(np.median(np.abs(lateral[pressed]) / normal_n[pressed]))
        if steps[k] == 0.0:
            _check_rest_friction(link, k, ratio, float(np.median(np.abs(lateral))))
        ratios.append(ratio)
        normals.append(normal)
        if on_step is not None:
            on_step(k + 1, len(steps))

    def collect(upto: int) -> None:
        """Take the steps' forces in order, up to step ``upto``, as far as they have come."""
        while len(ratios) < upto:
            try:
                forces = _step_forces(link, *window(len(ratios)), len(ratios))
            except StepCut as cut:
                cut.next_index = sent[0]
                raise
            if forces is None:
                return
            take(len(ratios), forces)

    def send(index: int, amplitudes) -> None:
        link.send(index, amplitudes)
        sent[0] = index + len(amplitudes)

    for k, w in enumerate(steps):
        for lo in range(0, per, BLOCK_SAMPLES):
            send(start + k * per + lo, np.full((min(BLOCK_SAMPLES, per - lo), 1), w))
            collect(k)
    # the plate back at rest, for long enough that the reports go past the last step
    end = start + len(steps) * per
    for lo in range(0, 2 * LATE_SAMPLES, BLOCK_SAMPLES):
        send(end + lo, np.zeros((BLOCK_SAMPLES, 1)))
    deadline = time.monotonic() + 2 * sweep.step_s + REPORT_WAIT_S
    collect(len(steps))
    while len(ratios) < len(steps):
        if time.monotonic() > deadline:
            i0, n = window(len(ratios))
            raise LinkStalled(f"{link.label}: no force reports for samples {i0} to "
                              f"{i0 + n - 1} after {2 * sweep.step_s + REPORT_WAIT_S:g} s; "
                              f"the device stopped taking data or reporting")
        time.sleep(0.005)
        collect(len(steps))
    ratios, normals = np.array(ratios), np.array(normals)
    rest = 0.5 * (ratios[0:-1:2] + ratios[2::2])
    return np.array(sweep.levels), normals[1::2], ratios[1::2] / rest


def _check_rest_friction(link, k: int, ratio: float, lateral_n: float) -> None:
    """Raise DeviceError when rest step ``k``'s friction coefficient ``ratio`` (median
    |F_t| / F_n) is below ``MIN_REST_FRICTION``: mu0, which every mu' is divided by
    (seed 003, eq 1), is nil. ``lateral_n``: the step's median lateral force in size (N)."""
    if ratio >= MIN_REST_FRICTION:
        return
    raise DeviceError(f"{link.label}: the device reported no friction at rest: lateral force "
                      f"{lateral_n:.3g} N with the plate still (step {k + 1}), {ratio:.2g} "
                      f"of the normal force where a sliding fingertip gives 0.3 to 1.5; is "
                      f"the lateral force sensor connected and the finger sliding?")


def _step_forces(link, index0: int, n: int, k: int):
    """(lateral, normal) of step ``k``'s samples ``index0 .. index0 + n - 1``: all of them
    once reported; those reported once the reports have gone ``LATE_SAMPLES`` past them
    (the rest were dropped); None while they may still come."""
    whole = link.force_report(index0, n)
    if whole is not None:
        return whole.lateral_n, whole.normal_n
    latest = link.force_report()
    if latest is None or latest.index0 < index0 + n + LATE_SAMPLES:
        return None
    lateral, normal = link.forces_covered(index0, n)
    if lateral.size < MIN_COVERED * n:
        raise StepCut(f"{link.label}: the device's reports cover {lateral.size} of step "
                      f"{k + 1}'s {n} samples (it drops a report when it underruns or its "
                      f"watchdog trips: a host starved of CPU)")
    return lateral, normal


def _wait_for_finger(link, index: int) -> int:
    """Keep the plate at rest from sample ``index`` on until the device's reports show a
    finger pressing (at most ``TOUCH_WAIT_S``); returns the next sample to send."""
    deadline = time.monotonic() + TOUCH_WAIT_S
    while True:
        latest = link.force_report()
        if latest is not None and float(np.median(latest.normal_n)) >= MIN_NORMAL_N:
            return index
        if time.monotonic() > deadline:
            raise DeviceError(f"{link.label}: no finger on the plate after {TOUCH_WAIT_S:g} s "
                             f"(normal force below {MIN_NORMAL_N:g} N); touch it and slide")
        link.send(index, np.zeros((BLOCK_SAMPLES, 1)))  # paced: waits for the device's room
        index += BLOCK_SAMPLES
