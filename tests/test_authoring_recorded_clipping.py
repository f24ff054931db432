"""A recorded layer whose gain times its model's loudest output (noise through 1/A(z))
passes the room mu' has about mu_mean is warned about when the file is read, with the share of Gaussian
samples of that deviation beyond the limits and a gain that leaves 3 deviations."""

import math

from frictex.textures.ar_synthesis import output_power_gain
from frictex.textures.loader import check_scene
from test_ar_texture import COEFFS, VARIANCES, _xml
from test_texture_loader import write

LOUDEST = max(math.sqrt(v * output_power_gain(a)) for a, v in zip(COEFFS, VARIANCES))  # m/s^2


def _warnings(tmp_path, gain: float, xml: str | None = None):
    (tmp_path / "wood.xml").write_text(xml or _xml(), encoding="utf-8")
    body = f'[[layer]]\ntype = "recorded"\nmodel = "wood.xml"\ngain = {gain!r}\n'
    scene, problems, warnings = check_scene(write(tmp_path, body))
    assert scene is not None and problems == [], problems
    return [str(w) for w in warnings]


def test_a_gain_twice_the_room_warns_with_the_gaussian_share_clipped(tmp_path):
    gain = 0.4 / LOUDEST  # 2 deviations of 0.2 each side: 2 Q(0.5) = 61.7 % outside
    (warning,) = _warnings(tmp_path, gain)
    assert "scene.toml:10: layer[1].gain: " in warning, warning
    assert "model 1, 20 mm/s and 0.2 N" in warning and "is 0.4 of mu'" in warning, warning
    assert "at least 61.7% of the samples" in warning, warning
    assert f"lower gain to {0.2 / 1.2 * gain:.3g} or less" in warning, warning


def test_a_huge_variance_warns_and_an_ordinary_gain_does_not(tmp_path):
    huge = _xml().replace("<var>2e-06</var>", "<var>1e+99</var>")
    (warning,) = _warnings(tmp_path, 0.02, huge)
    assert "layer[1].gain: " in warning and "at least 99.9% of the samples" in warning, warning
    assert _warnings(tmp_path, 0.19 / LOUDEST) == []  # within the room: no warning
