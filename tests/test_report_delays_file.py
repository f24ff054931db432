"""A ``--loop-delays`` file is read as it was written or refused in one line naming the
file and the field: delays the loop can never see (later than its wait), and fields of
the wrong type (a string of digits for blocks, fractions, booleans, a load that is no
number); a FIFO, a device or a file over the size cap without reading it; and
report.md says what a sequence nobody measured was."""

import json
import os
import subprocess
import sys

import pytest

from frictex.app.commands.cli import main
from frictex.app.measure import report_closed_loop as rcl
from frictex.app.measure.link_report_delays import LOST, MAX_FILE_BYTES, read, wait_blocks
from frictex.device.errors import InputError

#: a report_delays object as ``ReportDelays.to_json`` writes it (measured, 5 s)
GOOD = {"blocks": [2, 3, LOST, 5], "seconds": 5, "rate_hz": rcl.RATE_HZ, "block": rcl.BLOCK,
        "busy": 2, "load_start": 1.5, "load_end": 2.0}
WAIT = wait_blocks(rcl.RATE_HZ, rcl.BLOCK)
#: longest a command is waited for (s): a hang, not a busy machine
HANG_S = 120.0


def _write(tmp_path, **fields):
    """``GOOD`` with ``fields`` in its place, written as a file; its path."""
    path = tmp_path / "delays.json"
    path.write_text(json.dumps({**GOOD, **fields}))
    return path


def test_the_wait_is_the_loops_50_ms_in_blocks():
    assert WAIT == 10  # LoopConfig.max_wait_s = 50 ms at 5 kHz in blocks of 25


def test_delays_up_to_the_wait_and_unrecorded_loads_are_read(tmp_path):
    delays = read(_write(tmp_path, blocks=[0, WAIT, LOST], load_start=None),
                  rcl.RATE_HZ, rcl.BLOCK)
    assert delays.blocks == (0, WAIT, LOST) and delays.largest() == WAIT
    assert delays.load_start != delays.load_start  # null: NaN, not recorded


@pytest.mark.parametrize("fields, said", [
    ({"blocks": [2, 3, 5000]}, r"blocks\[2\] is 5000, expected at most the loop's wait, 10"),
    ({"blocks": [WAIT + 1]}, r"blocks\[0\] is 11, expected at most the loop's wait"),
    ({"blocks": "223"}, "blocks is '223', expected a non-empty list"),
    ({"blocks": [2.9, 0.5]}, r"blocks\[0\] is 2.9, expected a whole number"),
    ({"blocks": [2.0]}, r"blocks\[0\] is 2.0, expected a whole number"),
    ({"blocks": [True, False]}, r"blocks\[0\] is True, expected a whole number"),
    ({"seconds": True}, "seconds is True, expected a finite number"),
    ({"busy": "2"}, "busy is '2', expected a finite number"),
    ({"load_start": "x"}, "load_start is 'x', expected a number, null or NaN"),
    ({"load_end": False}, "load_end is False, expected a number, null or NaN"),
])
def test_a_field_of_the_wrong_type_or_out_of_reach_is_named(tmp_path, fields, said):
    path = _write(tmp_path, **fields)
    with pytest.raises(InputError, match=said) as err:
        read(path, rcl.RATE_HZ, rcl.BLOCK)
    assert str(err.value).startswith(f"{path}: report delays: ")
    assert "\n" not in str(err.value)


def test_the_command_refuses_an_impossible_delay_before_running(tmp_path, capsys):
    path = _write(tmp_path, blocks=[2, 3, 5000])
    assert main(["report", "--quick", "--loop-delays", str(path),
                 "--out", str(tmp_path / "o")]) == 2
    err = capsys.readouterr().err
    assert "blocks[2] is 5000" in err and len(err.strip().splitlines()) == 1


def _line(tmp_path, blocks: list) -> str:
    """report.md's sentence on the delays of an unmeasured file with ``blocks``."""
    path = _write(tmp_path, blocks=blocks, seconds=0)
    return rcl._delays_line(read(path, rcl.RATE_HZ, rcl.BLOCK).to_json())


def test_an_unmeasured_sequence_is_said_to_be_replayed_from_its_file(tmp_path):
    line = _line(tmp_path, [0, 0, 0, 0, 9])
    assert "every report" not in line
    assert "replayed a sequence of 5 report delays" in line and "largest 9 blocks" in line
    assert f"recorded in {tmp_path / 'delays.json'}" in line


def test_an_unmeasured_constant_is_said_to_be_one(tmp_path):
    line = _line(tmp_path, [4, 4])
    assert line.startswith("These runs had every report 4 blocks late (not measured, "
                           f"recorded in {tmp_path / 'delays.json'}")
    assert rcl._delays_line(rcl.UNMEASURED.to_json()) == (
        f"These runs had every report {rcl.REPORT_DELAY_BLOCKS} blocks late (not measured).")


def test_a_fifo_is_refused_at_argument_checking_without_waiting_for_a_writer(tmp_path):
    """In a process of its own: read as a file, a FIFO with no writer blocks forever."""
    fifo = tmp_path / "delays.fifo"
    os.mkfifo(fifo)
    done = subprocess.run([sys.executable, "-m", "frictex", "report", "--quick",
                           "--loop-delays", str(fifo), "--out", str(tmp_path / "o")],
                          capture_output=True, text=True, stdin=subprocess.DEVNULL,
                          timeout=HANG_S)
    assert done.returncode == 2, done.stderr
    assert done.stderr.strip().splitlines() == [
        f"frictex: error: {fifo}: is a FIFO (named pipe), not a regular file (frictex reads "
        "only regular files); expected a report.json or its report_delays object"]
    assert not (tmp_path / "o").exists()  # refused before the report's runs


def test_a_file_over_the_cap_is_refused_from_its_size(tmp_path):
    path = tmp_path / "huge.json"
    with open(path, "wb") as fh:
        fh.truncate(MAX_FILE_BYTES + 1)  # sparse: nothing is written
    with pytest.raises(InputError, match=f"more than the {MAX_FILE_BYTES:,} bytes"):
        read(path, rcl.RATE_HZ, rcl.BLOCK)
