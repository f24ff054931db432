"""The run engine: replay, the live thread and the report through one driver.

Expectations are computed here independently: the pipeline run in one call over the
whole trace, and its rows formatted with Python's %-formatting (the tables' definition).
"""

import os
import signal
import time

import numpy as np
import pyarrow.parquet as pq
import pytest

from frictex.app.engine.clocks import VirtualClock
from frictex.app.engine.driver import PipelineStage, drive
from frictex.app.engine.replay import run_replay
from frictex.app.engine.sinks import MemorySink
from frictex.app.engine.sources import TraceSource
from frictex.app.measure.report_matrix import run_blocks
from frictex.device.link.protocol import AMPLITUDE_STEP_UM
from frictex.rendering.input.trace_file import read_trace
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.tracking.tracks import apply_index
from frictex.textures.library import resolve_scene, resolve_trace
from frictex.textures.loader import load_scene

SCENE, TRACE = "composed-fine-grating-in-disc", "circle-30mms-60hz"


def one_call(scene, trace, rate_hz=10_000.0, block=50):
    """The pipeline over the whole trace in a single call: to the block after the last sample."""
    pipeline = build_pipeline(scene, rate_hz, block, t0_s=float(trace.t_s[0]))
    last = int(apply_index(trace.t_s[-1:], pipeline.tracker_config)[0])
    out, _ = pipeline.process(0, trace, pipeline.initial_state(), n_blocks=last // block + 1)
    return pipeline, out


def expected_friction_csv(out) -> bytes:
    rows = []
    for i in range(out.t_s.size):
        for f, fid in enumerate(out.finger_ids):
            if out.contact[f, i]:
                rows.append("%.7f,%d,%.4f,%.4f,%.6f,%.6f\n" % (
                    out.t_s[i], fid, out.x_mm[f, i], out.y_mm[f, i], out.mu_target[f, i],
                    out.amplitude_um[f, i]))
    return ("t_s,finger,x_mm,y_mm,mu_target,amplitude_um\n" + "".join(rows)).encode()


def expected_commands_csv(out) -> bytes:
    lines = ["t_s,ch0_um\n"] + ["%.7f,%.6f\n" % (t, c) for t, c in
                                zip(out.t_s.tolist(), out.commands_um[:, 0].tolist())]
    return "".join(lines).encode()


@pytest.fixture(scope="module")
def reference():
    scene = load_scene(resolve_scene(SCENE))
    trace = read_trace(resolve_trace(TRACE))
    return scene, trace, one_call(scene, trace)[1]


def test_replay_csv_is_the_pipeline_run_formatted(tmp_path, reference):
    scene, trace, out = reference
    summary = run_replay(scene, trace, tmp_path, progress=False)
    assert (tmp_path / "commands.csv").read_bytes() == expected_commands_csv(out)
    assert (tmp_path / "friction.csv").read_bytes() == expected_friction_csv(out)
    timings = summary["timings"]
    assert timings["x_realtime_end_to_end"] < timings["x_realtime_compute"]
    assert set(timings["loop_s"]) == {"read", "compute", "write", "commit"}


@pytest.mark.parametrize("fmt", ["npz", "parquet"])
def test_binary_tables_hold_the_pipeline_run_exactly(tmp_path, reference, fmt):
    scene, trace, out = reference
    run_replay(scene, trace, tmp_path, fmt=fmt, progress=False)
    load = np.load if fmt == "npz" else (lambda p: pq.read_table(p).to_pydict())
    commands = load(tmp_path / f"commands.{fmt}")
    friction = load(tmp_path / f"friction.{fmt}")
    np.testing.assert_array_equal(np.asarray(commands["ch0_um"]), out.commands_um[:, 0])
    np.testing.assert_array_equal(np.asarray(commands["t_s"]), out.t_s)
    touching = out.contact[0]
    np.testing.assert_array_equal(np.asarray(friction["amplitude_um"]), out.amplitude_um[0, touching])
    assert np.asarray(friction["finger"]).dtype == np.int64


class FailsAt:
    """A device link whose port vanishes at the n-th block."""

    def __init__(self, n):
        self.n, self.sent, self.closed = n, 0, False

    def send(self, index, amplitudes, phases):
        self.sent += 1
        if self.sent == self.n:
            raise OSError("port vanished")

    def close(self):
        self.closed = True


def test_an_error_mid_run_leaves_the_previous_run_as_it_was(tmp_path, reference):
    """Outputs are staged beside the folder: an error at block 300 (after several table
    batches were gathered) removes the staging folder, and the previous run's outputs
    stay byte for byte."""
    scene, trace, _ = reference
    out = tmp_path / "out"
    run_replay(scene, trace, out, progress=False)
    before = {p.name: p.read_bytes() for p in out.iterdir()}
    assert sorted(before) == ["commands.csv", "friction.csv", "summary.json"]
    link = FailsAt(300)
    with pytest.raises(OSError, match="port vanished"):
        run_replay(scene, trace, out, sink=link, progress=False, chunk_blocks=7)
    assert {p.name: p.read_bytes() for p in out.iterdir()} == before
    assert sorted(p.name for p in tmp_path.iterdir()) == ["out"]
    assert link.closed and link.sent == 300


@pytest.mark.parametrize("chunk", [1, 13, 200])
def test_blocks_per_call_do_not_change_the_result(reference, chunk):
    scene, trace, out = reference
    pipeline = build_pipeline(scene, 10_000.0, 50, t0_s=float(trace.t_s[0]))
    source = TraceSource(iter([trace]))
    source.first_time()
    source.start(pipeline.tracker_config)
    memory = MemorySink()
    blocks = drive(PipelineStage(pipeline), source, [memory], VirtualClock(), chunk_blocks=chunk)
    assert blocks * 50 == out.t_s.size
    np.testing.assert_array_equal(np.concatenate([o.commands_um for o in memory.outs]),
                                  out.commands_um)


def test_the_report_loop_is_the_same_run(reference):
    """``report_matrix.run_blocks`` (the report's and the bench's loop, on the driver)
    gives the one-call result over the span it is asked for, live (1 block a call) too."""
    scene, trace, _ = reference
    shifted = trace.slice(0, len(trace))
    t0 = float(trace.t_s[0])
    pipeline, out = one_call(scene, trace)
    for per_call in (1, 200):
        fresh = build_pipeline(scene, 10_000.0, 50, t0_s=t0)
        outs, seconds = run_blocks(fresh, shifted, per_call, out.t_s.size / 10_000.0 + t0)
        got = np.concatenate([o.commands_um for o in outs])
        np.testing.assert_array_equal(got, out.commands_um[:got.shape[0]])
        assert len(seconds) == len(outs)


def test_live_thread_on_the_device_paced_clock_with_the_simulated_device(tmp_path):
    """The live path, paced by a simulated device's own clock: every block the thread
    computed was sent, and the device's log holds exactly the commands sent, at their
    output indices (what does not depend on how the scheduler runs us)."""
    from frictex.app.live.haptic_thread import HapticThread
    from frictex.device.link.host import open_sink
    scene = load_scene(resolve_scene("grating-5mm"))
    log = tmp_path / "played.csv"
    link = open_sink("sim", channels=1, rate_hz=10_000.0, paced=True, log_path=log)
    sent_commands = []

    class Keep(MemorySink):
        def write(self, out, commands_um):
            super().write(out, commands_um)
            sent_commands.append(commands_um.copy())

    thread = HapticThread(scene, sink=link, recorder=Keep(), pacing="device")
    thread.start()
    thread.touch(0, 20.0, 32.4, 0.5, "down")
    deadline = time.monotonic() + 30.0
    while thread.stats.blocks < 120 and time.monotonic() < deadline and thread.error is None:
        thread.touch(0, 20.0 + 0.2 * thread.stats.blocks, 32.4, 0.5, "move")
        time.sleep(0.01)
    thread.stop()
    thread.join(timeout=30.0)
    assert not thread.is_alive() and thread.error is None
    status = link.status()
    assert status["state"] == "closed"  # the driver committed the link sink: drained, closed
    commands = np.concatenate(sent_commands)[:, 0]
    played = np.loadtxt(log, delimiter=",", skiprows=1, ndmin=2)
    index = played[:, 0].astype(np.int64)
    assert status["commanded_samples"] == commands.size
    assert status["played_samples"] + status["unplayed_samples"] == commands.size
    # the host never claims a sample played that was not (across a reconnect under load it
    # may count as lost some that did play: the safe side)
    assert status["played_samples"] <= played.shape[0] <= commands.size
    assert np.unique(index).size == index.size and index.max() < commands.size
    # rounded to the wire's step (1/4096 um): off by at most half a step
    np.testing.assert_allclose(played[:, 1], commands[index], atol=AMPLITUDE_STEP_UM / 2 + 1e-9)


def stroke(t0, x0, n=20, step_s=0.02, speed=40.0):
    """One finger down at t0, moving at ``speed`` mm/s, up after n samples (rows)."""
    rows = []
    for i in range(n):
        event = "down" if i == 0 else ("up" if i == n - 1 else "move")
        rows.append(f"{t0 + i * step_s!r},0,{x0 + speed * i * step_s!r},32.4,0.5,{event}")
    return rows


def write_csv(path, rows):
    path.write_text("t_s,finger,x_mm,y_mm,force_n,event\n" + "\n".join(rows) + "\n")
    return path


def test_a_long_gap_is_a_lift_and_its_silence_is_not_written(tmp_path):
    """Two strokes 1e9 s apart (a clock that jumped): written in full they would be 10^13
    rows. The gap is skipped (0.1 s kept each side), and the second stroke's commands are
    what the same stroke gives replayed alone."""
    scene = load_scene(resolve_scene("grating-5mm"))
    both = write_csv(tmp_path / "both.csv", stroke(0.0, 20.0) + stroke(1e9, 20.0))
    alone = write_csv(tmp_path / "alone.csv", stroke(1e9, 20.0))
    doc = run_replay(scene, str(both), tmp_path / "both", progress=False)
    assert doc["trace"]["gaps"] == {"limit_s": 5.0, "count": 1, "skipped_s": pytest.approx(1e9, rel=1e-9)}
    assert any("taken as lifts" in w for w in doc["warnings"])
    run_replay(scene, str(alone), tmp_path / "alone", progress=False)
    got = np.loadtxt(tmp_path / "both" / "commands.csv", delimiter=",", skiprows=1)
    ref = np.loadtxt(tmp_path / "alone" / "commands.csv", delimiter=",", skiprows=1)
    first = 0.38 + 0.1  # the first stroke (0.38 s) and the kept 0.1 s after it
    assert got.shape[0] == doc["output"]["samples"]
    assert got.shape[0] < (first + 0.1 + ref.shape[0] / 1e4 + 0.02) * 1e4
    # bit for bit but on the samples straddling a grating line, which play its two sides in
    # proportion (rendering.layers.band_limit): near 1e9 s time is resolved to 1.2e-7 s,
    # 5 nm at 40 mm/s, up to 1e-6 of a period in a sample's 8e-5 (a 1 % shift of the split)
    tail = got[-ref.shape[0]:, 1]
    level = (np.diff(ref[:, 1], prepend=np.nan) == 0) | (np.diff(ref[:, 1], append=np.nan) == 0)
    assert np.count_nonzero(~level) < 0.01 * level.size
    np.testing.assert_array_equal(tail[level], ref[level, 1])
    np.testing.assert_allclose(tail, ref[:, 1], rtol=0.01)
    assert np.all(np.diff(got[:, 0]) > 0)  # time runs forward, jumping once


def test_a_finger_held_over_a_long_gap_is_lifted_at_its_start(tmp_path):
    """No up before the gap: the finger is lifted where the gap starts (not held touching
    for the whole gap), and touches again with the next sample."""
    rows = stroke(0.0, 20.0)[:-1] + [r.replace(",move", ",move") for r in stroke(60.0, 40.0)[1:]]
    trace = write_csv(tmp_path / "held.csv", rows)
    doc = run_replay(load_scene(resolve_scene("grating-5mm")), str(trace), tmp_path / "o",
                     progress=False, max_gap_s=5.0)
    friction = np.loadtxt(tmp_path / "o" / "friction.csv", delimiter=",", skiprows=1)
    assert doc["trace"]["gaps"]["count"] == 1
    assert friction[:, 0].max() > 60.0 and not np.any((friction[:, 0] > 1.0) & (friction[:, 0] < 59.0))


def test_outputs_that_would_not_fit_the_disk_are_refused_before_writing(tmp_path, monkeypatch, capsys):
    """The outputs' size is estimated from the trace before anything is written."""
    import shutil
    from collections import namedtuple

    from frictex.app.commands.cli import main
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(10 << 30, 0, 100 << 20))
    assert main(["replay", SCENE, TRACE, "--out", str(tmp_path / "fits"), "--quiet"]) == 0
    assert main(["replay", SCENE, TRACE, "--out", str(tmp_path / "big"), "--rate", "1e6"]) == 1
    err = capsys.readouterr().err.strip().splitlines()
    # the trace's 5 s and two blocks of 5 ms after it
    assert len(err) == 1 and "the outputs (5.01 s at 1e+06 Hz" in err[0] and "is free" in err[0]
    assert sorted(p.name for p in tmp_path.iterdir()) == ["fits"]  # nothing made for "big"


