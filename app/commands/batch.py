"""``frictex batch MANIFEST --out DIR``: many replays, over this machine's cores or a cluster.

The manifest's grammar is in ``app.engine.batch``. Exit status: 0 every job finished,
1 some jobs failed (each is listed with its error, and in ``DIR/batch.csv``), 2 the
manifest or an option is bad (nothing ran).
"""

from __future__ import annotations

import argparse
import sys
from functools import partial
from pathlib import Path

from frictex.app.commands.argtypes import positive_int
from frictex.app.engine.batch import read_manifest, run_job, write_results
from frictex.app.engine.fanout import default_workers, fan_out
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
                             "on every worker")
    parser.add_argument("--quiet", action="store_true", help="no progress bar")
    add_allow_outside(parser)


def run(args: argparse.Namespace) -> int:
    jobs = read_manifest(Path(args.manifest), render_modes())
    out_dir = Path(args.out)
    out_dir.mkdir(parents=True, exist_ok=True)
    from tqdm import tqdm
    bar = tqdm(total=len(jobs), desc="batch", unit="job", disable=True if args.quiet else None)

    def done(row: dict) -> None:
        bar.update(1)
        if row["status"] != "ok":
            bar.write(f"frictex: job {row['name']} failed: {row['error']}", file=sys.stderr)

    try:
        rows = fan_out(partial(run_job, out_dir=str(out_dir.resolve())), jobs,
                       workers=args.jobs or default_workers(), scheduler=args.scheduler,
                       on_done=done)
    finally:
        bar.close()
    table = write_results(out_dir, rows)
    failed = [row for row in rows if row["status"] != "ok"]
    output_s = sum(row["output_s"] for row in rows)
    wall_s = sum(row["wall_s"] for row in rows)
    if not args.quiet:
        print(f"{len(rows) - len(failed)} of {len(rows)} jobs finished ({output_s:.1f} s of "
              f"output, {wall_s:.1f} s of job time); results in {table}")
    if failed:
        print(f"frictex: error: {len(failed)} of {len(rows)} jobs failed: "
              + "; ".join(f"{row['name']}: {row['error']}" for row in failed), file=sys.stderr)
        return 1
    return 0
