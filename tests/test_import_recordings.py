"""Importing real touch-screen recordings: getevent -lt logs (refdata), evemu, the CLI."""

import argparse
import unicodedata
from pathlib import Path

import numpy as np
import pytest
from hypothesis import assume, given, settings, strategies as st
from numpy.testing import assert_allclose

from frictex.app.commands.cli import main
from frictex.rendering.input.trace_import import add_import_arguments, run_import
from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X, ABS_MT_TRACKING_ID, EV_ABS, EV_KEY,
                                                  MAX_RECORDING_BYTES, MAX_RESOLUTION, SCREEN_MM,
                                                  AbsInfo, ScreenSpec,
                                                  decode_all, observed_ranges, screen_map)
from frictex.rendering.input.import_evemu import parse_evemu
from frictex.rendering.input.import_getevent import parse_getevent, read_getevent
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, TraceError, make_trace, read_trace
from frictex.rendering.tracking.tracks import TrackerConfig, TrackerState, apply_index, track

REFDATA = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "android-getevent"
needs_refdata = pytest.mark.skipif(not REFDATA.is_dir(),
                                   reason=f"refdata Android getevent logs not found at {REFDATA}")
REF_FILES = sorted(REFDATA.glob("*/*.txt")) if REFDATA.is_dir() else []
# what SOURCE.txt says of the Galaxy S phone: a 0..1023 digitizer on about 52 x 87 mm
PHONE = ["--x-range", "0", "1023", "--y-range", "0", "1023", "--width-mm", "52", "--height-mm", "87"]


def _import(argv):
    parser = argparse.ArgumentParser(prog="frictex trace import")
    add_import_arguments(parser)
    return run_import(parser.parse_args(argv), lambda path, text: Path(path).write_text(text))


def _most_down(samples):
    down, most = set(), 0
    for s in samples:
        (down.discard if s.event == UP else down.add)(s.finger)
        most = max(most, len(down))
    return most


# -- the real logs --------------------------------------------------------------------------
@needs_refdata
@pytest.mark.parametrize("path", REF_FILES, ids=lambda p: p.name)
def test_every_refdata_log_decodes_into_a_valid_trace(path):
    samples, dec = decode_all(read_getevent(path), str(path))
    expected = "B" if "paint" in path.name else "A"  # SOURCE.txt
    assert dec.protocol == expected and dec.dropped == 0 and dec.unplaced == 0
    t = np.array([s.t_s for s in samples])
    trace = make_trace(t - t[0], [s.finger for s in samples], [s.x for s in samples],
                       [s.y for s in samples], event=[s.event for s in samples], where=path.name)
    assert len(trace) == len(samples) and np.array_equal(trace.event, [s.event for s in samples])
    # SOURCE.txt: observed counts lie within 0..1023 (phone) and 43..1572 x 24..861 (tablet)
    hi = 1023 if path.parent.name == "Phone" else 1572
    assert 0 <= trace.x_mm.min() and trace.x_mm.max() <= hi


@needs_refdata
@pytest.mark.parametrize("name, fingers, most, touches", [
    ("Phone/phone-two-finger-drag.txt", 2, 2, 2),
    ("Tablet/tablet-two-finger-drag.txt", 2, 2, 2),
    ("Phone/phone-three-touches.txt", 1, 1, 3),
    ("Tablet/tablet-three-touches.txt", 1, 1, 3),
    ("Phone/phone-single-touch.txt", 1, 1, 1),
    ("Tablet/tablet-single-drag.txt", 1, 1, 1),
])
def test_finger_counts(name, fingers, most, touches):
    samples, _ = decode_all(read_getevent(REFDATA / name), name)
    assert len({s.finger for s in samples}) == fingers
    assert _most_down(samples) == most
    assert sum(s.event == DOWN for s in samples) == touches
    assert sum(s.event == UP for s in samples) == touches


