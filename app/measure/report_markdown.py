"""``frictex report``'s ``report.md``: the document (``app.measure.report_doc.Report``) in
words and tables, one function per section. A table with nothing to show (the scenes
chosen with ``--scenes`` have no rows for it) is replaced by a sentence saying so.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from frictex.app.measure.quantile_claim import quantile_ranks
from frictex.app.measure.report_claims import (GRATINGS, METRICS, NOT_CLAIMED, OUTPUT_HZ,
                                                TOUCH_HZ, count_line, family_note)
from frictex.app.measure.report_doc import Report, grating_rows, mean_defined
from frictex.app.measure.report_matrix import (MOTIONS, WARM_UP_S, Row, aliased,
                                                aliasing_degenerate, link_buffer_s,
                                                periods_per_sample)
from frictex.rendering.metrics import ALIGNMENT_CAP_MM, PHASE_BLIND_HZ
from frictex.rendering.pipeline import BLOCK_S

PLATE_LOOP_HZ = 400.0  # seed 003, Fig. 3b: the amplitude loop's -3 dB bandwidth
#: what the accuracy metrics score (shown under the metrics' definitions)
COMMANDED_NOTE = (
    "What is scored: mu' is the commanded friction, seed 003's eq 2 at the amplitude the "
    "renderer commands (the inversion's error counts), not what the plate delivers through "
    f"its {PLATE_LOOP_HZ:g} Hz amplitude loop, although the spectral band runs to 1 kHz. "
    "Every claim, and each table's time, spectral and alignment columns, use the commanded "
    "mu'. The matrix's tables add the time and spectral errors through the plate ('plate' "
    "columns): the commanded amplitude through device/finger.py's first-order model of "
    f"that loop (a {PLATE_LOOP_HZ:g} Hz low-pass, seed 003 Fig. 3b), then eq 2: what a "
    "finger on the plate gets. A fine grating swept fast loses most there (its edges are "
    "rounded off), whatever the renderer. There is no alignment error through the plate: "
    "the plate starts each touch at rest, so its rise at touch-down is a step no edge "
    "matches (scored at the cap), and the loop's lag (0.4 ms, 0.05 mm at 120 mm/s) is "
    "below what that error resolves. Every error is scored with each output sample "
    "played at the time it was computed for: no touch-to-plate delay. A live link's delay "
    "comes on top (the schedule latency below; `frictex bench latency` times it): "
    "delaying the output by 5 ms took the hybrid's alignment error on grating-5mm's "
    "human-like path from 0.18 to 0.46 mm and sho-held's from 0.58 to 0.95 mm.")
#: how each cost figure is timed and what a median over them does with a stall
WARM_TIMING = (
    f"each timed after an untimed {WARM_UP_S:g} s run of the same configuration; no timing "
    "is dropped: one stalled timing of the three moves the median at most to the next "
    "timing, two stalled ones are the median (on a machine shared with other work a "
    "configuration can then cost several times its neighbours': the stage table shows "
    "which stage stalled), so read a cost against its neighbours, not alone")
def plot_captions(settings) -> dict[str, tuple[str, ...]]:
    """report.md's captions under the plots, by file name (``settings``: the run's, for
    the conditions its timings were taken in)."""
    from frictex.app.measure.report_closed_loop import FIGURE_CAPTION as loop_caption
    return {
        "error_vs_cost.png": (
            "", "Error against compute cost: the matrix's one human-like draw, 50 Hz touch, "
            "each configuration's mean over the gratings of the errors of the commanded mu'; "
            "the time panel leaves the 0.6 mm grating out (its time error is not claimed: "
            "section Claims). Cost: the median over the gratings of one timing each "
            f"({WARM_TIMING}), taken with {_conditions(settings)}.", ""),
        "closed_loop.png": ("", loop_caption, ""),
        "error_vs_period.png": (
            "", "Error against grating period: the matrix's one draw of each motion, "
            "commanded mu', mean over the motions, leaving out sho-held's "
            "aliasing-degenerate rows (a constant mu', marked 'aliased' in the tables).", ""),
    }
#: which draw the matrix's tables show (the claims use the draws' section)
ONE_DRAW_NOTE = (
    "One draw of each motion, not one of the draws the claims use: the human-like motion is "
    "motion seed 7 sampled with touch-noise seed 11, without timing jitter or drops; the "
    "swipes are sampled with touch-noise seed 11. The section Draws (after the gratings' "
    "table) gives the claims' draws.")


def table(header, lines, empty: str) -> list[str]:
    """A markdown table, or the sentence ``empty`` where it has no lines."""
    lines = list(lines)
    if not lines:
        return [f"None in this report: {empty}."]
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    return out + ["| " + " | ".join(str(c) for c in line) + " |" for line in lines]


def _fmt(value) -> str:
    """Three decimals; '-' where the metric is undefined."""
    return "-" if value is None or np.isnan(value) else f"{value:.3f}"


def _by(rows: list[Row], key: str, values, metric: str) -> list[str]:
    """The mean of ``metric`` over the rows whose ``key`` is each of ``values``."""
    return [_fmt(mean_defined(getattr(r, metric) for r in rows if getattr(r, key) == v))
            for v in values]


def _plate_by(rows: list[Row], key: str, values, metric: str) -> list[str]:
    """:func:`_by` of a metric through the plate (``Row.through_plate``; rows without it
    count as undefined)."""
    return [_fmt(mean_defined(getattr(r.through_plate, metric) if r.through_plate else None
                              for r in rows if getattr(r, key) == v)) for v in values]


def _plate_gain(hz: float) -> float:
    """The share of a component at ``hz`` the plate's amplitude loop passes: a first-order
    low-pass at ``PLATE_LOOP_HZ`` (device/finger.py)."""
    return 1.0 / np.hypot(1.0, hz / PLATE_LOOP_HZ)


def _base(rows: list[Row]) -> list[Row]:
    """The rows at the reference output rate with exact inversion."""
    return [r for r in rows if r.output_hz == OUTPUT_HZ and r.inversion == "exact"]


def _intro(doc: Report) -> list[str]:
    return ["# frictex report: speed against error", "",
            f"{'Quick' if doc.quick else 'Full'} matrix, {len(doc.rows)} rows. "
            "Metrics (rendering/metrics.py): time error = RMS(mu' - mu'*) / std(mu'*); spectral "
            "error = distance of third-octave short-time spectra, 10 Hz - 1 kHz (phase "
            f"ignored only for textures of {PHASE_BLIND_HZ:g} Hz and above, v / P: below, a "
            "0.1 s window holds one or two edges and a shift of a quarter period costs 0.3 "
            "at 10 Hz, 1.3 at 4 Hz, more than a missing texture; the 15 mm grating under "
            "every motion and the 5 mm grating at 20 and 60 mm/s are below it, and their "
            "spectral claims say so); alignment error = mean distance (mm of path) between matching "
            "friction steps, both ways, each distance capped at "
            f"{ALIGNMENT_CAP_MM:g} mm (also the cost of a step with no partner: "
            f"{ALIGNMENT_CAP_MM:.3f} means no step was matched). '-' marks a metric that is "
            "undefined for the row (a scene without steps has no alignment error). Time and "
            "alignment matter for objects and coarse "
            "gratings (P > ~5 mm), the spectrum for fine textures (seed 003 section 6).", "",
            COMMANDED_NOTE, ""] + _quick_note(doc)


def _quick_note(doc: Report) -> list[str]:
    """What ``--quick`` ran, against the full report (empty for the full report)."""
    if not doc.quick:
        return []
    from frictex.app.measure import report_closed_loop as rcl
    from frictex.app.measure.report_seeds import DRAWS
    loop = doc.closed_loop
    runs = ""
    if loop is not None:
        runs = (f"; closed-loop runs of {loop.duration_s:g} s on {loop.fingers} fingers "
                f"(full: {rcl.DURATION_S:g} s)")
        if loop.adaptation is not None:
            runs += (f" and an adaptation study of {loop.adaptation.duration_s:g} s on "
                     f"{loop.adaptation.fingers} fingers (full: {rcl.ADAPT_S:g} s)")
    return ["What --quick runs: the small matrix (50 Hz touch, the human motion also at 120 "
            "and 240 Hz; the slow, fast and human motions; 10 kHz output, and on the gratings "
            "the output-rate and inversion sweep of the human motion), "
            f"{doc.draws.n} draws of each motion (full: {DRAWS}){runs}. Its intervals are "
            "those of these smaller samples: a claim not shown here may hold in the full "
            "report, and the closed-loop gains of short runs weigh the loop's start more "
            "than a session does.", ""]


def _claims(doc: Report) -> list[str]:
    lines = ["## Claims", "",
             f"Each claim compares renderers on the same {doc.draws.n} draws of each "
             "motion (paired by draw): the mean difference and its 95 % interval. A claim "
             "**holds** only where the interval excludes a loss; it **does not hold** where "
             "the whole interval lies on the losing side; otherwise it is **not shown** (the "
             "interval straddles the claim's bound: the draws do not settle it). "
             + NOT_CLAIMED
             + _degenerate_kinds(doc)
             + (" The groups 'closed loop: ...' compare friction control modes on the same "
                "simulated fingers, paired by finger, their RMS error against the reachable "
                "mu' (section Closed-loop friction defines it, and gives the error against "
                "the texture's target beside it)."
                if doc.closed_loop is not None else "")
             + (" " + family_note(doc.claims) if doc.claims else ""), ""]
    groups: dict[str, list] = {}
    for c in doc.claims:
        groups.setdefault(c.group, []).append(c)
    if not groups:
        lines += ["None in this report: no claim covers the scenes chosen.", ""]
    for group, cs in groups.items():
        lines.append(f"**{group}**: {count_line(cs)}.")
        lines += [f"- {c.verdict}: {c.scene}, {c.motion}, {c.metric}: {c.text}" for c in cs]
        lines.append("")
    return lines


ERROR_HEADER = ["time", "spectral", "alignment mm", "time, plate", "spectral, plate"]


def _errors(r: Row) -> list[str]:
    """A row's commanded errors, then those through the plate ('-' where not scored)."""
    plate = r.through_plate
    return [_fmt(r.time_error), _fmt(r.spectral_error), _fmt(r.alignment_error_mm),
            *((_fmt(plate.time_error), _fmt(plate.spectral_error)) if plate is not None
              else ("-",) * 2)]


