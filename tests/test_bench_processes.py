"""The machinery of ``frictex bench``'s whole-process figures: alternated runs, the load and
section totals beside every section, the bare-numpy floor program and the verdict on its
paired rounds, and the start-up row without frictex's bytecode cache (no timing
asserted)."""

import sys
import time
from pathlib import Path

import numpy as np
import pyarrow.parquet as pq
import pytest

import frictex.app
from frictex.app.commands.bench import _measured
from frictex.app.measure.bench_baseline import BARE, paired_figures
from frictex.app.measure.bench_startup import without_frictex_cache
from frictex.app.measure.figure import Figure
from frictex.app.measure.processes import Run, alternated, frictex_argv, median, run_process
from frictex.rendering.input.trace_file import read_trace, write_trace
from frictex.rendering.input.trace_synth import make_motion, sample


def test_alternated_rounds_run_each_command_once_reversing_the_order(tmp_path):
    log = tmp_path / "log"
    append = "import sys; open(sys.argv[1], 'a').write(sys.argv[2])"
    commands = {name: [sys.executable, "-c", append, str(log), name] for name in "abc"}
    runs = alternated(commands, 4)
    assert log.read_text() == "abc" "cba" "abc" "cba"
    assert {name: len(got) for name, got in runs.items()} == {"a": 4, "b": 4, "c": 4}
    assert all(r.code == 0 and r.wall_s > 0 and r.cpu_s >= 0 for got in runs.values() for r in got)


def test_what_comes_before_each_run_comes_just_before_it_untimed(tmp_path):
    """The baseline removes each command's last output this way: the hook runs before
    every run of its command, in the alternated order, and its time is no run's."""
    log = tmp_path / "log"
    append = "import sys; open(sys.argv[1], 'a').write(sys.argv[2])"
    commands = {name: [sys.executable, "-c", append, str(log), name] for name in "ab"}

    def before(name):
        with open(log, "a") as fh:
            fh.write(name.upper())
        if name == "a":
            time.sleep(1.5)  # a run of python -c takes a small part of that, even on a busy machine

    runs = alternated(commands, 2, before=before)
    assert log.read_text() == "AaBb" "BbAa"
    assert all(r.wall_s < 1.5 for r in runs["a"])


def test_a_failed_run_is_left_out_of_the_median():
    ok = run_process([sys.executable, "-c", "pass"])
    failed = run_process([sys.executable, "-c", "raise SystemExit(3)"])
    assert failed.code == 3
    assert median([ok, failed], "wall_s") == ok.wall_s
    assert np.isnan(median([failed], "wall_s"))


def test_a_childs_peak_memory_is_its_own_not_its_parents():
    # on Linux a child forked from this process would start at this process's peak
    held = np.ones(50 * 2**20)  # 400 MiB held here while the child runs
    done = run_process([sys.executable, "-c", "pass"])
    assert held[-1] == 1.0
    assert done.code == 0
    assert done.peak_mib < 50
    assert 0 < done.floor_mib < 50


def test_a_command_that_cannot_start_exits_127(tmp_path):
    assert run_process([str(tmp_path / "no-such-program")]).code == 127


def test_every_section_is_framed_by_the_load_and_its_whole_cost():
    inner = [Figure("demo", "something", 1.0, "s")]
    figures = _measured("demo", lambda quick: inner, True)
    labels = [f.label for f in figures]
    assert labels[1] == "something"
    assert labels[0].startswith("machine load at the start")
    assert labels[2].startswith("machine load at the end")
    assert [f.unit for f in figures[3:]] == ["s", "s", "s"]
    assert all(f.section == "demo" for f in figures)


