"""Trace CSV: the grammar, its errors, and exact round trips."""

import io
import unicodedata

import numpy as np
import pytest
from hypothesis import assume, example, given, settings, strategies as st

from frictex.app.commands.cli import main
from frictex.rendering.input.trace_file import (DOWN, MAX_LINE_BYTES, MOVE, NUMBER, UP, TraceError, ascii_float,
                                                concat_traces, format_trace, parse_trace, read_trace)


@pytest.mark.parametrize("field, value, message", [
    ("force_n", None, r"^trace: force_n is None: expected one number per sample, shape \(n,\)$"),
    ("event", 1, "^trace: event: expected an array or list of one number per sample, got int$"),
    ("x_mm", (x for x in (1.0, 2.0)), "^trace: x_mm: expected an array or list of one number "
                                      "per sample, got generator$"),
])
def test_a_trace_built_by_hand_refuses_a_field_that_is_not_an_array(field, value, message):
    from frictex.rendering.input.trace_file import Trace
    fields = {"t_s": [0.0, 0.1], "finger": [0, 0], "x_mm": [1.0, 2.0], "y_mm": [3.0, 4.0],
              "force_n": [0.5, 0.5], "event": [DOWN, UP]}
    with pytest.raises(TraceError, match=message):
        Trace(**{**fields, field: value})


def test_minimal_trace_defaults():
    tr = parse_trace("t_s,finger,x_mm,y_mm\n0,0,1,2\n0.02,0,2,2\n")
    assert len(tr) == 2 and tr.force_n.tolist() == [0.5, 0.5]
    assert tr.event.tolist() == [DOWN, MOVE]


def test_extra_columns_and_comments_are_ignored():
    tr = parse_trace("# from a phone\nfoo,t_s,x_mm,finger,y_mm\nz,0,1,3,2\n\nz,0.01,1,3,2\n")
    assert tr.finger.tolist() == [3, 3] and tr.x_mm.tolist() == [1.0, 1.0]


def test_first_sample_after_up_is_a_down():
    tr = parse_trace("t_s,finger,x_mm,y_mm,event\n0,0,1,1,move\n1,0,1,1,up\n2,0,5,5,move\n")
    assert tr.event.tolist() == [DOWN, UP, DOWN]


@pytest.mark.parametrize("text, message", [
    ("", "empty trace"),
    ("t_s,finger,x_mm\n0,0,1\n", r"lacks column\(s\) y_mm"),
    ("t_s,finger,x_mm,y_mm\n", "header but no samples"),
    ("t_s,finger,x_mm,y_mm\n0,0,abc,1\n", r'<t>:2: column x_mm: "abc" is not a number'),
    ("t_s,finger,x_mm,y_mm\n0,0,nan,1\n", "not a finite number"),
    ("t_s,finger,x_mm,y_mm\n0,-1,0,0\n",
     r'^<t>:2: column finger: "-1" is not an integer from 0 to 2147483647 \(32-bit ids'),
    ("t_s,finger,x_mm,y_mm\n0,1e20,0,0\n", r'^<t>:2: column finger: "1e20" is not an integer from 0'),
    ("t_s,finger,x_mm,y_mm\n0,9223372036854775807,0,0\n", r'^<t>:2: column finger: "9223372036854775807"'),
    ("t_s,finger,x_mm,y_mm\n1e308,0,0,0\n", r'^<t>:2: column t_s: "1e308" is not a number from -1e\+10 to 1e\+10 s$'),
    ("t_s,finger,x_mm,y_mm\n0,0,1e308,0\n", r'^<t>:2: column x_mm: "1e308" is not a number from -100000 to 100000 mm$'),
    ("t_s,finger,x_mm,y_mm\n0,0,0,-1e6\n", r'^<t>:2: column y_mm: "-1e6" is not a number from -100000 to 100000 mm$'),
    ("t_s,finger,x_mm,y_mm\n0,0,0,inf\n", r'^<t>:2: column y_mm: "inf" is not a finite number$'),
    ("t_s,finger,x_mm,y_mm,force_n\n0,0,0,0,1e4\n", r'^<t>:2: column force_n: "1e4" is not a number from 0 to 1000 N$'),
    ("t_s,finger,x_mm,y_mm\n0,1.5,0,0\n", 'finger: "1.5" is not an integer'),
    ("t_s,finger,x_mm,y_mm\n0,0,0\n", "3 fields, expected 4"),
    # a longer row, alone or after good rows (Arrow's path took its first fields, the
    # rest ignored), and every row longer
    ("t_s,finger,x_mm,y_mm\n0,0,0,0,9\n", r"^<t>:2: 5 fields, expected 4 as the header has"),
    ("t_s,finger,x_mm,y_mm\n" + "0,0,0,0\n" * 40 + "1,0,0,0,9\n",
     r"^<t>:42: 5 fields, expected 4 as the header has"),
    ("t_s,finger,x_mm,y_mm\n" + "0,0,0,0,9\n" * 40, r"^<t>:2: 5 fields, expected 4"),
    ("t_s,finger,x_mm,y_mm,force_n\n0,0,0,0,-2\n", r'^<t>:2: column force_n: "-2" is not a number from 0 to 1000 N$'),
    ("t_s,finger,x_mm,y_mm\n0,0,0," + "9" * 5000 + "\n", r"^<t>:2: line longer than 4096 bytes"),
    ("t_s,finger,x_mm,y_mm\n0,0\x00,0,0\n", r"^<t>:2: binary content \(a NUL byte at column 4\)"),
    ("t_s,finger,x_mm,y_mm\n" + "".join(f"0,{k},0,0\n" for k in range(21)),
     r"^<t>:22: 21 fingers touch at once \(finger 20 comes down while the others have no up "
     r"event\); at most 20 are accepted$"),
    ("t_s,finger,x_mm,y_mm,event\n0,0,0,0,press\n", '"press" is not one of down, move, up'),
])
def test_bad_traces_get_one_line_errors(text, message):
    with pytest.raises(TraceError, match=message):
        parse_trace(text, "<t>")


