"""The haptic pipeline: touch samples in, channel commands out, one call per block.

Assembled from the scene (DESIGN.md, "Model only what a scene needs"): the tracker,
one renderer per layer of the kind that layer asks for, composition, the device's
friction model and its actuation; nothing else is built. The same object runs live
(one block per call, paced by the wall or the device) and in replay (many blocks per
call, as fast as it goes): a sample takes effect at the block boundary after its
timestamp either way (see ``rendering.tracking.tracks``), so both give the same output.

    pipeline = build_pipeline(scene, rate_hz=10_000.0)  # blocks of 5 ms: 50 samples
    state = pipeline.initial_state()
    out, state = pipeline.process(block_index, samples, state, n_blocks=1)
"""

from __future__ import annotations

import time
from dataclasses import dataclass, field

import numpy as np
import numpy.typing as npt

from frictex.device.actuation.factory import make_actuation
from frictex.device.errors import InputError
from frictex.device.registry import UnknownName
from frictex.rendering.compose import compose
from frictex.rendering.tracking.finger_select import SelectionState, select_fingers
from frictex.device.friction import ClampCounts, make_friction_model
from frictex.rendering.input.trace_file import Trace, read_only_view
from frictex.rendering.renderers import (DEFAULT_SHO, LAYER_RENDERERS, RENDERERS, any_layer,
                                         build_renderer, render_modes)
from frictex.rendering.tracking.tracks import TrackerConfig, TrackerState, track
from frictex.device.profile import FORCE_PROFILES
from frictex.textures.model import Scene

#: friction inversions: the closed form (seed 003, eq 3) or a table built at scene load
INVERSIONS = ("exact", "lut")

STAGES = ("tracking", "layers", "composition", "inversion", "actuation")


@dataclass(frozen=True, eq=False)
class BlockOutput:
    """The pipeline's output for ``n`` samples; per-finger arrays are (F, n).

    t_s : (n,) output times (s). finger_ids : the F finger ids.
    contact : bool. x_mm, y_mm : the tracker's predicted position (mm), whatever the
    renderers (SHO-held plays the last touch sample's position), where ``contact`` is
    True; where it is False no finger touches and the entries mean nothing (a
    placeholder, 0 or a position left over): select them with ``x_mm[contact]``.
    mu_target : composed mu'.
    wanted_um : amplitude each finger's target asks for (um, zero-to-peak).
    amplitude_um : amplitude the actuation achieves under each finger (um, zero-to-peak).
    commands_um : (n, channels) channel commands (um). phases_rad : (n, channels) or None.
    clamps : counts of the friction inversion's guards in this block.
    limited : samples where an actuator limit changed the actuation's solution.
    capped : samples where the modal actuation could not give the fingers independent
        amplitudes (a singular locus, seed 001 eq 8).
    layer_clipped : per layer name, for the layers whose state counts ``clipped`` (a
        recorded texture's mu' limits, a clip's level sum past 1): the finger samples
        this block where the layer's own limits clipped the mu' it gave the target.
    off_structure : finger samples outside the vibrating structure (held at its edge).
    unserved : finger samples touching but not served by the modal actuation (beyond the
        p longest-touching fingers its p modes serve): they get the served ones' vibration.
    forces : travelling-wave profiles only (else None): per finger the wanted and
        achieved force vectors (N) and key-click button state per sample
        (``rendering.layers.force_layers.ForceBlock``).
    sample_ids : (F, n) int64 finger id of every sample, where a row passes from one
        finger to another within the call (a trace source reuses the rows of lifted
        fingers: ``app.engine.finger_slots``); else None, and row r is ``finger_ids[r]``
        throughout. Read per finger with :meth:`segments`.

    Every array is held as a read-only view (O(1)): an output handed on is not changed
    by whoever reads it; take ``.copy()`` to work on one.
    """

    index0: int
    t_s: npt.NDArray[np.float64]
    finger_ids: tuple[int, ...]
    contact: npt.NDArray[np.bool_]
    x_mm: npt.NDArray[np.float64]
    y_mm: npt.NDArray[np.float64]
    mu_target: npt.NDArray[np.float64]
    wanted_um: npt.NDArray[np.float64]
    amplitude_um: npt.NDArray[np.float64]
    commands_um: npt.NDArray[np.float64]
    phases_rad: npt.NDArray[np.float64] | None
    clamps: ClampCounts
    limited: int = 0
    capped: int = 0
    off_structure: int = 0
    unserved: int = 0
    layer_clipped: dict[str, int] = field(default_factory=dict)
    forces: object | None = None
    sample_ids: npt.NDArray[np.int64] | None = None

    #: the array fields, held read-only (not a dataclass field: no annotation)
    _ARRAY_FIELDS = ("t_s", "contact", "x_mm", "y_mm", "mu_target", "wanted_um",
                     "amplitude_um", "commands_um", "phases_rad", "sample_ids")

    def __post_init__(self) -> None:
        for name in self._ARRAY_FIELDS:
            value = getattr(self, name)
            if value is not None:
                object.__setattr__(self, name, read_only_view(value))

    def segments(self) -> list[tuple[int, int, int, int]]:
        """``(row, finger id, lo, hi)``: samples ``lo .. hi - 1`` of ``row`` belong to
        that finger (one per row unless :attr:`sample_ids` says otherwise); a stretch of a
        row no touch has taken yet (id -1, a replay's ``app.engine.finger_slots.UNNAMED``)
        belongs to no finger and is left out."""
        n = self.t_s.size
        if self.sample_ids is None:
            return [(row, fid, 0, n) for row, fid in enumerate(self.finger_ids) if fid >= 0]
        found = []
        for row, ids in enumerate(self.sample_ids):
            cuts = [0, *(np.flatnonzero(ids[1:] != ids[:-1]) + 1).tolist(), n]
            found += [(row, int(ids[lo]), lo, hi) for lo, hi in zip(cuts[:-1], cuts[1:])
                      if ids[lo] >= 0]
        return found

    def ids_per_sample(self) -> npt.NDArray[np.int64]:
        """(F, n) int64 finger id of every sample."""
        if self.sample_ids is not None:
            return self.sample_ids
        return np.repeat(np.array(self.finger_ids, dtype=np.int64)[:, None], self.t_s.size,
                         axis=1)


