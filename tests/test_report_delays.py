"""Force-report delays: measured on a live link, replayed block by block in the report's
closed-loop runs (issue 31: the report takes them from a loaded link, not a constant)."""

import json
from types import SimpleNamespace

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.app.measure.closed_loop_sim import LoopStage
from frictex.app.measure.link_report_delays import LOST, ReportDelays, measure
from frictex.device.link.forces import ForceReport
from frictex.rendering.control.loop import LoopConfig


class _Pipeline:
    """Records, per block, which block's report is the latest the stage handed over
    (each report's normal force is its block's number + 1)."""

    def __init__(self):
        self.latest: list[int | None] = []

    def initial_state(self):
        return SimpleNamespace(control=None)

    def process(self, k, samples, state, n_blocks, normal_force_n, force_reports):
        self.latest.append(None if normal_force_n is None else round(normal_force_n) - 1)
        return SimpleNamespace(t_s=np.zeros(1), commands_um=np.zeros((1, 1))), state


class _Sink:
    """Block k - 1's report when block k asks (as ``FingerSink`` after each write)."""

    def __init__(self):
        self.block = 0

    def take_report(self):
        if self.block == 0:
            self.block += 1
            return None
        self.block += 1
        j = self.block - 2
        return ForceReport(j * 25, np.zeros(25), np.full(25, j + 1.0))


def _expected_latest(delays: list[int], start: int, blocks: int) -> list[int | None]:
    """Written out: block j's report is due at block j + 1 + its delay, but not before an
    earlier report (one stream); the latest handed over at block k is the newest due."""
    due, last, out, newest = {}, 0, [], None
    for j in range(blocks):
        d = delays[(start + j) % len(delays)]
        if d != LOST:
            last = max(last, j + 1 + d)
            due[j] = last
    for k in range(blocks):
        for j, at in due.items():
            if at == k:
                newest = j if newest is None else max(newest, j)
        out.append(newest)
    return out


@settings(max_examples=200, deadline=None)
@given(st.lists(st.integers(min_value=-1, max_value=12), min_size=1, max_size=40),
       st.integers(min_value=0, max_value=100))
def test_the_stage_hands_each_report_over_as_late_as_the_sequence_says(delays, start):
    pipeline, blocks = _Pipeline(), 60
    stage = LoopStage(pipeline, _Sink(), delays, start)
    for k in range(blocks):
        stage.process(k, None, 1)
    assert pipeline.latest == _expected_latest(delays, start, blocks)


def test_a_constant_delay_is_the_old_fixed_lateness():
    pipeline = _Pipeline()
    stage = LoopStage(pipeline, _Sink(), ReportDelays.constant(3).blocks)
    for k in range(10):
        stage.process(k, None, 1)
    # block j's report first used by block j + 4: three whole blocks after j ends
    assert pipeline.latest == [None] * 4 + [0, 1, 2, 3, 4, 5]


def test_delays_read_back_from_json_and_say_their_distribution():
    d = ReportDelays((2, 3, LOST, 3, 5, 2, 3), seconds=1.5, rate_hz=5000.0, block=25, busy=2,
                     load_start=0.5, load_end=2.5)
    doc = json.loads(json.dumps(d.to_json()))
    assert ReportDelays.from_json(doc) == d
    assert doc["max"] == 5 and doc["lost"] == 1 and doc["p50"] == 3.0
    assert doc["counts"] == {"2": 2, "3": 3, "5": 1}
    assert d.measured and not ReportDelays.constant(3).measured
    assert ReportDelays((LOST, LOST)).largest() == 0
    starts = {d.start_for(seed) for seed in range(50)}
    assert starts <= set(range(7)) and len(starts) > 1
    assert d.start_for(4) == d.start_for(4)


def test_a_live_link_beside_a_busy_process_gives_a_delay_per_block():
    """What holds however the scheduler treats it: one entry per block kept, each a
    report's whole blocks of delay within the loop's wait, or LOST; reports came."""
    d = measure(1.0, 5000.0, 25, busy=1)
    wait = int(np.ceil(LoopConfig().max_wait_s * 5000.0 / 25))
    n = 200 + wait
    assert len(d.blocks) == n - wait - 1 - n // 10
    assert all(b == LOST or 0 <= b <= wait for b in d.blocks)
    assert d.come().size > 0
    assert d.busy == 1 and d.seconds == 1.0 and d.measured
