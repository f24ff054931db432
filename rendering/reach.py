"""Reach: how much of a scene asks for a friction (or a force) the device cannot give.

A device lowers friction only down to a floor: the lowest mu' it reaches at a normal force
within its amplitude limit (``device.friction.mu_floor``; seed 003 eq 2 at the amplifier
limit, or the asymptote A = k F_n). Each layer of a scene may stay above that floor while
their *product* (``rendering.compose``) goes below it: a grain at 0.72 times rings at 0.6
asks for 0.43. Those targets are clamped to the floor when the scene plays, and what the
finger feels there is flattened.

:func:`scene_reach` measures it before a session, at the scene's nominal normal force:

- over the scene's area: mu' composed on a grid of cell centres over the display
  (:data:`GRID_CELLS` along its longer side), each layer as :func:`as_previewed` shows it;
- over a typical stroke: a human-like motion across the display (``trace_synth``'s
  ``human`` motion, :data:`STROKE_S` s of minimum-jerk strokes and pauses, peak speeds
  around :data:`STROKE_SPEED_MM_S`), sampled like a touch screen at
  :data:`STROKE_RATE_HZ` and run through the scene's own pipeline (trackers, renderers,
  composition), counting the output samples in contact whose composed target is below
  the floor.

The layers named as the cause are those that lower mu' where the product falls below
the floor: each layer's share of the mean -ln mu' there, kept if at least
:data:`CAUSE_SHARE` of it.

The pipeline (and the kernels it compiles) runs only for a scene whose layers' lowest
mu' values multiply to less than the floor: below that bound no composition can fall
below it, and the answer is "none" without running anything.

A travelling-wave scene asks for forces as well (``rendering.layers.force_layers``):
:func:`force_reach` runs the typical stroke through its pipeline and gives the share of
its contact samples whose wanted force the wave cannot give there, and for each
key-click button the same over a press at its centre.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from frictex.device.friction import mu_floor
from frictex.rendering.compose import compose
from frictex.textures.overlap import Overlap, applies_alone, lowest_overlap

#: Grid cells along the display's longer side for the area share.
GRID_CELLS = 240
#: The typical stroke: duration (s), typical peak speed (mm/s), touch report rate (Hz), seed.
STROKE_S = 4.0
STROKE_SPEED_MM_S = 80.0
STROKE_RATE_HZ = 120.0
STROKE_SEED = 0
#: Shortest side (mm) the stroke is drawn on: ``trace_synth`` keeps 8 mm from each edge.
MIN_STROKE_SPAN_MM = 32.0
#: A layer is named as a cause if it holds at least this share of the mean -ln mu'
#: of the targets below the floor.
CAUSE_SHARE = 0.1
#: Targets within this of the floor count as reached (the inversion's own tolerance).
TOLERANCE = 1e-12


@dataclass(frozen=True)
class Reach:
    """What part of a scene lies below the device's floor.

    floor : lowest mu' the device reaches at ``force_n`` (N).
    area_share, stroke_share : fraction in [0, 1] of the display's area and of the typical
        stroke's contact samples whose composed target is below ``floor``.
    overlap : the lowest product of the lowest mu' of the layers a lone finger feels,
        where their extents overlap (``textures.overlap``): no target goes below it.
    causes : names of the layers whose product takes it below the floor, in file order.
    """

    floor: float
    force_n: float
    area_share: float
    stroke_share: float
    overlap: Overlap
    causes: tuple[str, ...]

    @property
    def below(self) -> bool:
        """True if any part of the area or the stroke lies below the floor."""
        return self.area_share > 0.0 or self.stroke_share > 0.0


class _MovingRight:
    """A height layer as a map sees it: felt sliding towards +x (above ``v_fade_mm_s``),
    instead of at rest (where it is flat at ``mu_rest``)."""

    def __init__(self, layer):
        self.layer = layer
        self.name = layer.name
        self.blend = layer.blend
        self.fingers = layer.fingers

    def covers(self, x, y):
        return self.layer.covers(x, y)

    def mu_at(self, x, y):
        layer = self.layer
        gx, gy = layer.shape.gradient(x, y)
        return layer.mu_of_motion(gx, gy, 2.0 * layer.v_fade_mm_s, 0.0)


def as_previewed(scene):
    """The scene with its height layers felt sliding towards +x (climbing flanks above
    their rest level, descending ones below); every other layer as it is."""
    return replace(scene, layers=tuple(
        _MovingRight(layer) if getattr(layer, "renderer_kind", None) == "height" else layer
        for layer in scene.layers))


def grid(display, cells: int = GRID_CELLS) -> tuple[np.ndarray, np.ndarray]:
    """Cell centres (mm) of a grid over the display, ``cells`` along its longer side."""
    w, h = display.width_mm, display.height_mm
    step = max(w, h) / cells
    nx, ny = max(1, round(w / step)), max(1, round(h / step))
    x = (np.arange(nx) + 0.5) * (w / nx)
    y = (np.arange(ny) + 0.5) * (h / ny)
    xx, yy = np.meshgrid(x, y)
    return xx.ravel(), yy.ravel()


def _area(scene):
    """(composed mu' (n,), per-layer (mu, covers) pairs of shape (1, n)) on the grid."""
    layers = as_previewed(scene).layers
    x, y = grid(scene.display)
    outputs = [(np.broadcast_to(layer.mu_at(x, y), x.shape)[None, :],
                np.broadcast_to(layer.covers(x, y) & applies_alone(layer), x.shape)[None, :])
               for layer in layers]
    mu = compose(outputs, [layer.blend for layer in layers], np.ones((1, x.size), bool))
    return mu[0], outputs


class _Recording:
    """A layer renderer that keeps what it gave (the pipeline's per-layer outputs)."""

    def __init__(self, inner):
        self.inner = inner
        self.outputs: list[tuple[np.ndarray, np.ndarray]] = []

    def __getattr__(self, name):
        return getattr(self.inner, name)

    def render(self, fingers, state):
        mu, covers, new_state = self.inner.render(fingers, state)
        self.outputs.append((np.array(mu, dtype=np.float64), np.array(covers, dtype=bool)))
        return mu, covers, new_state


def stroke_trace(scene, box=None):
    """The typical stroke over ``box`` (x0, y0, x1, y1) mm, default ``scene``'s display, at
    the scene's nominal force (a ``Trace``).

    The motion keeps ``trace_synth``'s margin from the edges, so along a side shorter than
    :data:`MIN_STROKE_SPAN_MM` it is drawn on that span and scaled onto the side (a 6 mm
    beam's stroke stays on the beam, moving slower across it)."""
    from frictex.rendering.input.trace_file import make_trace
    from frictex.rendering.input.trace_synth import make_motion, sample
    from frictex.textures.extent import display_box
    x0, y0, x1, y1 = display_box(scene.display) if box is None else box
    width, height = x1 - x0, y1 - y0
    span = (max(width, MIN_STROKE_SPAN_MM), max(height, MIN_STROKE_SPAN_MM))
    motion = make_motion("human", duration_s=STROKE_S, speed_mm_s=STROKE_SPEED_MM_S,
                         area_mm=span, seed=STROKE_SEED)
    trace = sample(motion, STROKE_RATE_HZ, force_n=scene.device.normal_force_n)
    if span == (width, height) and (x0, y0) == (0.0, 0.0):
        return trace
    return make_trace(trace.t_s, trace.finger, x0 + trace.x_mm * (width / span[0]),
                      y0 + trace.y_mm * (height / span[1]), trace.force_n, trace.event)


def _stroke_output(scene, recording: bool = False, trace=None):
    """The pipeline's output (a ``BlockOutput``) over ``trace`` (default the typical
    stroke), and its layer renderers (each a :class:`_Recording` of what it gave where
    ``recording``)."""
    from frictex.rendering.pipeline import build_pipeline
    from frictex.rendering.tracking.tracks import apply_index

    trace = stroke_trace(scene) if trace is None else trace
    pipe = build_pipeline(scene, t0_s=float(trace.t_s[0]))
    if recording:
        pipe.renderers = tuple(_Recording(r) for r in pipe.renderers)
    applied = apply_index(trace.t_s, pipe.tracker_config)
    blocks = int(applied[-1] // pipe.block_size) + 1
    out, _ = pipe.process(0, trace, pipe.initial_state(), n_blocks=blocks)
    return out, pipe.renderers


def _stroke(scene):
    """(composed mu' of the contact samples (m,), per-layer (mu, covers) (1, m) there)."""
    out, renderers = _stroke_output(scene, recording=True)
    touching = out.contact
    outputs = [(np.broadcast_to(mu, touching.shape)[touching][None, :],
                np.broadcast_to(covers, touching.shape)[touching][None, :])
               for mu, covers in (r.outputs[0] for r in renderers)]
    return out.mu_target[touching], outputs


def _causes(names, below: list[tuple[np.ndarray, list]]) -> tuple[str, ...]:
    """Layers holding at least CAUSE_SHARE of the mean -ln mu' where the product is below."""
    drops = np.zeros(len(names))
    for mask, outputs in below:
        for k, (mu, covers) in enumerate(outputs):
            lowered = np.where(covers[0][mask], -np.log(mu[0][mask]), 0.0)
            drops[k] += float(lowered.sum())
    total = drops.sum()
    if total <= 0.0:
        return ()
    return tuple(name for name, drop in zip(names, drops) if drop >= CAUSE_SHARE * total)


def scene_reach(scene) -> Reach:
    """The share of ``scene``'s area and of a typical stroke below the device's floor at
    the scene's nominal normal force (see the module docstring)."""
    force = scene.device.normal_force_n
    floor = mu_floor(scene.device, force)
    limit = floor - TOLERANCE
    overlap = lowest_overlap(scene.display, [layer for layer in scene.layers
                                             if applies_alone(layer)])
    if overlap.lowest >= limit:
        return Reach(floor, force, 0.0, 0.0, overlap, ())
    area_mu, area_layers = _area(scene)
    stroke_mu, stroke_layers = _stroke(scene)
    area_below, stroke_below = area_mu < limit, stroke_mu < limit
    causes = _causes([layer.name for layer in scene.layers],
                     [(area_below, area_layers), (stroke_below, stroke_layers)])
    return Reach(floor, force, float(area_below.mean()),
                 float(stroke_below.mean()) if stroke_mu.size else 0.0, overlap, causes)


@dataclass(frozen=True)
class ForceReach:
    """What part of a travelling-wave scene asks for a force the wave cannot give there.

    stroke_share : fraction in [0, 1] of the contact samples of typical strokes (over the
        display, and over each directional or guidance layer's region) whose wanted
        tangential force is out of reach, those under a key-click button that is on left
        out (a key is pressed, not stroked: a finger sliding against its push gets at
        most what the wave adds to friction).
    presses : per key-click layer, (name, fraction in [0, 1] of a press's samples with the
        button on whose push is out of reach): a still finger at the button's centre
        pressing to :data:`PRESS_PEAK` times ``click_n`` and back; samples pressing less
        than ``release_n`` (the button's dwell after a release) are left out.
    """

    stroke_share: float
    presses: tuple[tuple[str, float], ...]


#: a checking press's peak normal force, over the key's click_n
PRESS_PEAK = 1.25


def force_reach(scene) -> ForceReach | None:
    """On a travelling-wave scene (one with a force stage), what of its forces the wave
    cannot give (:class:`ForceReach`): out of reach forces are clamped to the nearest
    reachable one and counted as ``unreachable`` when the scene plays (the envelope the
    channels give within the amplifier's limit, ``PushActuation.envelope_limit_at``, which
    the pipeline's force stage plans with; on a finite beam also the travelling-wave ratio,
    which falls away from mid-span). None on any other scene."""
    from frictex.device.profile import FORCE_PROFILES
    from frictex.rendering.input.press_synth import press_trace
    from frictex.textures.model import KeyClick
    if scene.device.profile not in FORCE_PROFILES:
        return None
    unreachable = counted = 0
    for box in _stroke_boxes(scene):
        out, _ = _stroke_output(scene, trace=stroke_trace(scene, box))
        touching = out.contact if out.forces.button is None else (
            out.contact & (out.forces.button == 0))
        unreachable += int((out.forces.unreachable & touching).sum())
        counted += int(touching.sum())
    stroke = unreachable / counted if counted else 0.0
    presses = []
    for layer in scene.layers:
        if isinstance(layer, KeyClick):
            x, y = layer.geometry.center
            press = press_trace(peaks_n=(PRESS_PEAK * layer.click_n,), x_mm=x, y_mm=y,
                                rate_hz=STROKE_RATE_HZ, touch_n=0.5 * layer.release_n,
                                noise_n=0.0)
            pressed, _ = _stroke_output(scene, trace=press)
            sample = np.maximum(np.searchsorted(press.t_s, pressed.t_s, side="right") - 1, 0)
            on = (pressed.contact & (pressed.forces.button > 0)
                  & (press.force_n[sample] >= layer.release_n))
            presses.append((layer.name, float((pressed.forces.unreachable & on).sum() / on.sum())
                             if on.any() else 0.0))
    return ForceReach(stroke, tuple(presses))


def _stroke_boxes(scene) -> list:
    """Where :func:`force_reach` strokes: the display, and each directional or guidance
    layer's region on it (a long beam's typical stroke covers a fifth of it)."""
    from frictex.textures.extent import display_box, intersect, region_box
    from frictex.textures.model import Directional, Guidance
    display = display_box(scene.display)
    boxes = [display]
    for layer in scene.layers:
        if isinstance(layer, Directional | Guidance) and layer.region is not None:
            box = intersect(region_box(layer.region), display)
            if box is not None and box not in boxes:
                boxes.append(box)
    return boxes
