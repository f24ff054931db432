"""``frictex report``: speed against error over a matrix of scenes, motions, touch rates
and renderer configurations (see ``app.measure.report_matrix`` for what a row measures,
``app.measure.report_doc`` for report.json, ``app.measure.report_markdown`` for report.md,
``app.measure.report_output`` for the plots and ``app.measure.report_claims`` for the
checked targets),
and closed-loop friction over a simulated population of fingers on the chosen scenes it
covers (``app.measure.report_closed_loop``), fanned out the same way.

    frictex report --quick --out report/     # CI: a few minutes on one core
    frictex report --out report/             # the full matrix

Exit status: 0 the report was written (whatever its claims say: report.md lists each
claim as holding, not holding or not shown); with ``--strict``, 1 when any claim does
not hold or is not shown; 2 bad options.
"""

from __future__ import annotations

import argparse
import os
import sys
import time
from dataclasses import asdict
from functools import partial
from pathlib import Path

from frictex.app.commands.argtypes import positive_int
from frictex.app.engine.fanout import default_workers, fan_out
from frictex.app.measure import report_matrix as rm
from frictex.app.measure.tail import P99_SAMPLES
from frictex.device.errors import InputError, disk_full
from frictex.rendering.pipeline import BLOCK_S

#: seconds of live 5 ms blocks timed per case (``--quick``: the fewest blocks whose
#: 99th percentile is not simply their largest, ``app.measure.tail``; 0.5 s gave 100)
LIVE_S, QUICK_LIVE_S = 2.0, P99_SAMPLES * BLOCK_S


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--out", default="report", metavar="DIR",
                        help="folder for report.md, report.json and the plots (default: report)")
    parser.add_argument("--quick", action="store_true",
                        help="the small matrix (three motions at 50 Hz touch, the human "
                             "motion also at 120 and 240 Hz; on the gratings a 2-20 kHz "
                             "output-rate sweep and LUT inversion runs), half the draws "
                             "and 4 s closed-loop runs: a few minutes")
    parser.add_argument("--scenes", nargs="+", metavar="NAME", default=list(rm.SCENES),
                        help=f"the matrix's scenes to include, some of {' '.join(rm.SCENES)}, "
                             "each once (default: all of them)")
    parser.add_argument("--jobs", type=positive_int, default=None, metavar="N",
                        help="cases at once over this machine's cores (default: all of them; "
                             "report.json records it: timing figures measured N at a time)")
    parser.add_argument("--scheduler", metavar="ADDRESS", default=None,
                        help="run the matrix on a Dask cluster instead (pip install "
                             "'frictex[cluster]')")
    parser.add_argument("--real", metavar="DIR", default=None,
                        help="also replay the touch recordings in DIR (getevent logs, evemu "
                             "recordings, trace CSVs; searched recursively) in a section of "
                             "their own, e.g. ../shared/refdata/android-getevent")
    parser.add_argument("--loop-delays", metavar="FILE", default=None,
                        help="the closed-loop runs replay the force-report delays recorded in "
                             "FILE (a report.json, or its closed_loop.report_delays object) "
                             "instead of measuring this machine's link: the same FILE gives "
                             "the same closed-loop figures")
    parser.add_argument("--strict", action="store_true",
                        help="exit 1 when any claim does not hold or is not shown "
                             "(default: exit 0 once the report is written)")
    parser.add_argument("--no-progress", action="store_true", help="no progress bar")


def run(args: argparse.Namespace) -> int:
    """Write the report into ``--out``; a run stopped (a signal, an error) before it wrote
    anything there removes the folders it made for it (a SIGTERM left them empty)."""
    out = Path(args.out).absolute()
    made = [folder for folder in (out, *out.parents) if not folder.exists()]
    try:
        return _write_report(args)
    except BaseException:
        for folder in made:  # the folders it made, deepest first, while they are empty
            if not folder.is_dir() or any(folder.iterdir()):
                break
            folder.rmdir()
        raise


