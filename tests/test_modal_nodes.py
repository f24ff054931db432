"""Fingers on nodes of both of seed 001's plate modes: the plate at rest, counted capped.

A computed node is not exactly 0 (sin(17 pi/2 * 2/17) = 1.2e-16): the solver inverted
that rounding noise and the limit scaling drove V_AC to its 1 um limit for 0 um under
the finger, neither capped nor warned of."""

import json

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.device.actuation.modal import solve
from frictex.device.structures.plate2d import ACTUATORS, Plate2D
from frictex.textures.library import LIBRARY_DIR

PLATE = Plate2D(140, 140, 4, 57, 2561)  # seed 001's prototype, k = 8: nodes every 280/17 mm
NODE = 280 / 17


@pytest.mark.parametrize("method", ["exact", "regularised", "bounded"])
def test_a_finger_on_nodes_of_both_modes_gets_no_command(method):
    got = solve(PLATE.phi([NODE], [NODE]), [0.37], method, actuators=ACTUATORS, limits_um=1.0)
    assert np.array_equal(got.commands_um, np.zeros(2)) and got.capped and not got.limited
    np.testing.assert_allclose(got.error_um, [0.37], rtol=1e-12)


@pytest.mark.parametrize("method", ["exact", "regularised", "bounded"])
def test_a_micron_off_the_nodes_the_plate_is_still_driven(method):
    """1 um from the node the shapes are 1.9e-4: within reach, served as before."""
    got = solve(PLATE.phi([NODE + 1e-3], [NODE + 1e-3]), [0.37], method, actuators=ACTUATORS,
                limits_um=1.0)
    assert np.abs(got.commands_um).max() == pytest.approx(1.0) and not got.capped
    np.testing.assert_allclose(np.abs(got.achieved_um), [3.8148e-4], rtol=1e-3)


@pytest.mark.parametrize("method", ["exact", "regularised", "bounded"])
def test_a_replay_with_both_fingers_on_nodes_rests_and_warns(tmp_path, method):
    """Finger 0 at (280/17, 280/17) mm, finger 1 at (560/17, 840/17) mm: every sample had
    V_BD at the 1 um limit, none counted capped (a bounded scene's count came from the
    singular values alone)."""
    rows = [f"{0.02 * k:.2f},{f},{x!r},{y!r}" for k in range(20)
            for f, (x, y) in enumerate(((NODE, NODE), (2 * NODE, 3 * NODE)))]
    trace = tmp_path / "nodes.csv"
    trace.write_text("t_s,finger,x_mm,y_mm\n" + "\n".join(rows) + "\n", encoding="utf-8")
    scene = tmp_path / "plate.toml"
    text = (LIBRARY_DIR / "two-finger-plate-seed001.toml").read_text(encoding="utf-8")
    assert 'method = "regularised"' in text
    scene.write_text(text.replace('method = "regularised"', f'method = "{method}"'),
                     encoding="utf-8")
    out = tmp_path / "o"
    assert main(["replay", str(scene), str(trace), "--out", str(out),
                 "--rate", "1000", "--quiet"]) == 0
    summary = json.loads((out / "summary.json").read_text(encoding="utf-8"))
    commands = np.genfromtxt(out / "commands.csv", delimiter=",", names=True)
    assert summary["counts"]["contact_samples"] > 0
    assert summary["counts"]["modal_capped"] == summary["counts"]["contact_samples"]
    assert np.all(commands["V_AC_um"] == 0) and np.all(commands["V_BD_um"] == 0)
