"""The haptic pipeline in a child process: touches in, snapshots out, emergency stop,
scene switches answered by the child, the recording and the link opened there, and a
child that does not outlive the window's process."""

import os
import queue
import subprocess
import sys
import time

import numpy as np
import pytest

from app.live.haptic_process import HapticConfig, HapticProcess
from textures.library import resolve_scene
from textures.loader import load_scene

BLOCK_S = 50 / 10_000.0


def collect(haptic, seconds):
    """The snapshots the child publishes during ``seconds``."""
    snaps, end = [], time.monotonic() + seconds
    while time.monotonic() < end:
        try:
            snaps.append(haptic.snapshots.get(timeout=0.05))
        except queue.Empty:
            pass
    return snaps


def touching(snaps):
    """(t s, mu' target, command um) of finger 0 at its sampled instants in contact."""
    recs = [s.record for s in snaps if s.record.contact.size and s.record.contact[0].any()]
    t = np.concatenate([r.t_s[r.contact[0]] for r in recs])
    mu = np.concatenate([r.mu_target[0][r.contact[0]] for r in recs])
    cmd = np.concatenate([r.commands_um[r.contact[0], 0] for r in recs])
    return t, mu, cmd


def test_child_renders_stops_switches_and_records(tmp_path):
    text = resolve_scene("grating-5mm").read_text()
    assert "mu_low = 0.6" in text and "period_mm = 5" in text
    scene_file = tmp_path / "lines.toml"
    scene_file.write_text(text)
    rec = tmp_path / "rec"
    haptic = HapticProcess(load_scene(scene_file),
                           HapticConfig(scene_file, 10_000.0, 50, "sho", None, rec))
    try:
        assert haptic.pipeline.channels == ("ch0",) and haptic.render_override == "sho"
        assert 0.0 < haptic.now() < 60.0  # the child's output clock, read in this process
        haptic.touch(0, 1.0, 30.0, 0.5, "down")  # x = 1 mm: the first low line
        _, mu, cmd = touching(collect(haptic, 0.3))
        np.testing.assert_allclose(mu, 0.6, atol=1e-12)
        assert cmd[-1] > 0.5
        t_stop = haptic.now()
        haptic.estop.set()
        t, _, cmd = touching(collect(haptic, 0.2))
        t_release = haptic.now()
        haptic.estop.clear()
        stopped = t > t_stop + BLOCK_S  # zero from the next block on
        assert stopped.sum() > 10 and (cmd[stopped] == 0.0).all()

        edited = load_scene(scene_file)  # good when the window reads it...
        scene_file.write_text(text.replace("period_mm = 5", "period_mm = -5"))
        with pytest.raises(ValueError, match="period_mm"):
            haptic.switch(edited)  # ...broken when the child does
        _, mu, cmd = touching(collect(haptic, 0.2))
        np.testing.assert_allclose(mu, 0.6, atol=1e-12)  # the old scene stays
        assert cmd[-1] > 0.5  # and output resumed

        beam = load_scene(resolve_scene("two-finger-beam-seed000"))
        with pytest.raises(ValueError, match=r"drives channels xA, xB .*opened for ch0"):
            haptic.switch(beam)  # the recording was opened for one channel

        scene_file.write_text(text.replace("mu_low = 0.6", "mu_low = 0.3"))
        assert haptic.switch(load_scene(scene_file)).channels == ("ch0",)
        _, mu, _ = touching(collect(haptic, 0.3))
        np.testing.assert_allclose(mu[-10:], 0.3, atol=1e-12)
        assert haptic.error is None
    finally:
        haptic.stop()
    assert haptic.stats.blocks > 150 and haptic.stats.ramps >= 2  # resumed, crossfaded
    assert haptic.link == {"state": "none"} and haptic.dropped_records == 0
    commands = np.loadtxt(rec / "commands.csv", delimiter=",", skiprows=1)
    assert commands.shape[0] == haptic.stats.blocks * 50  # written by the child, all of it
    during = (commands[:, 0] > t_stop + BLOCK_S) & (commands[:, 0] < t_release)
    assert during.sum() > 1000 and (commands[during, 1] == 0.0).all()


def test_link_failure_in_the_child_comes_back_as_oserror(tmp_path):
    path = resolve_scene("grating-5mm")
    missing = tmp_path / "no-such-port"
    with pytest.raises(OSError, match="no-such-port"):
        HapticProcess(load_scene(path), HapticConfig(path, 10_000.0, 50, None, str(missing), None))


PARENT = """
import sys, time
from app.live.haptic_process import HapticConfig, HapticProcess
from textures.library import resolve_scene
from textures.loader import load_scene
path = resolve_scene("grating-5mm")
haptic = HapticProcess(load_scene(path), HapticConfig(path, 10_000.0, 50, None, None, None))
print(haptic._proc.pid, flush=True)
time.sleep(60)
"""


def running(pid):
    """False once ``pid`` has exited (a zombie left to a PID 1 that does not reap counts)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


def test_child_exits_when_the_window_process_dies():
    parent = subprocess.Popen([sys.executable, "-c", PARENT], stdout=subprocess.PIPE, text=True)
    try:
        child = int(parent.stdout.readline())
        assert running(child)
        parent.kill()  # no clean shutdown: SIGKILL
        parent.wait()
        deadline = time.monotonic() + 5.0
        while time.monotonic() < deadline and running(child):
            time.sleep(0.05)
        if running(child):
            os.kill(child, 9)
            pytest.fail(f"haptic child {child} outlived its parent by 5 s")
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()
