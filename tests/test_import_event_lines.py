"""Recording importers name the line of a bad event: a coordinate far off the screen, a
time going back on any event line, a misspelled multi-touch code name."""

import argparse
import re
from pathlib import Path

import pytest

from frictex.rendering.input.import_evemu import parse_evemu
from frictex.rendering.input.import_getevent import parse_getevent, read_log
from frictex.rendering.input.trace_file import TraceError
from frictex.rendering.input.trace_import import add_import_arguments, run_import

REFDATA = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "android-getevent"
DRAG = REFDATA / "Phone" / "phone-single-drag.txt"
needs_refdata = pytest.mark.skipif(not DRAG.is_file(),
                                   reason=f"refdata Android getevent logs not found at {REFDATA / 'Phone'}")
# what SOURCE.txt says of the Galaxy S phone: a 0..1023 digitizer on about 52 x 87 mm
PHONE = ["--x-range", "0", "1023", "--y-range", "0", "1023", "--width-mm", "52", "--height-mm", "87"]

EVEMU = """N: Test Touchscreen
A: 35 0 3072 0 0 12
A: 36 0 2048 0 0 12
E: 0.000001 0003 0039 6
E: 0.000001 0003 0035 1536
E: 0.000001 0003 0036 1024
E: 0.000001 0000 0000 0
E: 0.007450 0003 0035 1548
E: 0.007450 0000 0000 0
E: 0.015000 0003 0039 -1
E: 0.015000 0000 0000 0
"""


def _import(argv):
    parser = argparse.ArgumentParser(prog="frictex trace import")
    add_import_arguments(parser)
    return run_import(parser.parse_args(argv), lambda path, text: Path(path).write_text(text))


def _drag_with_line_50(tmp_path, pattern, replacement):
    """The refdata single drag with ``pattern`` replaced on line 50 (an ABS_MT_POSITION_X
    of the frame ending on line 52), written to tmp_path / edited.txt."""
    lines = DRAG.read_text().splitlines(keepends=True)
    assert "ABS_MT_POSITION_X" in lines[49]
    lines[49], n = re.subn(pattern, replacement, lines[49])
    assert n == 1
    path = tmp_path / "edited.txt"
    path.write_text("".join(lines))
    return path


# -- a coordinate far off the screen ---------------------------------------------------------
@needs_refdata
def test_a_glitch_count_is_named_by_its_line_with_its_mm_and_the_range(tmp_path):
    """0x7fffffff on line 50 was told as 'sample 7: x_mm is 109158504.05...'."""
    path = _drag_with_line_50(tmp_path, r"ABS_MT_POSITION_X +[0-9a-f]+",
                              "ABS_MT_POSITION_X    7fffffff")
    with pytest.raises(TraceError, match=r"^.*edited\.txt:50: device x count 2147483647 is "
                       r"1\.09159e\+08 mm on the screen \(device x range 0\.\.1023 over 52 mm\); "
                       r"expected -100000 to 100000 mm \(a glitch value\? else check --x-range\)$"):
        _import([str(path), "-o", str(tmp_path / "out.csv")] + PHONE)
    # swapped, device x runs along the screen's 87 mm height
    with pytest.raises(TraceError, match=r"edited\.txt:50: device x count 2147483647 is "
                       r"1\.82631e\+08 mm .*over 87 mm"):
        _import([str(path), "-o", str(tmp_path / "out.csv"), "--swap-xy"] + PHONE)


def test_an_evemu_glitch_count_is_named_by_its_line(tmp_path):
    src = tmp_path / "rec.evemu"
    src.write_text(EVEMU.replace("0036 1024", "0036 -2147483648"))
    with pytest.raises(TraceError, match=r"rec\.evemu:6: device y count -2147483648 is "
                       r"-1\.78957e\+08 mm on the screen \(device y range 0\.\.2048 over "
                       r"170\.667 mm\)"):
        _import([str(src), "-o", str(tmp_path / "out.csv")])


