"""The simulated device's force sensors and its force reports (PROTOCOL.md 4.9, 5.5).

A *sensor* gives, per tick of the device's sample clock, the lateral and the normal force
(N) under the finger: ``read(tick0, setpoint_um) -> (lateral_n (n,), normal_n (n,))`` for
ticks ``tick0 .. tick0 + n - 1``, ``setpoint_um`` (n, channels) being the amplitudes the
device put on its outputs at those ticks (um). :class:`ConstantSensor` reads fixed values;
:class:`FingerSensor` is a finger of ``device.finger`` sliding on the plate.

:class:`ForceWindows` turns the per-tick readings of the ticks that played (or gapped) a
sample into :class:`~device.link.protocol.ForceReport` messages, in integer wire counts,
exactly as the C firmware core does (``core/device.c``), so the two agree bit for bit.
"""

from __future__ import annotations

import numpy as np

from frictex.device.link import protocol as p

#: normal force (N) of the simulated finger when none is configured
FINGER_FORCE_N = 0.5


class ConstantSensor:
    """A sensor reading ``lateral_n`` and ``normal_n`` (N) at every tick."""

    def __init__(self, lateral_n: float, normal_n: float):
        self.lateral_n = float(lateral_n)
        self.normal_n = float(normal_n)

    def read(self, tick0: int, setpoint_um) -> tuple[np.ndarray, np.ndarray]:
        n = len(setpoint_um)
        return np.full(n, self.lateral_n), np.full(n, self.normal_n)


class FingerSensor:
    """One finger of ``device.finger``'s population sliding at ``speed_mm_s`` (mm/s; its
    sign the way along x: negative slides towards -x, and its lateral force reads
    negative, PROTOCOL.md 4.9) and
    pressing with ``normal_n`` (N) on channel 0's amplitude, as the plate's sensors see
    it: friction from seed 003's model with this person's constants, moisture drift and
    speed dependence, through the fingertip's compliance and the sensor's bandwidth,
    delay and noise (``device.finger.SensorParams``: 1 kHz, 0.5 ms, 2 mN lateral and 5 mN
    normal noise, 5 N full scale; ``sensor``, None for those). ``finger``: a seed of
    :func:`device.finger.draw_finger` or the :class:`~device.finger.FingerParams`
    themselves."""

    def __init__(self, finger, rate_hz: float, limit_um: float,
                 speed_mm_s: float = 100.0, normal_n: float = FINGER_FORCE_N, sensor=None):
        # with the finger only: device.finger brings scipy.signal (a second to import)
        from frictex.device.finger import FingerPlant, SensorParams, draw_finger
        sensor = SensorParams() if sensor is None else sensor
        params = draw_finger(finger) if isinstance(finger, int) else finger
        seed = finger if isinstance(finger, int) else 0
        self.plant = FingerPlant(params, rate_hz, limit_um, sensor, seed=seed)
        self.state = self.plant.initial_state()
        self.speed_mm_s = abs(float(speed_mm_s))
        self.direction = -1.0 if speed_mm_s < 0 else 1.0
        self.normal_n = float(normal_n)

    def read(self, tick0: int, setpoint_um) -> tuple[np.ndarray, np.ndarray]:
        sp = np.asarray(setpoint_um, dtype=np.float64)
        n = len(sp)
        block, self.state = self.plant.step(tick0, sp[:, 0], np.full(n, self.speed_mm_s),
                                            np.full(n, self.normal_n), self.state)
        return self.direction * block.lateral_n, block.normal_n


class ForceWindows:
    """Per-tick force counts -> ForceReport messages (PROTOCOL.md 4.9).

    A report covers ``pairs`` windows of ``decimation`` consecutive sample numbers; each
    value is the window's mean in counts, rounded half up (``floor((sum + d // 2) / d)``).
    Ticks that do not advance the play position, or one that plays a sample other than
    the next one, restart the report being built (its values are dropped).
    """

    def __init__(self, decimation: int, pairs: int):
        self.decimation = int(decimation)
        self.pairs = int(pairs)
        self._start: int | None = None
        self._held = np.zeros((0, 2), dtype=np.int64)

    def reset(self) -> None:
        self._start = None
        self._held = self._held[:0]

    def add(self, first_index: int, lateral_n, normal_n) -> list[p.ForceReport]:
        """Readings of ticks that played (or gapped) samples ``first_index``,
        ``first_index + 1``, ... (modulo 2**64); returns the reports they complete."""
        counts = np.column_stack([p.force_to_wire(lateral_n), p.force_to_wire(normal_n)])
        if not len(counts):
            return []
        if self._start is None or (self._start + len(self._held)) % p.INDEX_MODULUS != first_index:
            self._start, self._held = first_index, self._held[:0]
        self._held = np.concatenate([self._held, counts.astype(np.int64)])
        span = self.decimation * self.pairs
        out = []
        while len(self._held) >= span:
            sums = self._held[:span].reshape(self.pairs, self.decimation, 2).sum(axis=1)
            means = p.force_from_wire((sums + self.decimation // 2) // self.decimation)
            out.append(p.ForceReport(self._start, self.decimation,
                                     tuple(float(x) for x in means[:, 0]),
                                     tuple(float(x) for x in means[:, 1])))
            self._start = (self._start + span) % p.INDEX_MODULUS
            self._held = self._held[span:]
        return out
