"""Fits and intervals the data cannot settle, said so rather than given as numbers:
every trial correct (a one-sided bound), a flat likelihood, zero-width intervals, d'
at perfect performance; and the checks that keep a session analysable: a threshold
target the fit can reach, a session counted once, a stopped
session warned of. Each number is checked against a computation written out here."""

import math
from pathlib import Path

import numpy as np
import pytest
from scipy import optimize, special, stats

from frictex.app.commands.cli import main
from frictex.app.experiment import psychometric as P
from frictex.app.experiment import same_different as SD
from frictex.app.experiment.analysis import ZERO_WIDTH, analyse_study, report_lines, unsettled
from frictex.app.experiment.protocol import check_protocol
from test_experiment_analysis_limits import forced, session

LEVELS = np.array([0.1, 0.25, 0.5, 0.75, 1.1, 1.6])
TESTED = [0.1, 0.25, 0.5, 0.75, 1.1, 1.6]


def weibull_nll(alpha, beta, lapse, x, n, k):
    """The binomial negative log likelihood of a 2afc Weibull, written out."""
    p = 0.5 + (0.5 - lapse) * (1.0 - np.exp(-(x / alpha) ** beta))
    return -np.sum(stats.binom.logpmf(k, n, p))


def test_every_trial_correct_gives_a_bound_not_a_threshold():
    """The review's all-correct session: threshold 0.02185, 95 % [0.02185, 0.02185], on
    the corner of the start grid, not flagged."""
    n = np.full(6, 20.0)
    fit = P.fit(LEVELS, n, n, bootstrap=200)
    # any threshold far enough below the lowest level fits the data as well: flat
    assert weibull_nll(0.01, 5.0, 0.0, LEVELS, n, n) == pytest.approx(
        weibull_nll(0.001, 5.0, 0.0, LEVELS, n, n), abs=1e-9)
    # the bound: the first threshold of the grid (60 a decade) at which every trial correct
    # has a probability under 5 % however the slope and lapse rate are set: 20 trials at
    # 0.1, a Weibull at its 75 % point there, already give 0.75^20 = 0.003
    assert 0.1 < fit.threshold_below < 0.1 * 10 ** (2 / 60) and math.isnan(fit.threshold)
    assert math.isnan(fit.slope) and all(map(math.isnan, fit.threshold_ci + fit.slope_ci))
    assert fit.unsettled == P.ALL_CORRECT
    rows = forced((d, True) for d in TESTED for _ in range(20))
    summary = analyse_study([session("2afc", rows)])
    assert summary["pooled"]["threshold_below"] == pytest.approx(fit.threshold_below)
    assert "below 0.103 period_mm difference (no threshold, slope or interval): every trial" \
        in "\n".join(report_lines(summary))


def test_a_few_trials_all_correct_bound_nothing_and_say_so():
    """Seven trials, all correct (2 at 0.1, 2 at 0.5, 2 at 0.75, 1 at 1.6): an observer
    whose 75 % point is 0.56 answers so one time in ten, yet the fit said the threshold
    lay below 0.1. A near-flat function at 0.75 makes them all correct with 0.75^7 = 0.13
    at any threshold: nothing is bounded."""
    x, n = np.array([0.1, 0.5, 0.75, 1.6]), np.array([2.0, 2, 2, 1])
    assert weibull_nll(16.0, 0.01, 0.0, x, n, n) < -math.log(P.ALL_CORRECT_P)
    fit = P.fit(x, n, n, bootstrap=0)
    assert fit.unsettled == P.ALL_CORRECT + P.TOO_FEW_TO_BOUND
    assert fit.threshold_below == math.inf and math.isnan(fit.threshold)
    rows = forced((float(d), True) for d, k in zip(x, n) for _ in range(int(k)))
    summary = analyse_study([session("2afc", rows)])
    assert "threshold (0.75 correct, weibull): not bounded (no threshold, slope or interval)" \
        in "\n".join(report_lines(summary))


def test_a_flat_likelihood_flags_both_intervals():
    """The review's stopped session: 10 trials, one error at the lowest level; the
    maximum-likelihood slope is infinite (the likelihood rises towards a step) and the
    fit stopped at beta e^3 on the start grid."""
    n = np.array([2.0, 2, 1, 2, 1, 2])
    k = np.array([1.0, 2, 1, 2, 1, 2])
    fit = P.fit(LEVELS, n, k, bootstrap=200)
    step = weibull_nll(0.2, 200.0, 0.0, LEVELS, n, k)  # a near step between 0.1 and 0.25
    assert step == pytest.approx(math.log(2.0), abs=1e-6)
    assert weibull_nll(fit.alpha, fit.beta, fit.lapse, LEVELS, n, k) >= step - 1e-9
    assert fit.unsettled and "flat" in fit.unsettled
    rows = forced((d, c) for d, nn, kk in zip(TESTED, n, k)
                  for c in [True] * int(kk) + [False] * int(nn - kk))
    pooled = analyse_study([session("2afc", rows)])["pooled"]
    for name in ("threshold", "slope"):
        assert pooled[f"{name}_ci95_unsettled"] == f"unsettled: {fit.unsettled}"


def test_a_settled_fit_is_not_flagged():
    n = np.full(6, 20.0)
    fit = P.fit(LEVELS, n, np.array([11.0, 13, 14, 18, 18, 19]), bootstrap=0)
    assert fit.unsettled is None and fit.threshold_below is None


