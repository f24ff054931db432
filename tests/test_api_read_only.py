"""What the library hands a caller cannot be changed behind its back: a summary's
mappings, a Replay's attributes, a trace's and a pipeline output's arrays; and those
arrays are typed by their dtype (mypy --strict sees float64 and bool, not Any)."""

import json
import os
import pickle
import subprocess
import sys

import numpy as np
import pytest

import frictex

SCENE = "grating-5mm"


@pytest.fixture(scope="module")
def run():
    trace = frictex.synth_trace("swipe", duration_s=0.3, rate_hz=60.0)
    return frictex.replay(SCENE, trace)


def _mappings(summary):
    timings = summary.timings
    return {"fingers": summary.fingers, "layer_clipped": summary.layer_clipped,
            "loop_s": timings.loop_s, "stages_s": timings.stages_s,
            "layers_s": timings.layers_s}


@pytest.mark.parametrize("name", ["fingers", "layer_clipped", "loop_s", "stages_s", "layers_s"])
def test_a_summary_mapping_cannot_be_changed_nor_reach_to_dict(run, name):
    before = run.summary.to_dict()
    mapping = _mappings(run.summary)[name]
    with pytest.raises(TypeError, match="read-only"):
        mapping[99] = 1
    with pytest.raises(TypeError, match="read-only"):
        mapping.update({"x": 1})
    assert run.summary.to_dict() == before


def test_to_dict_is_plain_copies_a_caller_may_change(run):
    doc = run.summary.to_dict()
    assert type(doc["timings"]["loop_s"]) is dict and type(doc["fingers"]) is dict
    doc["timings"]["loop_s"]["x"] = 1.0
    assert "x" not in run.summary.timings.loop_s
    assert json.loads(json.dumps(run.summary.to_dict())) == run.summary.to_dict()


def test_nested_sections_are_read_only_dicts_json_and_pickle_take():
    doc = frictex.replay(SCENE, frictex.synth_trace("swipe", duration_s=0.2, rate_hz=60.0)).summary.to_dict()
    doc["device"] = {"commanded_samples": 10, "unplayed_by_cause": {"stall": 2}, "lost": [1, 2]}
    summary = frictex.Summary.from_dict(doc)
    device = summary.device
    assert isinstance(device, dict)
    with pytest.raises(TypeError, match="read-only"):
        device["unplayed_by_cause"]["stall"] = 0
    assert device["lost"] == [1, 2]  # a list still, equal to summary.json's (was a tuple)
    with pytest.raises(TypeError, match="read-only"):
        device["lost"].append(3)
    top = dict(device)  # one level copied: what is inside stays read-only, and says so
    top["commanded_samples"] = 0
    with pytest.raises(TypeError, match=r"to_dict\(\) \(dict\(...\) and list\(...\) copy one level"):
        top["unplayed_by_cause"]["stall"] = 0
    assert json.loads(json.dumps(device)) == doc["device"]
    assert summary.to_dict() == doc
    again = pickle.loads(pickle.dumps(summary))
    assert again == summary
    with pytest.raises(TypeError, match="read-only"):
        again.device["commanded_samples"] = 0


@pytest.mark.parametrize("name", ["out", "summary", "friction", "commands"])
def test_a_replays_attributes_cannot_be_reassigned(run, name):
    kept = getattr(run, name)
    with pytest.raises(AttributeError):
        setattr(run, name, None)
    assert getattr(run, name) is kept


def test_a_replays_tables_are_read_from_its_folder_once(tmp_path):
    r = frictex.replay(SCENE, frictex.synth_trace("swipe", duration_s=0.2, rate_hz=60.0),
                       out=tmp_path)
    assert r.friction is r.friction and r.commands.num_rows > 0


def test_make_trace_copies_its_inputs_and_its_arrays_are_read_only():
    t = np.linspace(0.0, 0.5, 31)
    x = np.linspace(10.0, 30.0, 31)
    trace = frictex.make_trace(t, np.zeros(31, dtype=np.int64), x, np.full(31, 20.0))
    assert not np.shares_memory(trace.x_mm, x) and not np.shares_memory(trace.t_s, t)
    x[5] = np.nan
    assert np.isfinite(trace.x_mm[5])
    for name in ("t_s", "finger", "x_mm", "y_mm", "force_n", "event"):
        with pytest.raises(ValueError, match="read-only"):
            getattr(trace, name)[0] = 0


def test_a_trace_built_from_lists_holds_read_only_arrays_and_has_a_length():
    trace = frictex.Trace([0.0], [0], [1.0], [1.0], [0.5], [0])
    assert len(trace) == 1
    assert all(isinstance(a, np.ndarray) and not a.flags.writeable
               for a in (trace.t_s, trace.finger, trace.x_mm, trace.y_mm, trace.force_n,
                         trace.event))


def test_a_trace_built_from_arrays_leaves_the_callers_arrays_writeable():
    x = np.array([1.0, 2.0])
    frictex.Trace(np.array([0.0, 0.1]), np.array([0, 0]), x, x.copy(), np.full(2, 0.5),
                  np.array([0, 2], dtype=np.int8))
    x[0] = 3.0  # a view was made read-only, not the caller's array


def test_a_pipeline_outputs_arrays_are_all_read_only():
    trace = frictex.synth_trace("swipe", duration_s=0.3, rate_hz=60.0)
    pipe = frictex.build_pipeline(SCENE)
    out = pipe.process(trace)
    arrays = ("t_s", "contact", "x_mm", "y_mm", "mu_target", "wanted_um", "amplitude_um",
              "commands_um")
    assert [name for name in arrays if getattr(out, name).flags.writeable] == []
    again = pipe.process(trace)  # the pipeline writes into none of them
    assert all(np.array_equal(getattr(out, name), getattr(again, name)) for name in arrays)


TYPED_SCRIPT = '''\
import numpy as np
import numpy.typing as npt

import frictex


def wrong(out: frictex.BlockOutput, trace: frictex.Trace) -> None:
    commands: npt.NDArray[np.int64] = out.commands_um
    contact: npt.NDArray[np.float64] = out.contact
    x: npt.NDArray[np.int64] = trace.x_mm
    finger: npt.NDArray[np.float64] = trace.finger
'''


def test_array_fields_are_typed_by_dtype(tmp_path):
    """Bare ``np.ndarray`` fields (dtype Any) took any of these assignments."""
    pytest.importorskip("mypy", reason="mypy is not installed (pip install 'frictex[test]')")
    script = tmp_path / "typed.py"
    script.write_text(TYPED_SCRIPT, encoding="utf-8")
    done = _mypy(tmp_path, script)
    lines = [line.split(":")[1] for line in done.stdout.splitlines() if ": error:" in line]
    assert lines == ["8", "9", "10", "11"], done.stdout + done.stderr


def _mypy(tmp_path, script):
    """mypy --strict on ``script`` against the source tree (as tests/test_typing.py)."""
    from test_typing import source_tree
    env = {**os.environ, "MYPYPATH": str(source_tree(tmp_path / "src"))}
    env.pop("PYTHONPATH", None)
    return subprocess.run([sys.executable, "-m", "mypy", "--strict", "--follow-imports=silent",
                           "--no-error-summary", "--cache-dir", str(tmp_path / "cache"),
                           script.name], capture_output=True, text=True, env=env,
                          cwd=script.parent, timeout=300)
