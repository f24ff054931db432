"""``frictex bench replay``: replays end to end, each in a fresh process as a user runs it.

- One finger, composed scene, 10 kHz, human-like strokes at 60 Hz (600 s; 60 s with
  ``--quick``), in each output format, one run each, one format after another (not
  alternated: ``frictex bench baseline`` compares the formats in alternated rounds):
  the run's own real-time factor end to end
  (reading the trace, computing, writing every output table, from ``summary.json``;
  not the summary's own writing nor the swap of the folder into place), the same with start-up (loading the scene and the kernels), the
  compute-only factor beside them, the whole process's wall time
  (interpreter start and imports too) and its peak memory. The same at a tenth of the
  length shows whether memory depends on the trace's length.
- The same strokes on ``app.measure.bench_pipeline``'s scene with every kind of issue-18
  layer (five height layers, a recorded texture, four clips), CSV and Parquet.
- Two fingers with modal actuation (seed 000's beam): the bundled crossing trace repeated
  to 98 s (24 s quick), CSV and Parquet.
- A one-second replay to CSV: the whole process's wall time (what a user waits; median
  of 5 runs one after another, its output folder removed before each, untimed).
- A batch of one-minute jobs (64; 16 quick) on all cores against the same batch run one
  job after another (``--jobs 1``): jobs per second of each, and the throughput ratio
  against issue 31's target of 1.5x as a verdict on paired rounds (4 pairs, alternated,
  after one run not counted: ``_batch_figures``; ``app.measure.ratio_claim``).

Every timed process starts with no unwritten file data of an earlier one: the batch's
runs each write ~2.5 GB of CSV, and the kernel writing the first run's pages back during
the second doubled the second's system time (4.5 -> 9.0 s for 64 jobs), so whichever
ran second was charged for both.
"""

from __future__ import annotations

import json
import shutil
import tempfile
from pathlib import Path

from frictex.app.measure.bench_pipeline import new_layer_scene
from frictex.app.measure.figure import Figure
from frictex.app.measure.processes import Run as ProcessRun
from frictex.app.measure.processes import (cores, failed_note, frictex_argv, median, medians_of,
                                           run_process)
from frictex.app.measure.ratio_claim import ratio_claim
from frictex.rendering.input.trace_file import Trace, concat_traces, read_trace, write_trace
from frictex.rendering.input.trace_synth import make_motion, sample
from frictex.textures.library import resolve_trace

SCENE = "composed-fine-grating-in-disc"
MODAL_SCENE, MODAL_TRACE = "two-finger-beam-seed000", "two-fingers-crossing-50hz"


def human_trace(duration_s: float) -> Trace:
    """Human-like strokes at 60 mm/s sampled at 60 Hz, ``duration_s`` long (seeded)."""
    return sample(make_motion("human", speed_mm_s=60.0, duration_s=duration_s, seed=7), 60.0,
                  noise_mm=0.05, seed=1)


def _repeated(trace: Trace, times: int, gap_s: float = 0.5) -> Trace:
    """``trace`` played ``times`` times, each start ``gap_s`` after the last one's end."""
    period = trace.duration_s + gap_s
    return concat_traces([Trace(trace.t_s + k * period, trace.finger, trace.x_mm, trace.y_mm,
                                trace.force_n, trace.event) for k in range(times)])


def replay_process(tmp: Path, scene: str, trace_path: Path, fmt: str) -> dict | None:
    """One ``frictex replay`` in a fresh process: its summary's real-time factors (end to
    end, compute only), the whole process's wall time (s), peak memory (MiB) and the most
    of that peak inherited from the launcher that started it (MiB, ``processes.Run``);
    None if it failed."""
    out = tmp / f"out-{trace_path.stem}-{fmt}"
    done = run_process(frictex_argv("replay", scene, str(trace_path), "--out", str(out),
                                    "--format", fmt, "--quiet"))
    if done.code != 0:
        return None
    timings = json.loads((out / "summary.json").read_text())["timings"]
    return {"x_realtime_end_to_end": timings["x_realtime_end_to_end"],
            "x_realtime_with_setup": timings["x_realtime_with_setup"],
            "x_realtime_compute": timings["x_realtime_compute"],
            "process_wall_s": done.wall_s, "peak_mib": done.peak_mib,
            "launcher_mib": done.floor_mib}


