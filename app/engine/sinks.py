"""Where a run's output goes: tables, a device link, PNG frames, the window's scope.

A sink takes every pipeline call's output and the channel commands actually sent
(``write(out, commands_um)``: ``out`` a ``rendering.pipeline.BlockOutput``, commands
(n, channels) um), then either ``commit()`` (the run finished: make the result final)
or ``abort()`` (the run failed: leave nothing that looks complete). The driver calls
them; a sink never calls another.

The :class:`Sink` protocol is an extension point: :data:`SINKS` holds the sinks' factories
by name (``tables``, ``link``, ``frames``, ``memory``, ``progress``, ``threaded``), and
another package adds one under entry-point group ``frictex.sinks``::

    [project.entry-points."frictex.sinks"]
    spy = "mypkg.spy:open_spy"      # open_spy(arg, request) -> a Sink

A factory is called ``factory(arg, request)``: ``arg`` the text after ``NAME:`` of
``--sink NAME[:ARG]`` ("" when none), ``request`` a :class:`SinkRequest` (what the run
makes). :func:`build_sink` builds one; replay builds its own sinks that way too, and
attaches the ones a user names (``frictex replay --sink``, ``frictex.replay(sinks=...)``).
Another package's sink is wrapped (:class:`PluginSink`): what it raises, building,
writing or committing, is a ``PluginError`` naming it (exit 1), and the run's own outputs
are then not written (the driver aborts every sink; replay's are staged).
"""

from __future__ import annotations

import queue
import threading
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Protocol

import numpy as np

from frictex.device.errors import InputError
from frictex.device.registry import (Expect, PluginError, Registry, build_entry, guarded,
                                     warn_once)

from frictex.app.engine.tables import open_table

FRICTION_COLUMNS = [("t_s", np.float64, "%.7f"), ("finger", np.int64, "%d"),
                    ("x_mm", np.float64, "%.4f"), ("y_mm", np.float64, "%.4f"),
                    ("mu_target", np.float64, "%.6f"), ("amplitude_um", np.float64, "%.6f")]
#: the friction table's further columns on a travelling-wave scene (a force stage): the
#: force wanted on the finger, x and y of the display, and the force the wave gives it
#: along x (N; the waves push only along x). There ``mu_target`` is the composed mu' of
#: the friction layers alone; direction-dependent friction and pushes are in the forces.
FORCE_COLUMNS = [("force_x_wanted_n", np.float64, "%.6f"),
                 ("force_y_wanted_n", np.float64, "%.6f"), ("force_x_n", np.float64, "%.6f")]


def friction_columns(forces: bool) -> list[tuple]:
    """``friction`` table columns: :data:`FRICTION_COLUMNS`, then :data:`FORCE_COLUMNS`
    where the scene has a force stage (``forces``)."""
    return FRICTION_COLUMNS + (FORCE_COLUMNS if forces else [])


def command_columns(channels: tuple[str, ...], phases: bool) -> list[tuple]:
    """``commands`` table columns: t_s, one amplitude per channel, phases if any."""
    cols = [("t_s", np.float64, "%.7f")]
    cols += [(f"{ch}_um", np.float64, "%.6f") for ch in channels]
    if phases:
        cols += [(f"{ch}_phase_rad", np.float64, "%.6f") for ch in channels]
    return cols


def friction_rows(out) -> dict[str, np.ndarray]:
    """``friction`` table rows of a block output: sample-major, then finger id, touching
    only; the force columns where ``out`` has forces."""
    names = [name for name, _, _ in friction_columns(out.forces is not None)][1:]
    columns = [out.contact, out.ids_per_sample(), out.x_mm, out.y_mm, out.mu_target,
               out.amplitude_um]
    if out.forces is not None:
        columns += [out.forces.wanted_n[..., 0], out.forces.wanted_n[..., 1],
                    out.forces.achieved_n[..., 0]]
    ids = columns[1]
    if ids.shape[0] > 1 and (np.diff(ids, axis=0) < 0).any():  # reused rows: by id again
        order = np.argsort(ids, axis=0, kind="stable")
        columns = [np.take_along_axis(c, order, axis=0) for c in columns]
    contact, *values = (c.T for c in columns)  # (n, F)
    t = np.broadcast_to(out.t_s[:, None], contact.shape)
    if contact.all():  # every finger down throughout: all rows in order (views for one finger)
        return {"t_s": t.ravel(), **{name: v.ravel() for name, v in zip(names, values)}}
    return {"t_s": t[contact], **{name: v[contact] for name, v in zip(names, values)}}


