"""Writing ``frictex report``'s outputs: ``report.json``, ``report.md`` and two plots.

``report.json``::

    {"report_version": 2, "quick": bool, "settings": {...}, "rows": [row, ...],
     "claims": [{"group", "scene", "motion", "metric", "text", "mean", "low", "high", "n",
                 "passed"}, ...],
     "draws": {...}, "headline": {...}, "closed_loop": {...} or null}

Claims are computed on ``draws`` (``app.measure.report_seeds``), paired by draw, with a
95 % interval (``app.measure.report_claims``); ``passed`` is true only where the interval
excludes a loss. ``closed_loop`` (``app.measure.report_closed_loop``): open loop,
closed loop and closed loop with adaptation over a simulated population of fingers;
its claims (groups "closed loop: ...") are in the same list, paired per finger.

Each row (see ``app.measure.report_matrix``) has ``scene``, ``period_mm`` (null for scenes that
are not one grating), ``motion``, ``touch_hz``, ``renderer``, ``output_hz``,
``inversion``, ``time_error``, ``spectral_error``, ``alignment_error_mm``, ``chatter``
(edges felt twice, ``rendering.metrics.chatter``; on the 15 and 5 mm gratings, else null),
``cost_us_per_s``, ``stages_us_per_s`` and ``throughput`` (``replay_x_realtime``,
``live_block_p99_us``, ``latency_ms``).
"""

from __future__ import annotations

import json
from dataclasses import asdict
from pathlib import Path

import numpy as np

from frictex.app.measure.report_seeds import summary_lines as draw_lines
from frictex.app.measure.report_claims import GRATINGS, METRICS, NOT_CLAIMED, OUTPUT_HZ, TOUCH_HZ, claims

REPORT_VERSION = 2
PLATE_LOOP_HZ = 400.0  # seed 003, Fig. 3b: the amplitude loop's -3 dB bandwidth
LABELS = {"time_error": "time error (NRMS)", "spectral_error": "spectral error",
          "alignment_error_mm": "alignment error (mm)"}


def _config(row) -> str:
    return f"{row['renderer']} {row['output_hz'] / 1000:g} kHz {row['inversion']}"


def _grating_rows(rows, touch_hz=TOUCH_HZ):
    return [r for r in rows if r["scene"] in GRATINGS and r["touch_hz"] == touch_hz]


def pareto(points: list[tuple[float, float]]) -> list[bool]:
    """Which (cost, error) points no other point beats on both (ties count as beaten only
    when strictly worse on one and no better on the other)."""
    out = []
    for c, e in points:
        out.append(not any((c2 <= c and e2 <= e) and (c2 < c or e2 < e) for c2, e2 in points))
    return out


def _config_points(rows):
    """Per configuration seen on the gratings at 50 Hz for every motion it ran:
    mean cost and mean of each metric over the motions the sweep shares (human)."""
    sweep = [r for r in _grating_rows(rows) if r["motion"] == "human"]
    configs: dict[str, list] = {}
    for r in sweep:
        configs.setdefault(_config(r), []).append(r)
    return {name: {"cost": float(np.mean([r["cost_us_per_s"] for r in rs])),
                   **{m: _mean(r[m] for r in rs) for m in METRICS}}
            for name, rs in configs.items()}