#: the notes' legend, by the note's first word
NOTE_LEGEND = {
    "same": "same: the renderer's errors equal those of the renderers named, to 1e-12: the "
            "path never reaches what tells them apart, so the cell compares nothing",
    "aliased": "aliased: the swipe crosses a whole number of periods between two touch "
               "samples, so every sample lands at the same phase and a position map read "
               "at the samples (sho-held) gives a constant mu': an aliasing-degenerate "
               "speed, not a measure of the renderer",
}


def cell_notes(rows: list[Row]) -> list[str]:
    """A note per row (aligned with ``rows``; "" for none): cells whose renderers score
    the same (a renderer-independent result), and sho-held on a swipe whose speed is
    aliasing-degenerate at the touch rate (``report_matrix.periods_per_sample``)."""
    notes = []
    for r in rows:
        same = sorted(o.renderer for o in rows if o is not r and _cell(o) == _cell(r)
                      and _same_errors(o, r))
        parts = [f"same as {', '.join(same)}"] if same else []
        if aliased(r):
            per = periods_per_sample(MOTIONS[r.motion], r.touch_hz, r.period_mm)
            parts.append(f"aliased: {per:g} periods per touch sample")
        notes.append("; ".join(parts))
    return notes


def _cell(r: Row) -> tuple:
    return r.scene, r.motion, r.touch_hz, r.output_hz, r.inversion


