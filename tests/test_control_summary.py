"""What the closed loop says about itself in a replay's summary.json (``ClosedLoop.report``,
app/engine/SUMMARY.md's ``control``): what the host measured from the device's force
reports, an oscillating gain, and a touch input whose normal force is implausible."""

import json
import math
from types import SimpleNamespace

import numpy as np
import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from frictex.app.commands.cli import main
from frictex.device.link.forces import ForceHistory, ForceReport
from frictex.device.profile import DeviceProfile
from frictex.rendering.control.loop import ClosedLoop
from frictex.rendering.control.swings import SWING, longest_run

N = 25
MU0 = 0.8
TARGET = 0.6


def _block(index0, speed, force_n=0.5):
    ones = np.ones((1, N))
    return np.full((1, N), TARGET), SimpleNamespace(
        contact=ones > 0, force=force_n * ones, vx=speed * ones, vy=0.0 * ones, index0=index0)


def _measured_mu(j: int) -> np.ndarray:
    """The relative friction block j's report reads (its first: the finger at rest, mu0)."""
    return np.ones(N) if j == 0 else 0.2 + 0.1 * (j % 3) + 0.01 * np.arange(N) / N


def _run(delay, blocks, lost=(), input_force_n=0.5):
    """Block 0 as a stroke starts (1 mm/s: the plate held still, mu0 measured), then
    10 mm/s; block j's report (F_n 0.5 N, F_t = MU0 mu'_j F_n) comes ``delay`` blocks
    after it ends, except the ``lost`` ones. Returns the loop and its final state."""
    loop = ClosedLoop(DeviceProfile(), 5000.0, N, mode="closed")
    state, history = loop.initial_state(), ForceHistory()
    for k in range(blocks):
        j = k - 1 - delay
        if j >= 0 and j not in lost:
            normal = np.full(N, 0.5)
            history.add(ForceReport(j * N, MU0 * _measured_mu(j) * normal, normal))
        target, fingers = _block(k * N, 1.0 if k == 0 else 10.0, input_force_n)
        _, _, state = loop.invert(target, fingers, state, history.window)
    return loop, state


@pytest.mark.parametrize("delay, lost", [(0, ()), (2, ()), (3, (10, 11))])
def test_the_measured_friction_against_the_target_is_what_the_reports_read(delay, lost):
    blocks = 40
    loop, state = _run(delay, blocks, lost)
    measured = loop.report(state)["measured"]
    folded = blocks - len(state.pending)  # blocks 0 .. folded - 1 paired or given up
    good = [j for j in range(folded) if j not in lost]
    assert measured["reports"] == len(good) and measured["reports_missed"] == len(lost)
    assert measured["report_delay_p50_blocks"] == measured["report_delay_p99_blocks"] == delay
    # written out: every good report after mu0's (block 0), its samples all sliding
    err = np.concatenate([_measured_mu(j) - TARGET for j in good if j > 0])
    assert measured["samples"] == err.size
    assert math.isclose(measured["rms_mu_vs_target"], float(np.sqrt(np.mean(err ** 2))),
                        rel_tol=1e-12)
    assert state.mu0 == MU0


def test_without_reports_nothing_is_measured():
    loop = ClosedLoop(DeviceProfile(), 5000.0, N, mode="closed")
    state = loop.initial_state()
    for k in range(5):
        _, _, state = loop.invert(*_block(k * N, 10.0), state, None)
    measured = loop.report(state)["measured"]
    assert len(state.pending) == 1  # the block just sent: the others folded as missed
    assert measured == {"reports": 0, "reports_missed": 4, "reports_pending_at_end": 1,
                        "report_delay_p50_blocks": None, "report_delay_p99_blocks": None,
                        "samples": 0, "rms_mu_vs_target": None}


def test_a_touch_input_without_normal_force_is_said_once_and_counted():
    loop, state = _run(1, 30, input_force_n=0.0)
    report = loop.report(state)
    assert report["input_force_implausible_blocks"] == loop.report(state)["measured"]["reports"]
    said = [m for m in report["messages"] if "touch input's normal force" in m]
    assert len(said) == 1 and "0 N" in said[0] and "0.5 N" in said[0]
    _, fine = _run(1, 30)
    assert loop.report(fine)["input_force_implausible_blocks"] == 0
    assert not loop.report(fine)["messages"]


def _reference_swings(log_c: np.ndarray) -> int:
    """The longest run of swings over SWING, each at least half the one before, written
    out with numpy (the report's former implementation)."""
    steps = np.diff(log_c)
    steps = steps[steps != 0.0]
    if steps.size == 0:
        return 0
    turns = np.flatnonzero(np.sign(steps[1:]) != np.sign(steps[:-1])) + 1
    swings = np.abs(np.add.reduceat(steps, np.concatenate([[0], turns])))
    longest = run = 0
    prev = np.inf
    for swing in swings:
        big = swing > np.log1p(SWING)
        run = run + 1 if big and swing >= prev / 2 else int(big)
        longest, prev = max(longest, run), swing
    return longest


@settings(max_examples=300, deadline=None)
@given(st.lists(st.one_of(st.just(0.0), st.floats(-1.5, 1.5)), max_size=60))
def test_the_loops_swing_count_is_the_reports(steps):
    log_c = np.cumsum([0.0, *steps])
    assert longest_run(log_c) == _reference_swings(log_c)


@pytest.mark.parametrize("force, warned", [("0", True), ("0.5", False), ("0.04", True)])
def test_an_open_loop_replay_of_a_trace_that_does_not_press_warns(tmp_path, force, warned):
    trace, out = tmp_path / "t.csv", tmp_path / "out"
    assert main(["trace", "synth", "swipe", "--force", force, "-o", str(trace)]) == 0
    assert main(["replay", "grating-15mm", str(trace), "--out", str(out), "--quiet"]) == 0
    said = [w for w in json.loads((out / "summary.json").read_text())["warnings"]
            if "press under 0.05 N" in w]
    assert len(said) == int(warned)
    if warned:
        assert f"the least {float(force):.2g} N" in said[0] and "force_n" in said[0]


def test_a_key_press_landing_through_a_low_force_is_not_warned_about(tmp_path):
    """The bundled key press rises from 0.04 N in one of its touch samples: a finger
    landing, not a trace without force."""
    out = tmp_path / "out"
    assert main(["replay", "keyclick-ring", "keyclick-press-100hz", "--out", str(out),
                 "--quiet"]) == 0
    assert not [w for w in json.loads((out / "summary.json").read_text())["warnings"]
                if "press under" in w]