@dataclass(frozen=True)
class PipelineState:
    tracker: TrackerState
    layers: tuple
    forces: object | None = None  # rendering.layers.force_layers.ForceState on force profiles
    control: object | None = None  # rendering.control.loop.ControlState with the loop on
    #: who holds each layer's positional finger role (left-most, ...), across blocks
    selection: SelectionState = field(default_factory=SelectionState)


@dataclass
class StageTimer:
    """Accumulated compute time per stage (s), for benchmarks and summary.json."""

    seconds: dict[str, float] = field(default_factory=lambda: {s: 0.0 for s in STAGES})
    layer_seconds: dict[str, float] = field(default_factory=dict)


def _layer_renderer(layer, mode: str, rate_hz: float):
    """The renderer of ``layer``: its kind's (``renderer_kind``: layers that render motion
    or events) if it has one, else renderer ``mode`` (``rendering.renderers``)."""
    kind = getattr(layer, "renderer_kind", None)
    if kind is None:
        return build_renderer(RENDERERS, mode, layer, rate_hz)
    return build_renderer(LAYER_RENDERERS, kind, layer, rate_hz)


def _layer_mode(layer, render_override: str | None, sho_variant: str) -> str:
    """The renderer a layer gets: a layer that renders motion or events its kind's
    (``renderer_kind``: "height", "ar", "clip"); other objects SHO; periodic layers the
    override if any, else their file's choice."""
    kind = getattr(layer, "renderer_kind", None)
    if kind is not None:
        return kind
    if not layer.is_periodic:
        return sho_variant
    mode = render_override or layer.render
    return sho_variant if mode == "sho" else mode


#: a block's length when none is given (s): 50 samples at the seed 003 link's 10 kHz, the
#: longest a touch sample waits to take effect
BLOCK_S = 0.005


def default_block_size(rate_hz: float, block_s: float = BLOCK_S) -> int:
    """Samples in a block of ``block_s`` (s) at ``rate_hz`` (Hz), at least 1."""
    return max(1, round(rate_hz * block_s))