def _write_report(args: argparse.Namespace) -> int:
    start = time.perf_counter()
    load_at_start = os.getloadavg()[0]
    out, real_dir = _checked(args)
    from frictex.app.measure.report_claims import count_line
    from frictex.app.measure.report_doc import Report, Timing, headline
    from frictex.app.measure.report_markdown import write_markdown
    jobs = args.jobs or default_workers()
    timings = {}
    rows, settings = _timed(timings, "matrix", lambda: _matrix(args, jobs))
    draws, real, modal, modal_replay, end_to_end = _beside_the_matrix(args, jobs, real_dir,
                                                                      timings)
    closed_loop = _timed(timings, "closed loop", lambda: _closed_loop(args, jobs))
    timings["whole report"] = Timing(time.perf_counter() - start,
                                     (load_at_start, os.getloadavg()[0]))
    doc = Report(quick=args.quick, settings=settings, rows=rows,
                 claims=_claims(draws, closed_loop), headline=headline(rows),
                 modal_replay=modal_replay, draws=draws, real=real, modal_inversion=modal,
                 end_to_end=end_to_end, closed_loop=closed_loop, timings=timings)
    doc.write(out / "report.json")
    plots = _plots(doc, out)
    write_markdown(doc, out / "report.md", plots)
    failed = [c for c in doc.claims if not c.passed]
    print(f"frictex report: {len(rows)} rows of the matrix in {settings.wall_s:.1f} s, the "
          f"whole report in {time.perf_counter() - start:.0f} s (its files written); "
          f"{count_line(doc.claims)}; "
          f"wrote {out / 'report.md'}, {out / 'report.json'}, {', '.join(plots)}")
    if failed and args.strict:
        print(f"frictex: error: {len(failed)} claims do not hold or are not shown (--strict): "
              + "; ".join(f"{c.verdict}: {c.scene} {c.motion} {c.metric}: {c.text}"
                          for c in failed[:3])
              + ("; ..." if len(failed) > 3 else ""), file=sys.stderr)
        return 1
    return 0


def _timed(timings: dict, section: str, measure):
    """``measure()``'s result; its wall time and the machine's 1-minute load before and
    after it go into ``timings[section]`` (``report_doc.Timing``)."""
    from frictex.app.measure.report_doc import Timing
    load_before, wall = os.getloadavg()[0], time.perf_counter()
    result = measure()
    timings[section] = Timing(time.perf_counter() - wall, (load_before, os.getloadavg()[0]))
    return result


def _checked(args: argparse.Namespace) -> tuple[Path, Path | None]:
    """The output folder, made (fail now, not after the matrix has run), and the folder
    of real recordings (None without ``--real``; one without recordings fails now)."""
    _check_scenes(args.scenes)
    out = Path(args.out)
    if out.exists() and not out.is_dir():
        raise InputError(f"--out {out}: exists and is not a folder")
    real_dir = None
    if args.real is not None:
        from frictex.app.measure.report_real import recordings
        real_dir = Path(args.real)
        recordings(real_dir)
    if args.loop_delays is not None:  # a file that holds no delays fails now
        from frictex.app.measure import report_closed_loop as rcl
        from frictex.app.measure.link_report_delays import read
        read(args.loop_delays, rcl.RATE_HZ, rcl.BLOCK)
    try:
        out.mkdir(parents=True, exist_ok=True)
    except OSError as exc:
        said = f"--out {out}: cannot make the report folder ({exc.strerror})"
        raise disk_full(exc, said) or InputError(said) from None
    return out, real_dir


def _check_scenes(scenes: list[str]) -> None:
    """Refuse a scene outside the matrix's, and one named twice (its draws would count
    twice in every claim's interval)."""
    outside = [s for s in scenes if s not in rm.SCENES]
    if outside:
        raise InputError(f"--scenes: {', '.join(outside)} {'is' if len(outside) == 1 else 'are'} "
                         f"not among the report's scenes; give some of {', '.join(rm.SCENES)}")
    repeated = next((s for i, s in enumerate(scenes) if s in scenes[:i]), None)
    if repeated is not None:
        raise InputError(f"--scenes: {repeated} given twice; give each scene once")


