"""Recorded-texture models whose line spectral frequencies are increasing in (0, pi) but
packed so close together that the float64 A(z) rebuilt from them has poles on or past
the unit circle: refused when read, one line naming the vertex; a filter that diverges
anyway restarts from rest, counted, and never puts inf or NaN into mu'; and the output
variance of a stable filter near the circle is finite."""

import math
import re

import numpy as np
import pytest

from frictex.rendering.layers.ar_texture import ArTextureRenderer
from frictex.textures.ar_synthesis import _synthesise, output_power_gain, pole_radius
from frictex.textures.errors import TextureError
from frictex.textures.hatt import ArTextureLayer, TextureModel, lsf_to_poly, parse_hatt_xml
from frictex.textures.loader import check_scene
from frictex.textures.model import VisualHints
from test_ar_texture import FORCES, SPEEDS, _synthesise as _render
from test_recorded_output_clipping import _impulse_energy
from test_texture_loader import write

CROWDED_20 = 0.30 + 0.02 * np.arange(20)   # float64 A(z): a pole at 1.064
CROWDED_10 = 0.300 + 0.001 * np.arange(10)  # a pole at 1.0026
NEAR_10 = 1.0 + 0.001 * np.arange(10)       # stable, a pole at 0.99984: rings 0.6 s at 10 kHz


def _xml(rows, var=1e-4):
    """A four-vertex model file, vertex k's ARlsf ``rows[k]``."""
    values = lambda xs: "".join(f"<value>{float(x)!r}</value>" for x in xs)  # noqa: E731
    models = "".join(f"<model><ARlsf>{values(w)}</ARlsf><var>{var!r}</var><speedMod>{s!r}"
                     f"</speedMod><forceMod>{f!r}</forceMod></model>"
                     for w, s, f in zip(rows, SPEEDS, FORCES))
    return (f"<modelSet><speedList>{values(SPEEDS)}</speedList><forceList>{values(FORCES)}"
            f"</forceList><tri>{values((1, 2, 3))}</tri><tri>{values((2, 4, 3))}</tri>"
            f"<numARCoeff>{len(rows[0])}</numARCoeff>{models}</modelSet>")


def _stable(order):
    return np.linspace(0.2, 2.8, order)


@pytest.mark.parametrize("crowded, vertex, radius", [(CROWDED_20, 3, "1.06"),
                                                     (CROWDED_10, 1, "1.00")])
def test_lsfs_packed_together_are_refused_naming_the_vertex(crowded, vertex, radius):
    rows = [_stable(crowded.size)] * 4
    rows[vertex - 1] = crowded
    with pytest.raises(TextureError) as info:
        parse_hatt_xml(_xml(rows), "crowd.xml")
    message = str(info.value)
    assert "\n" not in message
    assert re.match(rf"crowd\.xml: model {vertex}: its ARlsf gives A\(z\) a pole at radius "
                    rf"{re.escape(radius)}\d* , expected at most 0\.9999".replace(" ,", ","),
                    message), message


def test_a_crowded_model_is_a_problem_of_its_scene_line(tmp_path):
    (tmp_path / "crowd20.xml").write_text(_xml([CROWDED_20] * 4), encoding="utf-8")
    body = '[[layer]]\ntype = "recorded"\nmodel = "crowd20.xml"\ngain = 0.03\n'
    scene, problems, _ = check_scene(write(tmp_path, body))
    assert scene is None and len(problems) == 1
    assert re.search(r"layer\[1\]\.model: .*model 1: its ARlsf gives A\(z\) a pole at radius "
                     r"1\.06", str(problems[0])), problems[0]


