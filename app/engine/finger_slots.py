"""A recording's finger ids onto pipeline rows (slots) that lifted fingers give back.

Android gives every touch a new tracking id. A pipeline call has a row per finger id
it sees, so a log of 1,000 touches one at a time would cost per call what its ids add
up to, not what its fingers touching at once do (issue 15). :class:`FingerSlots` hands
each touch the lowest slot whose last finger lifted in an earlier block than the touch
begins, or a new slot if none is free (within one block a touch's first sample may come
before another finger's lift: in one row, that lift would end the touch; and a touch
held past the block would follow the lift with no output sample between them).

A touch that begins and lifts within one block (both apply at the same output index)
shows at no output sample: it may also take a slot whose finger lifted earlier in that
same block, its first sample after that lift. So the slots in use are bounded by the
fingers touching at once plus those lifting in a block, however many brief touches a
block holds (100,000 taps of 10 us within 2 s: 3 slots, were 251).

To the pipeline a slot touched again is a finger touching again: a new touch, with a
new touch id and fresh per-touch state, as a new finger id gets.

The outputs carry the recording's ids again: :meth:`FingerSlots.label` gives each
output row its finger id, and where a row passes from one finger to the next within a
call, the id of every sample (``BlockOutput.sample_ids``). A row whose slot's first
touch has not yet taken effect carries :data:`UNNAMED`: no id of the trace.
"""

from __future__ import annotations

from dataclasses import replace

import numpy as np

from frictex.rendering.input.trace_file import UP, Trace

#: the id of a row before its slot's first touch takes effect: not in contact, and no id
#: of the trace (those are >= 0), so that no summary lists it
UNNAMED = -1


class FingerSlots:
    """Slots for the touches of one trace, handed out in time order."""

    def __init__(self):
        self._slot_of: dict[int, int] = {}  # finger id touching (no up yet) -> its slot
        self._free_from: list[float] = []  # per slot: first output index a touch may take it
        self._lift_seq: list[int] = []  # per slot: sample number of its last lift (-1: none)
        self._seq = 0  # sample number of the first sample of the next assign call
        self._changes: list[tuple[int, int, int]] = []  # (output index, slot, id) to label
        self._id_of: dict[int, int] = {}  # slot -> finger id it carries (labelled so far)
        #: touches of more than one sample that began and lifted at one output index: in
        #: contact for no output sample
        self.brief_touches = 0

    def assign(self, samples: Trace, applied: np.ndarray) -> Trace:
        """``samples`` (the next consecutive ones of the trace) with each finger id
        replaced by its slot; ``applied``: their output indices (``apply_index``)."""
        finger = samples.finger
        n = finger.size
        order = np.argsort(finger, kind="stable")
        ids, up, at = finger[order], samples.event[order] == UP, applied[order]
        # a touch: one id's consecutive samples up to and including an up
        begins = np.ones(n, dtype=bool)
        begins[1:] = (ids[1:] != ids[:-1]) | up[:-1]
        starts = np.flatnonzero(begins)
        ends = np.append(starts[1:], n)
        first_at = np.minimum.reduceat(at, starts)
        last_at = np.maximum.reduceat(at, starts)
        slots = np.empty(starts.size, dtype=np.int64)
        for s in np.argsort(order[starts], kind="stable").tolist():  # touches in time order
            fid = int(ids[starts[s]])
            lifts = bool(up[ends[s] - 1])
            slot = self._slot_of.pop(fid, None)
            if slot is None:
                brief = lifts and first_at[s] == last_at[s]
                self.brief_touches += int(brief and ends[s] - starts[s] > 1)
                slot = self._free_slot(int(first_at[s]), self._seq + int(order[starts[s]]), brief)
                self._changes.append((int(first_at[s]), slot, fid))
            if lifts:  # free from the block after the lift's
                self._free_from[slot] = int(last_at[s]) + 1
                self._lift_seq[slot] = self._seq + int(order[ends[s] - 1])
            else:
                self._slot_of[fid] = slot
                self._free_from[slot] = np.inf
            slots[s] = slot
        renamed = np.empty(n, dtype=np.int64)
        renamed[order] = np.repeat(slots, ends - starts)
        self._seq += n
        return replace(samples, finger=renamed)

    def _free_slot(self, index: int, seq: int, brief: bool) -> int:
        """The lowest slot free for a touch whose first sample (number ``seq``) applies
        at output ``index``; ``brief``: it lifts at that same index (shows at no output)."""
        for slot, free_from in enumerate(self._free_from):
            if free_from <= index or (brief and free_from == index + 1 and self._lift_seq[slot] < seq):
                return slot
        self._free_from.append(np.inf)
        self._lift_seq.append(-1)
        return len(self._free_from) - 1

    def label(self, out):
        """``out`` (a ``rendering.pipeline.BlockOutput`` whose rows are slots) with the
        recording's finger ids: ``finger_ids`` each row's id at the call's first sample,
        and ``sample_ids`` (F, n) where a row carries more than one id in the call."""
        index0, end = out.index0, out.index0 + out.t_s.size
        # by output index; at one index in the order the touches began (stable)
        due = sorted((c for c in self._changes if c[0] < end), key=lambda c: c[0])
        self._changes = [c for c in self._changes if c[0] >= end]
        for _, slot, fid in (c for c in due if c[0] <= index0):
            self._id_of[slot] = fid
        inside = [c for c in due if c[0] > index0]  # a row changes finger within the call
        labelled = replace(out, finger_ids=tuple(self._id_of.get(s, UNNAMED) for s in out.finger_ids))
        if not inside:
            return labelled
        sample_ids = labelled.ids_per_sample()  # a new (F, n) array
        rows = {slot: row for row, slot in enumerate(out.finger_ids)}
        for at, slot, fid in inside:
            if slot in rows:
                sample_ids[rows[slot], at - index0:] = fid
            self._id_of[slot] = fid
        return replace(labelled, sample_ids=sample_ids)