def _same_errors(a: Row, b: Row) -> bool:
    pairs = [(a.time_error, b.time_error), (a.spectral_error, b.spectral_error),
             (a.alignment_error_mm, b.alignment_error_mm)]
    return all((x is None and y is None) or (x is not None and y is not None
                                             and abs(x - y) <= 1e-12) for x, y in pairs)


def _notes_legend(notes: list[str]) -> list[str]:
    """The legend of the notes used, as a paragraph (none where no row has a note)."""
    used = [text for key, text in NOTE_LEGEND.items()
            if any(part.startswith(key) for n in notes for part in n.split("; "))]
    return ["", "Notes: " + "; ".join(used) + "."] if used else []


def _degenerate_kinds(doc: Report) -> str:
    """A sentence naming the draws' swipes that are aliasing-degenerate on a grating at
    50 Hz ("" where none is)."""
    found = []
    for scene, kinds in doc.draws.values.items():
        for kind in kinds:
            per = periods_per_sample(MOTIONS.get(kind, {}), TOUCH_HZ, GRATINGS.get(scene))
            if aliasing_degenerate(per):
                found.append(f"the {kind} swipe on {scene} ({MOTIONS[kind]['speed_mm_s']:g} "
                             f"mm/s at {TOUCH_HZ:g} Hz: {per:g} periods per touch sample)")
    if not found:
        return ""
    return (" Aliasing-degenerate speeds: " + "; ".join(found) + ": every touch sample lands "
            "at the same phase, so sho-held renders a constant mu' there, and a claim against "
            "sho-held on it compares with a flat signal, not with position-map rendering at "
            "large.")


