"""Headless replay: outputs as DESIGN.md says, deterministic, complete or absent."""

import json

import numpy as np
import pytest

from frictex.app.engine.replay import run_replay
from frictex.rendering.input.trace_synth import make_motion, sample
from scenes import grating_scene


@pytest.fixture(scope="module")
def human_trace():
    return sample(make_motion("human", speed_mm_s=80.0, duration_s=3.0, seed=5), 120.0,
                  noise_mm=0.05, seed=5)


def _read_csv(path):
    return np.genfromtxt(path, delimiter=",", names=True)


def test_outputs_have_the_documented_columns(tmp_path, human_trace):
    summary = run_replay(grating_scene(5.0, render="sht"), human_trace, tmp_path, progress=False)
    commands = (tmp_path / "commands.csv").read_text().splitlines()
    friction = (tmp_path / "friction.csv").read_text().splitlines()
    assert commands[0] == "t_s,ch0_um"
    assert friction[0] == "t_s,finger,x_mm,y_mm,mu_target,amplitude_um"
    assert len(commands) - 1 == summary["output"]["samples"] == 50 * summary["counts"]["blocks"]
    assert len(friction) - 1 == summary["counts"]["contact_samples"]
    on_disk = json.loads((tmp_path / "summary.json").read_text())
    assert on_disk["clamps"] == summary["clamps"]
    assert set(on_disk["timings"]["stages_s"]) == {"tracking", "layers", "composition",
                                                   "inversion", "actuation"}


@pytest.mark.parametrize("fmt", ["csv", "npz", "parquet"])
def test_replaying_twice_is_byte_identical(tmp_path, human_trace, monkeypatch, fmt):
    """In every format, whenever each is written: the second replay runs a day later by
    the clock (npz members carried the time of writing)."""
    import time
    scene = grating_scene(0.6, render="sht")
    a = run_replay(scene, human_trace, tmp_path / "a", fmt=fmt, progress=False)
    real_time = time.time
    monkeypatch.setattr(time, "time", lambda: real_time() + 86_400.0)
    b = run_replay(scene, human_trace, tmp_path / "b", fmt=fmt, progress=False)
    for name in (f"commands.{fmt}", f"friction.{fmt}"):
        assert (tmp_path / "a" / name).read_bytes() == (tmp_path / "b" / name).read_bytes()
    a.pop("timings"), b.pop("timings")
    assert a == b


def test_npz_holds_the_same_columns_as_csv(tmp_path, human_trace):
    scene = grating_scene(5.0)
    run_replay(scene, human_trace, tmp_path / "csv", progress=False)
    run_replay(scene, human_trace, tmp_path / "npz", fmt="npz", progress=False)
    for stem in ("commands", "friction"):
        table = _read_csv(tmp_path / "csv" / f"{stem}.csv")
        with np.load(tmp_path / "npz" / f"{stem}.npz") as npz:
            assert list(npz.files) == list(table.dtype.names)
            for name in npz.files:
                # the CSV rounds (t_s to 0.1 us, um to 1 pm, mm to 0.1 um); npz is exact
                np.testing.assert_allclose(npz[name], table[name], atol=6e-5)


def test_a_failed_replay_leaves_no_partial_outputs(tmp_path, human_trace):
    class BrokenSink:
        closed = False

        def send(self, index, amplitudes, phases):
            raise OSError("port vanished")

        def close(self):
            self.closed = True

    sink = BrokenSink()
    with pytest.raises(OSError, match="port vanished"):
        run_replay(grating_scene(5.0), human_trace, tmp_path, sink=sink, progress=False)
    assert sorted(p.name for p in tmp_path.iterdir()) == []
    assert sink.closed


def test_sink_receives_every_block_in_order(tmp_path, human_trace):
    class Recorder:
        def __init__(self):
            self.blocks = []

        def send(self, index, amplitudes, phases):
            self.blocks.append((index, amplitudes.copy()))

        def status(self):
            return {"state": "closed" if self.closed else "open", "blocks_sent": len(self.blocks)}

        def close(self):
            self.closed = True

    sink = Recorder()
    sink.closed = False
    summary = run_replay(grating_scene(5.0), human_trace, tmp_path, sink=sink, progress=False)
    assert [i for i, _ in sink.blocks] == list(range(0, summary["output"]["samples"], 50))
    sent = np.concatenate([a[:, 0] for _, a in sink.blocks])
    written = _read_csv(tmp_path / "commands.csv")["ch0_um"]
    np.testing.assert_allclose(sent, written, atol=5e-7)
    assert summary["device"] == {"state": "closed", "blocks_sent": len(sink.blocks)}


def test_a_trace_read_in_small_chunks_replays_identically(tmp_path, monkeypatch):
    """Replay streams the trace (bounded memory): chunk boundaries change nothing."""
    import frictex.app.engine.replay as replay_module
    from frictex.rendering.input.trace_file import iter_trace

    trace = "two-fingers-crossing-50hz"
    run_replay("two-finger-beam-seed000", trace, tmp_path / "whole", progress=False)
    monkeypatch.setattr(replay_module, "iter_trace", lambda path, strict=False: iter_trace(path, chunk_rows=7, strict=strict))
    run_replay("two-finger-beam-seed000", trace, tmp_path / "chunked", progress=False)
    for name in ("commands.csv", "friction.csv"):
        assert (tmp_path / "whole" / name).read_bytes() == (tmp_path / "chunked" / name).read_bytes()
