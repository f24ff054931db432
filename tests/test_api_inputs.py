"""The API's inputs are checked as the command line's: a trace given as arrays (or lists)
as a trace file's rows are, every argument within the command line's bounds; a bad one is
one InputError line naming it, raised before anything runs."""

import math

import numpy as np
import pytest
from hypothesis import HealthCheck, given, settings
from hypothesis import strategies as st

import frictex
from frictex.app.commands.cli import main
from frictex.rendering.input.trace_file import write_trace

SCENE, TRACE = "grating-5mm", "swipe-40mms-50hz"
FIELDS = ("t_s", "finger", "x_mm", "y_mm", "force_n", "event")
FLOATS = ("t_s", "x_mm", "y_mm", "force_n")
PROPERTY = settings(max_examples=40, deadline=None,
                    suppress_health_check=[HealthCheck.function_scoped_fixture])


@pytest.fixture(scope="module")
def scene():
    return frictex.load_scene(SCENE)


@st.composite
def valid_columns(draw, max_samples: int = 30) -> dict[str, list]:
    """The fields of a valid trace as lists: time not decreasing over at most 1 s, up to
    three fingers, values within the trace file's ranges."""
    n = draw(st.integers(1, max_samples))
    steps = draw(st.lists(st.floats(0.0, 1.0 / max_samples), min_size=n, max_size=n))
    t0 = draw(st.floats(-1e3, 1e3))
    coords = st.floats(-200.0, 200.0)
    return {"t_s": (t0 + np.cumsum(steps)).tolist(),
            "finger": draw(st.lists(st.integers(0, 2), min_size=n, max_size=n)),
            "x_mm": draw(st.lists(coords, min_size=n, max_size=n)),
            "y_mm": draw(st.lists(coords, min_size=n, max_size=n)),
            "force_n": draw(st.lists(st.floats(0.0, 1000.0), min_size=n, max_size=n)),
            "event": draw(st.lists(st.sampled_from((frictex.DOWN, frictex.MOVE, frictex.UP)),
                                   min_size=n, max_size=n))}


def as_arrays(columns: dict[str, list]) -> dict[str, np.ndarray]:
    return {name: np.array(values) for name, values in columns.items()}


def same_trace(a: frictex.Trace, b: frictex.Trace) -> None:
    for name in FIELDS:
        got, want = getattr(a, name), getattr(b, name)
        assert got.dtype == want.dtype, name
        np.testing.assert_array_equal(got, want, err_msg=name)


@PROPERTY
@given(columns=valid_columns())
def test_a_trace_from_lists_or_arrays_is_the_trace_its_csv_reads_back_as(tmp_path_factory, scene,
                                                                        columns):
    """Lists and arrays give the trace a CSV of the same samples reads back as (events
    normalised as the reader does), and replay to the same tables as that file; so does
    a Trace built by hand from the lists."""
    path = tmp_path_factory.mktemp("t") / "t.csv"
    from_lists = frictex.make_trace(**columns)
    from_arrays = frictex.make_trace(**as_arrays(columns))
    write_trace(path, frictex.Trace(**as_arrays(columns)))  # the events as given
    read = frictex.read_trace(path, strict=True)
    same_trace(from_lists, read)
    same_trace(from_arrays, read)
    assert from_lists.t_s.dtype == np.float64 and from_lists.finger.dtype == np.int64
    from_file = frictex.replay(scene, path)
    for trace in (from_lists, frictex.Trace(**columns)):
        replayed = frictex.replay(scene, trace)
        assert replayed.commands.equals(from_file.commands)
        assert replayed.friction.equals(from_file.friction)


#: (field, a value no trace may hold there, the message's words)
BAD_VALUES = [(name, value, f"{name} is") for name in FLOATS
              for value in (math.nan, math.inf, -math.inf)]
BAD_VALUES += [("t_s", 2e10, "t_s is"), ("x_mm", -1e6, "x_mm is"), ("force_n", -1.0, "force_n is"),
               ("force_n", 1001.0, "force_n is"), ("finger", -3, "finger is"),
               ("finger", 2**31, "finger is"), ("finger", 1.5, "finger is"),
               ("finger", math.nan, "finger is"), ("event", 7, "event is 7"),
               ("event", -1, "event is -1"), ("event", 257, "event is 257"),
               ("event", 1.5, "event is 1.5"), ("event", math.nan, "event is nan")]


