"""The fit judged against the points' noise: noise alone keeps the model, a table follows
its columns' trend rather than single noisy points, the constants come with standard
errors, a fit stopped on a bound says so, and the sliding speed of the sweep is written;
too few amplitudes for the runs test leave the RMS to judge, and 2000 amplitudes are
tested as well as 12."""

import math
from types import SimpleNamespace

import matplotlib.figure
import numpy as np
import pytest

import frictex.app.commands.calibrate as calibrate
import frictex.device.link.host as host
from frictex.app.commands.cli import main
from frictex.device.calibration_fit import (B_BOUNDS, device_toml, few_runs_p, fit_points,
                                           model_jacobian, standard_errors)
from frictex.device.calibration_run import Sweep
from frictex.device.friction import forward_mu
from frictex.device.profile import FrictionParams
from frictex.textures.loader import load_scene

LEVELS_UM = np.array(Sweep().levels)  # the protocol's 12 levels, one point each
FORCE_N = np.full(LEVELS_UM.size, 0.5)
FINGER = FrictionParams(1.67, 1.13)


def noisy_sweeps(sd: float, count: int, finger: FrictionParams = FINGER, seed: int = 0):
    """``count`` sweeps' mu' of a finger following eq 2 exactly, plus noise of sd ``sd``."""
    rng = np.random.default_rng(seed)
    exact = forward_mu(LEVELS_UM, FORCE_N, finger)
    return [exact + rng.normal(0.0, sd, LEVELS_UM.size) for _ in range(count)]


def test_noise_alone_keeps_the_model():
    """Noise sd 0.03 puts the residual RMS above 0.02 in most sweeps (172 of 200 wrote a
    table, which fits the finger worse than the model); residuals without structure keep
    the model."""
    fits = [fit_points(LEVELS_UM, FORCE_N, mu) for mu in noisy_sweeps(0.03, 100)]
    assert sum(fit.residual_rms > 0.02 for fit in fits) > 60  # the old test's tables
    assert sum(fit.calibration is not None for fit in fits) <= 10


def test_a_table_is_not_pulled_down_by_one_low_point():
    """A step the model cannot follow, with one point 0.06 low at 1.6 um: a running
    minimum carried that point to every column after it (0.44 at 1.6 to 2.4 um); the
    decreasing regression pools it with its neighbours."""
    mu = np.where(LEVELS_UM < 1.2, 0.95, 0.5)
    mu[LEVELS_UM == 1.6] = 0.44
    fit = fit_points(LEVELS_UM, FORCE_N, mu)
    tail = np.array(fit.calibration.mu[0][1:])[LEVELS_UM >= 1.6]
    assert abs(tail.mean() - 0.5) < 0.015
    assert tail.max() > 0.48


def test_standard_errors_cover_the_true_b_as_often_as_they_say():
    """Noise sd 0.01: b varies about 5 % from sweep to sweep; b +- 1.96 standard errors
    covers the true b in about 95 % of sweeps."""
    fits = [fit_points(LEVELS_UM, FORCE_N, mu) for mu in noisy_sweeps(0.01, 200, seed=1)]
    b = np.array([fit.params.b_per_um for fit in fits])
    b_se = np.array([fit.b_se for fit in fits])
    k = np.array([fit.params.asymptote_per_n for fit in fits])
    k_se = np.array([fit.k_se for fit in fits])
    assert 0.88 < np.mean(abs(b - FINGER.b_per_um) < 1.96 * b_se) < 0.99
    assert 0.88 < np.mean(abs(k - FINGER.asymptote_per_n) < 1.96 * k_se) < 0.99
    assert 0.5 < np.median(b_se) / np.std(b) < 2.0


def test_a_fit_on_a_bound_says_b_is_not_determined():
    """A finger of b = 30 /um is fitted b = 20 /um, the upper bound, with a small residual."""
    fit = fit_points(LEVELS_UM, FORCE_N, forward_mu(LEVELS_UM, FORCE_N, FrictionParams(30.0, 1.13)))
    assert fit.params.b_per_um == pytest.approx(B_BOUNDS[1])
    assert fit.bound_notes == [f"b stopped on its upper bound {B_BOUNDS[1]:g} /um: the best fit "
                               "lies beyond it, so the points do not determine b (its value "
                               "and standard error are not estimates)"]
    assert fit_points(LEVELS_UM, FORCE_N, noisy_sweeps(0.0, 1)[0]).bound_notes == []


class ModelPlate:
    """A link to a plate announcing force reports; the sweep itself is replaced."""
    label = "model plate"
    info = SimpleNamespace(has_force_reports=True, limits_um=(2.5,), name="model plate")

    def close(self):
        pass


def calibrate_on(monkeypatch, finger: FrictionParams, *flags: str) -> int:
    """``frictex calibrate`` on a plate whose sweep gives eq 2's exact points of ``finger``."""
    monkeypatch.setattr(host, "open_sink", lambda *args, **kwargs: ModelPlate())
    monkeypatch.setattr(calibrate, "_sweeps", lambda link, sweep: (
        LEVELS_UM, FORCE_N, forward_mu(LEVELS_UM, FORCE_N, finger)))
    return main(["calibrate", "--device", "sim", *flags])


