"""The recorded layer's clipping warning measures the model's output, noise through
1 / A(z), not its excitation: HaTT's resonant vertex models are 81 to 685 times wider
than their excitation (a gain of 10 passed validate and clipped 96 % of a swipe)."""

import math
import re

import numpy as np
from scipy.signal import lfilter

from frictex.rendering.layers.ar_texture import ArTextureRenderer
from frictex.textures.ar_synthesis import output_power_gain
from frictex.textures.hatt import ArTextureLayer, lsf_to_poly
from frictex.textures.loader import check_scene
from frictex.textures.model import VisualHints
from test_ar_texture import COEFFS, FORCES, SPEEDS, VARIANCES, _model, _synthesise, _xml
from test_texture_loader import write


def _impulse_energy(a, tolerance=1e-13):
    """sum h^2 of 1 / A(z), the impulse response lengthened until the sum settles."""
    n = 1024
    while True:
        h = lfilter([1.0], a, np.r_[1.0, np.zeros(n - 1)])
        if h[n // 2:] @ h[n // 2:] < tolerance * (h @ h):
            return h @ h
        n *= 2


def test_the_power_gain_is_the_impulse_responses_energy():
    for a in COEFFS + [np.array([1.0, -0.5, 0.2]), np.array([1.0, 0.9])]:
        assert math.isclose(output_power_gain(a), _impulse_energy(a), rel_tol=1e-9)
    assert output_power_gain(np.array([1.0, -2.0, 1.0])) == math.inf  # a pole on the circle


def _warning(tmp_path, gain):
    (tmp_path / "wood.xml").write_text(_xml(), encoding="utf-8")
    body = f'[[layer]]\ntype = "recorded"\nmodel = "wood.xml"\ngain = {gain!r}\n'
    scene, problems, warnings = check_scene(write(tmp_path, body))
    assert scene is not None and problems == [], problems
    return [str(w) for w in warnings]


def _loudest_output():
    """(vertex, output standard deviation m/s^2) of the test model, from the impulse
    responses of the A(z) the file's LSFs give."""
    model = _model()
    stds = [math.sqrt(v * _impulse_energy(lsf_to_poly(w))) for w, v in zip(model.lsf, VARIANCES)]
    return int(np.argmax(stds)), max(stds)


def test_the_warning_names_the_loudest_output_and_a_gain_that_leaves_3_of_its_deviations(tmp_path):
    vertex, std = _loudest_output()
    assert std > 100 * math.sqrt(max(VARIANCES))  # a gain by the excitation would be far too loud
    (warning,) = _warning(tmp_path, 0.4 / std)  # 2 output deviations of 0.2 each side
    assert (f"model {vertex + 1}, {SPEEDS[vertex]:g} mm/s and {FORCES[vertex]:g} N: standard "
            f"deviation {std:.3g} m/s^2) is 0.4 of mu'") in warning, warning
    assert "at least 61.7% of the samples" in warning, warning
    suggested = float(re.search(r"lower gain to ([\d.e+-]+) or less", warning).group(1))
    assert math.isclose(suggested, 0.2 / (3 * std), rel_tol=2e-3), warning
    assert _warning(tmp_path, 0.19 / std) == []  # within the room: no warning


def test_the_suggested_gain_clips_about_the_gaussian_share_beyond_3_deviations(tmp_path):
    vertex, std = _loudest_output()
    (warning,) = _warning(tmp_path, 1.0 / std)
    suggested = float(re.search(r"lower gain to ([\d.e+-]+) or less", warning).group(1))
    layer = ArTextureLayer(name="t", render="sho", region=None, blend="multiply",
                           visual=VisualHints(), model=_model(), gain=suggested)
    mu, state = _synthesise(ArTextureRenderer(layer, 10_000.0), SPEEDS[vertex], FORCES[vertex],
                            60.0)
    share = state.clipped / mu.size  # a Gaussian's 0.27 % beyond 3 deviations
    assert 0.0005 < share < 0.006, share
