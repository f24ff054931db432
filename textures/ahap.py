"""Clips from Apple Haptic and Audio Pattern (AHAP) files: JSON in, ``textures.clips.Clip`` out.

What is read (every other key is ignored; times in s; the keys of an object are
distinct and numbers finite: a repeated key or NaN/Infinity is an error)::

    {"Version": 1.0,
     "Pattern": [
       {"Event": {"Time": 0.0, "EventType": "HapticTransient" | "HapticContinuous",
                  "EventDuration": 0.5,            # HapticContinuous only, > 0
                  "EventParameters": [{"ParameterID": "HapticIntensity", "ParameterValue": 0.8},
                                      ... "HapticSharpness" (0-1), "AttackTime",
                                      "DecayTime", "ReleaseTime" (>= 0 s), "Sustained" (0/1)]}},
       {"ParameterCurve": {"ParameterID": "HapticIntensityControl" | "HapticSharpnessControl",
                           "Time": 0.0,
                           "ParameterCurveControlPoints": [{"Time": 0.0, "ParameterValue": 1.0}, ...]}},
       {"Parameter": {"ParameterID": ..., "Time": 0.0, "ParameterValue": 0.5}}]}

Mapping onto a friction display (``textures.clips`` says how a clip plays):

- intensity (0-1) is the share of the clip's ``depth`` (the largest drop in mu');
- sharpness (0-1) is spectral content: a transient's pulse shortens from 30 ms to 5 ms,
  a continuous event's carrier rises from none (a smooth drop) to 250 Hz;
- a continuous event's envelope: a linear attack over AttackTime from 0 to full, then
  full to the end (Sustained, the default) or a linear decay to 0 over DecayTime (not
  Sustained), and in either case a linear release to 0 over the last ReleaseTime;
- every event ends by MAX_CLIP_S (60 s), a transient's end being its start plus its pulse;
- HapticIntensityControl (0-1) multiplies every event's intensity, HapticSharpnessControl
  (-1 to 1) is added to every event's sharpness (Apple's dynamic parameters: a product for
  intensity, a sum otherwise). Each ParameterCurve or Parameter of a control takes effect
  at its Time and holds until the next one of that control begins, which takes over with a
  step: a curve is held at its first point's value from its Time to that point, linear
  between its points and held at its last, a Parameter is held at its value. Before the
  first of a control, the control is neutral (x1, +0): a control changes nothing before
  its Time, even one after every event has ended.

Audio events and other parameters have no friction meaning: they are skipped and listed
in the returned notes. Every problem is reported with its place in the file, e.g.
``clip.ahap: Pattern[2].Event.EventParameters[0]: HapticIntensity is 1.5, expected 0 to 1``.
"""

from __future__ import annotations

import json
import math
from pathlib import Path

import numpy as np

from frictex.device.safe_text import escape, escape_path, quoted
from frictex.textures.clips import MAX_CLIP_S, Clip, ClipEvent
from frictex.textures.errors import TextureError
from frictex.textures.library import UnreadableText, read_utf8

MAX_AHAP_BYTES = 1 << 20
MAX_ITEMS = 10_000  # pattern entries, curve points
#: the events of one clip play for at most this long in total (s): a clip is computed
#: sample by sample over each event, once, when the scene is built
MAX_EVENTS_S = 10 * MAX_CLIP_S

_EVENT_PARAMS = {  # id: (lowest, highest)
    "HapticIntensity": (0.0, 1.0), "HapticSharpness": (0.0, 1.0), "AttackTime": (0.0, MAX_CLIP_S),
    "DecayTime": (0.0, MAX_CLIP_S), "ReleaseTime": (0.0, MAX_CLIP_S), "Sustained": (0.0, 1.0)}
_CONTROLS = {"HapticIntensityControl": (0.0, 1.0), "HapticSharpnessControl": (-1.0, 1.0)}


#: a key the JSON object does not have (``obj.get(key, MISSING)``), told from null
MISSING = object()


def _json_kind(v) -> str:
    """What parsed JSON value ``v`` is, in JSON's words: "an object", "an array", "a
    string", "a number", "true", "false" or "null"."""
    if isinstance(v, bool):
        return json.dumps(v)
    kinds = ((dict, "an object"), (list, "an array"), (str, "a string"), ((int, float), "a number"))
    return next((word for kind, word in kinds if isinstance(v, kind)), "null")


def _expected(wanted: str, v) -> str:
    """The problem with ``v`` where ``wanted`` (an object, an array) belongs."""
    return "missing" if v is MISSING else f"expected {wanted}, got {_json_kind(v)}"


