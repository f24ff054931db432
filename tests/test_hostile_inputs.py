"""Hostile traces, device logs and batch manifests through the ``frictex`` command.

Each is refused with exit 2 and one line on stderr that names the file, holds no control
character and no text of a file that is not what it claims to be (the marker SECRET), or
is accepted with sane outputs. A hang fails the test (``_bounded``: an alarm, never a
timing assertion). Covers issue 30's "numbers read as numbers that are not", special
files, sizes and names that become folders and table cells.
"""

from __future__ import annotations

import csv
import os
import signal
import unicodedata
from contextlib import contextmanager

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.rendering.input.trace_file import read_trace

SECRET = "root:$6$SECRETzz9$hash:19000:0:99999:7:::"
HEADER = "t_s,finger,x_mm,y_mm"
ESC = "\x1b]0;owned\x07\x1b[2J"


@contextmanager
def _bounded(seconds: int = 120):
    """Fail (instead of hanging) if the body is still running after ``seconds``."""
    def expire(signum, frame):
        raise TimeoutError(f"still running after {seconds} s: a hang")
    old = signal.signal(signal.SIGALRM, expire)
    signal.alarm(seconds)
    try:
        yield
    finally:
        signal.alarm(0)
        signal.signal(signal.SIGALRM, old)


def _run(argv: list[str]) -> int:
    """``frictex ARGV``'s exit status (a bad option exits from argparse)."""
    with _bounded():
        try:
            return main(argv)
        except SystemExit as exc:
            return exc.code


def _one_escaped_line(err: str, path) -> str:
    """The one error line of a refusal: names ``path``, shows no control character, no
    line of a file of another kind."""
    lines = _escaped_lines(err, path)
    assert len(lines) == 1, err
    return lines[0]


def _escaped_lines(err: str, path) -> list[str]:
    """The error lines of a refusal that lists each problem on a line of its own (a
    manifest's), each as :func:`_one_escaped_line` holds it."""
    lines = err.splitlines()
    assert lines and err.endswith("\n"), err
    for line in lines:
        assert line.startswith("frictex: error: ") and str(path) in line, line
        assert not any(unicodedata.category(ch) in ("Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp")
                       for ch in line), ascii(line)
        assert "SECRET" not in line, line
    return lines


def _make(tmp_path, name: str, content):
    """A file holding ``content`` (str as UTF-8, or bytes), or a special file: "fifo",
    "dir", "loop", "dangling", "sparse:N" (N MiB of zeros)."""
    path = tmp_path / name
    if content == "fifo":
        os.mkfifo(path)
    elif content == "dir":
        path.mkdir()
    elif content == "loop":
        os.symlink(path, path)
    elif content == "dangling":
        os.symlink(tmp_path / "nowhere", path)
    elif isinstance(content, str) and content.startswith("sparse:"):
        with open(path, "wb") as fh:
            fh.truncate(int(content.split(":")[1]) << 20)
    else:
        path.write_bytes(content if isinstance(content, bytes) else content.encode("utf-8"))
    return path


# -- traces -------------------------------------------------------------------------------

def _trace(*rows, header=HEADER):
    return header + "\n" + "".join(row + "\n" for row in rows)


