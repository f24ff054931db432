"""``frictex bench startup``: what each command costs as a whole process.

Every command a user types, each in a fresh process from the interpreter's start to its
exit (``app.measure.processes``): ``--version``, ``library``, ``validate``, and a
one-second replay into each output format, beside two floors measured in the same rounds:
the interpreter alone (``python -c pass``) and the interpreter importing numpy. The
commands run alternated, one of each per round (15 rounds; 5 with ``--quick``), and each
figure is the median over the rounds: wall time (what a user waits) and user + system
CPU (what the machine's load does not change much); ``frictex bench`` prints the
machine's load before and after. ``python -X importtime -m frictex ...`` says where a command's
start-up goes.

Python keeps each module's bytecode in ``__pycache__`` and compiles a module again only
where that cache is missing or older than its source. With ``PYTHONDONTWRITEBYTECODE``
set it writes no cache, so after frictex's sources change (an edit, a checkout) every
command compiles the changed modules again, each time. The section measures what that
costs at most: the one-second Parquet replay once more in the same rounds, with the
cache of every module but frictex's (``python -B -X pycache_prefix=DIR``, DIR filled by
one untimed run, frictex's part then removed): the mean of the rounds' differences
(without the cache less with it, in the same round) and its 95 % interval. It warns
where the variable is set. Each replay writes into an output folder of its own, removed
before each of its runs (untimed), so that no run writes over another's files.

Targets (issue 31): ``frictex --version`` under 0.15 s; a one-second replay under 0.5 s
of wall time on a quiet machine. Each gets a verdict from its own runs' wall times
(``ratio_claim.time_claim``: their geometric mean and its 95 % interval against the
bound; holds only where the whole interval is under it), one per output format.
"""

from __future__ import annotations

import importlib
import os
import shutil
import subprocess
import sys
import tempfile
from pathlib import Path

from frictex.app.measure.bench_replay import SCENE, human_trace
from frictex.app.measure.figure import Figure
from frictex.app.measure.ratio_claim import time_claim
from frictex.app.measure.processes import (Run, alternated, failed_note, frictex_argv, median,
                                           medians_of)
from frictex.app.measure.report_claims import paired
from frictex.rendering.input.trace_file import write_trace

#: the row of the one-second Parquet replay without frictex's bytecode cache
NO_CACHE = "frictex replay, one second, parquet, without frictex's bytecode cache"

#: wall time each command is to stay under (s), issue 31
TARGETS_S = {"frictex --version": 0.15, **{f"frictex replay, one second, {fmt}": 0.5
                                          for fmt in ("parquet", "npz", "csv")}}


def commands(tmp: Path) -> tuple[dict[str, list[str]], dict[str, Path]]:
    """(name -> argv of every command timed, the floors first; name -> the output folder
    of each replay, its own, to be removed before each of its runs: :func:`emptied`)."""
    trace = tmp / "one-second.csv"
    write_trace(trace, human_trace(1.0))
    found = {"python -c pass (floor)": [sys.executable, "-c", "pass"],
             "python -c 'import numpy' (floor)": [sys.executable, "-c", "import numpy"],
             "frictex --version": frictex_argv("--version"),
             "frictex library": frictex_argv("library"),
             "frictex validate grating-5mm": frictex_argv("validate", "grating-5mm")}
    outputs = {}
    for fmt in ("parquet", "npz", "csv"):
        name = f"frictex replay, one second, {fmt}"
        outputs[name] = tmp / f"out-{fmt}"
        found[name] = replay_argv(trace, outputs[name], fmt)
    outputs[NO_CACHE] = tmp / "out-parquet-no-cache"
    found[NO_CACHE] = without_frictex_cache(replay_argv(trace, outputs[NO_CACHE], "parquet"),
                                            tmp / "pycache")
    return found, outputs


def replay_argv(trace: Path, out: Path, fmt: str) -> list[str]:
    """``frictex replay`` of the bench scene and ``trace`` into ``out`` in format ``fmt``."""
    return frictex_argv("replay", SCENE, str(trace), "--out", str(out), "--format", fmt,
                        "--quiet")


def emptied(outputs: dict[str, Path]):
    """A ``before(name)`` for ``alternated``: removes command ``name``'s output folder,
    where it has one, so that no run writes over an earlier one's files."""
    def before(name: str) -> None:
        if name in outputs:
            shutil.rmtree(outputs[name], ignore_errors=True)
    return before


