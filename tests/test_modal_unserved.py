"""A third finger on a two-mode scene is not served: the replay counts its samples and
says so (device/actuation/modal_actuation.py, step 2)."""

import json

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.summary import _unserved_warning


def replay_still_fingers(tmp_path, xs_mm) -> dict:
    """summary.json of still fingers at ``xs_mm`` (y = 3 mm) on the two-mode beam for 1 s."""
    t = np.round(np.arange(100) * 0.01, 3)
    rows = [f"{s:.3f},{f},{x},3" for s in t for f, x in enumerate(xs_mm)]
    trace = tmp_path / "still.csv"
    trace.write_text("t_s,finger,x_mm,y_mm\n" + "\n".join(rows) + "\n", encoding="utf-8")
    assert main(["replay", "two-finger-beam-seed000", str(trace), "--out", str(tmp_path / "o"),
                 "--quiet"]) == 0
    return json.loads((tmp_path / "o" / "summary.json").read_text(encoding="utf-8"))


def test_a_third_finger_on_two_modes_is_counted_and_warned_of(tmp_path):
    # finger 2 asked for 0 um and felt 0.1456 um of the others' vibration, and the run said
    # nothing: no count, no warning
    summary = replay_still_fingers(tmp_path, (100.0, 150.0, 200.0))
    third = summary["fingers"]["2"]
    unserved = summary["counts"]["modal_unserved"]
    assert unserved == third["contact_samples"] > 0
    assert third["amplitude_error_max_um"] == pytest.approx(0.1456, abs=1e-3)
    assert [w for w in summary["warnings"] if "not served" in w] == [
        f"{unserved} finger samples were not served: the scene's 2 modes serve only 2 fingers "
        "at a time (those touching longest), so a further finger gets no control of its own "
        "and feels the vibration the served ones get (|Phi(x) W_M|, its achieved amplitude "
        "in fingers) whatever its target"]


def test_two_fingers_on_two_modes_are_all_served(tmp_path):
    summary = replay_still_fingers(tmp_path, (100.0, 150.0))
    assert summary["counts"]["modal_unserved"] == 0
    assert not [w for w in summary["warnings"] if "not served" in w]


def test_one_unserved_sample_is_said_in_the_singular():
    assert _unserved_warning(1, 2).startswith("1 finger sample was not served: the scene's 2 modes")