def test_calibrate_warns_of_a_fit_on_a_bound(monkeypatch, tmp_path, capsys):
    out = tmp_path / "device.toml"
    assert calibrate_on(monkeypatch, FrictionParams(30.0, 1.13), "--out", str(out)) == 0
    assert "frictex: warning: b stopped on its upper bound 20 /um" in capsys.readouterr().err
    assert "# b stopped on its upper bound 20 /um" in out.read_text()


def test_calibrate_gives_standard_errors_and_the_sweeps_speed(monkeypatch, tmp_path, capsys):
    """The printed fit and the written section give b and k with standard errors and say
    b applies at the sweep's 60 mm/s; the section still loads."""
    out = tmp_path / "device.toml"
    assert calibrate_on(monkeypatch, FINGER, "--out", str(out)) == 0
    printed = capsys.readouterr().out
    assert "fit at 60 mm/s sliding" in printed and "(standard errors of the points' scatter only" in printed
    text = out.read_text()
    assert "# standard error" in text and "applies at 60 mm/s sliding" in text
    scene = tmp_path / "scene.toml"
    scene.write_text('format = 1\nname = "c"\n[display]\nwidth_mm = 100.0\nheight_mm = 60.0\n'
                     'width_px = 100\nheight_px = 60\n' + text +
                     '[[layer]]\ntype = "disc"\nname = "d"\ncx_mm = 50.0\ncy_mm = 30.0\n'
                     'radius_mm = 10.0\nmu = 0.8\n')
    assert load_scene(scene).device.friction.b_per_um == pytest.approx(FINGER.b_per_um, rel=1e-5)


def test_the_plot_is_titled_with_the_fit_force_and_speed(monkeypatch, tmp_path):
    titles = []
    savefig = matplotlib.figure.Figure.savefig

    def saving(fig, *args, **kwargs):
        titles.append(fig.axes[0].get_title())
        return savefig(fig, *args, **kwargs)

    monkeypatch.setattr(matplotlib.figure.Figure, "savefig", saving)
    assert calibrate_on(monkeypatch, FINGER, "--out", str(tmp_path / "d.toml"),
                        "--plot", str(tmp_path / "fit.png")) == 0
    assert titles and "b 1.670" in titles[0] and "k 1.130" in titles[0]
    assert "RMS 0.0000" in titles[0] and "0.5 N, 60 mm/s sliding" in titles[0]



def test_the_runs_test_of_2000_amplitudes_is_a_probability():
    """Past about 1000 amplitudes the counts of arrangements overflowed: p was NaN and 2000
    noisy eq-2 points (RMS 0.03) were given a table for noise alone."""
    w = np.linspace(0.01, 2.4, 2000)
    force = np.full(w.size, 0.5)
    mu = forward_mu(w, force, FINGER) + np.random.default_rng(0).normal(0.0, 0.03, w.size)
    fit = fit_points(w, force, mu)
    assert fit.residual_rms > 0.02 and 0.05 < fit.runs_p <= 1.0 and fit.calibration is None
    stretches = np.tile([1.0] * 4 + [-1.0] * 4, 250)  # 500 runs where 1001 are expected
    assert 0.0 < few_runs_p(stretches) < 1e-100


def test_a_clear_misfit_at_five_amplitudes_gets_a_table_by_its_rms():
    """At 5 amplitudes the runs test's smallest p is 0.2: a linear fall (RMS 0.031, 1.6
    times the tolerance, below the ceiling) was kept as a fit; the RMS judges it, and the
    table says so."""
    w = np.repeat([0.5, 1.0, 1.5, 2.0, 2.4], 3)
    fit = fit_points(w, np.full(w.size, 0.5), 1.0 - 0.25 * w)
    assert not fit.fits and fit.calibration is not None and fit.judged_by == "RMS"
    assert fit.misfit_reason == ("residual RMS 0.031 above the tolerance 0.02; too few "
                                 "amplitudes for the runs test, whose smallest p here is 0.2")
    assert f"# the model does not fit ({fit.misfit_reason}): measured table" in \
        device_toml(fit, 2.5, 0.5)
    twelve = fit_points(LEVELS_UM, FORCE_N, 1.0 - 0.25 * LEVELS_UM)
    assert not twelve.fits and twelve.judged_by == "runs test"
    assert twelve.misfit_reason.startswith("its residuals run in long stretches")


def test_two_points_have_no_standard_error():
    """Two points fit (b, k) exactly: n - 2 = 0 degrees of freedom gave standard errors 0."""
    w, force = np.array([0.5, 2.0]), np.full(2, 0.5)
    jacobian = model_jacobian(w, force, FINGER.b_per_um, FINGER.asymptote_per_n)
    assert standard_errors(jacobian, np.zeros(2)) == (math.inf, math.inf)


def test_k_on_zero_is_its_physical_limit_not_an_undetermined_constant():
    """A finger of k = 0 (friction not depending on force) stops on k's lower bound in
    most sweeps at noise sd 0.01, with a standard error near 0.01 /N: the note says k is
    at its physical limit, not that the points do not determine it."""
    fits = [fit_points(LEVELS_UM, FORCE_N, mu)
            for mu in noisy_sweeps(0.01, 20, FrictionParams(1.67, 0.0))]
    on_zero = [fit for fit in fits if fit.at_bound == (("k", "lower"),)]
    assert len(on_zero) >= 5
    for fit in on_zero:
        assert fit.bound_notes == [f"k is 0 /N, its physical limit: the finger's friction does "
                                   f"not depend on the normal force, to within k's standard "
                                   f"error {fit.k_se:.2g} /N"]
        assert fit.k_se < 0.03