@PROPERTY
@given(columns=valid_columns(), data=st.data())
def test_a_bad_value_anywhere_is_refused_naming_its_field_and_sample(monkeypatch, scene,
                                                                      columns, data):
    field, value, words = data.draw(st.sampled_from(BAD_VALUES))
    i = data.draw(st.integers(0, len(columns["t_s"]) - 1))
    columns[field][i] = value
    if data.draw(st.booleans()):
        columns = as_arrays(columns)
    message = f"^trace: sample {i}: {words}"
    with pytest.raises(frictex.TraceError, match=message):
        frictex.make_trace(**columns)
    built = frictex.Trace(**columns)  # a Trace made by hand is checked where it is used
    monkeypatch.setattr("frictex._replay.replay_with", _never_reached)
    with pytest.raises(frictex.InputError, match=message):
        frictex.replay(scene, built)
    with pytest.raises(frictex.InputError, match=message):
        frictex.build_pipeline(scene).process(built)


def _never_reached(*args, **kwargs):
    raise AssertionError("a bad trace reached the replay")


@PROPERTY
@given(columns=valid_columns(), data=st.data())
def test_time_going_back_is_refused_at_its_sample(columns, data):
    n = len(columns["t_s"])
    if n < 2:
        return
    i = data.draw(st.integers(1, n - 1))
    columns["t_s"][i] = columns["t_s"][i - 1] - data.draw(st.floats(1e-6, 10.0))
    with pytest.raises(frictex.TraceError, match=f"^trace: sample {i}: t_s goes back"):
        frictex.make_trace(**columns)


@PROPERTY
@given(columns=valid_columns(), data=st.data())
def test_fields_of_unequal_length_are_refused(monkeypatch, scene, columns, data):
    field = data.draw(st.sampled_from(FIELDS[1:]))
    n = len(columns["t_s"])
    length = data.draw(st.integers(0, n + 3).filter(lambda k: k != n))
    columns[field] = (columns[field] * 4)[:length]
    with pytest.raises(frictex.TraceError, match=f"^trace: column {field} has shape"):
        frictex.make_trace(**columns)
    monkeypatch.setattr("frictex._replay.replay_with", _never_reached)
    with pytest.raises(frictex.InputError, match=f"column {field} has shape"):
        frictex.replay(scene, frictex.Trace(**columns))


@pytest.mark.parametrize("change, message", [
    ({"t_s": 0.5}, "^trace: t_s: expected an array or list of one number per sample, got "
                   "float$"),
    ({"x_mm": (x for x in (1.0, 2.0))}, "^trace: x_mm: expected an array or list of one number "
                                        "per sample, got generator$"),
    ({"x_mm": [[1.0, 2.0]]}, r"^trace: x_mm has shape \(1, 2\)"),
    ({"y_mm": [[1.0], [2.0, 3.0]]}, "^trace: y_mm is not an array of numbers"),
    ({"force_n": ["0.5", "1"]}, "^trace: force_n holds <U3 values: expected numbers"),
    ({"finger": [True, False]}, "^trace: finger holds bool values"),
    ({"event": [None, 1]}, "^trace: event holds object values"),
    ({"t_s": [], "finger": [], "x_mm": [], "y_mm": []}, "no samples"),
    ({"t_s": None}, r"^trace: t_s is None: expected one number per sample, shape \(n,\)$"),
    ({"y_mm": None}, "^trace: y_mm is None"),
    ({"x_mm": np.ma.masked_array([1.0, 99.0], mask=[False, True])},
     r"^trace: x_mm: sample 1 is masked: expected a number at every sample \(fill it, or "
     r"leave the sample out\)$"),
])
def test_what_is_not_a_column_of_numbers_is_refused(change, message):
    columns = {"t_s": [0.0, 0.02], "finger": [0, 0], "x_mm": [1.0, 2.0], "y_mm": [3.0, 4.0]}
    with pytest.raises(frictex.TraceError, match=message):
        frictex.make_trace(**{**columns, **change})


def test_a_masked_array_with_nothing_masked_is_its_values():
    trace = frictex.make_trace([0.0, 0.02], [0, 0], np.ma.masked_array([1.0, 2.0]), [3.0, 4.0])
    assert trace.x_mm.tolist() == [1.0, 2.0]


