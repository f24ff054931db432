"""Stopping the plate: a signal or a failed run stops it at once, every wait on the link
ends on an interrupt, and a link that gives up says where each sample went.

Durations are read on the device's own sample clock (its plate log, one row per tick),
never against the host's wall clock: what the host may still have committed when it is
told to stop is bounded by the protocol (its queue and the device's window), whatever
the scheduler does meanwhile.
"""

from __future__ import annotations

import io
import os
import signal
import subprocess
import sys
import threading
import time

import numpy as np
import pytest
from hypothesis import given
from hypothesis import strategies as st

from frictex.device.link.host import CommandSink, LinkStalled, open_port
from frictex.device.link.protocol import DeviceState
from frictex.device.link.simdevice import DeviceConfig, DeviceCore
from frictex.device.link.waits import interruptible
from link_checks import serve_on_pty, until

RATE = 10_000.0


class PlateLog:
    """A device core's per-tick output (``plate_log``): time on its clock (s), state and
    channel 0's setpoint (um)."""

    def __init__(self):
        self.chunks: list[tuple[np.ndarray, np.ndarray, np.ndarray]] = []

    def __call__(self, t, state, setpoint, plate):
        t = np.array(t, dtype=np.float64)
        self.chunks.append((t, np.broadcast_to(np.array(state), t.shape).copy(),
                            np.array(setpoint)[:, 0]))

    def arrays(self):
        chunks = list(self.chunks)
        return tuple(np.concatenate([c[k] for c in chunks]) for k in range(3))

    def vibrating(self) -> bool:
        return any(np.any(c[2] != 0.0) for c in list(self.chunks)[-20:])


@pytest.fixture
def device():
    """A simulated device (the Python reference core) served on a pty by a thread of
    this process: (core, plate log, pty path, stop(keep_pty))."""
    log = PlateLog()
    core = DeviceCore(DeviceConfig(limits_um=(4.0,)), plate_log=log)
    path, stop = serve_on_pty(core)
    yield core, log, path, stop
    stop()


def _vibrating_after(log: PlateLog, t_s: float) -> float:
    """Device time (s) from ``t_s`` to the last tick with a non-zero setpoint (0 if none)."""
    t, _, setpoint = log.arrays()
    on = np.flatnonzero((t >= t_s) & (setpoint != 0.0))
    return float(t[on[-1]] - t_s) if on.size else 0.0


def _flat_scene(tmp_path):
    """grating-15mm with both bands at mu' 0.6: the plate vibrates wherever the finger is."""
    from frictex.textures.library import resolve_scene
    text = open(resolve_scene("grating-15mm"), encoding="utf-8").read()
    assert "mu_high = 1.0" in text
    path = tmp_path / "flat.toml"
    path.write_text(text.replace("mu_high = 1.0", "mu_high = 0.6", 1), encoding="utf-8")
    return path


def _slide(duration_s: float):
    """A finger sliding back and forth over the plate for ``duration_s``, at 50 Hz."""
    from frictex.rendering.input.trace_file import DOWN, MOVE, UP, make_trace
    t = np.arange(0.0, duration_s, 0.02)
    x = 50.0 + 30.0 * np.sin(t)
    return make_trace(t, np.zeros(t.size, dtype=int), x, np.full(t.size, 32.0),
                      event=[DOWN] + [MOVE] * (t.size - 2) + [UP])


#: the longest the plate may vibrate on its own clock after the signal: what the host had
#: already committed (its queue, 64 blocks of 50 samples: 0.32 s; the device's window,
#: half its 4096-sample buffer: 0.2 s; the hold and the ramp, 45 ms) and a margin for
#: the device's thread running late behind the clock read at the signal. A run that
#: drained its chunk went on for 5 s.
AFTER_SIGNAL_S = 1.0


@pytest.mark.parametrize("sig, raised", [(signal.SIGINT, KeyboardInterrupt),
                                         (signal.SIGTERM, SystemExit),
                                         (signal.SIGHUP, SystemExit)])
