"""evemu recordings (``evemu-record``) to evdev events and axis ranges.

Grammar (the header describes the device, then one event per line)::

    line    := comment | header | event | blank
    comment := "#" anything                       # also after an event: "E: ... # EV_ABS / ..."
    header  := "N:" name | "I:" ids | "P:" props | "B:" bits | "L:" leds | "S:" sw
             | "A:" code min max fuzz flat [resolution]   # code in hex; resolution in units/mm
    event   := "E:" seconds "." micros type code value   # type, code: hex; value: decimal, signed

The ``A:`` lines give the counts range (and, when the resolution is not 0, the size in
mm) of each axis; the importer uses them unless the user overrides them.
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field

from frictex.rendering.input.evdev_decode import AbsInfo, Event, signed32
from frictex.rendering.input.trace_file import TraceError

# values are the kernel's __s32 (at most 10 digits); times whole seconds and microseconds
_EVENT = re.compile(r"^E:\s+(?P<t>\d{1,12}\.\d{1,9})\s+(?P<type>[0-9a-fA-F]{1,4})\s+"
                    r"(?P<code>[0-9a-fA-F]{1,4})\s+(?P<value>-?\d{1,10})\s*(?:#.*)?$")
_ABS = re.compile(r"^A:\s+(?P<code>[0-9a-fA-F]{1,2})\s+(?P<nums>-?\d{1,10}(?:\s+-?\d{1,10}){3,4})"
                  r"\s*(?:#.*)?$")
_HEADER_TAGS = ("N:", "I:", "P:", "B:", "L:", "S:")


@dataclass(frozen=True)
class EvemuRecording:
    """events : in file order, times in s. absinfo : axis code -> range. name : device name."""

    events: list[Event]
    absinfo: dict[int, AbsInfo] = field(default_factory=dict)
    name: str = ""


def parse_evemu(text: str, where: str = "<evemu>") -> EvemuRecording:
    """Parse an evemu recording (see the module docstring for the grammar)."""
    events: list[Event] = []
    absinfo: dict[int, AbsInfo] = {}
    name = ""
    for number, raw in enumerate(text.splitlines(), start=1):
        line = raw.strip()
        if not line or line.startswith("#"):
            continue
        if line.startswith("E:"):
            m = _EVENT.match(line)
            if m is None:
                raise TraceError(f"{where}:{number}: {line[:60]!r} is not an evemu event "
                                 "(expected 'E: seconds.micros TYPE CODE VALUE', type and code in hex)")
            events.append(Event(float(m["t"]), int(m["type"], 16), int(m["code"], 16),
                                signed32(int(m["value"])), number))
        elif line.startswith("A:"):
            m = _ABS.match(line)
            if m is None:
                raise TraceError(f"{where}:{number}: {line[:60]!r} is not an evemu axis line "
                                 "(expected 'A: CODE MIN MAX FUZZ FLAT [RESOLUTION]')")
            nums = [signed32(int(v)) for v in m["nums"].split()]
            absinfo[int(m["code"], 16)] = AbsInfo(nums[0], nums[1], nums[4] if len(nums) > 4 else 0)
        elif line.startswith("N:"):
            name = line[2:].strip()
        elif not line.startswith(_HEADER_TAGS):
            raise TraceError(f"{where}:{number}: {line[:60]!r} is not an evemu line "
                             "(expected '# comment', 'N:', 'I:', 'P:', 'B:', 'A:', 'L:', 'S:' or 'E:')")
    return EvemuRecording(events, absinfo, name)
