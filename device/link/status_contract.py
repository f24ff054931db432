"""What an output device's ``status()`` must hold for the engine and the demo to read it
(``device.link.devices.OutputDevice.status``): a dict with ``commanded_samples`` and
``unplayed_samples`` (counts: ints, 0 or more; no more unplayed than commanded), and
where present ``unplayed_by_cause`` (cause -> count) and the counts of
:data:`OPTIONAL_COUNTS`; every value one JSON can hold (it goes into ``summary.json``).
"""

from __future__ import annotations

import json

#: the counts of an output device's status read where they are there, beside
#: ``commanded_samples`` and ``unplayed_samples``
OPTIONAL_COUNTS = ("clamped_samples", "underruns")


def status_problem(status) -> str | None:
    """What keeps ``status`` from being read, said as what it is: not a dict;
    ``commanded_samples`` or ``unplayed_samples`` missing or not a count, more unplayed
    than commanded; an ``unplayed_by_cause`` that is not a dict of counts; a count of
    :data:`OPTIONAL_COUNTS` that is not one; a value JSON cannot hold. None when it can
    be read."""
    if not isinstance(status, dict):
        return f"a {type(status).__name__}, not a dict,"
    for key in ("commanded_samples", "unplayed_samples"):
        if key not in status:
            return f"a dict without {key!r}"
    for key in ("commanded_samples", "unplayed_samples", *OPTIONAL_COUNTS):
        if key in status and not _is_count(status[key]):
            return f"{key} {status[key]!r}, not a count (an int, 0 or more),"
    if status["unplayed_samples"] > status["commanded_samples"]:
        return (f"unplayed_samples {status['unplayed_samples']} over commanded_samples "
                f"{status['commanded_samples']}")
    causes = status.get("unplayed_by_cause", {})
    if not (isinstance(causes, dict) and all(_is_count(n) for n in causes.values())):
        return f"unplayed_by_cause {causes!r}, not a dict of cause -> count,"
    try:
        json.dumps(status, allow_nan=False)
    except (TypeError, ValueError) as exc:
        return f"a value JSON cannot hold ({exc})"
    return None


def _is_count(value) -> bool:
    """An int (not a bool) of 0 or more."""
    return isinstance(value, int) and not isinstance(value, bool) and value >= 0
