"""Headless replay: a scene and a trace through the pipeline, on a virtual clock (or the
one ``ReplayOptions.clock`` names: ``wall`` paces it in real time).

The output clock starts at the trace's first sample (t_s of output sample k is
t0 + k / rate) and runs until the block after the last sample. t_s is float64: a run
whose largest output time has a spacing over a step (1e10 s at 1 MHz), where t_s would
repeat, is refused, one past 1 % of a step (a Unix-time start at 1 MHz: 24 %) warned. The trace is read and
the outputs written in chunks, so memory stays bounded however long the trace (an hour
at 10 kHz is 36 million command rows). Each pipeline call runs ``chunk_blocks`` blocks
(by default about :data:`CHUNK_SAMPLES` finger-samples: fewer calls, arrays that still fit
the cache), but a touch sample still takes effect at the block boundary after it, so the
result equals a live run block by block: bit for bit with SHO and SHT; with the hybrid,
whose slew toward the measured phase starts again from its carried state at each call,
to rounding (on grating-5mm's 40 mm/s swipe, 3 to 6 of 20,050 samples lie within that
of a square edge and fall on its other side between one block per call and the
default). Two replays of the same inputs are byte-identical (``summary.json`` aside,
whose ``timings`` differ).

Outputs (DESIGN.md): ``commands.<fmt>`` (t_s, one column per channel in um, phases where
the actuation has them), ``friction.<fmt>`` (one row per touching finger and output
sample: t_s, finger, x_mm, y_mm, mu_target, amplitude_um; on a travelling-wave scene
also the force wanted and given, ``app.engine.sinks.FORCE_COLUMNS``), ``summary.json`` (written
last), ``frames/`` with ``--frames``. ``fmt``: csv, npz or parquet (``app.engine.tables``),
or ``memory``: no folder, the two tables kept as pyarrow Tables (``frictex.replay``).

Atomic runs: everything is written into a staging folder beside the output folder and
swapped in when the run commits (``app.engine.staging``): until then the previous run's
outputs stay as they were, whatever ends the run; a run refused before writing (disk
room, an output folder it cannot replace) touches nothing.
"""

from __future__ import annotations

import json
import math
import os
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Any

import numpy as np

from frictex.app.engine.clocks import ClockRequest, DeadlineStats, build_clock, clock_name
from frictex.app.engine.device_changes import device_warnings
from frictex.app.engine.driver import (PipelineStage, RunTimer, deferred_interrupts, drive,
                                       force_reports_of)
from frictex.app.engine.sinks import (SinkRequest, ThreadedSink, build_sink, command_columns,
                                      friction_columns, names_built)
from frictex.app.engine.sources import MAX_GAP_S, TraceSource
from frictex.app.engine.staging import Staging
from frictex.app.engine.summary import Totals, finite_json, summary, timings
from frictex.app.engine.tables import (MEMORY, SMALLER_FORMAT, WRITE_ELSEWHERE, check_memory,
                                       check_room, has_room, load_writer, room_hint,
                                       row_bytes)
from frictex.device.errors import DeviceError, InputError
from frictex.rendering.input.trace_file import MOVE, UP, Trace, iter_trace, most_touching
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.renderers import from_velocity
from frictex.textures.model import Scene

#: finger-samples per pipeline call by default (blocks x block size x fingers touching):
#: measured on the composed scene, 10-min trace, idle machine: compute 0.52 s at 10,000,
#: 0.37 s at 50,000, 0.67 s at 200,000 (per-call overhead against the cache)
CHUNK_SAMPLES = 50_000
#: blocks the link may hold for the device when the friction loop is on: the host stays
#: this close to the device's play position, so a block's force report comes back a
#: few blocks after it is computed (``rendering.control.loop``'s ``max_wait_s``)
LOOP_QUEUE_BLOCKS = 2
#: streaming to a device: the largest share of the commanded samples that may never play
#: before the run fails (``frictex replay --max-unplayed``, ``frictex.replay``'s
#: ``max_unplayed``)
MAX_UNPLAYED = 0.01