BAD_TRACES = {
    "arabic-indic digits": (_trace("\u0662\u0661,0,1,1"), 'column t_s: "\u0662\u0661" is not a number'),
    "underscore": (_trace("0,0,2_2,1"), 'column x_mm: "2_2" is not a number'),
    "fullwidth digit": (_trace("0,0,1,\uff11"), "column y_mm"),
    "devanagari finger": (_trace("0,\u0967,1,1"), "column finger"),
    "thin space": (_trace("0,0,1\u2009,1"), "column x_mm"),
    "form feed": (_trace("0,0,1\x0c,1"), "column x_mm: \"1\\x0c\" is not a number"),
    "nan": (_trace("0,0,nan,1"), "is not a finite number"),
    "inf": (_trace("inf,0,0,1"), "is not a finite number"),
    "Infinity": (_trace("0,0,0,-Infinity"), "is not a finite number"),
    "hex": (_trace("0x10,0,0,1"), "column t_s"),
    "empty number": (_trace("0,0,,1"), 'column x_mm: "" is not a number'),
    "x twice": (_trace("0,0,1,1,2", header=HEADER + ",x_mm"), 'header names column "x_mm" twice'),
    "t_s twice": (_trace("0,0,0,1,1", header="t_s,t_s,finger,x_mm,y_mm"), '"t_s" twice'),
    "shadow line": (SECRET + "\n" + SECRET + "\n", "not a trace header"),
    "escape header": (_trace("0,0,1,1", header=f"t_s,finger,{ESC},y_mm"), "lacks column(s) x_mm"),
    "no y": (_trace("0,0,1", header="t_s,finger,x_mm"), "lacks column(s) y_mm"),
    "utf-16": ("\ufeff" + _trace("0,0,1,1")).encode("utf-16"),
    "latin-1": (_trace("0,0,1,1").replace("1,1", "\xe9,1").encode("latin-1"), "not UTF-8 text"),
    "nul": (_trace("0,0,1\x00,1"), "binary content"),
    "long line": (_trace("0,0,1," + "1" * 5000), "line longer than 4096 bytes"),
    "empty": ("", "empty trace"),
    "comments only": ("# a comment\n\n# another\n", "empty trace"),
    "header only": (_trace(), "header but no samples"),
    "short row": (_trace("0,0,1"), "3 fields, expected 4"),
    "short row under a secret column": (_trace("0,0,1", header=f"{HEADER},{SECRET}{ESC}"),
                                        "3 fields, expected 5 as the header has (5 fields: t_s"),
    "escape event": (_trace(f"0,0,1,1,{ESC}", header=HEADER + ",event"), "column event"),
    "half finger": (_trace("0,1.5,1,1"), "is not an integer"),
    "negative finger": (_trace("0,-1,1,1"), "is not an integer"),
    "negative force": (_trace("0,0,1,1,-1", header=HEADER + ",force_n"), "column force_n"),
    "far x": (_trace("0,0,1e6,1"), "is not a number from -100000 to 100000 mm"),
    "far time": (_trace("1e11,0,1,1"), "column t_s"),
    "21 fingers": (_trace(*(f"0,{k},1,1" for k in range(21))), "21 fingers touch at once"),
    "unbalanced quote": (_trace('0,0,"1,1'), "3 fields, expected 4"),
    "fifo": ("fifo", "is a FIFO (named pipe), not a regular file"),
    "folder": ("dir", "is a folder, not a file"),
    "link loop": ("loop", "symbolic link loop"),
    "dangling link": ("dangling", "symbolic link to a missing file"),
    "sparse zeros": ("sparse:8", "binary content"),  # under MAX_RECORDING_BYTES (10 MiB)
}
BAD_TRACES["utf-16"] = (BAD_TRACES["utf-16"], "UTF-16 text")


@pytest.mark.parametrize("case", sorted(BAD_TRACES))
def test_hostile_traces_are_one_escaped_line(tmp_path, capsys, case):
    content, message = BAD_TRACES[case]
    path = _make(tmp_path, "trace.csv", content)
    code = _run(["trace", "import", str(path), "-o", str(tmp_path / "out.csv"), "--format", "csv"])
    assert code == 2
    assert message in _one_escaped_line(capsys.readouterr().err, path)
    assert not (tmp_path / "out.csv").exists()


def test_a_header_of_escapes_is_shown_escaped_or_not_at_all(tmp_path, capsys):
    path = _make(tmp_path, "trace.csv", _trace("0,0,1,1", header=f"t_s,finger,x_mm,y\x1bmm"))
    assert main(["trace", "import", str(path), "-o", str(tmp_path / "o.csv"), "--format", "csv"]) == 2
    line = _one_escaped_line(capsys.readouterr().err, path)
    assert "4 fields: t_s, finger, x_mm and 1 that is not a column name" in line


ACCEPTED_TRACES = {
    "signs and points": (_trace("+0,0,.5,1.", "1e-2,+0,-0.5,2E+0", " 0.02 ,\t0\t,1 , 3 "),
                         [0.0, 0.01, 0.02], [0.5, -0.5, 1.0], [1.0, 2.0, 3.0]),
    "bom and crlf": ("\ufeff" + _trace("0,0,1,2", "0.01,0,3,4").replace("\n", "\r\n"),
                     [0.0, 0.01], [1.0, 3.0], [2.0, 4.0]),
    "quoted and extra columns": ('note,' + HEADER + '\n"caf\u00e9, \u0662",0,0,"1",2\n',
                                 [0.0], [1.0], [2.0]),
}