def _empty(fig, path: Path, plt) -> None:
    fig.text(0.5, 0.5, "no seed 003 grating rows at 50 Hz in this report", ha="center")
    for ax in fig.axes:
        ax.set_axis_off()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_cost(rows, path: Path) -> None:
    """Error against compute cost per second of output, one point per configuration."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    points = _config_points(rows)
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.8), constrained_layout=True)
    if not points:
        return _empty(fig, path, plt)
    names = sorted(points)
    colours = {r: f"C{k}" for k, r in enumerate(sorted({n.split()[0] for n in names}))}
    for ax, metric in zip(axes, METRICS):
        xy = [(points[n]["cost"], points[n][metric]) for n in names]
        front = pareto(xy)
        labelled = 0
        for (x, y), n, f in zip(xy, names, front):
            ax.scatter(x, y, s=28, c=colours[n.split()[0]], marker="s" if "lut" in n else "o",
                       edgecolors="k" if f else "none", zorder=3)
            if f:  # label the front only (staggered: its points crowd); the legend names colours
                ax.annotate(n, (x, y), fontsize=6, xytext=(3, 3 + 9 * (labelled % 3)),
                            textcoords="offset points")
                labelled += 1
        fx = sorted((p for p, f in zip(xy, front) if f))
        ax.step([p[0] for p in fx], [p[1] for p in fx], where="post", c="k", lw=0.8,
                label="Pareto front")
        for r, c in colours.items():
            ax.scatter([], [], c=c, s=28, label=r)
        ax.scatter([], [], c="w", edgecolors="k", marker="s", s=28, label="LUT inversion")
        ax.set_xscale("log")
        ax.set_xlabel("compute per second of output (us/s; 2-20 kHz output)")
        ax.set_ylabel(LABELS[metric])
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=7)
    fig.suptitle("Error against cost: seed 003 gratings, human-like motion, 50 Hz touch")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def plot_period(rows, path: Path) -> None:
    """Each metric against grating period, one line per renderer (50 Hz, 10 kHz, exact)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    base = [r for r in _grating_rows(rows) if r["output_hz"] == OUTPUT_HZ
            and r["inversion"] == "exact"]
    renderers = sorted({r["renderer"] for r in base})
    periods = sorted(set(GRATINGS.values()))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5), constrained_layout=True)
    if not base:
        return _empty(fig, path, plt)
    for ax, metric in zip(axes, METRICS):
        for name in renderers:
            ys = [_mean(r[metric] for r in base if r["renderer"] == name and r["period_mm"] == p)
                  for p in periods]
            ax.plot(periods, ys, marker="o", label=name)
        ax.set_xscale("log")
        ax.set_yscale("log")
        ax.set_xlabel("grating period (mm)")
        ax.set_ylabel(LABELS[metric] + ", mean over motions")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Error against grating period, per renderer (50 Hz touch, 10 kHz output)")
    fig.savefig(path, dpi=110)
    plt.close(fig)


def headline(rows) -> dict:
    """The throughput and latency figures of issue 4: composed scene, one finger, 10 kHz."""
    pick = [r for r in rows if r["scene"] == "composed-fine-grating-in-disc"
            and r["output_hz"] == OUTPUT_HZ and r["inversion"] == "exact"
            and r["touch_hz"] == TOUCH_HZ]
    out = {}
    for r in pick:
        key = f"{r['renderer']}/{r['motion']}"
        out[key] = {**r["throughput"], "cost_us_per_s": r["cost_us_per_s"],
                    "stages_us_per_s": r["stages_us_per_s"]}
    return out


def write_json(rows, path: Path, quick: bool, settings: dict, modal: list[dict],
               modal_replay: dict, draws: dict, real: dict | None = None,
               end_to_end: dict | None = None, closed_loop: dict | None = None) -> dict:
    """``modal``: the speed and error figures of each modal inversion method
    (``app.measure.bench_modal``), under the key ``modal_inversion``; ``modal_replay``: two fingers
    with modal actuation in headless replay (``app.measure.bench_pipeline.modal_throughput``);
    ``draws``: the gratings under independent draws of motion (``app.measure.report_seeds``),
    on which the claims are computed; ``real``: the replayed real recordings
    (``app.measure.report_real``), or None; ``end_to_end``: whole replays in fresh
    processes per output format (``app.measure.bench_replay.end_to_end``); ``closed_loop``:
    the closed-loop section (``app.measure.report_closed_loop``), whose claims join the
    list, or None."""
    found = claims(draws)
    if closed_loop is not None:
        from frictex.app.measure.report_closed_loop import claims as loop_claims
        found += loop_claims(closed_loop)
    doc = {"report_version": REPORT_VERSION, "quick": quick, "settings": settings,
           "rows": rows, "claims": [asdict(c) for c in found],
           "headline": headline(rows), "modal_replay": modal_replay,
           "draws": draws, "real": real, "modal_inversion": modal, "end_to_end": end_to_end,
           "closed_loop": closed_loop}
    path.write_text(json.dumps(doc, indent=1) + "\n", encoding="utf-8")
    return doc


def _table(header, lines) -> list[str]:
    out = ["| " + " | ".join(header) + " |", "|" + "---|" * len(header)]
    out += ["| " + " | ".join(str(c) for c in line) + " |" for line in lines]
    return out


def _by_rate(rows, key, values, metric, **where):
    out = []
    for v in values:
        out.append(_fmt(_mean(r[metric] for r in rows
                              if r[key] == v and all(r[k] == w for k, w in where.items()))))
    return out


def _mean(values) -> float:
    """Mean of the defined values (None: a metric with nothing to measure), NaN if none."""
    defined = [v for v in values if v is not None]
    return float(np.mean(defined)) if defined else float("nan")


def _fmt(value) -> str:
    """Three decimals; '-' where the metric is undefined."""
    return "-" if value is None or np.isnan(value) else f"{value:.3f}"


