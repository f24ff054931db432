"""The friction loop (rendering/control) with the simulated finger on the run engine."""

import math

import numpy as np
import pytest

from frictex.app.measure.report_closed_loop import BLOCK, RATE_HZ, REPORT_DELAY_BLOCKS, Run, simulate
from frictex.device.finger import draw_finger, rest_mu
from frictex.rendering.control.loop import LoopConfig
from frictex.device.finger import SensorParams
from frictex.rendering.control.margins import COVER_SLOPE, KI_MAX, margins, scheduled_ki


def _simulate_loop(ki, delay_blocks, rate, block, blocks=1500):
    """The linearised loop of rendering.control.margins written out sample by sample: x
    (log gain) held over each block, through the plate's, the fingertip's and the
    sensor's one-pole low-passes and the sensor's delay, averaged over the block, used
    ``delay_blocks`` later by the integrator against a finger 1.5x off the model.
    Returns the measured error per block."""
    poles = [math.exp(-2 * math.pi * bw / rate) for bw in (400.0, 90.0, 1000.0)]
    line = [0.0] * int(round(0.0005 * rate))
    states = [0.0, 0.0, 0.0]
    x, offset, queue, errors = 0.0, math.log(1.5), [], []
    for _ in range(blocks):
        total = 0.0
        for _ in range(block):
            v = x
            for i, p in enumerate(poles):
                states[i] = p * states[i] + (1 - p) * v
                v = states[i]
            line.append(v)
            total += line.pop(0)
        queue.append(total / block + offset)
        errors.append(queue[-1])
        if len(queue) > delay_blocks:
            x -= ki * queue.pop(0)
    return np.abs(np.array(errors))


def _grows(errors):
    """Late error envelope against an earlier one: > 1 grows, < 1 decays."""
    return errors[-200:].max() / errors[300:500].max()


@pytest.mark.parametrize("rate,block", [(5000.0, 25), (10_000.0, 50)])
def test_margins_against_the_loop_simulated(rate, block):
    """At each report delay the scheduled gain settles; at the gain margin it turns: 3 %
    below it decays, 3 % above it grows; with the delay margin's whole blocks of extra
    delay it settles, one more block and it grows (the phase margin over the crossover)."""
    m = margins((0, 1, REPORT_DELAY_BLOCKS), SensorParams(), rate, block)
    for row in m["rows"]:
        d, ki = row["delay_blocks"], row["ki"]
        assert ki == scheduled_ki(d, SensorParams(), rate, block)
        assert _simulate_loop(ki, d, rate, block, blocks=4000)[-1] < 1e-6
        gm = row["gain_margin"]
        assert _grows(_simulate_loop(ki * gm * 0.97, d, rate, block)) < 1.0
        assert _grows(_simulate_loop(ki * gm * 1.03, d, rate, block)) > 1.0
        if d == 0:  # at longer delays the delay margin is tens of blocks: the same check
            extra = row["delay_margin_blocks"]
            assert _grows(_simulate_loop(ki, d + math.floor(extra), rate, block)) < 1.0
            assert _grows(_simulate_loop(ki, d + math.ceil(extra), rate, block)) > 1.0
        # the schedule: a gain margin of COVER_SLOPE (above the population's steepest
        # finger, 7.37) wherever the cap KI_MAX does not bind, and a wide phase margin
        assert gm >= COVER_SLOPE * (1 - 1e-9) and row["phase_margin_deg"] > 60
        assert ki <= KI_MAX and (ki == KI_MAX or abs(gm / COVER_SLOPE - 1) < 1e-3)
    kis = [row["ki"] for row in m["rows"]]
    assert kis == sorted(kis, reverse=True) and kis[-1] < kis[0] / 4  # later: slower


def test_loop_replay_is_deterministic_for_a_fixed_finger():
    a, sa = simulate(Run("grating-15mm", 2, "adaptive", 1.5))
    b, sb = simulate(Run("grating-15mm", 2, "adaptive", 1.5))
    np.testing.assert_array_equal(a.arrays()["delivered"], b.arrays()["delivered"])
    assert 0.0 < a.max_command_um <= 2.5  # never beyond the device's limit
    assert sa.state.control.log_c == sb.state.control.log_c
    assert sa.state.control.rls == sb.state.control.rls


def test_a_dead_sensor_falls_back_within_the_stale_time():
    dead_at = 1.0
    sink, stage = simulate(Run("grating-15mm", 2, "closed", 1.6, sensor_dead_after_s=dead_at))
    control = stage.state.control
    assert control.fallbacks == 1 and len(control.messages) == 1
    assert "stale" in control.messages[0]
    # everything from the first block past max_wait_s + stale_s + one block is open loop
    block_s = BLOCK / RATE_HZ
    bound = LoopConfig().max_wait_s + LoopConfig().stale_s + 2 * block_s
    run_after = 1.6 - dead_at
    assert control.fallback_samples >= (run_after - bound) * RATE_HZ - BLOCK


