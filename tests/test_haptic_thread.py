"""The live haptic thread, on a clock and input the test drives (no real time involved).

``run_scripted`` runs the thread's loop in the test's own thread with a fake wall clock:
sleeping advances it, and touch samples are fed when it reaches their times, so the
result is the same however busy the machine is.
"""

import pickle

import numpy as np
import pytest

from frictex.app.engine.sources import QueueSource
from frictex.app.live.haptic_thread import ChannelMismatch, HapticThread
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from scenes import grating_edges, straddling_samples


class Collect:
    """A sink keeping every block output and the commands sent."""

    def __init__(self):
        self.outs, self.commands = [], []
        self.committed = False

    def write(self, out, commands_um):
        self.outs.append(out)
        self.commands.append(commands_um.copy())

    def commit(self):
        self.committed = True

    abort = commit


def run_scripted(scene, events, end_s, **kwargs):
    """Run a HapticThread on a fake clock until ``end_s`` (s on its output clock),
    feeding ``events`` (t_s, finger, x_mm, y_mm, force_n, event name) as time reaches
    them. Returns (thread, Collect)."""
    now = [100.0]
    events = sorted(events)
    collect = Collect()
    holder = {}

    def sleep(dt):
        now[0] += dt
        thread = holder["thread"]
        while events and events[0][0] <= thread.now():
            t, *rest = events.pop(0)
            thread.touch(*rest)
        if thread.now() >= end_s:
            thread.stop()

    thread = HapticThread(scene, clock=lambda: now[0], sleep=sleep, recorder=collect, **kwargs)
    holder["thread"] = thread
    thread.wall.restart()
    thread.t0 = thread.wall.t0
    thread.run()
    assert thread.error is None
    return thread, collect


def drag(x0_mm, speed_mm_s, duration_s, every_s=0.02, y_mm=32.4):
    """A one-finger drag sampled every ``every_s``: down, moves, up."""
    times = np.arange(0.0, duration_s, every_s)
    events = [(0.01, 0, x0_mm, y_mm, 0.5, "down")]
    events += [(0.01 + t, 0, x0_mm + speed_mm_s * t, y_mm, 0.5, "move") for t in times[1:]]
    events.append((0.01 + duration_s, 0, x0_mm + speed_mm_s * duration_s, y_mm, 0.5, "up"))
    return events


def test_sht_texture_follows_a_live_drag():
    """grating-5mm renders periodic layers by synthesis from velocity: a live drag at
    40 mm/s for 1 s must give mu' steps at 40 / 2.5 = 16 per second. (A batch of live
    samples taken for a new touch would restart SHT's phase at every block and freeze
    mu'.)"""
    thread, collect = run_scripted(load_scene(resolve_scene("grating-5mm")),
                                   drag(20.0, 40.0, 1.0), end_s=1.2, render_override="sht")
    mu = np.concatenate([o.mu_target[0][o.contact[0]] for o in collect.outs if o.mu_target.size])
    # the two levels, but for one sample at most per edge that plays both sides
    # (rendering.layers.band_limit)
    steps = grating_edges(mu)
    assert straddling_samples(mu) <= steps
    assert 14 <= steps <= 17  # 16 edges in 40 mm, give or take the start and the stop
    assert thread.stats.deadline_misses == 0  # the fake clock never runs late
    assert collect.committed  # the driver commits the sinks when the thread stops


def test_blocks_follow_the_clock_one_per_block_time():
    """On the wall clock each block starts at t0 + k * block_s: 0.5 s of fake time at
    10 kHz in the live blocks of 25 samples is 200 blocks, contiguous on the output clock."""
    thread, collect = run_scripted(load_scene(resolve_scene("grating-5mm")), [], end_s=0.5)
    assert thread.block_size == 25
    assert len(collect.outs) == thread.stats.blocks
    assert abs(len(collect.outs) - 200) <= 1
    assert all(o.t_s.size == 25 for o in collect.outs)
    t = np.concatenate([o.t_s for o in collect.outs])
    np.testing.assert_allclose(np.diff(t), 1e-4, rtol=1e-9)