def _gratings(doc: Report) -> list[str]:
    base = _base(grating_rows(doc.rows))
    notes = cell_notes(base)
    lines = ["## Gratings at 50 Hz touch, 10 kHz output (one draw)", "",
             ONE_DRAW_NOTE + " Errors of the commanded mu', then through the plate "
             "(section intro).", ""]
    lines += table(["scene", "motion", "renderer", *ERROR_HEADER, "cost us/s", "note"],
                   [(r.scene, r.motion, r.renderer, *_errors(r), f"{r.cost_us_per_s:.0f}",
                     note) for r, note in zip(base, notes)],
                   "no seed 003 grating among the scenes chosen") + _notes_legend(notes)
    if doc.draws.values:
        from frictex.app.measure.report_seeds import summary_lines as draw_lines
        lines += ["", *draw_lines(doc.draws)[:-1]]
    if doc.real is not None:
        from frictex.app.measure.report_real import summary_lines as real_lines
        lines += ["", *real_lines(doc.real)[:-1]]
    return lines


def _other_scenes(doc: Report) -> list[str]:
    other = [r for r in _base(doc.rows) if r.scene not in GRATINGS]
    notes = cell_notes(other)
    return ["", "## Other scenes (one draw)", "", ONE_DRAW_NOTE + " Errors of the commanded "
            "mu', then through the plate (section intro).", ""] + table(
        ["scene", "motion", "touch Hz", "renderer", *ERROR_HEADER, "cost us/s", "note"],
        [(r.scene, r.motion, f"{r.touch_hz:g}", r.renderer, *_errors(r),
          f"{r.cost_us_per_s:.0f}", note) for r, note in zip(other, notes)],
        "only gratings among the scenes chosen") + _notes_legend(notes)


#: issue 4's throughput targets: replay (x real time, at least; judged here on compute
#: only), live block p99 (us of the thread's CPU time, at most; ``frictex bench
#: pipeline``: over 2,000 blocks) and two fingers with modal actuation in replay (x real
#: time, at least; compute only here)
REPLAY_TARGET_X = 1000.0
LIVE_P99_TARGET_US = 500.0
MODAL_TARGET_X = 200.0
BENCH_LIVE_BLOCKS = 2000


def _conditions(settings) -> str:
    """How the timings were taken: the cases run at once and the machine's load."""
    jobs = (f"{settings.jobs} cases at once" if settings.jobs is not None
            else f"on the Dask cluster {settings.scheduler}")
    load = settings.load_1min
    seen = ("load not recorded" if load is None else
            f"1-minute load {min(load):.1f}-{max(load):.1f} over the matrix")
    return f"{jobs} on {settings.cpu_count} CPUs, {seen}"


def _blocks(head: dict) -> str:
    """The live runs' block counts over the rows: '100' or '100-140'."""
    counts = sorted({v.live_blocks for v in head.values()})
    return f"{counts[0]:,}" if len(counts) == 1 else f"{counts[0]:,}-{counts[-1]:,}"


