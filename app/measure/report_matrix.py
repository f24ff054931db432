"""The measurements behind ``frictex report``: one row per (scene, motion, touch rate,
renderer configuration), each with accuracy (``rendering.metrics``) and cost.

A row renders one synthetic finger motion (``rendering.input.trace_synth``) sampled like a touch
screen at ``touch_hz`` (with 0.05 mm position noise, a good capacitive controller) and
compares the commanded friction with the scene on the true path: mu' of the friction
model (seed 003 eq 2) at the commanded amplitude, so the inversion's error counts but
not the plate's own dynamics. ``through_plate`` (matrix rows; None for the draws, whose
claims use the commanded figures) gives the time and spectral errors of the same
amplitude after the plate's amplitude loop, the first-order 400 Hz low-pass of
``device.finger`` (seed 003 section 4.2, Fig. 3b): what the plate delivers, which the
spectral error's band (to 1 kHz) sees. On a
scene of one coarse grating (15, 5 mm) a row also counts the edges felt twice
(``chatter``, None elsewhere).

Costs are compute time per second of output (one run of the case, timed after an
untimed ``WARM_UP_S`` run of another pipeline of the same configuration), per stage (tracking, each layer,
composition, inversion, actuation, link encode); ``replay_x_realtime`` counts the
pipeline stages only (a headless replay sends nothing); ``live_block_p99_thread_cpu_us``
is the 99th percentile (the largest under 101 blocks, ``app.measure.tail``; ``frictex
report --quick`` times 101) of one 5 ms block's compute in the thread's CPU time when the
same trace is fed block by block with the garbage collector frozen, as the live haptic
thread runs and as ``frictex bench pipeline`` times it (its wall time beside it, and the
count of blocks: a row's live run is short, so its p99 is over far fewer blocks than
the bench's 2,000); ``latency_ms`` is the longest wait of a touch sample for
the block that first uses it, plus the link's jitter buffer (``device.link.host.TARGET_S``).
"""

from __future__ import annotations

import time
from dataclasses import asdict, dataclass

import numpy as np

from frictex.app.engine.clocks import VirtualClock
from frictex.app.engine.driver import PipelineStage, drive
from frictex.app.engine.sinks import MemorySink
from frictex.app.engine.sources import TraceSource
from frictex.app.measure.tail import tail
from frictex.rendering.input.trace_synth import make_motion, sample, truth
from frictex.rendering.metrics import (CHATTER_PERIOD_MM, MetricError, accuracy, hold,
                                       reference, spectral_error, time_error)
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.renderers import RENDERERS, any_layer, sho_variant_of
from frictex.rendering.input.trace_file import Trace
from frictex.rendering.tracking.tracks import apply_index

#: bundled scenes of the matrix: the seed 003 gratings, one object scene, one composed
SCENES = ("grating-15mm", "grating-5mm", "grating-0.6mm", "objects-bump-edge-disc",
          "composed-fine-grating-in-disc")
#: finger motions: name -> make_motion arguments (mm, s, mm/s); the swipes run from 10 to
#: 94 mm, clear across every edge of the bundled scenes (the last at 90 mm)
MOTIONS = {
    "slow": dict(kind="swipe", speed_mm_s=20.0, duration_s=4.2, x0_mm=10.0),
    "fast": dict(kind="swipe", speed_mm_s=120.0, duration_s=0.7, x0_mm=10.0),
    "reversing": dict(kind="back-and-forth", speed_mm_s=60.0, duration_s=3.0, x0_mm=30.0,
                      length_mm=45.0),
    "human": dict(kind="human", speed_mm_s=60.0, duration_s=4.0, seed=7),
}
TOUCH_HZ = (50.0, 120.0, 240.0)
#: output (s) of the untimed run of a case's configuration before the run its costs come
#: from: the first run in a process pays first-use costs (allocations, caches) that made
#: a cold grating-15mm fast swipe cost hybrid 1538 us/s against 532 warm
WARM_UP_S = 0.1


