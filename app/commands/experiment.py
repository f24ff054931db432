"""``frictex experiment PROTOCOL --participant ... --out DIR`` runs a session;
``frictex experiment analyse SESSION [SESSION ...]`` fits and plots sessions of a study.

The protocol format: ``app/experiment/PROTOCOL_FORMAT.md``; the session folder:
``app/experiment/session.py``; the analysis: ``app/experiment/analysis.py``.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from frictex.device.errors import InputError

RECORD_HELP = ("per trial, 'all': the scene, the touch trace and their replay (what was "
               "sent to the device); 'traces': scene and trace; 'results': the results "
               "table only (default all)")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("target", nargs="+", metavar="PROTOCOL | analyse SESSION",
                        help="a protocol file (.toml) to run, or 'analyse' and session folders")
    parser.add_argument("--participant", metavar="NAME:OPTIONS", default=None,
                        help="who answers: 'simulated:weber=0.11,lapse=0.02[,seed=N]"
                             "[,stroke_s=S]' is a simulated participant (headless)")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="the session folder (run), or where analysis.json and "
                             "analysis.png go (analyse; default: SESSION/analysis)")
    parser.add_argument("--resume", action="store_true",
                        help="go on with the session in --out where it stopped")
    parser.add_argument("--seed", type=int, default=None,
                        help="trial order seed (default: the protocol's, else drawn; recorded)")
    parser.add_argument("--record", choices=("all", "traces", "results"), default="all",
                        help=RECORD_HELP)
    parser.add_argument("--check", action="store_true",
                        help="only check the protocol file and list its trials' count")
    parser.add_argument("--no-plot", action="store_true", help="analyse: no analysis.png")
    parser.add_argument("--quiet", action="store_true", help="no line per trial")


def _analyse(args: argparse.Namespace) -> int:
    from frictex.app.experiment.analysis import analyse, report_lines
    folders = args.target[1:]
    if not folders:
        raise InputError("analyse: give one or more session folders")
    out = Path(args.out) if args.out else Path(folders[0]) / "analysis"
    for summary in analyse(folders, out, plot=not args.no_plot):
        print("\n".join(report_lines(summary)))
    print(f"wrote {out / 'analysis.json'}" + ("" if args.no_plot else f" and {out / 'analysis.png'}"))
    return 0


def run(args: argparse.Namespace) -> int:
    if args.target[0] == "analyse":
        return _analyse(args)
    if len(args.target) != 1:
        raise InputError(f"expected one protocol file, got {len(args.target)} arguments "
                         f"(to analyse sessions: frictex experiment analyse SESSION ...)")
    from frictex.app.experiment.protocol import load_protocol
    protocol = load_protocol(args.target[0])
    if args.check:
        from frictex.app.experiment.scheduler import Scheduler
        scheduler = Scheduler(protocol, protocol.seed or 0)
        count = (f"{len(scheduler.practice)} practice and {len(scheduler.plan)} main trials"
                 if scheduler.plan is not None else
                 f"{len(scheduler.practice)} practice trials, then a staircase of at most "
                 f"{protocol.staircase.max_trials} trials")
        print(f"{args.target[0]}: {protocol.name}, {protocol.method}: {count}")
        return 0
    if args.out is None:
        raise InputError("--out DIR is required: the session folder")
    if args.participant is None and not args.resume:
        raise InputError("--participant is required, e.g. --participant "
                         "simulated:weber=0.11,lapse=0.02")
    from frictex.app.experiment.runner import make_presenter, run_session
    from frictex.app.experiment.session import read_info
    spec = args.participant if args.participant is not None else read_info(Path(args.out))["participant"]
    presenter = make_presenter(spec)

    def progress(trial, row):
        if not args.quiet:
            kind = "practice" if trial.practice else "trial"
            print(f"{kind} {trial.number}: {' vs '.join(trial.stimuli)} -> {row['response']}"
                  f"{'' if row['correct'] == '' else (' (correct)' if row['correct'] else ' (wrong)')}",
                  flush=True)

    session = run_session(protocol, presenter, args.out, seed=args.seed, participant=spec,
                          resume=args.resume, record=args.record, progress=progress)
    print(f"{len(session.rows)} trials in {args.out}/results.csv (seed {session.seed}); "
          f"analyse with: frictex experiment analyse {args.out}", file=sys.stderr)
    return 0
