"""evemu recordings (``evemu-record``) to evdev events and axis ranges.

Grammar (the header describes the device, then one event per line)::

    line    := comment | header | event | blank
    comment := "#" anything                       # also after an event: "E: ... # EV_ABS / ..."
    header  := "N:" name | "I:" ids | "P:" props | "B:" bits | "L:" leds | "S:" sw
             | "A:" code min max fuzz flat [resolution]   # code in hex; resolution in units/mm
    event   := "E:" seconds "." micros type code value   # type, code: hex; value: decimal, signed

The ``A:`` lines give the counts range (and, when the resolution is not 0, the size in
mm) of each axis; the importer uses them unless the user overrides them.

Numbers are ASCII (``0-9``, ``a-f``): Python's ``int`` and ``re``'s ``\\d`` also take
Unicode digits. Each quantity is held to what a device can report: values, ranges and
resolutions are the kernel's ``__s32`` (-2^31 to 2^31 - 1, never wrapped), a resolution
is 0 (unknown) to MAX_RESOLUTION units per mm, a time at most MAX_TIME_S and not before
the previous event's (the kernel stamps a device's events in order). The screen
size the resolution implies is checked where it is used (``evdev_decode.screen_map``).
A line that is not of the grammar is described, never printed.
"""

from __future__ import annotations

import math
import re
from dataclasses import dataclass, field

from frictex.rendering.input.evdev_decode import MAX_RESOLUTION, AbsInfo, Event
from frictex.rendering.input.import_getevent import event_time
from frictex.rendering.input.trace_file import TraceError

# values are the kernel's __s32 (at most 10 digits); times whole seconds and microseconds
_EVENT = re.compile(r"^E:\s+(?P<t>\d{1,12}\.\d{1,9})\s+(?P<type>[0-9a-fA-F]{1,4})\s+"
                    r"(?P<code>[0-9a-fA-F]{1,4})\s+(?P<value>-?\d{1,10})\s*(?:#.*)?$", re.ASCII)
_ABS = re.compile(r"^A:\s+(?P<code>[0-9a-fA-F]{1,2})\s+(?P<nums>-?\d{1,10}(?:\s+-?\d{1,10}){3,4})"
                  r"\s*(?:#.*)?$", re.ASCII)
_HEADER_TAGS = ("N:", "I:", "P:", "B:", "L:", "S:")
_S32 = (-(1 << 31), (1 << 31) - 1)
_ABS_FIELDS = ("minimum", "maximum", "fuzz", "flat", "resolution")


def _s32(text: str, what: str, where: str) -> int:
    """A decimal field as the kernel's ``__s32``; TraceError outside its range."""
    value = int(text)
    if not _S32[0] <= value <= _S32[1]:
        raise TraceError(f"{where}: {what} {value} is outside a 32-bit signed value "
                         f"({_S32[0]} to {_S32[1]}), which evdev values are")
    return value


@dataclass(frozen=True)
class EvemuRecording:
    """events : in file order, times in s. absinfo : axis code -> range. name : device name.
    warnings : what to show (a last line cut short, left out)."""

    events: list[Event]
    absinfo: dict[int, AbsInfo] = field(default_factory=dict)
    name: str = ""
    warnings: list[str] = field(default_factory=list)


def parse_evemu(text: str, where: str = "<evemu>") -> EvemuRecording:
    """Parse an evemu recording (see the module docstring for the grammar)."""
    events: list[Event] = []
    absinfo: dict[int, AbsInfo] = {}
    name = ""
    warnings: list[str] = []
    lines = text.splitlines()
    for number, raw in enumerate(lines, start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        at = f"{where}:{number}"
        if line.startswith("E:"):
            m = _EVENT.match(line)
            # an event cut within its value ('1548' cut to '15') still reads as one: a last
            # line without its line break is an event only where evemu-record's comment
            # after the value shows the value whole
            if (number == len(lines) and not text.endswith(("\n", "\r"))
                    and (m is None or "#" not in line[m.end("value"):])):
                warnings.append(f"{at}: the last line is cut short (no line break; the "
                                "recording stopped mid-line): left out")
                break
            if m is None:
                raise TraceError(f"{at}: an 'E:' line that is not an evemu event (expected "
                                 "'E: seconds.micros TYPE CODE VALUE': ASCII digits, type and "
                                 "code in hex, a decimal value)")
            t = event_time(m["t"], events[-1].t_s if events else -math.inf, at)
            events.append(Event(t, int(m["type"], 16), int(m["code"], 16),
                                _s32(m["value"], "value", at), number))
        elif line.startswith("A:"):
            m = _ABS.match(line)
            if m is None:
                raise TraceError(f"{at}: an 'A:' line that is not an evemu axis (expected "
                                 "'A: CODE MIN MAX FUZZ FLAT [RESOLUTION]': code in hex, the "
                                 "rest ASCII decimal)")
            nums = [_s32(v, what, at) for v, what in zip(m["nums"].split(), _ABS_FIELDS)]
            resolution = nums[4] if len(nums) > 4 else 0
            if not 0 <= resolution <= MAX_RESOLUTION:
                raise TraceError(f"{at}: axis {m['code']} resolution {resolution} units/mm: "
                                 f"expected 0 (unknown) to {MAX_RESOLUTION} units/mm")
            absinfo[int(m["code"], 16)] = AbsInfo(nums[0], nums[1], resolution)
        elif line.startswith("N:"):
            name = line[2:].strip()
        elif not line.startswith(_HEADER_TAGS):
            raise TraceError(f"{at}: not an evemu line (expected '# comment', 'N:', 'I:', 'P:', "
                             "'B:', 'A:', 'L:', 'S:' or 'E:' at its start)")
    return EvemuRecording(events, absinfo, name, warnings)
