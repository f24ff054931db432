"""Trace CSV: the grammar, its errors, and exact round trips."""

import numpy as np
import pytest
from hypothesis import given, settings, strategies as st

from app.commands.cli import main
from rendering.input.trace_file import DOWN, MOVE, UP, TraceError, format_trace, parse_trace, read_trace


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
    ("t_s,finger,x_mm,y_mm\n0,0,abc,1\n", r"<t>:2: column x_mm: 'abc' is not a number"),
    ("t_s,finger,x_mm,y_mm\n0,0,nan,1\n", "not a finite number"),
    ("t_s,finger,x_mm,y_mm\n1,0,0,0\n0.5,0,0,0\n", r"<t>:3: t_s goes back from 1.0 to 0.5"),
    ("t_s,finger,x_mm,y_mm\n0,-1,0,0\n", "finger: '-1' is not an integer >= 0"),
    ("t_s,finger,x_mm,y_mm\n0,1.5,0,0\n", "finger: '1.5' is not an integer"),
    ("t_s,finger,x_mm,y_mm\n0,0,0\n", "3 fields, expected 4"),
    ("t_s,finger,x_mm,y_mm,force_n\n0,0,0,0,-2\n", "force_n: -2.0 N is negative"),
    ("t_s,finger,x_mm,y_mm,event\n0,0,0,0,press\n", "'press' is not one of down, move, up"),
])
def test_bad_traces_get_one_line_errors(text, message):
    with pytest.raises(TraceError, match=message):
        parse_trace(text, "<t>")


def test_missing_and_binary_files(tmp_path):
    with pytest.raises(TraceError, match="no such trace file"):
        read_trace(tmp_path / "nope.csv")
    binary = tmp_path / "bin.csv"
    binary.write_bytes(b"\xff\xfe\x00\x81")
    with pytest.raises(TraceError, match="not a text file"):
        read_trace(binary)


finite = st.floats(-1e6, 1e6, allow_nan=False)


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
    from rendering.input.trace_file import make_trace
    batch = make_trace([1.0, 1.01], [0, 0], [5.0, 6.0], [0.0, 0.0], event=[MOVE, MOVE],
                       normalise=False)
    assert batch.event.tolist() == [MOVE, MOVE]
    assert make_trace([1.0], [0], [5.0], [0.0], event=[MOVE]).event.tolist() == [DOWN]


def test_chunked_reading_equals_whole_and_checks_across_chunks(tmp_path):
    from rendering.input.trace_file import concat_traces, iter_trace
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
    with pytest.raises(TraceError, match=r"t\.csv:4: t_s goes back"):
        list(iter_trace(path, chunk_rows=2))
