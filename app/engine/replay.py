"""Headless replay: a scene and a trace through the pipeline, on a virtual clock.

The output clock starts at the trace's first sample (t_s of output sample k is
t0 + k / rate) and runs until the block after the last sample. The trace is read and
the outputs written in chunks, so memory stays bounded however long the trace (an hour
at 10 kHz is 36 million command rows). Each pipeline call runs ``chunk_blocks`` blocks
(by default about :data:`CHUNK_SAMPLES` finger-samples: fewer calls, arrays that still fit
the cache), but a touch sample still takes effect at the block boundary after it, so the
result equals a live run block by block, and two replays of the same inputs are
byte-identical (``summary.json`` aside, whose ``timings`` differ).

Outputs (DESIGN.md): ``commands.<fmt>`` (t_s, one column per channel in um, phases where
the actuation has them), ``friction.<fmt>`` (one row per touching finger and output
sample: t_s, finger, x_mm, y_mm, mu_target, amplitude_um), ``summary.json`` (written
last). ``fmt``: csv, npz or parquet (``app.engine.tables``). A replay first removes an
earlier run's outputs from the folder; on any error it removes what it wrote, so the
folder holds a complete set of outputs or none.
"""

from __future__ import annotations

import json
import time
from pathlib import Path

from frictex.app.engine.clocks import VirtualClock
from frictex.app.engine.driver import PipelineStage, RunTimer, drive, force_reports_of
from frictex.app.engine.sinks import (FRICTION_COLUMNS, FrameSink, LinkSink, ProgressSink, TableSink,
                              command_columns)
from frictex.app.engine.sources import MAX_GAP_S, TraceSource
from frictex.app.engine.summary import Totals, finite_json, summary, timings
from frictex.app.engine.tables import FORMATS, check_room, load_writer, row_bytes
from frictex.rendering.input.trace_file import Trace, iter_trace, most_touching
from frictex.rendering.pipeline import build_pipeline
from frictex.textures.model import Scene

OUTPUT_STEMS = ("commands", "friction")
#: finger-samples per pipeline call by default (blocks x block size x fingers touching):
#: measured on the composed scene, 10-min trace, idle machine: compute 0.52 s at 10,000,
#: 0.37 s at 50,000, 0.67 s at 200,000 (per-call overhead against the cache)
CHUNK_SAMPLES = 50_000
#: blocks the link may hold for the device when the friction loop is on: the host stays
#: this close to the device's play position, so a block's force report comes back a
#: few blocks after it is computed (``rendering.control.loop``'s ``max_wait_s``)
LOOP_QUEUE_BLOCKS = 2


def load_inputs(scene, trace, strict: bool = False):
    """(Scene, iterator of trace chunks, trace path or None) from objects, paths or names.

    A trace file's iterator (``rendering.input.trace_file.TraceReader``) counts, in its
    ``order``, the samples it sorted or dropped where time went back; ``strict`` refuses
    such a trace instead.
    """
    if not isinstance(scene, Scene):
        from frictex.textures.library import resolve_scene
        from frictex.textures.loader import load_scene
        scene = load_scene(resolve_scene(scene))
    if isinstance(trace, Trace):
        return scene, iter([trace]), None
    from frictex.textures.library import resolve_trace
    trace_path = resolve_trace(trace)
    return scene, iter_trace(trace_path, strict=strict), trace_path


def clear_outputs(out_dir: Path) -> None:
    """Remove an earlier run's outputs (any format) and summary from ``out_dir``."""
    for stem in OUTPUT_STEMS:
        for fmt in FORMATS:
            (out_dir / f"{stem}.{fmt}").unlink(missing_ok=True)
    (out_dir / "summary.json").unlink(missing_ok=True)