def test_a_glitch_count_in_events_a_syn_dropped_threw_away_is_no_error(tmp_path, capsys):
    """The decoder drops what follows a SYN_DROPPED up to the next SYN_REPORT: a glitch
    there reaches no sample, and the recording imports as it did (with its warning)."""
    src = tmp_path / "rec.evemu"
    src.write_text(EVEMU.replace("E: 0.007450 0003 0035 1548",
                                 "E: 0.005000 0000 0003 0\nE: 0.005000 0003 0035 2147483647\n"
                                 "E: 0.005000 0000 0000 0\nE: 0.007450 0003 0035 1548"))
    assert _import([str(src), "-o", str(tmp_path / "out.csv")]) == 0
    assert "1 SYN_DROPPED" in capsys.readouterr().err


# -- time going back -------------------------------------------------------------------------
@needs_refdata
def test_getevent_time_going_back_on_any_event_line_is_refused(tmp_path):
    """Going back on line 50 (not a SYN_REPORT) was imported silently."""
    path = _drag_with_line_50(tmp_path, r"\[ *[0-9.]+\]", "[   1.0]")
    with pytest.raises(TraceError, match=r"edited\.txt:50: time goes back from 1411\.867073 to "
                       r"1\.0 s \(events must be in the order the kernel sent them\)$"):
        _import([str(path), "-o", str(tmp_path / "out.csv")] + PHONE)


def test_getevent_time_order_is_per_device():
    log = ("[ 2.0] /dev/input/event2: EV_ABS ABS_MT_POSITION_X 0000000a\n"
           "[ 1.5] /dev/input/event5: EV_SYN SYN_REPORT 00000000\n"
           "[ 2.0] /dev/input/event2: EV_SYN SYN_REPORT 00000000\n"
           "[ 1.9] /dev/input/event2: EV_ABS ABS_MT_POSITION_Y 00000014\n")
    assert [e.t_s for e in parse_getevent(log, "log", "/dev/input/event5")] == [1.5]
    with pytest.raises(TraceError, match=r"^log:4: time goes back from 2\.0 to 1\.9 s"):
        parse_getevent(log, "log", "/dev/input/event2")


def test_evemu_time_going_back_on_any_event_line_is_refused():
    back = EVEMU.replace("E: 0.007450 0003 0035 1548", "E: 0.000000 0003 0035 1548")
    with pytest.raises(TraceError, match=r"^rec:8: time goes back from 1e-06 to 0\.0 s"):
        parse_evemu(back, "rec")


# -- misspelled multi-touch codes -------------------------------------------------------------
def test_an_unknown_abs_mt_name_is_warned_of_once_at_its_first_line():
    log = ("[ 1.0] EV_ABS ABS_MT_FOO_BAR 0000000a\n"
           "[ 1.0] EV_ABS ABS_MT_POSITION_Y 00000014\n"
           "[ 1.0] EV_ABS ABS_MT_FOO_BAR 0000000b\n"
           "[ 1.0] EV_ABS ABS_MT_WIDTH_MAJOR 00000003\n"
           "[ 1.0] EV_ABS ABS_MISC 00000003\n"
           "[ 1.0] EV_KEY KEY_VOLUMEUP DOWN\n"
           "[ 1.0] EV_SYN SYN_MT_REPORT 00000000\n"
           "[ 1.0] EV_SYN SYN_REPORT 00000000\n")
    log_read = read_log(log, "log")
    assert log_read.warnings == ['log:1: "ABS_MT_FOO_BAR" is no multi-touch code Linux names '
                                 '(a typo?): its events are left out']
    assert [e.code for e in log_read.events][:5] == [-1, 0x36, -1, 0x32, -1]
    # the named codes frictex does not read are those of their hex forms
    assert parse_getevent("[ 1.0] 0003 0032 00000003\n")[0].code == 0x32


@needs_refdata
def test_a_misspelled_position_code_in_the_drag_is_named(tmp_path, capsys):
    """It was only 'warning: 1 contact reports without a position were left out'."""
    path = _drag_with_line_50(tmp_path, r"ABS_MT_POSITION_X   ", "ABS_MT_FOO_BAR      ")
    assert _import([str(path), "-o", str(tmp_path / "out.csv")] + PHONE) == 0
    err = capsys.readouterr().err
    assert err.count("ABS_MT_FOO_BAR") == 1
    assert 'edited.txt:50: "ABS_MT_FOO_BAR" is no multi-touch code Linux names (a typo?)' in err
