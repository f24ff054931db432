"""Touch samples off the display play as if at its edge (the tracker holds them there): a
replay says how many, and a trace in metres, on or off the display, is said to be one."""

import numpy as np
import pytest

from frictex.app.engine.replay import run_replay
from frictex.app.engine.sources import TraceStats
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, Trace, read_trace
from frictex.textures.library import list_scenes, list_traces, resolve_scene, resolve_trace
from frictex.textures.loader import load_scene

RATE_HZ = 120.0  # the swipes below: 2 s at 40 mm/s along y = 32.4 mm


def swipe_csv(tmp_path, x0_mm: float, scale: float = 1.0) -> str:
    """A 2 s, 80 mm swipe from ``x0_mm`` along y = 32.4 mm, its positions times ``scale``."""
    t = np.arange(int(2 * RATE_HZ) + 1) / RATE_HZ
    x, y = (x0_mm + 40.0 * t) * scale, np.full(t.size, 32.4 * scale)
    events = ["down"] + ["move"] * (t.size - 2) + ["up"]
    rows = "".join(f"{ti!r},0,{xi!r},{yi!r},0.5,{e}\n" for ti, xi, yi, e in zip(t.tolist(), x.tolist(), y.tolist(), events))
    path = tmp_path / "swipe.csv"
    path.write_text("t_s,finger,x_mm,y_mm,force_n,event\n" + rows)
    return str(path)


def replay(tmp_path, trace: str) -> dict:
    return run_replay(load_scene(resolve_scene("grating-5mm")), trace, tmp_path / "o",
                      progress=False)


def test_a_trace_off_the_display_is_counted_and_warned(tmp_path):
    """The swipe from x = 514 mm on the 108 mm display: every touch sample held at x = 108."""
    doc = replay(tmp_path, swipe_csv(tmp_path, 514.0))
    touching = int(2 * RATE_HZ)  # the down and the moves
    assert doc["trace"]["touch_samples_off_display"] == touching
    said = [w for w in doc["warnings"] if "off the 108 x 64.8 mm display" in w]
    assert len(said) == 1
    assert said[0].startswith(f"trace: {touching} of {touching} touch samples")
    assert "x 514 to 593.7 mm" in said[0] and "held at its edge" in said[0]
    assert "another display" in said[0] and "metres" not in said[0]


def test_a_trace_in_metres_is_said_to_be(tmp_path):
    """The same swipe from x = 14 mm written in metres lies on the display, near (0, 0)."""
    doc = replay(tmp_path, swipe_csv(tmp_path, 14.0, scale=1e-3))
    assert doc["trace"]["touch_samples_off_display"] == 0
    assert [w for w in doc["warnings"] if "in metres?" in w] == [
        "trace: all 240 touch samples over 1.99 s lie within 1 mm of (0, 0) (x 0.014 to "
        "0.09367 mm, y 0.0324 to 0.0324 mm): in metres? positions are in mm"]


def test_an_ordinary_swipe_is_not_warned_about(tmp_path):
    doc = replay(tmp_path, swipe_csv(tmp_path, 14.0))
    assert doc["trace"]["touch_samples_off_display"] == 0
    assert not [w for w in doc["warnings"] if "display" in w or "metres" in w]


def stats_of(trace: Trace, area_mm) -> TraceStats:
    stats = TraceStats()
    stats.add(trace)
    stats.set_area(area_mm)
    return stats


def touches(x_mm, y_mm=None) -> Trace:
    """One finger's touch at 100 Hz through ``x_mm`` (y = 10 mm unless given), then its lift."""
    x = np.append(np.asarray(x_mm, dtype=float), x_mm[-1])
    y = np.full(x.size, 10.0) if y_mm is None else np.append(y_mm, y_mm[-1])
    events = np.array([DOWN] + [MOVE] * (x.size - 2) + [UP], dtype=np.int8)
    return Trace(np.arange(x.size) / 100.0, np.zeros(x.size, dtype=np.int64), x, y,
                 np.full(x.size, 0.5), events)


def test_a_sample_on_the_edge_is_inside_and_one_just_past_it_is_counted_unwarned():
    """A touch screen reports slightly past its edge: 0.3 mm out is held there, not warned."""
    on_edge = stats_of(touches([0.0, 50.0, 108.0], [0.0, 64.8, 30.0]), (108.0, 64.8))
    assert on_edge.off_display == 0
    just_past = stats_of(touches(np.linspace(100.0, 108.3, 50)), (108.0, 64.8))
    assert just_past.off_display > 0 and just_past.warnings() == []


def test_a_drag_that_runs_briefly_past_the_edge_is_not_warned_about():
    """A mouse drag dragged past the window for 3 of its 60 samples."""
    x = np.concatenate((np.linspace(50.0, 107.0, 57), [110.0, 115.0, 120.0]))
    stats = stats_of(touches(x), (108.0, 64.8))
    assert stats.off_display == 3 and stats.warnings() == []


