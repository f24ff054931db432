"""frictex: render textures and objects on ultrasonic friction-modulation touchscreens.

The public, typed API::

    import frictex

    r = frictex.replay("grating-5mm", "swipe-40mms-50hz")   # bundled scene and trace
    r.summary.counts.contact_samples                        # typed summary
    r.friction.to_pandas()                                  # DataFrame (needs pandas)

- :func:`load_scene`, :func:`read_trace`, :func:`synth_trace`, :func:`make_trace`: the
  inputs (a texture file or bundled scene, a trace CSV or bundled trace, a synthetic
  finger motion, a trace from arrays checked as a trace file's rows are; its event codes
  :data:`DOWN`, :data:`MOVE`, :data:`UP`);
- :func:`build_pipeline`: the haptic pipeline of a scene; :meth:`Pipeline.process` runs
  a whole trace through it;
- :func:`replay`: a scene and a trace through the pipeline on a virtual clock, with the
  tables in memory or written into a folder (as ``frictex replay``); a :class:`Replay`;
- for a plugin's author (a renderer or an output device registered by entry point, as
  ``frictex.renderers`` and ``frictex.devices`` in frictex's own pyproject.toml): the
  contracts :class:`LayerRenderer` (what a layer's renderer answers, given each block's
  :class:`FingerBlock`) and :class:`OutputDevice` (what an output device answers, opened
  with a :class:`DeviceRequest`), and :class:`PluginError`, what frictex raises for
  another package's plugin that cannot be loaded, fails, or breaks its contract.

Units everywhere: positions in mm, time in s, velocity in mm/s, force in N, frequency in
Hz, vibration amplitude in um zero-to-peak, friction relative (mu' = mu(w) / mu(0)).
Errors are :class:`FrictexError`: :class:`InputError` (a ``ValueError``; a bad trace is
its :class:`TraceError`) for bad input, arguments beyond the command line's bounds
included, :class:`DeviceError` (an ``OSError``) for the device's link and samples it
never played, :class:`OutputSpaceError` when outputs do not fit, :class:`RunFailed` for a
:class:`Replay` whose output folder holds another run since. ``__version__`` is the
installed frictex's version (looked up on first use).

Everything else lives in the four layers below, in the order of DESIGN.md's data flow:
``frictex.app`` (commands, replay engine, live demo, reports) uses ``frictex.rendering``
(tracking, renderers, composition, friction inversion, visual layer), which uses
``frictex.textures`` (the texture file format and its library), which uses
``frictex.device`` (structures, actuation, link, protocol). ``import frictex`` loads none
of them (nor numpy, numba, scipy or pyarrow): each name here is imported on first use, and
so is each layer (``frictex.textures`` right after ``import frictex``); a module inside a
layer is imported as any submodule is (``import frictex.textures.model``, then
``frictex.textures.model.RENDERERS``).
"""

from __future__ import annotations

from typing import TYPE_CHECKING

#: public name -> the module that defines it
_WHERE = {
    "load_scene": "frictex._inputs",
    "read_trace": "frictex._inputs",
    "synth_trace": "frictex._inputs",
    "make_trace": "frictex._inputs",
    "DOWN": "frictex.rendering.input.trace_file",
    "MOVE": "frictex.rendering.input.trace_file",
    "UP": "frictex.rendering.input.trace_file",
    "TraceError": "frictex.rendering.input.trace_file",
    "build_pipeline": "frictex._pipeline",
    "Pipeline": "frictex._pipeline",
    "replay": "frictex._replay",
    "Replay": "frictex._replay",
    "Scene": "frictex.textures.model",
    "Trace": "frictex.rendering.input.trace_file",
    "BlockOutput": "frictex.rendering.pipeline",
    "Summary": "frictex.app.engine.summary_types",
    "SceneInfo": "frictex.app.engine.summary_types",
    "LayerInfo": "frictex.app.engine.summary_types",
    "TraceInfo": "frictex.app.engine.summary_types",
    "TimeOrderInfo": "frictex.app.engine.summary_types",
    "GapInfo": "frictex.app.engine.summary_types",
    "OutputInfo": "frictex.app.engine.summary_types",
    "Counts": "frictex.app.engine.summary_types",
    "Clamps": "frictex.app.engine.summary_types",
    "FingerErrors": "frictex.app.engine.summary_types",
    "Timings": "frictex.app.engine.summary_types",
    "FrictexError": "frictex.device.errors",
    "InputError": "frictex.device.errors",
    "DeviceError": "frictex.device.errors",
    "OutputSpaceError": "frictex.device.errors",
    "RunFailed": "frictex.device.errors",
    "LayerRenderer": "frictex.rendering.renderers",
    "FingerBlock": "frictex.rendering.tracking.tracks",
    "OutputDevice": "frictex.device.link.devices",
    "DeviceRequest": "frictex.device.link.devices",
    "PluginError": "frictex.device.registry",
}

