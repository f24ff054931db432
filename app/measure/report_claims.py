"""The claims ``frictex report`` checks, each over independent draws paired by draw.

A claim compares renderers on the same draws (``app.measure.report_seeds``): per draw the
difference d = A - c B of its two sides (c = 1, or 1 + tolerance for "within x % of"),
then the mean of d over the draws and its 95 % interval (Student's t, n - 1 degrees of
freedom). Each claim gets one of three verdicts (``Claim.verdict``): it **holds** only
where the interval excludes a loss (its upper end below 0, or at most 0 for "at or
below"); it **does not hold** where the interval lies wholly on the losing side (its
lower end above 0); otherwise it is **not shown**: the interval straddles 0 and the draws
do not settle it, whatever the mean says. Each interval is per claim (95 % each, not
adjusted for how many claims the report makes): a claim with no true advantage still
reads as holding up to 1 time in 40 (one side of a 95 % interval), so a few of many
verdicts may be chance (:func:`family_note`).

Some claims are decided by one number, not an interval (``Claim.decided_by``: the worst
run's figure, a computed bound, or a figure that holds by construction); they carry no
interval ends (``low`` and ``high`` None) and the count line counts them apart.

Groups (``auto`` is what ``render = "auto"`` picks for a periodic layer: the hybrid):

- ``seed 003``: plain SHO (sho-held) against SHT at 50 Hz reproduces seed 003's
  experiment (section 5): SHT has the lower spectral error on the 0.6 mm grating, SHO the
  lower alignment error on the 15 mm grating.
- ``auto beats SHO and SHT``: on the 15 and 5 mm gratings auto has lower time and
  spectral errors than sho-held and than SHT.
- ``auto near the best``: on the 15 and 5 mm gratings, human-like motion, auto's time
  and spectral errors are within 5 % of the best other renderer's (the lowest mean).
- ``auto on fine gratings``: on the 0.6 mm grating auto's spectral error is within 3 %
  of SHT's on human-like motion, and at or below it on constant-speed swipes.

Not claimed: time error on the 0.6 mm grating (``NOT_CLAIMED``).

A spectral claim on a texture slower than ``rendering.metrics.PHASE_BLIND_HZ`` (16 Hz) at
its motion's speed (the 15 mm grating under every motion, the 5 mm grating slow and
human-like: 1.3-12 Hz) says so in its text (:func:`phase_note`): there the spectral
error counts spatial phase too (a quarter-period shift costs 0.3-1.3), so it is no
phase-blind judgement of the texture's feel.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
from scipy.stats import t as student_t

from frictex.app.measure.report_matrix import MOTIONS
from frictex.device.errors import InputError
from frictex.rendering.metrics import PHASE_BLIND_HZ

METRICS = ("time_error", "spectral_error", "alignment_error_mm")
GRATINGS = {"grating-15mm": 15.0, "grating-5mm": 5.0, "grating-0.6mm": 0.6}
TOUCH_HZ = 50.0
OUTPUT_HZ = 10_000.0
AUTO = "hybrid"
CONFIDENCE = 0.95
#: what no claim is made about, and why (shown in report.md)
NOT_CLAIMED = (
    "Time error on the 0.6 mm grating is not claimed: it measures a spatial phase no finger "
    "feels (seed 003 section 6) and no renderer gets right while the finger moves (50 Hz "
    "samples, 0.05 mm noise and up to 20 ms of extrapolation put it 0.1-0.3 mm off, a sixth "
    "to a half of the 0.6 mm period).")


HOLDS = "holds"
REFUTED = "does not hold"
NOT_SHOWN = "not shown"
#: the verdicts in the order report.md and the count line give them
VERDICTS = (HOLDS, REFUTED, NOT_SHOWN)
#: how a claim is decided (``Claim.decided_by``): its 95 % interval over the draws or
#: fingers; or one number: the worst run's figure, a computed bound, or a figure that
#: cannot miss (the claim holds by construction)
INTERVAL, WORST_RUN, BOUND, BY_CONSTRUCTION = ("95 % interval", "worst run", "bound",
                                               "by construction")
DECIDED_BY = (INTERVAL, WORST_RUN, BOUND, BY_CONSTRUCTION)


def verdict(passed: bool, low: float) -> str:
    """A claim's verdict from whether it holds and the lower end of its interval on d
    (every claim is phrased so that d < 0 is the claim): ``REFUTED`` where it does not
    hold and the whole interval lies above 0, ``NOT_SHOWN`` where it does not hold
    otherwise (an interval that straddles 0, or none: NaN)."""
    if passed:
        return HOLDS
    return REFUTED if low > 0.0 else NOT_SHOWN


@dataclass(frozen=True)
class Claim:
    """One statement over ``n`` draws: d = A - c B per draw; ``mean`` of d and its 95 %
    interval [``low``, ``high``]; ``passed``: the interval excludes a loss; ``verdict``:
    ``HOLDS``, ``REFUTED`` or ``NOT_SHOWN`` (:func:`verdict`; derived from ``passed``
    and ``low`` where not given, as for a report.json written before verdicts).
    ``decided_by``: one of ``DECIDED_BY``; a claim decided by one number has ``mean``
    that number, ``low`` and ``high`` None and ``n`` the runs or rows it was taken over."""

    group: str
    scene: str
    motion: str
    metric: str
    text: str
    mean: float
    low: float | None
    high: float | None
    n: int
    passed: bool
    verdict: str = ""
    decided_by: str = INTERVAL

    def __post_init__(self):
        if self.decided_by not in DECIDED_BY:
            raise InputError(f"claim decided_by {self.decided_by!r}: expected one of "
                             f"{DECIDED_BY}")
        if not self.verdict:
            object.__setattr__(self, "verdict", verdict(self.passed, self.low))
        elif self.verdict not in VERDICTS:
            raise InputError(f"claim verdict {self.verdict!r}: expected one of {VERDICTS}")
        elif (self.verdict == HOLDS) != self.passed:
            raise InputError(f"claim verdict {self.verdict!r} contradicts passed={self.passed}")


def count_line(found: list[Claim]) -> str:
    """"N of M claims hold, K do not, J not shown": the verdicts of ``found`` counted;
    where some are decided by one number, how many of each kind (statistical, by one
    number, by construction) hold."""
    counts = {v: sum(c.verdict == v for c in found) for v in VERDICTS}
    line = (f"{counts[HOLDS]} of {len(found)} claims hold, {counts[REFUTED]} do not, "
            f"{counts[NOT_SHOWN]} not shown")
    one_number = [c for c in found if c.decided_by != INTERVAL]
    if not one_number:
        return line
    built = [c for c in one_number if c.decided_by == BY_CONSTRUCTION]
    statistical = [c for c in found if c.decided_by == INTERVAL]

    def held(cs):
        return f"{sum(c.passed for c in cs)} of {len(cs)} hold"
    by_interval = f"by a 95 % interval: {held(statistical)}; " if statistical else ""
    return (f"{line} ({by_interval}decided by one number, "
            f"no interval: {held(one_number)}, {len(built)} of them by construction)")


def family_note(found: list[Claim]) -> str:
    """What the claims' intervals mean together: how many are statistical and that each
    interval is per claim, unadjusted (module docstring)."""
    statistical = sum(c.decided_by == INTERVAL for c in found)
    return (f"The report makes {len(found)} claims, {statistical} of them judged by a 95 % "
            "interval: each interval is per claim, not adjusted for the others (no Holm or "
            "Bonferroni correction), so a claim with no true advantage still reads as "
            "holding up to 1 time in 40 (one side of a 95 % interval): were none of these "
            f"{statistical} advantages real, about {statistical / 40:.1f} would still read as "
            "holding. The others are "
            "decided by one number (the worst run's figure, a computed bound, or a figure "
            "that cannot miss: 'by construction') and have no interval.")


def paired(a, b, scale: float = 1.0) -> tuple[float, float, float, int]:
    """Mean of d = a - scale * b over the pairs where both are defined, its 95 % interval,
    and the number of pairs: ``(mean, low, high, n)`` (interval NaN below two pairs)."""
    d = np.array([x - scale * y for x, y in zip(a, b) if x is not None and y is not None],
                 dtype=np.float64)
    if d.size < 2:
        return (float(d.mean()) if d.size else math.nan), math.nan, math.nan, int(d.size)
    half = student_t.ppf(0.5 + CONFIDENCE / 2, d.size - 1) * d.std(ddof=1) / math.sqrt(d.size)
    mean = float(d.mean())
    return mean, float(mean - half), float(mean + half), int(d.size)


def phase_note(scene: str, kind: str, metric: str) -> str:
    """What a claim's text adds where its spectral error also counts phase: the texture
    frequency (Hz) of ``scene``'s grating at motion ``kind``'s speed (``MOTIONS``; the
    human-like strokes' nominal mean), when below ``PHASE_BLIND_HZ``; else ''."""
    speed = MOTIONS.get(kind, {}).get("speed_mm_s")
    if metric != "spectral_error" or scene not in GRATINGS or speed is None:
        return ""
    texture_hz = speed / GRATINGS[scene]
    if texture_hz >= PHASE_BLIND_HZ:
        return ""
    return (f" (a {texture_hz:.2g} Hz texture at {speed:g} mm/s: below {PHASE_BLIND_HZ:g} Hz "
            "the spectral error counts phase too)")


def _claim(group, scene, kind, metric, values, a, b, scale=1.0, strict=True) -> Claim | None:
    per = values.get(scene, {}).get(kind, {})
    if a not in per or b not in per:
        return None
    mean, low, high, n = paired(per[a][metric], per[b][metric], scale)
    side = f"{scale:g} x {b}" if scale != 1.0 else b
    relation = "<" if strict else "<="
    text = (f"{'auto (hybrid)' if a == AUTO else a} {relation} {side}: {a} - {side} = "
            f"{mean:+.3f}, 95 % interval [{low:+.3f}, {high:+.3f}], {n} draws"
            + phase_note(scene, kind, metric))
    holds = bool(high < 0.0 if strict else high <= 0.0)  # NaN: not shown
    return Claim(group, scene, kind, metric, text, mean, low, high, n, holds,
                 verdict(holds, low))


def claims(draws) -> list[Claim]:
    """Every claim the draws (``app.measure.report_seeds.Draws``) allow checking."""
    values = draws.values
    out: list[Claim | None] = []
    for kind in draws.kinds:
        out.append(_claim("seed 003", "grating-0.6mm", kind, "spectral_error", values,
                          "sht", "sho-held"))
        out.append(_claim("seed 003", "grating-15mm", kind, "alignment_error_mm", values,
                          "sho-held", "sht"))
    for scene in ("grating-15mm", "grating-5mm"):
        for kind in draws.kinds:
            for metric in ("time_error", "spectral_error"):
                for rival in ("sho-held", "sht"):
                    out.append(_claim("auto beats SHO and SHT", scene, kind, metric, values,
                                      AUTO, rival))
        per = values.get(scene, {}).get("human", {})
        for metric in ("time_error", "spectral_error"):
            rivals = [r for r in per if r != AUTO]
            if rivals:
                best = min(rivals, key=lambda r: np.mean(per[r][metric]))
                out.append(_claim("auto near the best", scene, "human", metric, values, AUTO,
                                  best, 1.05, strict=False))
    for kind in draws.kinds:
        out.append(_claim("auto on fine gratings", "grating-0.6mm", kind, "spectral_error",
                          values, AUTO, "sht", 1.03 if kind == "human" else 1.0, strict=False))
    return [c for c in out if c is not None]
