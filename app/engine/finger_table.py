"""Per-finger sums for a summary, bounded however many finger ids a trace holds.

A recording may give every touch a new id (100,000 taps in a 5 MB trace), so a summary
with an entry per id would grow with the ids, not with the fingers. :class:`FingerTable`
keeps a row of sums per id while it runs, at most ``2 * MAX_KEPT`` of them: past that,
the rows with the fewest contact samples (beyond the ``MAX_KEPT`` largest, and not on a
row of the output just added) are folded into one aggregate. Its report lists the
``MAX_LISTED`` ids with the most contact samples; the rest are aggregated and counted
(``app/engine/SUMMARY.md``, ``fingers_others``). An id folded while the run went stays
in the aggregate if it touches again.
"""

from __future__ import annotations

#: finger ids listed in a summary (those with the most contact samples)
MAX_LISTED = 100
#: finger ids kept apart while a run goes (folded down to this when twice as many)
MAX_KEPT = 1000


class FingerTable:
    """Rows of sums per finger id; column 0 is the contact samples.

    Parameters
    ----------
    kinds : per column, "sum" (added when rows merge) or "max" (the larger kept).
    listed, kept : :data:`MAX_LISTED`, :data:`MAX_KEPT`.
    """

    def __init__(self, kinds: tuple[str, ...], listed: int = MAX_LISTED, kept: int = MAX_KEPT):
        if kinds[0] != "sum" or not set(kinds) <= {"sum", "max"} or not 0 < listed <= kept:
            raise ValueError(f"bad FingerTable layout {kinds}, listed {listed}, kept {kept}")
        self.kinds = kinds
        self.listed, self.kept = listed, kept
        self.rows: dict[int, list] = {}
        self.folded: set[int] = set()  # ids in the aggregate
        self.others = [0] * len(kinds)

    def row(self, fid: int) -> list:
        """The row of ``fid`` (created at zero), to add into in place; for an id below 0
        (a row no finger has taken yet, ``app.engine.finger_slots.UNNAMED``) a row kept
        nowhere, so that no id the trace never named is listed."""
        if fid < 0:
            return [0] * len(self.kinds)
        row = self.rows.get(fid)
        if row is None:
            row = self.rows[fid] = [0] * len(self.kinds)
        return row

    def done_adding(self, touching) -> None:
        """After one output's rows were added: fold the smallest rows if over the bound,
        keeping those of the ids in ``touching`` (the output's finger ids)."""
        if len(self.rows) <= 2 * self.kept:
            return
        keep = set(touching)
        ranked = sorted(self.rows, key=lambda fid: (-self.rows[fid][0], fid))
        for fid in ranked[self.kept:]:
            if fid not in keep:
                self._fold(fid)

    def _fold(self, fid: int) -> None:
        row = self.rows.pop(fid)
        self.folded.add(fid)
        self.others = self._merged(self.others, row)

    def _merged(self, a: list, b: list) -> list:
        return [x + y if kind == "sum" else max(x, y) for kind, x, y in zip(self.kinds, a, b)]

    def report(self) -> tuple[dict[int, list], tuple[int, list] | None]:
        """The listed ids' rows, in id order, and (ids aggregated, their merged row) or
        None when every id is listed."""
        ranked = sorted((fid for fid in self.rows if fid not in self.folded),
                        key=lambda fid: (-self.rows[fid][0], fid))
        listed = {fid: self.rows[fid] for fid in sorted(ranked[:self.listed])}
        others, ids = self.others, set(self.folded)
        for fid in self.rows:
            if fid not in listed:
                others = self._merged(others, self.rows[fid])
                ids.add(fid)
        return listed, ((len(ids), others) if ids else None)
