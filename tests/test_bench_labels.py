"""``frictex bench``: each label says what it counts, and what is compared is measured
alike. No test here times anything: timers, pipelines and GL steps are fakes, and the
tests check the order of operations and the labels."""

from __future__ import annotations

import resource
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.app.commands import bench
from frictex.app.measure import bench_latency, bench_pipeline, bench_startup, in_turn
from frictex.app.measure.figure import Figure
from frictex.app.measure.processes import BusyProcesses, Run


def _pipeline_fakes(monkeypatch):
    """Fake build_pipeline and run_blocks; the log of (what, pipeline number)."""
    log, built = [], []

    def build_pipeline(*args, **kwargs):
        pipeline = SimpleNamespace(number=len(built), timer=SimpleNamespace(
            seconds={"layers": 0.0, "tracking": 0.001 * (len(built) + 1)}, layer_seconds={}))
        built.append(pipeline)
        log.append(("build", pipeline.number))
        return pipeline

    def run_blocks(pipeline, trace, blocks_per_call, duration_s):
        log.append(("run", pipeline.number))
        return [], np.full(3, 0.01 * (pipeline.number + 1))

    monkeypatch.setattr(bench_pipeline, "build_pipeline", build_pipeline)
    monkeypatch.setattr(bench_pipeline, "run_blocks", run_blocks)
    monkeypatch.setattr(bench_pipeline, "load", lambda name: name)
    return log


def test_a_replay_is_timed_on_a_fresh_pipeline_after_an_untimed_replay(monkeypatch):
    log = _pipeline_fakes(monkeypatch)
    pipeline, seconds = bench_pipeline.warmed_replay(
        lambda: bench_pipeline.build_pipeline(), None, 2.0)
    assert log == [("build", 0), ("run", 0), ("build", 1), ("run", 1)]
    assert pipeline.number == 1 and seconds.tolist() == [0.02] * 3


def test_the_modal_replay_and_its_stage_costs_come_from_the_run_after_the_untimed_one(
        monkeypatch):
    log = _pipeline_fakes(monkeypatch)
    modal = bench_pipeline.modal_throughput()
    assert log == [("build", 0), ("run", 0), ("build", 1), ("run", 1)]
    duration = modal["replay_x_realtime"] * 0.06
    assert modal["stages_us_per_s"]["tracking"] == pytest.approx(0.002 / duration * 1e6)


def test_live_labels_say_wall_or_thread_cpu_time_and_stage_rows_wall_time():
    wall = bench_pipeline.live_figures(np.full(400, 1e-4), "every issue-18 layer",
                                       bench_pipeline.WALL)
    cpu = bench_pipeline.live_figures(np.full(800, 1e-4), "every issue-18 layer",
                                      bench_pipeline.THREAD_CPU)
    demo = bench_pipeline.live_figures(np.full(800, 1e-4), "every issue-18 layer",
                                       bench_pipeline.THREAD_CPU, 25)
    assert [f.label for f in wall + cpu + demo] == [
        "live 5 ms block p50 of 400 blocks, every issue-18 layer, wall time",
        "live 5 ms block p99 of 400 blocks, every issue-18 layer, wall time",
        "live 5 ms block p50 of 800 blocks, every issue-18 layer, thread CPU time",
        "live 5 ms block p99 of 800 blocks, every issue-18 layer, thread CPU time",
        "live 5 ms block, every issue-18 layer, thread CPU time, target p99 under 500 us "
        "(95 % interval from the order statistics of 800 blocks of one run, taken as "
        "independent: the claim is this run's, at its load)",
        # the demo's 2.5 ms block is no target (README): no verdict
        "live 2.5 ms block p50 of 800 blocks, every issue-18 layer, thread CPU time",
        "live 2.5 ms block p99 of 800 blocks, every issue-18 layer, thread CPU time"]
    [stage] = bench_pipeline._stage_figures({"tracking": 125.0}, "hybrid")
    assert stage.unit == "us/s (wall time per second of output)"


class _FakeClock:
    """perf_counter and process_time of a process whose steps advance them."""

    def __init__(self):
        self.now = 0.0

    def __call__(self) -> float:
        return self.now


def test_the_floor_is_timed_alternated_with_the_frames_read_back_and_labelled_so(monkeypatch):
    from frictex.app.measure import bench_visual
    clock, log, released = _FakeClock(), [], []
    monkeypatch.setattr(in_turn, "time", SimpleNamespace(perf_counter=clock,
                                                         process_time=clock))

    def frame_step(backend, comp, view, read_back):
        assert read_back
        return (lambda: (log.append("frame"), setattr(clock, "now", clock.now + 0.003)),
                lambda: log.append("next"))

    def floor_step(backend, size):
        assert size == (1920, 19)
        return (lambda: (log.append("floor"), setattr(clock, "now", clock.now + 0.001)),
                lambda: released.append(True))

    monkeypatch.setattr(bench_visual, "frame_step", frame_step)
    monkeypatch.setattr(bench_visual, "floor_step", floor_step)
    comp = SimpleNamespace(viewport=SimpleNamespace(width_px=1920, height_px=19))
    figures = {f.label: f for f in bench_visual.against_floor(None, comp, None, 2, "W")}
    assert log == ["next", "frame", "floor", "floor", "next", "frame"] and released == [True]
    assert figures["frame + read back / floor W, wall time per round, target at most 2x "
                   "(geometric mean of 2 rounds)"].value == pytest.approx(3.0)
    assert figures["frame + read back / floor CPU W"].value == pytest.approx(3.0)
    assert "floor W (clear, scene quad, read back; alternated with the frames)" in figures
    assert figures["frame + read back W"].unit == "ms of wall time (best of 2)"
    assert figures["floor CPU W"].unit == "ms of CPU time (mean of 2, all threads)"