@pytest.mark.parametrize("case", sorted(ACCEPTED_TRACES))
def test_the_numbers_the_grammar_allows_are_read(tmp_path, case):
    content, t, x, y = ACCEPTED_TRACES[case]
    path = _make(tmp_path, "trace.csv", content)
    assert main(["trace", "import", str(path), "-o", str(tmp_path / "out.csv"), "--format", "csv"]) == 0
    for trace in (read_trace(path), read_trace(tmp_path / "out.csv")):
        assert trace.t_s.tolist() == t and trace.x_mm.tolist() == x and trace.y_mm.tolist() == y


# -- device logs --------------------------------------------------------------------------

def _getevent(*lines):
    return "".join(line + "\n" for line in lines)


GE_OK = ("[   1.000000] EV_ABS ABS_MT_TRACKING_ID 00000001",
         "[   1.000000] EV_ABS ABS_MT_POSITION_X 00000064",
         "[   1.000000] EV_ABS ABS_MT_POSITION_Y 00000064",
         "[   1.000000] EV_SYN SYN_REPORT 00000000")
GE_RANGE = ["--x-range", "0", "1023", "--y-range", "0", "1023", "--width-mm", "52",
            "--height-mm", "87"]


EVEMU_EVENTS = ("E: 0.000000 0003 0039 1", "E: 0.000000 0003 0035 100", "E: 0.000000 0003 0036 200",
                "E: 0.000000 0000 0000 0", "E: 0.010000 0003 0035 110", "E: 0.010000 0000 0000 0")


def _evemu(resolution="20", *events):
    head = ("# EVEMU 1.3", "N: hostile", f"A: 35 0 1023 0 0 {resolution}",
            f"A: 36 0 1023 0 0 {resolution}")
    return "".join(line + "\n" for line in (*head, *(events or EVEMU_EVENTS)))


BAD_LOGS = {
    "getevent arabic-indic time": (_getevent("[   \u0661.000000] EV_ABS ABS_MT_POSITION_X 00000064",
                                             *GE_OK), [], "not a getevent -lt line"),
    "getevent shadow line": (_getevent(*GE_OK, SECRET), [], "not a getevent -lt line"),
    "getevent value not hex": (_getevent("[ 1.000000] EV_ABS ABS_MT_POSITION_X 0000zz64"), [],
                               'value "0000zz64" is not 8 hex digits'),
    "getevent escape type": (_getevent(f"[ 1.000000] EV_{ESC[1:5]} ABS_MT_POSITION_X 00000064"),
                             [], "is not known"),
    "getevent escape device": (_getevent(f"[ 1.0] /dev/a{ESC[:3]}: EV_SYN SYN_REPORT 00000000",
                                         "[ 1.1] /dev/b: EV_SYN SYN_REPORT 00000000"), [],
                               "events of 2 devices"),
    "getevent far time": (_getevent("[ 99999999999.000000] EV_SYN SYN_REPORT 00000000"), [],
                          "is more than 1e+10 s"),
    "getevent untimed": (_getevent("EV_ABS ABS_MT_POSITION_X 00000064"), [], "without a timestamp"),
    "getevent nul": (_getevent(*GE_OK) + "\x00", [], "binary content"),
    "getevent latin-1": (_getevent(*GE_OK).encode("utf-8") + b"\xe9\n", [], "not UTF-8 text"),
    "getevent huge screen": (_getevent(*GE_OK), GE_RANGE[:6] + ["--width-mm", "1e9", "--height-mm", "87"],
                             "screen size 1e+09 mm: expected 1 to 10000 mm"),
    "getevent tiny screen": (_getevent(*GE_OK), GE_RANGE[:6] + ["--width-mm", "1e-9", "--height-mm", "87"],
                             "screen size 1e-09 mm: expected 1 to 10000 mm"),
    "getevent slot 999": (_getevent("[ 1.0] EV_ABS ABS_MT_SLOT 000003e7", *GE_OK), GE_RANGE,
                          "ABS_MT_SLOT 999 is out of range"),
    "getevent time back": (_getevent(*GE_OK, "[ 0.5] EV_ABS ABS_MT_POSITION_X 00000065",
                                     "[ 0.5] EV_SYN SYN_REPORT 00000000"), GE_RANGE, "time goes back"),
    "getevent fifo": ("fifo", [], "is a FIFO (named pipe), not a regular file"),
    "getevent oversize": ("sparse:11", [], "more than the 10,485,760 bytes"),
    "evemu resolution 2^31": (_evemu("2147483647"), [], "resolution 2147483647 units/mm"),
    "evemu resolution 2^31 - 1 wrapped": (_evemu("4294967295"), [], "outside a 32-bit signed value"),
    "evemu negative resolution": (_evemu("-5"), [], "resolution -5 units/mm"),
    "evemu sub-mm screen": (_evemu("5000"), [], "make a screen 0.205 mm across"),
    "evemu 60 m screen": (_evemu("0"), ["--width-mm", "60000", "--height-mm", "60"],
                          "screen size 60000 mm"),
    "evemu value past s32": (_evemu("20", "E: 0.000000 0003 0035 9999999999"), [],
                             "value 9999999999 is outside a 32-bit signed value"),
    "evemu arabic-indic axis": (_evemu("\u0662\u0660"), [], "not an evemu axis"),
    "evemu arabic-indic event": (_evemu("20", "E: 0.000000 0003 0035 \u0661\u0660\u0660"), [],
                                 "not an evemu event"),
    "evemu shadow line": (_evemu() + SECRET + "\n", [], "not an evemu line"),
    "evemu far time": (_evemu("20", "E: 99999999999.000000 0000 0000 0"), [], "is more than 1e+10 s"),
    "evemu no touches": (_evemu("20", "E: 0.000000 0000 0000 0"), [], "no touches found"),
    "evemu pressure without pressure": (_evemu(), ["--pressure-scale", "0.01"], "has no pressure"),
    "evemu escape option": (_evemu(), ["--width-mm", f"5{ESC}"], "is not a number"),
    "evemu arabic-indic option": (_evemu(), ["--width-mm", "\u0665\u0660"], "is not a number"),
}