@pytest.mark.parametrize("text, said", [
    ("t_s,finger,x_mm,y_mm\n0,\ud800,1,2\n", r"<trace>:2: not UTF-8 text \(byte 0xed at column 3\)"),
    # a byte that was not UTF-8, kept by errors="surrogateescape": told as that byte
    ("t_s,finger,x_mm,y_mm\n0,0,1,2\n0.1,0,\udcff,2\n", r"<trace>:3: not UTF-8 text \(byte 0xff at column 7\)"),
])
def test_text_with_a_lone_surrogate_is_refused_by_its_line(text, said):
    """parse_trace took text with a lone surrogate to its UTF-8 encoding, which raised
    UnicodeEncodeError."""
    with pytest.raises(TraceError, match=said):
        parse_trace(text)


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(TraceError, match=r"nope\.csv: No such file or directory; expected a trace CSV"):
        read_trace(tmp_path / "nope.csv")
    binary = tmp_path / "bin.csv"
    binary.write_bytes(b"t_s,finger,x_mm,y_mm\n0,0,\x81,0\n")
    with pytest.raises(TraceError, match=r"bin\.csv:2: not UTF-8 text \(byte 0x81 at column 5\)"):
        read_trace(binary)
    binary.write_bytes("t_s,finger,x_mm,y_mm\n".encode("utf-16"))
    with pytest.raises(TraceError, match=r"bin\.csv: UTF-16 text .*save it as UTF-8"):
        read_trace(binary)


finite = st.floats(-1e5, 1e5, allow_nan=False)


@settings(max_examples=50, derandomize=True, deadline=None)
@given(rows=st.lists(st.tuples(st.floats(0, 1e5), st.integers(0, 9), finite, finite,
                               st.floats(0, 10), st.sampled_from([0, 1, 2])), min_size=1, max_size=30))
def test_format_parse_round_trip_is_exact(rows):
    rows = sorted(rows, key=lambda r: r[0])
    text = "t_s,finger,x_mm,y_mm,force_n,event\n" + "".join(
        f"{t!r},{f},{x!r},{y!r},{F!r},{('down', 'move', 'up')[e]}\n" for t, f, x, y, F, e in rows)
    tr = parse_trace(text)
    again = parse_trace(format_trace(tr, comment="round trip"))
    for name in ("t_s", "finger", "x_mm", "y_mm", "force_n", "event"):
        assert np.array_equal(getattr(tr, name), getattr(again, name))


@settings(max_examples=100, derandomize=True, deadline=None)
@given(st.text(max_size=200))
def test_any_text_is_a_trace_or_a_trace_error(text):
    try:
        parse_trace("t_s,finger,x_mm,y_mm\n" + text)
    except TraceError:
        pass


def test_cli_bad_trace_exits_2_with_one_line(tmp_path, capsys):
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,finger,x_mm,y_mm\n0,0,1,1\n-1,0,1,1\n")
    scene = tmp_path / "s.toml"  # never reached: the trace is checked first or the scene fails
    code = main(["replay", str(scene), str(bad), "--out", str(tmp_path / "o")])
    err = capsys.readouterr().err
    assert code == 2 and err.startswith("frictex: error: ") and err.count("\n") == 1