def test_a_finger_at_rest_does_not_wind_the_integrator_up():
    """The trace holds still on a low-friction line: no sliding, so no update at all."""
    from frictex.app.engine.clocks import VirtualClock
    from frictex.app.engine.driver import drive
    from frictex.app.engine.sources import TraceSource
    from frictex.app.measure.closed_loop_sim import FingerSink, LoopStage
    from frictex.app.measure.report_matrix import load
    from frictex.device.finger import FingerPlant
    from frictex.rendering.input.trace_file import DOWN, MOVE, make_trace
    from frictex.rendering.pipeline import build_pipeline
    scene = load("grating-15mm")
    t = np.arange(0, 2.0, 0.02)
    trace = make_trace(t, np.zeros(t.size, dtype=int), np.full(t.size, 3.0),
                       np.full(t.size, 30.0), event=[DOWN] + [MOVE] * (t.size - 1))
    pipeline = build_pipeline(scene, rate_hz=RATE_HZ, block_size=BLOCK, control="closed")
    plant = FingerPlant(draw_finger(3), RATE_HZ, 2.5, seed=3)
    sink = FingerSink(plant, lambda s: np.zeros(np.size(s)), lambda s: np.full(np.size(s), 0.5))
    stage = LoopStage(pipeline, sink)
    source = TraceSource(iter([trace]), until_s=2.0)
    source.start(pipeline.tracker_config)
    drive(stage, source, [sink], VirtualClock())
    control = stage.state.control
    assert sink.arrays()["target"].min() < 1.0  # it was asked for a reduction
    assert control.log_c == 0.0 and control.updates == 0 and control.fallbacks == 0


def test_the_friction_at_rest_tracks_a_known_drift():
    """Finger 3's mu0 rises by moisture during the run; the estimate follows it."""
    sink, stage = simulate(Run("grating-15mm", 3, "closed", 6.0))
    truth = float(rest_mu(6.0, draw_finger(3)))
    start = float(rest_mu(0.0, draw_finger(3)))
    assert truth > start * 1.005  # a drift that is there
    assert abs(stage.state.control.mu0 / truth - 1) < 0.02


@pytest.mark.parametrize("fault,said", [(lambda r: (r.lateral_n * 0, r.normal_n * 0), "implausible"),
                                        (lambda r: (r.lateral_n + 10.0, r.normal_n), "saturated"),
                                        (lambda r: (r.lateral_n * np.nan, r.normal_n), "not finite")])
def test_a_sensor_that_goes_bad_falls_back_at_the_next_block(monkeypatch, fault, said):
    """Reports from 1.0 s on are zeros, beyond full scale, or NaN: open loop from the block
    that first has a bad report (REPORT_DELAY_BLOCKS after the block it measures), said
    once."""
    from frictex.app.measure import closed_loop_sim
    from frictex.device.link.forces import ForceReport
    write = closed_loop_sim.FingerSink.write

    def faulty(self, out, commands_um):
        write(self, out, commands_um)
        if out.t_s[0] >= 1.0 and self.report is not None:
            lat, nor = fault(self.report)
            self.report = ForceReport(self.report.index0, lat, nor)

    monkeypatch.setattr(closed_loop_sim.FingerSink, "write", faulty)
    _, stage = simulate(Run("grating-15mm", 2, "closed", 1.5))
    control = stage.state.control
    assert control.fallbacks == 1 and said in control.messages[0]
    assert control.fallback_samples >= 0.5 * RATE_HZ - (2 + REPORT_DELAY_BLOCKS) * BLOCK


def test_a_loop_past_its_gain_margin_is_seen_oscillating():
    """The report's oscillation check can fail: the same finger with the integrator's gain
    1.5x past the stated gain margin swings for many periods; at the stated gain not."""
    from frictex.rendering.control.swings import OSCILLATION_STEPS, longest_run as gain_swings
    _, stage = simulate(Run("grating-15mm", 4, "closed", 2.0))
    assert gain_swings(np.array(stage.log_c)) < OSCILLATION_STEPS
    report = stage.pipeline.control.report(stage.state.control)
    assert report["gain_oscillations"] == 0 and not report["messages"]
    row = margins((REPORT_DELAY_BLOCKS,), SensorParams(), RATE_HZ, BLOCK)["rows"][0]
    ki = row["ki"] * row["gain_margin"] * 1.5
    _, stage = simulate(Run("grating-15mm", 4, "closed", 3.0), loop_config=LoopConfig(ki=ki))
    assert set(stage.pipeline.control.ki_by_delay) == {ki}
    assert gain_swings(np.array(stage.log_c)) >= 2 * OSCILLATION_STEPS
    # the loop sees it too, says so once and counts it (the replay's summary)
    report = stage.pipeline.control.report(stage.state.control)
    assert report["gain_oscillations"] >= 1
    assert report["gain_swings_max"] == gain_swings(np.array(stage.log_c))
    said = [m for m in report["messages"] if "gain oscillates" in m]
    assert len(said) == 1 and f"ki {ki:.3g}" in said[0]


def test_mu0_is_measured_as_the_first_stroke_starts():
    """Finger 11 starts its first stroke on a reduced band of the 15 mm grating and slides
    slowly (4-20 mm/s) for half a second: the plate held still while it starts gives mu0
    within 2 % by 0.25 s (without the probe, the first unreduced band came at 0.67 s)."""
    sink, stage = simulate(Run("grating-15mm", 11, "closed", 0.4))
    assert stage.first_mu0_s is not None and stage.first_mu0_s < 0.25
    truth = float(rest_mu(0.4, draw_finger(11)))
    assert abs(stage.state.control.mu0 / truth - 1) < 0.02
    a = sink.arrays()
    assert (a["target"] < 1).mean() > 0.9  # it was on a reduced band throughout
