"""The constant-stimuli intervals of psychometric.fit_sets: the slope's bias-corrected
and accelerated (BCa) bootstrap interval and its jackknife, and how often the threshold's
and the slope's intervals cover a known observer's at the bundled period-2afc design.

The observer is a Weibull two-interval observer, gamma 0.5, lapse rate 0.02, alpha
0.7094 mm and beta 1.2419 of period difference: the Weibull (lapse 0.02) closest in
least squares to the simulated participant's curve (Weber 0.11, lapse 0.02) against a
5 mm grating over 0-2 mm. Its threshold (75 % correct) and slope there are found here by
root finding and a central difference, not by the module's formulas.
"""

from pathlib import Path

import numpy as np
import pytest
from scipy.optimize import brentq

from frictex.app.experiment import psychometric as P
from frictex.app.experiment.protocol import load_protocol

BUNDLED = Path(__file__).resolve().parents[1] / "app" / "experiment" / "protocols"
ALPHA, BETA, LAPSE = 0.7094, 1.2419, 0.02


def observer(x):
    """The known observer's proportion correct at period difference ``x`` (mm)."""
    return 0.5 + (0.5 - LAPSE) * (1.0 - np.exp(-(np.asarray(x) / ALPHA) ** BETA))


def test_bca_without_bias_or_skew_is_the_percentile_interval():
    """Bootstrap estimates symmetric about the estimate (z0 = 0) and a symmetric
    jackknife (a = 0): the BCa ends are the 2.5th and 97.5th percentiles."""
    boot = np.concatenate([np.linspace(-3.0, -0.01, 500), np.linspace(0.01, 3.0, 500)])
    jack = np.array([-1.0, -0.5, 0.5, 1.0])
    ends = P.bca_interval([0.0], boot[None, :], jack[None, :], np.ones((1, 4)))[0]
    assert ends == pytest.approx(np.percentile(boot, [2.5, 97.5]), abs=1e-12)


def test_bca_moves_with_the_bootstrap_bias_and_skew():
    """Bootstrap estimates mostly below the estimate (z0 > 0) move both ends up against
    the percentile interval; a jackknife skewed to high values (a < 0 here: the
    estimates' mean minus each, cubed) moves them down."""
    boot = np.random.default_rng(4).normal(0.0, 1.0, 4000)
    even = np.array([-1.0, -0.5, 0.5, 1.0])[None, :]
    pct = np.percentile(boot, [2.5, 97.5])
    biased = P.bca_interval([0.3], boot[None, :], even, np.ones((1, 4)))[0]
    assert np.all(biased > pct)
    skewed = P.bca_interval([0.0], boot[None, :], np.array([[-0.2, -0.1, 0.0, 1.5]]),
                            np.ones((1, 4)))[0]
    assert np.all(skewed < pct)
    assert np.all(np.isfinite(P.bca_interval([9.0], boot[None, :], even, np.ones((1, 4)))))


def test_grouped_jackknife_is_the_delete_one_trial_jackknife():
    """The 2 J grouped refits' slopes, weighted by the trials each stands for, are the
    refits deleting each of the data's trials in turn (done here trial by trial)."""
    x = np.array([0.1, 0.5, 1.1, 1.6])
    n = np.array([5.0, 5.0, 4.0, 5.0])
    k = np.array([3.0, 5.0, 2.0, 4.0])  # the second level: no incorrect trial to delete
    s, w = P._jackknife_slopes("weibull", x, n, k[None, :], 0.5, 0.06, 0.75)
    grouped = np.sort(np.repeat(s[0], w[0].astype(int)))
    trials = [(j, c) for j in range(x.size) for c in [1] * int(k[j]) + [0] * int(n[j] - k[j])]
    N, K = np.tile(n, (len(trials), 1)), np.tile(k, (len(trials), 1))
    for row, (j, c) in enumerate(trials):
        N[row, j] -= 1
        K[row, j] -= c
    params = P.fit_many("weibull", x, N, K, 0.5, 0.06)
    _, one_by_one = P.threshold_and_slope("weibull", params[:, 0], params[:, 1], 0.5,
                                          params[:, 2], 0.75)
    assert len(trials) == n.sum() and grouped == pytest.approx(np.sort(one_by_one), rel=1e-9)


def test_intervals_cover_the_true_threshold_and_slope_at_the_bundled_design():
    """200 sessions of the bundled period-2afc design (six levels, 20 trials each: 120
    trials) drawn from the known observer, each fitted with its own 500 bootstrap sets
    (in batches of 50 sessions, to bound memory). The threshold's percentile interval
    covers the observer's 75 % point in about 92 % of sessions; the slope's BCa interval
    covers its slope in about 90 % (nominal 95 for both; the slope's percentile interval
    covered 77-83 %: this test fails with it), and it misses only on the steep side. The
    fitted slope is too steep: its median is some 20 % above the true one."""
    protocol = load_protocol(BUNDLED / "period-2afc.toml")
    x = np.asarray(protocol.stimuli.levels, dtype=np.float64) - protocol.stimuli.reference
    n = np.full(x.size, 2.0 * protocol.repetitions)
    assert n.sum() == 120
    true_t = brentq(lambda v: observer(v) - 0.75, 1e-6, 10.0, xtol=1e-14)
    h = 1e-6
    true_s = (observer(true_t + h) - observer(true_t - h)) / (2.0 * h)
    k = np.random.default_rng(11).binomial(n.astype(int), observer(x), size=(200, x.size))
    fits = [f for batch in range(4) for f in P.fit_sets(
        x, n, k[50 * batch:50 * (batch + 1)], function="weibull", bootstrap=500, seed=batch)]
    t_cover = np.mean([f.threshold_ci[0] <= true_t <= f.threshold_ci[1] for f in fits])
    s_cover = np.mean([f.slope_ci[0] <= true_s <= f.slope_ci[1] for f in fits])
    too_steep = np.mean([f.slope_ci[0] > true_s for f in fits])
    # binomial sd over 200 sessions: 0.015 at 0.95, 0.021 at 0.90
    assert 0.88 <= t_cover <= 0.99, t_cover
    assert 0.86 <= s_cover <= 0.99 and too_steep >= 1.0 - s_cover - 0.01, (s_cover, too_steep)
    assert 1.05 < np.median([f.slope for f in fits]) / true_s < 1.5
