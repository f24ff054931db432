"""A whole replay: a scene and a trace through the pipeline, tables and a typed summary."""

from __future__ import annotations

import json
import os
import zipfile
from pathlib import Path
from collections.abc import Sequence
from typing import TYPE_CHECKING, Any

from frictex._args import flag, path_like, real
from frictex._inputs import checked, scene_of
from frictex._pipeline import run_settings
from frictex.app.engine.clocks import Clock
from frictex.app.engine.device_changes import unplayed_problem
from frictex.app.engine.replay import MAX_UNPLAYED, ReplayOptions, file_id, replay_with
from frictex.app.engine.sinks import Sink
from frictex.app.engine.sources import MAX_GAP_S
from frictex.app.engine.summary import finite_json
from frictex.app.engine.summary_types import Summary
from frictex.app.engine.tables import FORMATS, MEMORY, read_table
from frictex.device.errors import DeviceError, InputError, RunFailed
from frictex.rendering.input.trace_file import Trace
from frictex.textures.model import Scene

if TYPE_CHECKING:
    import numpy as np
    import pyarrow

__all__ = ["Replay", "replay"]


class Replay:
    """The result of :func:`replay`: the summary and the two tables.

    With an output folder the tables are read from it on first use (a long run's tables
    need not fit in memory), and only while the folder still holds this run: before
    reading, its ``summary.json`` must be the file this run wrote (the same device, inode,
    size and modification time); after a later run into the same folder (or the folder's
    removal) reading a table is a :class:`~frictex.device.errors.RunFailed` instead of
    another run's rows; so is a table file removed or damaged since (the message names
    the file and what is wrong). A table once read is kept. The folder is held as an absolute path
    (a later ``os.chdir`` changes nothing). Every attribute is read-only (assigning one
    is an ``AttributeError``).

    Attributes
    ----------
    summary : Summary
        What ``summary.json`` holds, typed; ``summary.to_dict()`` is that document.
    out : Path or None
        The output folder (absolute, links resolved), or None when the tables are in
        memory.
    """

    def __init__(self, summary: Summary, out: Path | None, tables: dict[str, Any] | None,
                 summary_id: tuple[int, ...] | None = None):
        self._summary = summary
        self._out = None if out is None else Path(os.path.realpath(out))
        self._tables = dict(tables or {})  # in memory (out is None), or read from out
        self._summary_id = summary_id

    @property
    def summary(self) -> Summary:
        """What ``summary.json`` holds, typed; ``summary.to_dict()`` is that document."""
        return self._summary

    @property
    def out(self) -> Path | None:
        """The output folder (absolute, links resolved), or None when the tables are in
        memory."""
        return self._out

    def _table(self, stem: str) -> pyarrow.Table:
        """The table ``stem``: kept in memory, or read from the output folder once."""
        if stem not in self._tables and self.out is not None:
            self._tables[stem] = self._read_table(self.out, stem)
        return self._tables[stem]

    def _read_table(self, folder: Path, stem: str) -> pyarrow.Table:
        """The table ``stem`` read from ``folder``, while the folder holds this run; a
        table file gone or unreadable is a RunFailed naming it and why."""
        path = folder / f"{stem}.{self.summary.output.format}"
        try:  # checked after reading: a run swapped in meanwhile is caught too
            table, problem = read_table(path), None
        except FileNotFoundError:
            table, problem = None, "is missing (removed since this run wrote it)"
        except _READ_ERRORS as exc:
            table, problem = None, f"cannot be read back: {_first_line(exc)}"
        if not self._holds_run(folder):
            raise RunFailed(f"{folder}: no longer holds this run (its summary.json was "
                            f"replaced or removed since): {path.name} would not be its table; "
                            "read the tables before the next run into the folder")
        if problem is not None:
            raise RunFailed(f"{path}: this run's {stem} table {problem}")
        return table

    def _holds_run(self, folder: Path) -> bool:
        """Whether ``folder/summary.json`` is still the file this run wrote."""
        try:
            return self._summary_id is None or file_id(folder / "summary.json") == self._summary_id
        except FileNotFoundError:
            return False

    @property
    def friction(self) -> pyarrow.Table:
        """One row per touching finger and output sample.

        Columns ``t_s`` (s), ``finger`` (id), ``x_mm``, ``y_mm`` (mm, the position used),
        ``mu_target`` (mu' composed from the layers), ``amplitude_um`` (the amplitude the
        actuation achieves under the finger, um zero-to-peak); ``.to_pandas()`` where
        pandas is installed. Read from the output folder on first use when there is one (while it holds
        this run: see the class).
        """
        return self._table("friction")

    @property
    def commands(self) -> pyarrow.Table:
        """One row per output sample: ``t_s`` (s), ``<channel>_um`` per actuator channel
        (um zero-to-peak) and ``<channel>_phase_rad`` (rad) where the actuation has phases.
        Read from the output folder on first use when there is one (while it holds this
        run: see the class)."""
        return self._table("commands")

    def __repr__(self) -> str:
        where = "in memory" if self.out is None else str(self.out)
        return (f"Replay({self.summary.scene.name!r}, {self.summary.output.samples} output "
                f"samples, {where})")


