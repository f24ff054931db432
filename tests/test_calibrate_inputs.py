"""``frictex calibrate``'s and replay's device options and output paths: every mistake is
one line, exit 2, before the device is opened (so before a person's finger sweep)."""

import os
import socket

import pytest

import frictex.device.link.host as host
from frictex.app.commands.argtypes import sim_finger_args, sim_options
from frictex.app.commands.calibrate import DEFAULT_FINGER, SIM_LIMIT_UM, _sim_args
from frictex.app.commands.cli import main
from frictex.device.calibration_run import Sweep
from frictex.device.errors import InputError


@pytest.fixture
def no_device(monkeypatch):
    """Fail the test if the command opens a device."""
    def refuse(spec, *args, **kwargs):
        raise AssertionError(f"the device {spec} was opened")
    monkeypatch.setattr(host, "open_sink", refuse)


def _one_line(capsys) -> str:
    err = capsys.readouterr().err
    assert "Traceback" not in err and len(err.strip().splitlines()) == 1, err
    return err.strip()


@pytest.mark.parametrize("argv, message", [
    (["--out", "{tmp}/missing/c.toml"], "--out {tmp}/missing/c.toml: the folder "
                                        "{tmp}/missing does not exist"),
    (["--out", "{tmp}"], "--out {tmp}: is a folder; give a file to write"),
    (["--out", "{tmp}/file/c.toml"], "--out {tmp}/file/c.toml: cannot be written (Not a "
                                     "directory)"),
    (["--out", "/proc/c.toml"], "--out /proc/c.toml: /proc: a file system that holds no files"),
    (["--plot", "{tmp}/missing/p.png"], "--plot {tmp}/missing/p.png: the folder "
                                        "{tmp}/missing does not exist"),
    (["--plot", "{tmp}"], "--plot {tmp}: is a folder"),
    (["--plot", "{tmp}/c.toml"], "--plot {tmp}/c.toml: the same file as --out {tmp}/c.toml"),
    (["--plot", "{tmp}/sock"], "--plot {tmp}/sock: is a socket"),
    (["--finger", "5", "--device", "/dev/pts/99"], "--finger 5: needs --device sim (a "
                                                   "simulated device); got --device /dev/pts/99"),
    (["--finger", "5", "--device", "sim:finger=2"], "--finger 5: --device sim:finger=2 already "
                                                    "names the simulated finger (finger=2)"),
    (["--finger", "-1"], "--finger -1: expected a person number >= 0"),
])
def test_calibrate_refuses_before_opening_the_device(argv, message, tmp_path, capsys, no_device):
    (tmp_path / "file").write_text("")
    sock = socket.socket(socket.AF_UNIX)
    sock.bind(str(tmp_path / "sock"))
    try:
        argv = ["calibrate", "--device", "sim", "--out", str(tmp_path / "c.toml"), *argv]
        before = sorted(os.listdir(tmp_path))
        assert main([a.replace("{tmp}", str(tmp_path)) for a in argv]) == 2
    finally:
        sock.close()
    assert _one_line(capsys).startswith("frictex: error: " + message.replace("{tmp}", str(tmp_path)))
    assert sorted(os.listdir(tmp_path)) == before  # nothing written


def test_a_full_disk_is_said_before_the_device_opens(monkeypatch, tmp_path, capsys, no_device):
    """No room for the calibration file: the disk's error (exit 1), not bad input."""
    import shutil
    from collections import namedtuple
    usage = namedtuple("usage", "total used free")
    monkeypatch.setattr(shutil, "disk_usage", lambda path: usage(1 << 30, 1 << 30, 0))
    assert main(["calibrate", "--device", "sim", "--out", str(tmp_path / "c.toml")]) == 1
    assert "--out " + str(tmp_path / "c.toml") in _one_line(capsys)
    assert os.listdir(tmp_path) == []


def test_a_missing_plot_library_is_said_before_the_device_opens(monkeypatch, tmp_path, capsys,
                                                                no_device):
    monkeypatch.setitem(__import__("sys").modules, "matplotlib", None)
    assert main(["calibrate", "--device", "sim", "--out", str(tmp_path / "c.toml"),
                 "--plot", str(tmp_path / "p.png")]) == 1  # not installed: not bad input
    assert "--plot needs frictex's 'report' extra" in _one_line(capsys)


def test_the_simulated_finger_comes_from_the_option_or_the_spec_once():
    sweep = Sweep()
    flags = dict(zip(*[iter(_sim_args("sim", None, sweep))] * 2))
    assert flags == {"--finger": str(DEFAULT_FINGER), "--finger-speed": f"{sweep.speed_mm_s:g}",
                     "--force": f"{sweep.force_n:g}", "--limit": f"{SIM_LIMIT_UM:g}"}
    assert dict(zip(*[iter(_sim_args("sim", 4, sweep))] * 2))["--finger"] == "4"
    # what the spec names, the spec decides; the rest is the sweep's
    named = dict(zip(*[iter(_sim_args("sim:finger=4,limit=3", None, sweep))] * 2))
    assert "--finger" not in named and "--limit" not in named and named["--force"] == "0.5"
    assert _sim_args("/dev/pts/99", None, sweep) == ()
    with pytest.raises(InputError, match="needs --device sim"):
        _sim_args("loop://", 2, sweep)


def test_sim_options_read_every_spelling_of_the_simulated_device():
    assert sim_options("sim") == []
    assert sim_options("sim:finger=2,force=0.4") == [("finger", "2"), ("force", "0.4")]
    assert sim_options("sim://?finger=2") == [("finger", "2")]
    assert sim_options("/dev/ttyACM0") is None and sim_options(None) is None
    assert sim_finger_args("--sim-finger", 3, "sim:force=0.4") == ("--finger", "3")
    with pytest.raises(InputError, match="unknown output device 'nodevice'"):
        sim_options("nodevice:x")


@pytest.mark.parametrize("device", ["sim:finger=2", "sim://?finger=2"])
def test_replay_says_a_finger_given_twice(device, tmp_path, capsys, no_device):
    out = tmp_path / "out"
    assert main(["replay", "grating-15mm", "swipe-40mms-50hz", "--out", str(out),
                 "--device", device, "--sim-finger", "3"]) == 2
    assert _one_line(capsys) == (f"frictex: error: --sim-finger 3: --device {device} already "
                                 "names the simulated finger (finger=2); give the finger once, "
                                 "in one of them")
    assert not out.exists()
