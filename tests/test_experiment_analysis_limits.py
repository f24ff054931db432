"""The analysis at its limits, on recorded answers written out here (no pipeline): a
staircase held at its floor, too few trials for a fit, no trials, no bootstrap, one
session pooled; and same-different d' under the differencing model."""

from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from frictex.app.experiment import same_different as SD
from frictex.app.experiment.analysis import NOT_MEASURED, SessionData, analyse_study, report_lines

STAIRCASE = {"rule": "1-up-2-down", "start": 1.0, "steps": [2.0], "scale": "linear",
             "reversals": 12, "max_trials": 100, "threshold_reversals": 8, "min": None,
             "max": None}


def session(method, rows, staircase=None, bootstrap=200, target=0.75):
    design = {"vary": "period_mm", "reference": 5.0, "guess": 0.5, "target": target,
              "analysis": {"function": "weibull", "lapse_max": 0.06, "target": None,
                           "bootstrap": bootstrap},
              "staircase": staircase, "scale": None}
    info = {"protocol": "p", "method": method, "design": design}
    return SessionData(Path("s"), info, [{"practice": "0", **r} for r in rows])


def forced(pairs):
    return [{"difference": repr(d), "correct": str(int(c))} for d, c in pairs]


def afc_rows(seed=3):
    rng = np.random.default_rng(seed)
    levels = [0.2, 0.4, 0.6, 0.8]
    p = dict(zip(levels, [0.55, 0.7, 0.85, 0.95]))
    return forced((d, rng.random() < p[d]) for d in levels for _ in range(20))


def test_a_staircase_held_at_its_floor_is_flagged():
    """The review's linear staircase from 1 by steps of 2: down steps would reach -1, so
    the level stays at 1; each held step is counted and the fitted threshold, below the
    smallest level tested, is flagged as extrapolated."""
    # 1-up-2-down: 2 correct at 1 (held), an error (up to 3), 2 correct at 3 (down to 1)
    pairs = [(1.0, True)] * 4 + ([(1.0, False)] + [(3.0, True)] * 2 + [(1.0, True)] * 4) * 6
    summary = analyse_study([session("staircase", forced(pairs), STAIRCASE)])
    assert summary["held_at_floor"] == 2 + 2 * 6 and summary["held_at_ceiling"] == 0
    pooled = summary["pooled"]
    assert pooled["threshold"] < 1.0 and pooled["threshold_in_tested_range"] is False
    printed = "\n".join(report_lines(summary))
    assert "outside the differences tested, 1 to 3: extrapolated" in printed
    assert "14 down step(s) held at the floor" in printed


@pytest.mark.parametrize("pairs, words", [
    ([(1.0, True)], "1 trial at 1 difference: a fit needs at least 2"),
    ([(1.0, True), (1.0, False), (3.0, True)], "3 trials, 0 reversals: a staircase's fit "
                                               "needs at least 4"),
    ([], "no main trials"),
])
def test_too_few_staircase_trials_get_no_threshold(pairs, words):
    summary = analyse_study([session("staircase", forced(pairs), STAIRCASE)])
    assert summary["pooled"] is None and summary["per_session"][0]["fit"] is None
    assert summary["no_fit"] == words == summary["per_session"][0]["no_fit"]
    assert report_lines(summary)[1:] == [f"  no threshold: {words}"]


@pytest.mark.parametrize("method", ["same-different", "magnitude"])
def test_no_trials_is_said(method):
    assert report_lines(analyse_study([session(method, [])]))[1:] == ["  no main trials"]


def test_one_session_pooled_has_the_sessions_intervals():
    """Identical data, identical intervals: the bootstrap's seed comes from the data."""
    summary = analyse_study([session("2afc", afc_rows())])
    assert summary["pooled"] == summary["per_session"][0]["fit"]
    lo, hi = summary["pooled"]["threshold_ci95"]
    assert lo < summary["pooled"]["threshold"] < hi
    other = analyse_study([session("2afc", afc_rows(seed=4))])["pooled"]
    assert other["threshold_ci95"] != [lo, hi]


def test_no_bootstrap_prints_no_interval():
    summary = analyse_study([session("2afc", afc_rows(), bootstrap=0)])
    pooled = summary["pooled"]
    assert pooled["threshold_ci_method"] is None and pooled["slope_ci_method"] is None
    printed = "\n".join(report_lines(summary))
    assert printed.count("no interval (bootstrap = 0)") == 2 and "nan" not in printed
    assert "bootstrap" not in pooled  # the count is in the method's words, where one ran


def test_a_staircase_names_each_intervals_method():
    pairs = [(1.0, True)] * 4 + ([(1.0, False)] + [(3.0, True)] * 2 + [(1.0, True)] * 4) * 6
    pooled = analyse_study([session("staircase", forced(pairs), STAIRCASE, bootstrap=20,
                                    target=0.7071)])["pooled"]
    assert pooled["threshold_ci_method"].startswith("Bayesian 95 % credible interval")
    assert pooled["slope_ci_method"].endswith("20 runs; " + NOT_MEASURED)
    assert pooled["slope_definition"].startswith("d psi / dx at the threshold")


def test_differencing_d_prime_recovers_a_simulated_observer():
    """Observers of the differencing model (M&C 2005 ch. 9) simulated trial by trial:
    2 x 10^6 pairs each; d' from their rates is the d' simulated (sd of the estimate
    about 0.005), and the yes-no formula z(H) - z(F) gives less."""
    rng = np.random.default_rng(5)
    trials = 2_000_000
    for d, k in [(0.8, 1.0), (1.5, 1.2), (2.5, 2.0)]:
        same = np.abs(rng.normal(0, 1, trials) - rng.normal(0, 1, trials)) > k
        diff = np.abs(rng.normal(d, 1, trials) - rng.normal(0, 1, trials)) > k
        h, f = diff.mean(), same.mean()
        assert float(SD.d_prime(h, f)) == pytest.approx(d, abs=0.03)
        assert stats.norm.ppf(h) - stats.norm.ppf(f) < d - 0.1
    assert SD.d_prime(0.3, 0.4) == 0.0 and SD.d_prime(0.4, 0.4) == 0.0


def test_same_different_names_its_model_and_interval():
    rows = [{"value": "5.5", "answer": a, "response": r}
            for a, r in [("different", "different")] * 8 + [("different", "same")] * 2
            + [("same", "different")] * 2 + [("same", "same")] * 8]
    summary = analyse_study([session("same-different", rows, bootstrap=500)])
    level = summary["levels"][0]
    assert summary["d_prime_model"] == SD.MODEL
    lo, hi = level["d_prime_ci95"]
    assert lo < level["d_prime"] < hi
    assert level["d_prime"] == pytest.approx(float(SD.d_prime(8.5 / 11, 2.5 / 11)))
    assert "d': differencing model" in "\n".join(report_lines(summary))
    none = analyse_study([session("same-different", rows, bootstrap=0)])
    assert none["levels"][0]["d_prime_ci95"] is None and none["d_prime_ci_method"] is None