class _Reader:
    """Typed access to parsed JSON with the path of each value for messages."""

    def __init__(self, where: str):
        self.where = where

    def fail(self, path: str, message: str):
        raise TextureError(f"{self.where}: {path}: {message}")

    def number(self, obj: dict, key: str, path: str, lo: float, hi: float,
               default: float | None = None) -> float:
        if key not in obj:
            if default is None:
                self.fail(path, f"missing {key}")
            return default
        v = obj[key]
        if isinstance(v, bool) or not isinstance(v, (int, float)) or not _finite(v):
            self.fail(path, f"{key} is {json.dumps(v)[:40]}, expected a number from {lo:g} to {hi:g}")
        if not lo <= v <= hi:
            self.fail(path, f"{key} is {v:g}, expected {lo:g} to {hi:g}")
        return float(v)

    def name(self, obj: dict, key: str, path: str):
        """``obj[key]`` if it is a string or absent (None); anything else fails."""
        v = obj.get(key)
        if v is not None and not isinstance(v, str):
            self.fail(path, f"{key} is {json.dumps(v)[:40]}, expected a string")
        return v

    def table(self, v, path: str) -> dict:
        """``v`` if it is a JSON object; ``MISSING`` or anything else fails."""
        if not isinstance(v, dict):
            self.fail(path, _expected("an object", v))
        return v

    def array(self, v, path: str) -> list:
        """``v`` if it is a JSON array of at most MAX_ITEMS; ``MISSING`` or anything
        else fails."""
        if not isinstance(v, list):
            self.fail(path, _expected("an array", v))
        if len(v) > MAX_ITEMS:
            self.fail(path, f"{len(v)} entries, at most {MAX_ITEMS} are read")
        return v


def _finite(v: int | float) -> bool:
    try:
        return math.isfinite(v)
    except OverflowError:  # an integer too big for a float
        return False


def _envelope(params: dict, duration: float) -> tuple[tuple[float, float], ...]:
    """(t s from the event's start, level 0-1) breakpoints of a continuous event of
    ``duration`` s: the attack, then held or decaying, then the release (module docstring)."""
    attack = min(params.get("AttackTime", 0.0), duration)
    release = min(params.get("ReleaseTime", 0.0), duration - attack)
    points = [(0.0, 0.0 if attack > 0 else 1.0), (attack, 1.0)]
    if params.get("Sustained", 1.0) < 0.5:
        decay = params.get("DecayTime", 0.0)
        # the decay stops where the release begins; the line to (duration, 0) is the release
        end = min(attack + decay, duration - release)
        points.append((end, max(0.0, 1.0 - (end - attack) / decay) if decay > 0 else 0.0))
        points.append((duration, 0.0))
    else:
        points += [(duration - release, 1.0), (duration, 0.0 if release > 0 else 1.0)]
    return tuple(points)


def _event(r: _Reader, ev: dict, path: str, notes: list) -> ClipEvent | None:
    kind = ev.get("EventType")
    if kind not in ("HapticTransient", "HapticContinuous"):
        if isinstance(kind, str) and kind.startswith("Audio"):
            notes.append(f"{path}: {kind} skipped (no friction meaning)")
            return None
        r.fail(path, f"EventType is {json.dumps(kind)[:40]}, expected HapticTransient or "
                     f"HapticContinuous")
    time_s = r.number(ev, "Time", path, 0.0, MAX_CLIP_S)
    params = {}
    plist = r.array(ev.get("EventParameters", []), f"{path}.EventParameters")
    for k, p in enumerate(plist):
        ppath = f"{path}.EventParameters[{k}]"
        p = r.table(p, ppath)
        pid = r.name(p, "ParameterID", ppath)
        if pid not in _EVENT_PARAMS:
            notes.append(f"{ppath}: parameter {pid!r} skipped")
            continue
        lo, hi = _EVENT_PARAMS[pid]
        value = p.get("ParameterValue")
        if pid == "Sustained" and isinstance(value, bool):
            value = float(value)
        params[pid] = r.number({pid: value}, pid, ppath, lo, hi)
    intensity = params.get("HapticIntensity", 1.0)
    sharpness = params.get("HapticSharpness", 0.5)
    if kind == "HapticTransient":
        return ClipEvent("transient", time_s, intensity, sharpness)
    duration = r.number(ev, "EventDuration", path, 1e-6, MAX_CLIP_S)
    return ClipEvent("continuous", time_s, intensity, sharpness, duration,
                     _envelope(params, duration))


def _control_points(r: _Reader, entry: dict, key: str, path: str, notes: list):
    """(control id, (start s, [(t, value), ...])) of a ParameterCurve or Parameter, or None
    if skipped."""
    pid = r.name(entry, "ParameterID", path)
    if pid not in _CONTROLS:
        notes.append(f"{path}: {key} {pid!r} skipped")
        return None
    lo, hi = _CONTROLS[pid]
    t0 = r.number(entry, "Time", path, 0.0, MAX_CLIP_S)
    if key == "Parameter":
        return pid, (t0, [(t0, r.number(entry, "ParameterValue", path, lo, hi))])
    points = []
    cpath = f"{path}.ParameterCurveControlPoints"
    for k, p in enumerate(r.array(entry.get("ParameterCurveControlPoints", MISSING), cpath)):
        ppath = f"{cpath}[{k}]"
        p = r.table(p, ppath)
        t = t0 + r.number(p, "Time", ppath, 0.0, MAX_CLIP_S)
        if points and t < points[-1][0]:
            r.fail(ppath, f"Time goes back ({t - t0:g} s after {points[-1][0] - t0:g} s)")
        points.append((t, r.number(p, "ParameterValue", ppath, lo, hi)))
    if not points:
        r.fail(cpath, "no control points")
    return pid, (t0, points)


