"""The firmware as ARM code: the QEMU port (device/firmware/sf2/, a Cortex-M3 that
``qemu-system-arm -M emcraft-sf2`` runs) on a pty, driven by frictex's own host link
through the shared link checks, as the Python simulated device and the host build are.
What it plays comes back through semihosting, a record per played sample."""

import io
import os
import select
import shutil
import time
import tty

import numpy as np
import pytest

from frictex.device.firmware import qemuport
from frictex.device.firmware.build import FirmwareBuildError
from frictex.device.link import protocol as p
from frictex.device.link.faults import Faults, Plug
from frictex.device.link.host import CommandSink, LinkError, open_port
from link_checks import (accounted, all_played_unless_tripped, clean_unless_starved, in_order_within,
                         until)

STEP = p.AMPLITUDE_STEP_UM
RATE = qemuport.RATE_HZ
MISSING = [tool for tool in (qemuport.QEMU, "arm-none-eabi-gcc") if shutil.which(tool) is None]
pytestmark = pytest.mark.skipif(bool(MISSING), reason=f"{' and '.join(MISSING)} not installed "
                                "(Debian: qemu-system-arm, gcc-arm-none-eabi; bash .ci/setup-firmware)")


@pytest.fixture(scope="module")
def elf():
    try:
        return qemuport.firmware()
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


def _signal(n, seed=0):
    rng = np.random.default_rng(seed)
    return np.clip(1.5 + np.cumsum(rng.normal(0, 0.02, n)), 0.0, 2.9)[:, None]


def _still(log, seconds):
    """Whether the played log did not grow for ``seconds``."""
    size = log.stat().st_size
    time.sleep(seconds)
    return log.stat().st_size == size


def test_the_host_link_streams_to_the_firmware_in_qemu_and_it_plays_what_it_is_sent(elf, tmp_path):
    log = tmp_path / "played.bin"
    sig = _signal(6000)
    with qemuport.QemuDevice(log, elf=elf) as dev:
        sink = CommandSink(lambda: open_port(dev.path), 1, RATE, paced=True, process=dev.proc)
        assert sink.status()["state"] == "simulated"
        assert sink.info.name == "frictex fw emcraft-sf2" and sink.info.limits_um == (4.0,)
        for b in range(0, 6000, 50):
            sink.send(b, sig[b:b + 50], None)
        sink.close()
        assert dev.wait(30.0) == 0  # it left QEMU once the Stop had played out
    status = sink.status()
    index, amp = qemuport.played_log(log)
    in_order_within(index, np.arange(6000))
    np.testing.assert_allclose(amp[:, 0] * STEP, sig[index, 0], atol=STEP / 2 + 1e-9)
    assert status["protocol_version"] == p.PROTOCOL_VERSION
    all_played_unless_tripped(status, index, 6000)
    # QEMU starved of CPU took no block for half a second in 2 of 3 runs beside four
    # busy processes: a recovery, its drops counted
    clean_unless_starved(status, 120)


def test_the_firmware_in_qemu_clamps_what_the_host_did_not(elf, tmp_path):
    """A host that skips its clamp (raw frames): the device clamps to its 4 um, counts it."""
    log = tmp_path / "played.bin"
    with qemuport.QemuDevice(log, elf=elf) as dev:
        port = open_port(dev.path)
        try:
            frames = [p.Hello(1), p.Block(0, np.array([[8192], [16384], [65535]], np.uint16)),
                      p.Heartbeat(7)]
            port.write(b"\x00" + b"".join(p.encode(m, k, 1) for k, m in enumerate(frames)))
            replies, decoder = [], p.Decoder()
            deadline = time.monotonic() + 20.0
            while len(replies) < 2 and time.monotonic() < deadline:
                replies += [f.message for f in decoder.feed(port.read(4096))]
            info, status = replies
            assert isinstance(info, p.Info) and info.limits_um == (4.0,)
            assert status.echo == 7 and status.clamped == 1
            port.write(p.encode(p.Stop(True), 3, 1))
            assert dev.wait(30.0) == 0
        finally:
            port.close()
    index, amp = qemuport.played_log(log)
    np.testing.assert_array_equal(index, [0, 1, 2])
    np.testing.assert_array_equal(amp[:, 0], [8192, 16384, 16384])


def test_a_firmware_in_qemu_of_the_wrong_kind_is_refused(elf):
    with qemuport.QemuDevice(elf=elf) as dev:
        with pytest.raises(LinkError, match=r"has 1 channel\(s\), the pipeline sends 2"):
            CommandSink(lambda: open_port(dev.path), 2, RATE)
        with pytest.raises(LinkError, match="sample rate 10000 Hz, the pipeline runs at 8000"):
            CommandSink(lambda: open_port(dev.path), 1, 8000.0)