def test_a_signal_during_a_replay_stops_the_plate_at_once(device, tmp_path, sig, raised):
    """Ctrl-C, SIGTERM or SIGHUP while a paced replay streams to a device: the run ends
    within tens of ms of device time, with a Stop without drain (the device flushed what
    it held, counted), and the plate ramps to zero; no output folder is left."""
    from frictex.app.engine.replay import ReplayOptions, replay_with
    core, log, path, _ = device
    at = {}

    def signal_once_vibrating():
        until(log.vibrating, "the plate vibrating", timeout_s=120.0)
        time.sleep(0.3)
        at["t"] = core.tick / RATE
        os.kill(os.getpid(), sig)
    # under nohup (or a shell's background job) the signal is ignored, and a run keeps it
    # so by design (test_engine): here it must be delivered
    before = signal.getsignal(sig)
    if before is signal.SIG_IGN:
        signal.signal(sig, signal.SIG_DFL)
    killer = threading.Thread(target=signal_once_vibrating, daemon=True)
    killer.start()
    try:
        with pytest.raises(raised) as caught:
            replay_with(_flat_scene(tmp_path), _slide(15.0), tmp_path / "out",
                        ReplayOptions(device=path, progress=False))
    finally:
        signal.signal(sig, before)
    killer.join(timeout=5.0)
    if raised is SystemExit:
        assert caught.value.code == 128 + sig
        assert caught.value.reason == f"terminated by {signal.Signals(sig).name}"
    assert not (tmp_path / "out").exists()
    until(lambda: core.stopped and np.all(core.setpoint == 0.0), "the plate at rest")
    after = _vibrating_after(log, at["t"])
    assert after <= AFTER_SIGNAL_S, f"the plate vibrated {after:.3f} s after the signal"
    # from the Stop on (the device's last entry into SILENT) the ramp took ramp_ms
    t, state, setpoint = log.arrays()
    moving = np.flatnonzero(state != DeviceState.SILENT)
    stop = moving[-1] + 1 if moving.size else 0
    on = np.flatnonzero(setpoint[stop:] != 0.0)
    ramp_s = float(t[stop + on[-1]] - t[stop]) if on.size else 0.0
    assert ramp_s <= core.config.ramp_ms * 1e-3 + 1.0 / RATE


def _rows(path) -> np.ndarray:
    """The complete rows of a plate log being written: (t_s, state, setpoint, plate)."""
    lines = path.read_text(encoding="utf-8").split("\n")[1:-1] if path.exists() else []
    return np.array([[float(v) for v in line.split(",")] for line in lines]).reshape(-1, 4)


def _last_logged_s(path) -> float:
    """The device clock (s) of the last complete row of a plate log being written."""
    with open(path, "rb") as fh:
        fh.seek(0, os.SEEK_END)
        fh.seek(max(0, fh.tell() - 4096))
        rows = fh.read().split(b"\n")
    return float(rows[-2].split(b",")[0])


def test_the_command_says_sigterm_and_stops_the_plate(tmp_path):
    """The command line as the engineer ran it: ``frictex sim-device --plate-log`` in
    its own process, ``frictex replay --device PTY`` in another, SIGTERM 0.3 s into the
    vibration: one line, exit 143, the plate log at rest soon after on its own clock."""
    from frictex.app.commands.sim_device import spawn
    plate = tmp_path / "plate.csv"
    sim, pty_path = spawn(1, RATE, extra=("--plate-log", str(plate)))
    trace = tmp_path / "slide.csv"
    from frictex.rendering.input.trace_file import write_trace
    write_trace(trace, _slide(15.0))
    replay = subprocess.Popen([sys.executable, "-m", "frictex", "replay",
                               str(_flat_scene(tmp_path)), str(trace), "--out",
                               str(tmp_path / "out"), "--device", pty_path, "--quiet"],
                              stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)
    try:
        until(lambda: replay.poll() is not None or np.any(_rows(plate)[:, 2] != 0.0),
              "the plate vibrating", timeout_s=120.0)
        time.sleep(0.3)
        # the device's clock at the signal: its log's last row just after a flush (it
        # flushes every 0.25 s, a starved device later: a fresh row, not a stale one)
        flushed = _last_logged_s(plate)
        until(lambda: _last_logged_s(plate) > flushed, "a fresh flush of the plate log",
              timeout_s=60.0)
        t_signal = _last_logged_s(plate)
        replay.send_signal(signal.SIGTERM)
        _, err = replay.communicate(timeout=60.0)
    finally:
        if replay.poll() is None:
            replay.kill()
        sim.wait(timeout=30.0)
    assert replay.returncode == 128 + signal.SIGTERM, err
    # a loaded machine may add the link's recoveries ('frictex: warning: ...') before it
    said = [line for line in err.strip().splitlines() if not line.startswith("frictex: warning:")]
    assert said == ["frictex: terminated by SIGTERM"], err
    data = _rows(plate)
    on = data[(data[:, 0] >= t_signal) & (data[:, 2] != 0.0)]
    after = float(on[-1, 0] - t_signal) if len(on) else 0.0
    # the log may have flushed more rows just before the signal: the clock read at it may
    # be a poll and a flush late
    assert after <= AFTER_SIGNAL_S + 0.25, f"the plate vibrated {after:.3f} s after SIGTERM"


