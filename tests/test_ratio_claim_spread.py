"""Rounds that show nothing: all the same ratio (a clock too coarse to tell them apart),
and a round where frictex's own run took no measurable time."""

from __future__ import annotations

from frictex.app.commands.bench import failed_figures
from frictex.app.measure.bench_baseline import paired_figures
from frictex.app.measure.processes import Run
from frictex.app.measure.ratio_claim import ratio_claim, time_claim


def test_rounds_all_giving_the_same_ratio_show_nothing_and_say_why():
    claim = ratio_claim([1.19, 1.19, 1.19], 1.2, at_most=True)
    assert claim.verdict == "not shown"
    figure = claim.figure("baseline", "reading the trace", 1.2, at_most=True)
    assert figure.unit == ("x (every round the same ratio: no spread, no interval (clock "
                           "too coarse)): not shown")
    assert figure.value == 1.19


def test_rounds_with_some_spread_still_give_a_verdict():
    assert ratio_claim([1.01, 1.02, 1.01, 1.02], 1.2, at_most=True).verdict == "holds"


def _run(wall_s: float) -> Run:
    return Run(wall_s, wall_s / 2, 10.0, 0)


def test_a_round_where_frictex_took_no_measurable_time_is_left_out_not_a_crash():
    bare = [_run(1.0), _run(1.0), _run(1.0), _run(1.0)]
    ours = [_run(1.1), _run(0.0), _run(1.3), _run(1.2)]
    labels = [f.label for f in paired_figures("X", bare, ours, 1.2)]
    assert [label for label in labels if ", round " in label] == [
        "X, frictex against bare, round 1", "X, frictex against bare, round 3",
        "X, frictex against bare, round 4"]
    assert ("X, frictex against bare, target at most 1.2x (geometric mean of 3 rounds, 1 of 4 "
            "not measured (0 s))") in labels
    # no run failed: the bench's exit status must not say one did
    assert failed_figures(paired_figures("X", bare, ours, 1.2)) == []


def test_identical_rounds_say_no_interval_even_where_rounding_parts_its_ends():
    # the mean and deviation of 15 equal logs round to an interval an ulp wide
    claim = ratio_claim([0.47527085752291953] * 15, 1.2, at_most=True)
    assert claim.verdict == "not shown"
    assert claim.low == claim.high == claim.geomean
    assert claim.interval_text().startswith("every round the same ratio: no spread")


def test_identical_runs_against_a_time_bound_are_called_runs_and_times():
    claim = time_claim([0.1] * 5, 0.15)
    figure = claim.figure("startup", "--version", 0.15, at_most=True, unit=" s", of="runs")
    assert figure.unit == ("s (every run the same time: no spread, no interval (clock too "
                           "coarse)): not shown")
    assert time_claim([0.1], 0.15).interval_text(" s", "runs") == "one run, no interval"
