"""trace import / synth: output checks, the -p header, cut logs, scales, help defaults."""

import shutil
from pathlib import Path

import pytest

from frictex.app.commands.cli import main

REFDATA = Path(__file__).resolve().parents[2] / "shared" / "refdata" / "android-getevent"
needs_refdata = pytest.mark.skipif(not REFDATA.is_dir(),
                                   reason=f"refdata Android getevent logs not found at {REFDATA}")
PHONE = ["--x-range", "0", "1023", "--y-range", "0", "1023", "--width-mm", "52", "--height-mm", "87"]
DRAG = REFDATA / "Phone" / "phone-single-drag.txt"


def _error(argv, capsys) -> str:
    """The one-line error of a refused command (exit 2)."""
    assert main(argv) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err
    return err


@needs_refdata
def test_import_refuses_to_overwrite_its_input(tmp_path, capsys):
    log = tmp_path / "self.txt"
    shutil.copy(DRAG, log)
    err = _error(["trace", "import", str(log), "-o", str(log), *PHONE], capsys)
    assert "the same file as the input" in err
    assert log.read_bytes() == DRAG.read_bytes()


@needs_refdata
@pytest.mark.parametrize("out, said", [("/nonexist/x.csv",
                                        "-o /nonexist/x.csv: the folder /nonexist does not exist"),
                                       ("/dev/full", "-o /dev/full: cannot be written")])
def test_import_names_an_output_it_cannot_write(out, said, capsys):
    assert said in _error(["trace", "import", str(DRAG), "-o", out, *PHONE], capsys)


