"""summary.json lists only finger ids the trace names: a row of the pipeline that no
touch has taken yet (a lift and a new touch of one finger inside one output block)
is no finger."""

import json

import pytest

from frictex.app.commands.cli import main

# finger 0 lifts at 0.0205 s and touches again at 0.0215 s, inside one 5 ms block
RETOUCH = """t_s,finger,x_mm,y_mm,event
0.000,{f},10,10,down
0.0205,{f},12,10,up
0.0215,{f},60,30,down
0.050,{f},62,30,up
"""


def _summary(tmp_path, text):
    tmp_path.mkdir(exist_ok=True)
    trace = tmp_path / "t.csv"
    trace.write_text(text)
    out = tmp_path / "out"
    assert main(["replay", "grating-5mm", str(trace), "--out", str(out), "--quiet"]) == 0
    return json.loads((out / "summary.json").read_text())


@pytest.mark.parametrize("finger", [0, 5])
def test_a_lift_and_touch_in_one_block_lists_only_the_traces_finger(tmp_path, finger):
    doc = _summary(tmp_path, RETOUCH.format(f=finger))
    assert doc["trace"]["fingers"] == [finger]
    assert list(doc["fingers"]) == [str(finger)]
    assert doc["fingers"][str(finger)]["contact_samples"] == doc["counts"]["contact_samples"]


def test_a_brief_touch_at_the_traces_first_sample_is_in_contact_for_a_block(tmp_path):
    """Blocks start at the trace's first sample: a down there takes effect at once, so a
    down, up, down within 0.2 ms at the start holds the first touch for one block (50
    samples at 10 kHz), not within a block, where the same three samples later in a
    trace both apply at the next block boundary (same.csv's count of 1)."""
    doc = _summary(tmp_path, """t_s,finger,x_mm,y_mm,event
0.0301,5,20,20,down
0.0302,5,20,20,up
0.0303,5,70,20,down
0.050,5,72,20,up
""")
    assert doc["trace"]["touches_within_a_block"] == 0
    assert doc["fingers"]["5"]["contact_samples"] == 50 + 150
    late = _summary(tmp_path / "late", """t_s,finger,x_mm,y_mm,event
0.000,0,10,10,down
0.0205,0,12,10,up
0.0301,5,20,20,down
0.0302,5,20,20,up
0.0303,5,70,20,down
0.050,5,72,20,up
""")
    assert late["trace"]["touches_within_a_block"] == 1
    assert late["fingers"]["5"]["contact_samples"] == 150