@needs_refdata
def test_three_touches_are_three_taps_in_sequence():
    samples, _ = decode_all(read_getevent(REFDATA / "Phone/phone-three-touches.txt"), "three")
    assert [s.event for s in samples] == [DOWN, UP] * 3
    # each tap lifted at the empty SYN_MT_REPORT frame, about 0.04 to 0.1 s after it began
    dur = np.array([samples[i + 1].t_s - samples[i].t_s for i in (0, 2, 4)])
    assert_allclose(dur, [1482.473085 - 1482.431956, 1484.414221 - 1484.342681,
                          1486.531224 - 1486.430734], atol=1e-9)


@needs_refdata
def test_the_0_57_ms_rereport_is_kept():
    samples, _ = decode_all(read_getevent(REFDATA / "Phone/phone-two-finger-drag.txt"), "drag")
    f0 = [s for s in samples if s.finger == 0]
    dt = np.diff([s.t_s for s in f0])
    moved = np.hypot(np.diff([s.x for s in f0]), np.diff([s.y for s in f0])) > 0
    short = dt < 0.001
    # SOURCE.txt: gaps of 0.57 ms, half the sample pairs without motion
    assert short.sum() >= 40 and np.all((dt[short] > 0.0005) & (dt[short] < 0.0007))
    assert 0.4 < 1 - moved.mean() < 0.6
    # the first such pair in the file: finger 0 at x 0x09, then 0x19 0.576 ms later
    i = int(np.argmax(short & moved))
    assert (f0[i].x, f0[i + 1].x) == (0x09, 0x19)
    assert_allclose(dt[i], 1807.506256 - 1807.505680, atol=1e-9)


@needs_refdata
def test_tracker_velocity_stays_sane_on_the_two_finger_drag(tmp_path):
    out = tmp_path / "drag.csv"
    assert _import([str(REFDATA / "Phone/phone-two-finger-drag.txt"), "-o", str(out)] + PHONE) == 0
    trace = read_trace(out)
    cfg = TrackerConfig(rate_hz=10_000.0, quantum=50, t0_s=0.0)
    n = int((trace.duration_s + 0.05) * cfg.rate_hz)
    block, state = track(0, n, trace, TrackerState(), cfg)
    assert state.jumps == 0 and state.out_of_order == 0
    naive_max = 0.0
    for row, fid in enumerate(block.ids):
        m = np.flatnonzero(trace.finger == fid)
        t, x, y = trace.t_s[m], trace.x_mm[m], trace.y_mm[m]
        step = np.hypot(np.diff(x), np.diff(y)) / np.diff(t)
        naive_max = max(naive_max, step.max())
        speed = np.hypot(block.vx[row], block.vy[row])
        assert np.all(np.isfinite(speed)) and speed.max() < 2000.0  # a finger, not a glitch
        # against the finite difference over >= 30 ms windows, at the samples' apply times
        errors, refs = [], []
        for k in range(len(t)):
            j = np.flatnonzero(t <= t[k] - 0.030)
            if trace.event[m[k]] != MOVE or t[k] - t[0] < 0.06 or not j.size:
                continue
            j = j[-1]
            ref = np.array([x[k] - x[j], y[k] - y[j]]) / (t[k] - t[j])
            i = min(int(apply_index(t[k:k + 1], cfg)[0]), n - 1)
            errors.append(np.hypot(block.vx[row, i] - ref[0], block.vy[row, i] - ref[1]))
            refs.append(np.hypot(*ref))
        assert len(errors) > 80
        assert np.median(errors) < 20.0 and max(errors) < 0.5 * max(refs)
    # the hard case is real: a difference quotient between raw samples exceeds 2000 mm/s
    assert naive_max > 2000.0


# -- getevent grammar -----------------------------------------------------------------------
GETEVENT = """add device 1: /dev/input/event2
  name:     "synaptics"
[    1.000000] EV_ABS       ABS_MT_POSITION_X    0000000a
[    1.000000] EV_ABS       ABS_MT_POSITION_Y    00000014
[    1.000000] EV_SYN       SYN_MT_REPORT        00000000
[    1.000000] EV_SYN       SYN_REPORT           00000000
"""