def periods_per_sample(motion: dict, touch_hz: float, period_mm: float | None) -> float | None:
    """Grating periods a constant-speed ``motion`` (``MOTIONS``' arguments) crosses
    between two touch samples at ``touch_hz``; None for other motions or no grating. A
    whole number makes the speed aliasing-degenerate: every sample lands at the same
    phase, so a position map read at the samples gives a constant mu' (120 mm/s at 50 Hz
    on the 0.6 mm grating: 2.4 mm, 4 periods)."""
    if motion.get("kind") != "swipe" or not period_mm:
        return None
    return motion["speed_mm_s"] / touch_hz / period_mm


def aliasing_degenerate(per_sample: float | None) -> bool:
    """Whether :func:`periods_per_sample`'s figure is a whole number (to 1e-6)."""
    return per_sample is not None and abs(per_sample - round(per_sample)) < 1e-6


def aliased(row: Row) -> bool:
    """Whether ``row`` is sho-held on a swipe whose speed is aliasing-degenerate at its
    touch rate: a constant mu', not a measure of the renderer."""
    per = periods_per_sample(MOTIONS.get(row.motion, {}), row.touch_hz, row.period_mm)
    return row.renderer == "sho-held" and aliasing_degenerate(per)
OUTPUT_HZ = (2000.0, 5000.0, 10_000.0, 20_000.0)
INVERSIONS = ("exact", "lut")
#: the reference grid (Hz): at least the highest output rate
REFERENCE_HZ = 20_000.0
#: position noise of the sampled traces (mm, standard deviation)
TOUCH_NOISE_MM = 0.05


@dataclass(frozen=True)
class Case:
    """One row's inputs."""

    scene: str
    motion: str
    touch_hz: float
    renderer: str
    output_hz: float
    inversion: str = "exact"


@dataclass(frozen=True)
class Steps:
    """Friction steps of the true path (``ideal``) and of the rendered friction
    (``rendered``), as ``rendering.metrics.accuracy`` counts them."""

    ideal: int
    rendered: int


@dataclass(frozen=True)
class Throughput:
    """Speed figures of a row: ``replay_x_realtime`` (seconds of output per second of
    pipeline compute), ``live_block_p99_thread_cpu_us`` and ``live_block_p99_wall_us``
    (99th percentile of one 5 ms block's compute, us, the largest under 101 blocks:
    ``app.measure.tail``; in the thread's CPU time with the
    garbage collector frozen and in wall time) over ``live_blocks`` blocks, ``latency_ms``
    (longest wait of a touch sample for its block plus the link's jitter buffer, ms)."""

    replay_x_realtime: float
    live_block_p99_thread_cpu_us: float
    live_block_p99_wall_us: float
    live_blocks: int
    latency_ms: float


@dataclass(frozen=True)
class PlateErrors:
    """A row's time and spectral errors (``rendering.metrics``) of mu' through the plate's
    amplitude loop (module docstring). No alignment error: the plate starts each touch
    at rest, so its rise at touch-down is a step of mu' that no edge of the scene matches
    (scored at the 10 mm cap: on the composed scene's human-like stroke 1.29 mm against
    0.021 mm commanded), while the loop's own lag (0.4 ms: 0.05 mm at 120 mm/s) is below
    what the alignment error resolves."""

    time_error: float
    spectral_error: float


def through_plate(amplitude_um: np.ndarray, rate_hz: float) -> np.ndarray:
    """The amplitude the plate delivers (um) for the commanded ``amplitude_um`` at
    ``rate_hz``: ``device.finger``'s first-order low-pass at the plate loop's bandwidth,
    starting at rest."""
    from frictex.device.finger import SensorParams, lowpass, pole
    return lowpass(amplitude_um, pole(SensorParams().plate_bw_hz, rate_hz), 0.0)[0]


def _plate_errors(ref, t_out: np.ndarray, pipeline, amplitude_um: np.ndarray,
                  force_n: float) -> PlateErrors:
    """The time and spectral errors of what the plate delivers for ``amplitude_um``."""
    delivered = pipeline.friction.forward(through_plate(amplitude_um, pipeline.rate_hz), force_n)
    mu = np.where(ref.contact, hold(t_out, delivered, ref.t_s, pipeline.rate_hz), 1.0)
    return PlateErrors(time_error(mu, ref.mu, ref.contact),
                       spectral_error(mu, ref.mu, ref.contact, ref.rate_hz))


