"""What another package's renderer or output device hands back is checked where frictex
wraps it: one that breaks its contract is a PluginError naming the package, never a value
written into the friction target or a traceback (exit 70)."""

from types import SimpleNamespace

import numpy as np
import pytest

from frictex.device.registry import PluginError
from frictex.rendering.renderers import PluginRenderer

WHO = "renderer 'flat' of frictex-flat (frictex_flat:Flat)"


def flat_renderer(mu_value: float):
    """A plugin renderer's factory whose every mu' is ``mu_value`` over the whole block."""
    class Flat:
        def __init__(self, layer, rate_hz):
            pass

        def initial_state(self):
            return None

        def render(self, block, state):
            shape = (len(block.ids), block.n)
            return np.full(shape, mu_value), np.ones(shape, dtype=bool), state
    return Flat


def rendered(mu_value: float):
    renderer = PluginRenderer(flat_renderer(mu_value), WHO, SimpleNamespace(name="lines"), 1e4)
    block = SimpleNamespace(ids=(0,), n=4)
    return renderer.render(block, renderer.initial_state())


@pytest.mark.parametrize("mu_value", [-1.0, 0.0, 5.0, 1.0 + 1e-9])
def test_a_plugin_renderers_mu_outside_0_1_is_refused_naming_it_and_the_layer(mu_value):
    with pytest.raises(PluginError, match=rf"^{WHO.replace('(', '.').replace(')', '.')} "
                                          rf"returned 4 mu' values outside \(0, 1\] "
                                          rf"\(the first {mu_value:g}\) on layer 'lines', "
                                          "where it covers$"):
        rendered(mu_value)


def test_a_plugin_renderers_nan_is_still_said_as_not_finite():
    with pytest.raises(PluginError, match="4 mu' values that are not finite"):
        rendered(np.nan)


@pytest.mark.parametrize("mu_value", [1.0, 0.05])
def test_a_plugin_renderers_mu_in_0_1_passes(mu_value):
    mu, covers, _ = rendered(mu_value)
    assert mu.tolist() == [[mu_value] * 4] and covers.all()
