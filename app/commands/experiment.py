"""``frictex experiment PROTOCOL --participant ... --out DIR`` runs a session;
``frictex experiment analyse SESSION [SESSION ...]`` fits and plots sessions of a study.

A window session the participant stops (Escape, closing the window) is one line saying
where it stopped and how to resume, exit 130 (as Ctrl-C); SIGTERM or SIGHUP stop it the
same way, ``frictex: terminated by SIGTERM at trial N ...``, exit 128 + the signal.

PROTOCOL is a protocol file or, when no file of that name exists, a bundled protocol's
name (``app.experiment.protocol.resolve_protocol``). The protocol format:
``app/experiment/PROTOCOL_FORMAT.md``; the session folder:
``app/experiment/session.py``; the analysis: ``app/experiment/analysis.py``.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

from frictex.device.errors import InputError

#: the exit status of a window session the participant stopped (Escape, the window
#: closed): 130, as for Ctrl-C; the answered trials are kept and --resume goes on
PAUSED_EXIT = 130
RECORD_HELP = ("per trial, 'all': the scene, the touch trace and their replay (what was "
               "sent to the device); 'traces': scene and trace; 'results': the results "
               "table only (default all; kept in session.json: --resume goes on with the "
               "session's own)")


def session_seed(text: str) -> int:
    """``--seed``: an integer from 0 to 2^63 - 1 (refused before anything is written)."""
    from frictex.app.experiment.scheduler import SEED_LIMIT
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if not 0 <= value < SEED_LIMIT:
        raise argparse.ArgumentTypeError(f"{text}: expected an integer from 0 to 2^63 - 1")
    return value


def add_arguments(parser: argparse.ArgumentParser) -> None:
    from frictex.app.experiment.protocol import protocol_names
    parser.add_argument("target", nargs="+", metavar="PROTOCOL | analyse SESSION",
                        help="a protocol file (.toml) to run, or the name of a bundled "
                             f"protocol ({', '.join(protocol_names())}; a file of that name "
                             "wins), or 'analyse' and session folders")
    parser.add_argument("--participant", metavar="NAME:OPTIONS", default=None,
                        help="who answers: 'window' is a person at the demo's window (on "
                             "--device, as frictex demo); 'simulated:weber=0.11,lapse=0.02"
                             "[,seed=N][,stroke_s=S]' is a simulated participant (headless; "
                             "its seed, the noise of its answers and its strokes, defaults "
                             "to one drawn from the session's --seed, so sessions of "
                             "different seeds are independent participants; recorded as "
                             "participant_seed in session.json)")
    parser.add_argument("--participant-id", metavar="ID", default=None,
                        help="the participant's code (a plain name such as P07), recorded in "
                             "session.json; checked against the session's on --resume")
    parser.add_argument("--out", metavar="DIR", default=None,
                        help="the session folder (run), or where analysis.json and "
                             "analysis.png go (analyse; default for one session: "
                             "SESSION/analysis; required for several)")
    parser.add_argument("--resume", action="store_true",
                        help="go on with the session in --out where it stopped")
    parser.add_argument("--seed", type=session_seed, default=None,
                        help="the session's seed, 0 to 2^63 - 1: the trial order and a "
                             "simulated participant's own seed (default: the protocol's, "
                             "else drawn; recorded)")
    parser.add_argument("--record", choices=("all", "traces", "results"), default=None,
                        help=RECORD_HELP)
    parser.add_argument("--check", action="store_true",
                        help="only check the protocol file and list its trials' count")
    parser.add_argument("--no-plot", action="store_true", help="analyse: no analysis.png")
    parser.add_argument("--quiet", action="store_true", help="no line per trial")
    from frictex.app.commands.argtypes import add_link_arguments
    from frictex.app.commands.preview import frame_size
    add_link_arguments(parser)
    from frictex.textures.outside import add_allow_outside
    add_allow_outside(parser)  # the protocol's scenes and the files they name
    parser.add_argument("--size", type=frame_size, default=None, metavar="WxH",
                        help="--participant window: the window's size in px (default: the "
                             "first stimulus's display size)")
    parser.add_argument("--haptic", choices=("process", "thread"), default="process",
                        help="--participant window: where the haptic pipeline runs (as "
                             "frictex demo --haptic)")
    parser.add_argument("--screenshots", metavar="DIR", default=None,
                        help="--participant window: folder for screenshots taken with P "
                             "(default: --out/screenshots)")


def _analyse(args: argparse.Namespace) -> int:
    from frictex.app.experiment.analysis import analyse, report_lines
    folders = args.target[1:]
    if not folders:
        raise InputError("analyse: give one or more session folders")
    from frictex.app.experiment.session import folder_of
    if args.out is None and len(folders) > 1:  # SESSION/analysis is that session's own
        raise InputError(f"analyse: {len(folders)} sessions are pooled; give --out DIR for "
                         f"their analysis (without it, each session's own goes to "
                         f"SESSION/analysis)")
    out = folder_of(args.out) if args.out is not None else Path(folders[0]) / "analysis"
    for summary in analyse(folders, out, plot=not args.no_plot):
        print("\n".join(report_lines(summary)))
    print(f"wrote {out / 'analysis.json'}" + ("" if args.no_plot else f" and {out / 'analysis.png'}"))
    return 0


def _in_window(args: argparse.Namespace, protocol, presenter, session):
    """``session()`` run in the demo's window on the live haptic side of ``--device``
    (``app.experiment.window_presenter``); its result."""
    from frictex.app.commands.argtypes import sim_device_args
    from frictex.app.commands.demo import _start_haptic
    from frictex.app.experiment.window_presenter import run_in_window
    from frictex.rendering.visual.context import NoDisplayError
    from frictex.rendering.visual.device_panels import default_frame_size
    from frictex.rendering.visual.windows import open_backend
    from frictex.textures.loader import load_scene
    if args.faults is not None and args.device is None:
        raise InputError("--faults needs --device: the faults are injected on the link to it")
    demo = argparse.Namespace(**vars(args), input=("mouse", None), renderer=None,
                              rate=10_000.0, block=50)
    sim_device_args(demo)  # a bad --sim-finger is refused before the window opens
    s = protocol.stimuli
    first = s.listed[0].scene if s.listed else s.scene
    scene = load_scene(first)
    out = Path(args.out)
    try:
        backend = open_backend("glfw", args.size or default_frame_size(scene),
                               title=f"frictex experiment: {protocol.name}", vsync=False)
    except NoDisplayError as exc:
        raise NoDisplayError(f"{exc}: a window participant needs one (run the session on the "
                             "machine with the display, or under xvfb-run to try it); "
                             "'--participant simulated:weber=0.11,lapse=0.02' runs the "
                             "protocol headless") from None
    return run_in_window(presenter, session, backend,
                         lambda sc, record: _start_haptic(demo, sc, Path(sc.source), record),
                         scene, out / "live", Path(args.screenshots or out / "screenshots"),
                         "none" if args.device is None else "starting")


def warn_staircase(protocol) -> None:
    """Say on stderr what keeps ``protocol``'s staircase, if any, from a threshold."""
    from frictex.app.experiment.protocol import staircase_warnings
    staircase = protocol.staircase
    for line in staircase_warnings(staircase, protocol.stimuli) if staircase else []:
        print(f"frictex: warning: {line}", file=sys.stderr)


