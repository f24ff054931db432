"""What ``frictex bench`` prints from its samples: ratio targets judged on alternated
rounds with the whole interval beside the verdict, a paired difference with its t
interval, a p99 only where the samples are enough for one, and each figure's count. No
test times anything: steps, timers and samples are fakes."""

from __future__ import annotations

import math
from types import SimpleNamespace

import numpy as np
import pytest
from scipy.stats import t as student_t

from frictex.app.measure import bench_baseline, in_turn
from frictex.app.measure.bench_latency import _figures as latency_figures
from frictex.app.measure.bench_link import delay_figures, heartbeat_figures
from frictex.app.measure.bench_modal import error_figures
from frictex.app.measure.bench_startup import cache_cost_figure
from frictex.app.measure.processes import Run
from frictex.app.measure.tail import tail


class _Clock:
    """perf_counter and process_time of a process whose steps advance them."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def _timed_by(monkeypatch) -> _Clock:
    clock = _Clock()
    monkeypatch.setattr(in_turn, "time", SimpleNamespace(perf_counter=clock,
                                                         process_time=clock))
    return clock


def test_steps_in_turn_reverse_their_order_every_other_round_and_keep_each_rounds_time(
        monkeypatch):
    clock, log = _timed_by(monkeypatch), []

    def step(name, seconds):
        return lambda: (log.append(name), setattr(clock, "now", clock.now + seconds))

    got = in_turn.timed_in_turn([(step("a", 0.004), lambda: log.append("next")),
                                 (step("b", 0.002), None)], 4)
    assert log == ["next", "a", "b", "b", "next", "a"] * 2
    (a_wall, a_cpu), (b_wall, _) = got
    assert a_wall.tolist() == pytest.approx([0.004] * 4) and b_wall.tolist() == pytest.approx(
        [0.002] * 4)
    assert a_cpu.tolist() == pytest.approx([0.004] * 4)

    log.clear()
    clock.now = 0.0
    got = in_turn.timed_in_turn([(step("a", 0.004), lambda: log.append("next")),
                                 (step("b", 0.002), None)], 2, warmup=1)
    assert log == ["next", "a", "b"] + ["next", "a", "b", "b", "next", "a"]  # untimed first
    assert got[0][0].tolist() == pytest.approx([0.004] * 2)


def test_trace_reading_alternates_the_readers_and_judges_2x_on_each_rounds_ratio(
        monkeypatch, tmp_path):
    import pyarrow.csv as pcsv
    clock, log = _timed_by(monkeypatch), []

    def reader(name, seconds):
        return lambda *args, **kwargs: (log.append(name),
                                        setattr(clock, "now", clock.now + seconds))

    monkeypatch.setattr(bench_baseline, "read_trace", reader("frictex", 0.003))
    monkeypatch.setattr(pcsv, "read_csv", reader("pyarrow", 0.002))
    path = tmp_path / "t.csv"
    path.write_text("# a comment\nt_s,x_mm,y_mm\n0,0,0\n")
    figures = bench_baseline._reading_figures(path, reads=4)
    assert log == ["frictex", "pyarrow"] + ["frictex", "pyarrow", "pyarrow", "frictex"] * 2
    assert [f.label for f in figures] == [
        "reading the trace, frictex read_trace (median of 4, alternated)",
        "reading the trace, pyarrow.csv.read_csv (median of 4, alternated)",
        "reading the trace, frictex against pyarrow, target at most 2x (geometric mean of 4 "
        "rounds)"]
    assert figures[2].value == pytest.approx(1.5)


def test_trace_reading_gives_a_verdict_with_its_interval_not_a_ratio_of_medians():
    ours = np.array([2.0, 2.2, 1.9, 2.1, 2.4, 2.0, 2.3]) * 1e-3
    theirs = np.array([0.7, 1.4, 0.7, 1.5, 0.8, 1.4, 0.75]) * 1e-3
    [_, _, verdict] = bench_baseline.reading_figures(ours, theirs)
    logs = np.log(ours / theirs)
    half = student_t.ppf(0.975, 6) * logs.std(ddof=1) / math.sqrt(7)
    low, high = math.exp(logs.mean() - half), math.exp(logs.mean() + half)
    assert low < 2.0 < high  # 2.7x of the medians, yet the rounds settle nothing
    assert verdict.value == pytest.approx(math.exp(logs.mean()))
    assert verdict.unit == f"x (95 % interval {low:.2f}-{high:.2f}x): not shown"


def test_the_frame_against_the_floor_is_judged_on_each_rounds_ratio_with_its_interval():
    from frictex.app.measure.bench_visual import floor_figures
    read_wall = np.array([3.0, 2.0, 3.2, 1.9]) * 1e-3
    floor_wall = np.array([1.0, 1.5, 1.0, 1.5]) * 1e-3  # best against best: 1.9x
    cpu = np.full(4, 1e-3)
    figures = {f.label: f for f in floor_figures((read_wall, cpu), (floor_wall, cpu), "W")}
    verdict = figures["frame + read back / floor W, wall time per round, target at most 2x "
                      "(geometric mean of 4 rounds)"]
    logs = np.log(read_wall / floor_wall)
    half = student_t.ppf(0.975, 3) * logs.std(ddof=1) / 2.0
    assert verdict.value == pytest.approx(math.exp(logs.mean()))
    assert verdict.unit == (f"x (95 % interval {math.exp(logs.mean() - half):.2f}-"
                            f"{math.exp(logs.mean() + half):.2f}x): not shown")
    assert figures["frame + read back W"].value == pytest.approx(1.9)
    assert figures["floor W (clear, scene quad, read back; alternated with the frames)"
                   ].value == pytest.approx(1.0)
    assert not any("best against best" in f.unit for f in figures.values())


def _runs(walls, failed=()):
    return [Run(w, w, 50.0, 1 if k in failed else 0) for k, w in enumerate(walls)]


def test_the_bytecode_cache_cost_is_the_mean_of_paired_differences_with_a_t_interval():
    without = _runs([0.70, 0.62, 0.90, 0.66, 0.75])
    cached = _runs([0.66, 0.60, 0.80, 0.64, 9.0], failed={4})  # round 5 left out
    figure = cache_cost_figure(without, cached)
    d = np.array([0.04, 0.02, 0.10, 0.02])
    half = student_t.ppf(0.975, 3) * d.std(ddof=1) / 2.0
    assert figure.value == pytest.approx(d.mean() * 1e3)  # 45 ms; the medians differ by 60
    assert figure.label.endswith("(mean of 4 paired rounds' differences, 1 of 5 failed)")
    assert figure.unit == (f"ms (95 % interval {(d.mean() - half) * 1e3:.1f} to "
                           f"{(d.mean() + half) * 1e3:.1f} ms)")


def test_a_p99_of_100_samples_or_fewer_is_called_the_max():
    assert tail(np.arange(100.0)) == ("max", 99.0)
    name, value = tail(np.arange(1001.0))
    assert name == "p99" and value == pytest.approx(990.0)


def test_latency_of_20_touches_prints_their_max_not_a_p99():
    figures = latency_figures("trace", np.linspace(0.001, 0.020, 20), 20)
    assert [(f.label, f.value) for f in figures[:2]] == [
        ("trace: p50 of 20 played of 20 touches", pytest.approx(10.5)),
        ("trace: max of 20 played of 20 touches", pytest.approx(20.0))]


def test_force_report_delays_count_the_reports_and_give_the_load_of_the_run():
    figures = delay_figures(np.array([1, 1, 2, 5] * 10), 45, 0, 4.71)
    where = "live, 5 ms blocks, no busy processes added, load 4.7"
    assert [(f.label, f.value) for f in figures] == [
        (f"force report delay p50 of 40 reports ({where})", 1.5),
        (f"force report delay max of 40 reports ({where})", 5.0),
        (f"force reports lost ({where})", 5.0)]
    many = delay_figures(np.ones(400, np.int64), 400, 2, 6.0)
    assert [f.label.split(" of ")[0] for f in many[:3]] == [
        "force report delay p50", "force report delay p99", "force report delay max"]
    assert "beside 2 busy processes, load 6.0" in many[0].label


def test_modal_errors_count_their_samples():
    figures = error_figures("pinv random", np.full((500, 2), 0.01), np.zeros(500, bool))
    assert [f.label for f in figures] == ["pinv random: mean error (500 samples)",
                                          "pinv random: worst error (500 samples)",
                                          "pinv random: samples at a limit (500 samples)"]


def test_the_heartbeat_round_trip_counts_its_samples_and_is_a_max_when_few():
    """A link's status gives the round trips' count and max: 40 of them are labelled with
    their count and their tail is the max; 500 get a p99."""
    few = {"latency_samples": 40, "latency_ms_p50": 1.0, "latency_ms_p99": 2.9,
           "latency_ms_max": 3.0}
    assert [(f.label, f.value) for f in heartbeat_figures(few)] == [
        ("heartbeat round trip p50 of 40", 1.0), ("heartbeat round trip max of 40", 3.0)]
    many = {**few, "latency_samples": 500}
    assert heartbeat_figures(many)[1].label == "heartbeat round trip p99 of 500"
    assert heartbeat_figures(many)[1].value == 2.9