def end_to_end(duration_s: float, formats=("csv", "npz", "parquet")) -> dict:
    """``replay_process`` of the composed scene on a human-like trace of ``duration_s``,
    per output format (``frictex report`` states these beside its compute-only figures)."""
    with tempfile.TemporaryDirectory(prefix="frictex-e2e-") as name:
        path = Path(name) / f"human-{duration_s:g}.csv"
        write_trace(path, human_trace(duration_s))
        return {"scene": SCENE, "duration_s": duration_s,
                "formats": {fmt: replay_process(Path(name), SCENE, path, fmt) for fmt in formats}}


def _replay_figures(tmp: Path, label: str, scene: str, trace_path: Path, fmt: str,
                    duration_s: float) -> list[Figure]:
    got = replay_process(tmp, scene, trace_path, fmt)
    if got is None:
        return [Figure("replay", f"{label} {fmt}: replay failed", float("nan"), "")]
    once = "x real time (one run)"
    return [Figure("replay", f"{label} {fmt}, end to end (read, compute, write)",
                   got["x_realtime_end_to_end"], once),
            Figure("replay", f"{label} {fmt}, end to end with start-up (scene, kernels)",
                   got["x_realtime_with_setup"], once),
            Figure("replay", f"{label} {fmt}, compute only", got["x_realtime_compute"], once),
            Figure("replay", f"{label} {fmt}, whole process (start, imports too)",
                   duration_s / got["process_wall_s"], once),
            Figure("replay", f"{label} {fmt}, peak memory (of which at most "
                   f"{got['launcher_mib']:.0f} MiB the launcher's)", got["peak_mib"],
                   "MiB (one run)")]


#: throughput all cores should reach against one job after another (issue 31)
BATCH_TARGET = 1.5
#: paired rounds of the batch figures: (one after another, all cores), then reversed
BATCH_PAIRS = 4


def _batch_figures(tmp: Path, jobs: int) -> list[Figure]:
    """Jobs per second of a batch of ``jobs`` one-minute jobs on all cores and one after
    another, each round's throughput ratio (wall time one after another over all cores'
    in the same pair of runs), their geometric mean with its 95 % interval and the
    verdict on :data:`BATCH_TARGET`, from :data:`BATCH_PAIRS` pairs in the order 1 N,
    N 1, 1 N, ... (drift in the machine's speed favours neither side) after one run not
    counted. Each run starts as the one before left the machine: that run's output just
    removed. The kernel gives a run the page cache freed just before more cheaply than
    pages it has not used lately (a job's system time was 55-65 ms after the last run's
    output was removed, 130-150 ms with it still cached), so without the first run the
    first counted one paid more.

    Beside them, the cores each kept busy (CPU time over wall time): one job at a time
    already keeps more than one core busy (its writer threads format the output while
    the pipeline computes the next blocks), which bounds what N at once can gain."""
    n = cores()
    if n < 2:
        return [Figure("replay", "batch on all cores: this machine has one core", 1, "core")]
    trace_path = tmp / "minute.csv"
    write_trace(trace_path, human_trace(60.0))
    manifest = tmp / "batch.csv"
    manifest.write_text("scene,trace\n" + f"{SCENE},{trace_path}\n" * jobs)
    _batch_run(tmp, manifest, n)
    runs: dict[int, list[ProcessRun]] = {1: [], n: []}
    for pair in range(BATCH_PAIRS):
        for workers in ((1, n) if pair % 2 == 0 else (n, 1)):
            runs[workers].append(_batch_run(tmp, manifest, workers))
    return _batch_pair_figures(jobs, runs[1], runs[n], n)


