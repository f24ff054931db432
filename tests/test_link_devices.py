"""Output devices by name (device/link/devices.py), the in-process ``sim`` device
(device/link/simport.py), the first handshake's back-off and the stall policy's bound
(device/link/stall.py)."""

import io
import os
import time

import numpy as np
import pytest

from frictex.device.errors import DeviceError, InputError
from frictex.device.link import protocol as p
from frictex.device.link.devices import DEVICES, DeviceRequest, OutputDevice, resolve, sim_pairs
from frictex.device.link.faults import parse_faults
from frictex.device.link.host import CommandSink, LinkError, open_sink
from frictex.device.link.simdevice import DeviceConfig, DeviceCore
from frictex.device.link.simport import SimDevice, sim_config
from frictex.device.link.stall import StallPolicy
from frictex.device.registry import UnknownName

RATE = 10_000.0


def _children() -> list[int]:
    """Processes whose parent is this one (Linux /proc)."""
    kids = []
    for pid in filter(str.isdigit, os.listdir("/proc")):
        try:
            with open(f"/proc/{pid}/stat") as fh:
                stat = fh.read()
        except OSError:
            continue
        if int(stat.rsplit(")", 1)[1].split()[1]) == os.getpid():
            kids.append(int(pid))
    return kids


def test_sim_is_in_process_and_plays_every_sample(tmp_path):
    before = _children()
    log = tmp_path / "played.csv"
    with open_sink("sim", 1, RATE, paced=True, log_path=log) as sink:
        assert set(_children()) <= set(before)  # no process started
        assert sink.status()["state"] == "simulated"
        assert isinstance(sink, OutputDevice)
        for b in range(0, 3000, 50):
            sink.send(b, np.full((50, 1), 1.25))
    st = sink.status()
    played = np.loadtxt(log, delimiter=",", skiprows=1, ndmin=2)
    assert st["commanded_samples"] == 3000
    assert st["played_samples"] + st["unplayed_samples"] == 3000
    assert len(played) >= st["played_samples"]
    np.testing.assert_allclose(played[:, 1], 1.25)


def test_sim_options_reach_the_device():
    with open_sink("sim:limit=2.5,finger=3", 1, RATE, paced=False) as sink:
        assert sink.info.limits_um[0] == pytest.approx(2.5, abs=p.AMPLITUDE_STEP_UM)
        assert sink.info.has_force_reports
    with open_sink("sim://?buffer=2048", 1, RATE, paced=False) as sink:
        assert sink.info.buffer_samples == 2048
    with open_sink("sim", 1, RATE, paced=False, sim_args=("--lateral", "0.2")) as sink:
        assert sink.info.has_force_reports


@pytest.mark.parametrize("spec, message", [
    ("sim:tcp", "sim device option 'tcp': expected one of limit, "),
    ("sim:buffer=lots", "sim device option buffer='lots': expected an integer"),
    ("sim:finger=-1", "finger = -1: expected a seed >= 0"),
    ("nosuchdevice", "unknown output device 'nosuchdevice'; expected one of port, sim"),
    ("", "expected NAME\\[:ARG\\], a URL or a port path"),
])
def test_bad_device_specs_are_input_errors(spec, message):
    with pytest.raises(InputError, match=message):
        open_sink(spec, 1, RATE)


def test_specs_resolve_to_devices():
    assert resolve("sim") == (DEVICES.get("sim"), "")
    assert resolve("sim:finger=3") == (DEVICES.get("sim"), "finger=3")
    assert resolve("sim://?finger=3") == (DEVICES.get("sim"), "?finger=3")
    for port in ("/dev/pts/7", "socket://127.0.0.1:9", "loop://", "COM3", "./ttyX"):
        assert resolve(port) == (DEVICES.get("port"), port)
    with pytest.raises(UnknownName):
        resolve("rfc9999:x")
    assert sim_pairs("a=1,b=2", ("--c", "3", "--sensor")) == [("a", "1"), ("b", "2"),
                                                               ("c", "3"), ("sensor", "1")]


