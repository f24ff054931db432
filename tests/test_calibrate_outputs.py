"""What ``frictex calibrate`` says of its outputs: a plot named for another format is
refused before the device opens; a measured table is said to be refused by closed-loop
replays; points left out as not finite are counted; a finger pressing too hard is a
failed run (exit 1) naming the press."""

import numpy as np

from frictex.app.commands import calibrate
from frictex.app.commands.cli import main
from frictex.device.friction import forward_mu
from frictex.device.link import host
from frictex.device.profile import FrictionParams
from test_calibration_fit_noise import FORCE_N, LEVELS_UM, ModelPlate


def calibrate_points(monkeypatch, mu, *flags, force_n=FORCE_N):
    """``frictex calibrate`` on a plate whose sweep gives the points (LEVELS_UM, force_n, mu)."""
    monkeypatch.setattr(host, "open_sink", lambda *args, **kwargs: ModelPlate())
    monkeypatch.setattr(calibrate, "_sweeps", lambda link, sweep: (LEVELS_UM, force_n, mu))
    return main(["calibrate", "--device", "sim", *flags])


def test_a_plot_not_named_png_is_refused_before_the_device_opens(monkeypatch, tmp_path, capsys):
    opened = []
    monkeypatch.setattr(host, "open_sink", lambda *args, **kwargs: opened.append(1))
    assert main(["calibrate", "--device", "sim", "--out", str(tmp_path / "c.toml"),
                 "--plot", str(tmp_path / "p.jpg")]) == 2
    err = capsys.readouterr().err
    assert "--plot" in err and "give a name ending in .png" in err
    assert len(err.strip().splitlines()) == 1 and not opened


def test_a_table_is_said_to_be_refused_by_closed_loop_replays(monkeypatch, tmp_path, capsys):
    seed = forward_mu(LEVELS_UM, FORCE_N, FrictionParams(1.67, 1.13))
    shuffled = np.random.default_rng(0).permutation(seed)
    out = tmp_path / "c.toml"
    assert calibrate_points(monkeypatch, shuffled, "--out", str(out)) == 0
    assert "[device.calibration]" in out.read_text()
    assert "'replay --control closed' refuses it" in capsys.readouterr().err


def test_points_not_finite_are_counted_on_stderr(monkeypatch, tmp_path, capsys):
    mu = forward_mu(LEVELS_UM, FORCE_N, FrictionParams(1.67, 1.13))
    mu[4] = np.inf
    assert calibrate_points(monkeypatch, mu, "--out", str(tmp_path / "c.toml")) == 0
    assert "frictex: warning: 1 points left out of the fit: not finite" in capsys.readouterr().err


def test_a_press_too_hard_is_exit_1_naming_it(monkeypatch, tmp_path, capsys):
    flat = np.ones(LEVELS_UM.size)
    assert calibrate_points(monkeypatch, flat, "--out", str(tmp_path / "c.toml"),
                            force_n=np.full(LEVELS_UM.size, 1.5)) == 1
    said = capsys.readouterr().err.strip().splitlines()[-1]
    assert said.startswith("frictex: error: the fitted mu' falls by only")
    assert "the finger pressed 1.5 N, too hard" in said
