"""A renderer for tests that register one in process: mu' ``MU`` wherever the layer is."""

import numpy as np


class FlatRenderer:
    """A renderer of mu' = :attr:`MU` everywhere (a subclass sets its own, or changes
    what ``render`` returns)."""

    MU = 0.5

    def __init__(self, layer, rate_hz):
        pass

    def initial_state(self):
        return None

    def render(self, block, state):
        shape = (len(block.ids), block.n)
        return np.full(shape, self.MU), np.ones(shape, dtype=bool), state
