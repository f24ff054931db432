"""What a device link is opened with: ``frictex sim-device``'s options against what the
protocol and the firmware can hold, and ``--device`` URLs checked before pyserial sees
them (one line, exit 2, for every malformed one)."""

import re
import socket
from pathlib import Path

import pytest
import serial
from hypothesis import HealthCheck, example, given, settings, strategies as st
from serial.rfc2217 import Serial as Rfc2217Serial
from serial.urlhandler.protocol_loop import Serial as LoopSerial
from serial.urlhandler.protocol_spy import Serial as SpySerial

from frictex.app.commands.cli import main
from frictex.device.errors import DeviceError, InputError
from frictex.device.link import protocol as p
from frictex.device.link.devices import resolve
from frictex.device.link.port import URL_SCHEMES, TcpPort, check_url, open_port
from frictex.device.link.simdevice import (MAX_CHANNELS, NAME_MAX, STORE_WORDS, DeviceConfig,
                                           open_listener)

FW_LIMITS = Path(__file__).parents[1] / "device" / "firmware" / "core" / "fw_limits.h"
SETTINGS = settings(max_examples=300, deadline=None, derandomize=True,
                    suppress_health_check=[HealthCheck.too_slow])


def run_cli(argv) -> int:
    """``frictex ARGV``'s exit code (argparse's errors exit through SystemExit)."""
    try:
        return main(argv)
    except SystemExit as exc:
        return exc.code


def _fw_define(name: str) -> int:
    """A ``#define NAME <product of integers>`` of the firmware's fw_limits.h."""
    found = re.search(rf"#define {name} \(?([\d *u]+)\)?\n", FW_LIMITS.read_text())
    value = 1
    for factor in found.group(1).replace("u", "").split("*"):
        value *= int(factor)
    return value


def test_the_sim_devices_bounds_are_the_firmwares():
    assert (MAX_CHANNELS, STORE_WORDS, NAME_MAX) == (
        _fw_define("FW_MAX_CHANNELS"), _fw_define("FW_STORE_WORDS"), _fw_define("FW_NAME_MAX"))


def mostly(good, bad):
    """``good`` nine draws in ten, else ``bad``: every field must pass for a config to."""
    return st.one_of(*[good] * 9, bad)


@SETTINGS
@given(channels=mostly(st.integers(1, 8), st.sampled_from([-1, 0, 9, 255, 256, 1000])),
       rate=mostly(st.floats(1e-3, 4e6, exclude_max=True),
                   st.sampled_from([0.0, 4e-4, 4e6, 5e6, float("nan"), float("inf")])),
       limit=mostly(st.floats(2 ** -12, 65535 * 2 ** -12), st.floats(-1e-3, 17.0)),
       buffer=mostly(st.integers(2, 32768), st.integers(-1, 2 ** 33)),
       watchdog=mostly(st.integers(1, 25), st.integers(-1, 52)),
       ramp=mostly(st.integers(0, 25), st.integers(-1, 52)), name=st.text(max_size=40))
@example(channels=1000, rate=1e4, limit=4.0, buffer=4096, watchdog=25, ramp=20, name="x")
@example(channels=1, rate=1e-4, limit=4.0, buffer=4096, watchdog=25, ramp=20, name="x")
@example(channels=1, rate=1e4, limit=1e-4, buffer=4096, watchdog=25, ramp=20, name="x")
def test_a_config_the_device_accepts_is_one_its_info_can_say(channels, rate, limit, buffer,
                                                             watchdog, ramp, name):
    """Each DeviceConfig either is refused in one line naming the field, or its Info
    encodes and decodes to what it declares (``--channels 1000`` was accepted and died on
    the first Hello)."""
    try:
        config = DeviceConfig(channels=channels, rate_hz=rate, limits_um=(limit,),
                              buffer_samples=buffer, watchdog_ms=watchdog, ramp_ms=ramp,
                              name=name)
    except InputError as exc:
        assert str(exc).startswith("sim-device ") and ": expected " in str(exc)
        assert "\n" not in str(exc)
        return
    info = config.info()
    (frame,) = p.Decoder().feed(p.encode(info))
    back = frame.message
    assert (back.channels, back.buffer_samples, back.watchdog_ms, back.ramp_ms, back.name) == (
        channels, buffer, watchdog, ramp, name)
    assert back.limits_um == info.limits_um and min(back.limits_um) > 0
    assert back.sample_rate_hz > 0


