"""Every block the closed loop sends is counted once in its summary's ``control``: its
report used, missed, rejected, or still due when the run ended
(``measured.reports_pending_at_end``, app/engine/SUMMARY.md's ``control``)."""

import json
import re
from pathlib import Path
from types import SimpleNamespace

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.device.link.forces import ForceHistory, ForceReport
from frictex.device.profile import DeviceProfile
from frictex.rendering.control.loop import ClosedLoop

N = 25
RATE = 5000.0
DOC = Path(__file__).resolve().parents[1] / "app" / "engine" / "SUMMARY.md"


def _counted(control: dict) -> int:
    """The blocks ``control`` accounts for: used, missed, rejected and still due."""
    measured = control["measured"]
    return (measured["reports"] + measured["reports_missed"]
            + sum(control["reports_rejected"].values()) + measured["reports_pending_at_end"])


def _run(delay: int, blocks: int, lost=(), bad=()):
    """A finger sliding at 10 mm/s (the first block at 1 mm/s: mu0 measured) under a
    plate whose block j's report comes ``delay`` blocks after its end, except the
    ``lost`` ones; the ``bad`` ones read a lateral force that is not finite."""
    loop = ClosedLoop(DeviceProfile(), RATE, N, mode="closed")
    state, history = loop.initial_state(), ForceHistory()
    ones = np.ones((1, N))
    for k in range(blocks):
        j = k - 1 - delay
        if j >= 0 and j not in lost:
            normal = np.full(N, 0.5)
            lateral = np.full(N, np.nan if j in bad else 0.4 - 0.2 * (j > 0))
            history.add(ForceReport(j * N, lateral, normal))
        fingers = SimpleNamespace(contact=ones > 0, force=0.5 * ones,
                                  vx=(1.0 if k == 0 else 10.0) * ones, vy=0.0 * ones,
                                  index0=k * N)
        _, _, state = loop.invert(np.full((1, N), 0.6), fingers, state, history.window)
    return loop.report(state)


@pytest.mark.parametrize("delay, lost, bad", [(0, (), ()), (3, (10, 11), ()),
                                              (2, (5,), (20,)), (11, (), ())])
def test_each_block_sent_is_used_missed_rejected_or_still_due(delay, lost, bad):
    """The blocks whose reports had not come when the run ended (the last ``delay`` + 1,
    at most the 10 blocks of ``max_wait_s`` and two) are counted as pending."""
    blocks = 40
    report = _run(delay, blocks, lost, bad)
    measured = report["measured"]
    assert _counted(report) == blocks
    assert sum(report["reports_rejected"].values()) == len(bad)
    wait_blocks = int(round(ClosedLoop(DeviceProfile(), RATE, N).wait_samples)) // N
    # the block just sent, and those sent before it up to max_wait_s since their end
    assert measured["reports_pending_at_end"] == min(delay, wait_blocks + 1) + 1


@pytest.mark.parametrize("mode", ["closed", "adaptive"])
@pytest.mark.parametrize("clock", ["wall", "virtual"])
def test_a_replay_on_the_simulated_device_counts_every_block(tmp_path, mode, clock):
    """grating-15mm on the simulated finger 3: the blocks used, missed, rejected and
    still due add up to the run's blocks (401; 392 were counted before, on the wall
    clock, the last 9 nowhere)."""
    out = tmp_path / "out"
    assert main(["replay", "grating-15mm", "swipe-40mms-50hz", "--out", str(out), "--device",
                 "sim", "--sim-finger", "3", "--control", mode, "--clock", clock,
                 "--quiet", "--max-unplayed", "1"]) == 0  # the reports' count is the point
    doc = json.loads((out / "summary.json").read_text())
    blocks, rest = divmod(doc["output"]["samples"], doc["output"]["block_size"])
    assert rest == 0 and blocks == 401
    assert doc["control"]["measured"]["reports_pending_at_end"] >= 1  # the last block sent
    assert _counted(doc["control"]) == blocks


def test_each_measured_key_is_documented():
    """SUMMARY.md's ``control`` row names every key of ``control.measured`` (the schema
    test leaves ``control``'s keys to the loop's tests)."""
    row = next(line for line in DOC.read_text(encoding="utf-8").splitlines()
               if line.startswith("| `control` |"))
    named = set(re.findall(r"`([a-z0-9_]+)`", row))
    assert set(_run(1, 10)["measured"]) - named == set()
