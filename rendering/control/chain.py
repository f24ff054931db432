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
from scipy.signal import lfilter, lfilter_zi

from device.finger import SensorParams, pole


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
        self.delay = int(round(sensor.sensor_delay_s * rate_hz))
        #: total group delay at low frequency (samples): one pole adds p / (1 - p)
        self.lag_samples = self.delay + sum(p / (1.0 - p) for p in poles)

    def initial_state(self, values) -> ChainState:
        """Each row at rest at its value in ``values`` (k,)."""
        v = np.asarray(values, dtype=np.float64)[:, None]
        return ChainState(zi=v * self._zi, delay=np.repeat(v, self.delay, axis=1))

    def run(self, x: np.ndarray, state: ChainState) -> tuple[np.ndarray, ChainState]:
        """Filter the rows of ``x`` (k, n) from ``state``; returns (y (k, n), state after)."""
        y, zi = lfilter(self.b, self.a, x, axis=1, zi=state.zi)
        line = np.concatenate([state.delay, y], axis=1)
        n = x.shape[1]
        return line[:, :n], ChainState(zi=zi, delay=line[:, n:])
