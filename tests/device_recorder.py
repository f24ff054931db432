"""What a device core (Python or C) played, tick by tick: its ``log`` and ``plate_log``."""

import numpy as np


class Recorder:
    """Collects the played log and the per-tick output of a device core."""

    def __init__(self):
        self.index, self.values, self.t, self.setpoint, self.plate = [], [], [], [], []

    def log(self, index, values, phases):
        self.index.append(index)
        self.values.append(values)

    def plate_log(self, t, state, setpoint, plate):
        self.t.append(t)
        self.setpoint.append(setpoint)
        self.plate.append(plate)

    def played(self):
        if not self.index:
            return np.zeros(0, dtype=np.int64), np.zeros((0, 1))
        return np.concatenate(self.index), np.concatenate(self.values)

    def ticks(self):
        return np.concatenate(self.t), np.concatenate(self.setpoint), np.concatenate(self.plate)
