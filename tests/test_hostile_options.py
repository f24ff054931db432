"""Out-of-range options of ``frictex trace synth``: one line, exit 2, nothing written
(they overflowed or tried to allocate terabytes)."""

import pytest

from frictex.app.commands.cli import main


@pytest.mark.parametrize("options, message", [
    (["--duration", "1e9"], "--duration 1e+09: expected 1e-06 to 100000 s"),
    (["--speed", "1e308"], "--speed 1e+308: expected over 0, up to 10000 mm/s"),
    (["--x0", "nan"], "--x0 nan: expected -100000 to 100000 mm"),
    (["--noise", "-1"], "--noise -1: expected 0 to 1000 mm"),
    (["--rate", "1000", "--duration", "20000"],
     "--rate 1000 Hz over --duration 20000 s is 20,000,000 samples; at most 10,000,000"),
])
def test_synth_options_out_of_range_are_one_line(tmp_path, capsys, options, message):
    assert main(["trace", "synth", "swipe", "-o", str(tmp_path / "s.csv"), *options]) == 2
    assert capsys.readouterr().err == f"frictex: error: {message}\n"
    assert not (tmp_path / "s.csv").exists()


@pytest.mark.parametrize("motion, options, message", [
    ("human", ["--x0", "150", "--y0", "3"], "start (150, 3) mm: outside the 108 x 64.8 mm area"),
    ("human-varied", ["--area", "600", "6"], "area 600 x 6 mm: a human motion keeps 8 mm from"),
    ("swipe", ["--area", "600", "60"], "--area: only the human motions wander in an area"),
    ("human", ["--area", "1e9", "60"], "--area 1e+09: expected over 0, up to 100000 mm"),
])
def test_a_start_or_area_a_motion_cannot_have_is_one_line(tmp_path, capsys, motion, options,
                                                           message):
    assert main(["trace", "synth", motion, "-o", str(tmp_path / "s.csv"), *options]) == 2
    err = capsys.readouterr().err
    assert err.startswith(f"frictex: error: {message}") and err.count("\n") == 1
    assert not (tmp_path / "s.csv").exists()


def test_the_range_messages_lowest_values_are_those_the_options_take(tmp_path, capsys):
    """An option said to take values "over 0" refuses 0; every other one takes its lowest."""
    from frictex.app.commands.trace import ABOVE_LOWEST, LIMITS
    for name, (lowest, _, _) in LIMITS.items():
        option = f"--{name.replace('_', '-')}"
        extra = ["--truth", str(tmp_path / "truth.csv")] if name == "truth_rate" else []
        motion = "human" if name == "area" else "press" if name in ("peaks", "force_noise") else "swipe"
        values = [f"{lowest:g}"] * (2 if name == "area" else 1)
        try:
            code = main(["trace", "synth", motion, "-o", str(tmp_path / f"{name}.csv"), option,
                         *values, *extra])
        except SystemExit as exc:  # argparse's refusal
            code = exc.code
        err = capsys.readouterr().err
        assert (code == 2) == (name in ABOVE_LOWEST), (name, err)
