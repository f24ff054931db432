"""The ``forces`` section of a replay's summary.json (travelling-wave profiles only).

Per finger, over the samples it touches: how far the force the wave gives (forward
model, ``rendering.layers.force_layers``) was from the force the scene wanted, along x (the
axis the waves push on), in N; how many samples asked for a force out of reach there
(clamped and counted, e.g. near a beam end where the wave stands); and the key-click
phase flips.
"""

from __future__ import annotations

import numpy as np

from frictex.app.engine.finger_table import FingerTable


class ForceSummary:
    """Accumulates ``BlockOutput.forces`` over a replay; ``report()`` gives the section
    (bounded in the ids it lists: ``app.engine.finger_table``)."""

    def __init__(self):
        # id -> [samples, sum sq, max |err|, unreachable, clicks, max |wanted|]
        self.table = FingerTable(("sum", "sum", "max", "sum", "sum", "max"))

    def add(self, out) -> None:
        forces = out.forces
        if forces is None:
            return
        err = np.where(out.contact, forces.achieved_n[..., 0] - forces.wanted_n[..., 0], 0.0)
        segments = out.segments()
        for row, fid, lo, hi in segments:
            s = self.table.row(fid)
            s[0] += int(out.contact[row, lo:hi].sum())
            s[1] += float(np.sum(err[row, lo:hi] ** 2))
            s[2] = max(s[2], float(np.abs(err[row, lo:hi]).max(initial=0.0)))
            s[3] += int(forces.unreachable[row, lo:hi].sum())
            s[4] += int(forces.clicks[row, lo:hi].sum())
            s[5] = max(s[5], float(np.abs(forces.wanted_n[row, lo:hi, 0]).max(initial=0.0)))
        self.table.done_adding(fid for _, fid, _, _ in segments)

    @staticmethod
    def _entry(n, sq, mx, unreachable, clicks, wmax) -> dict:
        return {"contact_samples": n, "force_error_rms_n": (sq / n) ** 0.5 if n else None,
                "force_error_max_n": mx if n else None, "wanted_max_n": wmax if n else None,
                "unreachable_samples": unreachable, "clicks": clicks}

    def report(self) -> dict | None:
        """{finger: {contact_samples, force_error_rms_n, force_error_max_n, wanted_max_n,
        unreachable_samples, clicks}} for the listed fingers (at most ``MAX_LISTED``, those
        with the most contact samples), or None if the replay had no force stage."""
        if not (self.table.rows or self.table.folded):
            return None
        return {str(fid): self._entry(*row) for fid, row in self.table.report()[0].items()}

    def others(self) -> dict | None:
        """The same entry over the fingers not listed, or None (no force stage, or every
        finger listed)."""
        rest = self.table.report()[1]
        return None if rest is None else self._entry(*rest[1])