def _batch_pair_figures(jobs: int, one: list[ProcessRun], many: list[ProcessRun],
                        n: int) -> list[Figure]:
    """``_batch_figures``' figures from the runs one after another (``one``) and ``n`` at
    once (``many``), pair k at index k: a pair where either run failed is left out of
    the ratios, the others keep their numbers, and the labels say how many failed."""
    pairs = [(k, a, b) for k, (a, b) in enumerate(zip(one, many))
             if a.code == 0 and b.code == 0]
    ratios = {k: a.wall_s / b.wall_s for k, a, b in pairs}
    claim = ratio_claim(list(ratios.values()), BATCH_TARGET, at_most=False)
    runs = {1: one, n: many}
    rates = {w: jobs / median(r, "wall_s") for w, r in runs.items()}
    busy = {w: median(r, "cpu_s") / median(r, "wall_s") for w, r in runs.items()}
    figures = [Figure("replay", f"batch of {jobs} one-minute jobs, one after another "
                      f"({medians_of(one)})", rates[1], "jobs/s"),
               Figure("replay", f"batch of {jobs} one-minute jobs, {n} at once "
                      f"({medians_of(many)})", rates[n], "jobs/s")]
    against = f"batch throughput, {n} cores against one after another"
    figures += [Figure("replay", f"{against}, pair {k + 1}", r, "x") for k, r in ratios.items()]
    failed = len(one) - len(pairs)
    note = failed_note(failed, len(one))
    figures += [claim.figure("replay", against, BATCH_TARGET, at_most=False, note=note),
                Figure("replay", "batch one after another: cores kept busy (CPU / wall)",
                       busy[1], "cores"),
                Figure("replay", f"batch {n} at once: cores kept busy (CPU / wall)", busy[n],
                       f"of {n}")]
    return [f.of_failed(failed) for f in figures]


def _batch_run(tmp: Path, manifest: Path, workers: int) -> ProcessRun:
    """``frictex batch MANIFEST --jobs WORKERS`` as a whole process (its wall and CPU
    time; a failed run counts in no median); its output (2.5 GB for 64 jobs) is removed
    afterwards."""
    out = tmp / f"b{workers}"
    done = run_process(frictex_argv("batch", str(manifest), "--out", str(out), "--jobs",
                                    str(workers), "--quiet"))
    shutil.rmtree(out, ignore_errors=True)
    return done


def _one_second_figure(tmp: Path, trace_path: Path, runs: int = 5) -> Figure:
    """The median wall time (s) of ``runs`` one-second replays of ``trace_path`` to CSV,
    one after another (not alternated with anything), its output folder removed before
    each run (untimed, so that no run overwrites the one before), over the runs that
    succeeded (the label says how many failed)."""
    out = tmp / "one-second-csv"
    done = []
    for _ in range(runs):
        shutil.rmtree(out, ignore_errors=True)
        done.append(run_process(frictex_argv("replay", SCENE, str(trace_path), "--out",
                                             str(out), "--format", "csv", "--quiet")))
    failed = sum(r.code != 0 for r in done)
    return Figure("replay", "one-second replay to CSV, whole process, one run after another, "
                  f"its output folder removed before each (median of {runs}"
                  f"{failed_note(failed, runs)})", median(done, "wall_s"), "s", failed)


def run(quick: bool) -> list[Figure]:
    long_s = 60.0 if quick else 600.0
    figures = []
    with tempfile.TemporaryDirectory(prefix="frictex-bench-") as name:
        tmp = Path(name)
        for duration in (long_s, long_s / 10):
            path = tmp / f"human-{duration:g}.csv"
            write_trace(path, human_trace(duration))
            for fmt in ("csv", "npz", "parquet"):
                figures += _replay_figures(tmp, f"one finger {duration:g} s", SCENE, path, fmt,
                                           duration)
        layers = tmp / "every-layer"
        layers.mkdir()
        new_layer_scene(layers)  # writes scene.toml and its files there
        path = tmp / f"every-layer-{long_s:g}.csv"
        write_trace(path, human_trace(long_s))
        for fmt in ("csv", "parquet"):
            figures += _replay_figures(tmp, f"every issue-18 layer {long_s:g} s",
                                       str(layers / "scene.toml"), path, fmt, long_s)
        two = _repeated(read_trace(resolve_trace(MODAL_TRACE)), 5 if quick else 20)
        path = tmp / "two-fingers.csv"
        write_trace(path, two)
        for fmt in ("csv", "parquet"):
            figures += _replay_figures(tmp, f"two fingers modal {two.duration_s:.0f} s",
                                       MODAL_SCENE, path, fmt, two.duration_s)
        one = tmp / "one-second.csv"
        write_trace(one, human_trace(1.0))
        figures.append(_one_second_figure(tmp, one))
        figures += _batch_figures(tmp, 16 if quick else 64)
    return figures