@pytest.mark.parametrize("kind, kwargs, message", [
    ("swipe", {"duration_s": 100_000.0}, r"^a swipe with x0_mm=14, y0_mm=32.4, speed_mm_s=40, "
     r"duration_s=100000, angle_deg=0 reaches x_mm = 4.00001e\+06; a trace's positions stay "
     r"within \+-100000 mm$"),
    ("swipe", {"angle_deg": -90.0, "speed_mm_s": 1e4, "duration_s": 11.0}, "reaches y_mm = -1"),
    ("back-and-forth", {"x0_mm": 99_990.0}, "length_mm=80, angle_deg=0 reaches x_mm = 100070"),
    ("circle", {"y0_mm": -99_990.0}, "radius_mm=20 reaches y_mm = -100010"),
])
def test_a_path_beyond_a_trace_s_positions_names_the_arguments(kind, kwargs, message):
    """A swipe of 100000 s failed as 'trace: sample 2500: x_mm is 100014.0 ...', naming none."""
    with pytest.raises(frictex.InputError, match=message):
        frictex.synth_trace(kind, **kwargs)


def test_a_path_within_a_trace_s_positions_is_made():
    """The far end counts, not the start: a back-and-forth shorter than its duration
    reaches only as far as it goes."""
    near_edge = frictex.synth_trace("back-and-forth", x0_mm=99_950.0, duration_s=1.0)
    assert near_edge.x_mm.max() == pytest.approx(99_990.0)


def test_a_trace_that_is_not_there_is_a_trace_error(tmp_path):
    with pytest.raises(frictex.TraceError, match="no such file$"):
        frictex.read_trace(tmp_path / "missing.csv")
    with pytest.raises(frictex.TraceError, match="did you mean swipe-40mms-50hz"):
        frictex.read_trace("swipe-40mms")


def test_the_event_codes_are_the_trace_file_s_words(tmp_path):
    path = tmp_path / "t.csv"
    path.write_text("t_s,finger,x_mm,y_mm,event\n0,0,1,1,down\n0.02,0,2,1,move\n0.04,0,3,1,up\n",
                    encoding="utf-8")
    assert frictex.read_trace(path).event.tolist() == [frictex.DOWN, frictex.MOVE, frictex.UP]
    assert sorted({frictex.DOWN, frictex.MOVE, frictex.UP}) == [0, 1, 2]


@pytest.mark.parametrize("kwargs, message", [
    ({"rate_hz": 1e7}, r"^rate_hz=10000000.0: expected 100 to 1e\+06 Hz$"),
    ({"rate_hz": 1.0}, r"^rate_hz=1.0: expected 100 to 1e\+06 Hz$"),
    ({"rate_hz": 0}, r"^rate_hz=0.0: expected 100 to 1e\+06 Hz$"),
    ({"rate_hz": "60"}, r"^rate_hz='60': expected a number \(Hz\)$"),
    ({"rate_hz": math.nan}, r"^rate_hz=nan: expected 100 to 1e\+06 Hz$"),
    ({"block_size": 0}, r"^block_size=0: expected 1 to 100000 samples$"),
    ({"block_size": 100_001}, r"^block_size=100001: expected 1 to 100000 samples$"),
    ({"block_size": 2.5}, r"^block_size=2.5: expected a whole number \(samples\)$"),
    ({"block_size": True}, r"^block_size=True: expected a whole number \(samples\)$"),
    ({"control": "foo"}, "^control='foo': expected one of open, closed, adaptive or None$"),
    ({"renderer": "nope"}, "^renderer='nope': expected one of sho, .*hybrid.* or None$"),
])
@pytest.mark.parametrize("call", ["replay", "build_pipeline"])
def test_run_settings_keep_the_command_line_s_bounds(monkeypatch, scene, call, kwargs, message):
    monkeypatch.setattr("frictex._replay.replay_with", _never_reached)
    args = (scene, TRACE) if call == "replay" else (scene,)
    with pytest.raises(frictex.InputError, match=message):
        getattr(frictex, call)(*args, **kwargs)


def test_the_command_line_refuses_what_the_api_refuses(tmp_path, capsys):
    """The same bounds: each value the API refuses above, the command refuses too."""
    for option, value in (("--rate", "1e7"), ("--rate", "1"), ("--block", "0"),
                          ("--block", "100001"), ("--block", "2.5"), ("--max-gap", "-1"),
                          ("--max-unplayed", "1.5")):
        with pytest.raises(SystemExit) as exit_:
            main(["replay", SCENE, TRACE, "--out", str(tmp_path / "o"), option, value])
        assert exit_.value.code == 2, (option, value)
    assert not (tmp_path / "o").exists()


