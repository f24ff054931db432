"""Every synthetic bundled trace is what the command on its first line makes.

The synthesis is float64 arithmetic through numpy and scipy; a new version of either may
change the last printed digit of a position (seen with numpy 2.4 against the versions
the traces were made with). So the comment line, the header, the finger ids and the
events must match exactly, and the numbers to a relative 1e-12 (about 4 ulp at 17
significant digits; a change in the synthesis itself moves them by far more).
"""

import csv
import math

import pytest

from frictex.app.commands.cli import main
from frictex.textures.library import list_traces, resolve_trace

SYNTHETIC = [e.name for e in list_traces()
             if "(frictex trace synth" in resolve_trace(e.name).read_text().splitlines()[0]]


def test_most_bundled_traces_say_how_they_were_made():
    assert {"swipe-40mms-50hz", "human-strokes-120hz", "keyclick-press-100hz"} <= set(SYNTHETIC)


@pytest.mark.parametrize("name", SYNTHETIC)
def test_bundled_trace_is_made_by_the_command_on_its_first_line(name, tmp_path):
    bundled = resolve_trace(name).read_text(encoding="utf-8")
    command = bundled.splitlines()[0].split("(frictex ", 1)[1].rstrip(")").split()
    assert main([*command, "-o", str(tmp_path / "again.csv")]) == 0
    again = (tmp_path / "again.csv").read_text(encoding="utf-8")
    ours, theirs = again.splitlines(), bundled.splitlines()
    assert ours[:2] == theirs[:2]  # the command and the header
    assert len(ours) == len(theirs)
    for line, (row, expected) in enumerate(zip(csv.reader(ours[2:]), csv.reader(theirs[2:])), 3):
        assert len(row) == len(expected), f"line {line}"
        for cell, want in zip(row, expected):
            if want.lstrip("-").replace(".", "", 1).replace("e-", "", 1).isdigit() and "." in want:
                assert math.isclose(float(cell), float(want), rel_tol=1e-12, abs_tol=1e-12), \
                    f"line {line}: {cell} against {want}"
            else:
                assert cell == want, f"line {line}"
