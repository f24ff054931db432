"""``frictex bench closed-loop``: the live block budget with the friction loop on.

The seed 003 15 mm grating at 10 kHz in 5 ms blocks (50 samples), one block per pipeline
call as the live haptic thread runs it, a simulated finger (person 1) answering each
block with its force report. Figures: compute per block (pipeline with the loop, not
the simulated finger) at the median and the 99th percentile, for open loop and the
adaptive loop; the budget is 500 us at p99.
"""

from __future__ import annotations

import time

import numpy as np

from app.measure.figure import Figure


class _Timed:
    """A stage that times only the pipeline call."""

    def __init__(self, stage):
        self.stage = stage
        self.seconds: list[float] = []
        self.cpu_seconds: list[float] = []

    def process(self, k, samples, n):
        t, c = time.perf_counter(), time.thread_time()
        result = self.stage.process(k, samples, n)
        self.cpu_seconds.append(time.thread_time() - c)
        self.seconds.append(time.perf_counter() - t)
        return result


def run(quick: bool) -> list[Figure]:
    from app.engine.clocks import VirtualClock
    from app.engine.driver import drive
    from app.engine.sources import TraceSource
    from app.measure.closed_loop_sim import FingerSink, LoopStage
    from app.measure.report_closed_loop import finger_force, finger_speed
    from app.measure.report_matrix import load
    from device.finger import FingerPlant, draw_finger
    from rendering.input.trace_synth import make_motion, sample
    from rendering.pipeline import build_pipeline
    duration = 2.0 if quick else 10.0
    scene = load("grating-15mm")
    motion = make_motion("human", speed_mm_s=60.0, duration_s=duration, seed=1)
    trace = sample(motion, 50.0, noise_mm=0.05, seed=101)
    figures = []
    for mode in ("open", "adaptive"):
        pipeline = build_pipeline(scene, rate_hz=10_000.0, block_size=50, control=mode)
        plant = FingerPlant(draw_finger(1), 10_000.0, scene.device.amplitude_limit_um, seed=1)
        sink = FingerSink(plant, finger_speed(motion), finger_force(1))
        stage = _Timed(LoopStage(pipeline, sink))
        source = TraceSource(iter([trace]), until_s=duration)
        source.start(pipeline.tracker_config)
        drive(stage, source, [sink], VirtualClock())
        for clock, seconds in (("wall", stage.seconds), ("cpu", stage.cpu_seconds)):
            us = np.array(seconds) * 1e6
            figures += [Figure("closed-loop", f"5 ms block median ({clock}), {mode}",
                               float(np.median(us)), "us"),
                        Figure("closed-loop", f"5 ms block p99 ({clock}), {mode}",
                               float(np.percentile(us, 99)), "us")]
    return figures