def test_live_batches_keep_their_events():
    from frictex.rendering.input.trace_file import make_trace
    batch = make_trace([1.0, 1.01], [0, 0], [5.0, 6.0], [0.0, 0.0], event=[MOVE, MOVE],
                       normalise=False)
    assert batch.event.tolist() == [MOVE, MOVE]
    assert make_trace([1.0], [0], [5.0], [0.0], event=[MOVE]).event.tolist() == [DOWN]


def test_chunked_reading_equals_whole_and_checks_across_chunks(tmp_path):
    from frictex.rendering.input.trace_file import concat_traces, iter_trace
    path = tmp_path / "t.csv"
    path.write_text("t_s,finger,x_mm,y_mm,event\n" + "".join(
        f"{k * 0.01},{k % 2},{k},{k},{'up' if k in (5, 6) else 'move'}\n" for k in range(20)))
    whole = read_trace(path)
    chunked = concat_traces(iter_trace(path, chunk_rows=3))
    for name in ("t_s", "finger", "x_mm", "event"):
        assert np.array_equal(getattr(whole, name), getattr(chunked, name))
    # finger 1 lifts at row 5, finger 0 at row 6: their next samples are downs
    assert chunked.event[7] == DOWN and chunked.event[8] == DOWN and chunked.event[9] == MOVE
    path.write_text("t_s,finger,x_mm,y_mm\n0,0,0,0\n0.02,0,0,0\n0.01,0,0,0\n")
    with pytest.raises(TraceError, match=r"t\.csv:4: t_s goes back from 0.02 to 0.01 s \(time "
                                         r"must not decrease in a strict read: --strict, strict=True\)"):
        list(iter_trace(path, chunk_rows=2, strict=True))


# ---------------------------------------------------------------------------
# Time that goes back (issue 14, 4d): sorted within the tolerance, dropped beyond it


def test_bom_at_the_start_is_dropped():
    tr = parse_trace("\ufefft_s,finger,x_mm,y_mm\n0,0,1,2\n")
    assert tr.x_mm.tolist() == [1.0]


def test_interleaved_fingers_are_sorted_into_time_order(tmp_path):
    from frictex.rendering.input.trace_file import iter_trace
    path = tmp_path / "t.csv"
    # finger 1's sample at 8 ms is logged after finger 0's at 10 ms (2 ms back)
    path.write_text("t_s,finger,x_mm,y_mm\n0,0,0,0\n0.010,0,1,0\n0.008,1,5,5\n0.010,1,6,5\n"
                    "0.020,0,2,0\n")
    reader = iter_trace(path)
    tr = concat_traces(reader)
    assert tr.t_s.tolist() == [0.0, 0.008, 0.010, 0.010, 0.020]
    assert tr.finger.tolist() == [0, 1, 0, 1, 0]  # equal times keep their file order
    assert tr.x_mm.tolist() == [0.0, 5.0, 1.0, 6.0, 2.0]
    assert tr.event.tolist() == [DOWN, DOWN, MOVE, MOVE, MOVE]
    assert reader.order.as_dict() == {"tolerance_s": 0.005, "reordered": 1, "dropped": 0}
    assert reader.order.warnings() == [
        "1 touch samples were up to 5 ms earlier than the sample before them and were sorted "
        "into time order"]


def test_samples_further_back_are_dropped_and_counted(tmp_path):
    from frictex.rendering.input.trace_file import iter_trace
    path = tmp_path / "t.csv"
    path.write_text("t_s,finger,x_mm,y_mm\n0,0,0,0\n0.1,0,1,0\n0.05,0,9,9\n0.09,0,9,9\n0.2,0,2,0\n")
    reader = iter_trace(path)
    tr = concat_traces(reader)
    assert tr.t_s.tolist() == [0.0, 0.1, 0.2] and tr.x_mm.tolist() == [0.0, 1.0, 2.0]
    assert reader.order.as_dict() == {"tolerance_s": 0.005, "reordered": 0, "dropped": 2}
    assert reader.order.warnings() == [
        "2 touch samples went back in time by more than 5 ms and were dropped (the first at "
        "line 4; --strict refuses such a trace)"]
    with pytest.raises(TraceError, match=r"t\.csv:4: t_s goes back from 0\.1 to 0\.05 s"):
        read_trace(path, strict=True)


def _reference_order(times, tolerance):
    """Indices of the rows kept, in output order, and (reordered, dropped): written from
    the rule, one row at a time, independently of the chunked reader."""
    latest, kept, reordered, dropped = -np.inf, [], 0, 0
    for i, t in enumerate(times):
        if t >= latest:
            latest = t
        elif t >= latest - tolerance:
            reordered += 1
        else:
            dropped += 1
            continue
        kept.append(i)
    kept.sort(key=lambda i: times[i])  # list.sort is stable
    return kept, reordered, dropped