def write_markdown(doc: dict, path: Path, plots: list[str]) -> None:
    rows = doc["rows"]
    lines = ["# frictex report: speed against error", "",
             f"{'Quick' if doc['quick'] else 'Full'} matrix, {len(rows)} rows. "
             "Metrics (rendering/metrics.py): time error = RMS(mu' - mu'*) / std(mu'*); spectral "
             "error = distance of third-octave short-time spectra, 10 Hz - 1 kHz (phase "
             "ignored); alignment error = mean distance (mm of path) between matching "
             "friction steps, both ways. Time and alignment matter for objects and coarse "
             "gratings (P > ~5 mm), the spectrum for fine textures (seed 003 section 6).", ""]
    lines += ["## Claims", "",
              f"Each claim compares renderers on the same {doc['draws']['n']} draws of each "
              "motion (paired by draw): the mean difference and its 95 % interval. A claim "
              "**holds** only where the interval excludes a loss; otherwise it is **not "
              "shown** (the draws do not settle it). " + NOT_CLAIMED
              + (" The groups 'closed loop: ...' compare friction control modes on the same "
                 "simulated fingers, paired by finger (section Closed-loop friction)."
                 if doc.get("closed_loop") is not None else ""), ""]
    groups: dict[str, list] = {}
    for c in doc["claims"]:
        groups.setdefault(c["group"], []).append(c)
    for group, cs in groups.items():
        ok = sum(c["passed"] for c in cs)
        lines.append(f"**{group}**: {ok} of {len(cs)} hold.")
        lines += [f"- {'holds' if c['passed'] else 'not shown'}: {c['scene']}, {c['motion']}, "
                  f"{c['metric']}: {c['text']}" for c in cs]
        lines.append("")
    lines += ["## Gratings at 50 Hz touch, 10 kHz output", ""]
    base = [r for r in _grating_rows(rows) if r["output_hz"] == OUTPUT_HZ and r["inversion"] == "exact"]
    lines += _table(["scene", "motion", "renderer", "time", "spectral", "alignment mm", "cost us/s"],
                    [(r["scene"], r["motion"], r["renderer"], f"{r['time_error']:.3f}",
                      f"{r['spectral_error']:.3f}", _fmt(r['alignment_error_mm']),
                      f"{r['cost_us_per_s']:.0f}") for r in base])
    if doc["draws"]["values"]:
        lines += ["", *draw_lines(doc["draws"])[:-1]]
    if doc["real"] is not None:
        from frictex.app.measure.report_real import summary_lines as real_lines
        lines += ["", *real_lines(doc["real"])[:-1]]
    lines += ["", "## Other scenes", ""]
    other = [r for r in rows if r["scene"] not in GRATINGS and r["output_hz"] == OUTPUT_HZ
             and r["inversion"] == "exact"]
    lines += _table(["scene", "motion", "touch Hz", "renderer", "time", "spectral", "alignment mm",
                     "cost us/s"],
                    [(r["scene"], r["motion"], f"{r['touch_hz']:g}", r["renderer"],
                      f"{r['time_error']:.3f}", f"{r['spectral_error']:.3f}",
                      _fmt(r['alignment_error_mm']), f"{r['cost_us_per_s']:.0f}") for r in other])
    lines += ["", "## Throughput and latency (composed scene, one finger, 10 kHz)", ""]
    head = doc["headline"]
    lines += _table(["renderer/motion", "replay x real time, compute only", "live 5 ms block p99 us",
                     "latency ms", "cost us/s"],
                    [(k, f"{v['replay_x_realtime']:.0f}", f"{v['live_block_p99_us']:.0f}",
                      f"{v['latency_ms']:.1f}", f"{v['cost_us_per_s']:.0f}") for k, v in head.items()])
    if head:
        stages = next(iter(head.values()))["stages_us_per_s"]
        lines += ["", "Per-stage cost (us per second of output) for the first of these: "
                  + ", ".join(f"{k} {v:.0f}" for k, v in stages.items())
                  + ". Replay counts the pipeline stages; link encode is what a live link adds."]
    e2e = doc.get("end_to_end")
    if e2e:
        done = {fmt: got for fmt, got in e2e["formats"].items() if got is not None}
        lines += ["", f"End to end ({e2e['scene']}, a {e2e['duration_s']:g} s human-like trace, "
                  "each a fresh `frictex replay` process: reading the trace, computing, writing "
                  "every output): " + "; ".join(
                      f"{fmt} {got['x_realtime_end_to_end']:.0f}x real time (compute only "
                      f"{got['x_realtime_compute']:.0f}x; whole process with start-up "
                      f"{e2e['duration_s'] / got['process_wall_s']:.0f}x, peak "
                      f"{got['peak_mib']:.0f} MiB)" for fmt, got in done.items())
                  + (f"; failed: {', '.join(sorted(set(e2e['formats']) - set(done)))}"
                     if len(done) < len(e2e["formats"]) else "") + "."]
    modal = doc["modal_replay"]
    lines += ["", f"Two fingers with modal actuation ({modal['scene']}, trace {modal['trace']}, "
              f"{modal['output_hz'] / 1e3:g} kHz): replay {modal['replay_x_realtime']:.0f}x real "
              "time, compute only; per stage (us per second of output): "
              + ", ".join(f"{k} {v:.0f}" for k, v in modal["stages_us_per_s"].items()) + "."]
    lines += ["", "Targets: replay >= 1000x real time, live p99 <= 500 us (10 % of a 5 ms block); "
              "two fingers with modal actuation >= 200x real time in replay. "
              "Latency = longest wait of a touch sample for its block (<= one 5 ms block) plus the "
              "link's 20 ms jitter buffer (device.link.host.TARGET_S). These figures are measured on "
              f"the machine that wrote the report ({doc['settings']['cpu_count']} CPUs) and vary "
              "with its load; no test asserts them.", ""]
    lines += ["## Physical limits", ""]
    hybrid = [r for r in _grating_rows(rows) if r["renderer"] == "hybrid" and r["motion"] == "human"
              and r["inversion"] == "exact"]
    rates = sorted({r["output_hz"] for r in hybrid})
    if rates:
        lines += [f"Output rate against the plate's {PLATE_LOOP_HZ:g} Hz amplitude loop (seed 003, "
                  "Fig. 3b): the plate follows nothing above ~400 Hz, so an output rate a few times "
                  "that (2 kHz) already carries all it can reproduce; higher rates only place "
                  "steps more finely in time (1 / rate: 0.5 ms at 2 kHz, 0.05 ms at 20 kHz). "
                  "Hybrid, gratings, human motion, mean over gratings:", ""]
        lines += _table(["metric", *(f"{h / 1000:g} kHz" for h in rates)],
                        [(m, *_by_rate(hybrid, "output_hz", rates, m)) for m in METRICS])
        lines.append("")
    held = [r for r in rows if r["scene"] == "grating-0.6mm" and r["renderer"] == "sho-held"
            and r["output_hz"] == OUTPUT_HZ and r["inversion"] == "exact"]
    touch = sorted({r["touch_hz"] for r in held})
    lines += ["Touch rate against texture frequency: a grating of period P under a finger at v "
              "is a signal at v / P (0.6 mm at 40 mm/s: 67 Hz); position-map rendering (SHO) "
              "can only render up to half the touch rate (25 Hz at 50 Hz, seed 003 section "
              "4.4.1), above which it aliases. sho-held on the 0.6 mm grating, spectral error by "
              "touch rate (mean over motions):", ""]
    lines += _table(["touch rate", *(f"{t:g} Hz" for t in touch)],
                    [("spectral error", *_by_rate(held, "touch_hz", touch, "spectral_error"))])
    lines += ["", "## Inversion", "",
              "Exact (seed 003 eq 3, closed form) against the table built at scene load "
              "(rendering/inversion_lut.py); the table's amplitude error is reported in "
              "settings.lut_max_error_um. Mean over the gratings, human motion, 50 Hz, 10 kHz:", ""]
    inv = [r for r in _grating_rows(rows) if r["motion"] == "human" and r["output_hz"] == OUTPUT_HZ]
    names = sorted({r["inversion"] for r in inv})
    lines += _table(["", *names],
                    [(m, *_by_rate(inv, "inversion", names, m)) for m in (*METRICS, "cost_us_per_s")]
                    + [("inversion us/s", *[
                        f"{np.mean([r['stages_us_per_s']['inversion'] for r in inv if r['inversion'] == n]):.0f}"
                        for n in names])])
    lines += ["", "## Modal inversion (two fingers, seed 000 beam)", "",
              "Each method of device/actuation/modal.py on seed 000's beam (modes 16, 17; actuator "
              "limit 0.75 um), two fingers at random and near-singular (within 0.5 mm) "
              "positions; the default, regularised, is the one that stays continuous across "
              "a singular locus (app/measure/bench_modal.py says how each figure is made):", ""]
    lines += _table(["figure", "value", "unit"],
                    [(f["label"], f"{f['value']:.4g}", f["unit"]) for f in doc["modal_inversion"]])
    if doc.get("closed_loop") is not None:
        from frictex.app.measure.report_closed_loop import markdown as loop_lines
        lines += ["", *loop_lines(doc["closed_loop"])[:-1]]
    lines += ["", "## Plots", ""] + [f"![{p}]({p})" for p in plots]
    path.write_text("\n".join(lines) + "\n", encoding="utf-8")
