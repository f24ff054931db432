"""The public API, frictex: cheap to import, typed results equal to what the command writes."""

import json
import subprocess
import sys

import numpy as np
import pytest

import frictex
from frictex.app.commands.cli import main

SCENE, TRACE = "grating-5mm", "swipe-40mms-50hz"


def run_python(code: str, cwd) -> str:
    done = subprocess.run([sys.executable, "-c", code], cwd=cwd, capture_output=True,
                          text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    return done.stdout


def test_import_frictex_loads_no_numeric_library(tmp_path):
    out = run_python("import sys, frictex; print(sorted(m for m in ('numpy', 'numba', 'scipy', "
                     "'pyarrow', 'frictex.app') if m in sys.modules))", tmp_path)
    assert out.strip() == "[]"


def test_the_issue_s_one_line_works_as_written(tmp_path):
    out = run_python("import frictex; r = frictex.replay('grating-5mm', 'swipe-40mms-50hz'); "
                     "print(r.friction.num_rows, r.summary.to_dict()['timings'])", tmp_path)
    rows, timings = out.split(" ", 1)
    assert int(rows) > 0
    assert "'x_realtime_end_to_end': " in timings and "'stages_s': {" in timings
    assert list(tmp_path.iterdir()) == []  # in memory: nothing written


def test_every_public_name_resolves_and_is_documented():
    for name in frictex.__all__:
        value = getattr(frictex, name)
        assert value.__doc__, name
    with pytest.raises(AttributeError, match="no attribute 'nope'"):
        frictex.nope  # noqa: B018


def test_all_is_the_lazy_table_and_dir_the_public_names():
    """``__all__`` is written out for type checkers; it must name exactly what
    ``__getattr__`` imports. ``dir`` lists those, not the module's helpers."""
    assert frictex.__all__ == sorted(frictex._WHERE)
    public = [name for name in dir(frictex) if not name.startswith("__")]
    assert public == sorted({*frictex.__all__, *frictex._LAYERS})  # the layers: tab completion
    assert "__version__" in dir(frictex)


@pytest.mark.parametrize("scene, trace", [(SCENE, TRACE), ("keyclick-ring", "keyclick-press-100hz")])
def test_the_typed_summary_is_summary_json_exactly(tmp_path, scene, trace):
    r = frictex.replay(scene, trace, out=tmp_path / "o", format="npz")
    text = (tmp_path / "o" / "summary.json").read_text(encoding="utf-8")
    assert json.dumps(r.summary.to_dict(), indent=2) + "\n" == text
    assert isinstance(r.summary, frictex.Summary) and isinstance(r.summary.clamps, frictex.Clamps)
    assert r.summary.output.files == ("commands.npz", "friction.npz")
    assert r.summary.clamps.total == sum(json.loads(text)["clamps"].values())
    assert frictex.Summary.from_dict(json.loads(text)) == r.summary


def test_tables_in_memory_are_the_command_s_files(tmp_path, capsys):
    """In memory, the tables hold exactly what `frictex replay --format parquet` writes,
    and what a Replay with a folder reads back."""
    memory = frictex.replay(SCENE, TRACE)
    assert memory.out is None and memory.summary.output.format == "memory"
    assert memory.summary.output.files == ()
    assert main(["replay", SCENE, TRACE, "--out", str(tmp_path / "cli"), "--format", "parquet",
                 "--quiet"]) == 0
    on_disk = frictex.replay(SCENE, TRACE, out=tmp_path / "api", format="parquet")
    import pyarrow.parquet as pq
    for stem in ("friction", "commands"):
        written = pq.read_table(tmp_path / "cli" / f"{stem}.parquet")
        assert getattr(memory, stem).equals(written)
        assert getattr(on_disk, stem).equals(written)


def test_a_pipeline_runs_a_whole_trace_as_a_replay_does():
    scene = frictex.load_scene(SCENE)
    trace = frictex.read_trace(TRACE)
    out = frictex.build_pipeline(scene).process(trace)
    r = frictex.replay(scene, trace)
    assert out.commands_um.shape == (r.summary.output.samples, 1)
    np.testing.assert_array_equal(out.commands_um[:, 0], r.commands.column("ch0_um").to_numpy())
    np.testing.assert_array_equal(out.t_s, r.commands.column("t_s").to_numpy())


def test_synth_trace_makes_what_the_command_writes(tmp_path, capsys):
    assert main(["trace", "synth", "circle", "--rate", "60", "--duration", "1.5", "--noise",
                 "0.05", "--seed", "3", "-o", str(tmp_path / "c.csv")]) == 0
    made = frictex.synth_trace("circle", rate_hz=60.0, duration_s=1.5, noise_mm=0.05, seed=3)
    read = frictex.read_trace(tmp_path / "c.csv")
    for name in ("t_s", "finger", "x_mm", "y_mm", "force_n", "event"):
        np.testing.assert_array_equal(getattr(made, name), getattr(read, name))
    press = frictex.synth_trace("press", peaks_n=(1.0,))
    assert press.force_n.max() > 0.8 and np.ptp(press.x_mm) == 0.0


def test_pandas_opens_the_tables():
    pd = pytest.importorskip("pandas")
    frame = frictex.replay(SCENE, TRACE).friction.to_pandas()
    assert isinstance(frame, pd.DataFrame) and list(frame.columns)[:2] == ["t_s", "finger"]


@pytest.mark.parametrize("call, message", [
    (lambda: frictex.replay(SCENE, TRACE, format="csv"), "kept in memory unless out"),
    (lambda: frictex.replay(SCENE, TRACE, out="o", format="xlsx"), "expected one of csv"),
    (lambda: frictex.synth_trace("zigzag"), "expected one of swipe, .*press"),
    (lambda: frictex.load_scene("no-such-scene"), "no-such-scene"),
    (lambda: frictex.read_trace("no-such-trace"), "no-such-trace"),
    (lambda: frictex.build_pipeline(frictex.load_scene(SCENE)).process(
        frictex.synth_trace("swipe").slice(0, 0)), "no samples"),
    (lambda: frictex.replay(SCENE, TRACE, strict="no"), r"^strict='no': expected True or False$"),
    (lambda: frictex.replay(SCENE, TRACE, progress=2), r"^progress=2: expected True or False$"),
    (lambda: frictex.read_trace(TRACE, strict="yes"), r"^strict='yes': expected True or False"),
    # Path("") is ".": an empty name was once refused as "a folder, not a file"
    (lambda: frictex.load_scene(""), r"^name_or_path='': the name is empty; expected a texture"),
    (lambda: frictex.read_trace(""), r"^path='': the name is empty; expected a trace CSV"),
    (lambda: frictex.replay("", TRACE), r"^scene='': the name is empty"),
    (lambda: frictex.replay(SCENE, ""), r"^trace='': the name is empty"),
    (lambda: frictex.replay(SCENE, TRACE, out=""), r"^out='': the name is empty"),
])
def test_bad_input_is_an_input_error(tmp_path, monkeypatch, call, message):
    monkeypatch.chdir(tmp_path)
    with pytest.raises(frictex.InputError, match=message):
        call()
    assert list(tmp_path.iterdir()) == []


def test_a_replay_never_reads_a_later_runs_tables(tmp_path, monkeypatch):
    """Its tables are read lazily from the folder, but only while the folder holds its
    run: after a later run into it, a RunFailed, never the other run's rows; and a
    relative folder still means the same one after os.chdir."""
    monkeypatch.chdir(tmp_path)
    first = frictex.replay(SCENE, TRACE, out="out")
    early = first.commands  # read now: kept
    monkeypatch.chdir(tmp_path.parent)
    assert first.out == tmp_path / "out"
    assert first.friction.num_rows > 0  # read after chdir, from the same folder
    second = frictex.replay(SCENE, "circle-30mms-60hz", out=tmp_path / "out", format="npz")
    third = frictex.replay(SCENE, "circle-30mms-60hz", out=tmp_path / "out2")
    (tmp_path / "out2" / "summary.json").write_text("{}")  # replaced by hand
    with pytest.raises(frictex.RunFailed, match="no longer holds this run"):
        third.friction
    assert first.commands is early
    assert second.friction.num_rows != first.friction.num_rows
    frictex.replay(SCENE, TRACE, out=tmp_path / "out", format="npz")
    with pytest.raises(frictex.RunFailed, match="no longer holds this run"):
        second.commands  # same format, same name: another run's table


@pytest.mark.parametrize("fmt, damage, reason", [
    ("csv", lambda path: path.unlink(), "is missing"),
    ("csv", lambda path: path.write_text('garbage\n"'),
     "cannot be read back: Casting field 'garbage'"),
    ("csv", lambda path: (path.unlink(), path.mkdir()), "cannot be read back: Is a directory"),
    ("npz", lambda path: path.write_bytes(path.read_bytes()[:100]), "cannot be read back: "),
    ("parquet", lambda path: path.write_bytes(b"garbage"), "cannot be read back: "),
])
def test_a_table_file_removed_or_damaged_since_is_named(tmp_path, fmt, damage, reason):
    """With summary.json untouched, a table file gone or damaged is a RunFailed in one line
    naming the file and what is wrong, not 'no longer holds this run' or a pyarrow error."""
    r = frictex.replay(SCENE, TRACE, out=tmp_path / "o", format=fmt)
    damage(tmp_path / "o" / f"friction.{fmt}")
    with pytest.raises(frictex.RunFailed) as caught:
        r.friction  # noqa: B018
    message = str(caught.value)
    assert message.startswith(f"{tmp_path / 'o' / f'friction.{fmt}'}: this run's friction "
                              f"table {reason}")
    assert "\n" not in message
    assert r.commands.num_rows > 0  # the other table still reads


def test_tables_read_back_from_a_folder_equal_the_tables_in_memory(tmp_path):
    in_memory = frictex.replay(SCENE, TRACE)
    for fmt in ("parquet", "npz", "csv"):
        written = frictex.replay(SCENE, TRACE, out=tmp_path / fmt, format=fmt)
        for stem in ("friction", "commands"):
            got, want = getattr(written, stem), getattr(in_memory, stem)
            assert got.schema.equals(want.schema)
            if fmt != "csv":
                assert got.equals(want)
            else:  # to its printed precision: t_s 7 decimals, the rest at least 4
                for a, b in zip(got.columns, want.columns):
                    np.testing.assert_allclose(a.to_numpy(), b.to_numpy(), rtol=0, atol=5.1e-5)


def test_process_runs_through_a_pause_that_a_replay_skips():
    """As Pipeline.process's docstring says: every output sample of the trace's span,
    a 20 s pause included (240,050 at 10 kHz), where replay skips the pause (42,050),
    the two the same up to the pause's start."""
    from frictex.rendering.input.trace_file import make_trace
    stroke = frictex.synth_trace("swipe", duration_s=2.0)
    twice = make_trace(np.concatenate([stroke.t_s, stroke.t_s + 22.0]),
                       np.concatenate([stroke.finger, stroke.finger + 1]),
                       np.concatenate([stroke.x_mm, stroke.x_mm]),
                       np.concatenate([stroke.y_mm, stroke.y_mm]))
    scene = frictex.load_scene(SCENE)
    out = frictex.build_pipeline(scene).process(twice)
    replayed = frictex.replay(scene, twice)
    assert out.t_s.size == 240_050 and replayed.commands.num_rows == 42_050
    assert replayed.summary.trace.gaps.count == 1
    start = int(round((stroke.t_s[-1] - stroke.t_s[0]) * 10_000))  # the pause's start
    np.testing.assert_array_equal(out.t_s[:start], replayed.commands.column("t_s").to_numpy()[:start])
    np.testing.assert_array_equal(out.commands_um[:start, 0],
                                  replayed.commands.column(1).to_numpy()[:start])


def test_version_is_the_installed_one_as_the_command_prints_it(tmp_path, capsys):
    from importlib.metadata import version
    assert frictex.__version__ == version("frictex")
    with pytest.raises(SystemExit):
        main(["--version"])
    assert capsys.readouterr().out == f"frictex {frictex.__version__}\n"
    out = run_python("import sys, frictex; print(frictex.__version__, sorted(m for m in ("
                     "'numpy', 'numba', 'scipy', 'pyarrow') if m in sys.modules))", tmp_path)
    assert out.split(" ", 1) == [frictex.__version__, "[]\n"]


def test_replay_takes_the_command_s_options_with_its_defaults():
    import argparse
    import inspect
    from frictex.app.commands.replay import add_arguments
    parser = argparse.ArgumentParser()
    add_arguments(parser)
    command = parser.parse_args([SCENE, TRACE, "--out", "o"])
    from frictex.app.engine.replay import MAX_UNPLAYED
    assert command.max_unplayed is None  # given only with --device; MAX_UNPLAYED there
    command.max_unplayed = MAX_UNPLAYED
    defaults = {name: p.default for name, p in inspect.signature(frictex.replay).parameters.items()}
    for api, option in (("rate_hz", "rate"), ("block_size", "block"), ("max_gap_s", "max_gap"),
                        ("max_unplayed", "max_unplayed"), ("faults", "faults"),
                        ("device", "device"), ("control", "control"), ("renderer", "renderer"),
                        ("strict", "strict")):
        assert defaults[api] == getattr(command, option), api


def test_a_device_leaving_samples_unplayed_fails_the_replay_as_it_fails_the_command(tmp_path,
                                                                                   capsys):
    """A watchdog trip (its samples never play): with max_unplayed 0 the command exits 1
    and replay raises DeviceError, the same sentence, the outputs written and the run's
    Replay on the error; with 1 the same run returns. The device section is a dict of
    PROTOCOL.md 6.4's counters."""
    link = ["--device", "sim", "--faults", "trip@0.3", "--max-unplayed", "0"]
    assert main(["replay", SCENE, TRACE, "--out", str(tmp_path / "cli"), "--quiet", *link]) == 1
    said = capsys.readouterr().err
    assert "of the commanded samples never played on the device (limit 0.00%, --max-unplayed)" in said
    with pytest.raises(frictex.DeviceError, match=r"never played on the device \(limit 0\.00%, "
                                                   r"max_unplayed\); outputs in ") as caught:
        frictex.replay(SCENE, TRACE, out=tmp_path / "api", device="sim", faults="trip@0.3",
                       max_unplayed=0.0)
    failed = caught.value.replay
    assert failed.out == tmp_path / "api" and failed.friction.num_rows > 0
    device = failed.summary.device
    assert isinstance(device, dict) and device["unplayed_samples"] > 0
    assert device["played_samples"] + device["unplayed_samples"] == device["commanded_samples"]
    passed = frictex.replay(SCENE, TRACE, device="sim", faults="trip@0.3", max_unplayed=1.0)
    assert passed.summary.device["unplayed_samples"] > 0
