"""trace synth: a press's defaults are press_synth's own, and options a motion does not
use are refused rather than ignored."""

import pytest

from frictex.app.commands.cli import main
from frictex.rendering.input.trace_file import read_trace
from frictex.textures.library import resolve_trace


def test_a_press_by_default_is_the_bundled_keyclick_press(tmp_path):
    """The defaults were (14, 32.4) mm, 50 Hz and 0.5 N: off keyclick-ring's 140 x 30 mm
    display (195 of 195 samples), no click; press_synth's own are (70, 15) mm, 100 Hz and
    0.1 N, which make keyclick-press-100hz."""
    out = tmp_path / "p.csv"
    assert main(["trace", "synth", "press", "-o", str(out)]) == 0
    assert out.read_bytes() == resolve_trace("keyclick-press-100hz").read_bytes()


def test_a_path_keeps_its_own_defaults(tmp_path):
    out = tmp_path / "s.csv"
    assert main(["trace", "synth", "swipe", "-o", str(out)]) == 0
    trace = read_trace(out)
    assert (len(trace), trace.x_mm[0], trace.y_mm[0], trace.force_n[0]) == (101, 14.0, 32.4, 0.5)


@pytest.mark.parametrize("motion, option", [
    ("press", ["--noise", "0.1"]), ("press", ["--jitter", "0.001"]),
    ("press", ["--duration", "5"]), ("press", ["--speed", "80"]),
    ("circle", ["--angle", "30"]), ("circle", ["--length", "50"]),
    ("swipe", ["--radius", "5"]), ("human", ["--angle", "45"]),
    ("back-and-forth", ["--peaks", "2"])])
def test_an_option_the_motion_does_not_use_is_refused(tmp_path, capsys, motion, option):
    """These were accepted and ignored (exit 0)."""
    out = tmp_path / "t.csv"
    assert main(["trace", "synth", motion, *option, "-o", str(out)]) == 2
    err = capsys.readouterr().err.strip()
    assert f"{option[0]} {option[1]}: a {motion} does not use it; leave it out" in err
    assert "\n" not in err and not out.exists()


def test_an_unused_option_at_its_default_is_accepted(tmp_path):
    """A trace's first line repeats every path option, those the motion ignores at their
    defaults: the command must still run."""
    assert main(["trace", "synth", "circle", "--angle", "0", "--length", "80",
                 "-o", str(tmp_path / "c.csv")]) == 0


def test_a_truth_rate_without_truth_is_refused(tmp_path, capsys):
    """--truth-rate sets the rate of --truth's true path: alone it was ignored (exit 0)."""
    out = tmp_path / "s.csv"
    assert main(["trace", "synth", "swipe", "--truth-rate", "100", "-o", str(out)]) == 2
    assert "--truth-rate 100: the rate of --truth's true path, and no --truth was given" in (
        capsys.readouterr().err)
    assert not out.exists()
    assert main(["trace", "synth", "swipe", "--truth-rate", "100", "-o", str(out),
                 "--truth", str(tmp_path / "t.csv")]) == 0
