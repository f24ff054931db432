"""argparse types shared by the subcommands: each rejects a bad value with one line."""

from __future__ import annotations

import argparse

from frictex.app.engine.limits import BLOCK_SIZES, OUTPUT_RATES_HZ
from frictex.device.errors import InputError


def positive_float(text: str) -> float:
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not value > 0 or value == float("inf"):
        raise argparse.ArgumentTypeError(f"{text!r} must be a positive finite number")
    return value


def positive_int(text: str) -> int:
    try:
        value = int(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a whole number") from None
    if value < 1:
        raise argparse.ArgumentTypeError(f"{text!r} must be at least 1")
    return value


def share(text: str) -> float:
    """A share in [0, 1]."""
    try:
        value = float(text)
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not a number") from None
    if not 0.0 <= value <= 1.0:
        raise argparse.ArgumentTypeError(f"{text!r} must be between 0 and 1")
    return value


def fault_plan(text: str):
    """A ``--faults`` spec (``device.link.faults.parse_faults``)."""
    from frictex.device.link.faults import parse_faults
    try:
        return parse_faults(text)
    except ValueError as exc:
        raise argparse.ArgumentTypeError(str(exc)) from None


def bounded(kind, low, high, unit: str):
    """An argparse type: ``kind(text)`` (int or float) within [low, high] ``unit``."""
    def parse(text: str):
        value = positive_int(text) if kind is int else positive_float(text)
        if not low <= value <= high:
            raise argparse.ArgumentTypeError(f"{text!r} {unit}: expected {low:g} to {high:g}")
        return value
    return parse


#: an output rate (Hz) within app.engine.limits (seed 003's link runs at 10 kHz)
output_rate = bounded(float, *OUTPUT_RATES_HZ, "Hz")
#: a block size (output samples) within app.engine.limits
block_size = bounded(int, *BLOCK_SIZES, "samples")


def add_link_arguments(parser: argparse.ArgumentParser) -> None:
    """``--device``, ``--faults``, ``--sim-finger`` and ``--control``, as every command
    that streams to a device takes them."""
    from frictex.textures.model import CONTROL_MODES
    parser.add_argument("--device", metavar="NAME[:ARG]|PORT", default=None,
                        help="stream the commands to an output device: 'sim' starts a "
                             "simulated one, 'audio[:NAME]' plays through a sound card (the "
                             "audio extra), otherwise a serial port or pyserial URL; an unknown "
                             "NAME lists every device installed, a package's too (default: no "
                             "link)")
    parser.add_argument("--faults", metavar="SPEC", type=fault_plan, default=None,
                        help="with --device: inject link faults, e.g. 'corrupt=0.001,"
                             "stall=0.2@1.5,trip@3,unplug=2@4' (grammar: device/link/faults.py)")
    parser.add_argument("--sim-finger", type=int, default=None, metavar="N",
                        help="with --device sim: the simulated device reports the lateral and "
                             "normal force of person N of the simulated finger population "
                             "(device/finger.py), sliding at 100 mm/s with 0.5 N")
    parser.add_argument("--control", choices=CONTROL_MODES, default=None,
                        help="friction control instead of the scene file's: open loop, closed "
                             "on the device's measured friction, or closed and adapting the "
                             "friction model (needs a device with force reports, e.g. "
                             "--device sim --sim-finger 3; rendering/control/loop.py)")


def sim_device_args(args: argparse.Namespace) -> tuple[str, ...]:
    """``frictex sim-device`` flags from ``--sim-finger`` (:func:`sim_finger_args`);
    every option of :func:`add_link_arguments` that acts on a device is refused without
    ``--device`` rather than ignored."""
    if args.device is None and args.faults is not None:
        raise InputError("--faults: needs --device (the faults are injected on the link to a "
                         "device); no --device was given")
    unplayed = getattr(args, "max_unplayed", None)
    if args.device is None and unplayed is not None:
        raise InputError(f"--max-unplayed {unplayed:g}: needs --device (the share of samples a "
                         "device never played); no --device was given")
    return sim_finger_args("--sim-finger", args.sim_finger, args.device)


def add_max_unplayed(parser: argparse.ArgumentParser, default: float, more: str = "") -> None:
    """``--max-unplayed`` (replay, demo), refused without ``--device`` by
    :func:`sim_device_args`; ``more`` ends its help."""
    parser.add_argument("--max-unplayed", type=share, default=None, metavar="SHARE",
                        help="with --device: exit 1 when more than this share of the "
                             f"commanded samples never played on the device (default "
                             f"{default:g}){more}")


def sim_options(device: str | None) -> list[tuple[str, str]] | None:
    """The (option, text) pairs a ``--device`` spec gives the simulated device (``sim``:
    none; ``sim:finger=2`` or ``sim://?finger=2``: ``[("finger", "2")]``); None when
    ``device`` is None or names another device. An unknown device name is ``UnknownName``
    (an InputError) listing the known."""
    if device is None:
        return None
    import importlib
    importlib.import_module("frictex.device.link.host")  # registers the built-in devices
    from frictex.device.link.devices import DEVICES, resolve, sim_pairs
    factory, arg = resolve(device)
    return sim_pairs(arg, ()) if factory is DEVICES.get("sim") else None


def sim_finger_args(option: str, finger: int | None, device: str | None) -> tuple[str, ...]:
    """``frictex sim-device`` flags for the simulated finger ``finger`` (person number,
    given as ``option``: replay's ``--sim-finger``, calibrate's ``--finger``); () when it
    is None. Refused (InputError) below 0, without a simulated ``device``, and with a
    ``device`` spec that already names a finger (``sim:finger=2``)."""
    if finger is None:
        return ()
    if finger < 0:
        raise InputError(f"{option} {finger}: expected a person number >= 0")
    pairs = sim_options(device)
    if pairs is None:
        given = f"got --device {device}" if device else "no --device was given"
        raise InputError(f"{option} {finger}: needs --device sim (a simulated device); {given}")
    named = [text for name, text in pairs if name == "finger"]
    if named:
        raise InputError(f"{option} {finger}: --device {device} already names the simulated "
                         f"finger (finger={named[-1]}); give the finger once, in one of them")
    return ("--finger", str(finger))
