"""Headless replay: a scene and a recorded trace through the whole pipeline, on a virtual clock.

The output clock starts at the trace's first sample (t_s of output sample k is
t0 + k / rate) and runs until the block after the last sample. The trace is read in
chunks and the outputs written in chunks, so memory stays bounded however long the
trace (an hour at 10 kHz is 36 million command rows). Each pass processes
``chunk_blocks`` blocks at once (fast), but a touch sample still takes effect at the
block boundary after it (see ``rendering.tracking.tracks``), so the result equals a live run
block by block, and two replays of the same inputs are byte-identical (timings aside,
which ``summary.json`` keeps under its own key).

Outputs (DESIGN.md): ``commands.csv`` (t_s, one column per channel in um, phases where
the actuation has them), ``friction.csv`` (one row per touching finger and output
sample: t_s, finger, x_mm, y_mm, mu_target, amplitude_um), ``summary.json``. With
``fmt="npz"`` the two tables are ``commands.npz`` / ``friction.npz`` with one array per
column. Either all outputs are written or none (partial files are removed on error).
"""

from __future__ import annotations

import json
import time
from pathlib import Path

import numpy as np

from app.engine.force_summary import ForceSummary
from app.engine.tables import TableWriter
from device.friction import ClampCounts
from rendering.pipeline import STAGES, build_pipeline
from rendering.input.trace_file import Trace, iter_trace
from rendering.tracking.tracks import apply_index
from textures.model import Scene

SUMMARY_VERSION = 1


def _load_inputs(scene, trace):
    if not isinstance(scene, Scene):
        from textures.library import resolve_scene
        from textures.loader import load_scene
        scene = load_scene(resolve_scene(scene))
    if isinstance(trace, Trace):
        return scene, iter([trace]), None
    from textures.library import resolve_trace
    trace_path = resolve_trace(trace)
    return scene, iter_trace(trace_path), trace_path


class _TraceFeed:
    """Touch samples from a stream of trace chunks, handed out by the blocks in which
    they take effect; reads ahead only as far as the window asked for needs."""

    def __init__(self, chunks):
        self.chunks = chunks
        self.pending: Trace | None = None
        self.applied = np.zeros(0, dtype=np.int64)
        self.config = None
        self.ended = False
        self.stats = _TraceStats()

    def first_time(self) -> float:
        self._read_more()
        return float(self.pending.t_s[0])

    def _read_more(self) -> None:
        chunk = next(self.chunks, None)
        if chunk is None:
            self.ended = True
            return
        self.stats.add(chunk)
        self.pending = chunk if self.pending is None else _join(self.pending, chunk)
        if self.config is not None:
            self.applied = apply_index(self.pending.t_s, self.config)

    def start(self, tracker_config) -> None:
        self.config = tracker_config
        self.applied = apply_index(self.pending.t_s, tracker_config)

    def take(self, end_index: int) -> Trace | None:
        """The samples taking effect before output index ``end_index``."""
        while not self.ended and (self.applied.size == 0 or self.applied[-1] < end_index):
            self._read_more()
        hi = int(np.searchsorted(self.applied, end_index))
        if hi == 0:
            return None
        taken = _slice_trace(self.pending, 0, hi)
        self.pending = _slice_trace(self.pending, hi, len(self.pending))
        self.applied = self.applied[hi:]
        return taken

    @property
    def done(self) -> bool:
        return self.ended and self.applied.size == 0


