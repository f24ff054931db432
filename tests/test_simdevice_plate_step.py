"""PROTOCOL.md 5.4: the plate's amplitude loop, first order, discretised exactly
(a = exp(-2 pi f_c / f_s)) in the Python reference and the C host port's board alike:
a step never overshoots, rings or goes negative, even at f_c / f_s = 0.4 (the bilinear
transform gave 1.51, 2.25, 1.87 um after a step to 2 um there, and -0.25 um after the
step back to 0) or at f_c / f_s = 4 (the default 400 Hz at 100 Hz, once refused as above
half the rate), and its response is 1 - a^n."""

import numpy as np
import pytest

from frictex.device.firmware.ccore import CDeviceCore
from frictex.device.link import protocol as p
from frictex.device.errors import InputError
from frictex.device.link.simdevice import DeviceConfig, DeviceCore
from frictex.device.link.simport import sim_config
from device_recorder import Recorder

RATE = 100.0
BANDWIDTHS = [40.0, 400.0]     # f_c / f_s = 0.4 and 4 (400 Hz: the default)
STEP_UM, HELD = 2.0, 20        # 20 ticks at 2 um, then 20 at 0
CORES = [DeviceCore, CDeviceCore]

pytestmark = pytest.mark.usefixtures("firmware_sim_library")


def _step_response(cls, bandwidth_hz):
    """Setpoints and plate amplitudes (um), one per tick, of a 2 um step held 20 ticks and
    then a step back to 0 held 20 ticks, a heartbeat every 5 ms, with the loop's corner
    at ``bandwidth_hz`` (Hz)."""
    rec = Recorder()
    core = cls(DeviceConfig(rate_hz=RATE, bandwidth_hz=bandwidth_hz, limits_um=(4.0,)),
               log=rec.log, plate_log=rec.plate_log)
    seq = iter(range(1000))
    core.receive(p.encode(p.Hello(2 * HELD), next(seq), version=1), 0.0)
    um = np.r_[np.full(HELD, STEP_UM), np.zeros(HELD)].reshape(-1, 1)
    core.receive(p.encode(p.Block(0, p.amplitude_to_wire(um)[0]), next(seq)), 0.0)
    for t in np.arange(0.005, 2 * HELD / RATE + 0.05, 0.005):
        core.advance_to(t)
        core.receive(p.encode(p.Heartbeat(0), next(seq)), t)
    _, setpoint, plate = rec.ticks()
    return setpoint[:, 0], plate[:, 0]


@pytest.mark.parametrize("bandwidth_hz", BANDWIDTHS)
@pytest.mark.parametrize("cls", CORES)
def test_a_step_neither_overshoots_nor_goes_negative(cls, bandwidth_hz):
    setpoint, plate = _step_response(cls, bandwidth_hz)
    assert setpoint.max() == STEP_UM
    assert plate.max() <= STEP_UM and plate.min() >= 0.0


@pytest.mark.parametrize("bandwidth_hz", BANDWIDTHS)
@pytest.mark.parametrize("cls", CORES)
def test_the_step_response_is_1_minus_a_to_the_n(cls, bandwidth_hz):
    setpoint, plate = _step_response(cls, bandwidth_hz)
    pole = np.exp(-2 * np.pi * bandwidth_hz / RATE)
    first = int(np.argmax(setpoint > 0))
    n = np.arange(1, HELD + 1)  # ticks the step has been held
    up = STEP_UM * (1 - pole ** n)
    np.testing.assert_allclose(plate[first:first + HELD], up, rtol=1e-12, atol=1e-12)
    down = up[-1] * pole ** n   # then the step to 0: a decay, never below it
    np.testing.assert_allclose(plate[first + HELD:first + 2 * HELD], down, rtol=1e-12,
                               atol=1e-12)


@pytest.mark.parametrize("cls", CORES)
def test_a_sim_device_at_100_hz_takes_the_default_bandwidth(cls):
    """``frictex replay ... --rate 100 --device sim`` was refused: "sim-device bandwidth_hz
    = 400.0: expected positive and below half the sample rate"; the exact discretisation
    holds at any rate (PROTOCOL.md 5.4)."""
    config = sim_config([], channels=1, rate_hz=100.0, phases=False)
    assert config.bandwidth_hz == 400.0
    reply = p.Decoder().feed(cls(config).receive(p.encode(p.Hello(10), 0), 0.0))
    assert [f.message.sample_rate_hz for f in reply] == [100.0]


@pytest.mark.parametrize("bandwidth_hz", [0.0, -1.0, float("inf"), float("nan")])
def test_a_bandwidth_that_is_not_positive_and_finite_is_refused(bandwidth_hz):
    with pytest.raises(InputError, match="bandwidth_hz = .*: expected positive and finite$"):
        DeviceConfig(rate_hz=RATE, bandwidth_hz=bandwidth_hz)
