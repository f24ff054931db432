"""The nominal path from a commanded amplitude to the force sensor, as the host models it.

The plate's amplitude loop (seed 003, Fig. 3b: 400 Hz), the fingertip's tangential
compliance (seed 003, section 3: 3.84 ms rise time, about 90 Hz) and the sensor
(bandwidth and delay), each a one-pole low-pass (``device.finger``'s constants), run as
one third-order filter. The controller passes what it asked for through this chain so
that it compares the sensor's reading with a reference delayed and smoothed the same way.
Several signals run in one call, one per row.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from scipy.signal import lfilter_zi

from frictex.device.finger import SensorParams, pole
from frictex.device.jit import njit


@dataclass(frozen=True, eq=False)
class ChainState:
    """Per row: the filter's state (k, 3) and the delay line (k, d)."""

    zi: np.ndarray
    delay: np.ndarray


class Chain:
    """Plate -> skin -> sensor, at ``rate_hz``: ``y, state = chain.run(x, state)``."""

    def __init__(self, sensor: SensorParams, rate_hz: float):
        poles = [pole(bw, rate_hz) for bw in (sensor.plate_bw_hz, sensor.skin_bw_hz,
                                              sensor.sensor_bw_hz)]
        self.b, self.a = np.array([1.0]), np.array([1.0])
        for p in poles:
            self.b = np.convolve(self.b, [1.0 - p])
            self.a = np.convolve(self.a, [1.0, -p])
        self._zi = lfilter_zi(self.b, self.a)
        self._b = np.zeros(self.a.size)  # b padded to a's length, as lfilter runs it
        self._b[:self.b.size] = self.b
        self.delay = int(round(sensor.sensor_delay_s * rate_hz))
        #: total group delay at low frequency (samples): one pole adds p / (1 - p)
        self.lag_samples = self.delay + sum(p / (1.0 - p) for p in poles)
        self.run(np.zeros((1, 1)), self.initial_state([0.0]))  # load the kernel now

    def initial_state(self, values) -> ChainState:
        """Each row at rest at its value in ``values`` (k,)."""
        v = np.asarray(values, dtype=np.float64)[:, None]
        return ChainState(zi=v * self._zi, delay=np.repeat(v, self.delay, axis=1))

    def run(self, x: np.ndarray, state: ChainState) -> tuple[np.ndarray, ChainState]:
        """Filter the rows of ``x`` (k, n) from ``state``; returns (y (k, n), state after)."""
        y, zi, delay = _run(self._b, self.a, np.ascontiguousarray(x, dtype=np.float64),
                            state.zi, state.delay)
        return y, ChainState(zi=zi, delay=delay)


@njit(cache=True, nogil=True)
def _run(b, a, x, zi, delay):
    """:meth:`Chain.run`'s filter and delay line. The filter is scipy's ``lfilter``
    (direct form II transposed, ``a[0]`` = 1) in its own order of operations, so that
    its output is lfilter's to the bit; it runs here to leave out lfilter's call
    overhead (15-20 us a block, more than the filtering)."""
    k, n = x.shape
    m = a.size - 1
    d = delay.shape[1]
    line = np.empty((k, d + n))
    zi_out = np.empty((k, m))
    for r in range(k):
        z = zi[r].copy()
        line[r, :d] = delay[r]
        for i in range(n):
            xi = x[r, i]
            yi = z[0] + b[0] * xi
            for j in range(m - 1):
                z[j] = z[j + 1] + xi * b[j + 1] - yi * a[j + 1]
            z[m - 1] = xi * b[m] - yi * a[m]
            line[r, d + i] = yi
        zi_out[r] = z
    return line[:, :n].copy(), zi_out, line[:, n:].copy()