def test_emergency_stop_is_immediate_and_resumes_by_a_ramp():
    """While the stop is set every command is 0 um; the block after it clears ramps from
    0 to the pipeline's commands (no step the finger feels)."""
    scene = load_scene(resolve_scene("grating-5mm"))
    holder = {}
    now = [0.0]  # the output clock starts at 0 on this clock

    class EstopAt:
        """Set between 0.3 and 0.5 s, as two key presses would."""

        def is_set(self):
            return 0.3 <= now[0] < 0.5

    estop = EstopAt()

    def sleep(dt):
        now[0] += dt
        thread = holder["thread"]
        if thread.now() >= 0.8:
            thread.stop()

    collect = Collect()
    thread = HapticThread(scene, clock=lambda: now[0], sleep=sleep, recorder=collect,
                          estop=estop)
    holder["thread"] = thread
    thread.touch_at(0.0, 0, 20.0, 32.4, 0.5, 0)
    thread.run()
    t = np.concatenate([o.t_s for o in collect.outs])
    cmd = np.concatenate(collect.commands)[:, 0]
    stopped = (t >= 0.3 + 0.005) & (t < 0.5)
    assert stopped.sum() > 1000 and (cmd[stopped] == 0.0).all()
    # the recording's amplitude under the finger is the 0 um sent, not what the
    # pipeline would have played (it was up to 1.51 um)
    amplitude = np.concatenate([o.amplitude_um.max(axis=0) for o in collect.outs])
    assert amplitude[~stopped & (t < 0.3)].max() > 0.5 and (amplitude[stopped] == 0.0).all()
    after = np.flatnonzero(t >= 0.5)[:60]
    assert cmd[after[-1]] > 0.5  # the finger is on a slippery line: well above 0
    # a ramp across one block, not a step: each sample moves about 1/25 of the way
    assert np.max(np.abs(np.diff(cmd[after]))) < 1.5 * cmd[after[-1]] / thread.block_size


def test_touch_stamps_never_go_back_nor_ahead():
    """Sources with their own clocks (TUIO arrival, evdev kernel time) feed one live
    batch: a stamp before the last one is moved up to it, one in the future down to now
    (make_trace refuses a batch going back in time)."""
    now = [10.0]
    thread = HapticThread(load_scene(resolve_scene("grating-5mm")), clock=lambda: now[0])
    now[0] = 12.0  # the thread's clock reads 2.0 s
    thread.touch_at(1.5, 0, 1.0, 1.0, 0.5, 0)
    thread.touch_at(0.7, 1, 2.0, 2.0, 0.5, 0)  # older than the last stamp
    thread.touch_at(9.0, 0, 3.0, 3.0, 0.5, 1)  # in the future
    trace, n = QueueSource(thread.touches, thread.block_s).take(800, 1)  # block 800: 2.0 s
    assert trace.t_s.tolist() == [1.5, 1.5, 2.0] and trace.finger.tolist() == [0, 1, 0]
    assert n == 1


def test_switch_to_another_device_is_refused_while_recording():
    """A recording (or a link) was opened for the scene's channels: a scene driving other
    channels (a beam's two transducers) would not fit it. Without one, it ramps in."""
    plate = load_scene(resolve_scene("grating-5mm"))
    beam = load_scene(resolve_scene("two-finger-beam-seed000"))
    thread = HapticThread(plate, recorder=Collect())
    with pytest.raises(ChannelMismatch, match=r"two-finger-beam-seed000 drives channels xA, xB .*"
                                              r"opened for ch0 \(plate-seed003\)") as refused:
        thread.switch(beam)
    # it reaches the window's process whole (the haptic process pickles it)
    again = pickle.loads(pickle.dumps(refused.value))
    assert isinstance(again, ValueError) and str(again) == str(refused.value)
    assert (again.scene, again.opened) == ("two-finger-beam-seed000", "ch0 (plate-seed003)")
    assert thread.stage.changes.empty()
    free = HapticThread(plate)
    assert free.switch(beam).channels == ("xA", "xB")
    out, commands = free.stage.process(0, None, 1)
    assert commands.shape == (25, 2) and free.pipeline.channels == ("xA", "xB")