@settings(max_examples=80, derandomize=True, deadline=None)
@given(steps=st.lists(st.sampled_from([0.0, 0.001, 0.004, 0.005, 0.01, -0.001, -0.003,
                                       -0.005, -0.0051, -0.02]), min_size=1, max_size=40),
       chunk_rows=st.integers(1, 9))
def test_chunked_reordering_matches_the_rule(tmp_path_factory, steps, chunk_rows):
    from frictex.rendering.input.trace_file import iter_trace
    times = np.round(np.cumsum([1.0] + steps), 6).tolist()
    path = tmp_path_factory.mktemp("order") / "t.csv"
    path.write_text("t_s,finger,x_mm,y_mm\n" + "".join(
        f"{t!r},{i % 3},{float(i)!r},0\n" for i, t in enumerate(times)))
    reader = iter_trace(path, chunk_rows=chunk_rows)
    tr = concat_traces(reader)
    kept, reordered, dropped = _reference_order(times, 0.005)
    assert tr.x_mm.tolist() == [float(i) for i in kept]
    assert (reader.order.reordered, reader.order.dropped) == (reordered, dropped)


def test_rows_held_for_reordering_are_bounded(tmp_path, monkeypatch):
    from frictex.rendering.input import trace_file
    from frictex.rendering.input.trace_file import iter_trace
    path = tmp_path / "t.csv"
    # 12 rows at one time, read 3 at a time, at most 3 held back: a later row 1 ms
    # earlier can no longer go before the ones handed out, and is dropped
    path.write_text("t_s,finger,x_mm,y_mm\n" + "1.0,0,0,0\n" * 12 + "0.999,0,9,9\n1.0,0,1,1\n")
    monkeypatch.setattr(trace_file, "MAX_HELD_ROWS", 3)
    reader = iter_trace(path, chunk_rows=3)
    chunks = list(reader)
    assert max(len(c) for c in chunks) <= 6
    tr = concat_traces(chunks)
    assert tr.x_mm.tolist() == [0.0] * 12 + [1.0]
    assert (reader.order.reordered, reader.order.dropped) == (0, 1)
    # with room to hold them all, the same row is within the tolerance and sorted in
    monkeypatch.setattr(trace_file, "MAX_HELD_ROWS", 65_536)
    whole = iter_trace(path, chunk_rows=3)
    assert concat_traces(whole).x_mm.tolist() == [9.0] + [0.0] * 12 + [1.0]
    assert (whole.order.reordered, whole.order.dropped) == (1, 0)


@pytest.mark.parametrize("rows, message", [
    ("0,0,0,0,move\n0,0,nan,0,slide\n", r'<t>:3: column x_mm: "nan"'),
    ("0,0,0,0,slide\n0,0,nan,0,move\n", r'<t>:2: column event: "slide"'),
    ("1,0,0,0,move\n0.5,0,0,0,move\n0,0,nan,0,move\n", r"<t>:3: t_s goes back from 1\.0 to 0\.5"),
    ("1,0,0,0,move\n0.5,0,0,0,slide\n", r'<t>:3: column event: "slide"'),  # values first
    ("1,0,0,0,move\n1,0,0,0,slide\n0.5,0,0,0,move\n", r'<t>:3: column event: "slide"'),
    ("1,0,inf,0,move\n0.5,0,0,0,move\n", r'<t>:2: column x_mm: "inf" is not a finite number'),
])
def test_the_first_problem_in_file_order_is_reported(rows, message):
    with pytest.raises(TraceError, match=message):
        parse_trace("t_s,finger,x_mm,y_mm,event\n" + rows, "<t>", strict=True)


def _reference_touches(fingers, events, down):
    """Events and fingers touching after each sample, one sample at a time from the rule
    (a finger's first sample, or its first after an up, is a down unless it is an up)."""
    down, out, touching = set(down), [], []
    for f, e in zip(fingers, events):
        if f not in down and e != UP:
            e = DOWN
        if e == UP:
            down.discard(f)
        else:
            down.add(f)
        out.append(e)
        touching.append(len(down))
    return out, touching, down


@settings(max_examples=100, derandomize=True, deadline=None)
@given(samples=st.lists(st.tuples(st.integers(0, 6), st.sampled_from([DOWN, MOVE, UP])),
                        max_size=40),
       down=st.sets(st.integers(0, 6), max_size=3))