class _TraceStats:
    """What the summary says about the trace, gathered chunk by chunk."""

    MAX_STEPS = 100_000  # the touch rate is the median over the first steps

    def __init__(self):
        self.samples = 0
        self.fingers: set[int] = set()
        self.first_t = self.last_t = None
        self.steps: list[np.ndarray] = []
        self.n_steps = 0

    def add(self, chunk: Trace) -> None:
        times = chunk.t_s if self.last_t is None else np.concatenate(([self.last_t], chunk.t_s))
        if self.n_steps < self.MAX_STEPS:
            steps = np.diff(times)
            steps = steps[steps > 0][: self.MAX_STEPS - self.n_steps]
            self.steps.append(steps)
            self.n_steps += steps.size
        self.samples += len(chunk)
        self.fingers.update(chunk.fingers)
        self.first_t = float(chunk.t_s[0]) if self.first_t is None else self.first_t
        self.last_t = float(chunk.t_s[-1])

    def report(self, path) -> dict:
        steps = np.concatenate(self.steps) if self.steps else np.zeros(0)
        return {"path": str(path) if path else None, "samples": self.samples,
                "fingers": sorted(self.fingers), "duration_s": self.last_t - self.first_t,
                "touch_rate_hz": float(1.0 / np.median(steps)) if steps.size else None}


def _command_columns(pipeline):
    cols = [("t_s", np.float64, "%.7f")]
    cols += [(f"{ch}_um", np.float64, "%.6f") for ch in pipeline.channels]
    if pipeline.actuation.has_phases:
        cols += [(f"{ch}_phase_rad", np.float64, "%.6f") for ch in pipeline.channels]
    return cols


FRICTION_COLUMNS = [("t_s", np.float64, "%.7f"), ("finger", np.int64, "%d"),
                    ("x_mm", np.float64, "%.4f"), ("y_mm", np.float64, "%.4f"),
                    ("mu_target", np.float64, "%.6f"), ("amplitude_um", np.float64, "%.6f")]


def friction_rows(out) -> dict[str, np.ndarray]:
    """Rows (sample-major, then finger) for the fingers touching."""
    contact = out.contact.T  # (n, F)
    n, f = contact.shape
    ids = np.broadcast_to(np.array(out.finger_ids, dtype=np.int64), (n, f))
    t = np.broadcast_to(out.t_s[:, None], (n, f))
    return {"t_s": t[contact], "finger": ids[contact], "x_mm": out.x_mm.T[contact],
            "y_mm": out.y_mm.T[contact], "mu_target": out.mu_target.T[contact],
            "amplitude_um": out.amplitude_um.T[contact]}


def run_replay(scene, trace, out_dir, rate_hz: float = 10_000.0, fmt: str = "csv", sink=None,
               device: str | None = None, block_size: int = 50, render_override: str | None = None,
               chunk_blocks: int = 200, progress: bool = True, frames=None) -> dict:
    """Replay ``trace`` (Trace or path/bundled name) on ``scene`` (Scene or path/name).

    Writes the outputs into ``out_dir`` (created if needed) and returns the summary
    (also written as ``summary.json``). ``sink``: an optional command sink (see
    ``device.link.host.open_sink``) that receives every block; the replay closes it (a paced
    link drains first) before writing the summary, so its counters are final. ``device``:
    instead of a sink, a link spec (``"sim"``, a port or a pyserial URL) opened here, paced,
    with the channels and phases of the scene's actuation. ``frames``: an optional object
    with ``add(out)`` and ``close()`` receiving every chunk's output (PNG frames).
    """
    wall0 = time.perf_counter()
    scene, chunks, trace_path = _load_inputs(scene, trace)
    feed = _TraceFeed(chunks)
    t0 = feed.first_time()
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    pipeline = build_pipeline(scene, rate_hz=rate_hz, block_size=block_size,
                              render_override=render_override, t0_s=t0)
    if device is not None:
        from device.link.host import open_sink
        sink = open_sink(device, channels=len(pipeline.channels), rate_hz=rate_hz,
                         phases=pipeline.actuation.has_phases, paced=True)
    feed.start(pipeline.tracker_config)
    state = pipeline.initial_state()
    commands = TableWriter(out_dir, "commands", _command_columns(pipeline), fmt)
    friction = TableWriter(out_dir, "friction", FRICTION_COLUMNS, fmt)
    totals = _Totals()
    bar = _progress(feed, rate_hz, progress)
    block = 0
    try:
        # until the block after the last sample: every sample takes effect, the last
        # touch's end is in the output
        while not feed.done:
            samples = feed.take((block + chunk_blocks) * block_size)
            nb = chunk_blocks
            if feed.done and samples is not None:
                last = int(apply_index(samples.t_s[-1:], pipeline.tracker_config)[0])
                nb = last // block_size + 1 - block
            out, state = pipeline.process(block, samples, state, n_blocks=nb)
            _write(out, pipeline, commands, friction)
            totals.add(out)
            if sink is not None:
                for b in range(nb):
                    s = slice(b * block_size, (b + 1) * block_size)
                    phases = None if out.phases_rad is None else out.phases_rad[s]
                    sink.send(out.index0 + b * block_size, out.commands_um[s], phases)
            if frames is not None:
                frames.add(out)
            if bar is not None:
                bar.update(nb * block_size / rate_hz)
            block += nb
        files = [commands.commit().name, friction.commit().name]
    except BaseException:
        commands.abort()
        friction.abort()
        raise
    finally:
        if bar is not None:
            bar.close()
        if frames is not None:
            frames.close()
        if sink is not None:
            sink.close()

    summary = _summary(scene, feed.stats.report(trace_path), pipeline, state, totals, fmt,
                       files, block, sink)
    summary["timings"] = _timings(pipeline, block * block_size / rate_hz,
                                  time.perf_counter() - wall0)
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    return summary


