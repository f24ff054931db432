"""``frictex bench baseline`` and the one-second replay over runs that failed: rounds keep
their numbers, a failed run's pair is left out on both sides, the labels say how many
failed, and no figure is NaN (or a division by zero) without saying why."""

import math

from frictex.app.measure import bench_replay
from frictex.app.measure.bench_baseline import paired_figures
from frictex.app.measure.processes import Run


def _run(wall_s: float, code: int = 0) -> Run:
    return Run(wall_s, wall_s / 2, 10.0, code)


def _figures(bare: list, ours: list, target: float | None = 1.2) -> dict:
    """``paired_figures``' figures by the end of their label (after the format's)."""
    return {f.label.removeprefix("X, "): f for f in paired_figures("X", bare, ours, target)}


def test_a_failed_bare_run_leaves_its_round_out_and_the_others_keep_their_numbers():
    bare = [_run(1.0), _run(1.0, code=1), _run(1.0), _run(1.0)]
    ours = [_run(1.1), _run(9.0), _run(1.3), _run(1.2)]
    got = _figures(bare, ours)
    rounds = {k: v.value for k, v in got.items() if "round " in k and "rounds" not in k}
    assert rounds == {"frictex against bare, round 1": 1.1,
                      "frictex against bare, round 3": 1.3,
                      "frictex against bare, round 4": 1.2}
    median_ours = got["frictex (median of 3 rounds, 1 of 4 failed, alternated)"]
    assert median_ours.value == 1.2  # 9.0, whose bare run failed, is left out
    assert "bare numpy/pyarrow (median of 3 rounds, 1 of 4 failed)" in got
    assert ("frictex against bare, target at most 1.2x (geometric mean of 3 rounds, 1 of 4 "
            "failed)") in got


def test_every_bare_run_failing_says_so_and_gives_no_nan_ratio():
    got = _figures([_run(1.0, code=1)] * 4, [_run(1.1)] * 4)
    assert "frictex against bare: no round had both runs succeed, 4 of 4 failed" in got
    assert not any("geometric mean" in k or "target" in k for k in got)
    nan = [k for k, f in got.items() if math.isnan(f.value)]
    assert nan and all("4 of 4 failed" in k for k in nan)


def test_a_bare_run_of_no_time_is_left_out_not_divided_by():
    got = _figures([_run(0.0), _run(1.0)], [_run(1.1), _run(1.1)])
    assert got["frictex against bare, round 2"].value == 1.1
    assert "frictex against bare, round 1" not in got


def test_one_round_says_it_has_no_interval():
    got = _figures([_run(1.0)], [_run(1.1)])
    units = " ".join(f.unit for f in got.values()) + " ".join(got)
    assert "nan" not in units and "one round, no interval" in units


def test_the_one_second_replay_leaves_failed_runs_out_of_its_median(monkeypatch, tmp_path):
    runs = iter([_run(0.5), _run(30.0, code=1), _run(0.6), _run(0.7), _run(30.0, code=1)])
    monkeypatch.setattr(bench_replay, "run_process", lambda argv: next(runs))
    figure = bench_replay._one_second_figure(tmp_path, tmp_path / "one.csv")
    assert figure.value == 0.6
    assert figure.label == ("one-second replay to CSV, whole process, one run after another, "
                            "its output folder removed before each (median of 5, 2 of 5 "
                            "failed)")