def test_event_normalisation_and_touch_count_follow_the_rule(samples, down):
    from frictex.rendering.input.trace_file import _touch_steps
    fingers = np.array([f for f, _ in samples], dtype=np.int64)
    events = np.array([e for _, e in samples], dtype=np.int8)
    carried = set(down)
    got_events, got_touching = _touch_steps(fingers, events, carried)
    want_events, want_touching, want_down = _reference_touches(fingers.tolist(), events.tolist(), down)
    assert got_events.tolist() == want_events
    assert got_touching.tolist() == want_touching
    assert carried == want_down


@settings(max_examples=400, derandomize=True, deadline=None)
@given(text=st.text(alphabet=st.sampled_from(list('ab,1 .\r\t"e-')), min_size=1, max_size=14),
       end=st.sampled_from(["\n", "\r\n", ""]))
def test_fields_split_a_line_as_the_csv_module_does(text, end):
    import csv
    from frictex.rendering.input.trace_file import _fields
    line = text + end
    assume(line.strip())  # blank lines are skipped before a line is split
    try:
        want = next(csv.reader([line]), [])
    except csv.Error:
        want = None
    try:
        got = _fields(line, "<t>", 1)
    except TraceError:
        got = None
    assert got == want


@pytest.mark.parametrize("data, said", [
    # an ELF executable's start: a bare CR comes before its first line feed
    (b"\x7fELF\x02\x01\x01\x00" + b"\x00" * 8 + b"\x03\x00>\x00\x01\x00\x00\x00\xd0\r\x01\n",
     r"/bin\.csv:1: binary content \(a NUL byte at column 8\); expected CSV text$"),
    (b"\x8b\r\xff\r\x1f\n", r"/bin\.csv:1: not UTF-8 text \(byte 0x8b at column 1\)"),
    # a line longer than MAX_LINE_BYTES with binary bytes in its first MAX_LINE_BYTES
    (b"\xe9" + b"x" * MAX_LINE_BYTES + b"\n", r"/bin\.csv:1: not UTF-8 text \(byte 0xe9 at column 1\)"),
])
def test_binary_content_is_named_before_a_bare_cr_or_the_line_length(tmp_path, data, said):
    (tmp_path / "bin.csv").write_bytes(data)
    with pytest.raises(TraceError, match=said):
        read_trace(tmp_path / "bin.csv")


def _reference_lines(data: bytes, where: str, limit: int):
    """Lines as a line-at-a-time reader gives them (the rule of ``_blocks``, written out):
    (number, text without its break) until the first line that, in its first ``limit``
    bytes, holds a NUL, is not UTF-8 or holds a bare CR (one followed by more of the
    line), or else is too long (``limit`` bytes with its break), which ends in its
    TraceError message; a UTF-8 BOM at the start is dropped, a UTF-16 one refused."""
    import codecs
    import re
    out, fh = [], io.BytesIO(data)
    for number in range(1, 10**9):
        raw = fh.readline()
        if not raw:
            return out, None
        if number == 1:
            if raw.startswith((codecs.BOM_UTF16_LE, codecs.BOM_UTF16_BE)):
                return out, f"{where}: UTF-16 text"
            if raw.startswith(codecs.BOM_UTF8):
                raw = raw[3:]
            if not raw:  # a file of a BOM alone has no lines
                return out, None
        head = raw[:limit]
        if head.find(0) >= 0:
            return out, f"{where}:{number}: binary content (a NUL byte at column {head.find(0) + 1})"
        try:  # a long line's head may end within a character
            codecs.getincrementaldecoder("utf-8")().decode(head, final=len(raw) <= limit)
        except UnicodeDecodeError as exc:
            return out, f"{where}:{number}: not UTF-8 text (byte {head[exc.start]:#04x} at column {exc.start + 1})"
        if re.search(rb"\r[^\r\n]", head):
            return out, f"{where}:{number}: a line ends in a bare CR"
        if len(raw) > limit:
            return out, f"{where}:{number}: line longer than {limit} bytes"
        text = raw.decode("utf-8")
        out.append((number, text[:-1] if text.endswith("\n") else text))


@settings(max_examples=400, derandomize=True, deadline=None)
@given(data=st.lists(st.sampled_from([b"a", b",", b"\n", b"\r", b"\0", b"\xff", b"\xc3\xa9",
                                      b"\xe2", b"\xef\xbb\xbf", b"\xff\xfe", b"12345678"]),
                     max_size=30).map(b"".join),
       block=st.integers(1, 12), limit=st.integers(2, 12))