def test_getevent_labels_and_hex_forms_agree():
    named = parse_getevent(GETEVENT)
    hexed = parse_getevent("[ 1.000000] 0003 0035 0000000a\n[ 1.000000] 0003 0036 00000014\n"
                           "[ 1.000000] 0000 0002 00000000\n[ 1.000000] 0000 0000 00000000\n")
    assert [e[:4] for e in named] == [e[:4] for e in hexed]
    assert named[0] == (1.0, EV_ABS, ABS_MT_POSITION_X, 10, 3)


def test_getevent_values():
    ev = parse_getevent("[ 2.5] EV_ABS ABS_MT_TRACKING_ID ffffffff\n[ 2.5] EV_KEY BTN_TOUCH DOWN\n"
                        "[ 2.5] EV_ABS ABS_MISC 000000f7\n")
    assert [e[1:4] for e in ev] == [(EV_ABS, ABS_MT_TRACKING_ID, -1), (EV_KEY, 0x14A, 1), (EV_ABS, -1, 0xF7)]


def test_getevent_devices():
    two = ("[ 1.0] /dev/input/event2: EV_SYN SYN_REPORT 00000000\n"
           "[ 1.1] /dev/input/event5: EV_SYN SYN_REPORT 00000000\n")
    with pytest.raises(TraceError, match=r'2 devices \("/dev/input/event2", "/dev/input/event5"\); choose one'):
        parse_getevent(two, "log")
    assert [e.t_s for e in parse_getevent(two, "log", "/dev/input/event5")] == [1.1]
    with pytest.raises(TraceError, match='no events of device "/dev/input/event9"'):
        parse_getevent(two, "log", "/dev/input/event9")


@pytest.mark.parametrize("text, message", [
    ("[ 1.0] EV_ABS ABS_MT_POSITION_X 0000000a\nhello there\n", r"^log:2: not a getevent -lt line \(expected '\[ seconds"),
    ("EV_ABS ABS_MT_POSITION_X 0000000a\n", r"^log:1: event without a timestamp: record with 'getevent -lt'"),
    ("[ 1.0] EV_BOGUS ABS_MT_POSITION_X 0000000a\n", r'^log:1: event type "EV_BOGUS" is not known'),
    ("[ 1.0] EV_ABS ABS_MT_POSITION_X 12345678910\n", r'^log:1: value "12345678910" is not 8 hex digits'),
])
def test_getevent_errors_name_file_and_line(text, message):
    with pytest.raises(TraceError, match=message):
        parse_getevent(text, "log")


# -- evemu ----------------------------------------------------------------------------------
EVEMU = """# EVEMU 1.3
# Input device name: "Test Touchscreen"
N: Test Touchscreen
I: 0018 04f3 2234 0111
P: 02 00 00 00 00 00 00 00
B: 03 00 00 00 00 00 00 00 00
A: 00 0 3072 0 0 12
A: 01 0 2048 0 0 12
A: 2f 0 9 0 0 0
A: 35 0 3072 0 0 12
A: 36 0 2048 0 0 12
A: 39 0 65535 0 0 0
################################
#      Waiting for events      #
################################
E: 0.000001 0003 0039 0006\t# EV_ABS / ABS_MT_TRACKING_ID   6
E: 0.000001 0003 0035 1536\t# EV_ABS / ABS_MT_POSITION_X    1536
E: 0.000001 0003 0036 1024\t# EV_ABS / ABS_MT_POSITION_Y    1024
E: 0.000001 0001 014a 0001\t# EV_KEY / BTN_TOUCH            1
E: 0.000001 0000 0000 0000\t# ------------ SYN_REPORT (0) ---------- +0ms
E: 0.007450 0003 0035 1548\t# EV_ABS / ABS_MT_POSITION_X    1548
E: 0.007450 0000 0000 0000\t# ------------ SYN_REPORT (0) ---------- +7ms
E: 0.015000 0003 0039 -001\t# EV_ABS / ABS_MT_TRACKING_ID   -1
E: 0.015000 0001 014a 0000\t# EV_KEY / BTN_TOUCH            0
E: 0.015000 0000 0000 0000\t# ------------ SYN_REPORT (0) ---------- +8ms
"""


