"""Whether paired rounds show a speed target: the rounds' ratios, their geometric mean and
its 95 % interval, and a verdict, as ``frictex report`` gives its claims.

A ratio of two processes' wall times varies from round to round on a shared machine (a
1-second replay against its floor gave 0.60-1.46x in five rounds, median 1.19x), so
neither one round's ratio nor the median of a few settles a target. Per round the log of
the ratio is taken; their mean and its 95 % interval (Student's t over the rounds,
``report_claims.paired``) are turned back into ratios (exp): the geometric mean ratio
and its interval. The target **holds** where the whole interval lies on its side, **does
not hold** where the whole interval lies on the other side, and is **not shown**
otherwise (and below two rounds, which give no interval): ``report_claims.verdict``.
Rounds that all give the same ratio give no interval either: a spread of zero comes from
a clock too coarse to tell the rounds apart, not from rounds that agree, so it is no
evidence and the target is not shown.

A fixed target on a time ("``--version`` under 0.15 s") is judged the same way from the
runs' times themselves (:func:`time_claim`): their geometric mean and its 95 % interval
against the bound, so that a median a little under the bound on a loaded machine is no
"holds".

Each printed end of an interval has as many decimals as it takes to put it on the side
of the target that decided the verdict (:func:`end_text`): two where they do (or two
significant digits, for a time of 0.047 s), more where that would round the end onto the
target (an upper end of 1.996 against "at most 2x" prints 1.996, not 2.00).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from frictex.app.measure.figure import Figure
from frictex.app.measure.report_claims import NOT_SHOWN, paired, verdict


@dataclass(frozen=True)
class RatioClaim:
    """``geomean`` of ``rounds`` ratios and its 95 % interval [``low``, ``high``] (NaN
    below two rounds; ``low == high`` where every round gave the same ratio, which is
    no interval); ``verdict`` on ``target``: ``holds``, ``does not hold`` or ``not
    shown``."""

    geomean: float
    low: float
    high: float
    rounds: int
    verdict: str
    target: float

    def interval_text(self, unit: str = "x", of: str = "rounds") -> str:
        """``95 % interval 0.80-1.04x`` (``unit`` after each number: "x", or " s" for
        times), or why there is none (under two rounds, or no spread between them; ``of``:
        what was averaged, "rounds" or "runs")."""
        if self.rounds > 1 and self.low == self.high:
            same = "ratio" if of == "rounds" else "time"
            return (f"every {of[:-1]} the same {same}: no spread, no interval (clock too "
                    "coarse)")
        if self.rounds > 1:
            return (f"95 % interval {end_text(self.low, self.target)}-"
                    f"{end_text(self.high, self.target)}{unit}")
        return f"one {of[:-1]}, no interval" if self.rounds == 1 else f"no {of[:-1]}, no interval"

    def figure(self, section: str, label: str, target: float, at_most: bool,
               note: str = "", unit: str = "x", of: str = "rounds") -> Figure:
        """The verdict as one figure, the whole interval beside it: ``LABEL, target at most
        1.2x (geometric mean of 8 rounds)  0.91 x (95 % interval 0.80-1.04x): holds``
        (``note``: how many rounds failed, ``processes.failed_note``; ``unit``: "x", or
        " s" for a time against a bound, see :func:`time_claim`; ``of``: what was
        averaged, "rounds" or "runs")."""
        side = "at most" if at_most else "at least"
        return Figure(section, f"{label}, target {side} {target:g}{unit} (geometric mean of "
                      f"{self.rounds} {of}{note})", self.geomean,
                      f"{unit.strip()} ({self.interval_text(unit, of)}): {self.verdict}")


def end_text(end: float, target: float) -> str:
    """``end`` with the fewest decimals that keep it on its side of ``target`` once
    printed (1.996 against 2: "1.996"; 1.93: "1.93"), and at least two decimals and two
    significant digits (0.0473 s: "0.047", not "0.05"); ``repr`` where nine do not."""
    digits = 1 - math.floor(math.log10(abs(end))) if end != 0.0 and math.isfinite(end) else 2
    for decimals in range(max(2, digits), 10):
        text = f"{end:.{decimals}f}"
        if (float(text) > target) == (end > target) and (float(text) < target) == (end < target):
            return text
    return repr(end)


def ratio_claim(ratios: list[float], target: float, at_most: bool) -> RatioClaim:
    """What the paired rounds' ``ratios`` (each > 0) show about the target: each ratio
    ``<= target`` (``at_most``) or ``>= target``. See the module."""
    if any(not (r > 0.0 and math.isfinite(r)) for r in ratios):
        raise ValueError(f"ratios must be positive and finite: {ratios}")
    sign = 1.0 if at_most else -1.0  # the claim as d < 0 on every round
    d = [sign * (math.log(r) - math.log(target)) for r in ratios]
    mean, low, high, n = paired(d, [0.0] * len(d))
    holds = bool(high < 0.0)  # NaN (under two rounds): not shown
    spread = n < 2 or min(d) != max(d)  # none: no evidence (module docstring)
    geomean = math.exp(math.log(target) + sign * mean)
    if not spread:  # ends equal, as the dataclass says; rounding could part them by an ulp
        return RatioClaim(geomean, geomean, geomean, n, NOT_SHOWN, target)
    ends = sorted(math.log(target) + sign * end for end in (low, high))
    return RatioClaim(geomean, math.exp(ends[0]), math.exp(ends[1]), n, verdict(holds, low),
                      target)


def time_claim(seconds: list[float], bound_s: float) -> RatioClaim:
    """What runs taking ``seconds`` each (> 0) show about "a run takes at most
    ``bound_s``", judged on their geometric mean (not on each run: one slow run of many
    can pass): its 95 % interval against the bound, as :func:`ratio_claim`
    judges a ratio against its target (its figure: ``figure(..., unit=" s", of="runs")``)."""
    return ratio_claim(seconds, bound_s, at_most=True)