def _p99_unjudged(head: dict) -> str:
    """Why the rows' live p99s, all under the target, are no verdict on it: a verdict
    needs the 95 % interval's upper end (``app.measure.quantile_claim``), which a p99 of
    too few blocks has none of, and which the rows, keeping their p99 and not their
    blocks, cannot give in any case."""
    few = any(quantile_ranks(v.live_blocks, 0.99)[1] > v.live_blocks for v in head.values())
    why = (f"a p99 of {_blocks(head)} blocks has no upper end to its 95 % interval"
           if few else "the rows keep their p99, not the blocks its 95 % interval is taken "
                       "from")
    return (f"every row's figure is under it, which is no verdict: {why} "
            f"(`app.measure.quantile_claim`); `frictex bench pipeline` gives one over "
            f"{BENCH_LIVE_BLOCKS:,} blocks")


def _throughput_verdicts(head: dict, settings) -> str:
    """The throughput targets against this run's rows, none of which gives a verdict:
    replay and the live p99 are said missed by the rows that miss them, or else met by
    every row's figure, which is no verdict (replay: one timing a row, no interval; the
    p99: :func:`_p99_unjudged`); latency is not judged: the block schedule bounds it for
    every trace, so no row could miss it."""
    from frictex.device.link.host import TARGET_S
    latency_bound = (BLOCK_S + TARGET_S) * 1e3
    replay_miss = [k for k, v in head.items() if v.replay_x_realtime < REPLAY_TARGET_X]
    p99_miss = [k for k, v in head.items()
                if v.live_block_p99_thread_cpu_us > LIVE_P99_TARGET_US]

    def timed(miss):
        return (f"not shown here: {len(miss)} of {len(head)} rows miss it, one timing each "
                f"after an untimed {WARM_UP_S:g} s run of the same configuration, with "
                f"{_conditions(settings)}; `frictex bench pipeline` times it alone")
    replay = (timed(replay_miss) if replay_miss else
              "every row's figure meets it, which is no verdict: one timing a row has no "
              "interval")
    p99 = timed(p99_miss) if p99_miss else _p99_unjudged(head)
    return (f"Targets (issue 4) against these rows: replay >= {REPLAY_TARGET_X:g}x real time, "
            f"judged here on compute only (end to end: section below): {replay}; "
            f"live p99 <= {LIVE_P99_TARGET_US:g} us of the thread's CPU time (10 % of a 5 ms "
            f"block), over {_blocks(head)} blocks a row: {p99}; latency <= one block plus the "
            f"link buffer "
            f"({latency_bound:g} ms): not judged here: the block schedule bounds it for "
            "every trace (a sample is used by the next block that starts after it), so the "
            "schedule column cannot miss it; `frictex bench latency` times the live path.")


def _throughput(doc: Report) -> list[str]:
    head = doc.headline
    lines = ["", "## Throughput and latency (composed scene, one finger, "
             f"{TOUCH_HZ:g} Hz touch, {OUTPUT_HZ / 1000:g} kHz)", "",
             f"Measured with {_conditions(doc.settings)}: each case's timings compete with "
             "the others run at once and with whatever else the machine runs. Live: one "
             "pipeline call per 5 ms block, timed as `frictex bench pipeline` times it (the "
             "garbage collector frozen, as the live haptic process has it), in the thread's "
             "CPU time (what the target is set in) and in wall time (which adds the time "
             "other processes take), over the row's own short run.", ""]
    lines += table(["renderer/motion", f"replay x real time, compute only (target >= "
                    f"{REPLAY_TARGET_X:g}, compute only)", "live 5 ms block p99 us, thread "
                    f"CPU (target <= {LIVE_P99_TARGET_US:g})", "live p99 us, wall time",
                    "live blocks", "schedule latency ms (block wait + link buffer)",
                    "cost us/s"],
                   [(k, f"{v.replay_x_realtime:.0f}", f"{v.live_block_p99_thread_cpu_us:.0f}",
                     f"{v.live_block_p99_wall_us:.0f}", f"{v.live_blocks:,}",
                     f"{v.latency_ms:.1f}", f"{v.cost_us_per_s:.0f}") for k, v in head.items()],
                   "the composed scene is not among the scenes chosen")
    if head:
        lines += ["", _throughput_verdicts(head, doc.settings)]
    if head:
        stages = next(iter(head.values())).stages_us_per_s
        lines += ["", "Per-stage cost (us per second of output) for the first of these: "
                  + ", ".join(f"{k} {v:.0f}" for k, v in stages.items())
                  + ". Replay counts the pipeline stages; link encode is what a live link adds. "
                  "Schedule latency: computed from the block schedule, not timed: the longest "
                  "a touch sample of the matrix's trace waits for the block that first uses it "
                  f"(under one {BLOCK_S * 1e3:g} ms block by construction; 0 where the trace's "
                  "timestamps fall on block boundaries, as the synthetic 50 Hz trace's 20 ms "
                  "steps do), plus the jitter buffer a paced link keeps "
                  f"({link_buffer_s() * 1e3:g} ms); the live touch-to-output latency, timed end "
                  "to end, is `frictex bench latency`'s."]
    return (lines + _end_to_end(doc.end_to_end, doc.timings.get("end to end"))
            + _modal_replay(doc))


