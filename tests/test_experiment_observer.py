"""The simulated participant feels what the pipeline outputs and answers as its Weber
fraction says; the psychometric fit finds the likelihood's maximum, and its intervals
cover the observer's true threshold at their nominal rate.

"The threshold" here is the stimulus difference the observer answers correctly with the
probability a method targets: 75 % for two-interval forced choice by constant stimuli,
and for a 1-up-2-down staircase the 70.7 % point it converges on (Levitt 1971: p^2 = 1/2).
With a Weber fraction k, lapse rate l and the attribute felt proportional to the level
(a grating's depth: the friction contrast under the finger), it is
reference x (ratio_at(p, k, l) - 1), computed here from the model, not stored.
"""

import math
import shutil
from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import minimize

from frictex.app.experiment import psychometric as P
from frictex.app.experiment.analysis import analyse_study, read_session
from frictex.app.experiment.observer import (SimulatedParticipant, feel_scene, p_choose_larger,
                                             parse_spec, ratio_at)
from frictex.app.experiment.presenter import Shown
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import run_session
from frictex.app.experiment.scheduler import Trial
from frictex.app.experiment.stimuli import load_base, stimulus_doc, write_scene
from frictex.device.errors import InputError

ROOT = Path(__file__).resolve().parents[1]
GRATING = ROOT / "textures" / "library" / "grating-5mm.toml"
WEBER, LAPSE = 0.11, 0.02


def scene_with(tmp_path, vary, value):
    base = load_base(GRATING)
    return write_scene(stimulus_doc(base, vary, 0, value, None), tmp_path / f"{vary}{value}.toml",
                       base.folder)


def whole(scene):
    return (0.0, 0.0, scene.display.width_mm, scene.display.height_mm)


def test_felt_contrast_is_the_gratings_depth_and_period_its_period(tmp_path):
    for depth in (0.2, 0.35):
        felt = feel_scene(scene_with(tmp_path, "depth", depth), whole(scene_with(tmp_path, "depth", depth)), 1.0, 4)
        assert felt.contrast == pytest.approx(depth, abs=1e-12)
        assert 0.0 <= felt.fidelity <= 1.0
    periods = [feel_scene(s, whole(s), 2.0, 4).period_mm
               for s in (scene_with(tmp_path, "period_mm", p) for p in (4.0, 8.0))]
    # the path crosses lines at angles too: the felt period is the path's, a little longer
    assert periods[1] / periods[0] == pytest.approx(2.0, rel=0.1)
    assert 4.0 <= periods[0] <= 5.5


def test_answers_follow_the_weber_model(tmp_path):
    """Over many trials, the share of correct answers is p_choose_larger's."""
    a, b = (scene_with(tmp_path, "depth", d) for d in (0.3, 0.33))
    shown = [Shown(n, s, s.source.read_text(), whole(s), 1.0, False) for n, s in (("a", a), ("b", b))]
    observer = SimulatedParticipant(WEBER, LAPSE, seed=2)
    observer.attribute = "contrast"
    trials = 3000
    correct = sum(observer.present(Trial(i, False, ("a", "b"), 0.33, 0.03, "2", ("1", "2")),
                                   shown).response == "2" for i in range(1, trials + 1))
    p = float(p_choose_larger(0.33 / 0.3, WEBER, LAPSE))
    assert abs(correct / trials - p) < 4 * math.sqrt(p * (1 - p) / trials)


def test_weber_fraction_is_the_75_percent_ratio():
    assert float(p_choose_larger(1.0 + WEBER, WEBER, 0.0)) == pytest.approx(0.75, abs=1e-12)
    assert ratio_at(0.8, WEBER, LAPSE) == pytest.approx(
        float(np.exp(np.interp(0.8, p_choose_larger(np.exp(np.linspace(0, 1, 20001)), WEBER, LAPSE),
                               np.linspace(0, 1, 20001)))), rel=1e-6)


@pytest.mark.parametrize("spec, words", [("weber=0", "outside"), ("weber=x", "not a number"),
                                         ("lapse=1", "below 1"), ("speed=3", "key of"),
                                         ("weber=nan", "outside")])
def test_bad_participant_specs(spec, words):
    with pytest.raises(InputError, match=words):
        parse_spec(spec)


@pytest.mark.parametrize("function", P.FUNCTIONS)
def test_the_fit_is_the_likelihoods_maximum(function):
    """Against scipy.optimize.minimize from two starts on the same likelihood."""
    x = 0.3 * np.array([0.03, 0.06, 0.1, 0.15, 0.22, 0.32])
    n = np.full(x.size, 40.0)
    k = np.random.default_rng(3).binomial(40, p_choose_larger(1 + x / 0.3, WEBER, LAPSE),
                                          size=(25, x.size)).astype(float)
    params = P.fit_many(function, x, n, k, 0.5, 0.06)
    low, high = P._A_BOUNDS[function], P._B_BOUNDS
    u = x / x.max()
    for row, (alpha, beta, lam) in zip(k, params):
        if function == "weibull":
            mine = np.array([np.log(alpha / x.max()), np.log(beta), lam])
        else:
            mine = np.array([alpha / x.max(), np.log(beta / x.max()), lam])
        nll = lambda th: P._nll_only(th[None, :], function, u, n, row, 0.5)[0]
        best = min((minimize(nll, mine + d, method="L-BFGS-B", bounds=[low, high, (0, 0.06)])
                    for d in (np.zeros(3), np.array([0.3, -0.3, 0.02]))), key=lambda r: r.fun)
        assert nll(mine) <= best.fun + 1e-7


