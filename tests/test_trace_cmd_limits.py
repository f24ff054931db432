"""``frictex trace synth press`` bounds: it ignores --duration, so its size comes from the
number of --peaks and --rate, and both are checked before any sample is made."""

import pytest

from frictex.app.commands import trace as trace_cmd
from frictex.app.commands.cli import main
from frictex.rendering.input.trace_file import read_trace


def synth_press(out, peaks, *options):
    return main(["trace", "synth", "press", "--peaks", *map(str, peaks), *options, "-o", str(out)])


def test_presses_beyond_the_sample_cap_are_refused_before_any_is_made(tmp_path, capsys, monkeypatch):
    monkeypatch.setattr(trace_cmd, "press_trace", lambda **kw: pytest.fail("made the presses"))
    assert synth_press(tmp_path / "p.csv", [1.0] * 80, "--rate", "100000") == 2
    assert "--peaks: 80 presses of 1.3 s at --rate 100000 Hz are 10,400,080 samples; " \
           "at most 10,000,000" in capsys.readouterr().err
    assert not (tmp_path / "p.csv").exists()


def test_more_presses_than_the_limit_are_refused(tmp_path, capsys):
    assert synth_press(tmp_path / "p.csv", [1.0] * (trace_cmd.MAX_PRESSES + 1)) == 2
    assert f"--peaks: {trace_cmd.MAX_PRESSES + 1} presses; at most {trace_cmd.MAX_PRESSES}" \
        in capsys.readouterr().err


def test_the_most_presses_with_the_longest_numbers_read_back(tmp_path):
    """The first line repeats every peak twice: at the limit it still fits a trace line."""
    out = tmp_path / "p.csv"
    longest = "0.000123457"
    assert synth_press(out, [longest] * trace_cmd.MAX_PRESSES, "--x0", "-12345.6789", "--y0",
                       "-12345.6789", "--force", longest, "--force-noise", longest,
                       "--seed", "123456789012345678", "--rate", "100") == 0
    assert len(read_trace(out)) == trace_cmd.MAX_PRESSES * 131


def test_a_negative_seed_is_refused_in_one_line(tmp_path, capsys):
    assert synth_press(tmp_path / "p.csv", [1.0], "--seed", "-1") == 2
    assert "--seed -1: expected 0 to 1e+18" in capsys.readouterr().err


@pytest.mark.parametrize("motion, options, said", [
    ("swipe", [], "a swipe without --noise or --jitter"),
    ("circle", ["--noise", "0"], "a circle without --noise or --jitter"),
    ("press", ["--force-noise", "0"], "a press without --force-noise")])
def test_a_seed_with_nothing_random_to_seed_is_refused(tmp_path, capsys, motion, options, said):
    """--seed 5 on a noiseless swipe was taken and changed nothing: the same trace as
    --seed 0, which a user comparing seeds would not expect."""
    out = tmp_path / "t.csv"
    assert main(["trace", "synth", motion, *options, "--seed", "5", "-o", str(out)]) == 2
    assert capsys.readouterr().err.strip() == (f"frictex: error: --seed 5: {said} has nothing "
                                               "random to seed; leave it out")
    assert not out.exists()


@pytest.mark.parametrize("motion, options", [
    ("swipe", ["--noise", "0.1"]), ("back-and-forth", ["--jitter", "0.001"]), ("human", []),
    ("press", [])])  # a press's force noise is on by default
def test_a_seed_with_something_random_is_taken(tmp_path, motion, options):
    made = []
    for seed in ("5", "6"):
        out = tmp_path / f"{seed}.csv"
        assert main(["trace", "synth", motion, *options, "--seed", seed, "-o", str(out)]) == 0
        made.append(out.read_text().splitlines()[1:])  # past the first line, which names it
    assert made[0] != made[1]


@pytest.mark.parametrize("option, value, said", [
    ("--duration", "1e-320", "--duration 9.99989e-321: expected 1e-06 to 100000 s"),
    ("--rate", "1e-320", "--rate 9.99989e-321: expected 0.001 to 100000 Hz")])
def test_a_path_under_a_billionth_of_a_sample_interval_is_refused(tmp_path, capsys, option,
                                                                  value, said):
    """A duration or rate whose product rounded to no interval made a trace of one row, a
    lift with no touch-down (exit 0, 'wrote 1 samples')."""
    out = tmp_path / "s.csv"
    assert main(["trace", "synth", "swipe", f"{option}={value}", "-o", str(out)]) == 2
    assert said in capsys.readouterr().err and not out.exists()
    assert main(["trace", "synth", "swipe", "--duration", "1e-6", "-o", str(out)]) == 0
    assert [int(e) for e in read_trace(out).event] == [0, 2]
