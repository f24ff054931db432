"""The haptic pipeline in a child process: touches in, snapshots out, emergency stop,
scene switches answered by the child, the recording and the link opened there, and a
child that does not outlive the window's process. The tests wait for what the child
reports (snapshots, the output times of stops and switches), never for a set time."""

import os
import queue
import subprocess
import sys
import time

import numpy as np
import pytest

from frictex.app.live.haptic_process import HapticConfig, HapticProcess
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

BLOCK_S = 50 / 10_000.0


WAIT_S = 120.0  # bound of every wait on the child: only a broken child reaches it


def collect_until(haptic, done):
    """The snapshots the child publishes until ``done(snapshots)`` holds."""
    snaps, deadline = [], time.monotonic() + WAIT_S
    while not done(snaps):
        assert time.monotonic() < deadline, "the child stopped publishing what was awaited"
        assert haptic.error is None
        try:
            snaps.append(haptic.snapshots.get(timeout=0.05))
        except queue.Empty:
            pass
    return snaps


def touching(snaps, after_s=-1.0):
    """(t s, mu' target, command um) of finger 0 at its sampled instants in contact,
    from ``after_s`` on."""
    recs = [s.record for s in snaps if s.record.contact.size]
    if not recs:
        return np.zeros(0), np.zeros(0), np.zeros(0)
    keep = [r.contact[0] & (r.t_s >= after_s) for r in recs]
    return tuple(np.concatenate([a[k] for a, k in zip(arrays, keep)]) for arrays in
                 ([r.t_s for r in recs], [r.mu_target[0] for r in recs],
                  [r.commands_um[:, 0] for r in recs]))


def applied_at(snaps, kind):
    """Output time (s) at which the child reports ``kind`` took effect, or None."""
    for snap in reversed(snaps):
        for t, event, _ in snap.status["applied"][1]:
            if event == kind:
                return t
    return None


def until_applied(kind, samples_after=10):
    """A ``done`` for collect_until: ``kind`` took effect and the finger was sampled
    ``samples_after`` times since."""
    def done(snaps):
        t = applied_at(snaps, kind)
        return t is not None and touching(snaps, t)[0].size >= samples_after
    return done


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
        _, mu, cmd = touching(collect_until(haptic, lambda s: touching(s)[0].size >= 20))
        np.testing.assert_allclose(mu, 0.6, atol=1e-12)
        assert cmd[-1] > 0.5
        haptic.estop.set()
        t_set = haptic.now()  # read after the set: this process may be descheduled between
        snaps = collect_until(haptic, until_applied("output-stop"))
        t_on = applied_at(snaps, "output-stop")
        assert t_on < t_set + BLOCK_S  # never ahead of the clock: a block at most
        _, _, cmd = touching(snaps, t_on)
        assert (cmd == 0.0).all()
        haptic.estop.clear()
        t_off = applied_at(collect_until(haptic, until_applied("output-resume")), "output-resume")

        edited = load_scene(scene_file)  # good when the window reads it...
        scene_file.write_text(text.replace("period_mm = 5", "period_mm = -5"))
        with pytest.raises(ValueError, match="period_mm"):
            haptic.switch(edited)  # ...broken when the child does
        t_failed = haptic.now()
        _, mu, cmd = touching(collect_until(haptic, lambda s: touching(s, t_failed)[0].size >= 20),
                              t_failed)
        np.testing.assert_allclose(mu, 0.6, atol=1e-12)  # the old scene stays
        assert cmd[-1] > 0.5  # and output resumed

        beam = load_scene(resolve_scene("two-finger-beam-seed000"))
        with pytest.raises(ValueError, match=r"drives channels xA, xB .*opened for ch0"):
            haptic.switch(beam)  # the recording was opened for one channel

        scene_file.write_text(text.replace("mu_low = 0.6", "mu_low = 0.3"))
        assert haptic.switch(load_scene(scene_file)).channels == ("ch0",)
        snaps = collect_until(haptic, until_applied("output-switch"))
        t_switch = applied_at(snaps, "output-switch")
        np.testing.assert_allclose(touching(snaps, t_switch)[1], 0.3, atol=1e-12)
        assert haptic.error is None
    finally:
        haptic.stop()
    assert [(t, e) for t, e, _ in haptic.stats.applied] == [
        (t_on, "output-stop"), (t_off, "output-resume"), (t_switch, "output-switch")]
    assert haptic.stats.ramps == 2  # resumed, crossfaded
    assert haptic.link == {"state": "none"} and haptic.dropped_records == 0
    commands = np.loadtxt(rec / "commands.csv", delimiter=",", skiprows=1)
    assert commands.shape[0] == haptic.stats.blocks * 50  # written by the child, all of it
    during = (commands[:, 0] >= t_on) & (commands[:, 0] < t_off)
    assert during.sum() >= 100 and (commands[during, 1] == 0.0).all()
    assert commands[commands[:, 0] < t_on, 1].max() > 0.5


