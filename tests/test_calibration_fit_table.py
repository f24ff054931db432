"""A finger the model cannot follow gets its measured table from the protocol's own sweep
(one point per level), and points that cannot determine both constants are refused."""

import re
from types import SimpleNamespace

import numpy as np
import pytest

import frictex.app.commands.calibrate as calibrate
import frictex.device.link.host as host
from frictex.app.commands.cli import main
from frictex.device.calibration_fit import fit_points
from frictex.device.calibration_run import Sweep
from frictex.device.errors import InputError
from frictex.device.friction import forward_mu
from frictex.device.profile import FrictionParams
from frictex.textures.loader import load_scene

LEVELS_UM = np.array(Sweep().levels)  # 12 levels, 0.2 to 2.4 um, one point each
FORCE_N = 0.5


def step_finger(w_um):
    """mu' of a finger whose friction drops at once past 1.2 um: no exponential of eq 2."""
    return np.where(np.asarray(w_um) < 1.2, 0.95, 0.5)


def test_one_point_per_level_gives_one_column_per_level():
    fit = fit_points(LEVELS_UM, np.full(LEVELS_UM.size, FORCE_N), step_finger(LEVELS_UM))
    assert not fit.fits
    table = fit.calibration
    assert table.amplitudes_um == (0.0, *LEVELS_UM)
    assert table.forces_n == (FORCE_N,)
    row = np.array(table.mu[0])
    assert row[0] == 1.0 and np.all(np.diff(row) < 0)
    np.testing.assert_allclose(row[1:], step_finger(LEVELS_UM), atol=2e-5)


def test_more_levels_than_columns_are_binned_by_neighbouring_levels():
    w = np.linspace(0.1, 2.5, 48)  # 48 distinct amplitudes, one point each
    fit = fit_points(w, np.full(w.size, FORCE_N), step_finger(w))
    amplitudes = np.array(fit.calibration.amplitudes_um)
    np.testing.assert_allclose(amplitudes[1:], w.reshape(12, 4).mean(axis=1))


class StepLink:
    """A link to a plate announcing force reports; the sweep itself is replaced."""
    label = "step plate"
    info = SimpleNamespace(has_force_reports=True, limits_um=(2.5,), name="step plate")

    def close(self):
        pass


def test_calibrate_writes_the_table_it_says_it_wrote(monkeypatch, tmp_path, capsys):
    monkeypatch.setattr(host, "open_sink", lambda *args, **kwargs: StepLink())
    monkeypatch.setattr(calibrate, "_sweeps", lambda link, sweep: (
        LEVELS_UM, np.full(LEVELS_UM.size, FORCE_N), step_finger(LEVELS_UM)))
    out = tmp_path / "device.toml"
    assert main(["calibrate", "--device", "sim", "--out", str(out)]) == 0
    assert re.search(r"; the model does not fit \(residual RMS 0\.119 above the ceiling 0\.06, "
                     r"beyond noise whatever its pattern\): its measured table \(13 "
                     r"amplitudes\) written", capsys.readouterr().out)
    scene = tmp_path / "scene.toml"
    scene.write_text('format = 1\nname = "c"\n[display]\nwidth_mm = 100.0\nheight_mm = 60.0\n'
                     'width_px = 100\nheight_px = 60\n' + out.read_text() +
                     '[[layer]]\ntype = "disc"\nname = "d"\ncx_mm = 50.0\ncy_mm = 30.0\n'
                     'radius_mm = 10.0\nmu = 0.8\n')
    assert "# the model does not fit (residual RMS 0.119 above the ceiling" in out.read_text()
    table = load_scene(scene).device.calibration
    assert table is not None and table.amplitudes_um[1:] == tuple(LEVELS_UM)


@pytest.mark.parametrize("w_um", [np.full(12, 1.0), np.tile([0.0, 1.0, 2.0], 4)])
def test_points_at_fewer_than_three_amplitudes_are_refused(w_um):
    """At one amplitude eq 2 holds for a line of (b, k): 12 exact points of b 2.4, k 0.8 at
    1 um were 'fitted' b 5.34, k 0.904 with a residual of 4e-11; at two they fit exactly,
    whatever the finger."""
    normal = np.full(w_um.size, FORCE_N)
    mu = forward_mu(w_um, normal, FrictionParams(2.4, 0.8))
    with pytest.raises(InputError, match=r"at \d distinct amplitudes above 0 um \(within 1 nm "
                                         r"count as one\): expected at least 3 \(two "
                                         r"determine b and k"):
        fit_points(w_um, normal, mu)