class Sink(Protocol):
    """Where a run's output goes (see the module docstring).

    ``write`` is called once per pipeline call, in output order, from the run's thread;
    then exactly one of ``commit`` (the run completed) or ``abort`` (it failed or was
    stopped).
    """

    def write(self, out, commands_um: np.ndarray) -> None:
        """Take one pipeline call's output and the commands sent.

        ``out`` is a ``rendering.pipeline.BlockOutput`` of n output samples from output
        sample ``out.index0`` on: ``t_s`` (n,) s on the trace's clock; per finger slot (F, n) ``x_mm``,
        ``y_mm`` (mm), ``contact`` (bool), ``mu_target`` (mu', 0 to 1),
        ``amplitude_um`` (um zero-to-peak under the finger); ``forces`` (a
        ``rendering.layers.force_layers.ForceBlock``) on a travelling-wave scene, else
        None; ``phases_rad`` (n, channels)
        rad or None; ``ids_per_sample()`` the finger ids (F, n). ``commands_um``: (n,
        channels) float64, the amplitude commanded on each actuator channel (um
        zero-to-peak), in the order of :attr:`SinkRequest.channels`. Read them; do not
        change them or keep views of them past the call (copy what you keep)."""

    def commit(self) -> None:
        """The run finished: make the result final."""

    def abort(self) -> None:
        """The run failed: leave nothing that looks complete."""


@dataclass(frozen=True)
class SinkRequest:
    """What a sink is built for: the second argument of a :data:`SINKS` factory.

    Attributes
    ----------
    channels : tuple of str
        The actuator channels: the columns of ``commands_um``, in order.
    phases : bool
        ``out.phases_rad`` (n, channels, rad) comes with the commands.
    rate_hz : float
        Output samples per second (Hz).
    block_size : int
        Output samples per block.
    folder : Path or None
        The run's staging folder: a file written there appears in the output folder only
        when the run completes, swapped in with its tables (use names of your own, never
        ``commands.*``, ``friction.*``, ``summary.json`` or ``frames``); None when the
        tables are kept in memory (``frictex.replay`` without ``out``).
    fmt : str
        The tables' format: csv, npz, parquet or memory.
    link : OutputDevice or None
        The output device the run streams to (the ``link`` sink's), or None.
    frames : FrameWriter or None
        The run's PNG frame writer (the ``frames`` sink's), or None.
    queue_blocks : int
        Calls of ``write`` the ``threaded`` sink queues before its ``write`` waits for room.
    forces : bool
        ``out.forces`` comes with every output (a travelling-wave scene's force stage).
    """

    channels: tuple[str, ...]
    phases: bool = False
    rate_hz: float = 10_000.0
    block_size: int = 50
    folder: Path | None = None
    fmt: str = "csv"
    link: Any = None
    frames: Any = None
    queue_blocks: int = 64
    forces: bool = False


#: ``factory(arg, request) -> Sink``, by name
SINKS: Registry[Any] = Registry("sink", "frictex.sinks",
                                expect=Expect.factory("a factory(arg, request) returning a Sink"))


def sink_name(spec: str) -> tuple[str, str]:
    """NAME and ARG of a ``NAME[:ARG]`` sink spec; NAME registered (else ``UnknownName``
    listing the known)."""
    return SINKS.named(spec, "NAME[:ARG] (a str) or a Sink")


def build_sink(spec: str, request: SinkRequest) -> Sink:
    """The sink ``NAME[:ARG]`` of :data:`SINKS` built for ``request``: frictex's own as its
    factory returns it, another package's checked and wrapped in a :class:`PluginSink`."""
    name, arg = sink_name(spec)
    return build_entry(SINKS, "sink", name, arg, request, doing="building",
                       members=("write()", "commit()", "abort()"),
                       contract="a Sink (frictex.app.engine.sinks.Sink)", wrap=PluginSink)


def names_built(spec: str) -> list[str]:
    """The registered names a sink spec builds: NAME, and the sink ``threaded:NAME[:ARG]``
    runs on its thread."""
    name, arg = sink_name(spec)
    return [name] + (names_built(arg) if name == "threaded" and arg else [])


