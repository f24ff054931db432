"""Live blocks are timed with the garbage collector frozen, as the live haptic process
runs, and the collector is unfrozen when the timing ends, so that what the same process
runs next (a later bench section, the report's next case) runs as it would."""

from __future__ import annotations

import gc
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.app.engine.driver import PipelineStage
from frictex.app.measure import bench_pipeline
from frictex.app.measure.live_timing import time_blocks
from frictex.app.measure.report_matrix import load
from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.rendering.pipeline import build_pipeline


class _FreezeWatch(PipelineStage):
    """A pipeline stage that keeps the collector's freeze count at each call, and fails
    on call ``fail_at`` (None: never)."""

    def __init__(self, pipeline, fail_at=None):
        super().__init__(pipeline)
        self.frozen: list[int] = []
        self.fail_at = fail_at

    def process(self, k, samples, n):
        self.frozen.append(gc.get_freeze_count())
        if len(self.frozen) == self.fail_at:
            raise RuntimeError("block failed")
        return super().process(k, samples, n)


def _small():
    pipeline = build_pipeline(load("grating-5mm"), rate_hz=10_000.0)
    trace = sample(make_motion("human", speed_mm_s=60.0, duration_s=0.1, seed=7), 50.0,
                   noise_mm=0.05, seed=11)
    return pipeline, trace


def test_blocks_run_frozen_and_the_collector_is_unfrozen_after():
    pipeline, trace = _small()
    gc.collect()  # something to freeze
    stage = _FreezeWatch(pipeline)
    wall, cpu = time_blocks(stage, trace, 0.05)
    assert wall.size == cpu.size == len(stage.frozen) == 10
    assert min(stage.frozen) > 0
    assert gc.get_freeze_count() == 0


def test_the_collector_is_unfrozen_when_a_block_fails():
    pipeline, trace = _small()
    with pytest.raises(RuntimeError, match="block failed"):
        time_blocks(_FreezeWatch(pipeline, fail_at=3), trace, 0.05)
    assert gc.get_freeze_count() == 0


def test_the_composed_scenes_live_blocks_are_timed_frozen_like_the_other_live_rows(
        monkeypatch):
    """Every live row of ``frictex bench pipeline`` goes through ``time_blocks``; the
    replays alone (200 blocks a call) through ``run_blocks``."""
    timed, per_call = [], []
    monkeypatch.setattr(bench_pipeline, "build_pipeline",
                        lambda *a, **k: SimpleNamespace(timer=None))
    monkeypatch.setattr(bench_pipeline, "load", lambda name: name)
    monkeypatch.setattr(bench_pipeline, "PipelineStage", lambda pipeline: pipeline,
                        raising=False)
    monkeypatch.setattr(bench_pipeline, "warmed_replay",
                        lambda build, trace, duration: (build(), np.ones(4)))
    monkeypatch.setattr(bench_pipeline, "stage_costs", lambda pipeline, duration: {})
    monkeypatch.setattr(bench_pipeline, "run_blocks", lambda pipeline, trace, blocks, d: (
        per_call.append(blocks), ([], np.ones(4)))[1])
    monkeypatch.setattr(bench_pipeline, "time_blocks", lambda stage, trace, d, sinks=(): (
        timed.append(stage), (np.ones(4), np.ones(4)))[1])
    monkeypatch.setattr(bench_pipeline, "loop_blocks", lambda mode, d: (np.ones(4),) * 2)
    monkeypatch.setattr(bench_pipeline, "new_layer_blocks",
                        lambda d, block=50: (np.ones(4), np.ones(4), {}))
    monkeypatch.setattr(bench_pipeline, "_modal_replay", lambda: [])
    bench_pipeline.run(quick=True)
    assert len(timed) == 2  # the file's renderers and hybrid
    assert all(blocks != 1 for blocks in per_call)