@dataclass(frozen=True)
class Row:
    """One row of the matrix (module docstring): the case, its errors (``rendering.metrics``;
    None where a metric has nothing to measure), its cost in us per second of output, in
    all and per stage, its ``throughput`` and the inversion's clamp counts; ``through_plate``:
    the errors of what the plate delivers (None where not scored)."""

    scene: str
    period_mm: float | None
    motion: str
    touch_hz: float
    renderer: str
    output_hz: float
    inversion: str
    time_error: float
    spectral_error: float
    alignment_error_mm: float | None
    chatter: int | None
    steps: Steps
    cost_us_per_s: float
    stages_us_per_s: dict[str, float]
    throughput: Throughput
    clamps: dict
    through_plate: PlateErrors | None = None

    @property
    def config(self) -> str:
        """The renderer configuration: renderer, output rate, inversion."""
        return f"{self.renderer} {self.output_hz / 1000:g} kHz {self.inversion}"

    def to_json(self) -> dict:
        """The row as report.json holds it."""
        return asdict(self)

    @classmethod
    def from_json(cls, doc: dict) -> Row:
        """A row read back from report.json."""
        plate = doc.get("through_plate")
        return cls(**{**doc, "steps": Steps(**doc["steps"]),
                      "throughput": Throughput(**doc["throughput"]),
                      "through_plate": None if plate is None else PlateErrors(**plate)})


def matrix(quick: bool, scenes=SCENES) -> list[Case]:
    """The cases of the full or quick matrix.

    Full: every scene x motion x touch rate x renderer at 10 kHz, exact inversion; plus,
    at 50 Hz, every other output rate and the LUT inversion. Quick: 50 Hz, the
    constant-speed and human motions, 10 kHz; the human motion also at 120 and 240 Hz;
    and on the gratings, for the human motion, the output-rate and inversion sweep.
    Renderers that cannot differ on a scene (SHT and hybrid on a scene without periodic
    layers) are left out.
    """
    cases = []
    for scene in scenes:
        renderers = RENDERERS.names()
        if not _has_periodic(scene):
            renderers = tuple(filter(any_layer, renderers))
        for motion in MOTIONS:
            if quick and motion == "reversing":
                continue
            for touch in TOUCH_HZ:
                if quick and touch != 50.0 and motion != "human":
                    continue
                cases += [Case(scene, motion, touch, r, 10_000.0) for r in renderers]
            if quick and (motion != "human" or not scene.startswith("grating")):
                continue
            for r in renderers:
                cases += [Case(scene, motion, 50.0, r, hz) for hz in OUTPUT_HZ if hz != 10_000.0]
                cases.append(Case(scene, motion, 50.0, r, 10_000.0, "lut"))
    return cases


def _has_periodic(scene_name: str) -> bool:
    return any(layer.is_periodic for layer in load(scene_name).layers)


_SCENE_CACHE: dict = {}


def load(scene_name: str):
    """A bundled scene by name (loaded once per process)."""
    if scene_name not in _SCENE_CACHE:
        from frictex.textures.library import resolve_scene
        from frictex.textures.loader import load_scene
        _SCENE_CACHE[scene_name] = load_scene(resolve_scene(scene_name))
    return _SCENE_CACHE[scene_name]


def _pipeline(scene, case: Case):
    sho_variant = sho_variant_of(case.renderer)
    return build_pipeline(scene, rate_hz=case.output_hz,
                          render_override=case.renderer, sho_variant=sho_variant,
                          inversion=case.inversion)


class TimedStage(PipelineStage):
    """A pipeline stage that keeps each call's compute time (s)."""

    def __init__(self, pipeline):
        super().__init__(pipeline)
        self.seconds: list[float] = []

    def process(self, k, samples, n):
        t = time.perf_counter()
        result = super().process(k, samples, n)
        self.seconds.append(time.perf_counter() - t)
        return result