def _when(timing) -> str:
    """', 1-minute load 2.8-3.3, 41 s' of a section's ``report_doc.Timing``; '' for none."""
    return "" if timing is None else ", " + timing.conditions()


def _end_to_end(e2e: dict | None, timing) -> list[str]:
    """The end-to-end paragraph; ``timing``: its section's ``report_doc.Timing``."""
    if not e2e:
        return []
    done = {fmt: got for fmt, got in e2e["formats"].items() if got is not None}
    failed = sorted(set(e2e["formats"]) - set(done))
    return ["", f"End to end ({e2e['scene']}, a {e2e['duration_s']:g} s human-like trace, "
            f"one run of each format{_when(timing)}; "
            "each a fresh `frictex replay` process: reading the trace, computing, writing "
            "every output; peak: its peak resident memory, started from a small launcher "
            "process whose resident memory it may include, at most the launcher's figure "
            "given): " + "; ".join(
                f"{fmt} {got['x_realtime_end_to_end']:.0f}x real time (compute only "
                f"{got['x_realtime_compute']:.0f}x; whole process with start-up "
                f"{e2e['duration_s'] / got['process_wall_s']:.0f}x, peak "
                f"{got['peak_mib']:.0f} MiB, launcher {got['launcher_mib']:.0f} MiB)" for fmt, got in done.items())
            + (f"; failed: {', '.join(failed)}" if failed else "") + "."]


def _modal_replay(doc: Report) -> list[str]:
    from frictex.device.link.host import TARGET_S
    modal = doc.modal_replay
    x_modal = modal["replay_x_realtime"]
    return ["", f"Two fingers with modal actuation ({modal['scene']}, trace {modal['trace']}, "
            f"{modal['output_hz'] / 1e3:g} kHz; one run after an untimed one"
            f"{_when(doc.timings.get('modal replay'))}): replay {x_modal:.0f}x real "
            "time, compute only; per stage (us per second of output): "
            + ", ".join(f"{k} {v:.0f}" for k, v in modal["stages_us_per_s"].items()) + ".",
            "", f"Targets: replay >= {REPLAY_TARGET_X:g}x real time and two fingers with modal "
            f"actuation >= {MODAL_TARGET_X:g}x real time in replay, both judged here on compute "
            f"only (this run: {x_modal:.0f}x for two fingers, "
            f"{'at or above' if x_modal >= MODAL_TARGET_X else 'below'} "
            f"{MODAL_TARGET_X:g}x); a real-time factor without 'compute only' is end to end "
            "(reading the trace and writing the output too), which for one finger is the "
            "paragraph above and for two fingers `frictex bench replay`'s figure, not "
            f"measured here. Live p99 <= {LIVE_P99_TARGET_US:g} us of the thread's CPU time "
            "(10 % of a 5 ms block). "
            "Latency = longest wait of a touch sample for its block (<= one 5 ms block) plus the "
            f"link's {TARGET_S * 1e3:g} ms jitter buffer (device.link.host.TARGET_S). These "
            "figures are measured on "
            f"the machine that wrote the report ({doc.settings.cpu_count} CPUs) and vary "
            "with its load; no test asserts them.", ""]


