"""``frictex bench baseline``: frictex against the bare-numpy floor, as whole processes.

The bare program has 32 lines using numpy and pyarrow only (``BARE``): it
reads a trace with pyarrow's CSV reader, interpolates the finger to the 10 kHz output
rate, computes a grating's friction and amplitude, and writes the same two tables as a
replay (``friction``: six columns at 10 kHz; ``commands``: two) with pyarrow's Parquet
writer (the encodings frictex uses: byte-stream-split floats, a dictionary for the
integers), pyarrow's CSV writer (every digit of each float) or ``numpy.savez``.

For Parquet and npz it is a floor: it does less than a replay (no tracking, no scene,
no summary) with the same writer or a simpler one, so the ratio is an upper bound of
frictex's overhead. For CSV it is not: pyarrow's CSV writer, which writes every digit
of a float, is slower than frictex's fixed-decimal one (``app/engine/csv_text.py``), so
a CSV ratio under the target shows nothing about frictex's overhead, and the section
gives CSV no verdict.

Both run as fresh processes on the same human-like trace (600 s; 60 s with ``--quick``),
alternated, one of each per round (8 rounds; 4 with ``--quick``), each into a folder its
previous run's output was removed from just before (untimed): a program that overwrites
its last 90 MB of output frees those pages on its own time, which varied its system time
from 0.08 to 0.38 s a run (the bare program's whole run is 0.45 s). Per format the
section prints the median wall time of each, each round's ratio (frictex's run over the
bare run of the same round), their geometric mean with its 95 % interval, and a
verdict (``app.measure.ratio_claim``): the target **holds** only where the whole
interval is under it, **does not hold** where the whole interval is over it, and is
**not shown** otherwise. Beside them, in this process: reading that trace with
``read_trace`` against ``pyarrow.csv.read_csv``, 25 reads of each in alternated rounds
(the order reversed every other round) after one untimed read of each, their medians
and the same verdict on the rounds' ratios.

Targets (issue 31): a 10-minute Parquet replay at most 1.2x the floor, npz at most 1.3x
(CSV's 1.3x has no floor to be measured against here); trace reading at most 2x pyarrow's
reader. ``--quick`` (60 s) gives the replays no verdict: there start-up is half of
frictex's time.
"""

from __future__ import annotations

import shutil
import sys
import tempfile
from pathlib import Path

import numpy as np

from frictex.app.measure.bench_replay import SCENE, human_trace
from frictex.app.measure.figure import Figure
from frictex.app.measure.in_turn import timed_in_turn
from frictex.app.measure.processes import alternated, failed_note, frictex_argv, median
from frictex.app.measure.ratio_claim import ratio_claim
from frictex.rendering.input.trace_file import read_trace, write_trace

#: the bare program: python -c BARE TRACE OUT_DIR FORMAT
BARE = r"""
import sys
from pathlib import Path
import numpy as np
import pyarrow as pa, pyarrow.csv as pcsv
trace, out, fmt = sys.argv[1], Path(sys.argv[2]), sys.argv[3]
out.mkdir(parents=True, exist_ok=True)
with open(trace, "rb") as f:
    skip = 0
    while f.readline().startswith(b"#"):
        skip += 1
table = pcsv.read_csv(trace, read_options=pcsv.ReadOptions(skip_rows=skip))
t, x, y = (table[c].to_numpy() for c in ("t_s", "x_mm", "y_mm"))
ts = np.arange(t[0], t[-1], 1e-4)
xs, ys = np.interp(ts, t, x), np.interp(ts, t, y)
mu = 0.3 + 0.2 * (np.sin(2.0 * np.pi * xs / 2.0) > 0.0)
amp = np.clip(2.5 * (0.5 - mu) / 0.2, 0.0, 2.5)
tables = {"friction": {"t_s": ts, "finger": np.zeros(ts.size, np.int64), "x_mm": xs,
                       "y_mm": ys, "mu_target": mu, "amplitude_um": amp},
          "commands": {"t_s": ts, "ch0_um": amp}}
for name, cols in tables.items():
    if fmt == "npz":
        np.savez(out / f"{name}.npz", **cols)
        continue
    arrow = pa.table(cols)
    if fmt == "parquet":
        import pyarrow.parquet as pq
        floats = [c for c in cols if cols[c].dtype.kind == "f"]
        pq.write_table(arrow, out / f"{name}.parquet", compression="snappy",
                       use_dictionary=[c for c in cols if c not in floats],
                       use_byte_stream_split=floats)
    else:
        pcsv.write_csv(arrow, out / f"{name}.csv")
"""