def run_blocks(pipeline, trace: Trace, blocks_per_call: int, duration_s: float):
    """Run ``trace`` through ``pipeline`` from t = 0 for ``duration_s`` of output, on the
    run engine with a virtual clock, ``blocks_per_call`` blocks per pipeline call.

    Returns (outputs, per-call compute seconds).
    """
    stage = TimedStage(pipeline)
    source = TraceSource(iter([trace]), until_s=duration_s)
    source.start(pipeline.tracker_config)
    outputs = MemorySink()
    drive(stage, source, [outputs], VirtualClock(), chunk_blocks=blocks_per_call)
    return outputs.outs, np.array(stage.seconds)


def live_seconds(pipeline, trace: Trace, duration_s: float) -> tuple[np.ndarray, np.ndarray]:
    """Per-block (wall, thread CPU) seconds of ``trace`` through ``pipeline`` one 5 ms
    block per call for ``duration_s``, timed as ``frictex bench pipeline`` times its live
    blocks (``live_timing.time_blocks``: the garbage collector frozen meanwhile, as the
    live haptic process has it)."""
    from frictex.app.measure.live_timing import time_blocks
    return time_blocks(PipelineStage(pipeline), trace, duration_s)


def stack_fingers(outs, field: str, fill) -> tuple[list[int], np.ndarray]:
    """A per-finger output field over consecutive blocks: the finger ids any block has,
    and (F, n) values, ``fill`` where a block does not carry a finger (one that lifted
    and was forgotten, or not down yet)."""
    segments = [o.segments() for o in outs]
    ids = sorted({fid for found in segments for _, fid, _, _ in found})
    parts = []
    for o, found in zip(outs, segments):
        values = getattr(o, field)
        block = np.full((len(ids), o.t_s.size), fill, dtype=values.dtype)
        for row, fid, lo, hi in found:
            block[ids.index(fid), lo:hi] = values[row, lo:hi]
        parts.append(block)
    return ids, np.concatenate(parts, axis=1)


