"""``frictex report``'s plots of the matrix: error against compute cost, and error against
grating period. Each ``*_figure`` function builds a matplotlib figure (tests check it with
``app.measure.figure_check.text_flaws``); :func:`save` writes and closes it.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np

from frictex.app.measure.report_claims import GRATINGS, METRICS, OUTPUT_HZ
from frictex.app.measure.report_doc import grating_rows, mean_defined
from frictex.app.measure.report_matrix import Row, aliased

LABELS = {"time_error": "time error (NRMS)", "spectral_error": "spectral error",
          "alignment_error_mm": "alignment error (mm)"}
#: where a label may sit beside its point (offset points), in order of preference
LABEL_OFFSETS = ((4, 4), (4, -11), (-4, 4), (-4, -11), (4, 14), (4, -21), (-4, 14), (-4, -21))
#: resolution of the saved pictures (dots per inch)
DPI = 110


def pyplot():
    """matplotlib's pyplot on the Agg backend (no display needed)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt
    return plt


def save(fig, path: Path) -> None:
    """Write ``fig`` to ``path`` and close it."""
    fig.savefig(path, dpi=DPI)
    pyplot().close(fig)


def pareto(points: list[tuple[float, float]]) -> list[bool]:
    """Which (cost, error) points no other point beats on both (ties count as beaten only
    when strictly worse on one and no better on the other)."""
    out = []
    for c, e in points:
        out.append(not any((c2 <= c and e2 <= e) and (c2 < c or e2 < e) for c2, e2 in points))
    return out


#: gratings left out of a metric's mean in the cost plot: the 0.6 mm grating's time error
#: measures a spatial phase no finger feels, and no claim is made on it
#: (``report_claims.NOT_CLAIMED``)
LEFT_OUT = {"time_error": ("grating-0.6mm",)}


def _config_points(rows: list[Row]) -> dict[str, dict[str, float]]:
    """Per configuration seen on the gratings at 50 Hz for every motion it ran:
    the median cost over the gratings (one warm timing each, none dropped:
    ``report_markdown.WARM_TIMING``) and the mean of each metric over the motions the sweep shares
    (human) and the gratings (those of ``LEFT_OUT`` left out of that metric's mean)."""
    configs: dict[str, list[Row]] = {}
    for r in grating_rows(rows):
        if r.motion == "human":
            configs.setdefault(r.config, []).append(r)
    return {name: {"cost": float(np.median([r.cost_us_per_s for r in rs])),
                   **{m: mean_defined(getattr(r, m) for r in rs
                                      if r.scene not in LEFT_OUT.get(m, ())) for m in METRICS}}
            for name, rs in configs.items()}


def _panel_label(metric: str) -> str:
    """The cost plot's y label: the metric, and the gratings its mean covers."""
    left = LEFT_OUT.get(metric, ())
    kept = [f"{p:g}" for s, p in GRATINGS.items() if s not in left]
    return f"{LABELS[metric]}, {', '.join(kept)} mm" + (" only" if left else "")


def _empty(fig):
    fig.text(0.5, 0.5, "no seed 003 grating rows at 50 Hz in this report", ha="center")
    for ax in fig.axes:
        ax.set_axis_off()
    return fig


def _log_x(ax, values) -> None:
    """A log x axis labelled at 1, 2 and 5 times powers of ten where the values span at
    most two decades, at powers of ten otherwise; no minor labels (they collide)."""
    from matplotlib.ticker import FuncFormatter, LogLocator, NullFormatter
    ax.set_xscale("log")
    values = [v for v in values if v > 0]
    decades = np.log10(max(values) / min(values)) if values else 0.0
    subs = (1.0, 2.0, 5.0) if decades <= 2 else (1.0,)
    ax.xaxis.set_major_locator(LogLocator(base=10, subs=subs))
    ax.xaxis.set_major_formatter(FuncFormatter(lambda v, _: f"{v:g}"))
    ax.xaxis.set_minor_formatter(NullFormatter())


