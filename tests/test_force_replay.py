"""Replays of the bundled force scenes, end to end through ``frictex replay``: phase
columns in commands.csv, force figures in summary.json, the key-click flips once per
press at the click force, and two replays are byte-identical."""

import csv
import json

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.rendering.input.trace_file import read_trace
from frictex.textures.library import list_scenes, resolve_trace

CASES = {
    "keyclick-ring": "keyclick-press-100hz",
    "directional-beam": "back-and-forth-beam-60mms-60hz",
    "directional-ring": "back-and-forth-ring-40mms-60hz",
    "guidance-ring": "back-and-forth-ring-40mms-60hz",
    "keyclick-beam": "keyclick-press-beam-100hz",
    "guidance-beam": "back-and-forth-beam-60mms-60hz",
}


def replay(tmp_path, scene, trace, name="out"):
    out = tmp_path / name
    assert main(["replay", scene, trace, "--out", str(out)]) == 0
    with (out / "commands.csv").open() as f:
        rows = list(csv.reader(f))
    table = np.array(rows[1:], dtype=np.float64)
    return out, rows[0], table, json.loads((out / "summary.json").read_text())


@pytest.mark.parametrize("scene", sorted(CASES))
def test_bundled_force_scene_replays_with_phases_and_force_figures(tmp_path, scene):
    out, header, table, summary = replay(tmp_path, scene, CASES[scene])
    channels = summary["output"]["channels"]
    assert header == ["t_s"] + [f"{c}_um" for c in channels] + [f"{c}_phase_rad" for c in channels]
    assert np.isfinite(table).all() and table[:, 1:3].max() > 0.5
    forces = summary["forces"]["0"]
    assert forces["contact_samples"] == summary["counts"]["contact_samples"]
    assert forces["unreachable_samples"] == summary["clamps"]["unreachable"]
    assert forces["force_error_rms_n"] < 0.01 and forces["wanted_max_n"] > 0.03


def test_the_friction_table_holds_each_samples_forces(tmp_path):
    out, _, _, summary = replay(tmp_path, "directional-beam", CASES["directional-beam"])
    with (out / "friction.csv").open() as f:
        rows = list(csv.DictReader(f))
    assert list(rows[0])[-3:] == ["force_x_wanted_n", "force_y_wanted_n", "force_x_n"]
    wanted = np.array([float(r["force_x_wanted_n"]) for r in rows])
    given = np.array([float(r["force_x_n"]) for r in rows])
    # the scene's mu' 0.3 forward and 0.9 backward at mu0 0.5 and 0.5 N, signed; outside
    # its region (the trace runs 220-380 mm, the region 230-370) plain friction, 0.25 N
    assert sorted({round(abs(w), 6) for w in wanted} - {0.0}) == [0.075, 0.225, 0.25]
    forces = summary["forces"]["0"]
    rms = float(np.sqrt(np.mean((given - wanted) ** 2)))  # at the CSV's 6 decimals
    assert rms == pytest.approx(forces["force_error_rms_n"], abs=2e-6)
    assert np.abs(wanted).max() == pytest.approx(forces["wanted_max_n"])
    plain = tmp_path / "plain"
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(plain)]) == 0
    assert (plain / "friction.csv").read_text().splitlines()[0] == (
        "t_s,finger,x_mm,y_mm,mu_target,amplitude_um")


@pytest.mark.parametrize("scene", ["keyclick-ring", "keyclick-beam"])
def test_keyclick_flips_once_per_press_at_the_click_force(tmp_path, scene):
    _, _, table, summary = replay(tmp_path, scene, CASES[scene])
    assert summary["forces"]["0"]["clicks"] == 3
    t, w = table[:, 0], table[:, 1]
    on = w > 0
    shift = np.where(on, np.sign(np.sin(table[:, 3] - table[:, 4])), 0)
    changes = np.flatnonzero(np.diff(shift))
    steps = [(int(shift[i]), int(shift[i + 1])) for i in changes]
    # each press: off -> push one way -> reversed -> off, nothing else (no flicker)
    assert len(steps) == 9 and steps[0::3] == [(0, steps[0][1])] * 3
    assert all(b == -a for (_, a), (_, b) in zip(steps[0::3], steps[1::3]))
    trace = read_trace(resolve_trace(CASES[scene]))
    for i in changes[1::3] + 1:        # the flips: the last 10 ms of force samples >= 0.8 N
        recent = trace.force_n[(trace.t_s <= t[i]) & (trace.t_s > t[i] - 0.0151)]
        assert recent.size >= 1 and np.all(recent >= 0.8)
    for i in changes[0::3] + 1:        # wave on at 0.5 N
        assert trace.force_n[np.searchsorted(trace.t_s, t[i], side="right") - 1] >= 0.5


def test_two_replays_are_byte_identical(tmp_path):
    a, *_ = replay(tmp_path, "guidance-ring", CASES["guidance-ring"], "a")
    b, *_ = replay(tmp_path, "guidance-ring", CASES["guidance-ring"], "b")
    for name in ("commands.csv", "friction.csv"):
        assert (a / name).read_bytes() == (b / name).read_bytes()


def test_bundled_force_scenes_exist():
    assert {"keyclick-ring", "directional-beam", "guidance-ring"} <= {e.name for e in list_scenes()}


def test_keyclick_presses_with_a_new_finger_id_each_are_counted_per_id(tmp_path):
    """Android gives each press its own tracking id: the replay runs them on one reused
    row (``app.engine.finger_slots``), and the summary still counts one click for each
    id, with commands byte-identical to the same presses under one id."""
    from dataclasses import replace

    from frictex.rendering.input.trace_file import DOWN, write_trace
    trace = read_trace(resolve_trace(CASES["keyclick-ring"]))
    assert set(trace.finger.tolist()) == {0}
    renamed = replace(trace, finger=100 + np.cumsum(trace.event == DOWN).astype(np.int64))
    write_trace(tmp_path / "ids.csv", renamed)
    out_one, _, _, one = replay(tmp_path, "keyclick-ring", CASES["keyclick-ring"], "one")
    out_ids, _, _, ids = replay(tmp_path, "keyclick-ring", str(tmp_path / "ids.csv"), "ids")
    assert {fid: f["clicks"] for fid, f in ids["forces"].items()} == {"101": 1, "102": 1, "103": 1}
    assert sorted(ids["fingers"]) == ["101", "102", "103"]
    assert (out_ids / "commands.csv").read_bytes() == (out_one / "commands.csv").read_bytes()