def run(args: argparse.Namespace) -> int:
    if args.target[0] == "analyse":
        return _analyse(args)
    if len(args.target) != 1:
        raise InputError(f"expected one protocol file, got {len(args.target)} arguments "
                         f"(to analyse sessions: frictex experiment analyse SESSION ...)")
    from frictex.app.experiment.protocol import check_protocol, load_protocol, resolve_protocol
    path = resolve_protocol(args.target[0])
    if args.check:
        protocol, problems = check_protocol(path)
        if protocol is None:  # every problem, one line each, as frictex validate lists them
            from frictex.device.safe_text import printable
            for problem in problems:
                print(f"frictex: error: {printable(str(problem))}", file=sys.stderr)
            return 2
        from frictex.app.experiment.scheduler import Scheduler
        scheduler = Scheduler(protocol, protocol.seed or 0)
        count = (f"{len(scheduler.practice)} practice and {len(scheduler.plan)} main trials"
                 if scheduler.plan is not None else
                 f"{len(scheduler.practice)} practice trials, then a staircase of at most "
                 f"{protocol.staircase.max_trials} trials")
        print(f"{args.target[0]}: {protocol.name}, {protocol.method}: {count}")
        warn_staircase(protocol)
        return 0
    protocol = load_protocol(path)
    warn_staircase(protocol)
    if args.out is None:
        raise InputError("--out DIR is required: the session folder")
    from frictex.app.experiment.session import folder_of, participant_id
    out = folder_of(args.out)
    pid = participant_id(args.participant_id) if args.participant_id is not None else None
    if args.participant is None and not args.resume:
        raise InputError("--participant is required, e.g. --participant "
                         "simulated:weber=0.11,lapse=0.02")
    from frictex.app.experiment import window_presenter  # noqa: F401 (registers "window")
    from frictex.app.experiment.runner import make_presenter, run_session
    from frictex.app.experiment.session import read_info
    from frictex.app.engine.driver import between_runs
    spec = args.participant if args.participant is not None else read_info(out)["participant"]
    presenter = make_presenter(spec)

    def progress(trial, row):
        if not args.quiet:
            kind = "practice" if trial.practice else "trial"
            print(f"{kind} {trial.number}: {' vs '.join(trial.stimuli)} -> {row['response']}"
                  f"{'' if row['correct'] == '' else (' (correct)' if row['correct'] else ' (wrong)')}",
                  flush=True)

    def session():
        return run_session(protocol, presenter, out, seed=args.seed, participant=spec,
                           participant_id=pid, resume=args.resume, record=args.record,
                           progress=progress, between_trials=runs.check)

    with between_runs() as runs:
        if spec.partition(":")[0] == "window":
            from frictex.app.experiment.window_presenter import SessionPaused, stop_on_signals
            try:
                with stop_on_signals(presenter):
                    session = _in_window(args, protocol, presenter, session)
            except SessionPaused as exc:  # a planned stop: one line, exit 130 as for Ctrl-C
                print(f"frictex: session stopped at trial {exc.trial} ({exc.why}); resume "
                      f"with: frictex experiment {shlex.quote(args.target[0])} --out "
                      f"{shlex.quote(str(out))} --resume", file=sys.stderr)
                return PAUSED_EXIT
        else:
            session = session()
    if session.complete_before:
        print(f"{out}: the session is already complete ({len(session.rows)} trials); nothing "
              f"ran and session.json is left as it is; analyse with: frictex experiment "
              f"analyse {out}", file=sys.stderr)
        return 0
    print(f"{len(session.rows)} trials in {out / 'results.csv'} (seed {session.seed}); "
          f"analyse with: frictex experiment analyse {out}", file=sys.stderr)
    return 0
