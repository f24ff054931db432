"""PROTOCOL.md 5.3: the watchdog's hold and the ramp, rounded up to whole ticks, must end
within 50 ms, and a ramp (ramp_ms > 0) must last at least 2 ticks. At low sample rates
the ms sum alone was not enough: 25 + 20 ms at 20 Hz is one tick each, a 50 ms hold
then a step to zero. The C host port and the Python reference refuse alike."""

import subprocess

import pytest

from frictex.device.link.simdevice import DeviceConfig
from frictex.device.errors import InputError

REFUSED = [  # rate_hz, watchdog_ms, ramp_ms, the words naming the rule
    (20.0, 25, 20, "ramp_ms"),               # a one-tick ramp: a step
    (60.0, 25, 20, "watchdog_ms"),           # 2 + 2 ticks = 66.7 ms
    (20.0, 25, 0, "watchdog_ms"),            # 1 tick hold + the step = 100 ms
    (44_100.0, 25, 25, "watchdog_ms"),       # 1103 + 1103 ticks = 50.02 ms
]
ACCEPTED = [(100.0, 25, 20), (80.0, 25, 20), (1_000.0, 49, 0), (44_100.0, 25, 20),
            (10_000.0, 25, 25)]


@pytest.mark.parametrize("rate_hz, watchdog_ms, ramp_ms, name", REFUSED)
def test_the_reference_refuses_a_stop_longer_than_50_ms_in_ticks(rate_hz, watchdog_ms,
                                                                  ramp_ms, name):
    with pytest.raises(InputError, match=rf"^sim-device {name} = .*PROTOCOL.md 5.3") as exc:
        DeviceConfig(rate_hz=rate_hz, bandwidth_hz=rate_hz / 10, watchdog_ms=watchdog_ms,
                     ramp_ms=ramp_ms)
    assert "\n" not in str(exc.value)


@pytest.mark.parametrize("rate_hz, watchdog_ms, ramp_ms", ACCEPTED)
def test_the_reference_accepts_a_stop_within_50_ms_in_ticks(rate_hz, watchdog_ms, ramp_ms):
    cfg = DeviceConfig(rate_hz=rate_hz, bandwidth_hz=rate_hz / 10, watchdog_ms=watchdog_ms,
                       ramp_ms=ramp_ms)
    assert (cfg.ticks(watchdog_ms) + cfg.ticks(ramp_ms)) / rate_hz <= 0.050


def _host_port(binary, rate_hz, watchdog_ms, ramp_ms):
    """The C host port started with these settings: a refused configuration exits 2 at
    once; an accepted one runs (the caller kills it)."""
    return subprocess.Popen([str(binary), "--rate", repr(rate_hz), "--bandwidth",
                             repr(rate_hz / 10), "--watchdog-ms", str(watchdog_ms),
                             "--ramp-ms", str(ramp_ms)],
                            stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True)


@pytest.mark.parametrize("rate_hz, watchdog_ms, ramp_ms, name", REFUSED)
def test_the_c_core_refuses_a_stop_longer_than_50_ms_in_ticks(firmware_host_port, rate_hz,
                                                               watchdog_ms, ramp_ms, name):
    proc = _host_port(firmware_host_port, rate_hz, watchdog_ms, ramp_ms)
    out, err = proc.communicate(timeout=10)
    assert proc.returncode == 2 and out == ""
    assert err.startswith(f"frictex-fw-host: error: {name}") and "PROTOCOL.md 5.3" in err
    assert err.count("\n") == 1


@pytest.mark.parametrize("rate_hz, watchdog_ms, ramp_ms", ACCEPTED)
def test_the_c_core_accepts_a_stop_within_50_ms_in_ticks(firmware_host_port, rate_hz,
                                                          watchdog_ms, ramp_ms):
    proc = _host_port(firmware_host_port, rate_hz, watchdog_ms, ramp_ms)
    try:
        line = proc.stdout.readline()  # the port prints its pty path once it runs
        assert proc.poll() is None, proc.stderr.read()
        assert line
    finally:
        proc.kill()
        proc.communicate(timeout=10)
