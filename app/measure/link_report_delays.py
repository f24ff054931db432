"""How late a live link's force reports reach the host, measured on this machine.

A block's delay is the whole blocks from its end to the first block computed with its
force report in hand (``rendering.control.loop``'s D). ``measure`` streams live blocks
(the wall clock paces them, as the demo's haptic thread does) to the simulated device
with a finger (``sim:finger=3``), beside busy processes that take the other cores, and
keeps each block's delay in the order the blocks went out: a loaded machine delays
reports in bursts (several late blocks in a row), which independent draws from the
histogram would not reproduce. ``frictex report``'s closed-loop runs replay the
sequence (``closed_loop_sim.LoopStage``), each finger from its own starting block;
``frictex bench link`` gives its percentiles idle and loaded.

The sequence depends on the machine and its load, so the loop modes' figures differ from
one report to the next. report.json records it (``ReportDelays.to_json``, with the load it
was measured at), and ``read`` takes it back (``frictex report --loop-delays FILE``, FILE
a report.json or that object alone): the same sequence gives the same closed-loop figures.
"""

from __future__ import annotations

import json
import math
import reprlib
import time
from dataclasses import dataclass, replace
from pathlib import Path

import numpy as np

from frictex.app.measure.processes import BusyProcesses, load
from frictex.device.errors import InputError
from frictex.device.safe_files import read_bytes

#: the most bytes :func:`read` takes: a full report's report.json is about 1 MB (a quick
#: one 0.3 MB, the delays of a 20 s measurement 12 kB of it); 16 MiB leaves room for
#: --real's records and longer measurements, and refuses a device or a stray file at once
MAX_FILE_BYTES = 16 << 20

#: the delay of a block whose report never came within the loop's wait (``max_wait_s``)
LOST = -1


@dataclass(frozen=True)
class ReportDelays:
    """Per block, in the order sent, its report's delay in blocks (``LOST``: none came),
    and how it was measured: ``seconds`` of live blocks of ``block`` samples at
    ``rate_hz`` beside ``busy`` busy processes, the 1-minute load average at the start
    and end. ``seconds`` 0: not measured, a constant delay (tests, ``bench pipeline``).
    ``source``: the file the sequence was read from ("": measured by this run)."""

    blocks: tuple[int, ...]
    seconds: float = 0.0
    rate_hz: float = 0.0
    block: int = 0
    busy: int = 0
    load_start: float = float("nan")
    load_end: float = float("nan")
    source: str = ""

    @classmethod
    def constant(cls, delay_blocks: int) -> ReportDelays:
        """Every report ``delay_blocks`` blocks late."""
        return cls((int(delay_blocks),))

    @property
    def measured(self) -> bool:
        return self.seconds > 0

    def come(self) -> np.ndarray:
        """The delays of the reports that came (blocks, int64)."""
        d = np.asarray(self.blocks, dtype=np.int64)
        return d[d != LOST]

    def largest(self) -> int:
        """The largest delay of a report that came (0 if none came)."""
        come = self.come()
        return int(come.max()) if come.size else 0

    def start_for(self, seed: int) -> int:
        """Where in the sequence a run with ``seed`` starts (the same for every mode of one
        finger, so their comparison is paired)."""
        return int(np.random.default_rng([seed, 23]).integers(len(self.blocks)))

    def to_json(self) -> dict:
        come = self.come()
        counts = np.unique(come, return_counts=True) if come.size else ([], [])
        p50, p99 = (np.percentile(come, [50, 99]) if come.size else (float("nan"),) * 2)
        return {"blocks": list(self.blocks), "seconds": self.seconds, "rate_hz": self.rate_hz,
                "block": self.block, "busy": self.busy, "load_start": self.load_start,
                "load_end": self.load_end, "p50": float(p50), "p99": float(p99),
                "max": self.largest(), "lost": len(self.blocks) - int(come.size),
                "counts": {str(int(d)): int(c) for d, c in zip(*counts)},
                "source": self.source}

    @classmethod
    def from_json(cls, doc: dict) -> ReportDelays:
        """The sequence of :meth:`to_json` (its summary figures are recomputed, not read;
        a record written before ``source`` was kept reads as measured by its run; a load
        of null reads as NaN). ``doc``'s fields are taken as they are: :func:`read`
        checks a file's."""
        return cls(tuple(doc["blocks"]), doc["seconds"], doc["rate_hz"], doc["block"],
                   doc["busy"], _load_or_nan(doc["load_start"]), _load_or_nan(doc["load_end"]),
                   doc.get("source", ""))


def _load_or_nan(value) -> float:
    """A recorded load average, NaN where none was recorded (null)."""
    return float("nan") if value is None else value


#: the fields of :meth:`ReportDelays.to_json` that :func:`read` takes back
FIELDS = ("blocks", "seconds", "rate_hz", "block", "busy", "load_start", "load_end")


def wait_blocks(rate_hz: float, block: int) -> int:
    """The loop's wait for a force report (``LoopConfig.max_wait_s``) in whole blocks of
    ``block`` samples at ``rate_hz``: the latest delay a report the loop uses can have
    (one later is folded as missed, and :func:`measure` records it as ``LOST``)."""
    from frictex.rendering.control.loop import LoopConfig
    return int(np.ceil(LoopConfig().max_wait_s * rate_hz / block))


