"""The nominal path from a commanded amplitude to the force sensor, as the host models it.

The plate's amplitude loop (seed 003, Fig. 3b: 400 Hz), the fingertip's tangential
compliance (seed 003, section 3: 3.84 ms rise time, about 90 Hz) and the sensor
(bandwidth and delay), each a one-pole low-pass (``device.finger``'s constants). The
controller passes what it asked for through this chain so that it compares the sensor's
reading with a reference delayed and smoothed the same way.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np
from device.finger import SensorParams, lowpass, pole


@dataclass(frozen=True)
class ChainState:
    """Filter outputs of the three poles and the delay line after the last sample."""

    y: tuple[float, float, float] = (0.0, 0.0, 0.0)
    delay: tuple = ()


class Chain:
    """Plate -> skin -> sensor, at ``rate_hz``: ``y, state = chain.run(x, state)``."""

    def __init__(self, sensor: SensorParams, rate_hz: float):
        bws = (sensor.plate_bw_hz, sensor.skin_bw_hz, sensor.sensor_bw_hz)
        self.poles = tuple(pole(bw, rate_hz) for bw in bws)
        self.delay = int(round(sensor.sensor_delay_s * rate_hz))
        #: total group delay at low frequency (samples): one pole adds p / (1 - p)
        self.lag_samples = self.delay + sum(p / (1.0 - p) for p in self.poles)

    def initial_state(self, value: float = 0.0) -> ChainState:
        return ChainState(y=(value,) * 3, delay=(value,) * self.delay)

    def run(self, x: np.ndarray, state: ChainState) -> tuple[np.ndarray, ChainState]:
        """Filter ``x`` (n,) from ``state``; returns (y, state after)."""
        y = np.asarray(x, dtype=np.float64)
        ends = []
        for p, y0 in zip(self.poles, state.y):
            y, end = lowpass(y, p, y0)
            ends.append(end)
        line = np.concatenate([state.delay, y])
        n = y.size
        return line[:n], ChainState(y=tuple(ends), delay=tuple(line[n:]))
