"""Android ``getevent -lt`` logs to evdev events.

Grammar (one event per line; ``-l`` prints names, without it the fields are hex)::

    line    := "[" SPACES seconds "." micros "]" [ device ":" ] type code value
    type    := EV_ABS | EV_SYN | ... | 4 hex digits
    code    := ABS_MT_POSITION_X | SYN_REPORT | ... | 4 hex digits
    value   := 8 hex digits (a 32-bit field: ffffffff is -1) | DOWN | UP | REPEAT
    skipped := blank lines, "add device N: path", "  name: ...", "could not ..." lines

Codes frictex does not use (ABS_MISC, KEY_*) are kept with code -1, which the decoder
ignores. A log holding several devices needs ``device`` to pick one. The log does not
record the axis ranges (``getevent -p`` prints them): the importer must be told them.

Digits are ASCII (``re``'s ``\\d`` alone also takes Unicode digits); a time is at most
MAX_TIME_S. A line that is not of the grammar is described, never printed; the device
names and tokens an error shows are escaped and cut (``device.safe_text``).
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import NamedTuple

from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE,
                                    ABS_MT_SLOT, ABS_MT_TOUCH_MAJOR, ABS_MT_TRACKING_ID,
                                    BTN_TOUCH, EV_ABS, EV_KEY, EV_SYN, SYN_DROPPED,
                                    SYN_MT_REPORT, SYN_REPORT, Event, read_text, signed32)
from frictex.rendering.input.trace_file import MAX_TIME_S, TraceError
from frictex.device.safe_text import quoted

TYPES = {"EV_SYN": EV_SYN, "EV_KEY": EV_KEY, "EV_REL": 0x02, "EV_ABS": EV_ABS, "EV_MSC": 0x04,
         "EV_SW": 0x05, "EV_LED": 0x11, "EV_SND": 0x12, "EV_REP": 0x14, "EV_FF": 0x15,
         "EV_PWR": 0x16, "EV_FF_STATUS": 0x17}
CODES = {"SYN_REPORT": SYN_REPORT, "SYN_CONFIG": 0x01, "SYN_MT_REPORT": SYN_MT_REPORT,
         "SYN_DROPPED": SYN_DROPPED, "BTN_TOUCH": BTN_TOUCH, "ABS_MT_SLOT": ABS_MT_SLOT,
         "ABS_MT_TOUCH_MAJOR": ABS_MT_TOUCH_MAJOR, "ABS_MT_POSITION_X": ABS_MT_POSITION_X,
         "ABS_MT_POSITION_Y": ABS_MT_POSITION_Y, "ABS_MT_TRACKING_ID": ABS_MT_TRACKING_ID,
         "ABS_MT_PRESSURE": ABS_MT_PRESSURE}
VALUES = {"UP": 0, "DOWN": 1, "REPEAT": 2}

_LINE = re.compile(r"^\s*\[\s*(?P<t>\d{1,12}\.\d{1,9})\s*\]\s+(?:(?P<dev>/\S+):\s+)?"
                   r"(?P<type>\S+)\s+(?P<code>\S+)\s+(?P<value>\S+)\s*$", re.ASCII)
_UNTIMED = re.compile(r"^\s*(?:/\S+:\s+)?(EV_[A-Z_]+|[0-9a-f]{4})\s+\S+\s+\S+\s*$", re.ASCII)
_HEADER = ("add device", "name:", "could not", "version", "events:", "input props:",
           "location:", "id:", "bus ")
_HEX4 = re.compile(r"^[0-9a-fA-F]{4}$")
_HEX8 = re.compile(r"^[0-9a-fA-F]{1,8}$")


def _number(token: str, names: dict[str, int], where: str, line: int, field: str) -> int:
    if token in names:
        return names[token]
    if _HEX4.match(token):
        return int(token, 16)
    if field == "type":
        raise TraceError(f"{where}:{line}: event type {quoted(token)} is not known "
                         f"(expected EV_ABS, EV_SYN, ... or 4 hex digits)")
    return -1  # a code frictex does not use (ABS_MISC, KEY_VOLUMEUP, ...)


class GeteventLog(NamedTuple):
    """What a ``getevent`` log holds: its events (times in s, ``line`` 1-based) and the
    warnings to show (a last line cut short, left out)."""

    events: list[Event]
    warnings: list[str]


def parse_getevent(text: str, where: str = "<getevent>", device: str | None = None) -> list[Event]:
    """Events of a ``getevent -lt`` log (:func:`read_log`'s events)."""
    return read_log(text, where, device).events


def read_log(text: str, where: str = "<getevent>", device: str | None = None) -> GeteventLog:
    """Events of a ``getevent -lt`` log (see the module docstring for the grammar).

    Parameters
    ----------
    text : the log.
    where : names the source in error messages.
    device : keep only this device's lines (``/dev/input/event2``); required when the log
        holds events of several devices.

    A last line without a line break that is not of the grammar (a recording stopped
    mid-line with Ctrl-C) is left out with a warning.
    """
    events: list[Event] = []
    devices: dict[str, int] = {}
    warnings: list[str] = []
    lines = text.splitlines()
    for number, raw in enumerate(lines, start=1):
        stripped = raw.strip()
        if not stripped or stripped.startswith(_HEADER):
            continue
        m = _LINE.match(raw)
        if m is None and number == len(lines) and not text.endswith(("\n", "\r")):
            warnings.append(f"{where}:{number}: the last line is cut short (no line break; "
                            "the recording stopped mid-line): left out")
            break
        if m is None:
            if _UNTIMED.match(raw):
                raise TraceError(f"{where}:{number}: event without a timestamp: record with "
                                 "'getevent -lt' (the -t adds '[ seconds.micros]')")
            raise TraceError(f"{where}:{number}: not a getevent -lt line (expected "
                             "'[ seconds.micros] EV_TYPE CODE VALUE', ASCII digits)")
        dev = m["dev"] or ""
        devices.setdefault(dev, number)
        if device is not None and dev != device:
            continue
        etype = _number(m["type"], TYPES, where, number, "type")
        code = _number(m["code"], CODES, where, number, "code")
        token = m["value"]
        if token in VALUES:
            value = VALUES[token]
        elif _HEX8.match(token):
            value = signed32(int(token, 16))
        else:
            raise TraceError(f"{where}:{number}: value {quoted(token)} is not 8 hex digits "
                             "(or DOWN / UP / REPEAT)")
        t = float(m["t"])
        if t > MAX_TIME_S:
            raise TraceError(f"{where}:{number}: event time {t:g} s is more than {MAX_TIME_S:g} s "
                             "(evdev clocks count from boot or from 1970)")
        events.append(Event(t, etype, code, value, number))
    named = sorted(d for d in devices if d)
    if device is not None and device not in devices:
        raise TraceError(f"{where}: no events of device {quoted(device)} "
                         f"(the log has {_names(named) or 'no device names'})")
    if device is None and len(devices) > 1:
        raise TraceError(f"{where}: events of {len(devices)} devices ({_names(named)}); "
                         "choose one with --device")
    return GeteventLog(events, warnings)


def _names(devices: list[str], shown: int = 8) -> str:
    """The first ``shown`` device names, escaped, for an error."""
    more = f" and {len(devices) - shown} more" if len(devices) > shown else ""
    return ", ".join(quoted(d, 40) for d in devices[:shown]) + more


def read_getevent(path: str | Path, device: str | None = None) -> list[Event]:
    """Read a ``getevent -lt`` log file (see :func:`parse_getevent`)."""
    return parse_getevent(read_text(path, "getevent log"), str(path), device)
