"""The live haptic thread keeps a touch continuous across its input batches."""

import time

import numpy as np

from app.haptic_thread import HapticThread
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