def _physical_limits(doc: Report) -> list[str]:
    lines = ["## Physical limits", ""]
    hybrid = [r for r in grating_rows(doc.rows) if r.renderer == "hybrid" and r.motion == "human"
              and r.inversion == "exact"]
    rates = sorted({r.output_hz for r in hybrid})
    if rates:
        lines += [f"Output rate against the plate's amplitude loop: -3 dB at {PLATE_LOOP_HZ:g} Hz "
                  "(seed 003, Fig. 3b: 'a bandwidth of 400 Hz at 2 um'). The report's model of "
                  "it, a first-order low-pass (device/finger.py), passes "
                  f"{_plate_gain(1000.0):.0%} of a 1 kHz component and "
                  f"{_plate_gain(5000.0):.0%} of a 5 kHz one: an output rate of 2 kHz carries "
                  "up to 1 kHz, and higher rates add components the plate passes less and "
                  "less, while placing steps more finely in time (1 / rate: 0.5 ms at 2 kHz, "
                  "0.05 ms at 20 kHz). The time and spectral rows are the errors through the "
                  "plate (what a finger gets), the alignment row that of the commanded mu'. "
                  "Hybrid, gratings, human motion, mean over gratings. Each column is one "
                  "draw, so its alignment error moves with a single step: one spurious step "
                  "pair rendered at some rates and not at others doubles it, so a "
                  "difference in that row is not the rate's doing unless it holds across "
                  "draws:", ""]
        lines += table(["metric", *(f"{h / 1000:g} kHz" for h in rates)],
                       [(f"{m}, plate", *_plate_by(hybrid, "output_hz", rates, m))
                        for m in ("time_error", "spectral_error")]
                       + [("alignment_error_mm", *_by(hybrid, "output_hz", rates,
                                                      "alignment_error_mm"))], "")
        lines.append("")
    held = [r for r in _base(doc.rows) if r.scene == "grating-0.6mm" and r.renderer == "sho-held"]
    touch = sorted({r.touch_hz for r in held})
    motions = motions_at_every(held, touch)
    lines += ["Touch rate against texture frequency: a grating of period P under a finger at v "
              "is a signal at v / P" + _texture_frequencies(motions, doc.settings.motions, 0.6)
              + "; position-map rendering (SHO) "
              "can only render up to half the touch rate (25 Hz at 50 Hz, seed 003 section "
              "4.4.1), above which it aliases. sho-held on the 0.6 mm grating, spectral error by "
              "touch rate, mean over the same motions at every rate: those run at every rate "
              "and aliasing-degenerate at none (" + (", ".join(motions) or "none") + "):", ""]
    held = [r for r in held if r.motion in motions]
    return lines + table(["touch rate", *(f"{t:g} Hz" for t in touch)],
                         [("spectral error", *_by(held, "touch_hz", touch, "spectral_error"))]
                         if motions else [], "the 0.6 mm grating has no motion run at every "
                         "touch rate among the scenes chosen")


def _texture_frequencies(motions: list[str], motion_args: dict, period_mm: float) -> str:
    """' (0.6 mm at human's 60 mm/s: 100 Hz, ...)': v / P for each of ``motions`` at its
    speed (``motion_args``: name -> ``make_motion`` arguments, mm/s), or '' for none."""
    if not motions:
        return ""
    each = [f"{name}'s {motion_args[name]['speed_mm_s']:g} mm/s: "
            f"{motion_args[name]['speed_mm_s'] / period_mm:.0f} Hz" for name in motions]
    return f" ({period_mm:g} mm at " + ", ".join(each) + ")"


def motions_at_every(rows: list[Row], touch_hz: list[float]) -> list[str]:
    """The motions with a row at each of ``touch_hz`` and no aliasing-degenerate row
    (``report_matrix.aliased``), so that each rate's mean is over the same motions."""
    run = [{r.motion for r in rows if r.touch_hz == t} for t in touch_hz]
    degenerate = {r.motion for r in rows if aliased(r)}
    return sorted(set.intersection(*run) - degenerate) if run else []


