"""The analysis figure: one panel per study (``analysis.analyse``'s summaries).

Forced choice: proportion correct per difference (marker area by trials), the pooled
fit (labelled as pooled where it pools sessions), its threshold and 95 % interval. Same-different: hit and false-alarm rates per level.
Magnitude: mean rating per stimulus with its 95 % interval. Drawn with matplotlib's Agg
backend (no display needed); the layout keeps every label within the canvas.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np

from frictex.device.errors import require_extra


def _forced_choice(ax, s: dict) -> None:
    from frictex.app.experiment.psychometric import psi
    fit = s["pooled"]
    unit = s["vary"] or ""
    if fit is None:
        ax.text(0.5, 0.5, f"no threshold: {s['no_fit']}", ha="center", va="center",
                transform=ax.transAxes, wrap=True)
        return
    x = np.array([lv["difference"] for lv in fit["levels"]])
    n = np.array([lv["trials"] for lv in fit["levels"]])
    k = np.array([lv["correct"] for lv in fit["levels"]])
    ax.scatter(x, k / n, s=12 + 60 * n / n.max(), color="0.3", zorder=3, label="observed (area ∝ trials)")
    grid = np.linspace(x.min() * 0.8, x.max() * 1.1, 300)
    grid = grid[grid > 0]
    ax.plot(grid, psi(fit["function"], grid, fit["alpha"], fit["beta"], fit["guess"],
                      fit["lapse"]), color="C0", label=f"{fit['function']} fit"
            + (f", {s['sessions']} sessions pooled" if s["sessions"] > 1 else ""))
    lo, hi = fit["threshold_ci95"]
    if lo is not None and hi is not None:
        ax.axvspan(lo, hi, color="C1", alpha=0.2, label="threshold 95 %")
    if fit["threshold"] is not None:
        ax.axvline(fit["threshold"], color="C1", lw=1)
    if fit["threshold_below"] is not None and math.isfinite(fit["threshold_below"]):
        ax.axvspan(0.0, fit["threshold_below"], color="C1", alpha=0.2,
                   label="threshold below (every trial correct)")
    ax.axhline(fit["target"], color="0.6", lw=0.8, ls=":")
    ax.set_ylim(min(0.4, float((k / n).min()) - 0.05), 1.02)
    ax.set_xlabel(f"difference from the reference ({unit})")
    ax.set_ylabel("proportion correct")
    ax.legend(fontsize=7, loc="lower right")


def _same_different(ax, s: dict) -> None:
    levels = s["levels"]
    v = [lv["value"] for lv in levels]
    ax.plot(v, [lv["hit_rate"] for lv in levels], "o-", label="hits (AB, BA)")
    ax.plot(v, [lv["false_alarm_rate"] for lv in levels], "s--", label="false alarms (AA, BB)")
    ax.set_ylim(-0.02, 1.02)
    ax.set_xlabel(f"comparison ({s['vary']})")
    ax.set_ylabel('proportion "different"')
    ax.legend(fontsize=7)


def _magnitude(ax, s: dict) -> None:
    items = s["stimuli"]
    means = np.array([st["mean"] for st in items])
    err = np.array([[st["mean"] - (st["ci95"][0] if st["ci95"][0] is not None else st["mean"]),
                     (st["ci95"][1] if st["ci95"][1] is not None else st["mean"]) - st["mean"]]
                    for st in items]).T
    ax.bar(range(len(items)), means, yerr=err, color="C0", capsize=3)
    ax.set_xticks(range(len(items)), [st["stimulus"] for st in items], rotation=30, ha="right",
                  fontsize=7)
    if s.get("scale"):
        ax.set_ylim(s["scale"][0] - 0.5, s["scale"][1] + 0.5)
    ax.set_ylabel("mean rating")


def plot_studies(summaries: list[dict], path: Path) -> None:
    """One panel per study into the PNG ``path``."""
    require_extra("report", "matplotlib", "the analysis plot")
    import matplotlib
    matplotlib.use("Agg")
    from matplotlib.figure import Figure
    fig = Figure(figsize=(5.5, 3.8 * len(summaries)), layout="constrained")
    axes = fig.subplots(len(summaries), 1, squeeze=False)[:, 0]
    for ax, s in zip(axes, summaries):
        {"2afc": _forced_choice, "staircase": _forced_choice,
         "same-different": _same_different, "magnitude": _magnitude}[s["method"]](ax, s)
        ax.set_title(f"{s['study']} ({s['method']}, {s['sessions']} session"
                     f"{'s' * (s['sessions'] != 1)})", fontsize=9)
    fig.savefig(path, dpi=120)