@pytest.mark.parametrize("case", sorted(BAD_LOGS))
def test_hostile_device_logs_are_one_escaped_line(tmp_path, capsys, case):
    content, options, message = BAD_LOGS[case]
    path = _make(tmp_path, "rec.txt", content)
    fmt = "getevent" if case.startswith("getevent") else "evemu"
    code = _run(["trace", "import", str(path), "-o", str(tmp_path / "out.csv"), "--format", fmt,
                 *options])
    assert code == 2
    err = capsys.readouterr().err
    if "option" in case:  # a bad option is named, the file is not read
        assert err.count("\n") == 1 and message in err and "\x1b" not in err
    else:
        assert message in _one_escaped_line(err, path)
    assert not (tmp_path / "out.csv").exists()


def test_an_evemu_screen_of_plausible_size_is_read(tmp_path):
    path = _make(tmp_path, "rec.txt", _evemu("20"))
    assert main(["trace", "import", str(path), "-o", str(tmp_path / "out.csv")]) == 0
    trace = read_trace(tmp_path / "out.csv")
    # 1023 counts at 20 units/mm: a 51.15 mm screen; counts 100, 110 and 200
    np.testing.assert_allclose(trace.x_mm, [100 / 1023 * 51.15, 110 / 1023 * 51.15], rtol=1e-12)
    np.testing.assert_allclose(trace.y_mm, [200 / 1023 * 51.15] * 2, rtol=1e-12)


# -- batch manifests ----------------------------------------------------------------------

JOB = "grating-5mm,swipe-40mms-50hz"


def _manifest(*rows, header="scene,trace"):
    return header + "\n" + "".join(row + "\n" for row in rows)


