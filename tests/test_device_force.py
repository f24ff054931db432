"""The normal force from a device's force sensors replaces the trace's (issue: key-click
with the normal force "from the trace or from the device's force sensors")."""

import time

import numpy as np
from numpy.testing import assert_allclose

from frictex.app.live.haptic_thread import HapticThread
from frictex.device.link.host import CommandSink, open_port
from link_checks import start_sim_device
from frictex.device.friction import make_friction_model
from frictex.rendering.pipeline import build_pipeline
from frictex.rendering.input.trace_file import make_trace
from scenes import grating_scene


def _still_fingers(forces):
    n = len(forces)
    return make_trace(np.zeros(n), np.arange(n), np.full(n, 1.0), np.full(n, 30.0),
                      np.array(forces))


def test_measured_force_is_shared_among_the_touching_fingers():
    scene = grating_scene(5.0, mu_low=0.7)  # x = 1 mm: inside the first low line
    pipeline = build_pipeline(scene)
    trace = _still_fingers([0.1, 0.2])
    out, _ = pipeline.process(0, trace, pipeline.initial_state(), normal_force_n=0.6)
    model = make_friction_model(scene.device)
    expected, _ = model.invert(0.7, 0.3)  # 0.6 N over two fingers
    assert_allclose(out.wanted_um, expected, rtol=1e-12)
    without, _ = pipeline.process(0, trace, pipeline.initial_state())
    assert_allclose(without.wanted_um[1], model.invert(0.7, 0.2)[0], rtol=1e-12)


def test_live_demo_uses_a_simulated_force_sensor():
    """The sim device reports 0.8 N; the touch says 0.1 N. At 0.8 N seed 003's asymptote
    is 0.904, so mu' 0.7 is out of reach: the plate goes to its limit (counted). The
    thread runs on a clock the test drives (sleeping advances it), so 0.3 s of output is
    0.3 s however busy the machine is."""
    proc, path = start_sim_device(1, 10_000.0, extra=("--force", "0.8"))
    sink = CommandSink(lambda: open_port(path), 1, 10_000.0, paced=False, label="sim",
                       process=proc)
    sent = []

    class Keep:
        def write(self, out, commands_um):
            sent.append(commands_um.copy())

        def commit(self):
            pass

        abort = commit

    now = [0.0]
    holder = {}

    def sleep(dt):
        now[0] += dt
        if now[0] >= 0.3:
            holder["thread"].stop()

    try:
        deadline = time.monotonic() + 10.0
        while sink.device_force_n() is None and time.monotonic() < deadline:
            time.sleep(0.01)
        assert sink.device_force_n() == 0.8
        thread = HapticThread(grating_scene(5.0, mu_low=0.7), sink=sink, recorder=Keep(),
                              clock=lambda: now[0], sleep=sleep)
        holder["thread"] = thread
        thread.touch_at(0.0, 0, 1.0, 30.0, 0.1, 0)
        thread.run()  # the loop in this thread: closes the link when it stops
    finally:
        sink.close()
    assert thread.error is None
    commands = np.concatenate(sent)[-500:, 0]
    assert_allclose(commands, 2.5)
    assert thread.stats.clamps.unreachable > 0
