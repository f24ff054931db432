"""What the analysis says of a fit and a session, checked against numbers written out:
a steep fit's threshold judged apart from its slope (profile likelihood), a results
table cut short warned of, an interval's coverage quoted only for the design it was
measured on, a lapse rate on its bound, a staircase's geometric means, and the protocol
and perception checks of a staircase's max_trials and max."""

import itertools
import math
from pathlib import Path

import numpy as np
import pytest
from scipy import stats

from frictex.app.commands.cli import main
from frictex.app.experiment import psychometric as P
from frictex.app.experiment.analysis import (LAPSE_AT_BOUND, NOT_MEASURED, analyse_study,
                                             read_session, report_lines)
from frictex.app.experiment.perception_check import protocol_findings
from frictex.app.experiment.protocol import (Staircase, fewest_trials, load_protocol,
                                             staircase_warnings)
from frictex.app.experiment.scheduler import StaircaseState, staircase_step
from test_experiment_analysis_limits import STAIRCASE, forced, session

LEVELS = np.array([0.1, 0.25, 0.5, 0.75, 1.1, 1.6])
N = np.full(6, 20.0)


def weibull_nll(alpha, beta, lapse, k):
    """The binomial negative log likelihood of a 2afc Weibull at LEVELS, 20 trials each."""
    with np.errstate(over="ignore"):  # a step: (x / alpha) ** 403
        p = 0.5 + (0.5 - lapse) * (1.0 - np.exp(-(LEVELS / alpha) ** beta))
    return -np.sum(stats.binom.logpmf(k, N, p))


@pytest.fixture(scope="module")
def seed6(tmp_path_factory):
    """The review's session: period-2afc, Weber 0.06, seed 6 (counts 9, 15, 19, 19, 20,
    20 of 20)."""
    folder = tmp_path_factory.mktemp("seed6") / "s"
    assert main(["experiment", "period-2afc", "--participant", "simulated:weber=0.06,lapse=0",
                 "--seed", "6", "--out", str(folder), "--quiet"]) == 0
    return folder


def test_a_steep_fit_with_a_bounded_threshold_is_not_called_arbitrary(seed6):
    """Flagged 'its threshold and slope are arbitrary' before: the smallest eigenvalue
    of the local information goes to 0 for any steep fit."""
    summary = analyse_study([read_session(seed6)])
    fit = summary["pooled"]
    assert [level["correct"] for level in fit["levels"]] == [9, 15, 19, 19, 20, 20]
    assert fit["fit_unsettled"] is None and fit["slope_unsettled"] is None
    assert fit["threshold_ci95_unsettled"] is None and fit["slope_ci95_unsettled"] is None
    low, high = fit["threshold_ci95"]
    assert low < 0.30 < high  # the observer's 75 % point: 5 mm x 0.06
    # the threshold is bounded: a function through 75 % at a tenth of the lowest level,
    # or at ten times the highest, fits far worse than the fit (any slope, lapse)
    k = np.array([9.0, 15, 19, 19, 20, 20])
    best = weibull_nll(fit["alpha"], fit["beta"], fit["lapse"], k)
    for threshold in (0.01, 16.0):
        worst = min(weibull_nll(threshold / (-math.log(1 - (0.25 / (0.5 - lam)))) ** (1 / b),
                                b, lam, k)
                    for b in np.geomspace(0.0025, 403, 61) for lam in np.linspace(0, 0.06, 7))
        assert worst - best > P.PROFILE_DROP


def test_a_step_leaves_the_slope_bounded_below_and_the_threshold_settled():
    """Half right at 0.1 and every answer right from 0.25: a step between them fits as
    well as any function, so the slope is only bounded below; the threshold lies
    between the two levels all the same."""
    k = np.array([10.0, 20, 20, 20, 20, 20])
    fit = P.fit(LEVELS, N, k, bootstrap=200)
    step = weibull_nll(0.2, 403.0, 0.0, k)  # a step between 0.1 and 0.25
    # chance at 0.1, certainty above: the binomial at 0.1 alone
    assert step == pytest.approx(-stats.binom.logpmf(10, 20, 0.5), abs=1e-6)
    assert step - weibull_nll(fit.alpha, fit.beta, fit.lapse, k) < P.PROFILE_DROP
    assert fit.unsettled is None and fit.slope_unsettled == P.STEEP_SLOPE
    assert 0.1 <= fit.threshold_ci[0] and fit.threshold_ci[1] <= 0.25
    rows = forced((d, c) for d, kk in zip(LEVELS.tolist(), k)
                  for c in [True] * int(kk) + [False] * int(20 - kk))
    pooled = analyse_study([session("2afc", rows)])["pooled"]
    assert pooled["threshold_ci95_unsettled"] is None
    assert pooled["slope_ci95_unsettled"] == f"unsettled: {P.STEEP_SLOPE}"


