"""Fixed speed targets get a verdict from their own runs, worded as the ratio targets'
(holds / does not hold / not shown): a time under a bound from the geometric mean of its
runs and its 95 % interval (``ratio_claim.time_claim``), a p99 under a budget from a
distribution-free interval from order statistics (``quantile_claim``). Checked here
against scipy's binomial and t distributions, and on cases built on each side of the
bound."""

import math

import numpy as np
import pytest
from scipy.stats import binom
from scipy.stats import t as student_t

from frictex.app.measure import bench_pipeline, bench_startup
from frictex.app.measure.processes import Run
from frictex.app.measure.quantile_claim import quantile_claim, quantile_ranks
from frictex.app.measure.ratio_claim import time_claim


@pytest.mark.parametrize("n", [400, 500, 1000, 2000, 5000])
@pytest.mark.parametrize("q", [0.5, 0.9, 0.99])
def test_the_ranks_are_scipys_binomial_quantiles_and_cover_95_percent(n, q):
    low, high = quantile_ranks(n, q)
    assert low == int(binom.ppf(0.025, n, q))
    assert high == min(int(binom.ppf(0.975, n, q)) + 1, n + 1)
    if high <= n:
        assert binom.cdf(high - 1, n, q) - binom.cdf(low - 1, n, q) >= 0.95


def test_too_few_samples_give_the_p99_no_upper_end_and_no_verdict():
    claim = quantile_claim(np.full(300, 1e-6), 0.99, 500.0)
    assert claim.high == math.inf and claim.verdict == "not shown"
    assert claim.figure("pipeline", "x", "us").unit.endswith(
        "(95 % interval from 0.0000010 us, order statistic 293 of 300; too few samples for "
        "an upper end): not shown")  # no rank 301 of 300
    assert 367 == max(n for n in range(1, 1000) if 0.99 ** n > 0.025)  # the docstring's count


def _blocks_with_ranks_at(low_us: float, high_us: float) -> np.ndarray:
    """2,000 block times (us), shuffled, whose 1,971st smallest is ``low_us`` and
    1,989th ``high_us``: 300 us below, 1,000 us above."""
    low, high = quantile_ranks(2000, 0.99)
    ordered = np.concatenate([np.full(low - 1, 300.0), np.linspace(low_us, high_us, high - low + 1),
                              np.full(2000 - high, 1000.0)])
    return np.random.default_rng(3).permutation(ordered)


@pytest.mark.parametrize("low_us, high_us, verdict", [(480.0, 499.0, "holds"),
                                                      (501.0, 520.0, "does not hold"),
                                                      (480.0, 520.0, "not shown")])
def test_a_p99_holds_only_where_its_intervals_upper_end_is_under_the_budget(low_us, high_us,
                                                                            verdict):
    claim = quantile_claim(_blocks_with_ranks_at(low_us, high_us), 0.99, 500.0)
    assert (claim.low, claim.high, claim.verdict) == (low_us, high_us, verdict)


def test_the_pipeline_gives_each_thread_cpu_series_a_p99_verdict_on_10_percent_of_its_block():
    [*_, claim] = bench_pipeline.live_figures(_blocks_with_ranks_at(480.0, 520.0) * 1e-6,
                                              "every issue-18 layer", bench_pipeline.THREAD_CPU)
    assert claim.label == ("live 5 ms block, every issue-18 layer, thread CPU time, target p99 "
                           "under 500 us (95 % interval from the order statistics of 2,000 "
                           "blocks of one run, taken as independent: the claim is this "
                           "run's, at its load)")
    assert claim.unit == ("us (95 % interval 480.00 to 520.00 us, order statistics 1,971 and "
                          "1,989 of 2,000): not shown")


def _t_interval(seconds):
    """Geometric mean and 95 % interval of ``seconds``, from scipy's t."""
    logs = np.log(seconds)
    half = student_t.ppf(0.975, len(logs) - 1) * logs.std(ddof=1) / math.sqrt(len(logs))
    return tuple(math.exp(logs.mean() + k * half) for k in (0, -1, 1))


@pytest.mark.parametrize("seconds, verdict", [
    ([0.451, 0.468, 0.455, 0.462, 0.459], "holds"),
    ([0.451, 0.468, 0.543, 0.462, 0.459], "not shown"),  # one run on a loaded machine
    ([0.531, 0.548, 0.543, 0.552, 0.539], "does not hold")])
def test_a_time_under_a_bound_is_judged_from_its_runs_interval(seconds, verdict):
    claim = time_claim(seconds, 0.5)
    assert (claim.geomean, claim.low, claim.high) == pytest.approx(_t_interval(seconds),
                                                                  rel=1e-9)
    assert claim.verdict == verdict


def test_the_startup_target_figure_says_what_its_verdict_is_from():
    runs = [Run(s, 0.3, 50.0, 0) for s in (0.451, 0.468, 0.543, 0.462, 0.459)]
    figure = bench_startup.target_figure("frictex replay, one second, csv", runs, 0.5)
    low, high = _t_interval([r.wall_s for r in runs])[1:]
    assert figure.label == ("frictex replay, one second, csv, wall time per run (alternated), "
                            "target at most 0.5 s (geometric mean of 5 runs)")
    assert figure.unit == f"s (95 % interval {low:.2f}-{high:.2f} s): not shown"


@pytest.mark.parametrize("runs_ms, verdict", [([451.0, 468.0, 455.0], "holds"),
                                              ([451.0, 468.0, 543.0], "not shown")])
def test_a_bundled_scenes_static_image_is_judged_from_every_draw(runs_ms, verdict):
    from types import SimpleNamespace

    from frictex.app.measure import bench_visual
    comp = SimpleNamespace(viewport=SimpleNamespace(width_px=1920, height_px=1080))
    figure = bench_visual.static_target_figure(comp, "image grating-5mm", "1920x1080 on llvmpipe",
                                               runs_ms)
    assert figure.label == ("static image grating-5mm, 1920x1080 px drawn in the window "
                            "1920x1080 on llvmpipe, time per draw, target at most 0.5 s "
                            "(geometric mean of 3 draws)")
    assert figure.value == pytest.approx(_t_interval(np.array(runs_ms) / 1e3)[0])
    assert figure.unit.endswith(f": {verdict}")


def test_a_low_quantile_of_few_samples_has_an_upper_end_and_no_lower_one():
    """The p1 of 100 samples: no rank for its lower end, its upper end the 4th smallest."""
    claim = quantile_claim(np.arange(1, 101.0), 0.01, 50.0)
    assert claim.low == -math.inf and claim.high == 4.0
    assert claim.interval_text("us") == ("95 % interval up to 4.00 us, order statistic 4 of "
                                         "100; too few samples for a lower end")
