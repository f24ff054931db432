"""Calibration: the fit (device/calibration_fit.py), the protocol over a link
(device/calibration_run.py) and ``frictex calibrate`` on the simulated device."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.device.calibration_fit import fit_points
from frictex.device.calibration_run import Sweep, run_sweep
from frictex.device.errors import DeviceError, RunFailed
from frictex.device.finger import draw_finger, moisture
from frictex.device.link.forces import ForceReport
from frictex.device.link.host import LinkStalled
from link_checks import start_sim_device


def test_fit_recovers_constants_of_exact_points():
    w = np.linspace(0.0, 2.5, 15)
    f = np.full(15, 0.45)
    b, k = 1.3, 0.9
    mu = (1 - k * 0.45) * np.exp(-b * w) + k * 0.45
    fit = fit_points(w, f, mu)
    assert math.isclose(fit.params.b_per_um, b, rel_tol=1e-6)
    assert math.isclose(fit.params.asymptote_per_n, k, rel_tol=1e-6)
    assert fit.residual_rms < 1e-8 and fit.calibration is None


def test_a_curve_the_model_cannot_follow_gets_a_table():
    w = np.repeat(np.linspace(0.0, 2.5, 11), 4)
    mu = 1.0 - 0.4 * (w / 2.5) ** 3  # a late, steep drop: not an exponential
    fit = fit_points(w, np.full(w.size, 0.5), mu)
    assert not fit.fits
    row = fit.calibration.mu[0]
    assert row[0] == 1.0 and all(a > b for a, b in zip(row, row[1:]))


def test_too_few_points_is_a_clear_error():
    with pytest.raises(ValueError, match="usable calibration points"):
        fit_points([0.0, 0.0], [0.5, 0.5], [1.0, 1.0])


def test_a_flat_curve_is_refused_not_fitted():
    # a finger whose friction does not fall (mu' 1 at every amplitude): k F = 1 fits it
    # exactly for every b, so there is nothing to fit; the same with noise 0.01
    w = np.repeat(np.linspace(0.0, 2.5, 11), 4)
    noise = np.random.default_rng(3).normal(0.0, 0.01, w.size)
    for mu in (np.ones(w.size), np.clip(1.0 - 0.01 * w + noise, 0.0, 1.0)):
        with pytest.raises(RunFailed, match="did not fall with vibration"):
            fit_points(w, np.full(w.size, 0.5), mu)


def test_a_small_but_clear_fall_is_fitted():
    w = np.repeat(np.linspace(0.0, 2.5, 11), 4)
    mu = (1 - 0.9 * 0.5) * np.exp(-1.3 * w) + 0.9 * 0.5
    mu = 1.0 - 0.1 * (1.0 - mu) / (1.0 - mu.min())  # a 0.1 fall, eq 2's shape
    fit = fit_points(w, np.full(w.size, 0.5), mu)
    assert fit.fits and math.isclose(fit.params.b_per_um, 1.3, rel_tol=1e-4)


class ModelLink:
    """A paced link to a plate whose finger follows seed 003's eq 2 exactly (b, k), its
    friction at rest rising linearly with time, its reports coming one block late;
    ``dropped``: (first, last) samples whose reports the device dropped (an underrun)."""

    def __init__(self, b, k, normal_n=0.5, drift_per_s=0.02, dropped=None):
        self.info = SimpleNamespace(has_force_reports=True, limits_um=(2.5,))
        self.rate_hz, self.label = 10_000.0, "model"
        self.b, self.k, self.normal_n, self.drift = b, k, normal_n, drift_per_s
        self.dropped = dropped
        self.w = np.zeros(0)

    def send(self, index0, amplitudes):
        assert index0 == self.w.size
        self.w = np.concatenate([self.w, amplitudes[:, 0]])

    def _forces(self, index0, n):
        i = np.arange(index0, index0 + n)
        kf = self.k * self.normal_n
        mu = (1 - kf) * np.exp(-self.b * self.w[index0:index0 + n]) + kf
        mu0 = 0.6 * (1 + self.drift * i / self.rate_hz)
        reported = np.ones(n, bool) if self.dropped is None else ~(
            (i >= self.dropped[0]) & (i <= self.dropped[1]))
        return mu0 * mu * self.normal_n, np.full(n, self.normal_n), reported

    def force_report(self, index0=None, n=None):
        played = self.w.size - 50
        if index0 is None:
            return ForceReport(played - 40, *self._forces(played - 40, 40)[:2]) if played >= 40 else None
        if index0 + n > played:
            return None
        lateral, normal, reported = self._forces(index0, n)
        return ForceReport(index0, lateral, normal) if reported.all() else None

    def forces_covered(self, index0, n):
        lateral, normal, reported = self._forces(index0, min(n, self.w.size - 50 - index0))
        return lateral[reported], normal[reported]


def test_the_sweep_gives_eq_2s_points_with_a_linear_drift_cancelled():
    """Independent of the fit: each point is eq 2 at its level, to the drift's rounding."""
    w, normal, mu = run_sweep(ModelLink(1.4, 0.8), Sweep())
    kf = 0.8 * 0.5
    expected = (1 - kf) * np.exp(-1.4 * w) + kf
    assert_allclose = np.testing.assert_allclose
    assert_allclose(w, Sweep().levels)
    assert_allclose(normal, 0.5)
    # the median of a linearly rising ratio is its middle; the rests' mean is the middle
    # of the rests on either side, the same time: the drift cancels to first order
    assert_allclose(mu, expected, rtol=1e-3)
    fit = fit_points(w, normal, mu)
    assert abs(fit.params.b_per_um / 1.4 - 1) < 0.01 and abs(fit.params.asymptote_per_n / 0.8 - 1) < 0.01