STEP_LEVELS = np.array([0.1, 0.2, 0.3, 0.4, 0.5, 0.6])


@pytest.mark.parametrize("function", P.FUNCTIONS)
def test_a_step_is_the_steepest_spread_for_either_function(function):
    """Half right up to 0.3, every answer right from 0.4. The logistic's spread beta
    divides (x - alpha), so its steepest curve is its smallest beta, where the Weibull's
    is its largest: the logistic fit (beta 0.0035, a step) was not flagged. Shallow data,
    the logistic's flattest curve near as likely as its fit, are not flagged either."""
    k = np.array([10.0, 10, 11, 20, 20, 20])
    fit = P.fit(STEP_LEVELS, N, k, function=function, bootstrap=0)
    step = -np.sum(stats.binom.logpmf(k, N, np.where(STEP_LEVELS < 0.35, 0.5, 1.0)))
    fitted = -np.sum(stats.binom.logpmf(k, N, fit.psi(STEP_LEVELS)))
    assert step - fitted < P.PROFILE_DROP
    assert 0.3 < fit.threshold < 0.4
    assert fit.unsettled is None and fit.slope_unsettled == P.STEEP_SLOPE
    shallow = P.fit(STEP_LEVELS, N, np.array([11.0, 13, 14, 15, 16, 17]), function=function,
                    bootstrap=0)
    assert shallow.unsettled is None and shallow.slope_unsettled is None


def test_coverage_is_quoted_only_for_the_design_it_was_measured_on(seed6, tmp_path):
    """The bundled period-2afc, one complete session: its measured coverage; the same
    session's table cut to 46 trials: not measured for this design."""
    whole = analyse_study([read_session(seed6)])["pooled"]["slope_ci_method"]
    assert whole.endswith("; " + P.SLOPE_BCA_COVERAGE)
    cut = tmp_path / "cut"
    cut.mkdir()
    (cut / "session.json").write_bytes((seed6 / "session.json").read_bytes())
    (cut / "results.csv").write_bytes((seed6 / "results.csv").read_bytes()[:5000])
    summary = analyse_study([read_session(cut)])
    assert summary["pooled"]["slope_ci_method"].endswith("; " + NOT_MEASURED)


def test_a_results_table_cut_short_is_warned_of(seed6, tmp_path):
    """The review's t_mid: 5000 bytes of results.csv (46 main trials, the last line
    torn) were analysed with no word, session.json recording 124 trials."""
    data = (seed6 / "results.csv").read_bytes()
    for name, size, torn in (("torn", 5000, True), ("whole_lines", data.rfind(b"\n", 0, 5000) + 1,
                                                    False)):
        folder = tmp_path / name
        folder.mkdir()
        (folder / "session.json").write_bytes((seed6 / "session.json").read_bytes())
        (folder / "results.csv").write_bytes(data[:size])
        s = read_session(folder)
        rows = data[:size].count(b"\n") - 1  # the header's line end is not a row's
        summary = analyse_study([s])
        end = summary["session_ends"][0]
        assert (end["rows"], end["trials_recorded"], end["torn_last_line"]) == (rows, 124, torn)
        warning = (f"  warning: {folder}: results.csv holds {rows} of the 124 trials "
                   f"session.json records{'; its torn last line was skipped' * torn}: the "
                   f"table was cut short and the missing trials are not analysed")
        assert warning in report_lines(summary)
    assert not any("warning" in line for line in report_lines(analyse_study(
        [read_session(seed6)])))


def test_a_staircase_slope_interval_is_flagged_and_its_means_are_geometric():
    """A staircase's slope interval covered the true slope in 50 of 100 runs of the
    bundled depth-staircase: flagged, not a plain 95 %, without that figure here (a
    protocol of its own, two sessions). Two sessions' reversal thresholds average
    geometrically, as each session's reversals do on the log scale."""
    log = {**STAIRCASE, "scale": "log", "steps": [0.1], "reversals": 40, "max_trials": 400,
           "threshold_reversals": 4}
    rng = np.random.default_rng(1)
    sessions = []
    for name, alpha in (("a", 0.5), ("b", 0.8)):  # two observers' Weibull alpha
        sc, state, pairs = Staircase(**log), StaircaseState(1.0), []
        while len(state.reversals) < sc.reversals:
            p = 0.5 + 0.48 * (1.0 - math.exp(-(state.difference / alpha) ** 1.5))
            correct = bool(rng.random() < p)
            pairs.append((state.difference, correct))
            state = staircase_step(sc, state, correct)
        s = session("staircase", forced(pairs), log, bootstrap=20, target=0.7071)
        sessions.append(type(s)(Path(name), s.info, s.rows))
    summary = analyse_study(sessions)
    assert summary["pooled"]["slope_ci95_unsettled"] == P.RERUN_LOOSE
    each = [e["staircase"]["threshold"] for e in summary["per_session"]]
    assert each[0] != each[1]
    geometric = math.sqrt(each[0] * each[1])
    assert summary["staircase_threshold_mean"] == pytest.approx(geometric, rel=1e-12)
    assert (f"  staircases: geometric mean of the sessions' reversal geometric means "
            f"{geometric:.4g} period_mm") in report_lines(summary)