@dataclass(frozen=True, kw_only=True)
class ReplayOptions:
    """How a replay runs (the ``frictex replay`` options).

    Attributes
    ----------
    rate_hz : float
        Output sample rate (Hz).
    fmt : str
        Table format: csv, npz, parquet, or ``memory`` (no output folder).
    block_size : int or None
        Output samples per block; touch samples take effect at block boundaries. None:
        5 ms of samples (``rendering.pipeline.default_block_size``).
    render_override : str or None
        Render every periodic layer this way instead of as its file says.
    chunk_blocks : int or None
        Blocks per pipeline call (None: about :data:`CHUNK_SAMPLES` finger-samples).
    progress : bool
        A progress bar on stderr for long traces.
    strict : bool
        Refuse a trace whose time goes back (else sorted or dropped, counted, warned).
    device : str or None
        Stream the commands to a device: ``"sim"``, a port or a pyserial URL, opened with
        the channels and phases of the scene's actuation.
    faults : device.link.faults.FaultPlan or None
        Faults injected into that device's link.
    sim_args : tuple of str
        More ``frictex sim-device`` flags for ``device="sim"``.
    max_gap_s : float
        A longer gap between touch samples (s) is a lift, and its silence is skipped.
    control : str or None
        The friction loop's mode (open, closed, adaptive) instead of the scene file's.
        With the loop on, one block per pipeline call and, streaming to a device, the
        link's queue kept to :data:`LOOP_QUEUE_BLOCKS`.
    sinks : tuple of str or Sink
        More sinks fed every block besides the run's own (``app.engine.sinks``):
        ``NAME[:ARG]`` of :data:`~frictex.app.engine.sinks.SINKS`, built for the run, or
        sink objects, used as they are; committed before the tables, so a sink that fails
        leaves no outputs. The sinks the run builds itself (``tables``, ``link``,
        ``frames``, ``progress`` where it shows one) are refused.
    clock : str or Clock
        What paces the run, ``NAME[:ARG]`` of :data:`~frictex.app.engine.clocks.CLOCKS`:
        ``virtual`` (the default: as fast as it computes), ``wall`` (real time),
        ``device`` (the output device's room), a plugin's; or a clock object (``wait(k)``
        and ``finished(k, n)``), used as it is. With any but ``virtual``, one block per
        pipeline call (unless ``chunk_blocks`` says otherwise), as live.
    """

    rate_hz: float = 10_000.0
    fmt: str = "csv"
    block_size: int | None = None
    render_override: str | None = None
    chunk_blocks: int | None = None
    progress: bool = True
    strict: bool = False
    device: str | None = None
    faults: Any = None
    sim_args: tuple[str, ...] = ()
    max_gap_s: float = MAX_GAP_S
    control: str | None = None
    sinks: tuple[Any, ...] = ()
    clock: Any = "virtual"


@dataclass(frozen=True)
class ReplayResult:
    """What :func:`replay_with` returns.

    Attributes
    ----------
    summary : dict
        The summary document (``summary.json`` before non-finite numbers become null).
    tables : dict of str to pyarrow.Table, or None
        ``commands`` and ``friction`` when kept in memory (``fmt`` ``memory``); else None.
    summary_id : tuple of int, or None
        The written ``summary.json``'s (device, inode, size, mtime in ns), which tell
        this run's folder from a later run's; None without a folder.
    """

    summary: dict[str, Any]
    tables: dict[str, Any] | None
    summary_id: tuple[int, int, int, int] | None = None


def load_inputs(scene, trace, strict: bool = False):
    """(Scene, iterator of trace chunks, trace path or None, the scene file's warnings)
    from objects, paths or names.

    A trace file's iterator (``rendering.input.trace_file.TraceReader``) counts, in its
    ``order``, the samples it sorted or dropped where time went back; ``strict`` refuses
    such a trace instead. The warnings (strings) are those ``frictex validate`` gives the
    scene's file (none for a Scene object).
    """
    warnings = []
    if not isinstance(scene, Scene):
        from frictex.textures.library import resolve_scene
        from frictex.textures.loader import read_scene
        scene, warned = read_scene(resolve_scene(scene))
        warnings = [str(w) for w in warned]
    if isinstance(trace, Trace):
        return scene, iter([trace]), None, warnings
    from frictex.textures.library import resolve_trace
    trace_path = resolve_trace(trace)
    return scene, iter_trace(trace_path, strict=strict), trace_path, warnings


def run_replay(scene, trace, out_dir, *, sink=None, frames=None, **options) -> dict[str, Any]:
    """:func:`replay_with` for keyword options (the fields of :class:`ReplayOptions`);
    returns the summary document."""
    return replay_with(scene, trace, out_dir, ReplayOptions(**options), sink=sink,
                       frames=frames).summary