BAD_MANIFESTS = {
    "fifo": ("fifo", "is a FIFO (named pipe), not a regular file"),
    "folder": ("dir", "is a folder, not a file"),
    "oversize": ("sparse:2", "more than the 1,048,576 bytes"),
    "rate 5e-324": (_manifest(JOB + ",5e-324", header="scene,trace,rate_hz"),
                    'rate_hz "5e-324": expected 100 to 1e+06 Hz'),
    "rate 1e7": (_manifest(JOB + ",1e7", header="scene,trace,rate_hz"), "expected 100 to 1e+06 Hz"),
    "rate inf": (_manifest(JOB + ",inf", header="scene,trace,rate_hz"), 'rate_hz "inf" is not'),
    "rate arabic-indic": (_manifest(JOB + ",\u0661\u0660\u0660\u0660\u0660", header="scene,trace,rate_hz"),
                          "is not an ASCII decimal number"),
    "rate underscore": (_manifest(JOB + ",10_000", header="scene,trace,rate_hz"),
                        'rate_hz "10_000" is not an ASCII decimal number'),
    "block 0": (_manifest(JOB + ",0", header="scene,trace,block"), "expected 1 to 100000 samples"),
    "block 100001": (_manifest(JOB + ",100001", header="scene,trace,block"), "expected 1 to 100000 samples"),
    "block fraction": (_manifest(JOB + ",1.5", header="scene,trace,block"), "is not a whole number"),
    "block underscore": (_manifest(JOB + ",5_0", header="scene,trace,block"), "is not a whole number"),
    "block devanagari": (_manifest(JOB + ",\u096b\u0966", header="scene,trace,block"), "is not a whole number"),
    "name newline and escape": (_manifest(JOB + ',"a\n\x1b[2Jb"', header="scene,trace,name"),
                                "not a CSV row"),
    "name escape": (_manifest(JOB + f",x{ESC}", header="scene,trace,name"), "expected a plain folder name"),
    "name parent": (_manifest(JOB + ",..", header="scene,trace,name"), "expected a plain folder name"),
    "name dot": (_manifest(JOB + ",.", header="scene,trace,name"), "expected a plain folder name"),
    "name hidden": (_manifest(JOB + ",.x", header="scene,trace,name"), "expected a plain folder name"),
    "name separator": (_manifest(JOB + ",a/b", header="scene,trace,name"), "expected a plain folder name"),
    "name backslash": (_manifest(JOB + ",a\\b", header="scene,trace,name"), "expected a plain folder name"),
    "name too long": (_manifest(JOB + "," + "n" * 65, header="scene,trace,name"), "at most 64"),
    "name accented": (_manifest(JOB + ",essai-\u00e9", header="scene,trace,name"), "expected a plain folder name"),
    "name bidi override": (_manifest(JOB + ",a\u202eb", header="scene,trace,name"), "\\u202e"),
    "header twice": (_manifest(JOB + "," + JOB, header="scene,trace,scene,trace"), "twice"),
    "shadow line": (SECRET + "\n" + SECRET + "\n", "not a manifest header"),
    "escape header": (_manifest(JOB, header=f"scene,{ESC}"), "not a manifest header"),
    "nul": (_manifest(JOB + "\x00"), "holds a NUL byte"),
    "utf-16": (_manifest(JOB).encode("utf-16"), "UTF-16"),
    "latin-1": (_manifest(JOB + ",caf\xe9", header="scene,trace,name").encode("latin-1"), "not UTF-8 text"),
    "long line": (_manifest(JOB + "," + "x" * 5000, header="scene,trace,name"), "longer than 4096 bytes"),
    "bare carriage return": (_manifest(JOB.replace(",", "\r,")), "a line ends in a bare CR"),
    "escape format": (_manifest(JOB + f",{ESC}", header="scene,trace,format"), "format"),
    "escape renderer": (_manifest(JOB + f",{ESC}", header="scene,trace,renderer"), "renderer"),
}


@pytest.mark.parametrize("case", sorted(BAD_MANIFESTS))
def test_hostile_manifests_are_one_escaped_line(tmp_path, capsys, case):
    """One escaped line per problem: the first names the fault (a quote left open also
    breaks the next line, said on a line of its own)."""
    content, message = BAD_MANIFESTS[case]
    path = _make(tmp_path, "m.csv", content)
    code = _run(["batch", str(path), "--out", str(tmp_path / "out"), "--quiet"])
    assert code == 2
    assert message in _escaped_lines(capsys.readouterr().err, path)[0]
    assert not (tmp_path / "out").exists()


def test_a_job_reading_a_file_of_another_kind_fails_without_showing_it(tmp_path, capsys):
    shadow = _make(tmp_path, "shadow", SECRET + "\n")
    manifest = _make(tmp_path, "m.csv", _manifest(f"grating-5mm,{shadow}", header="scene,trace"))
    with _bounded():
        assert main(["batch", str(manifest), "--out", str(tmp_path / "out"), "--quiet"]) == 1
    err = capsys.readouterr().err
    assert "SECRET" not in err and "not a trace header" in err
    with open(tmp_path / "out" / "batch.csv", newline="") as fh:
        (row,) = list(csv.DictReader(fh))
    assert row["status"] == "failed" and "SECRET" not in row["error"]
    assert row["name"] == "0000-grating-5mm-shadow"