def test_a_lapse_rate_on_its_bound_is_flagged():
    """17 of 20 at each of the three highest levels: the fit wants lapses of 15 %, and
    its lapse rate stops on lapse_max (0.06)."""
    k = np.array([10.0, 12, 15, 17, 17, 17])
    rows = forced((d, c) for d, kk in zip(LEVELS.tolist(), k)
                  for c in [True] * int(kk) + [False] * int(20 - kk))
    summary = analyse_study([session("2afc", rows, bootstrap=0)])
    fit = summary["pooled"]
    assert fit["lapse"] == pytest.approx(0.06) and fit["lapse_at_bound"] == LAPSE_AT_BOUND
    assert any(line.endswith(f"; lapse 0.060 ({LAPSE_AT_BOUND})")
               for line in report_lines(summary))
    settled = forced((d, c) for d, kk in zip(LEVELS.tolist(), [11, 13, 14, 18, 18, 19])
                     for c in [True] * kk + [False] * (20 - kk))
    assert analyse_study([session("2afc", settled, bootstrap=0)])["pooled"][
        "lapse_at_bound"] is None


def test_fewest_trials_to_reach_the_threshold_reversals_is_exact():
    """1-up-2-down, 8 reversals: 13 trials can reach them (up, then down and up in
    turn), and no sequence of 12 answers does (all 4096 tried)."""
    sc = Staircase("1-up-2-down", 1.0, (0.1,), "log", 30, 10, 8, None, None)
    assert fewest_trials(sc, 8) == 13

    def reversals(answers):
        state = StaircaseState(sc.start)
        for correct in answers:
            state = staircase_step(sc, state, correct)
        return len(state.reversals)

    assert reversals([False] + [True, True, False] * 4) == 8
    assert max(reversals(a) for a in itertools.product([True, False], repeat=12)) < 8
    assert staircase_warnings(sc) == [
        "staircase.max_trials: 10 trials cannot reach the 8 reversals its threshold "
        "averages (1-up-2-down needs at least 13); the session would end without a "
        "reversal threshold"]
    assert staircase_warnings(Staircase("1-up-2-down", 1.0, (0.1,), "log", 30, 13, 8, None,
                                        None)) == []


STAIRCASE_PROTOCOL = """format = 1
name = "x"
method = "staircase"
[stimuli]
scene = "grating-5mm"
vary = "depth"
reference = 0.3
[presentation]
mode = "side-by-side"
exploration_s = 1.0
[staircase]
start = 0.005
max = {max}
"""


@pytest.mark.parametrize("top, flagged", [(0.01, True), (0.1, False)])
def test_a_staircase_max_below_the_threshold_is_flagged(tmp_path, top, flagged):
    """The review's st_below: depth 0.3 against at most 0.31 (3 %, under 11 %) passed
    with no warning; 0.4 (33 %) reaches the threshold."""
    path = tmp_path / "p.toml"
    path.write_text(STAIRCASE_PROTOCOL.format(max=top), encoding="utf-8")
    found = protocol_findings(load_protocol(path))
    assert [f.where for f in found] == ([f"stimuli 0.3 and {0.3 + top:g}"] if flagged else [])
    if flagged:
        assert "the staircase's largest comparison (its max)" in found[0].message


@pytest.mark.parametrize("max_trials, warned", [(10, True), (13, False)])
def test_check_and_a_run_warn_of_a_staircase_too_short_for_its_threshold(
        tmp_path, capsys, max_trials, warned):
    """`experiment --check` and a session of a protocol whose max_trials cannot reach its
    threshold reversals say so on stderr (the file stays valid: exit 0)."""
    path = tmp_path / "short.toml"
    path.write_text(STAIRCASE_PROTOCOL.format(max=0.1) + f"max_trials = {max_trials}\n")
    assert main(["experiment", str(path), "--check"]) == 0
    assert ("10 trials cannot reach the 8 reversals" in capsys.readouterr().err) == warned
    if warned:
        main(["experiment", str(path), "--participant", "simulated", "--out",
              str(tmp_path / "session")])
        assert "10 trials cannot reach the 8 reversals" in capsys.readouterr().err