class PluginSink:
    """Another package's sink (``inner``): what its ``write`` or ``commit`` raises, but
    frictex's own errors, is a ``PluginError`` naming it (``registry.guarded``); what its
    ``abort`` raises is a warning, as the run is failing already with its own error."""

    def __init__(self, inner: Sink, who: str):
        self.inner = inner
        self._who = who

    def write(self, out, commands_um: np.ndarray) -> None:
        guarded(self._who, "writing", self.inner.write, out, commands_um)

    def commit(self) -> None:
        guarded(self._who, "committing", self.inner.commit)

    def abort(self) -> None:
        try:
            guarded(self._who, "aborting", self.inner.abort)
        except PluginError as exc:
            warn_once(str(exc))


class TableSink:
    """``commands.<fmt>`` and ``friction.<fmt>`` in ``out_dir`` (DESIGN.md, replay output),
    or two pyarrow Tables in memory (``fmt`` ``memory``: ``app.engine.tables.MemoryTable``;
    ``files`` stays empty)."""

    def __init__(self, out_dir: Path | None, channels: tuple[str, ...], phases: bool, fmt: str,
                 forces: bool = False):
        self.channels = channels
        self.phases = phases
        self.commands = open_table(out_dir, "commands", command_columns(channels, phases), fmt)
        self.friction = open_table(out_dir, "friction", friction_columns(forces), fmt)
        self.files: list[str] = []

    def write(self, out, commands_um) -> None:
        cols = {"t_s": out.t_s}
        for k, ch in enumerate(self.channels):
            cols[f"{ch}_um"] = commands_um[:, k]
        if self.phases:
            for k, ch in enumerate(self.channels):
                cols[f"{ch}_phase_rad"] = out.phases_rad[:, k]
        self.commands.write(cols)
        self.friction.write(friction_rows(out))

    def commit(self) -> None:
        commands = self.commands.commit()
        try:
            friction = self.friction.commit()
        except BaseException:
            if commands is not None:
                commands.unlink(missing_ok=True)
            raise
        self.files = [path.name for path in (commands, friction) if path is not None]

    def abort(self) -> None:
        self.commands.abort()
        self.friction.abort()

    @classmethod
    def open(cls, arg: str, request: SinkRequest) -> TableSink:
        """The run's tables in ``request.folder`` (its :data:`SINKS` factory)."""
        SINKS.refuse_arg("tables", arg)
        return cls(request.folder, request.channels, request.phases, request.fmt,
                   request.forces)


class LinkSink:
    """Streams every block's commands to a device link (``device.link.host.CommandSink``);
    commit drains the link, abort stops the device at once (the link's ``abort``: Stop
    without drain; an output device without one is closed). Blocks go out
    ``block_size`` samples at a time, indexed on the output clock."""

    def __init__(self, link, block_size: int):
        self.link = link
        self.block_size = block_size
        #: the output sample after the last one handed to the link
        self.handed = 0

    def write(self, out, commands_um) -> None:
        for lo in range(0, commands_um.shape[0], self.block_size):
            s = slice(lo, lo + self.block_size)
            phases = None if out.phases_rad is None else out.phases_rad[s]
            self.link.send(out.index0 + lo, commands_um[s], phases)
            self.handed = out.index0 + min(lo + self.block_size, commands_um.shape[0])

    def commit(self) -> None:
        self.link.close()

    def abort(self) -> None:
        getattr(self.link, "abort", self.link.close)()

    @classmethod
    def open(cls, arg: str, request: SinkRequest) -> LinkSink:
        """``request.link`` fed by blocks of ``request.block_size`` (its factory)."""
        SINKS.refuse_arg("link", arg)
        if request.link is None:
            raise InputError("sink 'link' streams to an output device, and the run has "
                             "none: choose one (--device, device=)")
        return cls(request.link, request.block_size)


class FrameSink:
    """PNG frames of the visual layer (``app.engine.frames.FrameWriter``)."""

    def __init__(self, frames):
        self.frames = frames

    def write(self, out, commands_um) -> None:
        self.frames.add(out)

    def commit(self) -> None:
        self.frames.close()

    abort = commit

    @classmethod
    def open(cls, arg: str, request: SinkRequest) -> FrameSink:
        """The frames of ``request.frames`` (its factory)."""
        SINKS.refuse_arg("frames", arg)
        if request.frames is None:
            raise InputError("sink 'frames' writes the run's PNG frames and this run makes "
                             "none: ask for them with --frames FPS (frictex replay only: "
                             "frictex.replay makes no frames)")
        return cls(request.frames)


