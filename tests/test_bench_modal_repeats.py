"""``frictex bench modal``'s inversion times: each the median of several timed passes over
the samples, said in its unit. Nothing is timed: the module's clock is a fake whose first
pass of each method and case is slow."""

from types import SimpleNamespace

import pytest

from frictex.app.measure import bench_modal


class _SlowFirstPass:
    """perf_counter read as start, stop, start, stop...: every ``every``-th interval
    lasts ``slow`` s, the others 1 s."""

    def __init__(self, every: int, slow: float):
        self.every, self.slow, self.now, self.reads = every, slow, 0.0, 0

    def __call__(self) -> float:
        if self.reads % 2:
            interval = self.reads // 2
            self.now += self.slow if interval % self.every == 0 else 1.0
        self.reads += 1
        return self.now


def test_each_inversion_time_is_the_median_of_its_passes(monkeypatch):
    clock = _SlowFirstPass(bench_modal.REPEATS, slow=50.0)
    monkeypatch.setattr(bench_modal, "time", SimpleNamespace(perf_counter=clock))
    timed = [f for f in bench_modal.run(quick=True)
             if "time per sample" in f.label and not f.label.startswith("actuation")]
    assert bench_modal.REPEATS >= 5 and len(timed) == 6
    for figure in timed:  # one slow pass of 7, 500 samples a pass: 1 s / 500 per sample
        assert figure.value == pytest.approx(1e6 / 500, rel=1e-9), figure.label
        assert figure.unit == (f"us (wall time, median of {bench_modal.REPEATS} passes of "
                               "500 samples)")