def test_link_failure_in_the_child_comes_back_as_oserror(tmp_path):
    path = resolve_scene("grating-5mm")
    missing = tmp_path / "no-such-port"
    with pytest.raises(OSError, match="no-such-port"):
        HapticProcess(load_scene(path), HapticConfig(path, 10_000.0, 50, None, str(missing), None))


PARENT = """
import sys, time
from frictex.app.live.haptic_process import HapticConfig, HapticProcess
from frictex.app.live.haptic_thread import SNAPSHOT_QUEUE
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
path = resolve_scene("grating-5mm")
haptic = HapticProcess(load_scene(path), HapticConfig(path, 10_000.0, 50, None, None, None))
if sys.argv[1] == "full":  # nothing read: the child's snapshots fill their pipe
    while haptic.snapshots.qsize() < SNAPSHOT_QUEUE:
        time.sleep(0.01)
print(haptic._proc.pid, flush=True)
time.sleep(600)
"""


def running(pid):
    """False once ``pid`` has exited (a zombie left to a PID 1 that does not reap counts)."""
    try:
        with open(f"/proc/{pid}/stat") as f:
            return f.read().rsplit(")", 1)[1].split()[0] != "Z"
    except FileNotFoundError:
        return False


@pytest.mark.parametrize("snapshots", ["read", "full"])
def test_child_exits_when_the_window_process_dies(snapshots):
    """SIGKILL to the window's process, at once or once the snapshots it never read
    fill their pipe (the child then blocked at exit flushing them, for good): the child
    is gone within a bound (it is told by a parent-death signal, and watches its
    parent's pipe)."""
    parent = subprocess.Popen([sys.executable, "-c", PARENT, snapshots], stdout=subprocess.PIPE,
                              text=True)
    try:
        child = int(parent.stdout.readline())
        assert running(child)
        parent.kill()  # no clean shutdown: SIGKILL
        parent.wait()
        deadline = time.monotonic() + WAIT_S  # a bound, not a timing
        while time.monotonic() < deadline and running(child):
            time.sleep(0.05)
        if running(child):
            os.kill(child, 9)
            pytest.fail(f"haptic child {child} outlived its parent by {WAIT_S:g} s")
    finally:
        if parent.poll() is None:
            parent.kill()
            parent.wait()


def test_a_signal_raised_while_stopping_still_ends_the_child():
    """A second SIGTERM raised in stop()'s wait for the child's report skipped the
    terminate and kill: the child, blocked writing snapshots nobody read, stayed, and the
    interpreter's exit waited on it for ever (a demo that only SIGKILL ended)."""
    from frictex.app.engine.driver import Terminated
    from frictex.app.live.haptic_thread import SNAPSHOT_QUEUE
    path = resolve_scene("grating-5mm")
    haptic = HapticProcess(load_scene(path), HapticConfig(path, 10_000.0, 50, None, None, None))
    deadline = time.monotonic() + WAIT_S
    while haptic.snapshots.qsize() < SNAPSHOT_QUEUE:  # nothing read: the child blocks
        assert time.monotonic() < deadline, "the child published no snapshots"
        time.sleep(0.01)

    def interrupted(*args, **kwargs):
        raise Terminated(15)

    haptic._wait = interrupted
    with pytest.raises(Terminated):
        haptic.stop()
    assert not haptic._proc.is_alive()