def test_abort_flushes_what_the_device_holds_and_drops_the_queue(device):
    """``abort`` sends no more blocks and a Stop without drain: of a queue of 200
    blocks (1 s) at the host, none plays; the device plays at most its window after
    the abort (on its own clock), and every commanded sample is accounted for."""
    core, log, path, _ = device
    err = io.StringIO()
    sink = CommandSink(lambda: open_port(path), 1, RATE, paced=True, queue_blocks=200,
                       stderr=err)
    for b in range(0, 30_000, 50):
        sink.send(b, np.full((50, 1), 2.0), None)
        if sink.status()["queued_blocks"] >= 150 and log.vibrating():
            break
    t_abort = core.tick / RATE
    sink.abort()
    status = sink.status()
    assert status["state"] == "closed"
    assert status["unplayed_by_cause"]["stalled"] >= 100 * 50  # the queue, dropped
    assert status["played_samples"] + status["unplayed_samples"] == status["commanded_samples"]
    assert core.stopped
    until(lambda: np.all(core.setpoint == 0.0), "the plate at rest")
    window_s = core.config.buffer_samples / 2 / RATE
    hold_ramp_s = (core.config.watchdog_ms + core.config.ramp_ms) * 1e-3
    assert _vibrating_after(log, t_abort) <= window_s + hold_ramp_s + 0.05
    sink.abort()  # again: nothing
    sink.close()  # and a close after it: nothing
    assert sink.status()["state"] == "closed"


def _interrupt_at(n: int):
    """A wait's interrupt check that raises KeyboardInterrupt at its ``n``-th call, and
    the list of its calls."""
    calls = []

    def check():
        calls.append(1)
        if len(calls) >= n:
            raise KeyboardInterrupt
    return check, calls


def test_an_interrupt_cuts_a_draining_close_short(device):
    """A close drains what is queued; an interrupt in its wait raises there, and
    ``abort`` after it turns the drained Stop into a flush."""
    core, log, path, _ = device
    sink = CommandSink(lambda: open_port(path), 1, RATE, paced=True, queue_blocks=200)
    for b in range(0, 10_000, 50):
        sink.send(b, np.full((50, 1), 2.0), None)
    check, _ = _interrupt_at(3)
    with pytest.raises(KeyboardInterrupt), interruptible(check):
        sink.close()
    sink.abort()
    status = sink.status()
    assert status["state"] == "closed" and core.stopped
    assert status["unplayed_by_cause"]["stalled"] > 0  # the queue was not played out
    assert status["played_samples"] + status["unplayed_samples"] == status["commanded_samples"]


def test_the_handshake_wait_ends_on_an_interrupt(tmp_path):
    """A port where nothing answers: the handshake would retry for 10 s; an interrupt
    ends it at the next turn of the wait, and the link's thread and port go with it."""
    master, slave = os.openpty()
    try:
        check, calls = _interrupt_at(5)
        with pytest.raises(KeyboardInterrupt), interruptible(check):
            CommandSink(lambda: open_port(os.ttyname(slave)), 1, RATE, paced=True)
        assert len(calls) == 5
        assert not [t for t in threading.enumerate() if t.name.startswith("frictex-link-")]
    finally:
        os.close(master)
        os.close(slave)


def test_a_link_that_gives_up_says_what_it_sent_played_and_never_sent(device):
    """The device dies mid-stream (its pty stays, nothing answers): the LinkStalled's
    figures add up to what was commanded, and its message says each of them."""
    core, log, path, stop = device
    err = io.StringIO()
    sink = CommandSink(lambda: open_port(path), 1, RATE, paced=True, stderr=err,
                       stall_s=0.2, max_stalls=3)
    with pytest.raises(LinkStalled) as caught:
        for b in range(0, 10**7, 50):
            if b == 2000:
                stop(keep_pty=True)
            sink.send(b, np.ones((50, 1)), None)
    done = caught.value.progress
    assert done.commanded == b + 50
    assert done.played is not None and done.played <= done.sent <= done.commanded
    assert done.queued > 0  # blocks that waited at the host were never sent
    never = done.commanded - done.sent
    assert never >= done.dropped + done.queued
    said = str(caught.value)
    assert (f"of {done.commanded} samples commanded, {done.sent} were sent ({done.played} "
            f"played, {done.sent - done.played - (done.refused or 0)} not reported played"
            in said)
    assert f"{never} never sent ({done.dropped} dropped, {done.queued} queued" in said
    sink.abort()


