"""``frictex bench pipeline``: the haptic pipeline's speed on the composed scene, one finger,
10 kHz output, human-like strokes sampled at 120 Hz: headless replay (x real time),
live 5 ms blocks (p99 compute) and the cost of each stage (us per second of output);
and headless replay of two fingers with modal actuation (seed 000's beam, bundled
two-finger trace)."""

from __future__ import annotations

import numpy as np

from app.measure.figure import Figure
from app.measure.report_matrix import load, run_blocks
from rendering.input.trace_synth import make_motion, sample
from rendering.pipeline import build_pipeline

SCENE = "composed-fine-grating-in-disc"
MODAL_SCENE, MODAL_TRACE = "two-finger-beam-seed000", "two-fingers-crossing-50hz"
RATE_HZ = 10_000.0
BLOCK = 50  # 5 ms


def _trace(duration_s: float):
    return sample(make_motion("human", speed_mm_s=60.0, duration_s=duration_s, seed=7), 120.0,
                  noise_mm=0.05, seed=1)


def run(quick: bool) -> list[Figure]:
    duration = 2.0 if quick else 10.0
    trace = _trace(duration)
    figures = []
    for renderer in (None, "hybrid"):
        label = "file's renderers" if renderer is None else renderer
        replay = build_pipeline(load(SCENE), rate_hz=RATE_HZ, block_size=BLOCK,
                                render_override=renderer)
        _, seconds = run_blocks(replay, trace, 200, duration)
        compute = float(seconds.sum())
        figures.append(Figure("pipeline", f"replay compute only, {label}", duration / compute,
                              "x real time"))
        live = build_pipeline(load(SCENE), rate_hz=RATE_HZ, block_size=BLOCK,
                              render_override=renderer)
        _, per_block = run_blocks(live, trace, 1, duration)
        figures.append(Figure("pipeline", f"live 5 ms block p99, {label}",
                              float(np.percentile(per_block, 99) * 1e6), "us"))
        figures += _stage_figures(stage_costs(replay, duration), label)
    figures += _modal_replay()
    return figures


def _stage_figures(costs: dict[str, float], label: str) -> list[Figure]:
    """One figure per stage of ``costs`` (``stage_costs``)."""
    return [Figure("pipeline", f"  {name}, {label}", us, "us/s") for name, us in costs.items()]


def stage_costs(pipeline, duration: float) -> dict[str, float]:
    """Compute per stage and per layer of ``pipeline``'s runs so far (us per second of
    ``duration`` s of output)."""
    stages = dict(pipeline.timer.seconds)
    stages.pop("layers")
    stages.update({f"layer {k}": v for k, v in pipeline.timer.layer_seconds.items()})
    return {name: s / duration * 1e6 for name, s in stages.items()}


def modal_throughput() -> dict:
    """Headless replay of two fingers with modal actuation (seed 000's beam, the bundled
    two-finger trace, 10 kHz): ``replay_x_realtime`` and ``stages_us_per_s``."""
    from rendering.input.trace_file import read_trace
    from textures.library import resolve_trace
    trace = read_trace(resolve_trace(MODAL_TRACE))
    pipeline = build_pipeline(load(MODAL_SCENE), rate_hz=RATE_HZ, block_size=BLOCK,
                              t0_s=float(trace.t_s[0]))
    duration = trace.duration_s
    _, seconds = run_blocks(pipeline, trace, 200, duration)
    return {"scene": MODAL_SCENE, "trace": MODAL_TRACE, "output_hz": RATE_HZ,
            "replay_x_realtime": duration / float(seconds.sum()),
            "stages_us_per_s": stage_costs(pipeline, duration)}


def _modal_replay() -> list[Figure]:
    modal = modal_throughput()
    return [Figure("pipeline", "replay compute only, two fingers, modal beam (seed 000)",
                   modal["replay_x_realtime"], "x real time"),
            *_stage_figures(modal["stages_us_per_s"], "modal")]