#: trace reading: read_trace at most this many times pyarrow's reader's time (issue 31)
READ_TARGET = 2.0


def _reading_figures(path: Path, reads: int = 25, what: str = "the trace") -> list[Figure]:
    """``read_trace`` and ``pyarrow.csv.read_csv`` on ``path``, ``reads`` of each in
    alternated rounds (``in_turn``) after one untimed read of each: ``reading_figures``
    (``what``: the trace read, as the labels name it).
    A read of the 10-minute trace takes milliseconds, where the machine's jitter is a
    good part of a round's ratio: 25 rounds cost a fraction of a second."""
    import pyarrow.csv as pcsv

    lines = path.read_text().splitlines()
    skip = next(k for k, line in enumerate(lines) if not line.startswith("#"))  # comments
    options = pcsv.ReadOptions(skip_rows=skip)
    [(ours, _), (theirs, _)] = timed_in_turn(
        [(lambda: read_trace(path), None),
         (lambda: pcsv.read_csv(path, read_options=options), None)], reads, warmup=1)
    return reading_figures(ours, theirs, what)


def reading_figures(ours: np.ndarray, theirs: np.ndarray, what: str = "the trace"
                    ) -> list[Figure]:
    """The median seconds of each reader over the rounds (``ours``: ``read_trace``,
    ``theirs``: pyarrow's, same round at the same index), and the verdict on
    :data:`READ_TARGET` from each round's ratio of the two (``ratio_claim``); ``what``:
    the trace read (``trace_name``)."""
    of = f"median of {len(ours)}, alternated"
    claim = ratio_claim(list(np.asarray(ours) / np.asarray(theirs)), READ_TARGET, at_most=True)
    return [Figure("baseline", f"reading {what}, frictex read_trace ({of})",
                   float(np.median(ours)), "s"),
            Figure("baseline", f"reading {what}, pyarrow.csv.read_csv ({of})",
                   float(np.median(theirs)), "s"),
            claim.figure("baseline", f"reading {what}, frictex against pyarrow",
                         READ_TARGET, at_most=True)]


def trace_name(trace) -> str:
    """``the 60 s trace (3,600 rows)``: a trace's duration (s) and rows, as labels name it."""
    return f"the {trace.duration_s:g} s trace ({trace.t_s.size:,} rows)"


#: output format -> target ratio to the bare program (None: the bare program is no floor)
TARGETS = {"parquet": 1.2, "npz": 1.3, "csv": None}
#: why a format gets no verdict
NO_FLOOR = "the bare program is no floor (pyarrow's CSV writer is slower than frictex's)"
QUICK = "the targets are a 10-minute replay's (--quick runs 60 s, where start-up weighs more)"