def _control_curve(entries: list) -> tuple[tuple[float, float], ...]:
    """One control's (t, value) points from its entries (start s, points), each holding
    from its start until the next entry's (a later one takes over; at equal starts the
    later in the file): a curve held at its first value from its start and at its last to
    the next start, or cut there; a step between entries (two points at one time)."""
    entries = sorted(entries, key=lambda entry: entry[0])
    out = []
    for j, (start, points) in enumerate(entries):
        end = entries[j + 1][0] if j + 1 < len(entries) else math.inf
        points = [(start, points[0][1])] + points if points[0][0] > start else points
        kept = [p for p in points if p[0] < end]
        if not kept:  # taken over where it starts
            continue
        if end < math.inf:
            ts, vs = zip(*points)
            kept.append((end, float(np.interp(end, ts, vs))))
        out += kept
    return tuple(out)


class _NotStrict(ValueError):
    """JSON that parses but that AHAP (RFC 8259's interoperable JSON) does not allow."""


def _unique_keys(pairs: list[tuple[str, object]]) -> dict:
    """An object of distinct keys: ``json``'s hook (a second "Pattern" would otherwise
    silently replace the first)."""
    doc = dict(pairs)
    if len(doc) != len(pairs):
        seen: set[str] = set()
        twice = next(k for k, _ in pairs if k in seen or seen.add(k))
        raise _NotStrict(f"key {quoted(twice)} appears twice in one object; expected "
                         "distinct keys")
    return doc


def _no_constant(word: str):
    """``json``'s hook for NaN, Infinity and -Infinity: not JSON numbers."""
    raise _NotStrict(f"{word} is not a JSON number; expected finite numbers")


def parse_ahap(text: str, depth: float, where: str = "AHAP") -> tuple[Clip, list[str]]:
    """A clip (and notes on what was skipped) from AHAP JSON text; ``depth`` is the
    drop in mu' at full intensity, in (0, 1). Raises TextureError (one line) on any
    problem."""
    r = _Reader(where)
    try:
        doc = json.loads(text, object_pairs_hook=_unique_keys, parse_constant=_no_constant)
    except _NotStrict as exc:
        raise TextureError(f"{where}: {exc}") from None
    except json.JSONDecodeError as exc:
        raise TextureError(f"{where}:{exc.lineno}: not JSON ({exc.msg})") from None
    except RecursionError:
        raise TextureError(f"{where}: JSON nested too deeply") from None
    except ValueError as exc:  # an integer of more digits than Python converts
        raise TextureError(f"{where}: not JSON that can be read ({str(exc).split(';')[0]})") from None
    doc = r.table(doc, "top level")
    events, paths = [], []
    curves, notes = {"HapticIntensityControl": [], "HapticSharpnessControl": []}, []
    for k, item in enumerate(r.array(doc.get("Pattern", MISSING), "Pattern")):
        path = f"Pattern[{k}]"
        item = r.table(item, path)
        if "Event" in item:
            ev = _event(r, r.table(item["Event"], f"{path}.Event"), f"{path}.Event", notes)
            if ev is not None:
                events.append(ev)
                paths.append(f"{path}.Event")
            continue
        key = next((k2 for k2 in ("ParameterCurve", "Parameter") if k2 in item), None)
        if key is None:
            r.fail(path, f"expected Event, ParameterCurve or Parameter, got {escape(', '.join(sorted(item)[:3]))}")
        got = _control_points(r, r.table(item[key], f"{path}.{key}"), key, f"{path}.{key}", notes)
        if got is not None:
            curves[got[0]].append(got[1])
    if not events:
        r.fail("Pattern", "no haptic events")
    clip = Clip(tuple(events), depth, _control_curve(curves["HapticIntensityControl"]),
                _control_curve(curves["HapticSharpnessControl"]))
    # a transient's length depends on the sharpness curve, known only once all is read
    for ev, path in zip(events, paths):
        end = ev.time_s + clip.event_length_s(ev)
        if end > MAX_CLIP_S:
            r.fail(path, f"ends at {end:g} s; clips last at most {MAX_CLIP_S:g} s")
    playing = sum(clip.event_length_s(e) for e in events)
    if playing > MAX_EVENTS_S:
        r.fail("Pattern", f"the events play for {playing:g} s in total; a clip's events "
                          f"play for at most {MAX_EVENTS_S:g} s")
    return clip, notes


def read_ahap(path: str | Path, depth: float) -> tuple[Clip, list[str]]:
    """``parse_ahap`` on a file (a regular UTF-8 file of at most 1 MiB)."""
    try:
        text = read_utf8(path, MAX_AHAP_BYTES)
    except UnreadableText as exc:
        line = f":{exc.line}" if exc.line else ""
        raise TextureError(f"{escape_path(path)}{line}: {exc}") from None
    return parse_ahap(text, depth, escape_path(path))
