"""Whether a tail quantile of many samples lies under a bound ("live 5 ms block p99
under 500 us"), from a distribution-free 95 % interval for the quantile.

Of n independent samples, the number B that fall below the true q-quantile is binomial
(n, q), whatever the samples' distribution; so the k-th smallest sample x(k) lies at or
below the quantile exactly where B >= k, and [x(l), x(u)] covers it with probability
P(l <= B <= u - 1) = F(u - 1) - F(l - 1), F the binomial distribution function. The
ranks are l, the smallest k with F(k) >= 2.5 %, and u, one more than the smallest k with
F(k) >= 97.5 %: at least 95 % coverage (the interval from order statistics, e.g. Conover,
Practical Nonparametric Statistics, 3rd ed., section 3.2). Of 2,000 blocks the p99's
interval runs from the 1,971st to the 1,989th smallest. Where u > n (too few samples:
367 or fewer for the p99, where q^n, all n below the quantile, is over 2.5 %) the interval
has no upper end.

The samples are taken as independent. Consecutive blocks of one live run are not quite
(lag-1 autocorrelation up to 0.22, slow blocks in clusters): four 2,000-block runs back
to back gave p99 intervals of 150-168, 151-169, 217-449 and 158-188 us, so a verdict
holds for the run it was measured in, at that run's load, and repeating it is the test of
repeatability.

The verdict is worded as a ratio target's (``app.measure.ratio_claim``): **holds** where
the interval's upper end is under the bound, **does not hold** where its lower end is
over it, **not shown** otherwise.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from frictex.app.measure.figure import Figure
from frictex.app.measure.ratio_claim import end_text
from frictex.app.measure.report_claims import CONFIDENCE, verdict


def binomial_cdf(n: int, q: float) -> np.ndarray:
    """F(k) = P(B <= k) for k = 0..n, B binomial (``n``, ``q``), 0 < q < 1 (summed
    from the probabilities' logarithms, so that n in the thousands does not underflow
    before the sum)."""
    k = np.arange(n + 1)
    log_pmf = np.array([math.lgamma(n + 1) - math.lgamma(i + 1) - math.lgamma(n - i + 1)
                        for i in k]) + k * math.log(q) + (n - k) * math.log1p(-q)
    return np.minimum(np.cumsum(np.exp(log_pmf)), 1.0)


def quantile_ranks(n: int, q: float) -> tuple[int, int]:
    """(l, u), 1-based ranks of the order statistics bounding the 95 % interval for the
    ``q``-quantile of ``n`` samples (module docstring); u = n + 1 where there is no upper
    end, l = 0 where there is no lower end."""
    tail = (1.0 - CONFIDENCE) / 2.0
    cdf = binomial_cdf(n, q)
    low = int(np.searchsorted(cdf, tail))  # smallest k with F(k) >= tail
    high = int(np.searchsorted(cdf, 1.0 - tail)) + 1
    return low, min(high, n + 1)


@dataclass(frozen=True)
class QuantileClaim:
    """The ``q``-quantile of ``n`` samples (numpy's linear interpolation: ``value``), its
    95 % interval [``low``, ``high``] from order statistics ``ranks`` (-inf / inf where
    there is no such end) and the ``verdict`` on "at most ``bound``"."""

    q: float
    value: float
    low: float
    high: float
    ranks: tuple[int, int]
    n: int
    bound: float
    verdict: str

    def figure(self, section: str, label: str, unit: str, of: str = "samples") -> Figure:
        """``LABEL, target p99 under 500 us (95 % interval from the order statistics of
        2,000 samples)  431.2 us (95 % interval 412.00 to 455.30 us, order statistics 1,971
        and 1,989 of 2,000): holds`` (``of``: what the samples are)."""
        name = f"p{self.q * 100:g}"
        return Figure(section, f"{label}, target {name} under {self.bound:g} {unit} (95 % "
                      f"interval from the order statistics of {self.n:,} {of})",
                      self.value, f"{unit} ({self.interval_text(unit)}): {self.verdict}")

    def interval_text(self, unit: str) -> str:
        """The interval's ends and the ranks they are; an end there are too few samples
        for is said so, without a rank."""
        (low, high), (l, u) = (self.low, self.high), self.ranks
        if math.isfinite(low) and math.isfinite(high):
            return (f"95 % interval {end_text(low, self.bound)} to {end_text(high, self.bound)} "
                    f"{unit}, order statistics {l:,} and {u:,} of {self.n:,}")
        if math.isfinite(low):
            return (f"95 % interval from {end_text(low, self.bound)} {unit}, order statistic "
                    f"{l:,} of {self.n:,}; too few samples for an upper end")
        if math.isfinite(high):
            return (f"95 % interval up to {end_text(high, self.bound)} {unit}, order statistic "
                    f"{u:,} of {self.n:,}; too few samples for a lower end")
        return f"no 95 % interval: too few samples ({self.n:,})"


def quantile_claim(samples, q: float, bound: float) -> QuantileClaim:
    """What ``samples`` (at least one) show about "their ``q``-quantile at most
    ``bound``" (module docstring)."""
    ordered = np.sort(np.asarray(samples, dtype=np.float64))
    n = ordered.size
    l, u = quantile_ranks(n, q)
    low = float(ordered[l - 1]) if l >= 1 else -math.inf
    high = float(ordered[u - 1]) if u <= n else math.inf
    return QuantileClaim(q, float(np.quantile(ordered, q)), low, high, (l, u), n, bound,
                         verdict(high < bound, low - bound))
