"""``frictex calibrate`` writes the sweep's measured points (``--points``; by default
beside ``--out``), from which the calibration re-fits: seed 003, eq 2 fitted to the
points the fit used gives the b and k the command wrote."""

import csv
import math

import numpy as np
import pytest
from scipy.optimize import curve_fit

from frictex.app.commands import calibrate
from frictex.app.commands.cli import main
from frictex.device import calibration_fit
from frictex.device.calibration_identity import B_BOUNDS, K_BOUNDS
from frictex.device.friction import forward_mu
from frictex.device.link import host
from frictex.device.profile import FrictionParams
from test_calibration_fit_noise import FORCE_N, LEVELS_UM, ModelPlate


def _eq2(x, b, k):
    """Seed 003, eq 2: mu' = (1 - k F_n) exp(-b w) + k F_n, x = (w um, F_n N)."""
    w, f = x
    return (1.0 - k * f) * np.exp(-b * w) + k * f


def _read(path):
    """The points file's columns: amplitude, force, mu' (floats) and the used flags."""
    with open(path, newline="", encoding="utf-8") as fh:
        rows = list(csv.reader(fh))
    assert rows[0] == ["amplitude_um", "normal_force_n", "mu", "used_in_fit"]
    w, f, m = (np.array([float(r[i]) for r in rows[1:]]) for i in range(3))
    return w, f, m, np.array([r[3] == "1" for r in rows[1:]])


def _refit(w, f, m):
    """(b, k) of eq 2 by ``curve_fit`` on the points, within the fit's bounds."""
    theta, _ = curve_fit(_eq2, (w, f), m, p0=(1.0, 0.5), method="trf",
                         bounds=([B_BOUNDS[0], K_BOUNDS[0]], [B_BOUNDS[1], K_BOUNDS[1]]),
                         ftol=1e-15, xtol=1e-15, gtol=1e-15)
    return theta


#: how close the re-fit comes to the command's fit: its solver stops at scipy's default
#: tolerances (1e-8), 2.2e-8 of b from the minimum on the points left out's test
REFIT_RTOL = 1e-7


def _written(text: str, key: str) -> float:
    return float(text.split(f"{key} = ")[1].split()[0])


@pytest.fixture
def fits(monkeypatch):
    """The fits the command makes, as it made them (the file rounds b and k)."""
    made = []

    def fit_points(*args, **kwargs):
        made.append(calibration_fit.fit_points(*args, **kwargs))
        return made[-1]
    monkeypatch.setattr(calibrate, "fit_points", fit_points)
    return made


def _on(monkeypatch, points, *flags):
    """``frictex calibrate`` on a plate whose sweep gives ``points`` (w, F_n, mu')."""
    monkeypatch.setattr(host, "open_sink", lambda *args, **kwargs: ModelPlate())
    monkeypatch.setattr(calibrate, "_sweeps", lambda link, sweep: points)
    return main(["calibrate", "--device", "sim", *flags])


def test_the_simulated_fingers_points_refit_to_what_was_written(fits, tmp_path, capsys):
    out = tmp_path / "device.toml"
    assert main(["calibrate", "--device", "sim", "--finger", "4", "--out", str(out)]) == 0
    points = tmp_path / "device-points.csv"
    assert f"wrote {points} (the 12 measured points, 12 of them used in the fit" in (
        capsys.readouterr().out)
    w, f, m, used = _read(points)
    assert used.all() and w.size == 12
    b, k = _refit(w, f, m)
    fit = fits[0].params
    assert b == pytest.approx(fit.b_per_um, rel=REFIT_RTOL)
    assert k == pytest.approx(fit.asymptote_per_n, rel=REFIT_RTOL)
    text = out.read_text()  # its 6 significant digits
    assert b == pytest.approx(_written(text, "b_per_um"), rel=1e-5)
    assert k == pytest.approx(_written(text, "asymptote_per_n"), rel=1e-5)


def test_points_left_out_are_written_and_marked(fits, monkeypatch, tmp_path, capsys):
    """A point not finite, one at a negative amplitude and one without normal force are
    written as they came, 0 in ``used_in_fit``; the rest re-fit."""
    rng = np.random.default_rng(3)
    w, f = LEVELS_UM.copy(), FORCE_N + rng.normal(0.0, 0.01, LEVELS_UM.size)
    m = forward_mu(w, f, FrictionParams(1.4, 0.9)) + rng.normal(0.0, 0.002, w.size)
    m[2], w[5], f[7] = np.nan, -0.1, 0.0
    m[9] = np.inf
    points = tmp_path / "sweep.csv"
    assert _on(monkeypatch, (w, f, m), "--out", str(tmp_path / "c.toml"),
               "--points", str(points)) == 0
    assert f"wrote {points} (the 12 measured points, 8 of them used in the fit" in (
        capsys.readouterr().out)
    got_w, got_f, got_m, used = _read(points)
    np.testing.assert_array_equal(got_w, w)
    np.testing.assert_array_equal(got_f, f)
    np.testing.assert_array_equal(got_m, m)  # nan and inf as they came
    assert np.flatnonzero(~used).tolist() == [2, 5, 7, 9]
    assert fits[0].n_dropped == 4
    b, k = _refit(got_w[used], got_f[used], got_m[used])
    assert math.isclose(b, fits[0].params.b_per_um, rel_tol=REFIT_RTOL)
    assert math.isclose(k, fits[0].params.asymptote_per_n, rel_tol=REFIT_RTOL)
    assert not (tmp_path / "c-points.csv").exists()


def test_no_points_beside_a_stream(monkeypatch, tmp_path, capsys):
    """--out /dev/null has no folder of its own: no points unless --points names a file."""
    exact = (LEVELS_UM, FORCE_N, forward_mu(LEVELS_UM, FORCE_N, FrictionParams(1.67, 1.13)))
    assert _on(monkeypatch, exact, "--out", "/dev/null") == 0
    assert "--points" not in capsys.readouterr().out


@pytest.mark.parametrize("argv, message", [
    (["--points", "{tmp}/c.toml"], "--points {tmp}/c.toml: the same file as --out "
                                   "{tmp}/c.toml"),
    (["--points", "{tmp}/p.png", "--plot", "{tmp}/p.png"],
     "--plot {tmp}/p.png: the same file as --points {tmp}/p.png"),
    (["--points", "{tmp}/missing/p.csv"], "--points {tmp}/missing/p.csv: the folder "
                                          "{tmp}/missing does not exist"),
    (["--points", "{tmp}"], "--points {tmp}: is a folder"),
])
def test_a_points_file_that_cannot_be_written_is_refused_before_the_device_opens(
        monkeypatch, tmp_path, capsys, argv, message):
    opened = []
    monkeypatch.setattr(host, "open_sink", lambda *args, **kwargs: opened.append(1))
    argv = [a.format(tmp=tmp_path) for a in argv]
    assert main(["calibrate", "--device", "sim", "--out", str(tmp_path / "c.toml"),
                 *argv]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and message.format(tmp=tmp_path) in err[0] and not opened