def test_lines_read_in_blocks_as_line_by_line(data, block, limit):
    from unittest import mock
    from frictex.rendering.input import trace_file
    want, problem = _reference_lines(data, "<t>", limit)
    got = []
    with mock.patch.object(trace_file, "_READ_BYTES", block), \
            mock.patch.object(trace_file, "MAX_LINE_BYTES", limit):
        try:
            for first, block, count in trace_file._blocks(io.BytesIO(data), "<t>"):
                texts = block.decode("utf-8").split("\n")
                if block.endswith(b"\n"):  # each line ends with its break, the last maybe not
                    texts.pop()
                assert len(texts) == count
                got += [(first + k, text) for k, text in enumerate(texts)]
        except TraceError as exc:
            assert problem is not None and str(exc).startswith(problem), (str(exc), problem)
        else:
            assert problem is None, problem
    assert got == want


def test_a_row_search_that_finds_no_problem_says_so():
    """_first_row_problem always raises: rows that fail together but pass one by one (a
    parser bug, not a bad file) are an AssertionError naming the lines, never a return
    that would leave the columns unset (an UnboundLocalError later)."""
    from frictex.rendering.input.trace_file import TimeOrder, _RowParser
    parser = _RowParser(["t_s", "finger", "x_mm", "y_mm"], "good.csv", TimeOrder(), False, 100)
    rows = [(2, ["0.0", "1", "3", "4"]), (3, ["0.1", "1", "3", "4"])]
    with pytest.raises(AssertionError, match="good.csv: rows 2 to 3"):
        parser._first_row_problem(rows)


# ---------------------------------------------------------------------------
# Plain blocks parsed at once (Arrow's CSV reader) read exactly as line by line


def _read_both_ways(text: str, chunk_rows: int = 65_536):
    """(what reading ``text`` gives line by line, what it gives with every block tried as a
    plain block): each a tuple of the trace's columns or the TraceError's message."""
    from frictex.rendering.input import trace_file

    def read():
        try:
            blocks = trace_file._blocks(io.BytesIO(text.encode("utf-8")), "<t>")
            tr = concat_traces(trace_file._chunks(blocks, "<t>", chunk_rows,
                                                  trace_file.TimeOrder(), False))
        except TraceError as exc:
            return str(exc)
        return tuple(getattr(tr, name).tolist() for name in trace_file._COLUMNS)

    from unittest import mock
    with mock.patch.object(trace_file, "_plain_columns", lambda *args: None):
        by_line = read()
    with mock.patch.object(trace_file, "_PLAIN_MIN_LINES", 1):
        at_once = read()
    return by_line, at_once


_number = st.one_of(st.floats(0, 100).map(repr), st.integers(0, 9).map(str))
_row_fields = st.tuples(_number, _number, _number, _number, _number,
                        st.sampled_from(["move", "down", "up"])).map(list)
# field texts near the edges of what float() and Arrow's parser take, and event words
_odd_number = st.one_of(
    st.floats(allow_nan=True, allow_infinity=True).map(repr),
    st.text(alphabet="0123456789+-.eE_ naifINF\t\u00a0\u0663", min_size=0, max_size=8),
)
_odd_word = st.sampled_from([" up ", "up\t", "\u00a0up", "", "press", "Move", "0.0"])


@settings(max_examples=400, derandomize=True, deadline=None)
@example(rows=[["0.5", "0", "1", "2", "0.5", "move"]], odd_number=None, odd_word=(0, "press"),
         header=["t_s", "finger", "x_mm", "y_mm", "force_n", "event"], newline="\n")
@example(rows=[["0.5", "0", "1", "2", "0.5", "move"]], odd_number=(0, 2, "1_0"), odd_word=None,
         header=["t_s", "finger", "x_mm", "y_mm", "force_n", "event"], newline="\n")
@example(rows=[["0.5", "0", "1", "2", "0.5", "move"]], odd_number=None, odd_word=(0, ""),
         header=["t_s", "finger", "x_mm", "y_mm", "event", "force_n"], newline="\r\n")
@given(rows=st.lists(_row_fields, min_size=1, max_size=3),
       odd_number=st.none() | st.tuples(st.integers(0, 2), st.integers(0, 4), _odd_number),
       odd_word=st.none() | st.tuples(st.integers(0, 2), _odd_word),
       header=st.permutations(["t_s", "finger", "x_mm", "y_mm", "force_n", "event"]),
       newline=st.sampled_from(["\n", "\r\n"]))