def test_an_output_device_registered_by_name_is_opened_with_its_arg():
    got = {}

    class Null:
        """A device with every member a sink has; each does nothing."""
        label, channels, rate_hz, paced, info = "null", 1, RATE, True, None
        send = wait_for_room = status = unplayed_share = lambda *a, **k: None
        device_force_n = force_report = forces_covered = lambda *a, **k: None

        def close(self):
            got["closed"] = True

    def open_null(arg, request):
        got["arg"], got["request"] = arg, request
        return Null()
    DEVICES.register("test-null", open_null)
    sink = open_sink("test-null:/some/where", 2, RATE, paced=True, stall_s=0.5)
    assert isinstance(sink.inner, Null) and got["arg"] == "/some/where"
    assert got["request"] == DeviceRequest(channels=2, rate_hz=RATE, paced=True,
                                           stderr=got["request"].stderr, stall_s=0.5)


def test_faults_are_injected_over_sim():
    """Trips every 0.5 s after the link opens are heard by the device as silence (its
    watchdog, armed once it plays, trips). The stream goes on until a trip shows, at
    most 5 s: on a loaded machine the link may open and play late, or its thread sleep
    through one trip's window."""
    err = io.StringIO()
    sent = 0
    trips = ",".join(f"trip@{0.5 * k:g}" for k in range(1, 10))
    with open_sink("sim", 1, RATE, paced=True, faults=parse_faults(trips),
                   stderr=err) as sink:
        while sent < 5 * RATE and not sink.status().get("watchdog_trips"):
            sink.send(sent, np.ones((50, 1)))
            sent += 50
    st = sink.status()
    assert st["watchdog_trips"] >= 1  # the trip was injected: the device heard nothing
    assert st["played_samples"] + st["unplayed_samples"] == sent


class _LateDevice:
    """A port onto a device core that ignores its first ``deaf`` writes (a device still
    booting on a busy machine)."""

    def __init__(self, deaf: int):
        self.device = SimDevice(DeviceConfig())
        self.port = self.device.open()
        self.deaf = deaf
        self.timeout = self.port.timeout
        self.in_waiting = 0

    def read(self, size=1):
        return self.port.read(size)

    def write(self, data):
        if self.deaf:
            self.deaf -= 1
            return len(data)
        return self.port.write(data)

    def close(self):
        self.port.close()


def test_the_first_handshake_retries_with_back_off_until_the_device_answers():
    late = _LateDevice(deaf=4)  # Hellos at 0, 0.1, 0.3, 0.7 s unanswered; 1.5 s answered
    sink = CommandSink(lambda: late, 1, RATE, paced=False)
    try:
        st = sink.status()
        assert st["state"] == "connected" and st["retries"] == 4
    finally:
        sink.close()


def test_a_device_that_never_answers_is_a_device_error_after_the_stated_total():
    late = _LateDevice(deaf=10**6)
    t0 = time.monotonic()
    with pytest.raises(LinkError, match=r"no answer to the handshake within [0-9.]+ s "
                                        r"\([34] Hellos\); is it a frictex device\?") as info:
        CommandSink(lambda: late, 1, RATE, paced=False, handshake_s=1.0)
    assert time.monotonic() - t0 >= 1.0
    assert isinstance(info.value, DeviceError) and info.value.exit_code == 1


def test_a_wrong_device_is_refused_at_once():
    device = SimDevice(sim_config([], 2, RATE, False))
    with pytest.raises(LinkError, match="has 2 channel|sample rate 10000 Hz, the pipeline"):
        CommandSink(device.open, 1, 8000.0, handshake_s=60.0)