def test_evemu_header_and_events():
    rec = parse_evemu(EVEMU, "rec.evemu")
    assert rec.name == "Test Touchscreen"
    assert rec.absinfo[ABS_MT_POSITION_X] == AbsInfo(0, 3072, 12)
    assert rec.events[7] == (0.015, EV_ABS, ABS_MT_TRACKING_ID, -1, 23)
    samples, dec = decode_all(rec.events, "rec.evemu")
    assert dec.protocol == "B"
    assert [(s.x, s.y, s.event) for s in samples] == [(1536, 1024, DOWN), (1548, 1024, MOVE),
                                                      (1548, 1024, UP)]


def test_evemu_import_uses_the_header_ranges_and_resolution(tmp_path):
    src = tmp_path / "rec.evemu"
    src.write_text(EVEMU)
    out = tmp_path / "out.csv"
    assert _import([str(src), "-o", str(out)]) == 0
    trace = read_trace(out)
    # 3072 counts at 12 units/mm = 256 mm wide; 2048 / 12 = 170.67 mm high; centre touch
    assert_allclose(trace.x_mm, [128.0, 1548 / 12, 1548 / 12], rtol=1e-12)
    assert_allclose(trace.y_mm, [2048 / 24] * 3, rtol=1e-12)
    assert_allclose(trace.t_s, [0.0, 0.007449, 0.014999], atol=1e-12)


@pytest.mark.parametrize("line, message", [
    ("E: 0.1 0003 zz 5", r"rec:2: an 'E:' line that is not an evemu event"),
    ("A: 35 0 100", r"rec:2: an 'A:' line that is not an evemu axis"),
    ("Q: what", r"rec:2: not an evemu line \(expected"),
])
def test_evemu_errors_name_file_and_line(line, message):
    with pytest.raises(TraceError, match=message):
        parse_evemu("N: x\n" + line + "\n", "rec")


def test_an_evemu_recording_cut_mid_line_imports_what_came_before(tmp_path, capsys):
    """evemu-record stopped with Ctrl-C can end mid-line, as a getevent log can: the cut
    line is left out with a warning (it was refused: 'an 'E:' line that is not an evemu
    event'), and a malformed line that ends in a line break is still refused."""
    cut = EVEMU[:EVEMU.rindex("E: 0.015000 0000")] + "E: 0.015000 00"
    rec = parse_evemu(cut, "rec.evemu")
    assert len(rec.events) == 9
    assert rec.warnings == ["rec.evemu:25: the last line is cut short (no line break; the "
                            "recording stopped mid-line): left out"]
    src = tmp_path / "cut.evemu"
    src.write_text(cut)
    assert _import([str(src), "-o", str(tmp_path / "out.csv")]) == 0
    assert "cut.evemu:25: the last line is cut short" in capsys.readouterr().err
    with pytest.raises(TraceError, match=r"rec:25: an 'E:' line that is not an evemu event"):
        parse_evemu(cut + "\n", "rec")
    # saved whole but without its last line break: its last event (the comment after the
    # value shows it whole) is kept, with no warning
    whole = parse_evemu(EVEMU.rstrip("\n"), "rec")
    assert whole.events == parse_evemu(EVEMU, "rec").events and whole.warnings == []
    # cut within its value, the line still reads as an event (1548 as 15): left out too
    within = EVEMU[:EVEMU.index("E: 0.007450 0003 0035 1548")] + "E: 0.007450 0003 0035 15"
    assert len(parse_evemu(within, "rec").events) == 5
    assert parse_evemu(within, "rec").warnings[0].endswith("left out")