#: the four layers (module docstring), subpackages imported on first use as the names are
_LAYERS = ("app", "rendering", "textures", "device")

# written out, not computed, so that type checkers read it (tests/test_api.py: the keys of
# _WHERE, sorted)
__all__ = [
    "BlockOutput", "Clamps", "Counts", "DOWN", "DeviceError", "DeviceRequest", "FingerBlock",
    "FingerErrors", "FrictexError", "GapInfo", "InputError", "LayerInfo", "LayerRenderer",
    "MOVE", "OutputDevice", "OutputInfo", "OutputSpaceError", "Pipeline", "PluginError",
    "Replay", "RunFailed", "Scene", "SceneInfo", "Summary", "TimeOrderInfo", "Timings",
    "Trace", "TraceError", "TraceInfo", "UP", "build_pipeline", "load_scene", "make_trace",
    "read_trace", "replay", "synth_trace",
]

# annotated here, given by __getattr__ on first use, documented for pdoc
DOWN: int
"""Event code of a touch sample (:class:`Trace`'s ``event``), 0: a finger comes down."""
MOVE: int
"""Event code 1: a touching finger moves (or stays)."""
UP: int
"""Event code 2: a finger lifts."""
__version__: str
"""The installed frictex's version, as ``frictex --version`` prints it."""

if TYPE_CHECKING:  # what a type checker sees; "X as X": re-exported (mypy --strict)
    from frictex._inputs import load_scene as load_scene
    from frictex._inputs import make_trace as make_trace
    from frictex._inputs import read_trace as read_trace
    from frictex._inputs import synth_trace as synth_trace
    from frictex._pipeline import Pipeline as Pipeline
    from frictex._pipeline import build_pipeline as build_pipeline
    from frictex._replay import Replay as Replay
    from frictex._replay import replay as replay
    from frictex.app.engine.summary_types import Clamps as Clamps
    from frictex.app.engine.summary_types import Counts as Counts
    from frictex.app.engine.summary_types import FingerErrors as FingerErrors
    from frictex.app.engine.summary_types import GapInfo as GapInfo
    from frictex.app.engine.summary_types import LayerInfo as LayerInfo
    from frictex.app.engine.summary_types import OutputInfo as OutputInfo
    from frictex.app.engine.summary_types import SceneInfo as SceneInfo
    from frictex.app.engine.summary_types import Summary as Summary
    from frictex.app.engine.summary_types import TimeOrderInfo as TimeOrderInfo
    from frictex.app.engine.summary_types import Timings as Timings
    from frictex.app.engine.summary_types import TraceInfo as TraceInfo
    from frictex.device.errors import DeviceError as DeviceError
    from frictex.device.errors import FrictexError as FrictexError
    from frictex.device.errors import InputError as InputError
    from frictex.device.errors import OutputSpaceError as OutputSpaceError
    from frictex.device.errors import RunFailed as RunFailed
    from frictex.device.link.devices import DeviceRequest as DeviceRequest
    from frictex.device.link.devices import OutputDevice as OutputDevice
    from frictex.device.registry import PluginError as PluginError
    from frictex.rendering.input.trace_file import Trace as Trace
    from frictex.rendering.input.trace_file import TraceError as TraceError
    from frictex.rendering.pipeline import BlockOutput as BlockOutput
    from frictex.rendering.renderers import LayerRenderer as LayerRenderer
    from frictex.rendering.tracking.tracks import FingerBlock as FingerBlock
    from frictex.textures.model import Scene as Scene
else:  # at run time each name is imported on first use; a checker sees only those above
    def __getattr__(name: str) -> object:
        """Import a public name on first use (module docstring)."""
        import importlib
        if name == "__version__":
            from frictex.app.commands.cli import version
            value = version()
        elif name in _LAYERS:  # importing a subpackage sets it in globals() too
            value = importlib.import_module(f"frictex.{name}")
        else:
            try:
                module = _WHERE[name]
            except KeyError:
                raise AttributeError(f"module 'frictex' has no attribute {name!r}") from None
            value = getattr(importlib.import_module(module), name)
        globals()[name] = value
        return value


def __dir__() -> list[str]:
    """The public names, the four layers and the module's own dunder attributes (not its
    helpers)."""
    return sorted({*__all__, *_LAYERS, "__version__",
                   *(name for name in globals() if name.startswith("__") and name.endswith("__"))})