def replay(scene: Scene | str | Path, trace: Trace | str | Path, *,
           out: str | Path | None = None, format: str | None = None,
           renderer: str | None = None, device: str | None = None, faults: str | None = None,
           max_unplayed: float = MAX_UNPLAYED, rate_hz: float = 10_000.0,
           block_size: int | np.integer | None = None, control: str | None = None, strict: bool = False,
           max_gap_s: float = MAX_GAP_S, progress: bool = False,
           sinks: Sequence[str | Sink] = (), clock: str | Clock = "virtual") -> Replay:
    """Replay a touch trace on a scene, headless, on a virtual clock (``frictex replay``).

    Parameters
    ----------
    scene : Scene, str or Path
        A scene (:func:`load_scene`), a texture file or a bundled scene's name.
    trace : Trace, str or Path
        A trace (:func:`read_trace`, :func:`synth_trace`, :func:`make_trace`; checked as
        :func:`make_trace` checks arrays), a trace CSV or a bundled trace's name.
    out : str, Path or None, optional
        Write ``commands.<format>``, ``friction.<format>`` and ``summary.json`` into this
        folder (replaced whole when the run completes; the previous run's outputs stay
        until then). None (the default): keep the tables in memory, write nothing.
    format : str or None, optional
        With ``out``: ``csv`` (the default), ``npz`` or ``parquet``. Without ``out``: None.
    renderer : str or None, optional
        Render every periodic layer this way (``sho``, ``sho-held``, ``sho-predicted``,
        ``sht``, ``hybrid``) instead of as its file says.
    device : str or None, optional
        Also stream the commands to a device, paced by it: ``"sim"`` (the simulated
        device), a serial port or a pyserial URL (``--device``).
    faults : str or None, optional
        With ``device``: link faults to inject, e.g. ``"corrupt=0.001,stall=0.2@1.5"``
        (``--faults``; grammar: ``device/link/faults.py``).
    max_unplayed : float, optional
        With ``device``: the largest share (0 to 1) of the commanded samples that may
        never play on the device; more is a :class:`DeviceError` once the run is done
        (``--max-unplayed``, default 0.01). Another value without ``device`` is an
        :class:`InputError`, as the command refuses ``--max-unplayed`` without ``--device``.
    rate_hz : float, optional
        Output sample rate (Hz), 100 Hz to 1 MHz (``--rate``).
    block_size : int or None, optional
        Output samples per block, 1 to 100,000 (``--block``); touch samples take effect
        at block boundaries. None (the default): 5 ms of samples (50 at 10 kHz).
    control : str or None, optional
        The friction loop (``open``, ``closed``, ``adaptive``) instead of the scene file's.
    strict : bool, optional
        Refuse a trace whose time goes back (else sorted or dropped, counted, warned).
    max_gap_s : float, optional
        A longer gap between touch samples (s, more than 0) is a lift; its silence is
        skipped (``--max-gap``).
    progress : bool, optional
        A progress bar on stderr for long traces.
    sinks : sequence of str or Sink, optional
        More sinks fed every block (``--sink``): ``"NAME[:ARG]"`` of a registered sink
        (``frictex.app.engine.sinks.SINKS``, a package's under entry points
        ``frictex.sinks``), built for the run, or objects with ``write(out,
        commands_um)``, ``commit()`` and ``abort()`` (``frictex.app.engine.sinks.Sink``),
        used as they are. They are committed before the tables: one that fails leaves no
        outputs; a package's that raises is a ``PluginError`` naming it.
    clock : str or Clock, optional
        What paces the run (``--clock``): ``"virtual"`` (the default: as fast as it
        computes), ``"wall"`` (real time), ``"device"`` (the device's room), or a
        package's (entry points ``frictex.clocks``); or an object with ``wait(k)``
        (return when block k may be computed) and ``finished(k, n)`` (blocks k .. k + n
        - 1 reached the sinks), ``frictex.app.engine.clocks.Clock``, used as it is. With
        any clock but ``"virtual"`` the run computes one block per pipeline call.

    Returns
    -------
    Replay
        ``summary`` (typed), ``friction`` and ``commands`` (pyarrow Tables).

    Raises
    ------
    InputError
        A bad scene, trace or option: the command line's bounds apply, and the message
        names the argument (or the trace's field and first bad sample); a sink or clock
        name nobody registered (the message lists the known).
    DeviceError
        The device's link failed; or the device left more than ``max_unplayed`` of the
        commanded samples unplayed, where ``frictex replay --device`` exits 1: the run
        is complete (its outputs written into ``out``), and the error's ``replay``
        attribute is its :class:`Replay`.
    OutputSpaceError
        The outputs would not fit in ``out``'s file system (checked before writing).
    PluginError
        A ``RuntimeError``, not an InputError: another package's renderer, sink, clock,
        device or device profile (or one registered from your code) that cannot be
        loaded, raises, or returns what its contract does not allow; the message names
        it and its package.
    """
    scene = scene_of(scene)
    if isinstance(trace, Trace):
        trace = checked(trace)
    else:
        path_like("trace", trace, "a Trace, a trace CSV or a bundled trace's name")
    if out is not None:
        path_like("out", out, "a folder to write the tables into, or None")
    rate_hz, block_size = run_settings(rate_hz, block_size, renderer, control)
    max_gap_s = real("max_gap_s", max_gap_s, "s", positive=True)
    max_unplayed = real("max_unplayed", max_unplayed, "", (0.0, 1.0))
    if max_unplayed != MAX_UNPLAYED and device is None:
        raise InputError(f"max_unplayed {max_unplayed:g}: needs device (the share of samples "
                         "a device never played); no device was given")
    if device is not None and not isinstance(device, str):
        raise InputError(f"device: expected 'sim', a serial port or a pyserial URL, got "
                         f"{type(device).__name__}")
    if faults is not None:
        if device is None:
            raise InputError("faults are injected into a device's link: give device too")
        if not isinstance(faults, str):
            raise InputError(f"faults: expected a fault spec such as 'corrupt=0.001', got "
                             f"{type(faults).__name__}")
        from frictex.device.link.faults import parse_faults
        faults = parse_faults(faults)
    if format is not None and format not in FORMATS:  # a bad name first, out or not
        raise InputError(f"format {format!r}: expected one of {', '.join(FORMATS)}")
    if out is None and format is not None:
        raise InputError(f"format {format!r}: the tables are kept in memory unless out names "
                         "a folder to write them into")
    fmt = MEMORY if out is None else format or "csv"
    options = ReplayOptions(rate_hz=rate_hz, fmt=fmt, block_size=block_size,
                            render_override=renderer, device=device, faults=faults,
                            control=control, strict=flag("strict", strict),
                            max_gap_s=max_gap_s, progress=flag("progress", progress),
                            sinks=_sinks(sinks), clock=_clock(clock))
    result = replay_with(scene, trace, out, options)
    doc = json.loads(json.dumps(finite_json(result.summary), allow_nan=False))
    done = Replay(Summary.from_dict(doc), out, result.tables, result.summary_id)
    problem = unplayed_problem(result.summary.get("device"), max_unplayed, "max_unplayed")
    if problem is not None:
        error = DeviceError(problem + ("" if out is None else f"; outputs in {done.out}"))
        error.replay = done
        raise error
    return done