# -- the command ----------------------------------------------------------------------------
@needs_refdata
def test_import_writes_mm_and_keeps_pressure(tmp_path, capsys):
    out = tmp_path / "tap.csv"
    assert _import([str(REFDATA / "Phone/phone-single-touch.txt"), "-o", str(out)] + PHONE) == 0
    assert "wrote 2 samples" in capsys.readouterr().out
    trace = read_trace(out)
    # x 0x213 = 531 of 0..1023 on 52 mm; y 0x2f9 = 761 of 0..1023 on 87 mm
    assert_allclose([trace.x_mm[0], trace.y_mm[0]], [531 / 1023 * 52, 761 / 1023 * 87], rtol=1e-12)
    assert trace.t_s[0] == 0.0 and trace.force_n.tolist() == [0.5, 0.5]
    lines = out.read_text().splitlines()
    assert lines[1] == "t_s,finger,x_mm,y_mm,force_n,event,pressure,touch_major"
    assert lines[2].endswith(",down,37,4")  # 0x25 pressure, 4 touch-major


@needs_refdata
def test_import_pressure_scale_and_keep_time(tmp_path):
    out = tmp_path / "tap.csv"
    _import([str(REFDATA / "Phone/phone-single-touch.txt"), "-o", str(out), "--pressure-scale", "0.01",
             "--keep-time"] + PHONE)
    trace = read_trace(out)
    assert_allclose(trace.force_n, [0.37, 0.37], rtol=1e-12)
    assert trace.t_s.tolist() == [1193.605736, 1193.676258]  # the SYN_REPORT times


@needs_refdata
def test_import_without_ranges_warns_and_stretches(tmp_path, capsys):
    out = tmp_path / "drag.csv"
    _import([str(REFDATA / "Tablet/tablet-single-drag.txt"), "-o", str(out), "--width-mm", "217",
             "--height-mm", "136"])
    err = capsys.readouterr().err
    assert "warning: device x range unknown: using the observed" in err
    trace = read_trace(out)
    assert trace.x_mm.min() == 0.0 and trace.x_mm.max() == 217.0


def test_import_csv_round_trip(tmp_path):
    src = tmp_path / "in.csv"
    src.write_text("t_s,finger,x_mm,y_mm\n0,0,1,2\n0.02,0,2,2\n")
    out = tmp_path / "out.csv"
    assert _import([str(src), "-o", str(out)]) == 0
    assert read_trace(out).x_mm.tolist() == [1.0, 2.0]
    with pytest.raises(TraceError, match="--width-mm does not apply to a trace CSV"):
        _import([str(src), "-o", str(out), "--width-mm", "5"])


ONE_TOUCH = ("[ 1.0] EV_ABS ABS_MT_POSITION_X 0000000a\n[ 1.0] EV_ABS ABS_MT_POSITION_Y 0000000a\n"
             "[ 1.0] EV_SYN SYN_MT_REPORT 00000000\n[ 1.0] EV_SYN SYN_REPORT 00000000\n")


@needs_refdata
def test_import_warns_of_samples_off_screen_and_unfinished_frames(tmp_path, capsys):
    src = tmp_path / "cut.txt"
    src.write_text((REFDATA / "Phone/phone-single-drag.txt").read_text() + "[ 1500.0] EV_ABS ABS_MT_POSITION_X 00000001\n")
    _import([str(src), "-o", str(tmp_path / "o.csv"), "--x-range", "0", "600", "--y-range", "0", "1023",
             "--width-mm", "52", "--height-mm", "87"])
    err = capsys.readouterr().err
    assert "samples fall outside the 52 x 87 mm screen (check the ranges)" in err
    assert "1 events after the last SYN_REPORT (an unfinished frame) were left out" in err