def _encode_seconds(commands_um: np.ndarray, block: int) -> float | None:
    """Compute time (s) to put these commands on the wire, block by block."""
    try:
        from frictex.device.link.protocol import Block, amplitude_to_wire, encode
    except ImportError:
        return None
    t = time.perf_counter()
    for k in range(0, commands_um.shape[0], block):
        counts, _ = amplitude_to_wire(commands_um[k:k + block])
        encode(Block(k, counts), seq=k // block)
    return time.perf_counter() - t


def link_buffer_s() -> float:
    """The jitter buffer a paced link keeps (s): what ``latency_ms`` adds to the wait."""
    from frictex.device.link.host import TARGET_S
    return TARGET_S


class Runner:
    """Runs cases, caching the traces and references they share.

    ``motions``: name -> ``make_motion`` arguments, optionally with ``"sampling"``: the
    ``sample`` keywords for that motion's touch trace (``seed``, ``jitter_s``, ``drop``;
    default seed 11, no jitter, no drops; the noise is always ``TOUCH_NOISE_MM``).
    ``plate``: also score each row through the plate (``Row.through_plate``).
    """

    def __init__(self, live_s: float = 1.0, motions: dict | None = None, plate: bool = True):
        self.live_s = live_s
        self.plate = plate
        self.motions = MOTIONS if motions is None else motions
        self._refs: dict = {}
        self._traces: dict = {}

    def _motion(self, name: str):
        return make_motion(**{k: v for k, v in self.motions[name].items() if k != "sampling"})

    def reference(self, scene_name: str, motion_name: str):
        key = (scene_name, motion_name)
        if key not in self._refs:
            self._refs[key] = reference(load(scene_name), truth(self._motion(motion_name), REFERENCE_HZ))
        return self._refs[key]

    def trace(self, motion_name: str, touch_hz: float) -> Trace:
        key = (motion_name, touch_hz)
        if key not in self._traces:
            sampling = {"seed": 11, **self.motions[motion_name].get("sampling", {})}
            self._traces[key] = sample(self._motion(motion_name), touch_hz,
                                       noise_mm=TOUCH_NOISE_MM, **sampling)
        return self._traces[key]

    def run(self, case: Case) -> Row:
        """The row for ``case`` (see the module docstring and ``app.commands.report``)."""
        scene = load(case.scene)
        trace = self.trace(case.motion, case.touch_hz)
        ref = self.reference(case.scene, case.motion)
        duration = float(ref.t_s[-1]) + 1.0 / ref.rate_hz

        run_blocks(_pipeline(scene, case), trace, 200, min(WARM_UP_S, duration))
        pipeline = _pipeline(scene, case)
        outs, _ = run_blocks(pipeline, trace, 200, duration)
        t_out = np.concatenate([o.t_s for o in outs])
        ids, amplitudes = stack_fingers(outs, "amplitude_um", 0.0)
        amplitude = amplitudes[ids.index(int(trace.finger[0]))]
        commands = np.concatenate([o.commands_um for o in outs])
        felt = pipeline.friction.forward(amplitude, float(trace.force_n[0]))
        grating = (scene.layers[0] if len(scene.layers) == 1
                   and (scene.grating_period_mm or 0.0) >= CHATTER_PERIOD_MM else None)
        plate = None
        try:
            acc = accuracy(ref, t_out, felt, pipeline.rate_hz, layer=grating)
            if self.plate:
                plate = _plate_errors(ref, t_out, pipeline, amplitude, float(trace.force_n[0]))
        except MetricError as exc:
            raise MetricError(f"report case {case}: {exc}") from None
        output_s = t_out.size / pipeline.rate_hz
        stages = {name: s for name, s in pipeline.timer.seconds.items() if name != "layers"}
        for name, s in pipeline.timer.layer_seconds.items():
            stages[f"layer:{name}"] = s
        compute = sum(stages.values())
        encode = _encode_seconds(commands, pipeline.block_size)
        if encode is not None:
            stages["link_encode"] = encode

        live = _pipeline(scene, case)
        live_s = min(self.live_s, duration)
        wall, cpu = live_seconds(live, trace, live_s)
        applied_t = apply_index(trace.t_s, pipeline.tracker_config) / pipeline.rate_hz
        wait_s = float(np.max(applied_t - trace.t_s))

        clamps = None
        for o in outs:
            clamps = o.clamps if clamps is None else (clamps.add(o.clamps) or clamps)
        return Row(
            scene=case.scene, period_mm=scene.grating_period_mm, motion=case.motion,
            touch_hz=case.touch_hz, renderer=case.renderer, output_hz=case.output_hz,
            inversion=case.inversion,
            time_error=acc.time_error, spectral_error=acc.spectral_error,
            alignment_error_mm=acc.alignment_error_mm, chatter=acc.chatter,
            steps=Steps(ideal=acc.ideal_steps, rendered=acc.rendered_steps),
            cost_us_per_s=compute / output_s * 1e6,
            stages_us_per_s={k: v / output_s * 1e6 for k, v in stages.items()},
            throughput=Throughput(
                replay_x_realtime=output_s / compute,
                live_block_p99_thread_cpu_us=tail(cpu)[1] * 1e6,
                live_block_p99_wall_us=tail(wall)[1] * 1e6,
                live_blocks=int(wall.size),
                latency_ms=(wait_s + link_buffer_s()) * 1e3),
            clamps=clamps.as_dict(), through_plate=plate)


_RUNNERS: dict = {}


def run_case(case: Case, live_s: float = 1.0, motions: dict | None = None,
             plate: bool = True) -> Row:
    """``Runner(live_s, motions, plate).run(case)`` with one runner per process and
    settings, so that cases fanned out over processes (``app.engine.fanout``) share its
    caches."""
    key = (live_s, None if motions is None else repr(sorted(motions.items())), plate)
    if key not in _RUNNERS:
        _RUNNERS[key] = Runner(live_s=live_s, motions=motions, plate=plate)
    return _RUNNERS[key].run(case)