#: what reading a table file that is damaged (truncated, overwritten) or unreadable raises:
#: pyarrow's parse errors are ValueErrors, a broken npz a BadZipFile or EOFError
_READ_ERRORS = (OSError, ValueError, EOFError, zipfile.BadZipFile)


def _first_line(exc: BaseException) -> str:
    """An error reading a file, in one line: an OSError's reason (its path is named
    already), else the first line of its message."""
    if isinstance(exc, OSError) and exc.strerror:
        return exc.strerror
    lines = str(exc).strip().splitlines()
    return lines[0] if lines else type(exc).__name__


def _sinks(sinks: Sequence[str | Sink]) -> tuple[str | Sink, ...]:
    """``sinks`` as a tuple, each a str or a :class:`~frictex.app.engine.sinks.Sink`."""
    if isinstance(sinks, str) or not isinstance(sinks, Sequence):
        raise InputError(f"sinks: expected a list of sink names or Sink objects, got "
                         f"{type(sinks).__name__}")
    for item in sinks:
        if not isinstance(item, str) and not all(callable(getattr(item, method, None))
                                                  for method in ("write", "commit", "abort")):
            raise InputError(f"sinks: {type(item).__name__} is neither a sink's name "
                             "(NAME[:ARG]) nor a Sink (write, commit and abort)")
    return tuple(sinks)


def _clock(clock: str | Clock) -> str | Clock:
    """``clock``: a clock's name (``NAME[:ARG]``), or a
    :class:`~frictex.app.engine.clocks.Clock` (callable ``wait`` and ``finished``)."""
    if not isinstance(clock, str) and not all(callable(getattr(clock, method, None))
                                              for method in ("wait", "finished")):
        raise InputError(f"clock: {type(clock).__name__} is neither a clock's name "
                         "(NAME[:ARG]) nor a Clock (wait(k) and finished(k, n))")
    return clock