def test_a_static_image_names_the_pixels_drawn_not_only_the_window(monkeypatch):
    from frictex.app.measure import bench_visual
    comp = SimpleNamespace(viewport=SimpleNamespace(width_px=1920, height_px=19))
    figure = bench_visual.static_figure(comp, "image keyclick-beam", "1920x1080 on llvmpipe",
                                        [1.3, 1.26])
    assert figure.value == 1.26
    assert figure.label == ("static image keyclick-beam, 1920x19 px drawn in the window "
                            "1920x1080 on llvmpipe")


def test_latency_percentiles_count_the_touches_played_and_say_lost_ones_are_left_out():
    figures = bench_latency._figures("tuio", np.array([0.2821]), 20)
    assert [f.label for f in figures[:2]] == [
        "tuio: p50 of 1 played of 20 touches (19 lost, not in it)",
        "tuio: max of 1 played of 20 touches (19 lost, not in it)"]
    every = bench_latency._figures("audio", np.full(200, 0.01), 200, "events")
    assert every[1].label == "audio: p99 of 200 played of 200 events"


def _fake_rusage(monkeypatch, used: dict[int, list[float]]):
    """getrusage giving, per ``who``, the next of ``used`` (s) as user time."""
    calls = {who: iter(values) for who, values in used.items()}
    monkeypatch.setattr(bench.resource, "getrusage", lambda who: SimpleNamespace(
        ru_utime=next(calls[who]), ru_stime=0.0))


@pytest.mark.parametrize("name, children", [
    ("latency", "the commands it ran and the busy processes it started as load"),
    ("startup", "the commands it ran")])
def test_a_sections_own_cpu_is_apart_from_its_child_processes(monkeypatch, name, children):
    _fake_rusage(monkeypatch, {resource.RUSAGE_SELF: [10.0, 12.5],
                               resource.RUSAGE_CHILDREN: [1.0, 25.0]})
    def section(quick):
        if name == "latency":  # it starts busy processes as load
            with BusyProcesses(1, 5.0):
                pass
        return []
    figures = bench._measured(name, section, True)
    assert [(f.label, f.value) for f in figures[-2:]] == [
        ("the whole section, CPU user + system of this process", 2.5),
        (f"the whole section, CPU user + system of its child processes ({children})", 24.0)]


def test_every_startup_label_counts_the_runs_its_median_is_over():
    def runs(failed: int) -> list[Run]:
        return [Run(0.5, 0.4, 50.0, 1 if k < failed else 0) for k in range(5)]
    got = bench_startup.startup_figures({
        "frictex replay, one second, parquet": runs(2), bench_startup.NO_CACHE: runs(0)})
    labels = [f.label for f in got]
    assert labels[:2] == [
        "frictex replay, one second, parquet, wall (median of 3, 2 of 5 failed, alternated)",
        "frictex replay, one second, parquet, CPU user + system (median of 3, 2 of 5 failed)"]
    assert labels[2] == ("frictex replay, one second, parquet, wall time per run (alternated), "
                         "target at most 0.5 s (geometric mean of 3 runs, 2 of 5 failed)")
    assert got[2].failed == 2
    assert labels[4].endswith("CPU user + system (median of 5)")
    assert labels[-1].endswith("(mean of 3 paired rounds' differences, 2 of 5 failed)")
    assert isinstance(got[-1], Figure) and got[-1].value == pytest.approx(0.0)


def test_every_stage_row_says_whether_it_was_run_live_or_as_a_replay(monkeypatch):
    """Stage costs from a replay (200 blocks a call) are far below a live run's (one block a
    call): a row that did not say which would be compared with the wrong one."""
    per_block = np.full(400, 1e-4)
    for name, fake in [("warmed_replay", lambda build, trace, duration: (None, np.ones(1))),
                       ("stage_costs", lambda pipeline, duration: {"tracking": 1.0}),
                       ("build_pipeline", lambda *a, **k: None), ("load", lambda scene: None),
                       ("PipelineStage", lambda pipeline: None),
                       ("time_blocks", lambda *a: (per_block, per_block)),
                       ("loop_blocks", lambda mode, duration: (per_block, per_block)),
                       ("new_layer_blocks",
                        lambda duration, block=50: (per_block, per_block, {"tracking": 2.0})),
                       ("modal_throughput", lambda: {"replay_x_realtime": 5.0,
                                                     "stages_us_per_s": {"tracking": 3.0}})]:
        monkeypatch.setattr(bench_pipeline, name, fake)
    stages = [f.label for f in bench_pipeline.run(quick=True) if f.unit.startswith("us/s")]
    assert stages == ["  tracking, file's renderers, replay (200 blocks a call)",
                      "  tracking, hybrid, replay (200 blocks a call)",
                      "  tracking, issue-18 layers, live",
                      "  tracking, modal, replay (200 blocks a call)"]