class MemorySink:
    """Keeps every block output in a list (measurements and tests of short runs)."""

    def __init__(self):
        self.outs: list = []

    def write(self, out, commands_um) -> None:
        self.outs.append(out)

    def commit(self) -> None:
        """The list is the result."""

    abort = commit

    @classmethod
    def open(cls, arg: str, request: SinkRequest) -> MemorySink:
        """An empty list (its factory)."""
        SINKS.refuse_arg("memory", arg)
        return cls()


class ProgressSink:
    """A progress bar on stderr counting seconds of output (tqdm)."""

    def __init__(self, rate_hz: float):
        from frictex.app.engine.progress import progress_bar
        self.rate_hz = rate_hz
        self.bar = progress_bar(unit="s", desc="replay", disable=None,
                                bar_format="{desc}: {n:.0f} s of output [{elapsed}, {rate_fmt}]")

    def write(self, out, commands_um) -> None:
        self.bar.update(out.t_s.size / self.rate_hz)

    def commit(self) -> None:
        self.bar.close()

    abort = commit

    @classmethod
    def open(cls, arg: str, request: SinkRequest) -> ProgressSink:
        """A bar counting seconds at ``request.rate_hz`` (its factory)."""
        SINKS.refuse_arg("progress", arg)
        return cls(request.rate_hz)


class ThreadedSink:
    """Another sink, run on its own thread. ``wait`` False (the live haptic loop, which must
    never block): ``write`` never blocks the caller, a full queue drops the block, counted
    in ``dropped``. ``wait`` True (a replay, whose sinks get every call): ``write`` waits
    for room in the queue. ``inner`` gets exactly one of ``commit`` or ``abort``, but an
    ``abort`` after its ``commit`` raised (as the driver does for any sink)."""

    def __init__(self, inner, queue_blocks: int, name: str = "frictex-sink",
                 wait: bool = False):
        self.inner = inner
        self.wait = wait
        self.queue_blocks = queue_blocks
        #: calls of ``write`` and, of those, calls dropped (queue full, ``wait`` False)
        self.calls = self.dropped = 0
        self.error: BaseException | None = None
        self._inner_aborted = False
        self._queue: queue.Queue = queue.Queue(queue_blocks)
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def write(self, out, commands_um) -> None:
        self.calls += 1
        if self.wait:
            self._queue.put((out, commands_um))
            return
        try:
            self._queue.put_nowait((out, commands_um))
        except queue.Full:
            self.dropped += 1

    def dropped_warning(self) -> str | None:
        """The summary's sentence for the calls this sink dropped, or None when none."""
        if not self.dropped:
            return None
        return (f"sink threaded:{type(self.inner).__name__} dropped {self.dropped} of "
                f"{self.calls} pipeline calls (its queue of {self.queue_blocks} calls was "
                f"full): its output misses them")

    def _run(self) -> None:
        while (item := self._queue.get()) is not None:
            if self.error is None:
                try:
                    self.inner.write(*item)
                except BaseException as exc:  # raised again by commit
                    self.error = exc

    def _finish(self) -> None:
        if self._thread.is_alive():
            self._queue.put(None)
            self._thread.join()

    def commit(self) -> None:
        self._finish()
        if self.error is not None:
            self._abort_inner()
            raise self.error
        self.inner.commit()

    def abort(self) -> None:
        self._finish()
        self._abort_inner()

    def _abort_inner(self) -> None:
        if not self._inner_aborted:
            self._inner_aborted = True
            self.inner.abort()

    @classmethod
    def open(cls, arg: str, request: SinkRequest) -> ThreadedSink:
        """The sink ARG names (``threaded:NAME[:ARG]``) on its own thread, queueing
        ``request.queue_blocks`` calls and waiting for room beyond them, so that it gets
        every call (its factory; a replay builds it)."""
        if not arg:
            raise InputError("sink 'threaded' runs another sink on its own thread: name it, "
                             "threaded:NAME[:ARG]")
        return cls(build_sink(arg, request), request.queue_blocks, wait=True)


SINKS.register("tables", TableSink.open)
SINKS.register("link", LinkSink.open)
SINKS.register("frames", FrameSink.open)
SINKS.register("memory", MemorySink.open)
SINKS.register("progress", ProgressSink.open)
SINKS.register("threaded", ThreadedSink.open)