def label_points(ax, points, labels, fontsize: float = 6) -> None:
    """Label each (x, y) data point of ``ax`` beside it where the label overlaps no label
    placed before and stays inside the axes (``LABEL_OFFSETS`` in turn); points whose
    labels coincide share one label ("a; b"); a point with no free place is left
    unlabelled."""
    fig = ax.figure
    fig.draw_without_rendering()  # settle the layout: display positions are final
    renderer = fig.canvas.get_renderer()
    inside = ax.get_window_extent(renderer)
    merged: dict[tuple[int, int], list] = {}
    for (x, y), name in zip(points, labels):
        px, py = ax.transData.transform((x, y))
        merged.setdefault((round(px / 6), round(py / 6)), [(x, y), []])[1].append(name)
    placed = []
    for (x, y), names in merged.values():
        for dx, dy in LABEL_OFFSETS:
            text = ax.annotate("; ".join(names), (x, y), fontsize=fontsize, xytext=(dx, dy),
                               textcoords="offset points", ha="left" if dx > 0 else "right")
            box = text.get_window_extent(renderer)
            if (box.x0 >= inside.x0 and box.x1 <= inside.x1 and box.y0 >= inside.y0
                    and box.y1 <= inside.y1 and not any(box.overlaps(b) for b in placed)):
                placed.append(box)
                break
            text.remove()


def cost_figure(rows: list[Row]):
    """Error against compute cost per second of output, one point per configuration; the
    Pareto front's points labelled."""
    plt = pyplot()
    points = _config_points(rows)
    fig, axes = plt.subplots(1, 3, figsize=(15, 5.4), constrained_layout=True)
    if not points:
        return _empty(fig)
    names = sorted(points)
    colours = {r: f"C{k}" for k, r in enumerate(sorted({n.split()[0] for n in names}))}
    fronts = []
    for ax, metric in zip(axes, METRICS):
        xy = [(points[n]["cost"], points[n][metric]) for n in names]
        front = pareto(xy)
        for (x, y), n, f in zip(xy, names, front):
            ax.scatter(x, y, s=28, c=colours[n.split()[0]], marker="s" if "lut" in n else "o",
                       edgecolors="k" if f else "none", zorder=3)
        fx = sorted((p for p, f in zip(xy, front) if f))
        ax.step([p[0] for p in fx], [p[1] for p in fx], where="post", c="k", lw=0.8)
        _log_x(ax, [p[0] for p in xy])
        ax.set_xlabel("compute per second of output (us/s; 2-20 kHz output)")
        ax.set_ylabel(_panel_label(metric), fontsize=8)
        ax.grid(True, which="both", alpha=0.3)
        fronts.append([(p, n) for p, n, f in zip(xy, names, front) if f])
    handles = [plt.Line2D([], [], c="k", lw=0.8, label="Pareto front (labelled)")]
    handles += [plt.Line2D([], [], ls="", marker="o", c=c, label=r) for r, c in colours.items()]
    handles.append(plt.Line2D([], [], ls="", marker="s", mfc="w", mec="k", label="LUT inversion"))
    fig.legend(handles=handles, loc="outside lower center", ncol=len(handles), fontsize=8)
    fig.suptitle("Error against cost: seed 003 gratings, human-like motion (one draw), 50 Hz "
                 "touch; errors of the commanded mu'")
    for ax, front in zip(axes, fronts):
        label_points(ax, [p for p, _ in front], [n for _, n in front])
    return fig


def period_figure(rows: list[Row]):
    """Each metric against grating period, one line per renderer (50 Hz, 10 kHz, exact),
    the mean over the motions; aliasing-degenerate rows (``report_matrix.aliased``) are
    left out, as the tables mark them: they measure no renderer."""
    plt = pyplot()
    base = [r for r in grating_rows(rows) if r.output_hz == OUTPUT_HZ and r.inversion == "exact"
            and not aliased(r)]
    renderers = sorted({r.renderer for r in base})
    periods = sorted(set(GRATINGS.values()))
    fig, axes = plt.subplots(1, 3, figsize=(15, 4.5), constrained_layout=True)
    if not base:
        return _empty(fig)
    for ax, metric in zip(axes, METRICS):
        for name in renderers:
            ys = [mean_defined(getattr(r, metric) for r in base
                               if r.renderer == name and r.period_mm == p) for p in periods]
            ax.plot(periods, ys, marker="o", label=name)
        _log_x(ax, periods)
        ax.set_yscale("log")
        ax.set_xlabel("grating period (mm)")
        ax.set_ylabel(LABELS[metric] + ", mean over motions")
        ax.grid(True, which="both", alpha=0.3)
        ax.legend(fontsize=8)
    fig.suptitle("Error against grating period, per renderer (50 Hz touch, 10 kHz output; "
                 "aliasing-degenerate rows left out)")
    return fig
