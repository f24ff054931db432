"""A live demo's touches as a trace file (``touches.csv`` in ``--record``): every sample
the haptic side took, with the normal force it pressed with, in frictex's trace format
(``rendering.input.trace_file``), so that ``frictex replay SCENE REC/touches.csv --block
N`` (N the demo's block) plays what was felt.

The samples are the ones the haptic thread takes from its touch queue, block by block
(the mouse's, a follower finger's, a touch screen's), stamped on the output clock (s);
they are written on a thread of their own (``app.engine.sinks.ThreadedSink``), so the
haptic thread never waits on the disk. A replay's blocks start at the first touch, the
demo's at output time 0: where the first touch fell inside a block, a sample may take
effect one block (2.5 ms) apart from where the demo applied it. Scene switches and
emergency stops are not touches: events.csv has them.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from frictex.rendering.input.trace_file import Trace, format_trace

TOUCHES = "touches.csv"


class TouchTable:
    """A trace file at ``path``, its ``# comment`` and header written at once:
    ``write(samples)`` appends a ``Trace``'s rows; ``commit`` closes it, ``abort``
    removes it."""

    def __init__(self, path: Path, comment: str):
        self.path = Path(path)
        self._file = open(self.path, "w", encoding="utf-8")
        self._file.write(format_trace(Trace(*(np.zeros(0),) * 6), comment))

    def write(self, samples, _commands_um=None) -> None:
        """Append ``samples`` (a ``Trace``); the second argument, a sink's commands, is
        not used (the table is fed through ``ThreadedSink.write(samples, None)``)."""
        self._file.write(format_trace(samples).split("\n", 1)[1])  # without the header

    def commit(self) -> None:
        self._file.close()

    def abort(self) -> None:
        self._file.close()
        self.path.unlink(missing_ok=True)


class LoggedTouches:
    """A live touch source (``app.engine.sources.QueueSource``) whose samples, as the
    haptic thread takes them, also go to ``table`` (a ``ThreadedSink`` over a
    :class:`TouchTable`). It sits in the run's sinks as well, so that the file is
    committed (or removed) with the recording when the run ends; its ``write`` does
    nothing, the samples came through ``take``."""

    def __init__(self, source, table):
        self.source = source
        self.table = table

    @property
    def done(self) -> bool:
        return self.source.done

    def take(self, k: int, n: int):
        samples, n_run = self.source.take(k, n)
        if samples is not None:
            self.table.write(samples, None)
        return samples, n_run

    def resume_at(self, k: int) -> int:
        return self.source.resume_at(k)

    def label(self, out):
        return self.source.label(out)

    def write(self, out, commands_um) -> None:
        """A block's output: nothing to write (the samples came through ``take``)."""

    def commit(self) -> None:
        self.table.commit()

    def abort(self) -> None:
        self.table.abort()
