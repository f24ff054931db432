"""Effect clips started by touch events (``textures.clips.ClipLayer``).

Events are found on the output samples of the tracked fingers (``FingerBlock``), one
finger row at a time against its previous sample (carried between blocks in the state):

- down: touching now, and not before or under another touch id;
- lift: touching before, and not now or under another touch id (position: before);
- edge: the same touch strictly on the other side of the edge line than its last sample
  off the line (a sample on the line (within a picometre) keeps the side it came from, so reaching the
  line and going back fires nothing, from either side);
- force: the same touch, normal force at or above the threshold now and not before,
  having fallen below the re-arm level (``textures.clips.FORCE_REARM`` of the threshold)
  since it last rose through it; between the two levels it stands as it came (as
  on an edge line), so that noise about the threshold fires once.

Each must happen inside the layer's region (``down``, ``edge`` and ``force`` at the
current position, ``lift`` at the last one). An event at output sample k starts the
clip at k + 1: clip sample j plays at output index k + 1 + j. The tracker puts a touch
sample into effect at the same block boundary live and in replay, so replay gives the
same output indices as live, and live lags a touch by less than one block. The clip's
samples are computed once, at the output rate, when the renderer is built, with the
samples where its events' levels added past 1 (``textures.clips.Clip.sample``); each
such sample played under a touching finger is counted in the state (``clipped``).
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import NamedTuple

import numpy as np

from frictex.device.jit import njit
from frictex.rendering.tracking.tracks import FingerBlock

TRIGGER_CODES = {"down": 0, "lift": 1, "edge": 2, "force": 3}


class FingerPrev(NamedTuple):
    """One finger's last output sample: touching, touch id, inside the region, and the
    trigger's flag (edge: the side of the line of the touch's last sample off it, +1 the
    normal's, -1 the other, 0 none yet; force: +1 risen through the threshold, -1 fallen
    below the re-arm level, 0 neither yet); the truths
    as 0 or 1, so that the fingers' rows make one int64 array."""

    contact: int = 0
    touch_id: int = -1
    inside: int = 0
    flag: int = 0


@dataclass(frozen=True)
class ClipState:
    """Output index of the clip's first sample (-1: never started), each finger's
    last sample by finger id, and how many finger samples so far played a clip sample
    whose level sum was clipped at 1."""

    start: int = -1
    fingers: dict = field(default_factory=dict)
    clipped: int = 0


@njit(cache=True, nogil=True)
def _fired(trigger, contact, touch_id, inside, flag, prev):
    """bool (n,): the trigger fires for some finger at each sample (module docstring);
    and each finger's last sample, both (F, 4) int64 rows as :class:`FingerPrev`:
    ``prev`` before the block, the returned one after it."""
    fingers, n = contact.shape
    fired = np.zeros(n, dtype=np.bool_)
    last = np.empty((fingers, 4), dtype=np.int64)
    for i in range(fingers):
        c0, t0, in0, f0 = prev[i, 0] != 0, prev[i, 1], prev[i, 2] != 0, prev[i, 3]
        for j in range(n):
            c, t, inn, f = contact[i, j], touch_id[i, j], inside[i, j], np.int64(flag[i, j])
            same = c and c0 and t == t0
            if trigger == 0:
                event = c and not same and inn
            elif trigger == 1:
                event = c0 and not same and in0
            elif trigger == 2:
                event = same and f != 0 and f0 != 0 and f != f0 and inn
                if same and f == 0:
                    f = f0  # on the line: the side it came from
            else:
                if same and f == 0:
                    f = f0  # between the re-arm level and the threshold: as it came
                event = same and f == 1 and f0 != 1 and inn
            fired[j] |= event
            c0, t0, in0, f0 = c, t, inn, f
        last[i, 0], last[i, 1], last[i, 2], last[i, 3] = c0, t0, in0, f0
    return fired, last