def test_reports_a_device_dropped_are_done_without_or_refuse_the_step():
    """An underrun drops a report: a step missing a tenth of its reports is taken over the
    rest (eq 2 exactly, no drift); one missing over a fifth is refused, naming it."""
    per, kept = 5000, 3000
    start = 100  # after the two blocks of rest the wait for a finger sends
    step = 3  # the second level's step
    first = start + (step + 1) * per - kept
    kf = 0.8 * 0.5
    w, _, mu = run_sweep(ModelLink(1.4, 0.8, drift_per_s=0.0,
                                   dropped=(first + 1000, first + 1299)), Sweep())
    np.testing.assert_allclose(mu, (1 - kf) * np.exp(-1.4 * w) + kf, rtol=1e-12)
    with pytest.raises(LinkStalled, match="cover 2000 of step 4's 3000 samples"):
        run_sweep(ModelLink(1.4, 0.8, dropped=(first, first + 999)), Sweep())


def test_a_sweep_cut_by_a_starved_host_is_run_again_from_where_it_stopped(capsys):
    """calibrate's sweeps: the first loses a fifth of step 4's reports; the second starts
    past all the first sent and gives eq 2's points; three cut sweeps are an error."""
    from frictex.app.commands.calibrate import SWEEPS, _sweeps
    first = 100 + 4 * 5000 - 3000  # step 4's kept samples in the first sweep
    link = ModelLink(1.4, 0.8, drift_per_s=0.0, dropped=(first, first + 999))
    w, _, mu = _sweeps(link, Sweep())
    kf = 0.8 * 0.5
    np.testing.assert_allclose(mu, (1 - kf) * np.exp(-1.4 * w) + kf, rtol=1e-12)
    err = capsys.readouterr().err
    assert err.count("frictex: warning: model: the device's reports cover 2000 of step 4's "
                     "3000 samples") == 1 and f"sweeping again (2 of {SWEEPS})" in err
    every_sweep = ModelLink(1.4, 0.8, dropped=(0, 10**9))
    with pytest.raises(LinkStalled, match=f"in each of {SWEEPS} sweeps: calibrate again"):
        _sweeps(every_sweep, Sweep())


def test_a_device_without_force_reports_or_a_lower_limit_is_refused():
    link = ModelLink(1.4, 0.8)
    link.info.has_force_reports = False
    with pytest.raises(DeviceError, match="sends no force reports"):
        run_sweep(link, Sweep())
    link = ModelLink(1.4, 0.8)
    link.info.limits_um = (2.0, 4.0)  # only channel 0 is driven
    with pytest.raises(DeviceError, match="limit 2 um is below the sweep's 2.4 um"):
        run_sweep(link, Sweep())