def replay_with(scene, trace, out_dir: str | Path | None, options: ReplayOptions, *,
                sink=None, frames=None) -> ReplayResult:
    """Replay ``trace`` (Trace or path/bundled name) on ``scene`` (Scene or path/name).

    Writes the outputs into ``out_dir`` (created if needed; staged and swapped in whole,
    see the module docstring), or keeps the tables in memory when ``out_dir`` is None
    (``options.fmt`` then :data:`~frictex.app.engine.tables.MEMORY`). ``sink``: an
    optional device link (``device.link.host.open_sink(..., paced=True)``) that receives
    every block and, by waiting for the device's room, paces the run; the replay closes it
    (draining first) before writing the summary, so its counters are final; with the
    friction loop on it must be a ``device.link.host.CommandSink``. ``frames``: an optional
    ``app.engine.frames.FrameWriter`` (its frames are staged with the tables). Ctrl-C is
    held while kernels run and ends the run between blocks (``KeyboardInterrupt``); one
    that comes once the outputs are being swapped into ``out_dir`` is held and dropped:
    the run completes and returns.
    """
    if (out_dir is None) != (options.fmt == MEMORY):
        raise InputError(f"output format {options.fmt!r}: tables in memory need no output "
                         "folder, files need one")
    if frames is not None and out_dir is None:
        raise InputError("frames are written into an output folder: give one")
    with deferred_interrupts() as check:
        return _replay(scene, trace, out_dir, options, sink, frames, check)


def _replay(scene, trace, out_dir, options: ReplayOptions, sink, frames, check) -> ReplayResult:
    wall0 = time.perf_counter()
    timer = RunTimer()
    scene, chunks, trace_path, scene_warnings = load_inputs(scene, trace, options.strict)
    inputs_s = time.perf_counter() - wall0
    write0 = time.perf_counter()
    load_writer(options.fmt)  # the format's library: part of writing, not of start-up
    timer.seconds["write"] += time.perf_counter() - write0
    read0 = time.perf_counter()
    slides = SlideSteps()
    source = TraceSource(slides.watch(chunks), max_gap_s=options.max_gap_s)
    t0 = source.first_time()
    timer.seconds["read"] += time.perf_counter() - read0
    staging = None if out_dir is None else Staging(out_dir)
    if staging is not None:
        staging.check(inputs=(trace_path, scene.source))
    build0 = time.perf_counter()
    pipeline = build_pipeline(scene, rate_hz=options.rate_hz, block_size=options.block_size,
                              render_override=options.render_override, t0_s=t0,
                              control=options.control)
    setup_s = inputs_s + time.perf_counter() - build0  # scene and kernels loaded
    looped = pipeline.control is not None
    if looped and options.device is None and sink is None:
        raise InputError(f"control {pipeline.control.mode!r} reads the force reports of a "
                         "device, and no device was given: stream to one with a lateral force "
                         "sensor (--device sim:finger=SEED, device=\"sim:finger=SEED\", "
                         "simulates a finger), or use --control open, control=\"open\"")
    read0 = time.perf_counter()
    source.start(pipeline.tracker_config)
    timer.seconds["read"] += time.perf_counter() - read0
    _check_time_resolution(_largest_time_known(source, pipeline), options.rate_hz, t0)
    if staging is not None and source.ended:  # the outputs' size is known before writing
        _check_outputs_fit(staging.out, source, pipeline, options.fmt, frames)
    if options.fmt == MEMORY and source.ended:
        _check_tables_fit_memory(source, pipeline)
    if options.sim_args and options.device is None:
        raise InputError("sim_args are for a simulated device (device 'sim')")
    _check_attached(options, sink, frames, source)
    check()
    folder = summary_id = None
    try:
        if staging is not None:
            folder = staging.begin()
        if options.device is not None:
            from frictex.device.link.host import open_sink
            sink = open_sink(options.device, channels=len(pipeline.channels),
                             rate_hz=options.rate_hz, phases=pipeline.actuation.has_phases,
                             paced=True, faults=options.faults, sim_args=tuple(options.sim_args),
                             profile=scene.device.profile,
                             **({"queue_blocks": LOOP_QUEUE_BLOCKS} if looped else {}))
            if looped and not sink.info.has_force_reports:
                getattr(sink, "abort", sink.close)()
                raise DeviceError(f"{sink.label} sends no force reports (it announces no "
                                  f"lateral force sensor, PROTOCOL.md 4.9), so control "
                                  f"{pipeline.control.mode!r} has nothing to measure: use a "
                                  "device with one (--device sim:finger=SEED, "
                                  "device=\"sim:finger=SEED\", simulates a finger), or "
                                  "--control open, control=\"open\"")
        if frames is not None:
            frames.into(folder)
        doc, tables = _run(pipeline, source, chunks, trace_path, scene, folder, options, sink,
                           frames, timer, check)
        doc["warnings"] += sparse_touch_warnings(slides.median_s(), pipeline)
        doc["warnings"][:0] = scene_warnings
        output_s = doc["output"]["duration_s"]
        doc["timings"] = timings(pipeline, output_s, timer.seconds,
                                 time.perf_counter() - wall0, setup_s)
        if staging is not None:
            if staging.removed:
                doc["warnings"].append(f"removed the leftovers of killed runs beside "
                                       f"{staging.out.name}: " + ", ".join(staging.removed))
            text = json.dumps(finite_json(doc), indent=2, allow_nan=False) + "\n"
            summary_id = file_id(staging.write_text("summary.json", text))  # the swap keeps it
            with check.committing():  # held through the swap: then the run is complete
                staging.commit()
    except BaseException:
        check.end()
        if staging is not None:
            staging.abort()
        raise
    return ReplayResult(doc, tables, summary_id)