def test_the_stall_policy_bounds_waiting_without_progress():
    policy = StallPolicy(RATE, give_up_s=5.0)
    t = 0.0
    for _ in range(100):  # a clean link: every second waited plays a second
        t += 0.01
        policy.account(t, 100, waiting=True)
    assert policy.lag_s == pytest.approx(0.0, abs=1e-9) and not policy.failed
    for _ in range(1000):  # computing, no block waiting: nothing counts
        t += 0.01
        policy.account(t, 0, waiting=False)
    assert policy.lag_s == pytest.approx(0.0, abs=1e-9)
    # a link that comes back and loses again: half of each second waited plays
    waited = 0.0
    while not policy.failed:
        waited += 0.01
        policy.account(t + waited, 50, waiting=True)
    # fails once lag > 5 s + 0.25 x played, lag = waited / 2 and played = 1 s + waited / 2
    assert waited == pytest.approx(2 * (5.0 + 0.25 * 1.0) / (1 - 0.25), abs=0.02)
    assert "without progress while blocks waited" in policy.describe()


def test_the_sim_device_plays_its_silence_when_nobody_calls():
    clock = [0.0]
    device = SimDevice(DeviceConfig(), clock=lambda: clock[0])
    port = device.open()
    port.write(p.encode(p.Hello(100), 0, 3))
    port.write(p.encode(p.Block(0, np.ones((500, 1), dtype=np.uint16)), 1, 3))
    clock[0] = 1.0  # the host stopped for a second: the device's clock ran on
    replies = p.Decoder().feed(port.read(4096))  # the next call plays that second
    assert [type(f.message) for f in replies] == [p.Info, p.Flushed]
    core: DeviceCore = device.core
    assert core.counters.watchdog_trips == 1 and core.level == 0


def test_the_sim_device_plays_its_silence_before_a_write_after_it():
    """The host's first call after 300 ms of silence is a write (PROTOCOL.md 5.3): the
    silence trips the watchdog before the frame re-arms it."""
    clock = [0.0]
    device = SimDevice(DeviceConfig(), clock=lambda: clock[0])
    port = device.open()
    port.write(p.encode(p.Hello(100), 0, 4))
    port.write(p.encode(p.Block(0, np.full((400, 1), 4096, dtype=np.uint16)), 1, 4))
    assert [type(f.message) for f in p.Decoder().feed(port.read(4096))] == [p.Info]
    clock[0] = 0.3
    port.write(p.encode(p.Heartbeat(7), 2, 4))
    replies = [f.message for f in p.Decoder().feed(port.read(4096))]
    assert [type(m) for m in replies] == [p.Flushed, p.Status]
    assert replies[-1].watchdog_trips == 1 and replies[-1].state != p.DeviceState.PLAYING
    assert device.core.counters.watchdog_trips == 1 and device.core.level == 0


@pytest.mark.parametrize("device, code, message", [
    ("/dev/nonexistent-frictex", 1, "frictex: error: cannot open device port "
                                    "'/dev/nonexistent-frictex'"),
    ("nosuchdevice", 2, "frictex: error: unknown output device 'nosuchdevice'; expected "
                        "one of port, sim"),
])
def test_a_device_that_cannot_be_reached_is_exit_1_a_bad_name_exit_2(tmp_path, capsys,
                                                                       device, code, message):
    from frictex.app.commands.cli import main
    assert main(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(tmp_path),
                 "--device", device]) == code
    err = capsys.readouterr().err
    assert err.startswith(message) and err.count("\n") == 1


class _GarbageDevice:
    """A port whose device answers every read with bytes that are no frame (a device at
    the wrong baud rate, or other firmware), zero bytes among them."""

    timeout = 0.01
    in_waiting = 0

    def __init__(self):
        self.rng = np.random.default_rng(5)

    def read(self, size=1):
        time.sleep(0.005)
        return self.rng.integers(0, 256, 64, dtype=np.uint8).tobytes()

    def write(self, data):
        return len(data)

    def close(self):
        pass


def test_a_device_that_answers_only_garbage_is_told_apart_from_a_silent_one():
    with pytest.raises(LinkError, match=r"no answer to the handshake within [0-9.]+ s "
                                        r"\([34] Hellos\): [0-9]+ bytes came back, none of "
                                        r"them a valid frame \([0-9]+ malformed frames thrown "
                                        r"away\); is the baud rate right, and is it a frictex "
                                        r"device\?$"):
        CommandSink(lambda: _GarbageDevice(), 1, RATE, paced=False, handshake_s=1.0)
