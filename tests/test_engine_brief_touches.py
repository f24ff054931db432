"""Touches that begin and lift within one output block are in contact for no output
sample: the summary counts them and says so."""

import json

import numpy as np

from frictex.app.engine.replay import run_replay
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

TAPS = 200  # each a new id: 2 ms down, 2 ms up


def test_taps_shorter_than_a_block_are_counted_and_warned(tmp_path):
    """Taps every 4 ms at 5 ms blocks: a tap touches an output sample only where its
    down and up fall on either side of a block boundary."""
    rows = "".join(f"{0.004 * i:.3f},{i},5,5,0.5,down\n{0.004 * i + 0.002:.3f},{i},5,5,0.5,up\n"
                   for i in range(TAPS))
    trace = tmp_path / "taps.csv"
    trace.write_text("t_s,finger,x_mm,y_mm,force_n,event\n" + rows)
    doc = run_replay(load_scene(resolve_scene("grating-5mm")), str(trace), tmp_path / "o",
                     fmt="npz", progress=False)
    written = json.loads((tmp_path / "o" / "summary.json").read_text())
    with np.load(tmp_path / "o" / "friction.npz") as friction:
        seen = np.unique(friction["finger"]).size
    within = written["trace"]["touches_within_a_block"]
    assert 0 < seen < TAPS and within == TAPS - seen
    assert any(line.startswith(f"{within} touches began and lifted within one output block")
               for line in doc["warnings"])


def test_a_touch_held_over_blocks_is_not_counted(tmp_path):
    trace = tmp_path / "held.csv"
    trace.write_text("t_s,finger,x_mm,y_mm\n0,0,1,1\n0.001,0,1.1,1\n0.05,0,2,1\n")
    doc = run_replay(load_scene(resolve_scene("grating-5mm")), str(trace), tmp_path / "o",
                     progress=False)
    assert doc["trace"]["touches_within_a_block"] == 0
    assert not any("within one output block" in line for line in doc["warnings"])