@needs_refdata
def test_a_log_cut_mid_line_imports_what_came_before(tmp_path, capsys):
    data = DRAG.read_bytes()
    cut = tmp_path / "cut.txt"
    cut.write_bytes(data[:len(data) // 2 + 10])  # cut 10 bytes into a 60-odd-byte line
    assert data[len(data) // 2 + 10 - 1] != ord("\n")
    assert main(["trace", "import", str(cut), "-o", str(tmp_path / "o.csv"), *PHONE]) == 0
    assert "the last line is cut short" in capsys.readouterr().err


@needs_refdata
@pytest.mark.parametrize("tail", ["/dev/input/event2: EV_ABS       ABS_MT_POSI",
                                  "EV_ABS       ABS_MT_POSITION_X    0000027"])
def test_a_log_cut_within_its_last_token_imports_what_came_before(tmp_path, capsys, tail):
    """A last line cut within its code or value has the line grammar's shape: it was
    refused ('event type "/dev/input/event2:" is not known') or read as another value
    (0x27 for 0x273), where a cut earlier in the line was left out."""
    lines = DRAG.read_text().splitlines(keepends=True)
    whole = tmp_path / "whole.txt"
    whole.write_text("".join(lines))
    assert main(["trace", "import", str(whole), "-o", str(tmp_path / "whole.csv"), *PHONE]) == 0
    stamp = lines[-1].split("]")[0] + "]"
    cut = tmp_path / "cut.txt"
    cut.write_text("".join(lines) + f"{stamp} {tail}")
    assert main(["trace", "import", str(cut), "-o", str(tmp_path / "o.csv"), *PHONE]) == 0
    assert "the last line is cut short" in capsys.readouterr().err
    body = [(tmp_path / name).read_text().split("\n", 1)[1] for name in ("o.csv", "whole.csv")]
    assert body[0] == body[1]  # after the first line, which names the file imported


@needs_refdata
def test_a_log_saved_without_its_last_line_break_keeps_its_last_event(tmp_path, capsys):
    """A whole log whose last line lacks only its line break (an editor, a copy): its last
    event has its whole value (8 hex digits) and is kept, with no warning."""
    whole, bare = tmp_path / "whole.txt", tmp_path / "bare.txt"
    whole.write_bytes(DRAG.read_bytes())
    bare.write_bytes(DRAG.read_bytes().rstrip(b"\r\n"))
    for path in (whole, bare):
        assert main(["trace", "import", str(path), "-o", str(path.with_suffix(".csv")),
                     *PHONE]) == 0
    assert "cut short" not in capsys.readouterr().err
    body = [(tmp_path / name).read_text().split("\n", 1)[1] for name in ("bare.csv", "whole.csv")]
    assert body[0] == body[1]  # after the first line, which names the file imported


def test_a_malformed_line_that_ends_in_a_line_break_is_still_refused(tmp_path, capsys):
    log = tmp_path / "bad.txt"
    log.write_text("[    1.000000] EV_SYN       SYN_REPORT           00000000\n[    1.0\n")
    assert "bad.txt:2: not a getevent -lt line" in _error(
        ["trace", "import", str(log), "-o", str(tmp_path / "o.csv"), *PHONE], capsys)


def _section(x_max: int, resolution: int = 0) -> str:
    """The start of a 'getevent -lpt' log: the -p section of one touch screen."""
    axis = ", fuzz 0, flat 0, resolution {r}".format(r=resolution)
    return ("add device 1: /dev/input/event2\n"
            '  name:     "sec_touchscreen"\n'
            "  events:\n"
            f"    ABS (0003): ABS_MT_TOUCH_MAJOR    : value 0, min 0, max 255{axis}\n"
            f"                ABS_MT_POSITION_X     : value 0, min 0, max {x_max}{axis}\n"
            f"                ABS_MT_POSITION_Y     : value 0, min 0, max 2047{axis}\n"
            "  input props:\n"
            "    <none>\n")


def _drag_lines() -> str:
    """Two frames of one contact (protocol A) at x 100, 300 and y 1024."""
    frames = []
    for t, x in (("1.000000", 0x64), ("1.010000", 0x12c)):
        frames += [f"[    {t}] EV_ABS       ABS_MT_POSITION_X    {x:08x}",
                   f"[    {t}] EV_ABS       ABS_MT_POSITION_Y    00000400",
                   f"[    {t}] EV_ABS       ABS_MT_TRACKING_ID   00000000",
                   f"[    {t}] EV_SYN       SYN_MT_REPORT        00000000",
                   f"[    {t}] EV_SYN       SYN_REPORT           00000000"]
    return "\n".join(frames) + "\n"


def _import_columns(tmp_path, text, *options):
    """x_mm and y_mm of the trace imported from the log ``text``."""
    from frictex.rendering.input.trace_file import read_trace
    log = tmp_path / "log.txt"
    log.write_text(text)
    out = tmp_path / "o.csv"
    assert main(["trace", "import", str(log), "-o", str(out), *options]) == 0
    trace = read_trace(out)
    return trace.x_mm, trace.y_mm


def test_the_p_section_gives_the_ranges(tmp_path, capsys):
    x, y = _import_columns(tmp_path, _section(4095) + _drag_lines(), "--width-mm", "100",
                           "--height-mm", "50")
    assert x.tolist() == pytest.approx([100 / 4095 * 100, 300 / 4095 * 100])
    assert y.tolist() == pytest.approx([1024 / 2047 * 50] * 2)
    assert "range unknown" not in capsys.readouterr().err


def test_the_p_section_resolution_gives_the_size_and_an_option_wins(tmp_path):
    x, y = _import_columns(tmp_path, _section(4000, resolution=40) + _drag_lines(),
                           "--x-range", "0", "1000", "--width-mm", "100")
    assert x.tolist() == pytest.approx([100 / 1000 * 100, 300 / 1000 * 100])  # the options'
    assert y.tolist() == pytest.approx([1024 / 2047 * 2047 / 40] * 2)


@needs_refdata
def test_an_observed_range_warns_that_positions_and_speeds_are_wrong(tmp_path, capsys):
    tablet = REFDATA / "Tablet" / "tablet-single-drag.txt"
    assert main(["trace", "import", str(tablet), "-o", str(tmp_path / "o.csv"),
                 "--width-mm", "217", "--height-mm", "136"]) == 0
    err = capsys.readouterr().err
    assert "positions and speeds are wrong unless the gesture covered the whole screen" in err
    assert "'getevent -lpt' (its -p section gives the ranges)" in err


@pytest.mark.parametrize("options, said", [
    ([], "device x counts 100..2.14748e+09 (the observed range) over 100 mm are 2.15e+07 units/mm"),
    (["--x-range", "0", "1e12"], "device x counts 0..1e+12 (--x-range) over 100 mm are 1e+10 units/mm"),
])
def test_a_scale_no_digitizer_has_is_refused(tmp_path, capsys, options, said):
    text = _drag_lines().replace("0000012c", "7fffffff")
    log = tmp_path / "glitch.txt"
    log.write_text(text)
    err = _error(["trace", "import", str(log), "-o", str(tmp_path / "o.csv"), "--width-mm", "100",
                  "--height-mm", "50", "--y-range", "0", "2047", *options], capsys)
    assert said in err


@pytest.mark.parametrize("force", ["1", "0"])
def test_force_is_refused_for_a_trace_csv(tmp_path, capsys, force):
    csv = tmp_path / "nf.csv"
    csv.write_text("t_s,finger,x_mm,y_mm,event\n0,0,1,1,down\n0.02,0,2,1,up\n")
    err = _error(["trace", "import", str(csv), "-o", str(tmp_path / "o.csv"), "--force", force],
                 capsys)
    assert "--force does not apply to a trace CSV" in err


def test_a_sample_without_pressure_names_its_time_plainly():
    from frictex.rendering.input.evdev_decode import AxisMap, RawSample, ScreenMap
    from frictex.rendering.input.trace_file import TraceError
    screen = ScreenMap(AxisMap(0, 100, 50), AxisMap(0, 100, 50), pressure_n=0.01)
    sample = RawSample(0.25, 0, 10.0, 10.0, float("nan"), float("nan"), 1)
    with pytest.raises(TraceError, match=r"sample 0 at 0\.25 s has no pressure"):
        screen.arrays([sample])


def test_a_pressure_scale_that_overflows_is_the_force_s_one_line_and_no_numpy_warning():
    import warnings
    from frictex.rendering.input.evdev_decode import AxisMap, RawSample, ScreenMap
    from frictex.rendering.input.trace_file import TraceError
    screen = ScreenMap(AxisMap(0, 100, 50), AxisMap(0, 100, 50), pressure_n=1e308)
    with warnings.catch_warnings():
        warnings.simplefilter("error")  # numpy's overflow warning printed a source line
        with pytest.raises(TraceError, match=r"sample 0: force_n is inf, expected a number "
                                             r"from 0 to 1000 N"):
            screen.trace([RawSample(0.25, 0, 10.0, 10.0, 40.0, 40.0, 1)])


def test_a_getevent_ltr_log_reads_as_without_its_rates():
    from frictex.rendering.input.import_getevent import parse_getevent
    plain = _drag_lines()
    rated = plain.replace("SYN_REPORT           00000000", "SYN_REPORT           00000000    rate 67")
    assert "rate 67" in rated
    assert parse_getevent(rated) == parse_getevent(plain)


def _syn_dropped_log(tmp_path, keep=None):
    """A getevent -lpt log of two fingers (slot 1 id 0x65, slot 0 id 0x66), a
    SYN_DROPPED, slot 1 moved and lifted, then slot 0 lifted; its first ``keep`` events."""
    axis = ", fuzz 0, flat 0, resolution 10"
    header = ("add device 1: /dev/input/event2\n  name:     \"sec_touchscreen\"\n  events:\n"
              f"    ABS (0003): ABS_MT_SLOT           : value 0, min 0, max 9{axis}\n"
              f"                ABS_MT_POSITION_X     : value 0, min 0, max 1023{axis}\n"
              f"                ABS_MT_POSITION_Y     : value 0, min 0, max 1023{axis}\n"
              f"                ABS_MT_TRACKING_ID    : value 0, min 0, max 65535{axis}\n"
              "  input props:\n    <none>\n")
    events = [("100.000000", "EV_ABS", "ABS_MT_SLOT", 1), ("100.000000", "EV_ABS", "ABS_MT_TRACKING_ID", 0x65),
              ("100.000000", "EV_ABS", "ABS_MT_POSITION_X", 0x200), ("100.000000", "EV_ABS", "ABS_MT_POSITION_Y", 0x200),
              ("100.000000", "EV_ABS", "ABS_MT_SLOT", 0), ("100.000000", "EV_ABS", "ABS_MT_TRACKING_ID", 0x66),
              ("100.000000", "EV_ABS", "ABS_MT_POSITION_X", 0x100), ("100.000000", "EV_ABS", "ABS_MT_POSITION_Y", 0x100),
              ("100.000000", "EV_SYN", "SYN_REPORT", 0), ("100.050000", "EV_SYN", "SYN_DROPPED", 0),
              ("100.070000", "EV_ABS", "ABS_MT_SLOT", 1), ("100.070000", "EV_ABS", "ABS_MT_POSITION_Y", 0x300),
              ("100.070000", "EV_SYN", "SYN_REPORT", 0),
              ("100.080000", "EV_ABS", "ABS_MT_TRACKING_ID", 0xFFFFFFFF), ("100.080000", "EV_SYN", "SYN_REPORT", 0),
              ("100.090000", "EV_ABS", "ABS_MT_SLOT", 0), ("100.090000", "EV_ABS", "ABS_MT_TRACKING_ID", 0xFFFFFFFF),
              ("100.090000", "EV_SYN", "SYN_REPORT", 0)]
    log = tmp_path / "b1.txt"
    log.write_text(header + "".join(f"[  {t}] {ty:<12} {code:<20} {v:08x}\n"
                                    for t, ty, code, v in events[:keep]))
    return log


def test_a_getevent_log_with_syn_dropped_lifts_each_finger_from_its_own_slot(tmp_path, capsys):
    from frictex.rendering.input.trace_file import UP, read_trace
    out = tmp_path / "b1.csv"
    assert main(["trace", "import", str(_syn_dropped_log(tmp_path)), "-o", str(out)]) == 0
    trace = read_trace(out)
    lifts = trace.event == UP
    assert trace.finger[lifts].tolist() == [1, 0]  # slot 1 first
    assert trace.t_s[lifts].tolist() == pytest.approx([0.08, 0.09])
    assert trace.y_mm[lifts].tolist() == pytest.approx([0x300 / 10, 0x100 / 10])
    err = capsys.readouterr().err
    assert "1 SYN_DROPPED" in err and "still down" not in err


def test_a_finger_left_down_after_a_syn_dropped_may_have_lost_its_lift(tmp_path, capsys):
    """Slot 0's lift cut off: the warning names the drop as a cause beside a cut log."""
    out = tmp_path / "b1.csv"
    assert main(["trace", "import", str(_syn_dropped_log(tmp_path, keep=-3)), "-o", str(out)]) == 0
    err = capsys.readouterr().err
    assert ("finger 0 still down at the end of the recording (cut mid-touch? or a lift lost "
            "to SYN_DROPPED?)") in err


def test_positions_with_no_tracking_id_beside_touches_are_said_left_out(tmp_path, capsys):
    """A protocol B slot that got X and Y but never a tracking id is no contact: left out,
    and said (it was left out without a word)."""
    rec = tmp_path / "rec.evemu"
    rec.write_text("N: x\nA: 2f 0 9 0 0 0\nA: 35 0 1000 0 0 0\nA: 36 0 1000 0 0 0\n"
                   "A: 39 0 65535 0 0 0\n"
                   "E: 1.00 0003 002f 0\nE: 1.00 0003 0039 7\nE: 1.00 0003 0035 100\n"
                   "E: 1.00 0003 0036 100\nE: 1.00 0000 0000 0\n"
                   "E: 1.01 0003 002f 1\nE: 1.01 0003 0035 500\nE: 1.01 0003 0036 500\n"
                   "E: 1.01 0000 0000 0\n"
                   "E: 1.02 0003 002f 0\nE: 1.02 0003 0039 -1\nE: 1.02 0000 0000 0\n")
    assert main(["trace", "import", str(rec), "-o", str(tmp_path / "o.csv"), "--width-mm", "50",
                 "--height-mm", "50"]) == 0
    assert ("positions in 1 frame came with no ABS_MT_TRACKING_ID (protocol B contacts start "
            "with one) and were left out") in capsys.readouterr().err