def run_replay(scene, trace, out_dir, rate_hz: float = 10_000.0, fmt: str = "csv", sink=None,
               device: str | None = None, block_size: int = 50, render_override: str | None = None,
               chunk_blocks: int | None = None, progress: bool = True, frames=None, strict: bool = False,
               faults=None, max_gap_s: float = MAX_GAP_S, control: str | None = None,
               sim_args: tuple[str, ...] = ()) -> dict:
    """Replay ``trace`` (Trace or path/bundled name) on ``scene`` (Scene or path/name).

    Writes the outputs into ``out_dir`` (created if needed) and returns the summary
    (also written as ``summary.json``). ``sink``: an optional device link
    (``device.link.host.open_sink(..., paced=True)``) that receives every block and, by
    waiting for the device's room, paces the run; the replay closes it (draining first) before writing the summary, so its
    counters are final. ``device``: instead of a link, a spec (``"sim"``, a port or a
    pyserial URL) opened here with the channels and phases of the scene's actuation,
    with ``faults`` (``device.link.faults.FaultPlan``) injected if given. ``frames``: an
    optional ``app.engine.frames.FrameWriter``. ``strict``: refuse a trace whose time
    goes back (else sorted or dropped, counted and warned about). ``max_gap_s``: a longer
    gap between touch samples is a lift, and its silence is skipped
    (``app.engine.sources``). ``control``: the friction loop's mode (open, closed,
    adaptive) instead of the scene file's; with the loop on, one block per pipeline call
    (the loop acts once a block) and, streaming to a device, the link's queue kept to
    :data:`LOOP_QUEUE_BLOCKS` so that the device's force reports come back within the
    loop's wait (``rendering.control.loop``); the summary gets a ``control`` section.
    A ``sink`` passed in must then be a link (``device.link.host.CommandSink``).
    ``sim_args``: more ``frictex sim-device`` flags for ``device="sim"`` (e.g. a
    simulated finger's force reports: ``("--finger", "3")``).
    """
    wall0 = time.perf_counter()
    timer = RunTimer()
    scene, chunks, trace_path = load_inputs(scene, trace, strict)
    load_writer(fmt)
    source = TraceSource(chunks, max_gap_s=max_gap_s)
    read0 = time.perf_counter()
    t0 = source.first_time()
    timer.seconds["read"] += time.perf_counter() - read0
    out_dir = Path(out_dir)
    out_dir.mkdir(parents=True, exist_ok=True)
    clear_outputs(out_dir)
    build0 = time.perf_counter()
    pipeline = build_pipeline(scene, rate_hz=rate_hz, block_size=block_size,
                              render_override=render_override, t0_s=t0, control=control)
    setup_s = read0 - wall0 + time.perf_counter() - build0  # scene and kernels loaded
    looped = pipeline.control is not None
    if device is not None:
        from frictex.device.link.host import open_sink
        sink = open_sink(device, channels=len(pipeline.channels), rate_hz=rate_hz,
                         phases=pipeline.actuation.has_phases, paced=True, faults=faults,
                         sim_args=tuple(sim_args),
                         **({"queue_blocks": LOOP_QUEUE_BLOCKS} if looped else {}))
    elif sim_args:
        raise ValueError("sim_args are for a simulated device (device 'sim')")
    read0 = time.perf_counter()
    source.start(pipeline.tracker_config)
    timer.seconds["read"] += time.perf_counter() - read0
    if source.ended:  # the whole trace is read: the outputs' size is known before writing
        _check_outputs_fit(out_dir, source, pipeline, fmt)
    totals = Totals()
    sinks = [totals]
    if sink is not None:  # a paced link: its send waits (bounded) for the device's room
        sinks.append(LinkSink(sink, block_size))
    if frames is not None:
        sinks.append(FrameSink(frames))
    if progress and _long(source):
        sinks.append(ProgressSink(rate_hz))
    # last: its files become final only once the link has drained and the frames are out
    tables = TableSink(out_dir, pipeline.channels, pipeline.actuation.has_phases, fmt)
    sinks.append(tables)
    if looped:
        chunk_blocks = 1
    elif chunk_blocks is None:
        fingers = max(1, most_touching(source.pending)) if source.pending is not None else 1
        chunk_blocks = max(1, CHUNK_SAMPLES // (block_size * fingers))
    stage = PipelineStage(pipeline)
    if looped and sink is not None:  # the loop reads the device's forces
        stage = PipelineStage(pipeline, sink.device_force_n, force_reports_of(sink))
    blocks = drive(stage, source, sinks, VirtualClock(), chunk_blocks=chunk_blocks, timer=timer)

    output_s = blocks * block_size / rate_hz
    doc = summary(scene, source.stats.report(trace_path), pipeline, stage.state.tracker, totals,
                  fmt, tables.files, blocks)
    order = getattr(chunks, "order", None)
    if order is not None:
        doc["trace"]["time_order"] = order.as_dict()
        doc["warnings"] += order.warnings()
    if looped:
        doc["control"] = pipeline.control.report(stage.state.control)
        doc["warnings"] += doc["control"]["messages"]
    doc["trace"]["gaps"] = source.gaps.as_dict()
    doc["warnings"] += source.gaps.warnings()
    if sink is not None:
        doc["device"] = sink.status()
        doc["warnings"] += device_warnings(doc["device"])
    doc["timings"] = timings(pipeline, output_s, timer.seconds, time.perf_counter() - wall0,
                             setup_s)
    text = json.dumps(finite_json(doc), indent=2, allow_nan=False) + "\n"
    (out_dir / "summary.json").write_text(text, encoding="utf-8")
    return doc


def _check_outputs_fit(out_dir: Path, source: TraceSource, pipeline, fmt: str) -> None:
    """Refuse, before writing anything, outputs that would not fit the disk."""
    trace = source.pending
    output_s = trace.duration_s - source.gaps.skipped_s + 2 * pipeline.block_size / pipeline.rate_hz
    samples = output_s * pipeline.rate_hz
    fingers = max(1, most_touching(trace))
    need = samples * (row_bytes(command_columns(pipeline.channels, pipeline.actuation.has_phases), fmt)
                      + fingers * row_bytes(FRICTION_COLUMNS, fmt))
    check_room(out_dir, need, f"the outputs ({output_s:.6g} s at {pipeline.rate_hz:g} Hz, "
                              f"up to {fingers} fingers, {fmt})")


def device_warnings(status: dict) -> list[str]:
    """What the device never played, by cause (``device.link.host.CommandSink.status``)."""
    commanded, unplayed = status.get("commanded_samples", 0), status.get("unplayed_samples", 0)
    if not unplayed:
        return []
    causes = ", ".join(f"{n} {cause.replace('_', ' ')}"
                       for cause, n in status.get("unplayed_by_cause", {}).items() if n)
    return [f"{unplayed} of {commanded} commanded samples ({unplayed / commanded:.2%}) were "
            f"never played by the device ({causes})"]


def _long(source: TraceSource) -> bool:
    """Worth a progress bar: the trace's first chunk spans 30 s or more, or is not all of it."""
    return float(source.pending.t_s[-1] - source.pending.t_s[0]) >= 30.0 or not source.ended
