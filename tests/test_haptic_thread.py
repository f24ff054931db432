"""The live haptic thread keeps a touch continuous across its input batches."""

import time

import numpy as np
import pytest

from app.live.haptic_thread import HapticThread
from textures.library import resolve_scene
from textures.loader import load_scene


def test_sht_texture_follows_a_live_drag():
    """grating-5mm renders by period synthesis (auto, 5 mm): a live drag at 40 mm/s must
    give mu' steps at 40 / 2.5 = 16 per second. (A batch of live samples taken for a new
    touch would restart SHT's phase at every block and freeze mu'.)"""
    outs = []
    thread = HapticThread(load_scene(resolve_scene("grating-5mm")),
                          recorder=lambda out, commands: outs.append(out))
    thread.start()
    try:
        t_start = thread.now()
        thread.touch(0, 20.0, 32.4, 0.5, "down")
        while (t := thread.now() - t_start) < 1.0:
            thread.touch(0, 20.0 + 40.0 * t, 32.4, 0.5, "move")
            time.sleep(0.01)
        thread.touch(0, 60.0, 32.4, 0.5, "up")
        time.sleep(0.05)
    finally:
        thread.stop()
        thread.join(timeout=2)
    mu = np.concatenate([o.mu_target[0][o.contact[0]] for o in outs if o.mu_target.size])
    steps = np.count_nonzero(np.diff(mu) != 0)
    assert set(np.round(np.unique(mu), 6)) == {0.6, 1.0}
    assert 12 <= steps <= 18  # 16 edges in 40 mm, give or take the start and the stop


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
    trace = thread._drain_touches(2.0)
    assert trace.t_s.tolist() == [1.5, 1.5, 2.0] and trace.finger.tolist() == [0, 1, 0]


def test_switch_to_another_device_is_refused_while_recording():
    """A recording (or a link) was opened for the scene's channels: a scene driving other
    channels (a beam's two transducers) would not fit it. Without one, it ramps in."""
    plate = load_scene(resolve_scene("grating-5mm"))
    beam = load_scene(resolve_scene("two-finger-beam-seed000"))
    thread = HapticThread(plate, recorder=lambda out, commands: None)
    with pytest.raises(ValueError, match=r"two-finger-beam-seed000 drives channels xA, xB .*"
                                         r"opened for ch0 \(plate-seed003\)"):
        thread.switch(beam)
    assert thread.commands.empty()
    free = HapticThread(plate)
    assert free.switch(beam).channels == ("xA", "xB")
    out, commands = free._process(0, None, free._drain_commands())
    assert commands.shape == (50, 2) and free.pipeline.channels == ("xA", "xB")