def paired_figures(label: str, bare: list, ours: list, target: float | None,
                   no_target: str = NO_FLOOR) -> list[Figure]:
    """Figures of one format over the rounds whose two runs both succeeded (a round
    where either failed, or took no measurable time, is left out on both sides, and the
    labels say how many): median wall times, each kept round's ratio (frictex's run
    over the bare run of the same round, labelled by its round), their geometric mean
    and its 95 % interval, the verdict on ``target`` (none where it is None:
    ``no_target`` says why), and median CPU times."""
    rounds = len(bare)
    ran = [(k, b, o) for k, (b, o) in enumerate(zip(bare, ours)) if b.code == 0 and o.code == 0]
    kept = [(k, b, o) for k, b, o in ran if b.wall_s > 0 and o.wall_s > 0]
    failed = rounds - len(ran)
    note = failed_note(failed, rounds) + (
        f", {len(ran) - len(kept)} of {rounds} not measured (0 s)" if len(kept) < len(ran)
        else "")
    kept_bare, kept_ours = [b for _, b, _ in kept], [o for _, _, o in kept]
    of = f"median of {len(kept)} rounds{note}"
    figures = [Figure("baseline", f"{label}, bare numpy/pyarrow ({of})",
                      median(kept_bare, "wall_s"), "s"),
               Figure("baseline", f"{label}, frictex ({of}, alternated)",
                      median(kept_ours, "wall_s"), "s")]
    figures += [Figure("baseline", f"{label}, frictex against bare, round {k + 1}",
                       o.wall_s / b.wall_s, "x") for k, b, o in kept]
    figures += _ratio_figures(label, [o.wall_s / b.wall_s for _, b, o in kept], target,
                              no_target, note)
    figures += [Figure("baseline", f"{label}, bare CPU user + system ({of})",
                       median(kept_bare, "cpu_s"), "s"),
                Figure("baseline", f"{label}, frictex CPU user + system ({of})",
                       median(kept_ours, "cpu_s"), "s")]
    return [f.of_failed(failed) for f in figures]


def _ratio_figures(label: str, ratios: list[float], target: float | None, no_target: str,
                   note: str) -> list[Figure]:
    """The rounds' ``ratios``' geometric mean with its 95 % interval: with a ``target``,
    one figure with the verdict on it (``RatioClaim.figure``); without, a second figure
    saying why there is no verdict (``no_target``); with no ratio, one figure saying why
    (``note``: how many rounds failed)."""
    if not ratios:
        return [Figure("baseline", f"{label}, frictex against bare: no round had both runs "
                       f"succeed{note}", 0, "rounds")]
    if target is not None:
        return [ratio_claim(ratios, target, at_most=True).figure(
            "baseline", f"{label}, frictex against bare", target, at_most=True, note=note)]
    claim = ratio_claim(ratios, 1.0, at_most=True)  # its geometric mean and interval only
    return [Figure("baseline", f"{label}, frictex against bare, geometric mean of "
                   f"{claim.rounds} rounds{note}", claim.geomean,
                   f"x ({claim.interval_text()})"),
            Figure("baseline", f"{label}, no verdict: {no_target}", len(ratios), "rounds")]


def run(quick: bool) -> list[Figure]:
    duration = 60.0 if quick else 600.0
    rounds = 4 if quick else 8
    figures = []
    with tempfile.TemporaryDirectory(prefix="frictex-baseline-") as name:
        tmp = Path(name)
        trace = tmp / f"human-{duration:g}.csv"
        strokes = human_trace(duration)
        write_trace(trace, strokes)
        figures += _reading_figures(trace, what=trace_name(strokes))
        commands, outputs = {}, {}
        for fmt in TARGETS:
            outputs[f"bare {fmt}"] = tmp / f"bare-{fmt}"
            outputs[f"frictex {fmt}"] = tmp / f"frictex-{fmt}"
            commands[f"bare {fmt}"] = [sys.executable, "-c", BARE, str(trace),
                                       str(outputs[f"bare {fmt}"]), fmt]
            commands[f"frictex {fmt}"] = frictex_argv(
                "replay", SCENE, str(trace), "--out", str(outputs[f"frictex {fmt}"]), "--format",
                fmt, "--quiet")
        runs = alternated(commands, rounds,
                          before=lambda name: shutil.rmtree(outputs[name], ignore_errors=True))
    for fmt, target in TARGETS.items():
        figures += paired_figures(f"{duration:g} s replay to {fmt}, whole process",
                                  runs[f"bare {fmt}"], runs[f"frictex {fmt}"],
                                  None if quick else target,
                                  NO_FLOOR if target is None else QUICK)
    return figures
