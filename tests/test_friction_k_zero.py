"""k = 0 (seed 003 eq 2's asymptote A = k F_n = 0: friction not depending on the normal
force) is the fit's lower bound and a physical value: calibrate writes it as 0, texture
files accept it, and a replay inverts eq 3 there as w = -ln(mu') / b."""

import math

import numpy as np
import pytest

import frictex
from frictex.device.calibration_fit import device_toml, fit_points
from frictex.textures.errors import TextureError
from frictex.textures.loader import load_scene

SCENE = """format = 1
name = "k0"
[display]
width_mm = 108.0
height_mm = 64.8
width_px = 800
height_px = 480
{device}
[[layer]]
type = "grating"
name = "lines"
period_mm = 5
mu_low = 0.6
"""


def friction_on_zero_k():
    """A fit of points whose friction rises with force (k = -0.05 /N, beyond the bound)."""
    w = np.repeat(np.linspace(0.2, 2.4, 12), 3)
    force = np.full(w.size, 0.5)
    a = -0.05 * 0.5
    return fit_points(w, force, (1 - a) * np.exp(-1.5 * w) + a)


def test_a_fit_stopped_on_k_zero_writes_k_zero():
    fit = friction_on_zero_k()
    assert ("k", "lower") in fit.at_bound
    assert fit.params.asymptote_per_n == 0.0
    assert "\nasymptote_per_n = 0        # standard error" in device_toml(fit, 2.5, 0.5)


def test_a_replay_at_k_zero_inverts_eq_3_with_no_clamps(tmp_path):
    fit = friction_on_zero_k()
    scene = tmp_path / "k0.toml"
    scene.write_text(SCENE.format(device=device_toml(fit, 2.5, 0.5)))
    friction = load_scene(scene).device.friction  # b as written, to 6 digits
    assert friction.asymptote_per_n == 0.0
    done = frictex.replay(scene, "swipe-40mms-50hz")
    mu = done.friction.column("mu_target").to_numpy()
    w = done.friction.column("amplitude_um").to_numpy()
    assert mu.min() == pytest.approx(0.6) and mu.max() == pytest.approx(1.0)
    np.testing.assert_allclose(w, -np.log(mu) / friction.b_per_um, rtol=1e-12, atol=0)
    assert math.isclose(w.max(), -math.log(mu.min()) / friction.b_per_um, rel_tol=1e-12)
    assert all(count == 0 for count in done.summary.to_dict()["clamps"].values())


def test_a_negative_k_is_still_refused(tmp_path):
    scene = tmp_path / "neg.toml"
    scene.write_text(SCENE.format(device="[device]\n[device.friction]\nasymptote_per_n = -0.1\n"))
    with pytest.raises(TextureError, match=r"asymptote_per_n: -0.1 is not >= 0"):
        load_scene(scene)