@pytest.mark.parametrize("kwargs, message", [
    ({"max_gap_s": -1}, r"^max_gap_s=-1.0: expected more than 0 \(s\)$"),
    ({"max_gap_s": 0.0}, r"^max_gap_s=0.0: expected more than 0 \(s\)$"),
    ({"max_gap_s": math.inf}, r"^max_gap_s=inf: expected a finite number more than 0 \(s\)$"),
    ({"max_unplayed": 1.5}, "^max_unplayed=1.5: expected 0 to 1$"),
    ({"max_unplayed": -0.1}, "^max_unplayed=-0.1: expected 0 to 1$"),
    ({"faults": "corrupt=0.001"}, "^faults are injected into a device's link: give device too$"),
    ({"faults": "zap=1", "device": "sim"}, "^fault 'zap=1': unknown name 'zap'"),
    ({"faults": 3, "device": "sim"}, "^faults: expected a fault spec"),
    ({"out": 3}, "^out=3: expected a folder"),
    ({"device": 0}, "^device: expected 'sim', a serial port or a pyserial URL, got int$"),
])
def test_replay_options_are_checked_before_it_runs(monkeypatch, scene, kwargs, message):
    monkeypatch.setattr("frictex._replay.replay_with", _never_reached)
    with pytest.raises(frictex.InputError, match=message):
        frictex.replay(scene, TRACE, **kwargs)


@pytest.mark.parametrize("call, message", [
    (lambda s: frictex.build_pipeline(s, inversion="nn"), "^inversion='nn': expected one of exact, lut$"),
    (lambda s: frictex.build_pipeline(3), "^scene=3: expected a Scene"),
    (lambda s: frictex.replay(s, 3), "^trace=3: expected a Trace, a trace CSV"),
    (lambda s: frictex.replay(None, TRACE), "^scene=None: expected a Scene"),
    (lambda s: frictex.build_pipeline(s).process("swipe"), "^trace: expected a Trace"),
    (lambda s: frictex.load_scene(3.5), "^name_or_path=3.5: expected a texture file"),
    (lambda s: frictex.read_trace(None), "^path=None: expected a trace CSV"),
])
def test_arguments_of_the_wrong_kind_are_input_errors(scene, call, message):
    with pytest.raises(frictex.InputError, match=message):
        call(scene)


def test_a_pipeline_takes_a_scene_by_name_as_replay_does(scene):
    by_name = frictex.build_pipeline(SCENE).process(frictex.read_trace(TRACE))
    by_scene = frictex.build_pipeline(scene).process(frictex.read_trace(TRACE))
    np.testing.assert_array_equal(by_name.commands_um, by_scene.commands_um)


@pytest.mark.parametrize("kwargs, message", [
    ({"duration_s": 1e9}, r"^duration_s=1000000000.0: expected 1e-06 to 100000 s$"),
    ({"duration_s": 1e5, "rate_hz": 1e3}, "^rate_hz=1000 Hz over duration_s=100000 s is "
                                          "100,000,000 samples; at most 10,000,000$"),
    ({"speed_mm_s": math.nan}, "^speed_mm_s=nan: expected more than 0 and at most 10000 mm/s$"),
    ({"speed_mm_s": 0.0}, "^speed_mm_s=0.0: expected more than 0"),
    ({"rate_hz": "60"}, r"^rate_hz='60': expected a number \(Hz\)$"),
    ({"rate_hz": -5}, "^rate_hz=-5.0: expected 0.001 to 100000 Hz$"),
    ({"x0_mm": 1e6}, "^x0_mm=1000000.0: expected -100000 to 100000 mm$"),
    ({"noise_mm": -1.0}, "^noise_mm=-1.0: expected 0 to 1000 mm$"),
    ({"jitter_s": 2.0}, "^jitter_s=2.0: expected 0 to 1 s$"),
    ({"angle_deg": 400}, "^angle_deg=400.0: expected -360 to 360 deg$"),
    ({"force_n": -0.1}, "^force_n=-0.1: expected 0 to 1000 N$"),
    ({"seed": -1}, "^seed=-1: expected at least 0$"),
    ({"seed": 1.5}, "^seed=1.5: expected a whole number$"),
    ({"radius_mm": 10**400}, "^radius_mm=inf: expected more than 0"),
])
def test_synth_trace_arguments_keep_the_command_s_limits(kwargs, message):
    with pytest.raises(frictex.InputError, match=message):
        frictex.synth_trace("circle", **kwargs)