@pytest.mark.parametrize("content, argv, message", [
    ("hello\n", [], "format not recognised"),
    ("[ 1.0] EV_SYN SYN_REPORT 00000000\n", [], "no touches found"),
    ("[ 1.0] EV_ABS ABS_MT_POSITION_X 0000000a\n[ 1.5] EV_SYN SYN_REPORT 00000000\nbad\n", [],
     r"rec.txt:3: not a getevent -lt line"),
    ("[ 1.0] EV_ABS ABS_MT_POSITION_X 0000000a\n[ 1.0] EV_ABS ABS_MT_POSITION_Y 0000000a\n"
     "[ 1.0] EV_SYN SYN_MT_REPORT 00000000\n[ 1.0] EV_SYN SYN_REPORT 00000000\n", [],
     r"device x range unknown \(the recording only shows x = 10\)"),
    (ONE_TOUCH, ["--x-range", "10", "5"], r"--x-range 10 5: expected MIN < MAX"),
    (ONE_TOUCH, ["--x-range", "0", "20", "--y-range", "0", "20", "--width-mm", "1", "--device", "/dev/x"],
     r'no events of device "/dev/x"'),
    (ONE_TOUCH, ["--format", "evemu", "--device", "/dev/x"], "--device applies to getevent logs"),
])
def test_import_errors(tmp_path, content, argv, message):
    src = tmp_path / "rec.txt"
    src.write_text(content)
    with pytest.raises(TraceError, match=message):
        _import([str(src), "-o", str(tmp_path / "o.csv")] + argv)


def test_cli_errors_are_one_line_exit_2(tmp_path, capsys):
    bad = tmp_path / "bad.txt"
    bad.write_text("[ 1.0] EV_ABS ABS_MT_POSITION_X 0000000a\n[ 0.5] EV_SYN SYN_REPORT 00000000\n")
    for argv in (["trace", "import", str(bad), "-o", str(tmp_path / "o.csv")],
                 ["trace", "import", str(tmp_path / "missing.txt"), "-o", str(tmp_path / "o.csv")],
                 ["trace", "import", str(bad), "-o", str(tmp_path / "o.csv"), "--format", "evemu"]):
        assert main(argv) == 2
        err = capsys.readouterr().err
        assert err.startswith("frictex: error: ") and err.count("\n") == 1, err
    bad.write_bytes(b"\xff\xfe\x00")
    assert main(["trace", "import", str(bad), "-o", str(tmp_path / "o.csv")]) == 2
    assert capsys.readouterr().err == (f"frictex: error: {bad}: is UTF-16 text (it starts with a "
                                       f"UTF-16 byte order mark); save it as UTF-8; expected a "
                                       f"text recording\n")
    bad.write_bytes(b"[ 1.0] EV_SYN SYN_REPORT 00000000\n[ 2.0] EV_\xff\n")
    assert main(["trace", "import", str(bad), "-o", str(tmp_path / "o.csv")]) == 2
    assert capsys.readouterr().err == (f"frictex: error: {bad}:2: not UTF-8 text (byte 0xff at "
                                       f"offset 44); expected a text recording\n")
    with pytest.raises(SystemExit) as exc:
        main(["trace", "import", str(bad), "-o", "x.csv", "--width-mm", "-3"])
    assert exc.value.code == 2 and "'-3' must be > 0" in capsys.readouterr().err


def test_csv_import_sorts_time_that_steps_back_and_says_so(tmp_path, capsys):
    src = tmp_path / "in.csv"
    src.write_text("t_s,finger,x_mm,y_mm\n0,0,0,0\n0.010,0,1,0\n0.008,1,5,5\n0.5,0,2,0\n0.3,0,9,9\n")
    out = tmp_path / "out.csv"
    assert main(["trace", "import", str(src), "-o", str(out)]) == 0
    err = capsys.readouterr().err.splitlines()
    assert err == ["frictex: warning: 1 touch samples were up to 5 ms earlier than the sample "
                   "before them and were sorted into time order",
                   "frictex: warning: 1 touch samples went back in time by more than 5 ms and "
                   "were dropped (the first at line 6; --strict refuses such a trace)"]
    written = read_trace(out)
    assert written.t_s.tolist() == [0.0, 0.008, 0.010, 0.5]
    assert written.finger.tolist() == [0, 1, 0, 0]


