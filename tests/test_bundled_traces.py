"""Every synthetic bundled trace is what the command on its first line makes (to the
last printed digit or so: tests/trace_text.py says why)."""

import pytest

from trace_text import assert_same_trace_text

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
    assert_same_trace_text((tmp_path / "again.csv").read_text(encoding="utf-8"), bundled)
