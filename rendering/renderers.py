"""The renderer extension point: what a layer's renderer answers, and the registries by
name the pipeline builds them from.

A renderer turns the finger tracks of a block into one layer's mu' under each finger
(STYLE.md 1: state passed in and out, no module globals)::

    renderer = RENDERERS.get("sht")(layer, rate_hz)
    state = renderer.initial_state()
    mu, covers, state = renderer.render(block, state)

Two registries (``device.registry``), both filled from entry points so that another
package adds a renderer with one module and one line of its pyproject.toml:

- :data:`RENDERERS` (group ``frictex.renderers``): what a periodic layer's ``render``
  key, ``--renderer`` and the demo's R key name (``textures.model.render_modes``: these
  and ``sho``, the run's SHO variant). Every layer without a period renders with the run's
  SHO variant, which must be a renderer whose class says ``any_layer = True`` (it reads the
  layer's map at a position; :func:`any_layer`).
- :data:`LAYER_RENDERERS` (group ``frictex.layer_renderers``): the renderers of the layers
  that render motion or events (heights, recorded textures, clips), by the layer's
  ``renderer_kind``. A layer of a kind nobody registered is an error naming the kinds
  that are.

frictex's own are listed in its pyproject.toml: the renderer names are part of the
texture format, which ``textures`` checks without importing this layer.
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from frictex.device.registry import Registry
from frictex.rendering.tracking.tracks import FingerBlock
from frictex.textures.model import RENDERERS, render_modes

__all__ = ["DEFAULT_SHO", "LAYER_RENDERERS", "RENDERERS", "LayerRenderer", "RendererFactory",
           "any_layer", "render_modes", "sho_variant_of"]

#: what a layer's ``render = "sho"`` means unless the run says otherwise
DEFAULT_SHO = "sho-predicted"


@runtime_checkable
class LayerRenderer(Protocol):
    """One layer's renderer, built for one scene and output rate."""

    def initial_state(self) -> Any:
        """The state before the first block (anything; None for a stateless renderer)."""

    def render(self, block: FingerBlock, state: Any) -> tuple[np.ndarray, np.ndarray, Any]:
        """mu' (F, n) float64 in (0, 1] finite, where the layer covers each finger (F, n)
        bool, and the state for the next block, for the F fingers and n samples of
        ``block``. Must not change ``state`` in place: a caller may keep it."""


class RendererFactory(Protocol):
    """What a registry holds: a renderer class (or function) built per layer."""

    def __call__(self, layer: Any, rate_hz: float) -> LayerRenderer:
        """The renderer of ``layer`` (``textures.model``) at output rate ``rate_hz`` (Hz)."""


#: renderers of the layers that render motion or events, by ``layer.renderer_kind``
LAYER_RENDERERS: Registry[RendererFactory] = Registry("dynamic layer kind",
                                                      "frictex.layer_renderers")


def any_layer(name: str) -> bool:
    """Whether renderer ``name`` renders any layer (can be a run's SHO variant)."""
    return bool(getattr(RENDERERS.get(name), "any_layer", False))


def sho_variant_of(name: str) -> str:
    """The SHO variant of a run that renders periodic layers with ``name``: ``name``
    itself where it renders any layer, else :data:`DEFAULT_SHO`."""
    return name if any_layer(name) else DEFAULT_SHO