@pytest.mark.parametrize("fmt", ["parquet", "csv", "npz"])
def test_the_bare_floor_writes_a_replays_two_tables(tmp_path, fmt):
    trace = sample(make_motion("human", speed_mm_s=60.0, duration_s=1.0, seed=7), 60.0,
                   noise_mm=0.05, seed=1)
    path = tmp_path / "trace.csv"
    write_trace(path, trace, comment="a comment line first")
    done = run_process([sys.executable, "-c", BARE, str(path), str(tmp_path / "out"), fmt])
    assert done.code == 0
    t = read_trace(path).t_s
    rows = np.arange(t[0], t[-1], 1e-4).size
    expected = {"friction": ["t_s", "finger", "x_mm", "y_mm", "mu_target", "amplitude_um"],
                "commands": ["t_s", "ch0_um"]}
    for name, columns in expected.items():
        out = tmp_path / "out" / f"{name}.{fmt}"
        if fmt == "parquet":
            table = pq.read_table(out)
            assert (table.column_names, table.num_rows) == (columns, rows)
        elif fmt == "npz":
            with np.load(out) as data:
                assert sorted(data.files) == sorted(columns)
                assert data["t_s"].size == rows
        else:
            lines = out.read_text().splitlines()
            assert lines[0].replace('"', "").split(",") == columns
            assert len(lines) == rows + 1


def _run(wall_s: float, code: int = 0) -> Run:
    return Run(wall_s, wall_s, 100.0, code)


def test_the_baseline_prints_each_rounds_paired_ratio_and_no_verdict_without_a_floor():
    bare = [_run(2.0), _run(4.0), _run(2.0), _run(2.0)]
    ours = [_run(2.2), _run(2.0), _run(9.0, code=1), _run(1.6)]  # round 3 failed: left out
    figures = {f.label.removeprefix("L, "): f for f in paired_figures("L", bare, ours, 1.2)}
    assert [figures[f"frictex against bare, round {k}"].value for k in (1, 2, 4)] == [
        pytest.approx(1.1), pytest.approx(0.5), pytest.approx(0.8)]
    assert "frictex against bare, round 3" not in figures
    verdict = figures["frictex against bare, target at most 1.2x (geometric mean of 3 "
                      "rounds, 1 of 4 failed)"]
    assert verdict.value == pytest.approx((1.1 * 0.5 * 0.8) ** (1 / 3))
    assert verdict.unit.endswith("x): not shown")  # 0.5-1.1x in three rounds settles nothing
    assert verdict.unit.startswith("x (95 % interval ")
    csv = [f.label for f in paired_figures("L", bare, ours, None)]
    assert any("no verdict: the bare program is no floor" in label for label in csv)
    assert not any("target" in label for label in csv)


def test_the_startup_row_without_frictexs_bytecode_cache_keeps_every_other_modules(tmp_path):
    argv = without_frictex_cache(frictex_argv("--version"), tmp_path)
    assert argv[:4] == [sys.executable, "-B", "-X", f"pycache_prefix={tmp_path}"]
    cached = [p.relative_to(tmp_path) for p in tmp_path.rglob("*.pyc")]
    assert any(p.name.startswith("argparse.") for p in cached)  # the standard library's
    frictex_dirs = [Path(p).resolve().relative_to("/") for p in frictex.app.__path__]
    assert not [p for p in cached if any(d in p.parents for d in frictex_dirs)]
    assert run_process(argv).code == 0


def test_the_batch_figures_pair_each_run_on_one_core_with_one_on_all(tmp_path, monkeypatch):
    from frictex.app.measure import bench_replay
    monkeypatch.setattr(bench_replay, "cores", lambda: 2)  # whatever this machine has
    figures = {f.label: f for f in bench_replay._batch_figures(tmp_path, 2)}
    against = "batch throughput, 2 cores against one after another"
    ratios = [figures[f"{against}, pair {k}"].value for k in range(1, 5)]
    assert all(r > 0 for r in ratios)
    verdict = figures[f"{against}, target at least 1.5x (geometric mean of 4 rounds)"]
    assert verdict.value == pytest.approx(np.exp(np.mean(np.log(ratios))))
    assert verdict.unit.startswith("x (95 % interval ")
    assert verdict.unit.rsplit("): ", 1)[1] in ("holds", "does not hold", "not shown")
    assert not [p for p in tmp_path.iterdir() if p.is_dir()]  # each run's output removed