def test_calibrate_recovers_the_simulated_finger_within_5_percent(tmp_path, capsys):
    """Through the simulated device's link and force reports, as on a plate; the section
    written is one the loader accepts."""
    from frictex.textures.loader import load_scene
    out = tmp_path / "device.toml"
    assert main(["calibrate", "--device", "sim", "--finger", "4", "--out", str(out),
                 "--plot", str(tmp_path / "fit.png")]) == 0
    text = out.read_text()
    b = float(text.split("b_per_um = ")[1].split()[0])
    k = float(text.split("asymptote_per_n = ")[1].split()[0])
    finger = draw_finger(4)
    printed = capsys.readouterr()
    seconds = float(printed.out.split(" s of sliding")[0].split()[-1])
    assert seconds < 30.0
    assert "calibrating: step 25/25" in printed.err
    # the 25 steps the progress counts are 12 amplitude steps between 13 rest steps
    assert "12 points from 25 steps in 12.5 s of sliding (one per amplitude step" in printed.out
    assert "13 rest steps" in printed.out
    assert f"wrote {out} (the [device] section" in printed.out
    assert f"wrote {tmp_path / 'fit.png'} (the measured points" in printed.out
    # the finger's effective constants at the protocol's 60 mm/s, mid-run
    b_true = finger.b_per_um / (1 + 60.0 / finger.v_c_mm_s)
    k_true = finger.k_per_n * (1 + finger.k_drift * moisture(seconds / 2, finger))
    assert abs(b / b_true - 1) < 0.05
    assert abs(k / k_true - 1) < 0.05
    assert text.startswith("[device]\n") and "amplitude_limit_um = 2.5\n" in text
    scene = tmp_path / "scene.toml"
    scene.write_text('format = 1\nname = "c"\n[display]\nwidth_mm = 100.0\nheight_mm = 60.0\n'
                     'width_px = 100\nheight_px = 60\n' + text +
                     '[[layer]]\ntype = "disc"\nname = "d"\ncx_mm = 50.0\ncy_mm = 30.0\n'
                     'radius_mm = 10.0\nmu = 0.8\n')
    device = load_scene(scene).device
    assert device.friction.b_per_um == b
    # what it was fitted on: the simulated device's handshake name and finger 4
    assert device.fitted.finger == 4 and device.fitted.device
    assert f'device = "{device.fitted.device}"' in text
    assert (tmp_path / "fit.png").stat().st_size > 0


def test_a_port_is_a_one_line_error(capsys, tmp_path):
    assert main(["calibrate", "--device", "/dev/ttyUSB9", "--out", str(tmp_path / "x")]) == 1  # the device, not the input (exit 2)
    err = capsys.readouterr().err.splitlines()
    assert len(err) == 1 and err[0].startswith("frictex: error: ") and "/dev/ttyUSB9" in err[0]
    assert not (tmp_path / "x").exists()


def test_no_finger_on_the_plate_is_said_after_the_wait(monkeypatch):
    import frictex.device.calibration_run as run
    monkeypatch.setattr(run, "TOUCH_WAIT_S", 0.05)
    link = ModelLink(1.4, 0.8, normal_n=0.0)
    with pytest.raises(DeviceError, match="no finger on the plate after 0.05 s"):
        run_sweep(link, Sweep())


def test_a_device_without_a_force_sensor_is_a_one_line_error(capsys, tmp_path):
    proc, path = start_sim_device(1, 10_000.0)  # no --finger: no force reports
    try:
        assert main(["calibrate", "--device", path, "--out", str(tmp_path / "x")]) == 1
        proc.wait(timeout=10)  # --once: it ends when the host closes the link
    finally:
        if proc.poll() is None:
            proc.kill()
            proc.wait(timeout=10)
    err = capsys.readouterr().err.splitlines()
    assert err[-1].startswith(f"frictex: error: {path}: the device sends no force reports")
    assert not any("slide a finger" in line for line in err)  # refused before asking
