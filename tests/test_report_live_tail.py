"""``frictex report``'s live p99: over enough blocks to be one (``app.measure.tail``),
not the 100 blocks of a 0.5 s run, whose "p99" lies between the two largest."""

from __future__ import annotations

import math

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


def _p99_verdict(blocks: int) -> str:
    from types import SimpleNamespace

    from frictex.app.measure import report_markdown as rmd
    head = {"sht/human": SimpleNamespace(replay_x_realtime=1e4,
                                         live_block_p99_thread_cpu_us=100.0,
                                         live_blocks=blocks)}
    settings = SimpleNamespace(jobs=2, cpu_count=2, load_1min=(1.0, 1.5))
    text = rmd._throughput_verdicts(head, settings)
    return text[text.index("live p99"):text.index("; latency")]


def test_a_live_p99_under_its_target_gets_no_verdict_from_the_rows():
    """Every row at 100 us read "met in every row" over 101 blocks; a p99's 95 % interval
    (``app.measure.quantile_claim``) has an upper end only where some block is above
    the p99 with 97.5 % probability: 1 - 0.99 ** n >= 0.975, n >= 368. The rows keep no
    blocks, so with more they still give no verdict."""
    fewest = math.ceil(math.log(0.025) / math.log(0.99))
    assert fewest == 368
    for blocks in (101, fewest - 1):
        text = _p99_verdict(blocks)
        assert "met in every row" not in text
        assert (f"every row's figure is under it, which is no verdict: a p99 of {blocks:,} "
                "blocks has no upper end to its 95 % interval") in text
    text = _p99_verdict(fewest)
    assert "met in every row" not in text
    assert "the rows keep their p99, not the blocks its 95 % interval is taken from" in text