def read(path, rate_hz: float, block: int) -> ReportDelays:
    """The report delays recorded in ``path``: a report.json (its ``closed_loop``
    section's ``report_delays``) or that object alone, measured at ``rate_hz`` in blocks
    of ``block`` samples (a sequence of other blocks would mean other delays). Raises
    InputError naming the file (and the field) when it cannot be read, holds no such
    sequence, has a field of the wrong type, or a delay later than the loop's wait; a
    FIFO, a device or a file over ``MAX_FILE_BYTES`` is refused without reading it
    (``device.safe_files.read_bytes``)."""
    path = Path(path)
    try:
        data = read_bytes(path, MAX_FILE_BYTES)
    except OSError as exc:
        raise InputError(f"{path}: {exc}; expected a report.json or its report_delays "
                         "object") from None
    try:
        doc = json.loads(data.decode("utf-8"))
    except (UnicodeDecodeError, ValueError) as exc:
        raise InputError(f"{path}: cannot read report delays: {exc}") from None
    if isinstance(doc, dict) and isinstance(doc.get("closed_loop"), dict):
        doc = doc["closed_loop"].get("report_delays")
    if not isinstance(doc, dict) or any(field not in doc for field in FIELDS):
        raise InputError(f"{path}: no report delays (expected a report.json with a closed-loop "
                         "section, or its report_delays object: " + ", ".join(FIELDS) + ")")
    _check_fields(path, doc, wait_blocks(rate_hz, block))
    delays = ReportDelays.from_json(doc)
    if delays.measured and (delays.rate_hz != rate_hz or delays.block != block):
        raise InputError(f"{path}: report delays measured at {delays.rate_hz:g} Hz in blocks "
                         f"of {delays.block}; the closed-loop runs use {rate_hz:g} Hz in blocks "
                         f"of {block}")
    return replace(delays, source=str(path))


def _check_fields(path: Path, doc: dict, wait: int) -> None:
    """Raise InputError naming ``path`` and the first field of ``doc`` (a report_delays
    object) whose type or value is not what :meth:`ReportDelays.to_json` writes: blocks
    a non-empty list of whole numbers from ``LOST`` to ``wait`` (blocks), seconds and
    rate_hz, block, busy finite numbers >= 0, the loads numbers, null or NaN."""
    def bad(field: str, value, expected: str) -> InputError:
        return InputError(f"{path}: report delays: {field} is {reprlib.repr(value)}, "
                          f"expected {expected}")

    blocks = doc["blocks"]
    if not isinstance(blocks, list) or not blocks:
        raise bad("blocks", blocks, "a non-empty list of whole blocks")
    for k, delay in enumerate(blocks):
        if not _whole(delay) or delay < LOST:
            raise bad(f"blocks[{k}]", delay, f"a whole number of blocks >= {LOST} "
                      f"({LOST}: lost)")
        if delay > wait:
            raise bad(f"blocks[{k}]", delay, f"at most the loop's wait, {wait} blocks (a "
                      f"report later than that is lost to the loop: {LOST})")
    for field in ("seconds", "rate_hz", "block", "busy"):
        if not (_number(doc[field]) and math.isfinite(doc[field]) and doc[field] >= 0):
            raise bad(field, doc[field], "a finite number >= 0")
    for field in ("load_start", "load_end"):
        load_avg = doc[field]
        if load_avg is not None and not (_number(load_avg) and not math.isinf(load_avg)):
            raise bad(field, load_avg, "a number, null or NaN (not recorded)")


def _number(value) -> bool:
    """Whether ``value`` (read from JSON) is a number: an int or float, not a bool."""
    return isinstance(value, (int, float)) and not isinstance(value, bool)


def _whole(value) -> bool:
    """Whether ``value`` (read from JSON) is a whole number written as one (2, not 2.0)."""
    return isinstance(value, int) and not isinstance(value, bool)


def measure(seconds: float, rate_hz: float, block: int, busy: int) -> ReportDelays:
    """Stream ``seconds`` of live blocks of ``block`` samples at ``rate_hz`` to the
    simulated device with a finger, beside ``busy`` busy processes; each block's report
    delay (module docstring). The first tenth is left out (the device's prefill), and so
    are the last blocks, whose reports had not yet had the loop's wait to come."""
    from frictex.device.link.host import open_sink
    wait = wait_blocks(rate_hz, block)
    n_blocks = int(seconds * rate_hz / block) + wait
    delays = np.full(n_blocks, LOST, dtype=np.int64)
    ones = np.ones((block, 1))
    load_start = load()
    with BusyProcesses(busy, seconds + 30.0):
        sink = open_sink("sim:finger=3", channels=1, rate_hz=rate_hz, paced=False)
        try:
            pending: list[int] = []  # blocks sent whose reports have not come
            t0 = time.perf_counter()
            for b in range(n_blocks):
                while time.perf_counter() < t0 + b * block / rate_hz:
                    time.sleep(2e-4)
                # a report later than the loop's wait is one the loop never uses: LOST
                pending = [j for j in pending if b - j - 1 <= wait]
                for j in [j for j in pending if sink.force_report(j * block, block) is not None]:
                    delays[j] = b - j - 1
                    pending.remove(j)
                sink.send(b * block, ones, None)
                pending.append(b)
        finally:
            sink.close()
    kept = delays[n_blocks // 10:n_blocks - wait - 1]
    return ReportDelays(tuple(int(d) for d in kept), seconds, rate_hz, block, busy,
                        load_start, load())
