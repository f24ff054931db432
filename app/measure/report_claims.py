"""The claims ``frictex report`` checks on its rows (issue 4's targets), each pass or fail.

- ``ranking``: plain SHO (sho-held) against SHT at a 50 Hz touch rate reproduces seed 003's
  experiment (section 5): SHT has the lower spectral error on the 0.6 mm grating, SHO the
  lower alignment error on the 15 mm grating.
- ``hybrid-best``: on each seed 003 grating, motion and metric, the hybrid is no worse than
  the better of SHO (sho-held, the seed's SHO) and SHT.
- ``hybrid-30``: ... and at least 30 % better than the worse of the two.

Both hybrid claims use the constant-speed (slow, fast) and human-like motions at 50 Hz,
10 kHz output, exact inversion. One is expected to fail: time error on the 0.6 mm
grating under the human-like motion (see ``PHASE_UNFELT`` and ``rendering.layers.hybrid``). sho-predicted, frictex's own SHO with position
prediction, is shown beside them in the report but is not part of the targets.
"""

from __future__ import annotations

from dataclasses import dataclass

METRICS = ("time_error", "spectral_error", "alignment_error_mm")
GRATINGS = {"grating-15mm": 15.0, "grating-5mm": 5.0, "grating-0.6mm": 0.6}
CLAIM_MOTIONS = ("slow", "fast", "human")
TOUCH_HZ = 50.0
OUTPUT_HZ = 10_000.0
#: the (scene, metric) the hybrid is not expected to win, and why (shown in report.md)
PHASE_UNFELT = {("grating-0.6mm", "time_error"): (
    "expected: on a 0.6 mm grating the time error measures a spatial phase no finger feels "
    "(seed 003 section 6) and no renderer gets right while the finger moves (50 Hz samples, "
    "0.05 mm noise and up to 20 ms of extrapolation put it 0.1-0.3 mm off, a third of a "
    "period); which renderer scores lowest depends on the draw of the strokes, see the seed "
    "scatter below")}


@dataclass(frozen=True)
class Claim:
    """One checked statement: its group, where it applies, the figures and the verdict."""

    group: str
    scene: str
    motion: str
    metric: str
    text: str
    passed: bool


def _index(rows) -> dict:
    return {(r["scene"], r["motion"], r["renderer"]): r for r in rows
            if r["touch_hz"] == TOUCH_HZ and r["output_hz"] == OUTPUT_HZ
            and r.get("inversion", "exact") == "exact"}


def claims(rows) -> list[Claim]:
    """Every claim the rows allow checking (a claim whose rows are missing is left out)."""
    at = _index(rows)
    out = []
    for motion in CLAIM_MOTIONS:
        fine = [at.get(("grating-0.6mm", motion, r)) for r in ("sht", "sho-held")]
        if all(fine):
            sht, sho = (f["spectral_error"] for f in fine)
            out.append(Claim("ranking", "grating-0.6mm", motion, "spectral_error",
                             f"SHT {sht:.3f} < SHO {sho:.3f}", sht < sho))
        coarse = [at.get(("grating-15mm", motion, r)) for r in ("sho-held", "sht")]
        if all(coarse):
            sho, sht = (c["alignment_error_mm"] for c in coarse)
            out.append(Claim("ranking", "grating-15mm", motion, "alignment_error_mm",
                             f"SHO {sho:.3f} mm < SHT {sht:.3f} mm", sho < sht))
    for scene in GRATINGS:
        for motion in CLAIM_MOTIONS:
            trio = [at.get((scene, motion, r)) for r in ("hybrid", "sho-held", "sht")]
            if not all(trio):
                continue
            hybrid, sho, sht = trio
            for metric in METRICS:
                h, a, b = hybrid[metric], sho[metric], sht[metric]
                better, worse = min(a, b), max(a, b)
                out.append(Claim("hybrid-best", scene, motion, metric,
                                 f"hybrid {h:.3f} <= better of SHO {a:.3f} / SHT {b:.3f}",
                                 h <= better))
                out.append(Claim("hybrid-30", scene, motion, metric,
                                 f"hybrid {h:.3f} <= 0.7 x worse {worse:.3f} = {0.7 * worse:.3f}",
                                 h <= 0.7 * worse))
    return out
