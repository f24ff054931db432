"""Which fingers each layer applies to: the layer key ``fingers`` turned into (F, n) masks.

Selectors (``textures.model``): ``"any"`` (every finger; no mask), ``"1"``, ``"2"``, ...
(1-based, in order of touch-down among the fingers touching at that sample: when finger
1 lifts, finger 2 becomes finger 1) and the positional ``"left-most"``, ``"right-most"``,
``"top-most"``, ``"bottom-most"`` (the touching finger with the smallest x, largest x,
smallest y, largest y; screen y points down). All are evaluated per output sample at the
positions the pipeline renders with (the predicted ones), so a layer follows "the left
finger" as fingers cross.

Positional roles have hysteresis: the finger holding a role keeps it until another
touching finger is more than ``HYSTERESIS_MM`` beyond it (further left, for "left-most")
or it lifts. Two fingers side by side wobble across each other: in the refdata tablet
two-finger drag (Asus TF201, one finger above the other, their x within 0-7 mm) plain
"left-most" swaps the fingers' roles 9 times in 1.5 s, and each finger's texture flips
between two layers. A fingertip's contact is about 10 mm across and rolls by a few mm
as it presses and drags, so 3 mm is well within one finger's wobble yet far less than
a deliberate crossing. Where no finger holds a role (at the start, or its holder lifted)
it goes to the extreme finger; ties (same coordinate) to the finger touching longest,
then to the lower row.

:func:`select_fingers` carries the role holders from one block to the next
(:class:`SelectionState`); :func:`finger_masks` starts afresh each call.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from frictex.device.actuation.base import touch_rank
from frictex.device.jit import njit
from frictex.textures.model import POSITIONAL_SELECTORS

ANY = "any"
#: a finger keeps a positional role until another is this much (mm) beyond it
HYSTERESIS_MM = 3.0


@dataclass(frozen=True)
class SelectionState:
    """Per layer index, the (finger id, touch id) holding its positional role."""

    holders: dict[int, tuple[int, int]] = field(default_factory=dict)


@njit(cache=True, nogil=True)
def _roles(contact, key, rank, start, hysteresis, holder):
    """Row holding the role at each sample, written to ``holder`` (n,), -1 where no
    finger touches. key : (F, n), smaller is more extreme; rank : (F, n) touch rank for
    ties; start : the row holding it before the first sample, or -1."""
    f_n, n = key.shape
    h = start
    for k in range(n):
        best = -1
        for f in range(f_n):
            if contact[f, k] and (best < 0 or key[f, k] < key[best, k]
                                  or (key[f, k] == key[best, k] and rank[f, k] < rank[best, k])):
                best = f
        if h < 0 or not contact[h, k] or (best >= 0 and key[best, k] < key[h, k] - hysteresis):
            h = best
        holder[k] = h


def _key(fingers, selector: str) -> np.ndarray:
    """(F, n) positions along the selector's axis, signed so that smaller is more extreme."""
    values = fingers.x_pred if selector in ("left-most", "right-most") else fingers.y_pred
    sign = 1.0 if selector in ("left-most", "top-most") else -1.0
    return np.ascontiguousarray(sign * np.asarray(values, dtype=np.float64))


def select_fingers(selectors, fingers, state: SelectionState | None = None,
                   hysteresis_mm: float = HYSTERESIS_MM
                   ) -> tuple[list[np.ndarray | None], SelectionState]:
    """Per layer, the (F, n) bool mask of the fingers it applies to (None for "any"), and
    the role holders to carry into the next block.

    Parameters
    ----------
    selectors : sequence of str, one per layer (validated by ``textures.loader``).
    fingers : rendering.tracking.tracks.FingerBlock (contact, touch_start, x_pred, y_pred
        used; ids and touch_id too when ``state`` is given).
    state : the previous block's :class:`SelectionState`, or None (no role held).
    hysteresis_mm : see the module docstring (mm, >= 0).
    """
    if all(s == ANY for s in selectors):
        return [None] * len(selectors), state or SelectionState()
    contact = np.ascontiguousarray(fingers.contact, dtype=np.bool_)
    rank = touch_rank(contact, fingers.touch_start)
    holders = dict(state.holders) if state is not None else {}
    masks = []
    for i, s in enumerate(selectors):
        if s == ANY:
            masks.append(None)
        elif s in POSITIONAL_SELECTORS:
            start = -1
            if i in holders:
                fid, touch = holders[i]
                if fid in fingers.ids:
                    row = fingers.ids.index(fid)
                    if fingers.touch_id[row, 0] == touch:
                        start = row
            holder = np.empty(contact.shape[1], dtype=np.int64)
            _roles(contact, _key(fingers, s), rank, start, float(hysteresis_mm), holder)
            masks.append(np.arange(contact.shape[0])[:, None] == holder[None, :])
            if state is not None and holder.size:
                last = int(holder[-1])
                if last >= 0:
                    holders[i] = (fingers.ids[last], int(fingers.touch_id[last, -1]))
                else:
                    holders.pop(i, None)
        else:
            masks.append(rank == int(s) - 1)
    return masks, SelectionState(holders)


def finger_masks(selectors, fingers, hysteresis_mm: float = HYSTERESIS_MM) -> list[np.ndarray | None]:
    """:func:`select_fingers` for one block on its own (no role carried in or out)."""
    return select_fingers(selectors, fingers, None, hysteresis_mm)[0]
