"""Android ``getevent -lt`` logs to evdev events.

Grammar (one event per line; ``-l`` prints names, without it the fields are hex)::

    line    := "[" SPACES seconds "." micros "]" [ device ":" ] type code value [ rate ]
    rate    := "rate" digits (``getevent -ltr``: reports per second, after SYN_REPORT; ignored)
    type    := EV_ABS | EV_SYN | ... | 4 hex digits
    code    := ABS_MT_POSITION_X | SYN_REPORT | ... | 4 hex digits
    value   := 8 hex digits (a 32-bit field: ffffffff is -1) | DOWN | UP | REPEAT
    skipped := blank lines, "add device N: path", "  name: ...", "could not ..." lines
    absinfo := [ "ABS (0003):" ] code ":" "value" v ", min" lo ", max" hi ", fuzz" f
               ", flat" f [ ", resolution" r ]

Codes frictex does not use (ABS_MISC, KEY_*) are kept with code -1, which the decoder
ignores; an unknown name starting ``ABS_MT_`` (a typo of a code frictex reads?) is also
warned of, once per name, at its first line. A device's events are in time order (the
kernel stamps them so), checked on every line. A log holding several devices needs
``device`` to pick one. A log recorded with ``getevent -lpt`` starts with a ``-p``
section per device ("add device N: path" up to the first event): its ``absinfo`` lines
give the axis ranges and resolutions (those of the device the events come from are
kept); its other lines are skipped.

Digits are ASCII (``re``'s ``\\d`` alone also takes Unicode digits); a time is at most
MAX_TIME_S. A line that is not of the grammar is described, never printed; the device
names and tokens an error shows are escaped and cut (``device.safe_text``).
"""

from __future__ import annotations

import math
import re
from pathlib import Path
from typing import NamedTuple

from frictex.rendering.input.evdev_decode import (ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_PRESSURE,
                                    ABS_MT_SLOT, ABS_MT_TOUCH_MAJOR, ABS_MT_TRACKING_ID,
                                    BTN_TOUCH, EV_ABS, EV_KEY, EV_SYN, SYN_DROPPED,
                                    SYN_MT_REPORT, SYN_REPORT, AbsInfo, Event, read_text,
                                    signed32)
from frictex.rendering.input.trace_file import MAX_TIME_S, TraceError
from frictex.device.safe_text import quoted

TYPES = {"EV_SYN": EV_SYN, "EV_KEY": EV_KEY, "EV_REL": 0x02, "EV_ABS": EV_ABS, "EV_MSC": 0x04,
         "EV_SW": 0x05, "EV_LED": 0x11, "EV_SND": 0x12, "EV_REP": 0x14, "EV_FF": 0x15,
         "EV_PWR": 0x16, "EV_FF_STATUS": 0x17}
CODES = {"SYN_REPORT": SYN_REPORT, "SYN_CONFIG": 0x01, "SYN_MT_REPORT": SYN_MT_REPORT,
         "SYN_DROPPED": SYN_DROPPED, "BTN_TOUCH": BTN_TOUCH, "ABS_MT_SLOT": ABS_MT_SLOT,
         "ABS_MT_TOUCH_MAJOR": ABS_MT_TOUCH_MAJOR, "ABS_MT_POSITION_X": ABS_MT_POSITION_X,
         "ABS_MT_POSITION_Y": ABS_MT_POSITION_Y, "ABS_MT_TRACKING_ID": ABS_MT_TRACKING_ID,
         "ABS_MT_PRESSURE": ABS_MT_PRESSURE,
         # the other multi-touch codes (Linux input-event-codes.h), which frictex does not read:
         # named, they are no typo of the ones it does (warned of; see read_log)
         "ABS_MT_TOUCH_MINOR": 0x31, "ABS_MT_WIDTH_MAJOR": 0x32, "ABS_MT_WIDTH_MINOR": 0x33,
         "ABS_MT_ORIENTATION": 0x34, "ABS_MT_TOOL_TYPE": 0x37, "ABS_MT_BLOB_ID": 0x38,
         "ABS_MT_DISTANCE": 0x3B, "ABS_MT_TOOL_X": 0x3C, "ABS_MT_TOOL_Y": 0x3D}
VALUES = {"UP": 0, "DOWN": 1, "REPEAT": 2}

_LINE = re.compile(r"^\s*\[\s*(?P<t>\d{1,12}\.\d{1,9})\s*\]\s+(?:(?P<dev>/\S+):\s+)?"
                   r"(?P<type>\S+)\s+(?P<code>\S+)\s+(?P<value>\S+)(?:\s+rate\s+\d{1,9})?\s*$",
                   re.ASCII)
_UNTIMED = re.compile(r"^\s*(?:/\S+:\s+)?(EV_[A-Z_]+|[0-9a-f]{4})\s+\S+\s+\S+\s*$", re.ASCII)
_ABSINFO = re.compile(r"^\s*(?:ABS \(0003\):\s*)?(?P<code>\S+)\s*:\s*value -?\d+, min "
                      r"(?P<min>-?\d{1,10}), max (?P<max>-?\d{1,10}), fuzz -?\d+, flat -?\d+"
                      r"(?:, resolution (?P<res>-?\d{1,10}))?\s*$", re.ASCII)