def _write(out, pipeline, commands: TableWriter, friction: TableWriter) -> None:
    cols = {"t_s": out.t_s}
    for k, ch in enumerate(pipeline.channels):
        cols[f"{ch}_um"] = out.commands_um[:, k]
    if out.phases_rad is not None:
        for k, ch in enumerate(pipeline.channels):
            cols[f"{ch}_phase_rad"] = out.phases_rad[:, k]
    commands.write(cols)
    friction.write(friction_rows(out))


class _Totals:
    """What the summary counts over the whole replay, block output by block output."""

    def __init__(self):
        self.clamps = ClampCounts()
        self.errors = _AmplitudeErrors()
        self.forces = ForceSummary()
        self.max_amplitude = 0.0
        self.contact_samples = 0
        self.limited = 0
        self.off_structure = 0

    def add(self, out) -> None:
        self.clamps.add(out.clamps)
        self.errors.add(out)
        self.forces.add(out)
        self.max_amplitude = max(self.max_amplitude, float(out.commands_um.max(initial=0.0)))
        self.contact_samples += int(out.contact.any(axis=0).sum())
        self.limited += out.limited
        self.off_structure += out.off_structure


class _AmplitudeErrors:
    """Per finger: how far the achieved amplitude was from the wanted one while touching."""

    def __init__(self):
        self.stats: dict[int, list] = {}  # finger id -> [contact samples, sum of squares, max]

    def add(self, out) -> None:
        err = np.where(out.contact, out.amplitude_um - out.wanted_um, 0.0)
        for row, fid in enumerate(out.finger_ids):
            s = self.stats.setdefault(fid, [0, 0.0, 0.0])
            s[0] += int(out.contact[row].sum())
            s[1] += float(np.sum(err[row] ** 2))
            s[2] = max(s[2], float(np.abs(err[row]).max(initial=0.0)))

    def report(self) -> dict:
        """{finger: {contact_samples, amplitude_error_rms_um, amplitude_error_max_um}}."""
        return {str(fid): {"contact_samples": n,
                           "amplitude_error_rms_um": (sq / n) ** 0.5 if n else 0.0,
                           "amplitude_error_max_um": mx}
                for fid, (n, sq, mx) in sorted(self.stats.items())}


def _join(a: Trace, b: Trace) -> Trace:
    return Trace(*(np.concatenate((getattr(a, n), getattr(b, n)))
                   for n in ("t_s", "finger", "x_mm", "y_mm", "force_n", "event")))