@pytest.mark.parametrize("flags, message", [
    (("--channels", "1000"), "argument --channels: '1000' channels: expected 1 to 8"),
    (("--channels", "9"), "expected 1 to 8"),
    (("--channels", "8", "--buffer", "40000"), "buffer_samples = 40000: expected 2 to 32768 "
                                                "samples for 8 channel(s)"),
    (("--limit", "0.0001"), "limits_um = (0.0001,): expected in [1/4096, 15.9998] um"),
    (("--rate", "0.0001"), "rate_hz = 0.0001: expected in [0.001, 4e6) Hz"),
    (("--ramp-ms", "1000"), "ramp_ms = 1000: expected in [0, 25] ms"),
    (("--ramp-ms", "-1"), "ramp_ms = -1: expected in [0, 25] ms"),
    (("--watchdog-ms", "45", "--ramp-ms", "6"), "ramp_ms = 6: expected in [0, 5] ms"),
    (("--watchdog-ms", "50"), "argument --watchdog-ms: '50' ms: expected 1 to 49"),
    (("--channels", "2", "--limit", "1", "--limit", "2", "--limit", "3"),
     "expected one value for all channels or one per channel (2)"),
])
def test_sim_device_refuses_what_the_device_cannot_declare(capsys, flags, message):
    assert run_cli(["sim-device", "--once", *flags]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and err[0].startswith("frictex: error: ") and message in err[0], err


def test_a_zero_ramp_is_what_the_ramp_message_allows():
    """``--ramp-ms 0`` was refused ('must be at least 1') though the message for 1000 says
    [0, 25] ms; the protocol and the firmware take 0 (one tick)."""
    from frictex.app.commands import sim_device
    import argparse
    parser = argparse.ArgumentParser()
    sim_device.add_arguments(parser)
    args = parser.parse_args(["--ramp-ms", "0"])
    config = DeviceConfig(ramp_ms=args.ramp_ms)
    assert config.info().ramp_ms == 0 and config.ticks(config.ramp_ms) == 1


# ------------------------------------------------------------------ --device URLs

#: pyserial's own parse of each scheme's URL (no port is opened)
PYSERIAL_PARSE = {"socket": lambda url: TcpPort(None).from_url(url),
                  "rfc2217": lambda url: Rfc2217Serial(None).from_url(url),
                  "loop": lambda url: LoopSerial(None).from_url(url),
                  "spy": lambda url: SpySerial(None).from_url(url)}

_text = st.text(st.characters(codec="utf-8", exclude_categories=("Cs",)), max_size=12)
_host = st.sampled_from(["127.0.0.1", "localhost", "[::1]", "plate.lab", "h_1"])
_piece = st.one_of(_host, _text, st.sampled_from(["", ":", "::", "[", "]", "@", "/", "#", "?",
                                                  "&", "=", " "]))
_port = st.one_of(st.integers(-5, 70_000).map(str), _text, st.sampled_from(["", "+5", "05"]))
_option = st.sampled_from(["logging", "logging=info", "logging=x", "timeout=2",
                           "timeout=-1", "timeout=nan", "poll_modem", "poll_modem=1",
                           "ign_set_control", "color", "raw", "raw=0", "all", "file=",
                           "foo", "foo=1", ""])


@st.composite
def device_urls(draw):
    """socket://, rfc2217://, loop:// and spy:// URLs, well- and malformed."""
    scheme = draw(st.sampled_from(sorted(URL_SCHEMES)))
    if draw(st.booleans()):
        middle = f"{draw(st.one_of(_host, _piece))}:{draw(_port)}"
    else:
        middle = draw(_piece) + draw(_piece)
    options = draw(st.lists(_option, max_size=3))
    query = ("?" + "&".join(options)) if options or draw(st.booleans()) else ""
    return f"{scheme}://{middle}{query}"


@SETTINGS
@given(url=device_urls())
@example(url="socket://")
@example(url="socket://127.0.0.1:notaport")
@example(url="socket://127.0.0.1:0")
@example(url="loop://?logging=bad")
@example(url="spy://loop://")
def test_a_url_is_refused_in_one_line_or_is_one_pyserial_reads(url):
    """Malformed URLs were pyserial's internals ("'<=' not supported between instances of
    'int' and 'NoneType'", "'debug|info|warning|error'"), exit 1, or a traceback
    (``loop://?logging=x``). Now: refused in one line naming the URL and the form; and
    whatever passes, pyserial's own parser takes, with a host and a port 1 to 65535
    where the scheme has them."""
    scheme = url.partition("://")[0]
    try:
        check_url(url)
    except InputError as exc:
        text = str(exc)
        assert text.startswith(f"device URL {url!r}: ") and "\n" not in text
        assert f"(form: {URL_SCHEMES[scheme][0]})" in text
        return
    assert "file=" not in url  # spy's file option opens the file: never drawn valid
    parsed = PYSERIAL_PARSE[scheme](url)
    if URL_SCHEMES[scheme][1]:
        host, port = parsed
        assert host and 1 <= port <= 65535


_level = st.sampled_from(["debug", "info", "warning", "error"])
_options = {
    "socket": [_level.map("logging={}".format)],
    "rfc2217": [_level.map("logging={}".format), st.just("ign_set_control"),
                st.just("poll_modem"),
                st.floats(1e-3, 1e3).map("timeout={!r}".format)],
    "loop": [_level.map("logging={}".format)],
    "spy": [st.just("color"), st.just("raw"), st.just("all")]}


@st.composite
def well_formed_urls(draw):
    """(URL, (host, port) or None) of each scheme, every option drawn at most once."""
    scheme = draw(st.sampled_from(sorted(URL_SCHEMES)))
    chosen = draw(st.lists(st.sampled_from(range(len(_options[scheme]))), unique=True))
    query = "&".join(draw(_options[scheme][k]) for k in chosen)
    query = "?" + query if query else ""
    if scheme in ("socket", "rfc2217"):
        host, port = draw(_host), draw(st.integers(1, 65535))
        return f"{scheme}://{host}:{port}{query}", (host.strip("[]"), port)
    if scheme == "spy":
        return f"spy://{draw(st.sampled_from(['/dev/ttyACM0', 'COM3', '/dev/pts/7']))}{query}", None
    return f"loop://{query}", None


@SETTINGS
@given(drawn=well_formed_urls())
def test_every_well_formed_url_passes_and_pyserial_reads_it_alike(drawn):
    url, address = drawn
    check_url(url)
    parsed = PYSERIAL_PARSE[url.partition("://")[0]](url)
    if address is not None:
        assert parsed == address


@pytest.mark.parametrize("url", [
    "socket://127.0.0.1:5000", "socket://[::1]:5000?logging=info", "socket://plate.lab:1/",
    "rfc2217://10.0.0.2:2217?timeout=2.5&poll_modem&ign_set_control",
    "loop://", "loop://?logging=debug", "spy:///dev/ttyACM0?raw&color&all",
    "spy://COM3?file=spy.txt"])
def test_well_formed_urls_pass(url):
    check_url(url)


@pytest.mark.parametrize("spec, message", [
    ("socket://", "device URL 'socket://': no host"),
    ("socket://127.0.0.1:notaport", "port 'notaport': expected a whole number 1 to 65535"),
    ("socket://127.0.0.1:70000", "port '70000': expected a whole number 1 to 65535"),
    ("socket://127.0.0.1:0", "port 0: expected a whole number 1 to 65535"),
    ("socket://h:5?logging=loud", "option logging='loud': expected debug|info|warning|error"),
    ("rfc2217://h:5?frob", "unknown option 'frob' (known: logging, ign_set_control, "
                           "poll_modem, timeout)"),
    ("loop://?logging=x", "option logging='x'"),
    ("spy:///dev/ttyS0?raw=0", "option raw='0': expected no value"),
    ("hwgrep://USB", "unknown URL scheme 'hwgrep'; expected a device ("),
])
def test_replay_refuses_a_malformed_device_url_with_exit_2(tmp_path, capsys, spec, message):
    out = tmp_path / "out"
    rc = run_cli(["replay", "grating-15mm", "swipe-40mms-50hz", "--out", str(out),
               "--device", spec])
    err = capsys.readouterr().err.strip().splitlines()
    assert rc == 2 and len(err) == 1 and err[0].startswith("frictex: error: "), err
    assert message in err[0] and not out.exists()


def test_open_port_checks_the_url_before_pyserial():
    with pytest.raises(InputError, match="port 'x'"):
        open_port("socket://localhost:x")
    port = open_port("loop://")  # a well-formed URL still opens
    try:
        assert isinstance(port, serial.SerialBase)
    finally:
        port.close()


def test_a_device_name_or_a_known_scheme_resolves():
    assert resolve("socket://h:1")[1] == "socket://h:1"
    assert resolve("sim://?finger=2")[1] == "?finger=2"
    with pytest.raises(InputError, match="unknown URL scheme 'foo'"):
        resolve("foo://x")


def test_a_listen_address_or_log_that_cannot_be_had_is_one_line(tmp_path, capsys):
    """``--tcp`` on an address of another machine is bad input (InputError, exit 2); a
    port in use is the machine's state (DeviceError, exit 1); an unwritable ``--log``
    names the file (exit 2). Called directly where success would serve for ever."""
    with pytest.raises(InputError, match=r"^cannot listen on '192\.0\.2\.1:0': .*expected "
                                         r"an address of this machine, such as 127\.0\.0\.1\)$"):
        open_listener("192.0.2.1", 0)
    taken = socket.create_server(("127.0.0.1", 0))
    try:
        port = taken.getsockname()[1]
        with pytest.raises(DeviceError, match=rf"^cannot listen on '127\.0\.0\.1:{port}': "
                                              r"[^(]+$"):
            open_listener("127.0.0.1", port)
    finally:
        taken.close()
    log = tmp_path / "missing" / "played.csv"
    assert run_cli(["sim-device", "--once", "--log", str(log)]) == 2
    err = capsys.readouterr().err.strip().splitlines()
    assert err == [f"frictex: error: cannot write the log file {log}: No such file or directory"]
