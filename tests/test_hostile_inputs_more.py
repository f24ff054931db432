"""Inputs at the edges of what the readers accept: a trace at the latest time a trace may
hold replays; files whose lines end in CR only are told so; the demo's evdev input gives
advice the demo can follow."""

import pytest

import frictex
from frictex.app.engine.batch import ManifestError, read_manifest
from frictex.app.live.inputs import open_source
from frictex.rendering.input.trace_file import MAX_TIME_S, TraceError, read_trace

CR_ONLY = r":1: a line ends in a bare CR \(a carriage return without a line feed, as old Mac " \
          r"files end their lines\); save the file with LF or CRLF line endings"


def test_a_trace_at_the_latest_time_a_trace_may_hold_replays(tmp_path):
    path = tmp_path / "late.csv"
    path.write_text(f"t_s,finger,x_mm,y_mm\n{MAX_TIME_S:.17g},0,1,1\n")
    frictex.replay("grating-5mm", path)  # the pipeline's warm-up touch stayed in range


@pytest.mark.parametrize("rows", [2, 400])  # one short line, or one past the line limit
def test_a_trace_whose_lines_end_in_cr_only_is_told_so(tmp_path, rows):
    path = tmp_path / "mac.csv"
    path.write_bytes(b"t_s,finger,x_mm,y_mm\r" + b"".join(b"%d,0,1,1\r" % k for k in range(rows)))
    with pytest.raises(TraceError, match="mac.csv" + CR_ONLY):
        read_trace(path)


def test_crlf_and_a_run_of_crs_before_a_line_feed_still_read(tmp_path):
    path = tmp_path / "dos.csv"
    path.write_bytes(b"t_s,finger,x_mm,y_mm\r\n0,0,1,1\r\r\n0.01,0,2,1\r")
    assert read_trace(path).x_mm.tolist() == [1.0, 2.0]


@pytest.mark.parametrize("rows", [1, 200])  # 200 rows: one line of 5 kB, once 'too long'
def test_a_manifest_whose_lines_end_in_cr_only_is_told_so(tmp_path, rows):
    path = tmp_path / "jobs.csv"
    path.write_bytes(b"scene,trace\r" + b"grating-5mm,swipe-40mms-50hz\r" * rows)
    with pytest.raises(ManifestError, match="jobs.csv" + CR_ONLY):
        read_manifest(path, ("sho",))


def test_the_demo_refuses_an_evdev_file_without_advising_options_it_lacks(tmp_path):
    path = tmp_path / "events"
    path.write_bytes(b"")
    with pytest.raises(ValueError) as refused:
        open_source("evdev", str(path))
    assert "--x-range" not in str(refused.value)
    assert "is not a multi-touch device reporting its axis ranges" in str(refused.value)
