"""Where a run's output goes: tables, a device link, PNG frames, the window's scope.

A sink takes every pipeline call's output and the channel commands actually sent
(``write(out, commands_um)``: ``out`` a ``rendering.pipeline.BlockOutput``, commands
(n, channels) um), then either ``commit()`` (the run finished: make the result final)
or ``abort()`` (the run failed: leave nothing that looks complete). The driver calls
them; a sink never calls another.

The :class:`Sink` protocol is an extension point: :data:`SINKS` holds the sinks by name
(``tables``, ``link``, ``frames``, ``memory``, ``progress``, ``threaded``), and another
package adds one under entry-point group ``frictex.sinks``. Each is built with its own
arguments (a sink class).
"""

from __future__ import annotations

import queue
import threading
from pathlib import Path
from typing import Protocol

import numpy as np

from frictex.device.registry import Registry

from frictex.app.engine.tables import open_table

FRICTION_COLUMNS = [("t_s", np.float64, "%.7f"), ("finger", np.int64, "%d"),
                    ("x_mm", np.float64, "%.4f"), ("y_mm", np.float64, "%.4f"),
                    ("mu_target", np.float64, "%.6f"), ("amplitude_um", np.float64, "%.6f")]


def command_columns(channels: tuple[str, ...], phases: bool) -> list[tuple]:
    """``commands`` table columns: t_s, one amplitude per channel, phases if any."""
    cols = [("t_s", np.float64, "%.7f")]
    cols += [(f"{ch}_um", np.float64, "%.6f") for ch in channels]
    if phases:
        cols += [(f"{ch}_phase_rad", np.float64, "%.6f") for ch in channels]
    return cols


def friction_rows(out) -> dict[str, np.ndarray]:
    """``friction`` table rows of a block output: sample-major, then finger id, touching
    only."""
    ids = out.ids_per_sample()
    columns = (out.contact, ids, out.x_mm, out.y_mm, out.mu_target, out.amplitude_um)
    if ids.shape[0] > 1 and (np.diff(ids, axis=0) < 0).any():  # reused rows: by id again
        order = np.argsort(ids, axis=0, kind="stable")
        columns = tuple(np.take_along_axis(c, order, axis=0) for c in columns)
    contact, ids, x, y, mu, amplitude = (c.T for c in columns)  # (n, F)
    t = np.broadcast_to(out.t_s[:, None], contact.shape)
    if contact.all():  # every finger down throughout: all rows in order (views for one finger)
        return {"t_s": t.ravel(), "finger": ids.ravel(), "x_mm": x.ravel(), "y_mm": y.ravel(),
                "mu_target": mu.ravel(), "amplitude_um": amplitude.ravel()}
    return {"t_s": t[contact], "finger": ids[contact], "x_mm": x[contact], "y_mm": y[contact],
            "mu_target": mu[contact], "amplitude_um": amplitude[contact]}


class Sink(Protocol):
    """Where a run's output goes (see the module docstring)."""

    def write(self, out, commands_um: np.ndarray) -> None:
        """Take one pipeline call's output and the (n, channels) commands sent (um)."""

    def commit(self) -> None:
        """The run finished: make the result final."""

    def abort(self) -> None:
        """The run failed: leave nothing that looks complete."""


#: sinks by name (their classes)
SINKS: Registry[type] = Registry("sink", "frictex.sinks")


@SINKS.register("tables")
class TableSink:
    """``commands.<fmt>`` and ``friction.<fmt>`` in ``out_dir`` (DESIGN.md, replay output),
    or two pyarrow Tables in memory (``fmt`` ``memory``: ``app.engine.tables.MemoryTable``;
    ``files`` stays empty)."""

    def __init__(self, out_dir: Path | None, channels: tuple[str, ...], phases: bool, fmt: str):
        self.channels = channels
        self.phases = phases
        self.commands = open_table(out_dir, "commands", command_columns(channels, phases), fmt)
        self.friction = open_table(out_dir, "friction", FRICTION_COLUMNS, fmt)
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


@SINKS.register("link")
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


@SINKS.register("frames")
class FrameSink:
    """PNG frames of the visual layer (``app.engine.frames.FrameWriter``)."""

    def __init__(self, frames):
        self.frames = frames

    def write(self, out, commands_um) -> None:
        self.frames.add(out)

    def commit(self) -> None:
        self.frames.close()

    abort = commit


@SINKS.register("memory")
class MemorySink:
    """Keeps every block output in a list (measurements and tests of short runs)."""

    def __init__(self):
        self.outs: list = []

    def write(self, out, commands_um) -> None:
        self.outs.append(out)

    def commit(self) -> None:
        """The list is the result."""

    abort = commit


@SINKS.register("progress")
class ProgressSink:
    """A progress bar on stderr counting seconds of output (tqdm)."""

    def __init__(self, rate_hz: float):
        from tqdm import tqdm
        self.rate_hz = rate_hz
        self.bar = tqdm(unit="s", desc="replay", disable=None,
                        bar_format="{desc}: {n:.0f} s of output [{elapsed}, {rate_fmt}]")

    def write(self, out, commands_um) -> None:
        self.bar.update(out.t_s.size / self.rate_hz)

    def commit(self) -> None:
        self.bar.close()

    abort = commit


@SINKS.register("threaded")
class ThreadedSink:
    """Another sink, run on its own thread so that ``write`` never blocks the caller (the
    live haptic loop): a full queue drops the block, counted in ``dropped``."""

    def __init__(self, inner, queue_blocks: int, name: str = "frictex-sink"):
        self.inner = inner
        self.dropped = 0
        self.error: BaseException | None = None
        self._queue: queue.Queue = queue.Queue(queue_blocks)
        self._thread = threading.Thread(target=self._run, name=name, daemon=True)
        self._thread.start()

    def write(self, out, commands_um) -> None:
        try:
            self._queue.put_nowait((out, commands_um))
        except queue.Full:
            self.dropped += 1

    def _run(self) -> None:
        while (item := self._queue.get()) is not None:
            if self.error is None:
                try:
                    self.inner.write(*item)
                except BaseException as exc:  # raised again by commit
                    self.error = exc

    def _finish(self) -> None:
        self._queue.put(None)
        self._thread.join()

    def commit(self) -> None:
        self._finish()
        if self.error is not None:
            self.inner.abort()
            raise self.error
        self.inner.commit()

    def abort(self) -> None:
        self._finish()
        self.inner.abort()
