"""Output times at large t: a replay whose t_s float64 cannot step by 1/rate refuses
before writing anything; one whose steps are off by more than 1 % of a step warns."""

import json
import re

import numpy as np

from frictex.app.commands.cli import main

RATE = 1e6


def _trace(path, t0):
    path.write_text("t_s,finger,x_mm,y_mm,event\n"
                    f"{t0!r},0,10,10,down\n{t0 + 0.01!r},0,11,10,move\n"
                    f"{t0 + 0.02!r},0,12,10,up\n")
    return path


def _replay(tmp_path, t0, out):
    trace = _trace(tmp_path / "t.csv", t0)
    return main(["replay", "grating-5mm", str(trace), "--rate", f"{RATE:g}", "--out", str(out),
                 "--format", "npz"])


def test_times_that_cannot_step_by_one_sample_are_refused_before_writing(tmp_path, capsys):
    t0 = 9999999000.0
    assert np.spacing(t0) > 1 / RATE  # independent: a step of t_s would repeat
    out = tmp_path / "out"
    assert _replay(tmp_path, t0, out) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "t_s could not increase" in err[0]
    assert "subtract its start" in err[0]
    assert not out.exists() and sorted(p.name for p in tmp_path.iterdir()) == ["t.csv"]


def test_times_off_by_over_a_percent_of_a_step_are_warned_with_the_worst_error(tmp_path, capsys):
    out = tmp_path / "out"
    assert _replay(tmp_path, 1764460000.0, out) == 0
    t_s = np.load(out / "commands.npz")["t_s"]
    worst = np.spacing(np.abs(t_s).max())  # independent: float64's spacing there
    assert 0.01 / RATE < worst < 0.5 / RATE
    assert np.diff(t_s).min() < 1 / RATE - 0.01 * worst  # the steps really are off
    warned = [w for w in json.loads((out / "summary.json").read_text())["warnings"]
              if "output step" in w]
    assert len(warned) == 1
    said = re.search(r"held to ([0-9.e+-]+) s, ([0-9.]+) %", warned[0])
    assert float(said.group(1)) == float(f"{worst:.3g}")
    assert float(said.group(2)) == round(100 * worst * RATE, 1)
    assert warned[0] in capsys.readouterr().err


def test_times_near_zero_are_not_warned(tmp_path):
    out = tmp_path / "out"
    assert _replay(tmp_path, 0.0, out) == 0
    doc = json.loads((out / "summary.json").read_text())
    assert not [w for w in doc["warnings"] if "output step" in w]


def test_times_held_to_under_a_step_still_increase_and_are_warned(tmp_path, capsys):
    """Spacing 0.95 of a step (t near 5e9 s at 1 MHz): every t_s still passes the one
    before (steps of 0.95 or 1.9 us), so the run is warned of, not refused."""
    out = tmp_path / "out"
    assert _replay(tmp_path, 5e9, out) == 0
    t_s = np.load(out / "commands.npz")["t_s"]
    assert 0.5 / RATE < np.spacing(t_s.max()) < 1 / RATE
    assert (np.diff(t_s) > 0).all()
    assert "of the output step" in capsys.readouterr().err