def test_the_fit_recovers_a_known_function():
    x = np.array([0.5, 1.0, 1.5, 2.0, 3.0])
    p = P.psi("weibull", x, 1.4, 2.5, 0.5, 0.02)
    n = np.full(x.size, 10**6)
    fit = P.fit(x, n, np.round(n * p), function="weibull", bootstrap=0)
    assert (fit.alpha, fit.beta, fit.lapse) == pytest.approx((1.4, 2.5, 0.02), rel=2e-3, abs=1e-4)
    threshold, slope = P.threshold_and_slope("weibull", 1.4, 2.5, 0.5, 0.02, 0.75)
    assert float(P.psi("weibull", threshold, 1.4, 2.5, 0.5, 0.02)) == pytest.approx(0.75)
    h = 1e-6
    numeric = (P.psi("weibull", threshold + h, 1.4, 2.5, 0.5, 0.02)
               - P.psi("weibull", threshold - h, 1.4, 2.5, 0.5, 0.02)) / (2 * h)
    assert float(slope) == pytest.approx(float(numeric), rel=1e-6)


def test_bad_fit_inputs():
    with pytest.raises(InputError, match="differences > 0"):
        P.fit([0.0, 1.0], [5, 5], [3, 4])
    with pytest.raises(InputError, match="between the guess rate"):
        P.fit([1.0, 2.0], [5, 5], [3, 4], target=0.97)


def test_constant_stimuli_intervals_cover_at_their_nominal_rate(tmp_path):
    """200 simulated 2afc sessions (depth 0.3 against six deeper gratings, 40 trials a
    level): the observer's correct answers are drawn from its model at the contrasts the
    pipeline renders (the cheap path: no per-trial pipeline), and the fits' 95 %
    intervals cover its 75 % point in about 95 % of the sessions."""
    reference = 0.3
    levels = reference + reference * np.array([0.03, 0.06, 0.1, 0.15, 0.22, 0.32])
    felt = {d: feel_scene(s, whole(s), 1.0, 7).contrast
            for d, s in ((d, scene_with(tmp_path, "depth", d)) for d in (reference, *levels))}
    p = p_choose_larger(np.array([felt[d] for d in levels]) / felt[reference], WEBER, LAPSE)
    true = reference * (ratio_at(0.75, WEBER, LAPSE) - 1.0)
    n = np.full(levels.size, 40)
    k = np.random.default_rng(2026).binomial(n, p, size=(200, levels.size))
    fits = P.fit_sets(levels - reference, n, k, function="weibull", bootstrap=100, seed=1)
    covered = sum(f.threshold_ci[0] <= true <= f.threshold_ci[1] for f in fits)
    assert 0.88 <= covered / 200 <= 0.99, covered  # nominal 0.95; binomial sd 0.015


@pytest.fixture(scope="module")
def staircases(tmp_path_factory):
    """20 sessions of the bundled 1-up-2-down depth staircase, each with its own simulated
    participant (Weber 0.11, lapse 0.02), analysed one by one (200 bootstrap runs each,
    not the bundled 1000); and the observer's 70.7 % point."""
    tmp_path = tmp_path_factory.mktemp("staircases")
    bundled = ROOT / "app" / "experiment" / "protocols" / "depth-staircase.toml"
    copy = tmp_path / "depth-staircase.toml"
    copy.write_text(bundled.read_text() + "\n[analysis]\nbootstrap = 200\n")
    protocol = load_protocol(copy)
    assert protocol.target == pytest.approx(0.5 ** 0.5)
    true = protocol.stimuli.reference * (ratio_at(protocol.target, WEBER, LAPSE) - 1.0)
    found = []
    for i in range(20):
        out = tmp_path / f"s{i}"
        run_session(protocol, SimulatedParticipant(WEBER, LAPSE, seed=100 + i), out, seed=i,
                    participant="simulated", record="results")
        found.append(analyse_study([read_session(out)])["per_session"][0])
        shutil.rmtree(out)
    return true, found


def test_staircases_find_the_observers_threshold_on_average(staircases):
    """The sessions' reversal means (geometric) and fitted 70.7 % points average to
    within 15 % of the observer's (single sessions scatter by about 35 %)."""
    true, found = staircases
    reversal = np.exp(np.mean([np.log(s["staircase"]["threshold"]) for s in found]))
    fitted = np.median([s["fit"]["threshold"] for s in found])
    assert reversal == pytest.approx(true, rel=0.15)
    assert fitted == pytest.approx(true, rel=0.15)


def test_staircase_intervals_cover_in_18_of_20(staircases):
    """The threshold's credible interval (psychometric.credible_threshold, the slope
    integrated out) covers the observer's 70.7 % point in at least 18 of the 20 sessions
    (20 measured; the percentile bootstrap's covered 17)."""
    true, found = staircases
    covered = sum(s["fit"]["threshold_ci95"][0] <= true <= s["fit"]["threshold_ci95"][1]
                  for s in found)
    assert covered >= 18, covered