def test_faults_on_the_wire_to_qemu_are_counted_and_never_played(elf, tmp_path):
    log = tmp_path / "played.bin"
    sig = _signal(8000, seed=4)
    with qemuport.QemuDevice(log, elf=elf) as dev:
        plug = Plug(lambda: open_port(dev.path), Faults(flip=4e-4, drop=2e-4, garbage=2e-4),
                    seed=11)
        sink = CommandSink(plug, 1, RATE, paced=False, stderr=io.StringIO(), process=dev.proc)
        t0 = time.perf_counter()
        for b in range(0, 8000, 50):
            while time.perf_counter() - t0 < b / RATE - 0.01:
                time.sleep(0.001)
            sink.send(b, sig[b:b + 50], None)
        sink.close()
        dev.wait(30.0)
    status = sink.status()
    index, amp = qemuport.played_log(log)
    # damage loses samples, never changes one; every loss is counted
    in_order_within(index, np.arange(8000))
    np.testing.assert_allclose(amp[:, 0] * STEP, sig[index, 0], atol=STEP / 2 + 1e-9)
    accounted(status, index, 8000)
    assert len(index) > (4000 if status["watchdog_trips"] == 0 else 0)
    assert status["device_crc_errors"] > 0 and status["resyncs"] > 0


def test_the_firmware_in_qemu_trips_its_watchdog_when_the_host_goes_quiet(elf, tmp_path):
    """Unplug the host while the device plays: the watchdog trips (counted), the output
    ramps to zero, nothing more plays until the host is back; its new stream then plays
    and every sample is accounted for."""
    log = tmp_path / "played.bin"
    with qemuport.QemuDevice(log, elf=elf) as dev:
        plug = Plug(lambda: open_port(dev.path))
        sink = CommandSink(plug, 1, RATE, paced=True, stderr=io.StringIO(), process=dev.proc)
        for b in range(0, 4000, 50):
            sink.send(b, np.full((50, 1), 2.0), None)
        until(lambda: sink.status().get("device_state") == "playing", "the device playing")
        plug.unplug()
        time.sleep(0.3)
        # QEMU's clock runs while QEMU runs: wait until the device stopped playing
        until(lambda: _still(log, 0.2), "the device's output stopping unplugged")
        plug.plug()
        until(lambda: sink.status()["state"] == "simulated", "the link coming back")
        for b in range(5000, 6000, 50):
            sink.send(b, np.full((50, 1), 1.0), None)
        sink.close()
        dev.wait(30.0)
    status = sink.status()
    index, amp = qemuport.played_log(log)
    assert status["watchdog_trips"] >= 1
    in_order_within(index, np.concatenate([np.arange(4000), np.arange(5000, 6000)]))
    second = index >= 5000
    assert np.all(amp[second, 0] * STEP == 1.0)  # what of the new stream played is exact
    # The new stream plays; on a busy machine QEMU's emulated device may fall so far behind
    # after the reconnect that the host's stall rule gives the stream up (seen in 2 of 5
    # runs beside two busy processes: 950 of its 1000 samples): then what did not play is
    # counted as stalled or lost, never silently missing (and accounted() below holds).
    if np.count_nonzero(second) < 1000:
        causes = status["unplayed_by_cause"]
        assert causes["stalled"] + causes["lost"] + causes["flushed"] >= 1000 - np.count_nonzero(second)
    assert np.all(amp[index < 4000, 0] * STEP == 2.0)
    accounted(status, index, 5000)


def _answer_after(path, burst, first, timeout_s=30.0):
    """Write ``burst`` to the pty ``path`` as fast as it takes it, reading what comes back
    meanwhile; then a Heartbeat (tokens and sequence numbers from ``first`` on) every
    0.5 s until one is answered. Returns that Status; fails naming how far it got if the
    burst was not taken, or nothing answered, within ``timeout_s``."""
    fd = os.open(path, os.O_RDWR | os.O_NOCTTY | os.O_NONBLOCK)
    try:
        tty.setraw(fd)
        decoder, pending, written, token, beat_at = p.Decoder(), burst, 0, first, 0.0
        deadline = time.monotonic() + timeout_s
        while time.monotonic() < deadline:
            if not pending and time.monotonic() >= beat_at:
                pending, beat_at = p.encode(p.Heartbeat(token), token, 1), time.monotonic() + 0.5
                token += 1
            readable, writable, _ = select.select([fd], [fd] if pending else [], [], 0.1)
            if writable:
                n = os.write(fd, pending)
                pending, written = pending[n:], written + n
            for frame in decoder.feed(os.read(fd, 1 << 16)) if readable else ():
                if isinstance(frame.message, p.Status) and frame.message.echo >= first:
                    return frame.message
        pytest.fail(f"the device took {min(written, len(burst))} of the burst's {len(burst)} "
                    f"bytes and answered no Heartbeat after it within {timeout_s:g} s")
    finally:
        os.close(fd)


def test_the_firmware_in_qemu_keeps_answering_through_a_burst_far_larger_than_its_ring(elf):
    """64 KiB of Heartbeats in one go, far more than the 1 KiB receive ring, arriving
    faster than the main loop answers them: the ring fills and the bytes wait in the UART,
    none lost. (The receive interrupt, asserted while the full FIFO waited, was entered
    over and over and the main loop never ran again: the device took 17 KiB of the burst
    and answered nothing more.)"""
    n = 4800
    frames = [p.Hello(1)] + [p.Heartbeat(k) for k in range(1, n)]
    burst = b"\x00" + b"".join(p.encode(m, k, 1) for k, m in enumerate(frames))
    assert len(burst) > 64 * 1024
    with qemuport.QemuDevice(elf=elf) as dev:
        status = _answer_after(dev.path, burst, n)
    assert status.echo >= n  # after every frame of the burst, in order
    assert status.crc_errors == 0 and status.lost_frames == 0
    assert status.frames_ok == status.echo + 1  # every frame, the Hello too: none lost
