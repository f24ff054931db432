"""``frictex batch MANIFEST --out DIR``: many replays, over this machine's cores or a cluster.

The manifest's grammar, ``batch.csv``'s columns, what ``DIR`` may hold and what a
signal does are in ``app.engine.batch``. Exit status: 0 every job finished, 1 some jobs
failed (each is listed with its error, and in ``DIR/batch.csv``) or a Dask cluster had
no worker for ``fanout.NO_WORKER_S`` or lost its scheduler (the jobs left are
``interrupted``, the finished ones kept), 2 the
manifest, an option or ``DIR`` is bad (nothing ran), 130 Ctrl-C (128 + the signal for
SIGTERM, SIGHUP) stopped it (``DIR/batch.csv`` lists the jobs that finished).
"""

from __future__ import annotations

import argparse
import signal
import sys
from functools import partial
from pathlib import Path

from frictex.app.commands.argtypes import positive_int
from frictex.app.engine.batch import RESULTS, not_ok, read_manifest, run_job
from frictex.app.engine.batch_folder import BatchFolder, kept_folder
from frictex.app.engine.driver import Terminated
from frictex.app.engine.fanout import (NO_WORKER_S, ClusterGone, Interrupted, default_workers,
                                       fan_out)
from frictex.rendering.renderers import render_modes
from frictex.textures.outside import add_allow_outside


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("manifest", help="CSV of jobs: scene,trace[,renderer][,rate_hz]"
                                         "[,block][,format][,name] (see README)")
    parser.add_argument("--out", required=True, metavar="DIR",
                        help="output folder: one subfolder per job, and batch.csv")
    parser.add_argument("--jobs", type=positive_int, default=None, metavar="N",
                        help="replays at once on this machine (default: its cores)")
    parser.add_argument("--scheduler", metavar="ADDRESS", default=None,
                        help="run on a Dask cluster (e.g. tcp://10.0.0.5:8786) instead; needs "
                             "pip install 'frictex[cluster]' and the files at the same paths "
                             "on every worker; a cluster with no worker for "
                             f"{NO_WORKER_S:.0f} s, or whose scheduler is lost, gives up "
                             "the jobs left (exit 1)")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    add_allow_outside(parser)


def run(args: argparse.Namespace) -> int:
    jobs = read_manifest(Path(args.manifest), render_modes())
    out_dir = Path(args.out)
    folder = BatchFolder(out_dir, [job.name for job in jobs])
    staged = folder.begin()
    try:
        rows, stop = _run_jobs(args, jobs, staged)
        rows, users = folder.commit(rows, stopped=stop is not None)
    except BaseException:
        folder.abort()
        raise
    for name in users:
        print(f"frictex: warning: {out_dir / name}: an earlier batch's job folder that also "
              "holds files not a run's output; left as it was", file=sys.stderr)
    return _report(args, rows, stop, out_dir / RESULTS)


def _report(args: argparse.Namespace, rows: list[dict], stop, table: Path) -> int:
    """The batch's last lines and exit status (module docstring); a stopped batch ends as
    an interrupted replay does (``KeyboardInterrupt``; or ``Terminated``, printed as
    ``frictex: terminated by SIGTERM``, exit 128 + the signal); one given up for want of
    Dask workers or its scheduler raises its :class:`ClusterGone` (one error line, exit 1)."""
    signalled = isinstance(stop, Interrupted)
    if not args.quiet or signalled:
        print(_totals(rows, table), file=sys.stderr if signalled else sys.stdout)
    if isinstance(stop, ClusterGone):
        raise stop
    if signalled:
        if stop.signum == signal.SIGINT:
            raise KeyboardInterrupt
        raise Terminated(stop.signum)  # the line and status a replay's SIGTERM gives
    failed = [row for row in rows if row["status"] == "failed"]
    if failed:
        print(f"frictex: error: {len(failed)} of {len(rows)} jobs failed: "
              + "; ".join(f"{row['name']}: {row['error']}" for row in failed), file=sys.stderr)
        return 1
    return 0


def _totals(rows: list[dict], table: Path) -> str:
    """One line: how many jobs finished, their seconds of output and of wall time, and the
    earlier job folders a stopped batch kept."""
    ok = [row for row in rows if row["status"] == "ok"]
    jobs = [row for row in rows if row["job"] is not None]
    kept = sum(map(kept_folder, rows))
    return (f"{len(ok)} of {len(jobs)} jobs finished ({sum(r['output_s'] for r in ok):.1f} s "
            f"of output, {sum(r['wall_s'] for r in ok):.1f} s of job time)"
            + (f", {kept} earlier job folders kept" if kept else "") + f"; results in {table}")


def _run_jobs(args: argparse.Namespace, jobs: list, out_dir: Path):
    """The jobs' result rows, with a progress bar, and the :class:`Interrupted` or
    :class:`ClusterGone` that stopped them (None if none did; the jobs it kept from
    finishing then have rows ``interrupted``)."""
    from frictex.app.engine.progress import progress_bar
    bar = progress_bar(total=len(jobs), desc="batch", unit="job",
                       disable=True if args.quiet else None)

    def done(row: dict) -> None:
        bar.update(1)
        if row["status"] != "ok":
            bar.write(f"frictex: job {row['name']} failed: {row['error']}", file=sys.stderr)

    try:
        return fan_out(partial(run_job, out_dir=str(out_dir.resolve())), jobs,
                       workers=args.jobs or default_workers(), scheduler=args.scheduler,
                       on_done=done, on_lost=lambda job, why: not_ok(job, "failed", why),
                       noun="jobs"), None
    except (Interrupted, ClusterGone) as stop:
        return [row if row is not None else _interrupted(job, stop)
                for job, row in zip(jobs, stop.results)], stop
    finally:
        bar.close()


def _interrupted(job, stop: Interrupted | ClusterGone) -> dict:
    """The row of a job that ``stop`` kept from finishing."""
    if isinstance(stop, ClusterGone):
        return not_ok(job, "interrupted", f"not finished: {stop.why}")
    how = "stopped while it ran" if job.index in stop.stopped else "not started"
    return not_ok(job, "interrupted", f"{how}: the batch was stopped by "
                                      f"{signal.Signals(stop.signum).name}")