def _matrix(args: argparse.Namespace, jobs: int):
    """The matrix's rows, fanned out, and the report's settings."""
    from frictex.app.engine.progress import progress_bar

    from frictex.app.measure.report_doc import Settings
    from frictex.device.friction import make_friction_model
    from frictex.rendering.inversion_lut import LutFrictionModel

    cases = rm.matrix(args.quick, tuple(args.scenes))
    wall = time.perf_counter()
    load_before = os.getloadavg()[0]
    bar = progress_bar(total=len(cases), desc="report", unit="case",
                       disable=args.no_progress or None)
    try:
        rows = fan_out(partial(rm.run_case, live_s=QUICK_LIVE_S if args.quick else LIVE_S), cases,
                       workers=jobs, scheduler=args.scheduler, on_done=lambda row: bar.update(1))
    finally:
        bar.close()
    lut = LutFrictionModel(make_friction_model(rm.load(args.scenes[0]).device))
    return rows, Settings(reference_hz=rm.REFERENCE_HZ, touch_noise_mm=rm.TOUCH_NOISE_MM,
                          block_s=BLOCK_S, motions=rm.MOTIONS,
                          lut_max_error_um=lut.max_error_um(), cpu_count=os.cpu_count(),
                          jobs=None if args.scheduler else jobs, scheduler=args.scheduler,
                          wall_s=time.perf_counter() - wall,
                          load_1min=(load_before, os.getloadavg()[0]))


def _beside_the_matrix(args: argparse.Namespace, jobs: int, real_dir: Path | None,
                       timings: dict):
    """The draws behind the claims, the real recordings' section (None without
    ``--real``), the modal inversion's figures, two fingers with modal actuation in
    replay, and whole replays end to end; each section's wall time and load into
    ``timings`` (``_timed``)."""
    from frictex.app.measure import bench_modal, report_seeds
    from frictex.app.measure.bench_pipeline import modal_throughput
    from frictex.app.measure.bench_replay import end_to_end
    modal = _timed(timings, "modal inversion",
                   lambda: [asdict(f) for f in bench_modal.run(args.quick)])
    gratings = [s for s in args.scenes if s in report_seeds.GRATINGS]
    draws = _timed(timings, "draws", lambda: report_seeds.draws(
        report_seeds.QUICK_DRAWS if args.quick else report_seeds.DRAWS, gratings,
        workers=jobs, scheduler=args.scheduler))
    real = None
    if real_dir is not None:
        from frictex.app.measure.report_real import real_section
        real = _timed(timings, "real recordings", lambda: real_section(real_dir, gratings))
    modal_replay = _timed(timings, "modal replay", modal_throughput)
    whole = _timed(timings, "end to end", lambda: end_to_end(20.0 if args.quick else 120.0))
    return draws, real, modal, modal_replay, whole


def _claims(draws, closed_loop) -> list:
    """The draws' claims, then the closed-loop section's (if run)."""
    from frictex.app.measure.report_claims import claims
    found = claims(draws)
    if closed_loop is not None:
        from frictex.app.measure.report_closed_loop import claims as loop_claims
        found += loop_claims(closed_loop)
    return found


def _plots(doc, out: Path) -> list[str]:
    """Write the plots into ``out``; their file names."""
    from frictex.app.measure import report_output as ro
    plots = {"error_vs_cost.png": ro.cost_figure(doc.rows),
             "error_vs_period.png": ro.period_figure(doc.rows)}
    if doc.closed_loop is not None:
        from frictex.app.measure.report_closed_loop import figure as loop_figure
        plots["closed_loop.png"] = loop_figure(doc.closed_loop)
    for name, fig in plots.items():
        ro.save(fig, out / name)
    return list(plots)


def _closed_loop(args: argparse.Namespace, jobs: int):
    """The closed-loop section (``report_loop_records.LoopSection``) on the chosen scenes
    it covers (None if it covers none), fanned out like the matrix."""
    from frictex.app.engine.progress import progress_bar

    from frictex.app.measure import report_closed_loop as rcl
    if not any(s in rcl.SCENES for s in args.scenes):
        return None
    delays = None
    if args.loop_delays is not None:
        from frictex.app.measure.link_report_delays import read
        delays = read(args.loop_delays, rcl.RATE_HZ, rcl.BLOCK)
    bar = progress_bar(total=rcl.runs_in(args.quick, args.scenes), desc="closed loop",
                       unit="run", disable=args.no_progress or None)
    try:
        return rcl.section(args.quick, workers=jobs, scenes=args.scenes,
                           scheduler=args.scheduler, on_done=lambda result: bar.update(1),
                           delays=delays)
    finally:
        bar.close()
