"""Calibration: the fit (device/calibration_fit.py) and ``frictex calibrate`` on the simulated plate."""

import math

import numpy as np
import pytest

from app.commands.cli import main
from device.calibration_fit import fit_points
from device.finger import draw_finger, moisture


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


def test_calibrate_recovers_the_simulated_finger_within_5_percent(tmp_path, capsys):
    out = tmp_path / "device.toml"
    assert main(["calibrate", "--device", "sim", "--finger", "4", "--out", str(out)]) == 0
    text = out.read_text()
    b = float(text.split("b_per_um = ")[1].split()[0])
    k = float(text.split("asymptote_per_n = ")[1].split()[0])
    finger = draw_finger(4)
    seconds = float(capsys.readouterr().out.split(" s of sliding")[0].split()[-1])
    assert seconds < 30.0
    # the finger's effective constants at the protocol's 60 mm/s, mid-run
    b_true = finger.b_per_um / (1 + 60.0 / finger.v_c_mm_s)
    k_true = finger.k_per_n * (1 + finger.k_drift * moisture(seconds / 2, finger))
    assert abs(b / b_true - 1) < 0.05
    assert abs(k / k_true - 1) < 0.05
    assert text.startswith("[device]\n")


def test_calibrate_writes_a_device_section_the_loader_accepts(tmp_path):
    from textures.loader import load_scene
    out = tmp_path / "device.toml"
    assert main(["calibrate", "--device", "sim", "--finger", "2", "--out", str(out),
                 "--plot", str(tmp_path / "fit.png")]) == 0
    scene = tmp_path / "scene.toml"
    scene.write_text('format = 1\nname = "c"\n[display]\nwidth_mm = 100.0\nheight_mm = 60.0\n'
                     'width_px = 100\nheight_px = 60\n' + out.read_text() +
                     '[[layer]]\ntype = "disc"\nname = "d"\ncx_mm = 50.0\ncy_mm = 30.0\n'
                     'radius_mm = 10.0\nmu = 0.8\n')
    fitted = float(out.read_text().split("b_per_um = ")[1].split()[0])
    assert load_scene(scene).device.friction.b_per_um == fitted
    assert (tmp_path / "fit.png").stat().st_size > 0


def test_a_port_is_a_one_line_error(capsys, tmp_path):
    assert main(["calibrate", "--device", "/dev/ttyUSB9", "--out", str(tmp_path / "x")]) == 2
    err = capsys.readouterr().err
    assert err.startswith("frictex: error: calibrate:") and err.count("\n") == 1
