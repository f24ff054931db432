"""Which fingers each layer applies to: the layer key ``fingers`` turned into (F, n) masks.

Selectors (``textures.model``): ``"any"`` (every finger; no mask), ``"1"``, ``"2"``, ...
(1-based, in order of touch-down among the fingers touching at that sample: when finger
1 lifts, finger 2 becomes finger 1) and the positional ``"left-most"``, ``"right-most"``,
``"top-most"``, ``"bottom-most"`` (the touching finger with the smallest x, largest x,
smallest y, largest y; screen y points down). All are evaluated per output sample at the
positions the pipeline renders with (the predicted ones), so a layer follows "the left
finger" as fingers cross. Ties (same touch-down time, same coordinate) go to the finger
touching longest, then to the lower row.
"""

from __future__ import annotations

import numpy as np

from device.actuation.base import touch_rank
from textures.model import POSITIONAL_SELECTORS

ANY = "any"


def _extreme(contact, values, rank, largest: bool) -> np.ndarray:
    """One-hot (F, n): the touching finger with the smallest (or largest) value."""
    key = np.where(contact, -values if largest else values, np.inf)
    best = key.min(axis=0, initial=np.inf)
    tied = contact & (key == best)
    first = np.where(tied, rank, np.iinfo(np.int64).max).min(axis=0, initial=np.iinfo(np.int64).max)
    return tied & (rank == first)


def finger_masks(selectors, fingers) -> list[np.ndarray | None]:
    """Per layer, the (F, n) bool mask of the fingers it applies to (None for "any").

    Parameters
    ----------
    selectors : sequence of str, one per layer (validated by ``textures.loader``).
    fingers : rendering.tracking.tracks.FingerBlock (contact, touch_start, x_pred, y_pred used).
    """
    if all(s == ANY for s in selectors):
        return [None] * len(selectors)
    contact = fingers.contact
    rank = touch_rank(contact, fingers.touch_start)
    axes = {"left-most": (fingers.x_pred, False), "right-most": (fingers.x_pred, True),
            "top-most": (fingers.y_pred, False), "bottom-most": (fingers.y_pred, True)}
    masks = []
    for s in selectors:
        if s == ANY:
            masks.append(None)
        elif s in POSITIONAL_SELECTORS:
            values, largest = axes[s]
            masks.append(_extreme(contact, values, rank, largest))
        else:
            masks.append(rank == int(s) - 1)
    return masks
