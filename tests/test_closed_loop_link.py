"""The friction loop closed over a real link: replay and the live thread streaming to the
simulated device, whose simulated finger (``frictex sim-device --finger``) sends the
force reports the loop reads, several blocks after each block."""

import json
import time

import numpy as np
import pytest

from frictex.app.commands.cli import main
from frictex.app.engine.replay import run_replay
from frictex.device.finger import draw_finger, rest_mu
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace

RATE = 10_000.0


def _swipe(duration_s=2.0, speed_mm_s=100.0):
    """A 50 Hz swipe across the 15 mm grating at the simulated finger's own speed."""
    t = np.arange(0.0, duration_s, 0.02)
    x = 20.0 + speed_mm_s * t
    events = [DOWN] + [MOVE] * (t.size - 2) + [UP]
    return make_trace(t, np.zeros(t.size, dtype=int), x, np.full(t.size, 40.0), event=events)


def test_a_replay_to_the_simulated_device_closes_the_loop_on_its_reports(tmp_path):
    """The loop pairs each block with its report however late it comes back over the
    link (measured, at least one block), its gain moves, it finds the finger's friction
    at rest, and no command passes the device's limit."""
    doc = run_replay("grating-15mm", _swipe(), tmp_path, rate_hz=RATE, device="sim",
                     sim_args=("--finger", "3"), control="closed", progress=False)
    loop = doc["control"]
    assert loop["mode"] == "closed" and loop["updates"] >= 20
    assert 1 <= loop["report_delay_blocks"] <= 10  # a link's delay, within max_wait_s
    assert loop["gain"] != 1.0
    # the simulated finger slides at 100 mm/s with 0.5 N; its friction at rest, measured
    truth = float(rest_mu(0.0, draw_finger(3)))
    assert abs(loop["mu0"] / truth - 1) < 0.05
    assert doc["counts"]["max_amplitude_um"] <= 2.5
    assert json.loads((tmp_path / "summary.json").read_text())["control"] == loop


@pytest.mark.parametrize("mode", ["closed", "adaptive"])
def test_a_loop_without_force_reports_is_refused_before_the_run(tmp_path, mode):
    """No device, or one that announces no lateral force sensor: the loop would have
    nothing to read and run open loop; the replay is refused before it runs, in one
    line (bad input without a device, exit 2; the device's lack, exit 1), and writes
    nothing."""
    from frictex.device.errors import DeviceError, InputError
    out = tmp_path / "out"
    with pytest.raises(InputError, match=f"control '{mode}' reads the force reports of a "
                                         "device, and no device was given"):
        run_replay("grating-15mm", _swipe(0.5), out, rate_hz=RATE, control=mode,
                   progress=False)
    with pytest.raises(DeviceError, match=r"sim:// sends no force reports .* so control "
                                          f"'{mode}' has nothing to measure"):
        run_replay("grating-15mm", _swipe(0.5), out, rate_hz=RATE, control=mode,
                   device="sim", progress=False)
    assert not out.exists()
    trace = tmp_path / "swipe.csv"
    from frictex.rendering.input.trace_file import write_trace
    write_trace(trace, _swipe(0.5))
    args = ["replay", "grating-15mm", str(trace), "--out", str(out), "--control", mode]
    assert main(args) == 2
    assert main([*args, "--device", "sim"]) == 1
    assert not out.exists()


def test_the_summary_line_names_each_gain():
    """The loop's two gains are different figures: the line says which is which."""
    from frictex.app.engine.summary import control_line
    line = control_line({"mode": "closed", "report_delay_blocks": 3,
                         "scheduled_delay_blocks": 2, "ki": 0.269, "gain": 1.25, "updates": 40,
                         "fallbacks": 0, "fallback_samples": 0})
    assert "depth gain c 1.250 at the end (reduction asked = c x the texture's; 40 updates)" \
        in line
    assert "integrator step ki 0.269 per block at the end (scheduled for reports 2 blocks late)" \
        in line
    assert line.count("gain") == 1  # the word alone, unnamed, nowhere


def test_the_summary_line_says_when_no_report_was_usable(tmp_path, capsys):
    """A saturated sensor (the simulated finger pressing 4.99 N): 390 reports came and
    none was usable; the line said 'force reports up to 0 blocks late'."""
    out = tmp_path / "out"
    assert main(["replay", "grating-15mm", "swipe-40mms-50hz", "--out", str(out), "--device",
                 "sim:finger=3,force=4.99", "--control", "adaptive", "--quiet"]) == 0
    control = json.loads((out / "summary.json").read_text())["control"]
    assert control["measured"]["reports"] == 0 and control["reports_rejected"]["saturated"] > 0
    from frictex.app.engine.summary import control_line
    rejected = sum(control["reports_rejected"].values())
    assert control_line(control).startswith(
        f"adaptive loop: no usable force report ({rejected} rejected, "
        f"{control['measured']['reports_missed']} missed); depth gain c 1.000")


