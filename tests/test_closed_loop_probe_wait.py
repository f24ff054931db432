"""The closed loop's probe (``rendering.control.loop``, docstring 1) holds the plate still
for the first force report's sake only while that report can still come in time: a
session that starts with the finger down and whose reports are late past ``max_wait_s``
or lost is fed forward open loop from the first block after the first report is missed,
not held until the stale fallback (``stale_s`` later); a usable report that comes later
still lets the probe measure mu0 and close the loop. At 5000 Hz with blocks of 25 samples
the loop waits 50 ms, 10 blocks."""

from types import SimpleNamespace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.device.friction import SeedFrictionModel
from frictex.device.link.forces import ForceHistory, ForceReport
from frictex.device.profile import DeviceProfile
from frictex.rendering.control.loop import ClosedLoop

RATE_HZ, N = 5000.0, 25
MU0 = 0.8
TARGET = 0.6  # a reduction of 0.4 asked everywhere: the probe's hold withholds all of it
SPEED = 1.0  # mm/s, the tracker's: slower than probe_mm_s all along, so the probe would hold
FORCE_N = 0.5
LOST = None


def _run(delay_of, blocks):
    """The loop over ``blocks`` blocks; block j's report (the finger on the still plate,
    F_t = MU0 F_n) comes ``delay_of(j)`` blocks after it ends (``LOST``: never). Returns
    the loop, each block's amplitude (um, (blocks, N)) and the final state."""
    loop = ClosedLoop(DeviceProfile(), RATE_HZ, N, mode="closed")
    state, history, due = loop.initial_state(), ForceHistory(), {}
    normal = np.full(N, FORCE_N)
    for j in range(blocks):
        delay = delay_of(j)
        if delay is not LOST:
            due.setdefault(j + 1 + delay, []).append(ForceReport(j * N, MU0 * normal, normal))
    wanted = []
    for k in range(blocks):
        for report in due.pop(k, []):
            history.add(report)
        ones = np.ones((1, N))
        fingers = SimpleNamespace(contact=ones > 0, force=FORCE_N * ones, vx=SPEED * ones,
                                  vy=0.0 * ones, index0=k * N)
        w, _, state = loop.invert(np.full((1, N), TARGET), fingers, state, history.window)
        wanted.append(w[0])
    return loop, np.array(wanted), state


def _first_after_missed(loop: ClosedLoop) -> int:
    """The first block computed after block 0's report is missed: block 0 ends at N, and
    its report is missed once the block being computed starts more than max_wait_s later."""
    return int(loop.wait_samples // N) + 2


def _open_loop_um() -> float:
    """The open loop's amplitude (um) for ``TARGET`` at ``FORCE_N``: the device's model."""
    w, _ = SeedFrictionModel(DeviceProfile()).invert(np.array([TARGET]), np.array([FORCE_N]))
    return float(w[0])


@pytest.mark.parametrize("late", [11, 30, LOST], ids=["late-11", "late-30", "lost"])
def test_reports_that_never_come_in_time_end_the_hold_at_the_first_missed(late):
    loop, wanted, state = _run(lambda j: late, 40)
    bound = _first_after_missed(loop)
    assert bound == 12
    assert not wanted[:bound].any()  # held: block 0's report could still have come
    assert _open_loop_um() > 0.3
    assert_allclose(wanted[bound:], _open_loop_um(), rtol=1e-9)
    assert state.reports == 0 and state.fallback  # the stale fallback came after, as before


def test_a_later_usable_report_still_measures_mu0_and_closes_the_loop():
    first_good = 30  # blocks 0 .. 29 lost, the rest 2 blocks late (in time)
    loop, wanted, state = _run(lambda j: LOST if j < first_good else 2, 160)
    bound = _first_after_missed(loop)
    assert_allclose(wanted[bound:first_good], _open_loop_um(), rtol=1e-9)
    assert any("stale" in m for m in state.messages)
    # once the reports are good again the probe holds the plate and measures mu0 ...
    assert not wanted[first_good:].all(axis=1).all()
    assert state.mu0 == pytest.approx(MU0, rel=1e-9) and not state.fallback
    # ... and the loop is closed: the reports read no reduction, so its gain asks more
    assert state.updates > 0
    assert wanted[-1].min() > 1.5 * _open_loop_um()


def test_reports_at_the_longest_wait_keep_the_whole_hold():
    """Reports 10 blocks late are in time: the plate is held until mu0 is measured, from
    block 0's report at block 11, as the probe did before any bound."""
    loop, wanted, state = _run(lambda j: 10, 30)
    assert state.mu0 == pytest.approx(MU0, rel=1e-9) and state.reports_missed == 0
    assert not wanted[:11].any()
    assert wanted[11:].all()