def test_a_zero_width_interval_is_flagged():
    assert unsettled((0.5, 0.5)) == ZERO_WIDTH
    assert unsettled((0.5, 0.6)) is None


def differencing_d_prime(h, f):
    """d' under the differencing model, by brentq (Macmillan & Creelman ch. 9)."""
    k = -math.sqrt(2.0) * stats.norm.ppf(f / 2.0)
    hits = lambda d: (stats.norm.cdf((d - k) / math.sqrt(2.0))
                      + stats.norm.cdf((-d - k) / math.sqrt(2.0)) - h)
    return optimize.brentq(hits, 0.0, 40.0)


def test_perfect_same_different_has_a_width_and_a_flag():
    """The review: d_prime_interval(20, 20, 0, 20, 1000) was (5.998, 5.998)."""
    low, high = SD.d_prime_interval(20, 20, 0, 20, 1000)
    top = differencing_d_prime(20.5 / 21, 0.5 / 21)
    assert high == pytest.approx(top, abs=1e-9) and low < top - 0.5
    # the low end: the draws at the corrected rates, percentiles written out
    rng = np.random.default_rng(P.data_seed([20, 20, 0, 20]))
    h, f = rng.binomial(20, 20.5 / 21, 1000), rng.binomial(20, 0.5 / 21, 1000)
    d = [differencing_d_prime((a + 0.5) / 21, (b + 0.5) / 21) if a > b else 0.0
         for a, b in zip(h, f)]
    assert low == pytest.approx(np.percentile(d, 2.5), abs=1e-6)
    assert "lower bound" in SD.ceiling(20, 20, 0, 20)
    assert SD.ceiling(15, 20, 5, 20) is None and SD.ceiling(0, 20, 20, 20) is None


def test_logistic_credible_interval_is_of_positive_thresholds():
    """The review: 95 % [-0.04325, 0.06398] from a linear grid of -10 to 10 times the
    largest difference. Checked against a finer grid written out here, with the same
    priors (log threshold, log spread, lapse rate)."""
    x = np.array([0.01, 0.02, 0.03, 0.04, 0.05])
    n = np.array([20.0, 30, 40, 30, 20])
    k = np.array([11.0, 19, 31, 27, 19])
    target = 0.5 ** 0.5
    low, high = P.credible_threshold("logistic", x, n, k, target=target)
    assert low > 0.0
    t = np.geomspace(0.001, 0.5, 4000)
    spread = np.exp(np.linspace(math.log(0.01), 0.0, 61)) * 0.05
    lapse = np.linspace(0.0, 0.06, 7)
    T, S, L = np.meshgrid(t, spread, lapse, indexing="ij")
    f = (target - 0.5) / (0.5 - L)
    a = T - S * np.log(f / (1.0 - f))
    log_like = sum(stats.binom.logpmf(kk, nn, 0.5 + (0.5 - L) * special.expit((xx - a) / S))
                   for xx, nn, kk in zip(x, n, k))
    marginal = np.exp(log_like - log_like.max()).sum(axis=(1, 2))
    cumulative = np.cumsum(marginal) / marginal.sum()
    expected = np.interp([0.025, 0.975], cumulative, t)
    # within a step of frictex's grid (60 a decade: 3.9 %)
    assert (low, high) == pytest.approx(tuple(expected), rel=0.04)


def write(tmp_path, levels, analysis):
    path = tmp_path / "p.toml"
    path.write_text(f'format = 1\nmethod = "2afc"\n[stimuli]\nscene = "grating-5mm"\n'
                    f'vary = "period_mm"\nreference = 5.0\nlevels = {levels}\n'
                    f'[analysis]\n{analysis}\n', encoding="utf-8")
    return path


@pytest.mark.parametrize("levels, analysis, line, words", [
    ("[5.5, 6.5]", "target = 0.97\nlapse_max = 0.05", 9,
     "analysis.target: 0.97 is not below 1 - lapse_max (0.95)"),
])
def test_a_protocol_its_analysis_would_refuse_is_refused(tmp_path, levels, analysis, line,
                                                         words):
    path = write(tmp_path, levels, analysis)
    protocol, problems = check_protocol(path)
    assert protocol is None and len(problems) == 1
    assert str(problems[0]) == f"{path}:{line}: {words}" + str(problems[0]).split(words)[1]
    assert check_protocol(write(tmp_path, "[5.5, 6.5]", "target = 0.9"))[0] is not None


def test_a_session_given_twice_is_refused(tmp_path, capsys):
    folder = tmp_path / "s"
    folder.mkdir()
    assert main(["experiment", "analyse", str(folder), str(folder) + "/.",
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err.strip()
    assert len(err.splitlines()) == 1 and "is given twice" in err


def test_a_stopped_session_is_warned_of():
    rows = forced((d, True) for d in (0.2, 0.4) for _ in range(3))
    stopped = session("2afc", rows)
    stopped.info.update(ended_utc=None, parts=[{"ended": "stopped (Terminated)"}])
    summary = analyse_study([stopped])
    assert summary["session_ends"] == [{"session": str(Path("s")),
                                        "ended": "stopped (Terminated)", "main_trials": 6,
                                        "rows": 6, "trials_recorded": None,
                                        "torn_last_line": False, "row_problems": []}]
    assert "  warning: s did not run to its end (stopped (Terminated), 6 main trials)" \
        in "\n".join(report_lines(summary))