# -- any log text: events, or one escaped line ------------------------------------------------

UNSAFE = {"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"}
_GETEVENT_BITS = ["[", "]", " ", "   1.000000", "0.5", "/dev/input/event2:", "EV_ABS", "EV_SYN",
                  "ABS_MT_POSITION_X", "ABS_MT_SLOT", "ABS_MT_TRACKING_ID", "SYN_REPORT",
                  "SYN_MT_REPORT", "0000000a", "ffffffff", "DOWN", "0003", "\n", "\u0661", "_",
                  "\x1b", "add device 1: /dev/input/event2", "99999999999.0"]
_EVEMU_BITS = ["E: ", "A: ", "N: ", "# ", "0.000000 ", "0003 ", "0000 ", "0035 ", "0036 ",
               "0039 ", "002f ", "-1", "100", "2147483647", "9999999999", " 0 1023 0 0 ", "20",
               "\n", "\u0662", "\x1b", "Q: "]


def _one_line_or_events(parse, text):
    """``parse(text)`` and the decoder on its events: events, or one TraceError naming
    the source, without a control character."""
    try:
        events = parse(text)
        decode_all(events if isinstance(events, list) else events.events, "<log>")
    except TraceError as exc:
        message = str(exc)
        assert message.startswith("<log>") and not any(
            unicodedata.category(ch) in UNSAFE for ch in message), ascii(message)


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.one_of(st.lists(st.sampled_from(_GETEVENT_BITS), max_size=40).map("".join),
                 st.text(max_size=200)))
def test_any_getevent_text_is_events_or_one_escaped_line(text):
    _one_line_or_events(lambda t: parse_getevent(t, "<log>"), text)


@settings(max_examples=300, derandomize=True, deadline=None)
@given(st.one_of(st.lists(st.sampled_from(_EVEMU_BITS), max_size=40).map("".join),
                 st.text(max_size=200)))
def test_any_evemu_text_is_events_or_one_escaped_line(text):
    _one_line_or_events(lambda t: parse_evemu(t, "<log>"), text)


@settings(max_examples=200, derandomize=True, deadline=None)
@given(resolution=st.integers(-2**31, 2**31 - 1), lo=st.integers(-2**31, 2**31 - 1),
       span=st.integers(1, 2**32))
def test_an_evemu_screen_is_of_plausible_size_or_refused(resolution, lo, span):
    """Whatever the A: line says: a screen of 1 to 10,000 mm, or one line naming the file."""
    hi = min(lo + span, 2**31 - 1)
    assume(hi > lo)
    text = (f"A: 35 {lo} {hi} 0 0 {resolution}\nA: 36 {lo} {hi} 0 0 {resolution}\n"
            f"E: 0.0 0003 0039 1\nE: 0.0 0003 0035 {lo}\nE: 0.0 0003 0036 {hi}\nE: 0.0 0000 0000 0\n")
    recording = parse_evemu_or_none(text)
    if recording is None:
        assert not 0 <= resolution <= MAX_RESOLUTION
        return
    try:
        screen, _ = screen_map(ScreenSpec(), recording.absinfo, where="<log>")
    except TraceError as exc:
        assert str(exc).startswith("<log>: ")
        size = (hi - lo) / resolution if resolution else None
        assert size is None or not SCREEN_MM[0] <= size <= SCREEN_MM[1]
    else:
        for axis in (screen.x, screen.y):
            assert SCREEN_MM[0] <= axis.size_mm <= SCREEN_MM[1]


def parse_evemu_or_none(text):
    try:
        return parse_evemu(text, "<log>")
    except TraceError as exc:
        assert "resolution" in str(exc)
        return None