def test_a_trace_in_metres_off_the_display_is_hinted_at():
    """Positions in metres, from a display whose origin is at its centre."""
    stats = stats_of(touches(np.linspace(-0.9, -0.6, 100), np.full(100, 0.01)), (108.0, 64.8))
    (said,) = stats.warnings()
    assert "off the 108 x 64.8 mm display" in said and said.endswith("or in metres?")


#: the bundled traces by the displays they are made for
PHONE = {"back-and-forth-60mms-50hz", "circle-30mms-60hz", "human-strokes-120hz",
         "swipe-40mms-50hz", "keyclick-press-100hz"}
RING = {"back-and-forth-ring-40mms-60hz", "keyclick-press-100hz"}
BEAM = {"back-and-forth-beam-60mms-60hz", "keyclick-press-beam-100hz", "two-fingers-crossing-50hz"}
SHORT_BEAM = {"keyclick-press-beam-100hz", "two-fingers-crossing-50hz"}  # seed 000's 350 mm


def traces_for(scene: str) -> set[str]:
    if scene == "two-finger-beam-seed000":
        return SHORT_BEAM
    return BEAM if "beam" in scene else RING if "ring" in scene else PHONE


def test_every_bundled_trace_is_paired_with_its_displays():
    assert {e.name for e in list_traces()} == PHONE | RING | BEAM


@pytest.mark.parametrize("scene", [e.name for e in list_scenes()])
def test_bundled_traces_on_their_bundled_scenes_are_not_warned_about(scene):
    display = load_scene(resolve_scene(scene)).display
    for name in sorted(traces_for(scene)):
        stats = stats_of(read_trace(resolve_trace(name)), (display.width_mm, display.height_mm))
        assert (name, stats.off_display, stats.warnings()) == (name, 0, [])


def test_a_looped_replay_warns_of_a_trace_off_the_display_too(tmp_path):
    """The friction loop leaves out the not-pressing line (it compares forces itself), not
    the off-display one."""
    doc = run_replay(load_scene(resolve_scene("grating-15mm")), swipe_csv(tmp_path, 514.0),
                     tmp_path / "o", progress=False, control="adaptive", device="sim:finger=1")
    assert [w for w in doc["warnings"] if "off the 108 x 64.8 mm display" in w]


@pytest.mark.parametrize("renderer", ["sho-held", "sht", "hybrid", "sho-predicted"])
def test_a_finger_past_the_edge_plays_the_texture_at_the_edge(tmp_path, renderer):
    """A swipe at 40 mm/s from x = 60 mm runs past the 108 mm display's right edge at
    1.2 s and on to 140 mm: once the velocity fit has slowed to the finger held there,
    every renderer plays one mu', the grating's at x = 108 mm. Only the prediction was
    held at the edge: SHO-held read the raw sample and SHT integrated the raw velocity,
    playing a grating edge every 5 mm of the finger's travel beyond the display."""
    import pyarrow.csv as pcsv
    doc = run_replay(load_scene(resolve_scene("grating-5mm")), swipe_csv(tmp_path, 60.0),
                     tmp_path / "o", progress=False, render_override=renderer)
    assert doc["trace"]["touch_samples_off_display"] > 0
    table = pcsv.read_csv(tmp_path / "o" / "friction.csv")
    t, x, mu = (table[c].to_numpy() for c in ("t_s", "x_mm", "mu_target"))
    beyond = (t > 1.2 + 0.1) & (t < 1.99)  # past the edge by more than the fit's window
    assert np.all(x[beyond] == 108.0)
    assert np.unique(mu[beyond]).size == 1, np.unique(mu[beyond])


@pytest.mark.parametrize("renderer", ["sht", "hybrid", "sho-predicted"])
def test_a_prediction_held_at_the_edge_rests_there(tmp_path, renderer):
    """A 200 mm/s swipe whose samples end at x = 104 mm, silent for 55 ms before its lift:
    the prediction reaches the 108 mm edge 20 ms on and is held there, and the finger
    plays one mu' there. SHT and the hybrid integrated the fit's velocity on while the
    prediction stood at the edge, playing two more grating edges in 25 ms."""
    import pyarrow.csv as pcsv
    t = np.arange(22) * 0.02  # 50 Hz, x = 20 .. 104 mm
    x = 20.0 + 200.0 * t
    rows = [f"{ti!r},0,{xi!r},32.4,0.5,{'down' if i == 0 else 'move'}\n"
            for i, (ti, xi) in enumerate(zip(t.tolist(), x.tolist()))]
    rows.append(f"{float(t[-1]) + 0.055!r},0,104.0,32.4,0.5,up\n")
    path = tmp_path / "edge.csv"
    path.write_text("t_s,finger,x_mm,y_mm,force_n,event\n" + "".join(rows))
    run_replay(load_scene(resolve_scene("grating-5mm")), str(path), tmp_path / "o",
               progress=False, render_override=renderer)
    table = pcsv.read_csv(tmp_path / "o" / "friction.csv")
    x_out, mu = (table[c].to_numpy() for c in ("x_mm", "mu_target"))
    at_edge = x_out == 108.0
    assert at_edge.sum() > 100  # 20 to 55 ms after the last sample, at 10 kHz
    assert np.unique(mu[at_edge]).size == 1, np.unique(mu[at_edge])
