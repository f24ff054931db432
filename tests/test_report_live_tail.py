"""``frictex report``'s live p99: over enough blocks to be one (``app.measure.tail``),
not the 100 blocks of a 0.5 s run, whose "p99" lies between the two largest."""

from __future__ import annotations

from frictex.app.commands import report
from frictex.app.measure.report_matrix import live_seconds, load
from frictex.app.measure.tail import P99_SAMPLES
from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.rendering.pipeline import build_pipeline


def test_quick_live_blocks_are_enough_for_a_p99_not_a_max():
    pipeline = build_pipeline(load("grating-5mm"), rate_hz=10_000.0)
    trace = sample(make_motion("human", speed_mm_s=60.0, duration_s=1.0, seed=7), 50.0,
                   noise_mm=0.05, seed=11)
    wall, cpu = live_seconds(pipeline, trace, report.QUICK_LIVE_S)
    assert wall.size == cpu.size >= P99_SAMPLES