def test_a_plain_block_parses_to_the_same_values_or_error_as_line_by_line(rows, odd_number,
                                                                          odd_word, header,
                                                                          newline):
    """Arrow takes a subset of the numbers float() takes, to the same doubles; anything
    else (and an unknown event word) makes the block fall back to line by line, which
    names the problem: the trace or the error is the same either way, with LF or CRLF
    line ends. Rows hold fields in the order t_s, finger, x_mm, y_mm, force_n, event,
    written in ``header``'s order."""
    if odd_number is not None:
        row, column, text = odd_number
        rows[row % len(rows)][column] = text
    if odd_word is not None:
        row, text = odd_word
        rows[row % len(rows)][5] = text
    names = ["t_s", "finger", "x_mm", "y_mm", "force_n", "event"]
    text = ",".join(header) + newline + "".join(
        ",".join(row[names.index(name)] for name in header) + newline for row in rows)
    by_line, at_once = _read_both_ways(text)
    assert repr(at_once) == repr(by_line)  # repr: NaN equals NaN, and -0.0 differs from 0.0


_row = st.builds(lambda t, f, x: f"{t!r},{f},{x!r},1.5", st.floats(0, 100), st.integers(0, 3),
                 st.floats(-1e3, 1e3))
_odd_line = st.sampled_from(["", " ", "# a comment", "\"0.5\",0,1,2", "0.5,0,1,2\r", "0.5,0,1",
                             "0.5,0,1,2,extra", "#0.5,0,1,2"])


@settings(max_examples=300, derandomize=True, deadline=None)
@example(rows=["0.5,0,1,2", "0.6,0,1,2"], odd=[(1, "")], note=None, chunk_rows=5)  # blank line
@example(rows=["0.5,0,1,2", "0.6,0,1,2"], odd=[(2, "")], note=None, chunk_rows=5)  # last line
@example(rows=["0.5,0,1,2", "0.6,0,1,2"], odd=[], note="#n", chunk_rows=5)
@example(rows=["0.5,0,1,2", "0.6,0,1,2"], odd=[], note='"1,2,3,4,5,6"', chunk_rows=5)
@example(rows=["0.5,0,1,2", "0.6,0,1,2"], odd=[(0, "0.5,0,1")], note=None, chunk_rows=5)
@given(rows=st.lists(_row, min_size=1, max_size=8),
       odd=st.lists(st.tuples(st.integers(0, 8), _odd_line), max_size=2),
       note=st.sampled_from([None, "n", "#n", '"1,2,3,4,5,6"']), chunk_rows=st.integers(1, 5))
def test_blocks_with_comments_blanks_quotes_and_ragged_rows_read_as_line_by_line(
        rows, odd, note, chunk_rows):
    """Comments, blank lines, quoted fields, carriage returns, short and long rows and
    time going back, in any mix and any chunk size, with an extra first column or not
    (quoted, its commas must not shift the others): the same trace or error."""
    for at, line in odd:
        rows.insert(at % (len(rows) + 1), line)
    header = "t_s,finger,x_mm,y_mm"
    if note is not None:  # every line gets the extra column, comments and blanks too
        header, rows = "note," + header, [f"{note},{row}" for row in rows]
    text = header + "\n" + "\n".join(rows) + "\n"
    by_line, at_once = _read_both_ways(text, chunk_rows)
    assert repr(at_once) == repr(by_line)


@pytest.mark.parametrize("newline", ["\n", "\r\n"])
def test_a_long_plain_trace_is_parsed_at_once_and_reads_as_line_by_line(tmp_path, monkeypatch,
                                                                         newline):
    """A trace of several read blocks (the size replays meet) takes the plain path, with
    LF or CRLF line ends (a file saved on Windows), with the line numbers of its errors
    right."""
    from frictex.rendering.input import trace_file
    n = 3 * trace_file._PLAIN_MIN_LINES
    k = np.arange(n)
    text = f"t_s,finger,x_mm,y_mm,force_n,event{newline}" + "".join(
        f"{t!r},0,{x!r},2.5,0.5,move{newline}"
        for t, x in zip((k / 60).tolist(), (k % 97 * 0.37).tolist()))
    calls = []
    real = trace_file._plain_columns
    monkeypatch.setattr(trace_file, "_READ_BYTES", 1 << 18)
    monkeypatch.setattr(trace_file, "_plain_columns",
                        lambda *a: calls.append(real(*a) is not None) or real(*a))
    by_line, at_once = _read_both_ways(text)
    assert at_once == by_line and len(at_once[0]) == n
    assert sum(calls) >= 1  # at least one block of >= _PLAIN_MIN_LINES lines went at once
    bad = text.split(newline)
    bad[n - 5] = bad[n - 5].replace("0.5,move", "-0.5,move")
    by_line, at_once = _read_both_ways(newline.join(bad))
    assert at_once == by_line == (f'<t>:{n - 4}: column force_n: "-0.5" is not a number from '
                                  f"0 to 1000 N")


