"""The ``forces`` section of a replay's summary.json (travelling-wave profiles only).

Per finger, over the samples it touches: how far the force the wave gives (forward
model, ``rendering.layers.force_layers``) was from the force the scene wanted, along x (the
axis the waves push on), in N; how many samples asked for a force out of reach there
(clamped and counted, e.g. near a beam end where the wave stands); and the key-click
phase flips.
"""

from __future__ import annotations

import numpy as np


class ForceSummary:
    """Accumulates ``BlockOutput.forces`` over a replay; ``report()`` gives the section."""

    def __init__(self):
        self.stats: dict[int, list] = {}  # id -> [samples, sum sq, max |err|, unreachable, clicks, max |wanted|]

    def add(self, out) -> None:
        forces = out.forces
        if forces is None:
            return
        err = np.where(out.contact, forces.achieved_n[..., 0] - forces.wanted_n[..., 0], 0.0)
        for row, fid, lo, hi in out.segments():
            s = self.stats.setdefault(fid, [0, 0.0, 0.0, 0, 0, 0.0])
            s[0] += int(out.contact[row, lo:hi].sum())
            s[1] += float(np.sum(err[row, lo:hi] ** 2))
            s[2] = max(s[2], float(np.abs(err[row, lo:hi]).max(initial=0.0)))
            s[3] += int(forces.unreachable[row, lo:hi].sum())
            s[4] += int(forces.clicks[row, lo:hi].sum())
            s[5] = max(s[5], float(np.abs(forces.wanted_n[row, lo:hi, 0]).max(initial=0.0)))

    def report(self) -> dict | None:
        """{finger: {contact_samples, force_error_rms_n, force_error_max_n, wanted_max_n,
        unreachable_samples, clicks}}, or None if the replay had no force stage."""
        if not self.stats:
            return None
        return {str(fid): {"contact_samples": n, "force_error_rms_n": (sq / n) ** 0.5 if n else 0.0,
                           "force_error_max_n": mx, "wanted_max_n": wmax,
                           "unreachable_samples": unreachable, "clicks": clicks}
                for fid, (n, sq, mx, unreachable, clicks, wmax) in sorted(self.stats.items())}