def _inversion(doc: Report) -> list[str]:
    inv = [r for r in grating_rows(doc.rows) if r.motion == "human" and r.output_hz == OUTPUT_HZ]
    names = sorted({r.inversion for r in inv})
    lines = ["", "## Inversion", "",
             "Exact (seed 003 eq 3, closed form) against the table built at scene load "
             "(rendering/inversion_lut.py), whose largest amplitude error is "
             f"{doc.settings.lut_max_error_um:.2g} um (settings.lut_max_error_um). Errors: "
             "mean over the gratings and over every renderer, human motion, 50 Hz, 10 kHz. "
             "Costs: the median over the same rows ('rows timed') of one run each, exact "
             f"and table timed in separate cases, not alternated ({WARM_TIMING}), taken "
             f"with {_conditions(doc.settings)}; a "
             "difference between them within the machine's spread is no difference:", ""]
    cost = [(label, *[f"{np.median([us(r) for r in inv if r.inversion == n]):.0f}"
                      for n in names])
            for label, us in (("cost us/s (median)", lambda r: r.cost_us_per_s),
                              ("inversion us/s (median)",
                               lambda r: r.stages_us_per_s["inversion"]))]
    counts = [("rows timed (one run each)",
               *[sum(r.inversion == n for r in inv) for n in names])]
    figures = [(m, *_by(inv, "inversion", names, m)) for m in METRICS]
    return lines + table(["", *names], figures + cost + counts if names else [],
                         "no seed 003 grating among the scenes chosen")


def _modal_inversion(doc: Report) -> list[str]:
    return ["", "## Modal inversion (two fingers, seed 000 beam)", "",
            "Each method of device/actuation/modal.py on seed 000's beam (modes 16, 17; actuator "
            "limit 0.75 um), two fingers at random and near-singular (within 0.5 mm) "
            "positions; the default, regularised, is the one that stays continuous across "
            "a singular locus (app/measure/bench_modal.py says how each figure is made); "
            f"one run{_when(doc.timings.get('modal inversion'))}:", ""
            ] + table(["figure", "value", "unit"],
                      [(f["label"], f"{f['value']:.4g}", f["unit"]) for f in doc.modal_inversion],
                      "no modal inversion figures")


def loop_baselines(section) -> list[str]:
    """The closed-loop section's two baselines defined, and the gains against the
    texture's target beside those against the reachable mu' (a paragraph, then a blank
    line)."""
    gains = []
    for scene, row in section.scenes.items():
        if "open" not in row:
            continue
        opened = row["open"].rms_pop
        modes = [f"{mode} {m.rms_pop:.4f} ({opened / max(m.rms_pop, 1e-12):.2f}x; against the "
                 f"reachable mu' {m.gain_vs_open:.2f}x)" for mode, m in row.items()
                 if mode != "open" and m.gain_vs_open is not None]
        if modes:
            gains.append(f"{scene}: open {opened:.4f} -> " + ", ".join(modes))
    return ["Two baselines. 'RMS' (and 'gain', 'worst', 'from mu0 on', and the claims "
            "'rms_reachable') is the error of the delivered mu' against the reachable mu': "
            "what a controller knowing this finger exactly delivers through the plate, the "
            "part no amplitude command can fix removed. 'raw RMS' is the error of the "
            "delivered mu' against the texture's target mu' (the scene's composed target), "
            "what issue 16 names: it also counts what no amplitude command can fix (targets "
            "beyond this finger's reach at the amplitude limit, the plate's 400 Hz lag at "
            "each edge). Against the target"
            + (": " + "; ".join(gains) + "." if gains else " no loop mode ran beside open "
               "loop."), ""]


def write_markdown(doc: Report, path: Path, plots: list[str]) -> None:
    """Write report.md: the claims, then each section's tables, then the plots."""
    lines = (_intro(doc) + _claims(doc) + _gratings(doc) + _other_scenes(doc)
             + _throughput(doc) + _physical_limits(doc) + _inversion(doc) + _modal_inversion(doc))
    if doc.closed_loop is not None:
        from frictex.app.measure.report_closed_loop import markdown as loop_lines
        loop = loop_lines(doc.closed_loop)[:-1]
        lines += ["", *loop[:2], *loop_baselines(doc.closed_loop), *loop[2:]]
    captions = plot_captions(doc.settings)
    lines += ["", "## Plots", ""] + [line for p in plots for line in
                                     (f"![{p}]({p})", *captions.get(p, ()))]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
