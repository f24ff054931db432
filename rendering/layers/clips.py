"""Effect clips started by touch events (``textures.clips.ClipLayer``).

Events are found on the output samples of the tracked fingers (``FingerBlock``), one
finger row at a time against its previous sample (carried between blocks in the state):

- down: touching now, and not before or under another touch id;
- lift: touching before, and not now or under another touch id (position: before);
- edge: the same touch on the other side of the edge line than before;
- force: the same touch, normal force at or above the threshold now and below before.

Each must happen inside the layer's region (``down``, ``edge`` and ``force`` at the
current position, ``lift`` at the last one). An event at output sample k starts the
clip at k + 1: clip sample j plays at output index k + 1 + j. The tracker puts a touch
sample into effect at the same block boundary live and in replay, so replay gives the
same output indices as live, and live lags a touch by less than one block. The clip's
samples are computed once, at the output rate, when the renderer is built.
"""

from __future__ import annotations

from dataclasses import dataclass, field

import numpy as np

from rendering.tracking.tracks import FingerBlock


@dataclass(frozen=True)
class FingerPrev:
    """One finger's last output sample."""

    contact: bool = False
    touch_id: int = -1
    x: float = 0.0
    y: float = 0.0
    force: float = 0.0


@dataclass(frozen=True)
class ClipState:
    """Output index of the clip's first sample (-1: never started), and each finger's
    last sample by finger id."""

    start: int = -1
    fingers: dict = field(default_factory=dict)


def _previous(row: np.ndarray, first) -> np.ndarray:
    """The array shifted one sample later, ``first`` at sample 0."""
    out = np.empty_like(row)
    out[0] = first
    out[1:] = row[:-1]
    return out


class ClipRenderer:
    """Renders one ``ClipLayer``; see the module docstring."""

    def __init__(self, layer, rate_hz: float):
        self.layer = layer
        self.samples, self.clipped = layer.clip.sample(rate_hz)

    def initial_state(self) -> ClipState:
        return ClipState()

    def _events(self, block: FingerBlock, i: int, prev: FingerPrev) -> np.ndarray:
        """bool (n,): the trigger fires for finger row i at each sample."""
        layer = self.layer
        c, tid = block.contact[i], block.touch_id[i]
        x, y = block.x_pred[i], block.y_pred[i]
        c0 = _previous(c, prev.contact)
        same = c & c0 & (tid == _previous(tid, prev.touch_id))
        if layer.trigger == "down":
            return c & ~same & layer.in_region(x, y)
        if layer.trigger == "lift":
            x0, y0 = _previous(x, prev.x), _previous(y, prev.y)
            return c0 & ~same & layer.in_region(x0, y0)
        if layer.trigger == "edge":
            side = layer.side(x, y)
            return same & (side != layer.side(_previous(x, prev.x), _previous(y, prev.y))) \
                & layer.in_region(x, y)
        f = block.force[i]
        with np.errstate(invalid="ignore"):
            above = f >= layer.force_n
            was = _previous(f, prev.force) >= layer.force_n
        return same & above & ~was & layer.in_region(x, y)

    def render(self, block: FingerBlock, state: ClipState):
        """mu' (F, n) and coverage (F, n): the clip under every touching finger while it plays."""
        n = block.n
        fired = np.zeros(n, dtype=bool)
        fingers = {}
        for i, fid in enumerate(block.ids):
            fired |= self._events(block, i, state.fingers.get(fid, FingerPrev()))
            fingers[fid] = FingerPrev(bool(block.contact[i, -1]), int(block.touch_id[i, -1]),
                                      float(block.x_pred[i, -1]), float(block.y_pred[i, -1]),
                                      float(block.force[i, -1]))
        index = block.index0 + np.arange(n)
        marks = np.where(fired, index + 1, -1)
        latest = np.maximum.accumulate(marks)
        start = np.maximum(_previous(latest, -1), state.start)  # an event starts the next sample
        offset = index - start
        playing = (start >= 0) & (offset < self.samples.size)
        mu_row = np.where(playing, self.samples[np.clip(offset, 0, self.samples.size - 1)], 1.0)
        covers = block.contact & playing
        new_start = max(state.start, int(latest[-1]))
        return (np.broadcast_to(mu_row, covers.shape), covers,
                ClipState(start=new_start, fingers=fingers))
