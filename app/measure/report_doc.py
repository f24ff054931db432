"""``frictex report``'s document: what ``report.json`` holds, as records, written and read
back.

``report.json``::

    {"report_version": 3, "quick": bool, "settings": {...}, "rows": [row, ...],
     "claims": [{"group", "scene", "motion", "metric", "text", "mean", "low", "high", "n",
                 "passed", "verdict", "decided_by"}, ...],
     "headline": {...}, "modal_replay": {...}, "draws": {...}, "real": {...} or null,
     "modal_inversion": [...], "end_to_end": {...} or null, "closed_loop": {...} or null,
     "timings": {section: {"wall_s", "load_1min"}, ...}}

``timings``: each section's wall time (s) and the machine's 1-minute load average as it
started and ended (``Timing``), by the names of ``SECTIONS``; "whole report" runs from
the command's start to the end of its sections, before its files (this one among them)
are written: the command's last line gives the time with them written.

Claims are computed on ``draws`` (``app.measure.report_seeds``), paired by draw, with a
95 % interval (``app.measure.report_claims``; ``decided_by`` "95 % interval", or for a
claim decided by one number "worst run", "bound" or "by construction", with ``low``
and ``high`` null); ``passed`` is true only where the interval
excludes a loss; ``verdict`` is "holds" (``passed``), "does not hold" (the whole interval
on the losing side) or "not shown" (the interval straddles the claim's bound). A
report.json written before ``verdict`` existed reads back with it derived. ``closed_loop`` (``app.measure.report_closed_loop``): open loop,
closed loop and closed loop with adaptation over a simulated population of fingers;
its claims (groups "closed loop: ...") are in the same list, paired per finger.

Each row (``app.measure.report_matrix.Row``) has ``scene``, ``period_mm`` (null for scenes
that are not one grating), ``motion``, ``touch_hz``, ``renderer``, ``output_hz``,
``inversion``, ``time_error``, ``spectral_error``, ``alignment_error_mm``, ``chatter``
(edges felt twice, ``rendering.metrics.chatter``; on the 15 and 5 mm gratings, else null),
``steps``, ``cost_us_per_s``, ``stages_us_per_s``, ``throughput`` (``replay_x_realtime``,
``live_block_p99_thread_cpu_us``, ``live_block_p99_wall_us``, ``live_blocks``,
``latency_ms``), ``clamps`` and ``through_plate`` (``time_error``
and ``spectral_error`` of what the plate delivers through its 400 Hz loop; the other
errors, and every claim, score the commanded mu'). ``settings.load_1min``: the machine's
1-minute load average as the matrix started and ended.
"""

from __future__ import annotations

import json
from dataclasses import asdict, dataclass
from pathlib import Path

import numpy as np

from frictex.app.measure.report_claims import GRATINGS, OUTPUT_HZ, TOUCH_HZ, Claim
from frictex.app.measure.report_loop_records import LoopSection
from frictex.app.measure.report_matrix import Row
from frictex.app.measure.report_seeds import Draws
from frictex.device.errors import InputError

REPORT_VERSION = 3
#: the parts of the report ``Report.timings`` times, in the order they run
SECTIONS = ("matrix", "modal inversion", "draws", "real recordings", "modal replay",
            "end to end", "closed loop", "whole report")
#: the scene of the headline's throughput and latency figures
HEADLINE_SCENE = "composed-fine-grating-in-disc"


@dataclass(frozen=True)
class Settings:
    """How the report was made: the reference grid (Hz), the touch noise (mm), the block
    (s), the matrix's motions (``make_motion`` arguments), the LUT inversion's largest
    amplitude error (um), this machine's CPUs, the cases run at once (None on a cluster),
    the Dask scheduler (None: this machine), the matrix's wall time (s) and the machine's
    1-minute load average as the matrix started and ended (None: not recorded, as in a
    report.json written before it was)."""

    reference_hz: float
    touch_noise_mm: float
    block_s: float
    motions: dict
    lut_max_error_um: float
    cpu_count: int | None
    jobs: int | None
    scheduler: str | None
    wall_s: float
    load_1min: tuple[float, float] | None = None


@dataclass(frozen=True)
class Timing:
    """When a part of the report ran: its wall time (s) and the machine's 1-minute load
    average as it started and ended."""

    wall_s: float
    load_1min: tuple[float, float]

    def conditions(self) -> str:
        """'1-minute load 2.8-3.3, 41 s' for report.md."""
        low, high = sorted(self.load_1min)
        return f"1-minute load {low:.1f}-{high:.1f}, {self.wall_s:.3g} s"


