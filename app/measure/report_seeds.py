"""How much of a claim is the draw: the seed 003 gratings under human-like motions drawn
with several seeds (``rendering.input.trace_synth``'s ``human`` strokes; the matrix uses one, seed 7).

Each seed is a different stroke pattern (pauses, reversals, speeds), sampled at 50 Hz
with the matrix's touch noise and rendered at 10 kHz, exact inversion, by plain SHO
(sho-held), SHT and the hybrid. The report shows each metric's mean and range over the
seeds, and in how many seeds the hybrid is no worse than the better of SHO and SHT: a
claim that holds in some draws and not others is about the draw, not the renderer.
"""

from __future__ import annotations

import numpy as np

from app.measure.report_claims import GRATINGS, METRICS, OUTPUT_HZ, TOUCH_HZ
from app.measure.report_matrix import MOTIONS, Case, Runner

RENDERERS = ("sho-held", "sht", "hybrid")
SEEDS = tuple(range(1, 9))
QUICK_SEEDS = SEEDS[:4]


def motions(seeds) -> dict:
    """make_motion arguments per motion name ``human-seed<k>``."""
    return {f"human-seed{k}": {**MOTIONS["human"], "seed": k} for k in seeds}


def scatter(seeds=SEEDS, scenes=tuple(GRATINGS)) -> dict:
    """Per grating, renderer and metric the values over ``seeds``; per grating and metric
    the number of seeds where the hybrid is no worse than the better of SHO and SHT.

    Returns ``{"seeds": [...], "values": {scene: {renderer: {metric: [...]}}},
    "hybrid_best": {scene: {metric: wins}}}`` (alignment error None where undefined).
    """
    runner = Runner(live_s=0.01, motions=motions(seeds))
    values: dict = {}
    for scene in scenes:
        per = values.setdefault(scene, {})
        for renderer in RENDERERS:
            rows = [runner.run(Case(scene, name, TOUCH_HZ, renderer, OUTPUT_HZ))
                    for name in runner.motions]
            per[renderer] = {m: [r[m] for r in rows] for m in METRICS}
    wins = {scene: {m: _wins(per, m) for m in METRICS} for scene, per in values.items()}
    return {"seeds": list(seeds), "values": values, "hybrid_best": wins}


def _wins(per: dict, metric: str) -> int:
    """Seeds where the hybrid's ``metric`` is at most the better of SHO's and SHT's (an
    undefined alignment error, no step to match in any of the three, counts as a win)."""
    wins = 0
    for h, a, b in zip(*(per[r][metric] for r in ("hybrid", "sho-held", "sht"))):
        defined = [v for v in (a, b) if v is not None]
        wins += h is None or not defined or h <= min(defined)
    return wins


def summary_lines(doc: dict) -> list[str]:
    """The report.md section for :func:`scatter`'s result."""
    n = len(doc["seeds"])
    lines = ["## Seed scatter (human-like motion, 50 Hz, 10 kHz)", "",
             f"The matrix's human-like motion is one draw (seed 7). Here the same kind of strokes "
             f"drawn with seeds {doc['seeds'][0]}-{doc['seeds'][-1]}: mean (min-max) of each "
             "metric, and in how many seeds the hybrid is no worse than the better of SHO and "
             "SHT.", "",
             "| scene | renderer | time | spectral | alignment mm |", "|---|---|---|---|---|"]
    for scene, per in doc["values"].items():
        for renderer, metrics in per.items():
            lines.append(f"| {scene} | {renderer} | "
                         + " | ".join(_spread(metrics[m]) for m in METRICS) + " |")
        wins = doc["hybrid_best"][scene]
        lines.append(f"| {scene} | hybrid no worse, seeds | "
                     + " | ".join(f"{wins[m]} of {n}" for m in METRICS) + " |")
    return lines + [""]


def _spread(values) -> str:
    defined = [v for v in values if v is not None]
    if not defined:
        return "-"
    return f"{np.mean(defined):.3f} ({min(defined):.3f}-{max(defined):.3f})"