def _slice_trace(trace: Trace, lo: int, hi: int) -> Trace:
    return Trace(trace.t_s[lo:hi], trace.finger[lo:hi], trace.x_mm[lo:hi], trace.y_mm[lo:hi],
                 trace.force_n[lo:hi], trace.event[lo:hi])


def _progress(feed: _TraceFeed, rate_hz: float, enabled: bool):
    """A progress bar (seconds of output) on stderr for long replays: when the trace's
    first chunk already spans 30 s or more, or does not hold the whole trace."""
    if not enabled:
        return None
    span = float(feed.pending.t_s[-1] - feed.pending.t_s[0])
    if span < 30.0 and feed.ended:
        return None
    from tqdm import tqdm
    return tqdm(unit="s", desc="replay", disable=None,
                bar_format="{desc}: {n:.0f} s of output [{elapsed}, {rate_fmt}]")


def _summary(scene, trace_report, pipeline, state, totals: _Totals, fmt, files, total_blocks,
             sink) -> dict:
    n_out = total_blocks * pipeline.block_size
    clamp_dict = totals.clamps.as_dict()
    warnings = []
    if clamp_dict["unreachable"] and pipeline.forces is not None:
        warnings.append(f"{clamp_dict['unreachable']} samples asked for a tangential force out "
                        "of the wave's reach and were clamped to the nearest reachable force")
    elif clamp_dict["unreachable"]:
        warnings.append(f"{clamp_dict['unreachable']} target samples were below the lowest "
                        "reachable mu' and were clamped to the amplitude limit")
    if clamp_dict["force_beyond_model"]:
        warnings.append(f"{clamp_dict['force_beyond_model']} samples had a normal force beyond "
                        "the friction model's range (asymptote capped)")
    if state.tracker.jumps:
        warnings.append(f"{state.tracker.jumps} finger jumps were treated as lift and touch")
    if state.tracker.out_of_order:
        warnings.append(f"{state.tracker.out_of_order} out-of-order touch samples were dropped")
    summary = {
        "summary_version": SUMMARY_VERSION,
        "scene": {"name": scene.name,
                  "path": str(scene.source) if scene.source else None,
                  "device": scene.device.profile,
                  "layers": [{"name": layer.name, "type": type(layer).__name__.lower(),
                              "renderer": mode}
                             for layer, mode in zip(scene.layers, pipeline.layer_modes)]},
        "trace": trace_report,
        "output": {"rate_hz": pipeline.rate_hz, "block_size": pipeline.block_size,
                   "samples": n_out, "duration_s": n_out / pipeline.rate_hz,
                   "channels": list(pipeline.channels), "format": fmt, "files": files},
        "counts": {"blocks": total_blocks, "contact_samples": totals.contact_samples,
                   "jumps": state.tracker.jumps, "out_of_order": state.tracker.out_of_order,
                   "max_amplitude_um": totals.max_amplitude,
                   "actuator_limited": totals.limited, "off_structure": totals.off_structure},
        "clamps": clamp_dict,
        "warnings": warnings,
        "fingers": totals.errors.report(),
    }
    if totals.limited:
        warnings.append(f"{totals.limited} samples hit an actuator limit (achieved amplitude "
                        "differs from the wanted one; see fingers)")
    if totals.off_structure:
        warnings.append(f"{totals.off_structure} finger samples were off the vibrating "
                        "structure and were held at its edge")
    if totals.forces.report() is not None:
        summary["forces"] = totals.forces.report()
    if sink is not None:
        summary["device"] = sink.status()
    return summary


def _timings(pipeline, output_s: float, wall_s: float) -> dict:
    stages = dict(pipeline.timer.seconds)
    compute = sum(stages.values())
    return {"wall_s": wall_s, "compute_s": compute,
            "x_realtime": output_s / compute if compute > 0 else None,
            "stages_s": {s: stages[s] for s in STAGES},
            "layers_s": dict(pipeline.timer.layer_seconds)}
