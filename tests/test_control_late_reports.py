"""What the closed loop says when the device's force reports come back too late to steer
it (``ClosedLoop.report``'s messages, also in summary.json's ``warnings``): many missed,
or half of them at the longest the loop waits. At 5000 Hz with blocks of 25 samples the
loop waits 50 ms, 10 blocks."""

import json

import pytest

from frictex.app.commands.cli import main

import test_control_summary as loop_runs
from test_control_summary import _run

HINT = "; pace the host to the plate"


def _late_messages(report: dict) -> list[str]:
    return [m for m in report["messages"] if "force reports" in m]


@pytest.mark.parametrize("delay, said", [(3, False), (9, False), (10, True)])
def test_a_median_delay_at_the_wait_limit_is_said_once(delay, said):
    loop, state = _run(delay, 60)
    report = loop.report(state)
    assert report["measured"]["report_delay_p50_blocks"] == delay
    messages = [m for m in _late_messages(report) if "median delay" in m]
    assert len(messages) == said
    if said:
        assert f"({delay} blocks)" in messages[0] and "50 ms" in messages[0]


@pytest.mark.parametrize("lost, said", [((10,), False), (tuple(range(10, 14)), True)])
def test_more_than_one_in_twenty_reports_missed_is_said(lost, said):
    loop, state = _run(2, 40, lost)
    measured = loop.report(state)["measured"]
    messages = [m for m in _late_messages(loop.report(state)) if "were missed" in m]
    assert len(messages) == said
    if said:
        folded = measured["reports"] + measured["reports_missed"]
        assert f"({len(lost)} of {folded})" in messages[0]


def test_the_callers_hint_ends_each_late_line():
    loop, state = _run(10, 60, tuple(range(20, 26)))
    messages = _late_messages(loop.report(state, late_hint=HINT))
    assert len(messages) == 2 and all(m.endswith(HINT) for m in messages)


def test_a_nan_target_is_left_out_of_the_measured_rms(monkeypatch):
    """A block whose texture gives nan for some samples (the inverse model clamps them,
    ``clamps.nonfinite_target``): the RMS of measured against target is over the others."""
    nan_samples = 5
    reference = _run(0, 30)
    block = loop_runs._block

    def block_with_nans(index0, speed, force_n=0.5):
        target, fingers = block(index0, speed, force_n)
        target[0, :nan_samples] = float("nan")
        return target, fingers

    monkeypatch.setattr(loop_runs, "_block", block_with_nans)
    loop, state = _run(0, 30)
    measured = loop.report(state)["measured"]
    kept = reference[0].report(reference[1])["measured"]["samples"]
    assert measured["rms_mu_vs_target"] is not None and measured["rms_mu_vs_target"] < 1.0
    assert measured["samples"] == kept - nan_samples * kept // loop_runs.N


def test_a_replay_on_the_virtual_clock_says_to_pace_the_host(tmp_path):
    """The default virtual clock lets the host run as far ahead of the simulated plate as
    its buffer allows: the reports come 6 blocks (60 ms) late, after the loop's wait of
    50 ms, and are all missed."""
    out = tmp_path / "out"
    assert main(["replay", "grating-15mm", "swipe-40mms-50hz", "--out", str(out), "--device",
                 "sim", "--sim-finger", "3", "--control", "closed", "--block", "100",
                 "--quiet", "--max-unplayed", "1"]) == 0  # the reports' delay is the point
    warnings = json.loads((out / "summary.json").read_text())["warnings"]
    said = [w for w in warnings if "force reports" in w]
    assert said and all(w.endswith("--clock wall paces it to the plate (or give the device "
                                   "a smaller buffer)") for w in said)


def test_a_report_later_than_the_wait_is_missed_not_used_at_the_longest_delay():
    """Reports 11 blocks (55 ms) late, the loop waiting 10 (50 ms): each was used as 10
    blocks late, its integrator stepping at the gain scheduled for 10 blocks (a gain
    margin of 7.33 at its real 11). Each is missed, as one that never came."""
    loop, state = _run(11, 40)
    measured = loop.report(state)["measured"]
    folded = 40 - len(state.pending)
    assert folded > 20
    assert measured["reports"] == 0 and measured["reports_missed"] == folded
    assert state.reports_late == folded
    assert state.delay_counts == () and state.delay_blocks == 0
    assert any("were missed" in m for m in _late_messages(loop.report(state)))
