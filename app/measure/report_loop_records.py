"""The records of ``frictex report``'s closed-loop section (``app.measure.report_closed_loop``):
one run's measurements, and the section's population statistics as report.json holds
them (``to_json`` and ``from_json`` keep its keys: a figure a mode does not have is left
out of its object, not written as null).

RMS figures are of mu' (dimensionless); times in s; amplitudes in um; forces in N.
"""

from __future__ import annotations

from dataclasses import asdict, dataclass, fields

import numpy as np


def _present(record, always=()) -> dict:
    """The record's fields as a dict, those that are None left out unless in ``always``."""
    return {f.name: getattr(record, f.name) for f in fields(record)
            if getattr(record, f.name) is not None or f.name in always}


@dataclass(frozen=True)
class LoopScore:
    """What a loop mode's run adds: the loop's fallbacks, its final log gain, mu0
    estimate and RLS model (``b_per_um``, ``k_per_n``), the longest run of gain swings,
    when it first knew mu0 (s; None: never) and the reachable RMS from then on (None:
    never)."""

    fallbacks: int
    log_c: float
    mu0_estimate: float
    b_per_um: float
    k_per_n: float
    swings: int
    first_mu0_s: float | None
    rms_after_mu0: float | None


@dataclass(frozen=True)
class RunScore:
    """One run's measurements (``report_closed_loop.score``): ``rms`` against the target,
    ``rms_reachable`` against the best the plate can deliver, the largest amplitude
    commanded (um); ``cumulative`` (open loop only): the squared reachable error summed
    up to each block and the samples counted, (sse, count); ``loop``: the loop modes'
    figures; ``adapted_gap`` (adaptive): the adapted model's relative RMS gap to the
    finger; ``noise_n`` and ``noise_fraction`` (adaptive runs with a noise rerun): the
    force noise the loop adds (N RMS) and its fraction of the mean friction force."""

    rms: float
    rms_reachable: float
    max_command_um: float
    cumulative: tuple[np.ndarray, np.ndarray] | None = None
    loop: LoopScore | None = None
    adapted_gap: float | None = None
    noise_n: float | None = None
    noise_fraction: float | None = None


@dataclass(frozen=True)
class PerFinger:
    """Each finger's figures of one scene and mode, in finger order (the loop modes'
    fields None for open loop; ``open_rms_after_mu0``: open loop's reachable RMS over the
    samples this mode's loop had mu0, None where it never had; ``noise_fraction``: the
    fingers with a noise rerun)."""

    rms_reachable: list[float]
    max_command_um: list[float]
    swings: list[int] | None = None
    rms_after_mu0: list[float | None] | None = None
    first_mu0_s: list[float | None] | None = None
    open_rms_after_mu0: list[float | None] | None = None
    noise_fraction: list[float] | None = None

    def to_json(self) -> dict:
        return _present(self)


@dataclass(frozen=True)
class LoopFigures:
    """The loop modes' population figures: the longest run of gain swings, how many
    fingers never found mu0, the population's reachable RMS from mu0 on (None: no finger
    found it), when mu0 was found (median, and the latest: None unless every finger found
    it), and open loop's RMS over the same samples against this mode's (None without an
    open-loop mode or a finger that found mu0)."""

    swings_max: int
    mu0_missing: int
    rms_after_mu0_pop: float | None
    first_mu0_s_median: float | None
    first_mu0_s_max: float | None
    gain_after_mu0: float | None = None

    def to_json(self) -> dict:
        return _present(self, always=("rms_after_mu0_pop", "first_mu0_s_median",
                                      "first_mu0_s_max"))


@dataclass(frozen=True)
class ModeSummary:
    """One scene and mode over the population: RMS over fingers of each finger's
    reachable RMS (``rms_reachable_pop``) and raw RMS (``rms_pop``), the worst finger's
    reachable RMS and its number (1-based), fallbacks, the largest amplitude commanded
    (um), ``per_finger``; ``loop``: the loop modes' figures; the adaptive mode's largest
    noise fraction (None without noise reruns) and adapted gap; against open loop (loop
    modes beside an open one): the population RMS gain, and the finger this mode treats
    worst against open loop, finger by finger: the largest ratio of its RMS to open
    loop's RMS on the same finger (``worst_ratio``; above 1: made worse) and that
    finger's number (1-based)."""

    rms_reachable_pop: float
    worst: float
    worst_finger: int
    rms_pop: float
    fallbacks: int
    max_command_um: float
    per_finger: PerFinger
    loop: LoopFigures | None = None
    noise_fraction_max: float | None = None
    adapted_gap_max: float | None = None
    gain_vs_open: float | None = None
    worst_ratio: float | None = None
    worst_ratio_finger: int | None = None

    def to_json(self) -> dict:
        """One flat object, as report.json holds it (the loop's figures beside the rest)."""
        doc = {k: v for k, v in _present(self).items() if k not in ("per_finger", "loop")}
        doc["per_finger"] = self.per_finger.to_json()
        if self.loop is not None:
            doc.update(self.loop.to_json())
        return doc

    @classmethod
    def from_json(cls, doc: dict) -> ModeSummary:
        names = {f.name for f in fields(LoopFigures)}
        loop = ({k: v for k, v in doc.items() if k in names} if "swings_max" in doc else None)
        rest = {k: v for k, v in doc.items() if k not in names and k != "per_finger"}
        return cls(**rest, per_finger=PerFinger(**doc["per_finger"]),
                   loop=LoopFigures(**loop) if loop is not None else None)


@dataclass(frozen=True)
class Adaptation:
    """The adaptation study: ``fingers`` fingers adapting ``duration_s`` on ``scene``;
    each one's gap (the adapted model's relative RMS against the true finger), largest
    and median."""

    scene: str
    duration_s: float
    fingers: int
    gap_max: float
    gap_median: float
    gaps: list[float]


@dataclass(frozen=True)
class LoopSection:
    """The closed-loop section: the runs' settings (``rate_hz``, ``block`` samples,
    ``report_delays``: ``link_report_delays.ReportDelays.to_json``), the Weber fraction the noise is judged against, the loop's
    margins by report delay (``rendering.control.margins.margins``), the population's
    range of the slope factor s, per scene and mode its :class:`ModeSummary`, and the
    adaptation study (None where not run)."""

    fingers: int
    duration_s: float
    rate_hz: float
    block: int
    weber_fraction: float
    report_delays: dict
    margins: dict
    slope_range: tuple[float, float]
    scenes: dict[str, dict[str, ModeSummary]]
    adaptation: Adaptation | None = None

    def to_json(self) -> dict:
        doc = {k: v for k, v in _present(self).items() if k not in ("scenes", "adaptation")}
        doc["scenes"] = {scene: {mode: m.to_json() for mode, m in row.items()}
                         for scene, row in self.scenes.items()}
        if self.adaptation is not None:
            doc["adaptation"] = asdict(self.adaptation)
        return doc

    @classmethod
    def from_json(cls, doc: dict) -> LoopSection:
        scenes = {scene: {mode: ModeSummary.from_json(m) for mode, m in row.items()}
                  for scene, row in doc["scenes"].items()}
        adaptation = Adaptation(**doc["adaptation"]) if "adaptation" in doc else None
        rest = {k: v for k, v in doc.items() if k not in ("scenes", "adaptation", "slope_range")}
        return cls(**rest, slope_range=tuple(doc["slope_range"]), scenes=scenes,
                   adaptation=adaptation)
