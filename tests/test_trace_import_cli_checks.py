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


def test_a_malformed_line_that_ends_in_a_line_break_is_still_refused(tmp_path, capsys):
    log = tmp_path / "bad.txt"
    log.write_text("[    1.000000] EV_SYN       SYN_REPORT           00000000\n[    1.0\n")
    assert "bad.txt:2: not a getevent -lt line" in _error(
        ["trace", "import", str(log), "-o", str(tmp_path / "o.csv"), *PHONE], capsys)