def test_a_stable_filter_near_the_circle_has_a_finite_output_variance(tmp_path):
    """0.99984 is within the 1 s ring of 10 kHz (0.9999): read, and its warning gives the
    impulse response's energy (the step-down recursion gave inf: a |k| >= 1 by rounding)."""
    a = lsf_to_poly(NEAR_10)
    assert 0.9998 < pole_radius(a) < 0.9999
    gain = output_power_gain(a)
    assert math.isclose(gain, _impulse_energy(a), rel_tol=1e-3)  # lfilter rounds otherwise
    (tmp_path / "near.xml").write_text(_xml([NEAR_10] * 4, var=1e-4), encoding="utf-8")
    body = '[[layer]]\ntype = "recorded"\nmodel = "near.xml"\ngain = 0.03\n'
    scene, problems, warnings = check_scene(write(tmp_path, body))
    assert problems == [] and len(warnings) == 1
    std = float(re.search(r"standard deviation ([\d.e+-]+) m/s\^2", str(warnings[0])).group(1))
    assert math.isclose(std, math.sqrt(1e-4 * gain), rel_tol=1e-3), warnings[0]
    assert "inf" not in str(warnings[0]) and "lower gain to 0 " not in str(warnings[0])


def test_a_diverging_filter_restarts_from_rest_and_is_counted():
    """A double pole at 1.1: every output that overflows is 0 and the history cleared;
    counted only where asked."""
    poly = np.array([1.0, -2.2, 1.21])
    history, out = np.zeros(2), np.empty(20_000)
    counted = np.zeros(out.size, bool)
    counted[: out.size // 2] = True
    restarts = _synthesise(poly, 1.0, np.uint64(5), 0, history, out, counted)
    assert np.isfinite(out).all() and np.isfinite(history).all()
    zeros = np.flatnonzero(out == 0.0)
    assert zeros.size >= 2 and restarts == np.count_nonzero(counted[zeros])
    assert 0 < restarts < zeros.size


def test_an_unstable_model_never_puts_nan_into_mu():
    """A model that bypasses the file check (built in code): mu' stays finite and every
    restart is counted in ``clipped``."""
    model = TextureModel(np.array(SPEEDS), np.array(FORCES), np.array([[0, 1, 2], [1, 3, 2]]),
                         np.array([CROWDED_20] * 4), np.full(4, 1e-4))
    layer = ArTextureLayer(name="t", render="sho", region=None, blend="multiply",
                           visual=VisualHints(), model=model, gain=0.0)
    mu, state = _render(ArTextureRenderer(layer, 10_000.0), SPEEDS[0], FORCES[0], 5.0)
    assert np.isfinite(mu).all()
    assert state.clipped >= 1  # gain 0: nothing else clips


def test_a_pole_pair_rounded_to_just_inside_the_circle_gives_inf_not_a_hang():
    """np.poly of a pair on the circle puts its poles at 0.9999999999999999: the impulse
    response never decays, and the energy sum ran on without end (10 minutes of CPU)."""
    a = np.real(np.poly([np.exp(0.3j), np.exp(-0.3j)]))
    assert pole_radius(a) < 1.0
    assert output_power_gain(a) == math.inf
    pair = np.real(np.poly([0.99 * np.exp(0.3j), 0.99 * np.exp(-0.3j)]))
    assert math.isfinite(output_power_gain(pair))  # a stable pair still settles


def test_coefficients_outside_the_circle_are_said_to_be_possibly_unstable_not_only_crowded():
    """(np.roots cannot tell: 13 pole pairs at 0.75 come back at up to 1.21.)"""
    from frictex.textures.hatt import poly_to_lsf
    outside = np.real(np.poly([1.01 * np.exp(0.3j), 1.01 * np.exp(-0.3j)]))
    with pytest.raises(ValueError, match=r"its roots are outside the unit circle \(1 / A\(z\) "
                                         r"unstable\), or crowd so close"):
        poly_to_lsf(outside)


def test_a_model_from_coefficients_is_checked_as_a_files_models_are():
    from frictex.textures.hatt import model_from_coefficients
    near = np.real(np.poly([0.99995 * np.exp(0.3j), 0.99995 * np.exp(-0.3j)]))
    with pytest.raises(TextureError, match=r"^coefficients\[1\] gives A\(z\) a pole at radius "
                                           r"0\.99995, expected at most 0\.9999"):
        model_from_coefficients([0, 100, 0], [0, 0, 1], [[0, 1, 2]],
                                [np.array([1.0, -0.5, 0.2]), near, np.array([1.0, -0.5, 0.2])],
                                [1.0] * 3, rate_hz=10_000.0)