def without_frictex_cache(argv: list[str], prefix: Path) -> list[str]:
    """``argv`` (a frictex command) as a command that finds the bytecode cache of every
    module in ``prefix`` except frictex's own, and writes none: it runs once here
    (untimed, writing its cache even where ``PYTHONDONTWRITEBYTECODE`` is set) to fill
    ``prefix``, whose frictex part is then removed."""
    env = {k: v for k, v in os.environ.items() if k != "PYTHONDONTWRITEBYTECODE"}
    subprocess.run([argv[0], "-X", f"pycache_prefix={prefix}", *argv[1:]], env=env,
                   stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL, check=False)
    # every frictex module, the top package (app/api) too, lies under these
    roots = {Path(p) for layer in ("app", "rendering", "textures", "device")
             for p in importlib.import_module(f"frictex.{layer}").__path__}
    for root in roots:
        shutil.rmtree(prefix / root.resolve().relative_to("/"), ignore_errors=True)
    return [argv[0], "-B", "-X", f"pycache_prefix={prefix}", *argv[1:]]


def run(quick: bool) -> list[Figure]:
    if os.environ.get("PYTHONDONTWRITEBYTECODE"):
        print("frictex: bench startup: PYTHONDONTWRITEBYTECODE is set, so Python writes no "
              "bytecode cache, and a command whose frictex modules changed since their "
              "cache was written compiles them again each time (up to the 'bytecode "
              "cache' figure below); unset it for the start-up a user gets", file=sys.stderr)
    rounds = 5 if quick else 15
    with tempfile.TemporaryDirectory(prefix="frictex-startup-") as name:
        found, outputs = commands(Path(name))
        runs = alternated(found, rounds, before=emptied(outputs))
    return startup_figures(runs)


def startup_figures(runs: dict[str, list[Run]]) -> list[Figure]:
    """Per command its median wall and CPU time over its runs that succeeded, each label
    counting them, the verdict on its target where it has one (``target_figure``), and
    the bytecode cache's cost (``cache_cost_figure``)."""
    figures = []
    for label, got in runs.items():
        failed = sum(r.code != 0 for r in got)
        figures += [Figure("startup", f"{label}, wall ({medians_of(got)}, alternated)",
                           median(got, "wall_s"), "s", failed),
                    Figure("startup", f"{label}, CPU user + system ({medians_of(got)})",
                           median(got, "cpu_s"), "s", failed)]
        if label in TARGETS_S:
            figures.append(target_figure(label, got, TARGETS_S[label]))
    return figures + [cache_cost_figure(runs[NO_CACHE],
                                        runs["frictex replay, one second, parquet"])]


def target_figure(label: str, got: list[Run], bound_s: float) -> Figure:
    """The verdict on "``label`` under ``bound_s`` of wall time" from the wall times of its
    runs that succeeded (``time_claim``), the failed ones counted in the label."""
    seconds = [r.wall_s for r in got if r.code == 0]
    failed = len(got) - len(seconds)
    return time_claim(seconds, bound_s).figure(
        "startup", f"{label}, wall time per run (alternated)", bound_s, at_most=True,
        note=failed_note(failed, len(got)), unit=" s", of="runs").of_failed(failed)


def cache_cost_figure(without: list[Run], cached: list[Run]) -> Figure:
    """What a one-second Parquet replay pays without frictex's bytecode cache (ms): per
    round the wall time without it less the one with it (the two ran in the same round),
    over the rounds where both succeeded, the mean of those differences and its 95 %
    interval (Student's t, ``report_claims.paired``)."""
    both = [(w.wall_s, c.wall_s) for w, c in zip(without, cached) if w.code == 0 == c.code]
    mean, low, high, n = paired([w for w, _ in both], [c for _, c in both])
    note = failed_note(len(without) - n, len(without))
    interval = (f"95 % interval {low * 1e3:.1f} to {high * 1e3:.1f} ms" if n > 1
                else "no interval under two rounds")
    return Figure("startup", "frictex's bytecode cache, what a one-second Parquet replay pays "
                  f"without it (mean of {n} paired rounds' differences{note})", mean * 1e3,
                  f"ms ({interval})", len(without) - n)