def test_stalls_in_a_row_are_said_once_then_summed_up(device):
    """A device gone for several stalls: the first is said when it happens, the rest
    once they end, with how long the device was away in all (at least the waits)."""
    core, log, path, stop = device
    err = io.StringIO()
    sink = CommandSink(lambda: open_port(path), 1, RATE, paced=True, queue_blocks=2,
                       stderr=err, stall_s=0.1, max_stalls=1000)
    sink.send(0, np.ones((50, 1)), None)
    stop(keep_pty=True)
    until(lambda: sink.status()["state"] == "disconnected", "the link seeing the device gone")
    for b in range(50, 50 + 6 * 50, 50):
        sink.send(b, np.ones((50, 1)), None)
    said = [line for line in err.getvalue().splitlines() if "stream goes on" in line]
    assert len(said) == 1 and "for 0.1 s; dropped a block of 50 samples" in said[0]
    stalls = sink.status()["stalls"]
    assert stalls == 6
    sink.abort()
    summary = [line for line in err.getvalue().splitlines() if " in all, until " in line]
    assert len(summary) == 1
    assert summary[0].endswith(f"until the run ended: {stalls} stalls, {stalls * 50} samples "
                               "dropped")
    away_s = float(summary[0].split(" for ")[1].split(" s in all")[0])
    assert away_s >= stalls * 0.1 - 0.05  # printed to 0.1 s


def test_a_replay_that_gives_up_says_how_much_of_the_trace_never_went(device, tmp_path):
    """The device dies 0.3 s into a 6 s replay: the give-up names the output handed
    over and the rest of the trace, which was never commanded, and keeps the figures."""
    from frictex.app.engine.replay import ReplayOptions, replay_with
    core, log, path, stop = device

    def kill_once_vibrating():
        until(log.vibrating, "the plate vibrating", timeout_s=120.0)
        time.sleep(0.3)
        stop(keep_pty=True)
    killer = threading.Thread(target=kill_once_vibrating, daemon=True)
    killer.start()
    with pytest.raises(LinkStalled) as caught:
        replay_with(_flat_scene(tmp_path), _slide(6.0), tmp_path / "out",
                    ReplayOptions(device=path, progress=False))
    killer.join(timeout=30.0)
    said = str(caught.value)
    done = caught.value.progress
    assert done is not None and done.commanded > 0
    handed_s = float(said.split("the replay stopped after ")[1].split(" s of output")[0])
    # handed over: every block commanded but the one the link refused (printed to 10 ms)
    assert handed_s == pytest.approx((done.commanded - 50) / RATE, abs=0.0051)
    last_s = float(said.split("of the 5.98 s trace (the last ")[1].split(" s never")[0])
    # each figure printed to 10 ms from the exact ones: their difference within two roundings
    assert last_s == pytest.approx(5.98 - handed_s, abs=0.0101)
    assert not (tmp_path / "out").exists()


@given(st.data())
def test_a_give_up_message_adds_up_to_what_was_commanded(data):
    """Whatever the figures, the message's parts add up: sent = played + not reported
    played + refused, commanded = sent + never sent, never sent = dropped + queued +
    being queued."""
    import re

    from frictex.device.link.session import LinkProgress
    commanded = data.draw(st.integers(0, 10**9))
    sent = data.draw(st.integers(0, commanded))
    played = data.draw(st.integers(0, sent))
    refused = data.draw(st.integers(0, sent - played))
    dropped = data.draw(st.integers(0, commanded - sent))
    queued = data.draw(st.integers(0, commanded - sent - dropped))
    said = LinkProgress(commanded, sent, played, refused, dropped, queued).describe()
    n = {k: int(v) for v, k in re.findall(r"(\d+) (samples commanded|were sent|played|not "
                                          r"reported played|flushed|never sent|dropped|"
                                          r"queued|being queued)", said)}
    assert n["samples commanded"] == commanded and n["were sent"] == sent
    assert n["played"] + n["not reported played"] + n.get("flushed", 0) == sent
    assert n["were sent"] + n["never sent"] == commanded
    assert n["dropped"] + n["queued"] + n.get("being queued", 0) == n["never sent"]