# -- the number grammar ---------------------------------------------------------------------

#: character categories an error message never holds (device.safe_text escapes them)
UNSAFE = {"Cc", "Cf", "Cs", "Co", "Cn", "Zl", "Zp"}
_PRINTABLE_ASCII = "".join(chr(c) for c in range(0x20, 0x7F) if chr(c) != "_") + "\t"


@settings(max_examples=600, derandomize=True, deadline=None)
@example("\u0662\u0661")
@example("2_2")
@example(" 1.5e-3\t")
@example("1e400")
@given(st.one_of(st.from_regex(NUMBER, fullmatch=True),
                 st.text(alphabet="0123456789+-.eE \tnaifINF_\x0c\u00a0\u0663\uff11", max_size=10),
                 st.text(alphabet=_PRINTABLE_ASCII, max_size=10)))
def test_the_number_grammar_is_float_on_ascii_without_words(text):
    """ascii_float takes what NUMBER states, to float's value; on printable ASCII without
    '_' (a block read with plain float) float takes no finite number the grammar refuses,
    so the fast path reads what the grammar does (inf and nan fail the range check)."""
    try:
        value = float(text)
    except ValueError:
        value = None
    try:
        strict = ascii_float(text)
    except ValueError:
        strict = None
    assert (strict is not None) == (NUMBER.fullmatch(text) is not None)
    if strict is not None:
        assert value == strict
        assert text.isascii() and "_" not in text
    elif value is not None and all(ch in _PRINTABLE_ASCII for ch in text):
        assert not np.isfinite(value)


@settings(max_examples=150, derandomize=True, deadline=None)
@given(st.text(max_size=300))
def test_any_header_or_row_is_read_or_one_escaped_line(text):
    """Whatever the text (control characters, other scripts): a trace, or one TraceError
    line with every character printable."""
    for doc in (text, "t_s,finger,x_mm,y_mm,event\n" + text):
        try:
            parse_trace(doc, "<t>")
        except TraceError as exc:
            message = str(exc)
            assert message.startswith("<t>") and not any(
                unicodedata.category(ch) in UNSAFE for ch in message), ascii(message)


@given(st.lists(st.integers(0, 2**31 - 1), min_size=1, max_size=20))  # 20: most touching
def test_a_traces_fingers_are_its_distinct_ids_ascending(ids):
    text = "t_s,finger,x_mm,y_mm\n" + "".join(f"{k},{f},1,1\n" for k, f in enumerate(ids))
    assert parse_trace(text).fingers == tuple(sorted(set(ids)))


def test_columns_it_does_not_read_are_warned_about_with_the_one_they_may_misspell(tmp_path):
    """A header saying force_N took every row's 3 N as the 0.5 N default without a word.
    Columns it ignores are named, a near miss with the column it may misspell; a field
    that is not a column name (an escape sequence) is counted, not shown."""
    from frictex.rendering.input.trace_file import ignored_columns, iter_trace
    path = tmp_path / "t.csv"
    path.write_text("t_s,finger,x_mm,y_mm,force_N,note,\x1b[2J\n0,0,10,10,3,a,b\n")
    reader = iter_trace(path)
    (chunk,) = list(reader)
    assert chunk.force_n.tolist() == [0.5]
    assert reader.warnings() == [
        "trace: 3 columns frictex does not read, ignored: force_N (did you mean force_n?), note, "
        "1 field that is not a column name (it reads t_s, finger, x_mm, y_mm, force_n, event)"]
    assert ignored_columns(["t_s", "finger", "x_mm", "y_mm", "event"]) is None


def test_a_replay_says_which_columns_it_ignored(tmp_path):
    import frictex
    path = tmp_path / "t.csv"
    path.write_text("t_s,finger,x_mm,y_mm,force_N\n0,0,10,10,3\n0.02,0,11,10,3\n")
    warnings = frictex.replay("grating-5mm", path).summary.warnings
    assert any("force_N (did you mean force_n?)" in w for w in warnings), warnings


def test_the_columns_frictex_import_adds_are_not_warned_about(tmp_path):
    """A trace imported from an Android log carries pressure and touch_major for the
    record; replaying one warned that they are not read."""
    from frictex.rendering.input.trace_file import ignored_columns
    assert ignored_columns(["t_s", "finger", "x_mm", "y_mm", "event", "pressure",
                            "touch_major"]) is None
    assert ignored_columns(["t_s", "finger", "x_mm", "y_mm", "Pressure"]).startswith(
        "trace: 1 column frictex does not read, ignored: Pressure")
