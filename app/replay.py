"""Headless replay: a scene and a recorded trace through the whole pipeline, on a virtual clock.

The output clock starts at the trace's first sample (t_s of output sample k is
t0 + k / rate) and runs until one block after the last sample. Each pass processes
``chunk_blocks`` blocks at once (fast), but a touch sample still takes effect at the
block boundary after it (see ``rendering.tracks``), so the result equals a live run
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

from app.force_summary import ForceSummary
from app.outputs import TableWriter
from rendering.pipeline import STAGES, build_pipeline
from rendering.trace_file import Trace, read_trace
from rendering.tracks import apply_index
from textures.model import Scene

SUMMARY_VERSION = 1


def _load_inputs(scene, trace):
    if not isinstance(scene, Scene):
        from textures.library import resolve_scene
        from textures.loader import load_scene
        scene = load_scene(resolve_scene(scene))
    trace_path = None
    if not isinstance(trace, Trace):
        from textures.library import resolve_trace
        trace_path = resolve_trace(trace)
        trace = read_trace(trace_path)
    return scene, trace, trace_path


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
    ``device.link.open_sink``) that receives every block; the replay closes it (a paced
    link drains first) before writing the summary, so its counters are final. ``device``:
    instead of a sink, a link spec (``"sim"``, a port or a pyserial URL) opened here, paced,
    with the channels and phases of the scene's actuation. ``frames``: an optional object
    with ``add(out)`` and ``close()`` receiving every chunk's output (PNG frames).
    """
    wall0 = time.perf_counter()
    scene, trace, trace_path = _load_inputs(scene, trace)
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    t0 = float(trace.t_s[0])
    pipeline = build_pipeline(scene, rate_hz=rate_hz, block_size=block_size,
                              render_override=render_override, t0_s=t0)
    if device is not None:
        from device.link import open_sink
        sink = open_sink(device, channels=len(pipeline.channels), rate_hz=rate_hz,
                         phases=pipeline.actuation.has_phases, paced=True)
    applied = apply_index(trace.t_s, pipeline.tracker_config)
    total_blocks = int(applied[-1] // block_size) + 1
    state = pipeline.initial_state()

    commands = TableWriter(out_dir, "commands", _command_columns(pipeline), fmt)
    friction = TableWriter(out_dir, "friction", FRICTION_COLUMNS, fmt)
    clamps = None
    errors = _AmplitudeErrors()
    forces = ForceSummary()
    max_amplitude = 0.0
    contact_samples = 0
    limited = off_structure = 0
    bar = _progress(total_blocks * block_size / rate_hz, progress)
    try:
        for block in range(0, total_blocks, chunk_blocks):
            nb = min(chunk_blocks, total_blocks - block)
            lo, hi = np.searchsorted(applied, [block * block_size, (block + nb) * block_size])
            chunk = _slice_trace(trace, lo, hi) if hi > lo else None
            out, state = pipeline.process(block, chunk, state, n_blocks=nb)
            cols = {"t_s": out.t_s}
            for k, ch in enumerate(pipeline.channels):
                cols[f"{ch}_um"] = out.commands_um[:, k]
                if out.phases_rad is not None:
                    cols[f"{ch}_phase_rad"] = out.phases_rad[:, k]
            commands.write(cols)
            friction.write(friction_rows(out))
            if clamps is None:
                clamps = out.clamps
            else:
                clamps.add(out.clamps)
            errors.add(out)
            forces.add(out)
            max_amplitude = max(max_amplitude, float(out.commands_um.max(initial=0.0)))
            contact_samples += int(out.contact.any(axis=0).sum())
            limited += out.limited
            off_structure += out.off_structure
            if sink is not None:
                for b in range(nb):
                    s = slice(b * block_size, (b + 1) * block_size)
                    phases = None if out.phases_rad is None else out.phases_rad[s]
                    sink.send(out.index0 + b * block_size, out.commands_um[s], phases)
            if frames is not None:
                frames.add(out)
            if bar is not None:
                bar.update(nb * block_size / rate_hz)
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

    summary = _summary(scene, trace, trace_path, pipeline, state, clamps, fmt, files,
                       total_blocks, contact_samples, max_amplitude, sink)
    summary["fingers"] = errors.report()
    summary["counts"].update(actuator_limited=limited, off_structure=off_structure)
    if limited:
        summary["warnings"].append(f"{limited} samples hit an actuator limit (achieved amplitude "
                                   "differs from the wanted one; see fingers)")
    if off_structure:
        summary["warnings"].append(f"{off_structure} finger samples were off the vibrating "
                                   "structure and were held at its edge")
    if forces.report() is not None:
        summary["forces"] = forces.report()
    summary["timings"] = _timings(pipeline, total_blocks * block_size / rate_hz,
                                  time.perf_counter() - wall0)
    (out_dir / "summary.json").write_text(json.dumps(summary, indent=2) + "\n", encoding="utf-8")
    return summary


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


def _slice_trace(trace: Trace, lo: int, hi: int) -> Trace:
    return Trace(trace.t_s[lo:hi], trace.finger[lo:hi], trace.x_mm[lo:hi], trace.y_mm[lo:hi],
                 trace.force_n[lo:hi], trace.event[lo:hi])


def _progress(total_s: float, enabled: bool):
    """A progress bar (seconds of output) on stderr for replays longer than 30 s."""
    if not enabled or total_s < 30.0:
        return None
    from tqdm import tqdm
    return tqdm(total=round(total_s, 3), unit="s", desc="replay", disable=None,
                bar_format="{l_bar}{bar}| {n:.0f}/{total:.0f} s of output [{elapsed}<{remaining}]")


def _summary(scene, trace, trace_path, pipeline, state, clamps, fmt, files, total_blocks,
             contact_samples, max_amplitude, sink) -> dict:
    n_out = total_blocks * pipeline.block_size
    steps = np.diff(trace.t_s)
    steps = steps[steps > 0]
    touch_hz = float(1.0 / np.median(steps)) if steps.size else None
    clamp_dict = clamps.as_dict()
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
        "trace": {"path": str(trace_path) if trace_path else None, "samples": len(trace),
                  "fingers": list(trace.fingers), "duration_s": trace.duration_s,
                  "touch_rate_hz": touch_hz},
        "output": {"rate_hz": pipeline.rate_hz, "block_size": pipeline.block_size,
                   "samples": n_out, "duration_s": n_out / pipeline.rate_hz,
                   "channels": list(pipeline.channels), "format": fmt, "files": files},
        "counts": {"blocks": total_blocks, "contact_samples": contact_samples,
                   "jumps": state.tracker.jumps, "out_of_order": state.tracker.out_of_order,
                   "max_amplitude_um": max_amplitude},
        "clamps": clamp_dict,
        "warnings": warnings,
    }
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
