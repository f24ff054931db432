"""A finger that touches down already sliding (a stroke that starts in the air): its
fingertip's lateral force rises through the skin's compliance (``device.finger``) for a
few ms, and its force report reads that rise as friction reduced far more than asked.
The loop must not learn from it (``rendering.control.loop``, docstring 1): the gain and
the adaptive model stay where they were, and no command jumps to the amplitude limit."""

import math
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.device.finger import FingerParams, FingerPlant
from frictex.device.link.forces import ForceHistory, ForceReport
from frictex.device.profile import DeviceProfile
from frictex.rendering.control.loop import ClosedLoop

RATE_HZ, N = 10000.0, 50
SPEED = 100.0  # mm/s, the tracker's and the finger's, touching down included
LIFT, DOWN, END = 250, 330, 350  # blocks: lifted over [LIFT, DOWN)
LATE = 2  # block k's report is folded at block k + LATE (one block late)


def _grating(k: int) -> float:
    """The target mu': bands of 15 blocks, 0.7 and 1.0."""
    return 0.7 if (k // 15) % 2 == 0 else 1.0


def _gain(loop: ClosedLoop, state) -> float:
    """The depth gain c at ``SPEED``."""
    report = loop.report(state)
    return report["gain"] * math.exp(report["log_gain_per_speed_ref"] * SPEED / 100.0)


def _run(mode: str):
    """The loop and the nominal finger over END blocks; returns per block (the mean
    command sent (um), the gain c after the block)."""
    device = DeviceProfile()
    loop = ClosedLoop(device, RATE_HZ, N, mode=mode)
    plant = FingerPlant(FingerParams(), RATE_HZ, device.amplitude_limit_um)
    state, finger, history = loop.initial_state(), plant.initial_state(), ForceHistory()
    reports, commands, gains = {}, [], []
    for k in range(END):
        if k - LATE in reports:
            history.add(reports.pop(k - LATE))
        down = not LIFT <= k < DOWN
        ones = np.ones((1, N))
        fingers = SimpleNamespace(contact=ones > 0 if down else ones < 0, force=0.5 * ones,
                                  vx=SPEED * ones, vy=0.0 * ones, index0=k * N)
        target = np.full((1, N), _grating(k) if down else 1.0)
        wanted, _, state = loop.invert(target, fingers, state, history.window)
        command = wanted[0]
        block, finger = plant.step(k * N, command, np.full(N, SPEED if down else 0.0),
                                   np.full(N, 0.5 if down else 0.0), finger)
        reports[k] = ForceReport(k * N, block.lateral_n, block.normal_n)
        commands.append(float(command.mean()))
        gains.append(_gain(loop, state))
    return loop, np.array(commands), np.array(gains)


@pytest.mark.parametrize("mode", ["closed", "adaptive"])
def test_a_moving_touch_down_teaches_the_loop_nothing(mode):
    loop, commands, gains = _run(mode)
    assert _grating(DOWN) == 0.7  # well within reach: about 0.7 um for the nominal finger
    after = commands[DOWN:DOWN + 20]
    assert after.max() < 0.9 * loop.limit_um, np.round(after, 3)
    # the touch-down block's report is folded at DOWN + LATE
    before, folded = gains[DOWN + LATE - 1], gains[DOWN + LATE]
    assert folded == pytest.approx(before, rel=0.03)
