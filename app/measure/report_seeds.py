"""The draws behind ``frictex report``'s claims: the seed 003 gratings under many
independent draws of finger motion, every renderer on the same draws.

Three kinds of motion, each drawn ``n`` times (16; 8 with ``--quick``), sampled at
50 Hz with the matrix's 0.05 mm touch noise and rendered at 10 kHz, exact inversion:

- ``human``: human-like strokes (``rendering.input.trace_synth``): draw k uses the
  minimum-jerk strokes and pauses of ``human`` for odd k and the ``human-varied`` mix
  (speed rippling within strokes, creeping, flicks, reversals, arcs, pauses) for even k,
  motion seed k; the touch trace is sampled 2 ms (standard deviation) off the 50 Hz
  grid, each sample stamped with the time it was taken (irregular but true stamps), and
  drops 5 % of the samples, as real controllers do;
- ``slow`` and ``fast``: the matrix's constant-speed swipes (20 and 120 mm/s), draw k
  with its own touch noise.

Draw k of every renderer renders the same trace, so claims compare renderers paired by
draw (``app.measure.report_claims``).
"""

from __future__ import annotations

from dataclasses import asdict, dataclass
from functools import partial

import numpy as np

from frictex.app.engine.fanout import fan_out
from frictex.app.measure.report_claims import GRATINGS, METRICS, OUTPUT_HZ, TOUCH_HZ
from frictex.app.measure.report_matrix import MOTIONS, Case, run_case
from frictex.rendering.renderers import RENDERERS

#: draws of each kind; every registered renderer runs on each (``auto`` picks the hybrid)
DRAWS = 16
QUICK_DRAWS = 8
#: motion kinds of the draws
KINDS = ("human", "slow", "fast")
#: timing faults of the human-like draws' touch traces
JITTER_S = 0.002
DROP = 0.05
#: what each draw keeps: the claims' metrics and the edges felt twice
#: (``rendering.metrics.chatter``)
DRAW_METRICS = (*METRICS, "chatter")


@dataclass(frozen=True)
class Draws:
    """Every renderer on ``n`` draws of each kind: ``values[scene][kind][renderer][metric]``
    is the metric per draw (alignment error and chatter None where undefined)."""

    n: int
    kinds: list[str]
    renderers: list[str]
    values: dict[str, dict[str, dict[str, dict[str, list]]]]

    def to_json(self) -> dict:
        """The draws as report.json holds them."""
        return asdict(self)

    @classmethod
    def from_json(cls, doc: dict) -> Draws:
        """Draws read back from report.json."""
        return cls(**doc)


def motions(n: int) -> dict:
    """``make_motion`` arguments (with their ``sampling``) per draw name ``<kind>-<k>``."""
    out = {}
    for k in range(1, n + 1):
        out[f"human-{k}"] = {**MOTIONS["human"], "kind": "human" if k % 2 else "human-varied",
                             "seed": k, "sampling": {"seed": 1000 + k, "jitter_s": JITTER_S,
                                                     "drop": DROP}}
        for kind in ("slow", "fast"):
            out[f"{kind}-{k}"] = {**MOTIONS[kind], "sampling": {"seed": 1000 + k}}
    return out


def draws(n: int, scenes=tuple(GRATINGS), workers: int = 1,
          scheduler: str | None = None) -> Draws:
    """Every renderer on ``n`` draws of each kind, per grating in ``scenes``."""
    spec = motions(n)
    cases = [Case(scene, f"{kind}-{k}", TOUCH_HZ, renderer, OUTPUT_HZ)
             for scene in scenes for kind in KINDS for k in range(1, n + 1)
             for renderer in RENDERERS.names()]
    rows = fan_out(partial(run_case, live_s=0.005, motions=spec, plate=False), cases,
                   workers=workers, scheduler=scheduler)
    values: dict = {}
    for case, row in zip(cases, rows):
        kind = case.motion.rsplit("-", 1)[0]
        per = values.setdefault(case.scene, {}).setdefault(kind, {}).setdefault(
            case.renderer, {m: [] for m in DRAW_METRICS})
        for m in DRAW_METRICS:
            per[m].append(getattr(row, m))
    return Draws(n, list(KINDS), list(RENDERERS.names()), values)


def summary_lines(doc: Draws) -> list[str]:
    """The report.md table of :func:`draws`: each metric's mean (min-max) over the draws."""
    lines = [f"## Draws (50 Hz touch, 10 kHz output, {doc.n} draws of each kind)", "",
             "Every claim above is computed on these draws, paired by draw (see "
             "app/measure/report_seeds.py for how they are made): mean (min-max) of each "
             "metric; chatter: edges felt twice (rendering/metrics.py), total over the "
             "draws, on the 15 and 5 mm gratings.", "",
             "| scene | motion | renderer | time | spectral | alignment mm | chatter |",
             "|---|---|---|---|---|---|---|"]
    for scene, kinds in doc.values.items():
        for kind, per in kinds.items():
            for renderer, metrics in per.items():
                doubled = [v for v in metrics.get("chatter", []) if v is not None]
                lines.append(f"| {scene} | {kind} | {renderer} | "
                             + " | ".join(_spread(metrics[m]) for m in METRICS)
                             + f" | {sum(doubled) if doubled else '-'} |")
    return lines + [""]


def _spread(values) -> str:
    defined = [v for v in values if v is not None]
    if not defined:
        return "-"
    return f"{np.mean(defined):.3f} ({min(defined):.3f}-{max(defined):.3f})"