_ADD_DEVICE = re.compile(r"^add device \d+:\s*(?P<dev>\S+)", re.ASCII)
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
    """What a ``getevent`` log holds: its events (times in s, ``line`` 1-based), the
    warnings to show (a last line cut short, left out), and the axes its ``-p`` section
    states for the device of the events (keyed by code; empty without one)."""

    events: list[Event]
    warnings: list[str]
    absinfo: dict[int, AbsInfo]


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

    A last line without a line break (a recording stopped mid-line with Ctrl-C) is left
    out with a warning unless its value is whole (8 hex digits, or a name): cut within its
    value it could still read as one ('00000273' cut to '0000027'); a file merely saved
    without its last line break keeps its last event.
    """
    events: list[Event] = []
    devices: dict[str, int] = {}
    warnings: list[str] = []
    last: dict[str, float] = {}  # device -> time of its last event (s)
    unknown_mt: dict[str, int] = {}  # unknown ABS_MT_* name -> its first line
    axes: dict[str, dict[int, AbsInfo]] = {}  # -p section of each device: code -> axis
    section: str | None = None  # the device whose -p section is being read
    lines = text.splitlines()
    for number, raw in enumerate(lines, start=1):
        stripped = raw.strip()
        added = _ADD_DEVICE.match(stripped)
        if added:
            section = added["dev"]
            axes.setdefault(section, {})
        if not stripped or stripped.startswith(_HEADER):
            continue
        m = _LINE.match(raw)
        if m is None and section is not None and not _UNTIMED.match(raw):
            _read_absinfo(stripped, axes[section])
            continue
        section = None if m else section
        # a last line without its line break may be cut anywhere, even within a value of
        # the grammar's shape ('00000273' cut to '0000027' reads 0x27): an event only with
        # its whole value (getevent's 8 hex digits, or DOWN / UP / REPEAT)
        if (number == len(lines) and not text.endswith(("\n", "\r"))
                and (m is None or not _whole_value(m["value"]))):
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
        events.append(_event(m, where, number, last.get(dev, -math.inf)))
        last[dev] = events[-1].t_s
        if m["code"].startswith("ABS_MT_") and m["code"] not in CODES:
            unknown_mt.setdefault(m["code"], number)
    warnings += [f"{where}:{first}: {quoted(name)} is no multi-touch code Linux names (a "
                 "typo?): its events are left out" for name, first in unknown_mt.items()]
    named = sorted(d for d in devices if d)
    if device is not None and device not in devices:
        raise TraceError(f"{where}: no events of device {quoted(device)} "
                         f"(the log has {_names(named) or 'no device names'})")
    if device is None and len(devices) > 1:
        raise TraceError(f"{where}: events of {len(devices)} devices ({_names(named)}); "
                         "choose one with --device")
    return GeteventLog(events, warnings, _device_axes(axes, device or next(iter(devices), "")))


def _whole_value(token: str) -> bool:
    """Whether an event's value token is as getevent writes it whole."""
    return token in VALUES or (len(token) == 8 and _HEX8.match(token) is not None)


def _event(m: re.Match, where: str, number: int, last: float) -> Event:
    """The event of log line ``number`` (``m``: its match of the line grammar; ``last``:
    the time of its device's previous event, s); a TraceError for a type, code, value or
    time that is not one."""
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
    return Event(event_time(m["t"], last, f"{where}:{number}"), etype, code, value, number)


def event_time(token: str, last: float, at: str) -> float:
    """The time (s) of the event at ``at`` (file:line) from its ``seconds.micros`` token;
    TraceError past MAX_TIME_S or before ``last`` (s; the time of the device's previous
    event: the kernel stamps a device's events in the order it sends them)."""
    t = float(token)
    if t > MAX_TIME_S:
        raise TraceError(f"{at}: event time {t:g} s is more than {MAX_TIME_S:g} s "
                         "(evdev clocks count from boot or from 1970)")
    if t < last:
        raise TraceError(f"{at}: time goes back from {last!r} to {t!r} s (events must be in "
                         "the order the kernel sent them)")
    return t


def _read_absinfo(line: str, axes: dict[int, AbsInfo]) -> None:
    """Add the axis of a ``-p`` section line to ``axes`` (code -> AbsInfo) when it states
    one of the codes frictex uses; other section lines say nothing frictex needs."""
    m = _ABSINFO.match(line)
    if m is None:
        return
    code = CODES.get(m["code"], int(m["code"], 16) if _HEX4.match(m["code"]) else -1)
    if code >= 0:
        axes[code] = AbsInfo(int(m["min"]), int(m["max"]), int(m["res"] or 0))


def _device_axes(axes: dict[str, dict[int, AbsInfo]], device: str) -> dict[int, AbsInfo]:
    """The axes the ``-p`` section states for ``device`` (the events' device; "" when the
    events name none: then the one section with a position axis, if there is one)."""
    if device:
        return axes.get(device, {})
    touch = [a for a in axes.values() if ABS_MT_POSITION_X in a]
    return touch[0] if len(touch) == 1 else {}


def _names(devices: list[str], shown: int = 8) -> str:
    """The first ``shown`` device names, escaped, for an error."""
    more = f" and {len(devices) - shown} more" if len(devices) > shown else ""
    return ", ".join(quoted(d, 40) for d in devices[:shown]) + more


def read_getevent(path: str | Path, device: str | None = None) -> list[Event]:
    """Read a ``getevent -lt`` log file (see :func:`parse_getevent`)."""
    return parse_getevent(read_text(path, "getevent log"), str(path), device)