def _dense_evemu(size: int) -> str:
    """An evemu log of about ``size`` bytes in its densest form: one finger moving, an
    X event and a SYN_REPORT per sample (about 25 bytes an event)."""
    head = ("# EVEMU 1.3\nN: T\nI: 0018 04f3 0001 0100\nA: 35 0 4095 0 0 40\nA: 36 0 2047 0 0 40\n"
            "E: 0.000001 0003 0039 5\nE: 0.000001 0003 0035 1000\nE: 0.000001 0003 0036 1000\n"
            "E: 0.000001 0000 0000 0\n")
    lines, n = [head], len(head)
    k = 0
    while n < size:
        k += 1
        t = 0.01 + k * 1e-6
        pair = f"E: {t:.6f} 0003 0035 {1000 + k % 2000}\nE: {t:.6f} 0000 0000 0\n"
        lines.append(pair)
        n += len(pair)
    return "".join(lines)


def test_the_recording_cap_keeps_the_largest_import_under_1_gib(tmp_path):
    """Memory scales with the bytes of a recording: the peak of importing 1 MiB of the
    densest evemu, scaled to MAX_RECORDING_BYTES, plus the interpreter's 100 MiB, stays
    under 1 GiB (the 64 MiB cap it replaces took 1.35 GB and 17 s of CPU)."""
    import tracemalloc
    src = tmp_path / "dense.evemu"
    src.write_text(_dense_evemu(1 << 20))
    size = src.stat().st_size
    tracemalloc.start()
    try:
        assert _import([str(src), "-o", str(tmp_path / "out.csv")]) == 0
        peak = tracemalloc.get_traced_memory()[1]
    finally:
        tracemalloc.stop()
    assert peak * MAX_RECORDING_BYTES / size + (100 << 20) < 1 << 30


def test_a_recording_over_the_cap_is_refused_unread(tmp_path):
    src = tmp_path / "big.evemu"
    with open(src, "wb") as f:
        f.truncate(MAX_RECORDING_BYTES + 1)
    with pytest.raises(TraceError, match="big.evemu"):
        _import([str(src), "-o", str(tmp_path / "out.csv")])


@needs_refdata
def test_an_unknown_range_keeps_a_strokes_shape():
    """phone-single-drag's x crosses 392 units of the digitizer while its y wobbles over
    11: at one scale for both axes that wobble is 4.4 mm of a 160 x 100 mm screen, where
    stretched to the screen's height it was all 100 mm (9.1 mm a unit: its last report,
    3 units down, moved the finger 27 mm in 16 ms)."""
    samples, _ = decode_all(read_getevent(REFDATA / "Phone" / "phone-single-drag.txt"), "drag")
    x_units = max(s.x for s in samples) - min(s.x for s in samples)
    y_units = max(s.y for s in samples) - min(s.y for s in samples)
    assert (x_units, y_units) == (392, 11)
    screen, warnings = screen_map(ScreenSpec(width_mm=160, height_mm=100), {},
                                  observed_ranges(samples), "drag")
    assert len(warnings) == 2 and "one scale for both axes" in warnings[1]
    trace = screen.trace(samples, "drag")
    assert np.ptp(trace.x_mm) == pytest.approx(160.0)
    assert np.ptp(trace.y_mm) == pytest.approx(11 * 160.0 / 392)


@needs_refdata
@pytest.mark.parametrize("name, still", [("Phone/galaxy-paint-new.txt", "finger 0 still down"),
                                         ("Phone/phone-two-finger-drag.txt", None)])
def test_a_log_cut_mid_touch_says_which_fingers_are_still_down(tmp_path, capsys, name, still):
    """galaxy-paint-new ends mid-stroke (tracking id 143 never lifted): its last row was a
    move and nothing said so; a log whose fingers all lift says nothing."""
    out = tmp_path / "t.csv"
    assert _import([str(REFDATA / name), "-o", str(out)] + PHONE) == 0
    said = [line for line in capsys.readouterr().err.splitlines() if "still down" in line]
    if still is None:
        assert said == []
    else:
        assert said == [f"frictex: warning: {still} at the end of the recording (cut "
                        "mid-touch?): no lift follows its last sample"]
        assert read_trace(out).event[-1] != UP