class Pipeline:
    """The stages for one scene; see the module docstring. ``block_size`` None: a
    block of :data:`BLOCK_S` (:func:`default_block_size`)."""

    def __init__(self, scene: Scene, rate_hz: float = 10_000.0, block_size: int | None = None,
                 render_override: str | None = None, sho_variant: str = DEFAULT_SHO,
                 t0_s: float = 0.0, tracker: TrackerConfig | None = None,
                 inversion: str = "exact", control: str | None = None, loop_config=None):
        if rate_hz <= 0 or not np.isfinite(rate_hz):
            raise ValueError(f"output rate {rate_hz!r} Hz: expected a positive number")
        if block_size is None:
            block_size = default_block_size(rate_hz)
        if block_size < 1:
            raise ValueError(f"block size {block_size!r}: expected at least 1 sample")
        if render_override is not None and render_override not in render_modes():
            raise UnknownName(f"unknown renderer {render_override!r}; expected one of "
                              f"{', '.join(render_modes())}")
        if not any_layer(sho_variant):
            raise InputError(f"SHO variant {sho_variant!r}: expected a renderer of any "
                             f"layer, one of {', '.join(filter(any_layer, RENDERERS.names()))}")
        self.scene = scene
        self.rate_hz = float(rate_hz)
        self.block_size = int(block_size)
        base = tracker or TrackerConfig()
        area = base.area_mm or (scene.display.width_mm, scene.display.height_mm)
        self.tracker_config = TrackerConfig(**{**base.__dict__, "rate_hz": self.rate_hz,
                                               "quantum": self.block_size, "t0_s": t0_s,
                                               "area_mm": area})
        self.layer_modes = tuple(_layer_mode(layer, render_override, sho_variant)
                                 for layer in scene.layers)
        self.renderers = tuple(_layer_renderer(layer, mode, self.rate_hz)
                               for layer, mode in zip(scene.layers, self.layer_modes))
        self.blends = tuple(layer.blend for layer in scene.layers)
        self.selectors = tuple(layer.fingers for layer in scene.layers)
        if inversion not in INVERSIONS:
            raise ValueError(f"unknown inversion {inversion!r}; expected one of "
                             f"{', '.join(INVERSIONS)}")
        self.friction = make_friction_model(scene.device)
        if inversion == "lut":
            from frictex.rendering.inversion_lut import LutFrictionModel
            self.friction = LutFrictionModel(self.friction)
        self.actuation = make_actuation(scene.device)
        self.control = None  # closed-loop friction (rendering.control.loop), not open loop
        control = scene.control if control is None else control  # the file's, or overridden
        if control != "open":
            from frictex.rendering.control.loop import ClosedLoop, LoopConfig
            self.control = ClosedLoop(scene.device, self.rate_hz, self.block_size, control,
                                      loop_config or LoopConfig())
        elif loop_config is not None:
            raise ValueError("a loop configuration needs a loop: control 'closed' or "
                             "'adaptive', not open loop")
        self.forces = None
        if scene.device.profile in FORCE_PROFILES:
            from frictex.rendering.layers.force_layers import ForceStage  # travelling-wave profiles only
            self.forces = ForceStage(scene, self.rate_hz, self.actuation)
        self.timer = StageTimer()
        self._warm_up()
        self.timer = StageTimer()

    def _warm_up(self) -> None:
        """Run one block with a touch at the display's centre and discard it.

        The per-sample kernels (numba, compiled once and cached on disk) are loaded into
        the process on their first call, ~0.2 s in a fresh process: that belongs to
        loading the scene, not to the first live block or a timed replay.
        """
        from frictex.rendering.input.trace_file import DOWN, MAX_TIME_S, MOVE, make_trace
        # a trace may start at the latest time a trace may hold: the touch's second
        # sample, 1 ms on, must be one too (the block it falls in does not matter here)
        t0 = min(self.tracker_config.t0_s, MAX_TIME_S - 1e-3)
        cx, cy = self.scene.display.width_mm / 2, self.scene.display.height_mm / 2
        touch = make_trace([t0, t0 + 1e-3], [0, 0], [cx, cx + 0.01], [cy, cy], event=[DOWN, MOVE])
        self.process(0, touch, self.initial_state(), n_blocks=2)

    @property
    def channels(self) -> tuple[str, ...]:
        return self.actuation.channels

    def initial_state(self) -> PipelineState:
        return PipelineState(tracker=TrackerState(),
                             layers=tuple(r.initial_state() for r in self.renderers),
                             forces=self.forces.initial_state() if self.forces else None,
                             control=self.control.initial_state() if self.control else None)

    def process(self, block_index: int, samples: Trace | None, state: PipelineState,
                n_blocks: int = 1, normal_force_n: float | None = None,
                force_reports=None) -> tuple[BlockOutput, PipelineState]:
        """Run ``n_blocks`` blocks starting at ``block_index`` (output index
        ``block_index * block_size``) with the touch samples that take effect in them.
        Every block asked for is rendered, one in a long pause between touch samples
        too (the finger touching, held where the tracker extrapolated it): taking a pause
        longer than ``max_gap_s`` as a lift and skipping it is the replay engine's
        (``app.engine.sources``), not this method's.

        ``normal_force_n``: the normal force (N) the device's force sensors measure now
        (seed 003's plate has four under its corners), used instead of the samples' force
        for the fingers touching. Sensors under the plate measure the total: with several
        fingers down it is shared equally among them. ``force_reports``: when the loop is
        on, ``force_reports(index0, n)`` gives the device's force reports over output samples
        ``index0 .. index0 + n - 1`` once they have come (``rendering.control.loop``), or
        None; None for a device without force reports.
        """
        clock = time.perf_counter
        secs = self.timer.seconds
        index0 = block_index * self.block_size
        n = n_blocks * self.block_size

        t = clock()
        fingers, tracker_state = track(index0, n, samples, state.tracker, self.tracker_config)
        if normal_force_n is not None:
            touching = fingers.contact
            share = normal_force_n / np.maximum(touching.sum(axis=0), 1)
            fingers = fingers.with_force(np.where(touching, share, fingers.force))
        t1 = clock()
        secs["tracking"] += t1 - t

        outputs, layer_states, layer_clipped = [], [], {}
        for renderer, layer_state, layer in zip(self.renderers, state.layers, self.scene.layers):
            t = clock()
            mu, covers, new_state = renderer.render(fingers, layer_state)
            outputs.append((mu, covers))
            layer_states.append(new_state)
            if hasattr(new_state, "clipped"):  # a running count: this block's part
                layer_clipped[layer.name] = new_state.clipped - layer_state.clipped
            dt = clock() - t
            secs["layers"] += dt
            self.timer.layer_seconds[layer.name] = self.timer.layer_seconds.get(layer.name, 0.0) + dt

        t = clock()
        masks, selection = select_fingers(self.selectors, fingers, state.selection)
        mu_target = compose(outputs, self.blends, fingers.contact, masks)
        t1 = clock()
        secs["composition"] += t1 - t

        forces, force_state, control_state = None, state.forces, state.control
        if self.control is not None:
            wanted, clamps, control_state = self.control.invert(mu_target, fingers,
                                                                state.control,
                                                                force_reports)
        elif self.forces is None:
            wanted, clamps = self.friction.invert(mu_target, fingers.force)
        else:  # inversion and actuation in one: the wave serves force targets
            forces, act, wanted, clamps, force_state = self.forces.render(fingers, mu_target,
                                                                          state.forces)
        t2 = clock()
        secs["inversion"] += t2 - t1

        if forces is None:
            act = self.actuation.command(wanted, fingers)
        secs["actuation"] += clock() - t2

        out = BlockOutput(index0=index0, t_s=fingers.t_s, finger_ids=fingers.ids,
                          contact=fingers.contact, x_mm=fingers.x_pred, y_mm=fingers.y_pred,
                          mu_target=mu_target, wanted_um=wanted, amplitude_um=act.achieved_um,
                          commands_um=act.commands_um, phases_rad=act.phases_rad,
                          clamps=clamps, limited=act.limited, capped=act.capped,
                          off_structure=act.off_structure, unserved=act.unserved,
                          layer_clipped=layer_clipped,
                          forces=forces)
        return out, PipelineState(tracker=tracker_state, layers=tuple(layer_states),
                                  forces=force_state, control=control_state, selection=selection)


def build_pipeline(scene: Scene, rate_hz: float = 10_000.0, block_size: int | None = None,
                   render_override: str | None = None, **kwargs) -> Pipeline:
    """The pipeline for ``scene`` (see :class:`Pipeline`)."""
    return Pipeline(scene, rate_hz=rate_hz, block_size=block_size,
                    render_override=render_override, **kwargs)
