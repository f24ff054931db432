"""A simulated finger on the plate, run by the engine: the device side of a closed loop.

``FingerSink`` takes each block's commands to the simulated plate and finger
(``device.finger.FingerPlant``) and keeps what the sensors report; ``LoopStage`` hands
each report to the pipeline's loop as late as a link delivers it and runs the pipeline
with the reports come so far (the loop's measurement) and the latest one's normal force
(open and closed loop alike, as the live demo reads a device's normal force either way;
a replay to a device reads it with the loop on). The delays are a sequence of whole
blocks per block (0: before the next block; ``link_report_delays.LOST``: never), a
measured link's (``link_report_delays.measure``) or one constant, replayed from
``start`` and from its beginning again when it runs out. Reports travel one stream, so
none overtakes an earlier one. One run::

    sink = FingerSink(plant, speed_of, force_of)
    drive(LoopStage(pipeline, sink, (4,)), source, [sink], VirtualClock())
"""

from __future__ import annotations

from collections import deque
from collections.abc import Sequence

import numpy as np

from frictex.app.measure.link_report_delays import LOST
from frictex.device.finger import FingerPlant, lowpass, rest_mu, true_amplitude, true_mu
from frictex.device.link.forces import ForceHistory, ForceReport


def x_direction(vx_mm_s: np.ndarray) -> np.ndarray:
    """The way a finger slides along x, +1 or -1 per sample, from its x velocity (mm/s,
    (n,)): the sign of ``vx_mm_s``; where it is 0 (the finger still, or moving only in y)
    the last way it moved along x, +x before any (the plate's x sensor then reads the
    friction as the last x motion signed it)."""
    sign = np.concatenate([[1.0], np.sign(np.asarray(vx_mm_s, dtype=np.float64))])
    last_moved = np.maximum.accumulate(np.where(sign != 0, np.arange(sign.size), 0))
    return sign[last_moved][1:]


class FingerSink:
    """The plate under one finger. ``speed_of(t_s)``, ``force_of(t_s)``: the finger's true
    sliding speed (mm/s) and normal force (N) at output times (arrays (n,));
    ``direction_of(t_s)``: the way it slides along x there, +1 or -1 (:func:`x_direction`;
    None: always +x), which signs its lateral force as a device reports it (PROTOCOL.md
    4.9: positive where the finger drags the plate towards +x). The sign is put on the
    sensor's reading: at a reversal the finger slows below sliding first, so the friction
    it reads has fallen towards 0 when the sign turns.

    Keeps per touching sample: target mu', delivered mu', ``best``: what a controller
    knowing this finger exactly would deliver through the plate's amplitude loop (the
    finger's own inverse of the target, clipped to the limit, through the loop's
    low-pass), true speed and normal force, mu0 (the finger's friction at rest), time (s).
    """

    def __init__(self, plant: FingerPlant, speed_of, force_of, sensor_dead_after_s=None,
                 direction_of=None):
        self.plant = plant
        self.direction_of = direction_of
        self.state = plant.initial_state()
        self.speed_of = speed_of
        self.force_of = force_of
        self.dead_after_s = sensor_dead_after_s
        self.report: ForceReport | None = None
        self.rows: dict[str, list] = {k: [] for k in ("t", "target", "delivered", "best",
                                                       "speed", "force", "mu0")}
        self._ideal = 0.0  # the ideal controller's plate amplitude (um) after the last block
        self.max_command_um = 0.0

    def write(self, out, commands_um) -> None:
        t = out.t_s
        self.max_command_um = max(self.max_command_um, float(np.max(commands_um, initial=0.0)))
        touching = out.contact.any(axis=0)
        speed = np.where(touching, self.speed_of(t), 0.0)
        force = np.where(touching, self.force_of(t), 0.0)
        block, self.state = self.plant.step(out.index0, commands_um[:, 0], speed, force,
                                            self.state)
        dead = self.dead_after_s is not None and t.size and t[0] >= self.dead_after_s
        lateral = block.lateral_n if self.direction_of is None else (
            block.lateral_n * self.direction_of(t))
        self.report = None if dead else ForceReport(out.index0, lateral, block.normal_n)
        finger = self.plant.finger
        row = int(np.argmax(out.contact.any(axis=1))) if touching.any() else 0
        target = out.mu_target[row] if touching.any() else np.ones(t.size)
        ideal = np.where(touching, true_amplitude(target, force, speed, t, finger,
                                                  self.plant.limit_um), 0.0)
        ideal, self._ideal = lowpass(ideal, self.plant.plate_pole, self._ideal)
        if touching.any():
            keep = touching
            self.rows["t"].append(t[keep])
            self.rows["target"].append(target[keep])
            self.rows["delivered"].append(block.delivered_mu[keep])
            self.rows["best"].append(true_mu(ideal[keep], force[keep], speed[keep], t[keep],
                                             finger))
            self.rows["speed"].append(speed[keep])
            self.rows["force"].append(force[keep])
            self.rows["mu0"].append(rest_mu(t[keep], finger))

    def take_report(self) -> ForceReport | None:
        """The report of the last block written (once; None if the sensor is dead)."""
        report, self.report = self.report, None
        return report

    def arrays(self) -> dict[str, np.ndarray]:
        return {k: np.concatenate(v) if v else np.zeros(0) for k, v in self.rows.items()}

    def commit(self) -> None:
        """Nothing to finalise."""

    def abort(self) -> None:
        """Nothing to undo."""


class LoopStage:
    """The pipeline fed with ``sink``'s force reports, each ``report_delays[(start + k) %
    len]`` blocks after block k ends (see the module docstring)."""

    def __init__(self, pipeline, sink: FingerSink, report_delays: Sequence[int] = (0,),
                 start: int = 0):
        self.pipeline = pipeline
        self.sink = sink
        self.report_delays = tuple(int(d) for d in report_delays)
        self.start = int(start)
        self._last_due = 0  # the block the last report in flight is due at
        self.state = pipeline.initial_state()
        self.history = ForceHistory()
        self._in_flight: deque = deque()  # (first block that sees it, report), in order
        self.log_c: list[float] = []  # the loop's gain after each block (loop modes)
        self.first_mu0_s: float | None = None  # output time (s) the loop first knew mu0

    def process(self, k: int, samples, n: int):
        report = self.sink.take_report()  # block k - 1's
        delay = self.report_delays[(self.start + k - 1) % len(self.report_delays)]
        if report is not None and delay != LOST:
            self._last_due = max(k + delay, self._last_due)
            self._in_flight.append((self._last_due, report))
        while self._in_flight and self._in_flight[0][0] <= k:
            self.history.add(self._in_flight.popleft()[1])
        latest = self.history.latest()
        normal = None
        if latest is not None and latest.normal_n.size and latest.normal_n.mean() > 0.05:
            normal = float(latest.normal_n.mean())
        out, self.state = self.pipeline.process(k, samples, self.state, n_blocks=n,
                                                normal_force_n=normal,
                                                force_reports=self.history.window)
        control = self.state.control
        if control is not None:
            self.log_c.append(control.log_c)
            if self.first_mu0_s is None and np.isfinite(control.mu0):
                self.first_mu0_s = float(out.t_s[0])
        return out, out.commands_um
