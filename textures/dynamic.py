"""The base of layers whose mu' depends on motion or time (heights, recorded textures, clips)."""

from __future__ import annotations

from dataclasses import dataclass
from typing import ClassVar

import numpy as np

from frictex.textures.model import _LayerBase

#: The output rate a scene's dynamic layers are checked for when it is read (Hz): the
#: default of ``frictex replay --rate`` and ``frictex demo --rate``.
OUTPUT_RATE_HZ = 10_000.0


@dataclass(frozen=True)
class DynamicLayer(_LayerBase):
    """A layer rendered by its own renderer (``renderer_kind``, built by
    ``rendering.pipeline``) from the fingers' motion, force or events. Statically -- drawn,
    previewed as a map, or under a finger at rest -- its mu' is ``rest_mu``."""

    renderer_kind: ClassVar[str] = ""

    @property
    def rest_mu(self) -> float:
        raise NotImplementedError

    def mu_at(self, x, y) -> np.ndarray:
        """mu' under a finger at rest: ``rest_mu`` everywhere."""
        return np.full(np.broadcast(np.asarray(x), np.asarray(y)).shape, self.rest_mu)