def test_the_live_thread_reads_the_links_force_reports():
    """The live haptic thread on the wall clock, streaming to the simulated device with a
    finger: a swipe fed as the window would feed it; the loop measures the reports'
    delay and learns from them. What is asserted holds however late the reports come
    on a busy machine (a report later than max_wait_s only makes the loop fall back)."""
    from frictex.app.live.haptic_thread import HapticThread
    from frictex.device.link.host import open_sink
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    scene = load_scene(resolve_scene("grating-15mm"))
    haptic = HapticThread(scene, RATE, 50, control="closed")
    haptic.sink = open_sink("sim", 1, RATE, paced=False, sim_args=("--finger", "3"))
    haptic.start()
    try:
        t0 = haptic.now()
        while (t := haptic.now() - t0) < 1.5:
            haptic.touch(0, 20.0 + 100.0 * t, 40.0, 0.5, "down" if t == 0 else "move")
            time.sleep(0.02)
        haptic.touch(0, 170.0, 40.0, 0.5, "up")
        time.sleep(0.1)
    finally:
        haptic.stop()
        haptic.join(timeout=10.0)
    assert haptic.error is None and not haptic.is_alive()
    loop = haptic.stats.control
    assert loop is not None and loop["mode"] == "closed"
    # the loop read the link's reports: it paired some (always later than the next
    # block), or they came later than max_wait_s and it fell back saying they were
    # stale; never "absent", as a loop that was not given them would say
    paired = loop["report_delay_blocks"] >= 1
    assert paired or (loop["fallbacks"] >= 1 and "stale" in loop["messages"][0])
    assert not any("absent" in message for message in loop["messages"])


@pytest.mark.parametrize("argv, message", [
    (["--sim-finger", "3"], "--sim-finger 3: needs --device sim (a simulated device); no "
                            "--device was given"),
    (["--sim-finger", "3", "--device", "/dev/null"], "got --device /dev/null"),
    (["--sim-finger", "-1", "--device", "sim"], "--sim-finger -1: expected a person number >= 0"),
    (["--faults", "corrupt=0.01"], "--faults: needs --device (the faults are injected on the "
                                   "link to a device); no --device was given"),
    (["--max-unplayed", "0.5"], "--max-unplayed 0.5: needs --device"),
])
def test_device_options_need_a_device(argv, message, tmp_path, capsys):
    """Device options without the device they act on are refused, not ignored."""
    out = tmp_path / "out"
    assert main(["replay", "grating-15mm", "swipe-40mms-50hz", "--out", str(out), *argv]) == 2
    assert not out.exists()
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1


def test_the_live_stage_tells_the_loop_what_an_emergency_stop_played():
    """A block the emergency stop zeroed is kept by the loop as played at 0 um with no
    reduction asked (so its report of a still plate is not read as a slippery finger),
    where the block before it, mid-band, asked for a reduction."""
    import threading
    from frictex.app.live.haptic_thread import HapticStats, LiveStage
    from frictex.rendering.pipeline import build_pipeline
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    pipeline = build_pipeline(load_scene(resolve_scene("grating-15mm")), RATE, 50,
                              control="closed")
    estop = threading.Event()
    stage = LiveStage(pipeline, estop, HapticStats())
    swipe = _swipe(0.5)
    block_s = 50 / RATE
    asking = False
    for k in range(100):  # slide until the loop asks for a reduction, then stop
        if asking:
            estop.set()
        take = (swipe.t_s >= k * block_s) & (swipe.t_s < (k + 1) * block_s)
        rows = np.flatnonzero(take)
        samples = None if not rows.size else make_trace(
            swipe.t_s[rows], swipe.finger[rows], swipe.x_mm[rows], swipe.y_mm[rows],
            event=swipe.event[rows])
        _, commands = stage.process(k, samples, 1)
        sent = stage.state.control.pending[-1]
        if asking:
            break
        asking = bool((sent.target < 1.0).any() and sent.w_um.any())
    # the stop came mid-band (7.5 mm at 100 mm/s is 15 blocks): the loop would have
    # asked again; it keeps what played
    assert asking and not commands.any()
    assert not sent.w_um.any() and (sent.target == 1.0).all()
