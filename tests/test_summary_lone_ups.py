"""Up events that lift no touch are warned about, counted; a finger with no contact
sample has no error figures (null), not an error of 0."""

import json

import numpy as np

from frictex import Summary
from frictex.app.commands.cli import main
from frictex.app.engine.sources import _lone_ups
from frictex.rendering.input.trace_file import DOWN, MOVE, UP


def test_a_trace_of_only_ups_warns_and_gives_no_error_figures(tmp_path, capsys):
    trace = tmp_path / "ups.csv"
    trace.write_text("t_s,finger,x_mm,y_mm,event\n0,0,10,10,up\n0.01,1,10,10,up\n")
    out = tmp_path / "out"
    assert main(["replay", "grating-5mm", str(trace), "--out", str(out)]) == 0
    doc = json.loads((out / "summary.json").read_text())
    said = [w for w in doc["warnings"] if "no touch to lift" in w]
    assert said == ["trace: 2 up events with no touch to lift (a finger with no down or move "
                    "since its last up) were ignored"]
    assert said[0] in capsys.readouterr().err
    assert doc["fingers"] == {
        fid: {"contact_samples": 0, "amplitude_error_rms_um": None, "amplitude_error_max_um": None}
        for fid in ("0", "1")}
    assert Summary.from_dict(doc).fingers[0].amplitude_error_rms_um is None


def test_ups_are_counted_against_the_touches_across_chunks():
    down: set[int] = set()
    # finger 3 touches and lifts, then lifts again; finger 4 comes down in this chunk
    finger = np.array([3, 4, 3, 3])
    event = np.array([DOWN, DOWN, UP, UP])
    assert _lone_ups(finger, event == UP, down) == 1 and down == {4}
    # next chunk: 4 moves and lifts (its down was in the chunk before), 3 lifts nothing
    assert _lone_ups(np.array([4, 4, 3]), np.array([MOVE, UP, UP]) == UP, down) == 1
    assert down == set()


def _replayed_warnings(tmp_path, rows: str) -> list[str]:
    trace = tmp_path / "t.csv"
    trace.write_text("t_s,finger,x_mm,y_mm,event\n" + rows)
    out = tmp_path / "out"
    assert main(["replay", "grating-5mm", str(trace), "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())["warnings"]


def test_a_finger_a_trace_that_lifts_fingers_leaves_touching_is_said(tmp_path):
    """A recording cut short (a phone's paint log: 14 downs, 13 ups) held its last touch
    down to the end of the output, unsaid; finger 1 lifted by a long gap is not said, nor
    is a trace with no up events (every sample touches: no event column)."""
    said = _replayed_warnings(tmp_path, "0,0,10,10,down\n0.01,1,20,10,down\n0.02,0,11,10,move\n"
                                        "0.03,1,21,10,up\n0.04,2,30,10,down\n6,0,12,10,move\n"
                                        "6.01,0,13,10,move\n")
    assert [w for w in said if w.startswith("trace: finger")] == [
        "trace: finger 0 still touching at its end (6.01 s), with no up event: held down to "
        "the end of the output (a recording cut short, or its last lift lost?)"]
    no_events = tmp_path / "plain"
    no_events.mkdir()
    plain = (no_events / "t.csv")
    plain.write_text("t_s,finger,x_mm,y_mm\n0,0,10,10\n0.01,0,11,10\n0.02,0,12,10\n")
    assert main(["replay", "grating-5mm", str(plain), "--out", str(no_events / "o"),
                 "--quiet"]) == 0
    doc = json.loads((no_events / "o" / "summary.json").read_text())
    assert not [w for w in doc["warnings"] if w.startswith("trace: finger")]