def test_a_disk_filling_up_mid_run_fails_loudly_and_leaves_nothing(tmp_path, monkeypatch):
    """Free space is checked before every batch: a run that outgrows the disk stops with
    one clear error, not a half-written file."""
    import shutil
    from collections import namedtuple

    from frictex.app.engine import tables
    usage = namedtuple("usage", "total used free")
    free = iter([1 << 40] * 3 + [1 << 20] * 100)  # plenty for the estimate, then full
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(1 << 41, 0, next(free)))
    monkeypatch.setattr(tables, "BATCH_ROWS", 5000)
    scene = load_scene(resolve_scene(SCENE))
    with pytest.raises(OSError, match=r"the next \d+ rows of .* need about"):
        run_replay(scene, resolve_trace(TRACE), tmp_path, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == []


def taps(n_touch, same_id):
    """``n_touch`` strokes one after another, each with its own id unless ``same_id``."""
    from frictex.rendering.input.trace_file import Trace
    t, f, x, ev = [], [], [], []
    for k in range(n_touch):
        for i in range(8):
            t.append(k * 0.2 + i / 60)
            f.append(0 if same_id else k)
            x.append(20.0 + (k % 50) + 0.5 * i)
            ev.append(0 if i == 0 else (2 if i == 7 else 1))
    t = np.array(t)
    return Trace(t, np.array(f, np.int64), np.array(x), np.full(t.size, 32.4),
                 np.full(t.size, 0.5), np.array(ev, np.int8))


def test_cost_follows_the_fingers_touching_not_the_ids_ever_seen():
    """Android's tracking ids grow with every touch: 300 touches one after another with
    300 ids give the commands of the same touches with one id, and no block carries more
    than the one finger touching (a lifted finger is forgotten once its lift is out)."""
    scene = load_scene(resolve_scene(SCENE))
    runs = {}
    for same in (True, False):
        trace = taps(300, same)
        pipeline = build_pipeline(scene, 10_000.0, 50, t0_s=0.0)
        source = TraceSource(iter([trace]))
        source.first_time()
        source.start(pipeline.tracker_config)
        memory = MemorySink()
        stage = PipelineStage(pipeline)
        drive(stage, source, [memory], VirtualClock(), chunk_blocks=1)
        runs[same] = memory.outs
        assert max(len(o.finger_ids) for o in memory.outs) == 1
        assert len(stage.state.tracker.fingers) == 0  # all lifted at the end
    # a re-touch of the same id and a new id take rounding-different paths (1e-15 um)
    np.testing.assert_allclose(np.concatenate([o.commands_um for o in runs[True]]),
                               np.concatenate([o.commands_um for o in runs[False]]), atol=1e-12)


def _by_source(trace, chunk_blocks):
    """``trace`` replayed on the run engine, ``chunk_blocks`` blocks per call."""
    pipeline = build_pipeline(load_scene(resolve_scene(SCENE)), 10_000.0, 50, t0_s=0.0)
    source = TraceSource(iter([trace]))
    source.first_time()
    source.start(pipeline.tracker_config)
    memory = MemorySink()
    drive(PipelineStage(pipeline), source, [memory], VirtualClock(), chunk_blocks=chunk_blocks)
    return memory.outs


def _in_one_call(trace, blocks):
    """``trace`` through the pipeline in one call, no source: a row per recording id."""
    pipeline = build_pipeline(load_scene(resolve_scene(SCENE)), 10_000.0, 50, t0_s=0.0)
    out, _ = pipeline.process(0, trace, pipeline.initial_state(), n_blocks=blocks)
    return out


def _rows(outs):
    from frictex.app.engine.sinks import friction_rows
    rows = [friction_rows(o) for o in outs]
    return {k: np.concatenate([r[k] for r in rows]) for k in rows[0]}


def _assert_same_rows(outs, reference):
    got, want = _rows(outs), _rows([reference])
    np.testing.assert_array_equal(got["finger"], want["finger"])
    np.testing.assert_array_equal(got["t_s"], want["t_s"])
    # a grating's phase summed over a call's samples rounds differently in a row touched
    # again than in a new one (2.8e-12 seen): equal to 1e-9, far below what a plate renders
    for k in ("x_mm", "y_mm", "mu_target", "amplitude_um"):
        np.testing.assert_allclose(got[k], want[k], rtol=0, atol=1e-9, err_msg=k)
    np.testing.assert_allclose(np.concatenate([o.commands_um for o in outs]),
                               reference.commands_um, rtol=0, atol=1e-9)


def test_long_calls_keep_the_rows_of_the_fingers_touching_and_the_recordings_ids():
    """A replay's calls span thousands of blocks; with a new id per touch each would carry
    a row per id it saw. The source gives a touch the row of a finger that lifted: 25
    taps with 25 ids in calls of up to 2000 blocks run on one row, and the friction table
    (finger ids included) and the commands equal those of the pipeline run in one call
    with a row per id, computed without the source."""
    trace = taps(25, False)
    outs = _by_source(trace, 2000)
    assert max(len(o.finger_ids) for o in outs) == 1
    assert len(outs) <= 3
    assert any(o.sample_ids is not None for o in outs)
    reference = _in_one_call(trace, sum(o.t_s.size for o in outs) // 50)
    assert len(reference.finger_ids) == 25
    _assert_same_rows(outs, reference)


def test_a_lift_and_the_next_touch_in_one_block_do_not_share_a_row():
    """Two fingers overlapping, ids new and reused, a touch and another finger's lift
    just after it in the same 5 ms block (in a shared row the lift would end the touch):
    per-id results equal the one-call reference, and no call needs more rows than fingers
    touch at once plus the one lifting in the block another touches."""
    from frictex.rendering.input.trace_file import Trace
    # (id, start s, samples at 100 Hz); 3 touches at 0.19005 s, 7 lifts at 0.1901 s, in
    # one block: in one row the lift would follow the touch
    strokes = [
        (7, 0.0001, 20), (9, 0.050, 30), (7, 0.300, 10), (3, 0.19005, 10), (11, 0.3505, 6),
        (9, 0.6000, 5), (4, 0.6001, 5)]
    t, f, x, y, ev = [], [], [], [], []
    for fid, start, count in strokes:
        for i in range(count):
            t.append(start + i * 0.01)
            f.append(fid)
            x.append(10.0 + fid + 0.4 * i)
            y.append(20.0 + 2 * fid)
            ev.append(0 if i == 0 else (2 if i == count - 1 else 1))
    order = np.argsort(t, kind="stable")
    trace = Trace(np.array(t)[order], np.array(f, np.int64)[order], np.array(x)[order],
                  np.array(y)[order], np.full(len(t), 0.5), np.array(ev, np.int8)[order])
    for chunk in (1, 7, 2000):
        outs = _by_source(trace, chunk)
        assert max(len(o.finger_ids) for o in outs) <= 3
        reference = _in_one_call(trace, sum(o.t_s.size for o in outs) // 50)
        _assert_same_rows(outs, reference)


@pytest.mark.parametrize("make, code", [
    (lambda: __import__("frictex.device.link.host", fromlist=["LinkStalled"]).LinkStalled("stalled"), 1),
    (lambda: OSError(28, "No space left on device"), 1),
    (lambda: OSError(2, "No such file or directory", "trace.csv"), 2),
    (lambda: __import__("frictex.device.errors", fromlist=["InputError"]).InputError("bad trace"), 2),
])
def test_exit_status_says_bad_input_or_a_run_that_could_not_finish(monkeypatch, capsys, make, code):
    from frictex.app.commands import cli, library
    def fail(args):
        raise make()
    monkeypatch.setattr(library, "run", fail)
    assert cli.main(["library"]) == code
    assert capsys.readouterr().err.startswith("frictex: error:")


def test_finger_roles_hold_across_blocks_as_in_one_call():
    """Positional roles (left-most ...) have hysteresis: who holds a role is carried from
    block to block, so live (one block a call) gives what one long call gives."""
    scene = load_scene(resolve_scene("two-finger-plate-seed001"))
    t = np.arange(0.0, 1.0, 0.02)
    rows = []
    for f, (x0, dx, y) in enumerate(((40.0, 60.0, 75.0), (100.0, -60.0, 45.0))):
        for i, ti in enumerate(t):
            rows.append((ti, f, x0 + dx * ti, y, 0 if i == 0 else (2 if i == t.size - 1 else 1)))
    rows.sort(key=lambda r: (r[0], r[1]))
    from frictex.rendering.input.trace_file import Trace
    a = np.array(rows)
    trace = Trace(a[:, 0], a[:, 1].astype(np.int64), a[:, 2], a[:, 3], np.full(len(rows), 0.5),
                  a[:, 4].astype(np.int8))
    results = {}
    for chunk in (1, 400):
        pipeline = build_pipeline(scene, 10_000.0, 50, render_override="sho-predicted")
        source = TraceSource(iter([trace]))
        source.first_time()
        source.start(pipeline.tracker_config)
        memory = MemorySink()
        drive(PipelineStage(pipeline), source, [memory], VirtualClock(), chunk_blocks=chunk)
        results[chunk] = np.concatenate([o.mu_target for o in memory.outs], axis=1)
    np.testing.assert_array_equal(results[1], results[400])


@pytest.mark.parametrize("sig, raised", [(signal.SIGINT, KeyboardInterrupt), (signal.SIGTERM, SystemExit)])
def test_a_signal_is_held_until_the_loop_checks(sig, raised):
    """Ctrl-C (or SIGTERM) during a step is held until ``check()``, between steps, where
    no compiled kernel runs; a second one raises at once; the handlers are restored."""
    from frictex.app.engine.driver import deferred_interrupts
    before = signal.getsignal(sig)
    with pytest.raises(raised) as caught:
        with deferred_interrupts() as check:
            os.kill(os.getpid(), sig)
            time.sleep(0.01)  # the handler has run: held, nothing raised
            with pytest.raises(raised):
                os.kill(os.getpid(), sig)
                time.sleep(1.0)
            check()
    if raised is SystemExit:
        assert caught.value.code == 128 + sig
    assert signal.getsignal(sig) is before


def test_an_ignored_signal_stays_ignored():
    """Under ``nohup`` SIGHUP is ignored: holding it would end a run the user meant to
    outlive the terminal."""
    from frictex.app.engine.driver import deferred_interrupts
    before = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        with deferred_interrupts() as check:
            assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
            os.kill(os.getpid(), signal.SIGHUP)
            check()  # nothing held
        assert signal.getsignal(signal.SIGHUP) is signal.SIG_IGN
    finally:
        signal.signal(signal.SIGHUP, before)


def test_signals_during_the_commit_are_held_and_dropped_once_it_succeeds():
    from frictex.app.engine.driver import deferred_interrupts
    done = []
    before = signal.signal(signal.SIGINT, signal.SIG_DFL)  # nothing to pass them on to
    try:
        with deferred_interrupts() as check:
            with check.committing():
                os.kill(os.getpid(), signal.SIGINT)
                os.kill(os.getpid(), signal.SIGINT)  # a second one: held too
                done.append(len(check.held))
    finally:
        signal.signal(signal.SIGINT, before)
    assert done == [2] and check.dropped == [signal.SIGINT, signal.SIGINT]
    with pytest.raises(KeyboardInterrupt):  # before the commit, a held one still raises
        with deferred_interrupts() as check:
            os.kill(os.getpid(), signal.SIGINT)
            with check.committing():
                done.append("committed")
    assert done == [2]


def test_once_the_run_is_ending_further_signals_are_held():
    """Once a held signal has been raised (or an error ends the run: ``check.end()``),
    more signals are held, not raised, so that the cleanup runs to its end (a batch
    worker whose parent dies can get several SIGINTs); the first is raised as the run
    ends."""
    from frictex.app.engine.driver import deferred_interrupts
    cleaned = []
    with pytest.raises(KeyboardInterrupt):
        with deferred_interrupts() as check:
            os.kill(os.getpid(), signal.SIGINT)
            try:
                check()
            except KeyboardInterrupt:
                os.kill(os.getpid(), signal.SIGINT)
                os.kill(os.getpid(), signal.SIGINT)
                time.sleep(0.05)  # the handler has run twice: held
                cleaned.append(len(check.held))
    assert cleaned == [3]
    with pytest.raises(SystemExit) as caught:  # an error ends the run: signals held
        with deferred_interrupts() as check:
            try:
                raise ValueError("the run failed")
            except ValueError:
                check.end()
                os.kill(os.getpid(), signal.SIGTERM)
                os.kill(os.getpid(), signal.SIGTERM)
                time.sleep(0.05)
                cleaned.append(len(check.held))
    assert cleaned == [3, 2] and caught.value.code == 128 + signal.SIGTERM


def test_brief_taps_within_a_block_share_a_row_with_the_same_results():
    """Taps that touch and lift within one 5 ms block (10 us each, a new id each, 200
    of them between two strokes) show at no output sample: they share rows, so no call
    carries more rows than fingers touch at once plus one lifting (they took a row each
    before), and the friction table and commands equal the one-call reference's."""
    from frictex.rendering.input.trace_file import Trace
    t, f, x, ev = [], [], [], []
    for i in range(8):  # a stroke, then 200 brief taps, then a stroke over them
        t.append(0.001 + i / 100)
        f.append(1)
        x.append(20.0 + i)
        ev.append(0 if i == 0 else (2 if i == 7 else 1))
    for k in range(200):
        for j, e in enumerate((0, 2)):
            t.append(0.1001 + k * 2e-5 + j * 1e-5)
            f.append(1000 + k)
            x.append(30.0 + k % 7)
            ev.append(e)
    for i in range(8):
        t.append(0.1002 + i / 100 + 1e-6)
        f.append(2)
        x.append(25.0 + i)
        ev.append(0 if i == 0 else (2 if i == 7 else 1))
    order = np.argsort(t, kind="stable")
    trace = Trace(np.array(t)[order], np.array(f, np.int64)[order], np.array(x)[order],
                  np.full(len(t), 32.4), np.full(len(t), 0.5), np.array(ev, np.int8)[order])
    for chunk in (1, 2000):
        outs = _by_source(trace, chunk)
        assert max(len(o.finger_ids) for o in outs) <= 3
        _assert_same_rows(outs, _in_one_call(trace, sum(o.t_s.size for o in outs) // 50))


def test_targets_that_are_not_finite_are_a_warning_saying_what_was_commanded():
    """The inversion commands 0 um for a NaN or inf target and counts it (device.friction);
    the run says so, where it said nothing."""
    from types import SimpleNamespace
    from frictex.app.engine.summary import Totals, warnings_of
    totals = Totals()
    totals.clamps.nonfinite_target = 7
    assert warnings_of(SimpleNamespace(forces=None), SimpleNamespace(jumps=0, out_of_order=0),
                       totals) == ["7 target samples were not finite (NaN or inf) and were "
                                   "commanded 0 um"]


@pytest.mark.parametrize("device, words", [
    ("[device.calibration]\namplitudes_um = [0.0, 1.0, 2.0, 3.0]\nforces_n = [0.3, 0.6]\n"
     "mu = [[1.0, 0.8, 0.6, 0.5], [1.0, 0.85, 0.7, 0.6]]\n",
     "had a normal force outside the calibration's measured forces (0.3 to 0.6 N): the "
     "nearest measured force's row was used"),
    ("[device.friction]\nasymptote_per_n = 0.5\n",
     "had a normal force beyond seed 003's friction model, whose asymptote 0.5 F_n reaches 1 "
     "there (full amplitude was commanded)")])
def test_the_warning_for_a_press_beyond_the_friction_model_names_the_model_in_use(
        tmp_path, device, words):
    """A 2.5 N press on a grating: beyond a calibration's forces (0.3-0.6 N), and beyond
    seed 003's model once k F_n >= 1 (k = 0.5 /N). Only the grating's low-friction
    samples (mu' 0.6 < 1) count; the warning says what the device's own model did."""
    text = resolve_scene("grating-5mm").read_text().replace("normal_force_n = 0.5\n",
                                                           "normal_force_n = 0.5\n" + device)
    (tmp_path / "s.toml").write_text(text)
    rows = [r.replace(",0.5,", ",2.5,") for r in stroke(0.0, 20.0, n=50)]
    trace = write_csv(tmp_path / "press.csv", rows)
    doc = run_replay(load_scene(tmp_path / "s.toml"), str(trace), None, fmt="memory",
                     progress=False)
    beyond = doc["clamps"]["force_beyond_model"]
    assert 0 < beyond < doc["output"]["samples"]
    assert f"{beyond} samples {words}" in doc["warnings"]
    assert doc["clamps"]["unreachable"] == 0


@pytest.mark.parametrize("rate_hz, samples", [(100.0, 1), (10_000.0, 50), (1e6, 5000)])
def test_a_block_is_5_ms_whatever_the_rate_unless_given(tmp_path, rate_hz, samples):
    """Touch samples take effect at block boundaries: a block of 50 samples at 100 Hz
    held each touch for up to 0.5 s. Without --block a block is 5 ms of samples (at
    least one), in the replay, the Python API and a batch job."""
    import frictex
    from frictex.app.engine.batch import read_manifest
    from frictex.rendering.renderers import render_modes
    trace = write_csv(tmp_path / "t.csv", stroke(0.0, 20.0, n=10))
    doc = run_replay("grating-5mm", str(trace), None, fmt="memory", rate_hz=rate_hz,
                     progress=False)
    assert doc["output"]["block_size"] == samples
    assert frictex.replay("grating-5mm", str(trace),
                          rate_hz=rate_hz).summary.output.block_size == samples
    manifest = tmp_path / "m.csv"
    manifest.write_text(f"scene,trace,rate_hz\ngrating-5mm,{trace},{rate_hz:g}\n")
    job, = read_manifest(manifest, render_modes())
    assert run_replay(job.scene, job.trace, None, fmt="memory", rate_hz=job.rate_hz,
                      block_size=job.block, progress=False)["output"]["block_size"] == samples
    assert run_replay("grating-5mm", str(trace), None, fmt="memory", rate_hz=rate_hz,
                      block_size=7, progress=False)["output"]["block_size"] == 7
