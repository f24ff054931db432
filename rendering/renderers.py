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
texture format, which ``textures`` checks without importing this layer. Anything another
package's renderer raises, building or rendering, is a :class:`PluginError` naming the
package and the layer (exit 1), not an internal error of frictex's
(:func:`build_renderer`). So is a renderer registered in-process from outside frictex's
own modules (``RENDERERS.register("wobble", Wobble)`` in a notebook): it is checked and
wrapped as a plugin's (``Registry.register``).
"""

from __future__ import annotations

from typing import Any, Protocol, runtime_checkable

import numpy as np

from frictex.device.registry import OWN_DISTRIBUTION, PluginError, Registry
from frictex.rendering.tracking.tracks import FingerBlock
from frictex.textures.model import (RENDERER_FACTORY, RENDERERS, loadable_render_modes,
                                    render_modes)

__all__ = ["DEFAULT_SHO", "LAYER_RENDERERS", "RENDERERS", "LayerRenderer", "RendererFactory",
           "any_layer", "build_renderer", "from_velocity", "loadable_render_modes", "render_modes",
           "sho_variant_of"]

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
                                                      "frictex.layer_renderers",
                                                      expect=RENDERER_FACTORY)


def any_layer(name: str) -> bool:
    """Whether renderer ``name`` renders any layer (can be a run's SHO variant)."""
    return bool(getattr(RENDERERS.get(name), "any_layer", False))


def from_velocity(name: str) -> bool:
    """Whether renderer ``name`` plays its texture from the tracker's velocity between
    touch samples (its class says ``from_velocity = True``), so that it plays none where
    the tracker takes the finger as resting; False for a layer renderer's kind (``height``,
    ``ar``, ``clip``: :data:`LAYER_RENDERERS`)."""
    return (name in RENDERERS.names()  # (``in RENDERERS`` looks for a new package: 20 ms)
            and bool(getattr(RENDERERS.get(name), "from_velocity", False)))


def sho_variant_of(name: str) -> str:
    """The SHO variant of a run that renders periodic layers with ``name``: ``name``
    itself where it renders any layer, else :data:`DEFAULT_SHO`."""
    return name if any_layer(name) else DEFAULT_SHO


def build_renderer(registry: Registry, name: str, layer: Any, rate_hz: float) -> LayerRenderer:
    """The renderer ``name`` of ``registry`` built for ``layer`` at ``rate_hz`` (Hz); another
    package's is wrapped so that what it raises names it (:class:`PluginRenderer`)."""
    factory = registry.get(name)
    origin = registry.origin(name)
    if origin == OWN_DISTRIBUTION:
        return factory(layer, rate_hz)
    return PluginRenderer(factory, f"{registry.kind} {name!r} of {origin}", layer, rate_hz)


class PluginRenderer:
    """Another package's renderer, whose exceptions become :class:`PluginError` saying
    whose renderer failed on which layer, and what it raised; as do outputs that break
    :class:`LayerRenderer`'s contract where frictex would fail on them or write them:
    mu' or covers not (fingers, samples) or not numbers, mu' outside (0, 1] where the
    layer covers; and a renderer built without ``initial_state`` or ``render``. The
    plugin reads the block through read-only views (``FingerBlock.read_only``): a write
    into it fails as the plugin's error instead of changing every later layer's input.
    ``inner``: the plugin's renderer."""

    def __init__(self, factory: RendererFactory, who: str, layer: Any, rate_hz: float):
        self._who = who
        self._layer = getattr(layer, "name", "?")
        self.inner = self._guarded("building", factory, layer, rate_hz)
        missing = [method for method in ("initial_state", "render")
                   if not callable(getattr(self.inner, method, None))]
        if missing:
            raise PluginError(f"{who} built a {type(self.inner).__name__} without "
                              f"{' or '.join(m + '()' for m in missing)} for layer "
                              f"{self._layer!r}; expected a LayerRenderer "
                              "(frictex.rendering.renderers.LayerRenderer)")
        self.any_layer = getattr(self.inner, "any_layer", False)

    def _guarded(self, doing: str, call, *args):
        try:
            return call(*args)
        except Exception as exc:  # noqa: BLE001 -- a plugin's bug, told as the plugin's
            raise PluginError(f"{self._who} failed {doing} layer {self._layer!r}: "
                              f"{type(exc).__name__}: {exc}") from exc

    def initial_state(self) -> Any:
        return self._guarded("starting", self.inner.initial_state)

    def render(self, block: FingerBlock, state: Any) -> tuple[np.ndarray, np.ndarray, Any]:
        got = self._guarded("rendering", self.inner.render, block.read_only(), state)
        shape = (len(block.ids), block.n)
        if not (isinstance(got, tuple) and len(got) == 3):
            raise PluginError(f"{self._who} returned {type(got).__name__} on layer "
                              f"{self._layer!r}; expected (mu', covers, state)")
        mu, covers, new_state = got
        for what, value in (("mu'", mu), ("covers", covers)):
            if np.shape(value) != shape:
                raise PluginError(f"{self._who} returned {what} of shape {np.shape(value)} on "
                                  f"layer {self._layer!r}; expected {shape} ({shape[0]} "
                                  f"finger(s) x {shape[1]} samples)")
        mu, covers = np.asarray(mu), np.asarray(covers)
        for what, value, kinds, expected in (("mu'", mu, "biuf", "real numbers"),
                                             ("covers", covers, "b", "booleans")):
            if value.dtype.kind not in kinds:
                raise PluginError(f"{self._who} returned {what} of dtype {value.dtype} on "
                                  f"layer {self._layer!r}; expected {expected}")
        mu, covers = mu.astype(np.float64, copy=False), covers.astype(bool, copy=False)
        bad = ~((mu > 0.0) & (mu <= 1.0)) & covers  # NaN fails both comparisons
        if bad.any():
            values = mu[bad]
            what = ("that are not finite (NaN or inf)" if not np.isfinite(values).any()
                    else f"outside (0, 1] (the first {values[0]:g})")
            raise PluginError(f"{self._who} returned {int(np.count_nonzero(bad))} mu' values "
                              f"{what} on layer {self._layer!r}, where it covers")
        return mu, covers, new_state