@pytest.mark.parametrize("kwargs, message", [
    ({"peaks_n": ()}, r"^peaks_n: no peaks; expected one or more peak forces \(N\)$"),
    ({"peaks_n": 1.0}, r"^peaks_n: expected a sequence of peak forces \(N\), got float$"),
    ({"peaks_n": (1.0, -2.0)}, r"^peaks_n\[1\]=-2.0: expected 0 to 1000 N$"),
    ({"peaks_n": (1.0,) * 300_000}, "^peaks_n: 300000 presses at rate_hz=100 would exceed"),
    ({"force_noise_n": math.inf}, "^force_noise_n=inf: expected 0 to 100 N$"),
])
def test_press_arguments_are_checked(kwargs, message):
    with pytest.raises(frictex.InputError, match=message):
        frictex.synth_trace("press", **kwargs)


@pytest.mark.parametrize("motion, kwargs", [("press", {}), ("swipe", {"speed_mm_s": 60.0}),
                                            ("press", {"rate_hz": 200.0, "force_n": 0.3})])
def test_a_synthetic_trace_is_the_command_s_with_the_same_options(tmp_path, motion, kwargs):
    """synth_trace takes frictex trace synth's defaults for each motion: a press at
    100 Hz and 0.1 N on keyclick-ring's button (it took a path's 50 Hz, 0.5 N and start,
    off the button: no click played), a path at 50 Hz and 0.5 N."""
    flags = {"speed_mm_s": "--speed", "rate_hz": "--rate", "force_n": "--force"}
    path = tmp_path / "t.csv"
    args = [str(a) for key, value in kwargs.items() for a in (flags[key], value)]
    assert main(["trace", "synth", motion, *args, "-o", str(path)]) == 0
    made, read = frictex.synth_trace(motion, **kwargs), frictex.read_trace(path)
    for name in FLOATS:  # the file's fixed decimals
        np.testing.assert_allclose(getattr(made, name), getattr(read, name), atol=1e-6,
                                   err_msg=name)
    for name in ("finger", "event"):
        np.testing.assert_array_equal(getattr(made, name), getattr(read, name), err_msg=name)


def test_the_api_s_press_plays_keyclick_ring_s_click():
    result = frictex.replay("keyclick-ring", frictex.synth_trace("press"))
    assert result.friction["amplitude_um"].to_numpy().max() > 0.0


def test_a_press_takes_its_peaks_from_any_sequence():
    listed = frictex.synth_trace("press", peaks_n=[1.0, 0.8])
    arrayed = frictex.synth_trace("press", peaks_n=np.array([1.0, 0.8]))
    same_trace(listed, arrayed)


@pytest.mark.parametrize("kind", ["human", "human-varied"])
def test_a_human_motion_starts_where_told_and_wanders_in_its_area(kind):
    trace = frictex.synth_trace(kind, duration_s=60.0, x0_mm=150.0, y0_mm=3.0,
                                area_mm=(600.0, 20.0), seed=3)
    assert (trace.x_mm[0], trace.y_mm[0]) == (150.0, 3.0)
    assert trace.x_mm.max() > 108.0  # beyond the default area: the area was used
    assert 0.0 <= trace.x_mm.min() and trace.x_mm.max() <= 600.0
    assert 0.0 <= trace.y_mm.min() and trace.y_mm.max() <= 20.0
    default = frictex.synth_trace(kind, duration_s=60.0, seed=3)
    assert (default.x_mm[0], default.y_mm[0]) == pytest.approx((0.3 * 108.0, 0.5 * 64.8))
    assert default.x_mm.max() <= 108.0 and default.y_mm.max() <= 64.8


@pytest.mark.parametrize("kind, kwargs, message", [
    ("human", {"x0_mm": 150.0}, r"^start \(150, 32.4\) mm: outside the 108 x 64.8 mm area"),
    ("swipe", {"area_mm": (100.0, 50.0)}, "^area_mm: only the human motions wander in an area"),
    ("human", {"area_mm": (100.0,)}, r"^area_mm: expected \(width, height\) in mm"),
    ("human", {"area_mm": (math.nan, 30.0)}, r"^area_mm\[0\]=nan: expected more than 0"),
])
def test_a_start_or_area_a_motion_cannot_have_is_refused(kind, kwargs, message):
    with pytest.raises(frictex.InputError, match=message):
        frictex.synth_trace(kind, **kwargs)
