"""A replay whose two fingers sit on seed 001's singular locus counts and warns of it."""

import json

import numpy as np

from frictex.app.commands.cli import main


def test_a_replay_on_the_singular_locus_counts_and_warns(tmp_path):
    # finger 2 one wavelength (32.94 mm) from finger 1 along x and y (seed 001, eq 8): both
    # got the same 0.311 um for mu' 0.85 and 0.80, and the run said 0 clamped, no warning
    t = np.round(np.arange(100) * 0.02, 3)
    rows = [f"{s:.3f},{f},{x + 0.6 * k:.4f},{y}" for k, s in enumerate(t)
            for f, (x, y) in enumerate(((20.0, 70.0), (52.9412, 102.9412)))]
    trace = tmp_path / "sing.csv"
    trace.write_text("t_s,finger,x_mm,y_mm\n" + "\n".join(rows) + "\n", encoding="utf-8")
    assert main(["replay", "two-finger-plate-seed001", str(trace), "--out", str(tmp_path / "o")]) == 0
    summary = json.loads((tmp_path / "o" / "summary.json").read_text(encoding="utf-8"))
    capped = summary["counts"]["modal_capped"]
    assert capped > 0
    assert any(w.startswith(f"{capped} samples: the fingers could not be given independent "
                            "amplitudes (seed 001 eq 8") for w in summary["warnings"])