def render_block(trigger, contact, touch_id, inside, flag, prev, index0, start, samples,
                 clipped, idle):
    """One block of the layer: mu' and coverage (F, n), the clip's start after the block,
    how many touching finger samples played a sample of ``clipped`` (bool, as ``samples``)
    and each finger's last sample (:func:`_fired`). The clip started at output index
    ``start`` (-1: none) plays under every touching finger; an event at sample j restarts
    it at j + 1. ``idle``: the (mu', coverage) of a block where the clip does not play
    (all 1, all False), returned as they are if so."""
    fired, last = _fired(trigger, contact, touch_id, inside, flag, prev)
    if not fired.any() and not (start >= 0 and start + samples.size > index0):
        return *idle, start, 0, last
    return *_play(fired, contact, index0, start, samples, clipped), last


@njit(cache=True, nogil=True)
def _play(fired, contact, index0, start, samples, clipped):
    """mu' and coverage (F, n) of a block where the trigger ``fired`` (n,), the clip's
    start after it and the clipped samples played (:func:`render_block`). Between events
    the clip's samples are copied as one slice."""
    fingers, n = contact.shape
    mu, covers = np.ones((fingers, n)), np.zeros((fingers, n), dtype=np.bool_)
    events = np.nonzero(fired)[0]
    played_clipped = 0
    j = 0  # samples j .. end - 1 play from ``start``
    for k in range(events.size + 1):
        end = events[k] + 1 if k < events.size else n
        stop = min(end, start - index0 + samples.size)  # the clip's end
        if start >= 0 and stop > j:
            lo, hi = index0 + j - start, index0 + stop - start
            for i in range(fingers):
                mu[i, j:stop] = samples[lo:hi]
                covers[i, j:stop] = contact[i, j:stop]
                played_clipped += np.count_nonzero(contact[i, j:stop] & clipped[lo:hi])
        if k < events.size:
            start = index0 + end
        j = end
    return mu, covers, start, played_clipped


class ClipRenderer:
    """Renders one ``ClipLayer``; see the module docstring."""

    def __init__(self, layer, rate_hz: float):
        self.layer = layer
        self.trigger = TRIGGER_CODES[layer.trigger]
        self.samples, self.clipped = layer.clip.sample(rate_hz)  # mu', and where it clipped
        self._idle = None  # (mu', coverage) of a block where nothing plays, read-only

    def _idle_block(self, shape) -> tuple[np.ndarray, np.ndarray]:
        """All 1 and all False in ``shape``, made once per shape (most blocks play nothing,
        and filling them took half the layer's time)."""
        if self._idle is None or self._idle[0].shape != shape:
            self._idle = (np.ones(shape), np.zeros(shape, dtype=bool))
            for a in self._idle:
                a.flags.writeable = False
        return self._idle

    def initial_state(self) -> ClipState:
        return ClipState()

    def _flag(self, block: FingerBlock) -> np.ndarray:
        layer = self.layer
        if layer.trigger == "edge":
            return layer.side(block.x_pred, block.y_pred)
        if layer.trigger == "force":
            return layer.force_level(block.force)
        return np.zeros(block.contact.shape, dtype=bool)

    def render(self, block: FingerBlock, state: ClipState):
        """mu' (F, n) and coverage (F, n): the clip under every touching finger while it plays."""
        inside = self.layer.in_region(block.x_pred, block.y_pred)
        flag = self._flag(block)
        prev = np.array([state.fingers.get(fid, FingerPrev()) for fid in block.ids],
                        dtype=np.int64).reshape(len(block.ids), 4)
        mu, covers, start, clipped, last = render_block(
            self.trigger, block.contact, block.touch_id, inside, flag, prev, block.index0,
            state.start, self.samples, self.clipped, self._idle_block(block.contact.shape))
        fingers = {fid: FingerPrev(*row) for fid, row in zip(block.ids, last.tolist())}
        return mu, covers, ClipState(start, fingers, state.clipped + int(clipped))