def file_id(path: Path) -> tuple[int, int, int, int]:
    """(device, inode, size, mtime in ns) of ``path``: what tells one written file from
    another written later at the same path."""
    st = os.stat(path)
    return st.st_dev, st.st_ino, st.st_size, st.st_mtime_ns


def _run(pipeline, source, chunks, trace_path, scene, folder, options: ReplayOptions, sink,
         frames, timer, check):
    """The block loop into the sinks; the summary document (without ``timings``) and the
    tables kept in memory (or None)."""
    looped = pipeline.control is not None
    totals = Totals()
    sinks = [totals]
    try:
        link, tables = _build_sinks(sinks, pipeline, source, folder, options, sink, frames)
        block_s = pipeline.block_size / options.rate_hz
        clock = build_clock(options.clock, ClockRequest(block_s, block_s, sink))
    except BaseException:  # a sink or clock that cannot be built: the sinks built are aborted
        for built in reversed(sinks[1:]):
            built.abort()
        raise
    chunk_blocks = options.chunk_blocks
    if looped or (options.clock != "virtual" and chunk_blocks is None):
        chunk_blocks = 1
    elif chunk_blocks is None:
        fingers = max(1, most_touching(source.pending)) if source.pending is not None else 1
        chunk_blocks = max(1, CHUNK_SAMPLES // (pipeline.block_size * fingers))
    stage = PipelineStage(pipeline)
    if looped and sink is not None:  # the loop reads the device's forces
        stage = PipelineStage(pipeline, sink.device_force_n, force_reports_of(sink))
    try:
        blocks = drive(stage, source, sinks, clock, chunk_blocks=chunk_blocks,
                       timer=timer, check=check)
    except OSError as exc:
        if link is None:
            raise
        from frictex.device.link.session import LinkStalled  # loaded with the link
        if not isinstance(exc, LinkStalled):
            raise
        raise _stopped(exc, link.handed / options.rate_hz, source) from exc

    # a streamed trace's last time was not known before the run
    _check_time_resolution(totals.largest_time_s, options.rate_hz, source.stats.first_t)
    doc = summary(scene, source.report(trace_path), pipeline, stage.state.tracker, totals,
                  options.fmt, tables.files, blocks)
    doc["warnings"] += _time_resolution_warnings(totals.largest_time_s, options.rate_hz)
    order = getattr(chunks, "order", None)
    if order is not None:
        doc["trace"]["time_order"] = order.as_dict()
        doc["warnings"] += chunks.warnings()
    if sink is not None:  # friction constants calibrated on another device or finger
        from frictex.device.calibration_identity import mismatch, simulated_finger
        # a package's device may declare no Info, a caller's sink (sink=) no info at all
        name = getattr(getattr(sink, "info", None), "name", "")
        said = mismatch(scene.device.fitted, name,
                        simulated_finger(options.device, options.sim_args))
        doc["warnings"] += [said] if said else []
    # a looped run's control report compares the force used with the device's, and says so
    doc["warnings"] += source.stats.warnings(pressing=not looped)
    if looped:
        doc["control"] = pipeline.control.report(stage.state.control,
                                                 late_hint=_late_reports_hint(options.clock))
        doc["warnings"] += doc["control"]["messages"]
    doc["warnings"] += _dropped_warnings(sinks)
    doc["trace"]["gaps"] = source.gaps.as_dict()
    doc["warnings"] += source.gaps.warnings()
    late = getattr(clock, "stats", None)
    if isinstance(late, DeadlineStats) and late.misses:
        doc["warnings"].append(f"clock {options.clock!r}: {late.misses} pipeline calls "
                               f"reached the sinks late (the worst "
                               f"{late.worst_lateness_s * 1e3:.1f} ms past its end)")
    if sink is not None:
        doc["device"] = sink.status()
        doc["warnings"] += device_warnings(doc["device"], doc["counts"]["max_amplitude_um"])
    in_memory = None
    if options.fmt == MEMORY:
        in_memory = {"commands": tables.commands.table, "friction": tables.friction.table}
    return doc, in_memory


class SlideSteps:
    """The intervals (s) between a finger's touch samples while it slides (a move to
    another position than its sample before, in the same touch), over the first
    ``MAX_STEPS`` of them, gathered from the trace's chunks as the run reads them."""

    MAX_STEPS = 100_000  # as TraceStats: the median over the first steps

    def __init__(self):
        self.steps: list[np.ndarray] = []
        self.n_steps = 0
        self._last: dict[int, tuple[float, float, float]] = {}  # touching finger -> (t, x, y)

    def watch(self, chunks):
        """``chunks`` (iterator of Trace) unchanged, each one added as it is read."""
        for chunk in chunks:
            self.add(chunk)
            yield chunk

    def add(self, chunk: Trace) -> None:
        ids = np.array(list(self._last), dtype=np.int64)
        held = np.array(list(self._last.values()), dtype=np.float64).reshape(-1, 3)
        finger = np.concatenate((ids, chunk.finger))
        order = np.argsort(finger, kind="stable")  # each finger's samples, the held one first
        finger = finger[order]
        t, x, y = (np.concatenate((held[:, k], column))[order]
                   for k, column in enumerate((chunk.t_s, chunk.x_mm, chunk.y_mm)))
        event = np.concatenate((np.full(ids.size, MOVE, dtype=np.int8), chunk.event))[order]
        slide = ((finger[1:] == finger[:-1]) & (event[:-1] != UP) & (event[1:] == MOVE)
                 & ((x[1:] != x[:-1]) | (y[1:] != y[:-1])))
        steps = np.diff(t)[slide]
        steps = steps[steps > 0][: max(self.MAX_STEPS - self.n_steps, 0)]
        self.steps.append(steps)
        self.n_steps += steps.size
        for i in np.flatnonzero(np.append(finger[1:] != finger[:-1], True)).tolist():
            if event[i] == UP:
                self._last.pop(int(finger[i]), None)
            else:
                self._last[int(finger[i])] = (float(t[i]), float(x[i]), float(y[i]))

    def median_s(self) -> float | None:
        """The median interval (s), None where no finger slid."""
        return float(np.median(np.concatenate(self.steps))) if self.n_steps else None


def sparse_touch_warnings(step_s: float | None, pipeline) -> list[str]:
    """The sentence for a sliding finger sampled (median interval ``step_s``, s) more
    sparsely than the tracker's prediction horizon, on a scene with layers that
    renderers playing from velocity render (``rendering.renderers.from_velocity``): past the horizon the tracker takes the finger as
    resting (velocity 0) until its next sample, and samples more than ``max_gap_s`` apart
    give it no velocity at all (``rendering.tracking.tracks``), so those layers play no
    texture there, where SHO plays the texture under each sample."""
    config = pipeline.tracker_config
    horizon, gap = config.predict_horizon_s, config.max_gap_s
    if step_s is None or step_s <= horizon:
        return []
    layers = [f"{layer.name!r} ({mode})" for layer, mode in
              zip(pipeline.scene.layers, pipeline.layer_modes) if from_velocity(mode)]
    if not layers:
        return []
    plays = "plays" if len(layers) == 1 else "play"
    if step_s > gap:
        none = f"no texture at all: samples more than {gap:g} s apart give a finger no velocity"
    else:
        none = (f"no texture from {horizon:g} s after each sample until the next (the finger "
                "is then taken as resting)")
    return [f"the touch samples of a sliding finger are {step_s:.3g} s apart (median), more "
            f"than the tracker's {horizon:g} s prediction horizon (its velocity window "
            f"{config.velocity_window_s:g} s): layer{'s' if len(layers) > 1 else ''} "
            f"{', '.join(layers)} {plays} {none}; replay with --renderer sho "
            f"(render_override=\"sho\"), or record at least {math.ceil(1 / horizon)} touch "
            "samples a second"]


def _dropped_warnings(sinks: list) -> list[str]:
    """A sentence per threaded sink that dropped calls: one a caller attached built not to
    wait (``ThreadedSink(inner, n)``, the live loop's kind); the run's ``threaded:`` wait."""
    said = [sink.dropped_warning() for sink in sinks if isinstance(sink, ThreadedSink)]
    return [sentence for sentence in said if sentence]


def _late_reports_hint(clock: str) -> str:
    """What to do when the loop's force reports come back late (appended to its line
    saying so): under the virtual clock the host computes as far ahead of the plate as
    the device's buffer lets the link send (31 % of the reports missed, all 5 blocks late,
    on grating-15mm with ``--device sim --block 100``; 1 missed with ``--clock wall``)."""
    if clock == "virtual":
        return ("; the virtual clock runs the host ahead of the plate as far as the "
                "device's buffer allows: --clock wall paces it to the plate (or give the "
                "device a smaller buffer)")
    return "; the device sends them back late or holds many blocks queued (a smaller buffer)"


def _build_sinks(sinks: list, pipeline, source: TraceSource, folder, options: ReplayOptions,
                 device, frames):
    """Append the run's sinks to ``sinks``, built by name (``app.engine.sinks.SINKS``): the
    device's link, the frames, the progress bar, the sinks attached, the tables last (its
    files become final only once the link has drained, the frames are out and the sinks
    attached have committed). Returns the link's sink (or None) and the tables'."""
    request = SinkRequest(tuple(pipeline.channels), pipeline.actuation.has_phases,
                          options.rate_hz, pipeline.block_size, folder, options.fmt, device,
                          frames, forces=pipeline.forces is not None)
    link = None
    if device is not None:  # a paced link: its send waits (bounded) for the device's room
        link = build_sink("link", request)
        sinks.append(link)
    if frames is not None:
        sinks.append(build_sink("frames", request))
    if options.progress and _long(source):
        sinks.append(build_sink("progress", request))
    sinks += [build_sink(s, request) if isinstance(s, str) else s for s in options.sinks]
    tables = build_sink("tables", request)
    sinks.append(tables)
    return link, tables


def _check_attached(options: ReplayOptions, link, frames, source: TraceSource) -> None:
    """Refuse, before anything is written, a clock or an attached sink of an unknown name
    (``UnknownName`` lists the known), and an attached sink the run builds itself."""
    clock_name(options.clock)
    built = {"tables": "its tables",
             "link": (link is not None or options.device is not None) and "with a device",
             "frames": frames is not None and "with frames",
             "progress": options.progress and _long(source) and "a long trace's"}
    for spec in options.sinks:
        if not isinstance(spec, str):
            continue
        for name in names_built(spec):
            if built.get(name):
                raise InputError(f"sink {spec!r}: the run builds its own {name!r} sink "
                                 f"({built[name]}); a sink is attached once")


def _stopped(exc, done_s: float, source: TraceSource):
    """The link's give-up (``LinkStalled``, its ``progress`` kept) with where the replay
    stopped: ``done_s`` of output handed to the link, of the trace's duration when the
    whole trace has been read; the rest was never commanded."""
    said = f"{exc}; the replay stopped after {done_s:.2f} s of output"
    stats = source.stats
    if source.ended and stats.last_t is not None:
        total_s = stats.last_t - stats.first_t
        said += (f" of the {total_s:.2f} s trace (the last {max(total_s - done_s, 0.0):.2f} s "
                 "never commanded)")
    return type(exc)(said, exc.progress)


def _largest_time_known(source: TraceSource, pipeline) -> float:
    """The largest |t_s| (s) of the output known before the run: from the trace's first
    sample to two blocks past the last one read (all of it unless streamed)."""
    t = source.pending.t_s
    return max(abs(float(t[0])), abs(float(t[-1])) + 2 * pipeline.block_size / pipeline.rate_hz)


def _time_spacing(largest_s: float) -> float:
    """float64's spacing (s) at output time ``largest_s``: each t_s is rounded to within
    half of it, so a step between two rows may be off by up to all of it."""
    return float(np.spacing(largest_s))


def _check_time_resolution(largest_s: float, rate_hz: float, t0_s: float) -> None:
    """Refuse output times whose float64 spacing passes the output step: t_s would repeat
    (up to a step, each rounded t0 + k / rate still passes the one before)."""
    spacing = _time_spacing(largest_s)
    if spacing > 1.0 / rate_hz:
        raise InputError(f"t_s could not increase: output times near {largest_s:.10g} s are "
                         f"held to {spacing:.3g} s, more than the output step "
                         f"{1 / rate_hz:.3g} s at {rate_hz:g} Hz; shift the trace's times "
                         f"(subtract its start, {t0_s:.10g} s) or lower --rate")


def _time_resolution_warnings(largest_s: float, rate_hz: float) -> list[str]:
    """The sentence for output times whose float64 spacing passes 1 % of the step."""
    spacing = _time_spacing(largest_s)
    if spacing <= 0.01 / rate_hz:
        return []
    return [f"output times near {largest_s:.10g} s are held to {spacing:.3g} s, "
            f"{100 * spacing * rate_hz:.1f} % of the output step {1 / rate_hz:.3g} s: a step "
            "of t_s may be off by up to that; shift the trace's times (subtract its start) "
            "to keep them exact"]


def _check_outputs_fit(out_dir: Path, source: TraceSource, pipeline, fmt: str, frames) -> None:
    """Refuse, before writing anything, outputs that would not fit the disk (frames
    counted): checked on the folder that will hold the staging folder."""
    output_s, need, what = _tables_size(source, pipeline, fmt)
    what = f"the outputs ({what}, {fmt}"
    frames_need = 0.0
    if frames is not None:
        frames_need = frames.frames_bytes(output_s)
        what += f", frames at {frames.fps:g} fps"
    folder = _existing(out_dir)
    hint = room_hint(fmt)
    if hint == SMALLER_FORMAT and not has_room(folder, need + frames_need):
        parquet_need = _tables_size(source, pipeline, "parquet")[1] + frames_need
        hint = hint if has_room(folder, parquet_need) else WRITE_ELSEWHERE
    check_room(folder, need + frames_need, what + ")", hint)


def _check_tables_fit_memory(source: TraceSource, pipeline) -> None:
    """Refuse, before computing anything, tables kept in memory that would not fit it
    (``tables.check_memory``): their values at 8 bytes, twice, as joining the chunks
    into a table holds both at once (``tables.MemoryTable.commit``)."""
    _, need, what = _tables_size(source, pipeline, MEMORY)
    check_memory(2 * need, f"the tables kept in memory ({what})",
                 "write them into a folder instead, a chunk at a time (replay(out=...))")


def _tables_size(source: TraceSource, pipeline, fmt: str) -> tuple[float, float, str]:
    """The output's duration (s) of the trace read whole (``source.pending``), the
    bytes of its two tables in ``fmt`` (up to ``tables.row_bytes`` a row), and the words
    saying how much output that is."""
    trace = source.pending
    output_s = trace.duration_s - source.gaps.skipped_s + 2 * pipeline.block_size / pipeline.rate_hz
    samples = output_s * pipeline.rate_hz
    fingers = max(1, most_touching(trace))
    need = samples * (row_bytes(command_columns(pipeline.channels, pipeline.actuation.has_phases), fmt)
                      + fingers * row_bytes(friction_columns(pipeline.forces is not None), fmt))
    said = "one finger" if fingers == 1 else f"up to {fingers} fingers"
    return output_s, need, f"{output_s:.6g} s at {pipeline.rate_hz:g} Hz, {said}"


def _existing(path: Path) -> Path:
    """``path`` or its nearest existing parent (whose file system it will be on)."""
    while not path.exists() and path.parent != path:
        path = path.parent
    return path


def _long(source: TraceSource) -> bool:
    """Worth a progress bar: the trace's first chunk spans 30 s or more, or is not all of it."""
    return float(source.pending.t_s[-1] - source.pending.t_s[0]) >= 30.0 or not source.ended
