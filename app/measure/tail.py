"""The tail of a bench figure's samples: their 99th percentile where they are enough for
one, else their largest.

With n samples the 99th percentile (numpy's linear interpolation) lies at rank
0.99 (n - 1): for n up to 100 that is between the two largest samples, so a "p99" of 20
touches is their largest in all but name. Such a figure is called the max.
"""

from __future__ import annotations

import numpy as np

#: fewest samples whose 99th percentile lies below the second largest
P99_SAMPLES = 101


def tail(values) -> tuple[str, float]:
    """``("p99", the 99th percentile)`` of ``values`` (at least one), or ``("max", the
    largest)`` with fewer than :data:`P99_SAMPLES`."""
    values = np.asarray(values, dtype=np.float64)
    if values.size < P99_SAMPLES:
        return "max", float(values.max())
    return "p99", float(np.percentile(values, 99))