@dataclass(frozen=True)
class HeadlineEntry:
    """The throughput and latency of one renderer and motion on the composed scene (one
    finger, 10 kHz, exact inversion): the row's ``throughput`` and costs (us/s)."""

    replay_x_realtime: float
    live_block_p99_thread_cpu_us: float
    live_block_p99_wall_us: float
    live_blocks: int
    latency_ms: float
    cost_us_per_s: float
    stages_us_per_s: dict[str, float]


def headline(rows: list[Row]) -> dict[str, HeadlineEntry]:
    """The throughput and latency figures of issue 4 by ``renderer/motion``: composed
    scene, one finger, 50 Hz touch, 10 kHz, exact inversion."""
    return {f"{r.renderer}/{r.motion}": HeadlineEntry(
                **asdict(r.throughput), cost_us_per_s=r.cost_us_per_s,
                stages_us_per_s=r.stages_us_per_s)
            for r in rows if r.scene == HEADLINE_SCENE and r.output_hz == OUTPUT_HZ
            and r.inversion == "exact" and r.touch_hz == TOUCH_HZ}


def grating_rows(rows: list[Row], touch_hz: float = TOUCH_HZ) -> list[Row]:
    """The rows on the seed 003 gratings at ``touch_hz``."""
    return [r for r in rows if r.scene in GRATINGS and r.touch_hz == touch_hz]


def mean_defined(values) -> float:
    """Mean of the defined values (None: a metric with nothing to measure), NaN if none."""
    defined = [v for v in values if v is not None]
    return float(np.mean(defined)) if defined else float("nan")


@dataclass(frozen=True)
class Report:
    """Everything ``report.json`` holds (module docstring). ``modal_replay``:
    ``app.measure.bench_pipeline.modal_throughput``; ``real``:
    ``app.measure.report_real.real_section`` or None; ``modal_inversion``: the figures of
    ``app.measure.bench_modal.run``; ``end_to_end``: ``app.measure.bench_replay.end_to_end``
    or None; ``timings``: ``Timing`` by the names of ``SECTIONS`` (those run)."""

    quick: bool
    settings: Settings
    rows: list[Row]
    claims: list[Claim]
    headline: dict[str, HeadlineEntry]
    modal_replay: dict
    draws: Draws
    real: dict | None
    modal_inversion: list[dict]
    end_to_end: dict | None
    closed_loop: LoopSection | None
    timings: dict[str, Timing]

    def to_json(self) -> dict:
        """The document as report.json holds it."""
        return {"report_version": REPORT_VERSION, "quick": self.quick,
                "settings": asdict(self.settings), "rows": [r.to_json() for r in self.rows],
                "claims": [asdict(c) for c in self.claims],
                "headline": {k: asdict(v) for k, v in self.headline.items()},
                "modal_replay": self.modal_replay, "draws": self.draws.to_json(),
                "real": self.real, "modal_inversion": self.modal_inversion,
                "end_to_end": self.end_to_end,
                "closed_loop": None if self.closed_loop is None else self.closed_loop.to_json(),
                "timings": {k: asdict(v) for k, v in self.timings.items()}}

    @classmethod
    def from_json(cls, doc: dict) -> Report:
        """A report read back from report.json's document (InputError for another
        version)."""
        if doc.get("report_version") != REPORT_VERSION:
            raise InputError(f"report.json: report_version {doc.get('report_version')!r}; "
                             f"this frictex reads version {REPORT_VERSION}")
        loop = doc["closed_loop"]
        return cls(quick=doc["quick"], settings=Settings(**doc["settings"]),
                   rows=[Row.from_json(r) for r in doc["rows"]],
                   claims=[Claim(**c) for c in doc["claims"]],
                   headline={k: HeadlineEntry(**v) for k, v in doc["headline"].items()},
                   modal_replay=doc["modal_replay"], draws=Draws.from_json(doc["draws"]),
                   real=doc["real"], modal_inversion=doc["modal_inversion"],
                   end_to_end=doc["end_to_end"],
                   closed_loop=None if loop is None else LoopSection.from_json(loop),
                   timings={k: Timing(v["wall_s"], tuple(v["load_1min"]))
                            for k, v in doc["timings"].items()})

    def write(self, path: Path) -> None:
        """Write report.json."""
        path.write_text(json.dumps(self.to_json(), indent=1) + "\n", encoding="utf-8")

    @classmethod
    def read(cls, path: Path) -> Report:
        """Read report.json back (InputError naming the file if it cannot be read)."""
        try:
            doc = json.loads(Path(path).read_text(encoding="utf-8"))
        except (OSError, ValueError) as exc:
            raise InputError(f"{path}: cannot read a report: {exc}") from None
        return cls.from_json(doc)
