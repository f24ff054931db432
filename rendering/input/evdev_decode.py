"""Linux evdev multi-touch events to touch samples, and device units to screen mm.

Input: a stream of evdev events ``(t_s, type, code, value)`` in the order the kernel
sent them (from a recording or a live device). Output: :class:`RawSample` per contact
per frame, in device units, with ``down`` / ``move`` / ``up`` events and stable finger
ids (the smallest integer >= 0 not held by another contact; reused after a lift).

Grammar of the stream (Linux ``Documentation/input/multi-touch-protocol.rst``)::

    stream   := { frame } [ partial ]
    frame    := { event } SYN_REPORT          # time of the frame = time of its SYN_REPORT
    protocol A: frame := { contact } SYN_REPORT
                contact := { ABS_MT_* } SYN_MT_REPORT   # full state of every contact, every frame;
                an empty frame (lone SYN_MT_REPORT, or BTN_TOUCH 0) lifts every contact
    protocol B: frame := { ABS_MT_SLOT n | ABS_MT_TRACKING_ID id | ABS_MT_* } SYN_REPORT
                slots keep their values; only changed axes are sent; TRACKING_ID -1 lifts

The protocol is recognised from the stream itself: a frame holding SYN_MT_REPORT is
protocol A, a frame with ABS_MT_SLOT, or with MT axes but no SYN_MT_REPORT, is protocol B.
A stream that mixes them is an error. Protocol A contacts carrying ABS_MT_TRACKING_ID are
matched by it; contacts without one are matched to the previous frame's contacts by least
total distance (matching by order would swap two fingers when the first one lifts).

Samples are never invented or merged: every contact reported in a protocol A frame gives a
sample, including a finger re-reported unmoved 0.6 ms after another one moved (refdata
phone-two-finger-drag); smoothing that is the tracker's job (``rendering/tracking/tracks.py``).
A protocol B slot gives a sample in each frame where one of its values changed.
SYN_DROPPED (the kernel's buffer overran) is counted and discards events up to the next
SYN_REPORT, but for protocol B only until an ABS_MT_SLOT: the lost events may have moved to
another slot, and the kernel sends ABS_MT_SLOT only when the slot changes, so events before it
are of an unknown slot; from it on they are that slot's changes and are kept (libevdev
re-reads every slot after a drop; a recording cannot, and changes lost with the dropped events
stay lost). Without an ABS_MT_SLOT after the drop the decoder keeps the slot it had.
Contacts without a known position are not emitted and are counted.
A protocol A frame that lifts everything may be among the events a drop lost, and a
screen that reuses one tracking id for every tap (Samsung's 0) would then carry the next
tap on as the same touch: the first frame after a drop that comes more than
:data:`LIFT_LOST_S` after the last frame with contacts lifts those contacts where they
were last seen (the one place a sample is inferred; counted in ``lifts_lost``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, NamedTuple

import numpy as np
from scipy.optimize import linear_sum_assignment

from frictex.rendering.input.trace_file import DEFAULT_FORCE_N, DOWN, MOVE, UP, Trace, TraceError, make_trace
from frictex.textures.library import UnreadableText, read_utf8

EV_SYN, EV_KEY, EV_ABS = 0x00, 0x01, 0x03
SYN_REPORT, SYN_MT_REPORT, SYN_DROPPED = 0x00, 0x02, 0x03
BTN_TOUCH = 0x14A
ABS_MT_SLOT = 0x2F
ABS_MT_TOUCH_MAJOR = 0x30
ABS_MT_POSITION_X = 0x35
ABS_MT_POSITION_Y = 0x36
ABS_MT_TRACKING_ID = 0x39
ABS_MT_PRESSURE = 0x3A
#: MT axes a contact's state is made of (what makes a protocol B frame recognisable)
MT_AXES = (ABS_MT_TOUCH_MAJOR, ABS_MT_POSITION_X, ABS_MT_POSITION_Y, ABS_MT_TRACKING_ID,
           ABS_MT_PRESSURE)
#: more simultaneous contacts (protocol B slots) than any touch screen reports
MAX_CONTACTS = 64
#: protocol A: silence (s) after a SYN_DROPPED past which the contacts of the last frame
#: are taken as lifted (a finger on the screen is reported at tens of Hz)
LIFT_LOST_S = 0.25
#: finest axis resolution believed (units per mm; 0.1 um a count): digitizers give 10 to 200
MAX_RESOLUTION = 10_000
#: screen sizes believed along an axis (mm): a watch's 20 mm to a 10 m interactive wall
SCREEN_MM = (1.0, 10_000.0)


class Event(NamedTuple):
    """One evdev event. ``line`` is where it came from (0: unknown), for error messages."""

    t_s: float
    type: int
    code: int
    value: int
    line: int = 0


class AbsInfo(NamedTuple):
    """An absolute axis as the kernel describes it (``struct input_absinfo``, evemu ``A:``).

    minimum, maximum : range of values (device units). resolution : units per mm (0: unknown).
    """

    minimum: int
    maximum: int
    resolution: int = 0


class RawSample(NamedTuple):
    """One contact in one frame, in device units (counts); ``nan`` where the device did not say."""

    t_s: float
    finger: int
    x: float
    y: float
    pressure: float
    touch_major: float
    event: int


class TouchSample(NamedTuple):
    """One contact in one frame on the screen: mm, N, s (what live sources hand the demo)."""

    t_s: float
    finger: int
    x_mm: float
    y_mm: float
    force_n: float
    event: int


def signed32(value: int) -> int:
    """A 32-bit field as the kernel's ``__s32`` (``ffffffff`` -> -1)."""
    value &= 0xFFFFFFFF
    return value - (1 << 32) if value & 0x80000000 else value


class _Contact:
    """Axis values of one contact (a protocol B slot, or a protocol A report)."""

    __slots__ = ("tracking_id", "x", "y", "pressure", "touch_major", "changed", "new")

    def __init__(self) -> None:
        self.tracking_id = -1
        self.x = self.y = self.pressure = self.touch_major = math.nan
        self.changed = False
        self.new = False

    def set_axis(self, code: int, value: int) -> None:
        if code == ABS_MT_POSITION_X:
            self.x = float(value)
        elif code == ABS_MT_POSITION_Y:
            self.y = float(value)
        elif code == ABS_MT_PRESSURE:
            self.pressure = float(value)
        elif code == ABS_MT_TOUCH_MAJOR:
            self.touch_major = float(value)
        self.changed = True

    @property
    def placed(self) -> bool:
        return not (math.isnan(self.x) or math.isnan(self.y))


class EvdevDecoder:
    """Incremental decoder: ``feed(events)`` returns the samples of the frames completed.

    Feeding a stream in any number of pieces gives the same samples as feeding it whole.
    Counters (read them after feeding): ``frames``, ``dropped`` (SYN_DROPPED),
    ``lifts_lost`` (protocol A contacts lifted across a drop: module docstring), ``unplaced``
    (contacts without X and Y, not emitted), ``untracked`` (protocol B frames with
    positions in a slot holding no ABS_MT_TRACKING_ID, not emitted). ``protocol`` is
    ``"A"``, ``"B"`` or None.

    Parameters
    ----------
    where : str
        Names the source in error messages (a file name).
    """

    def __init__(self, where: str = "<events>") -> None:
        self.where = where
        self.protocol: str | None = None
        self.frames = 0
        self.dropped = 0
        self.unplaced = 0
        self.untracked = 0
        self._frame: list[Event] = []
        self._skipping = False
        self._t_last = -math.inf
        self._slots: dict[int, _Contact] = {}
        self._slot = 0
        self._fingers: dict[object, int] = {}  # contact key -> finger id
        self._last: dict[object, _Contact] = {}  # protocol A: contacts of the previous frame
        self._last_t = -math.inf  # protocol A: time (s) of the previous frame with contacts
        self._dropped_since = False  # protocol A: a SYN_DROPPED since that frame
        self.lifts_lost = 0
        self._next_key = 0

    @property
    def pending(self) -> int:
        """Events buffered after the last SYN_REPORT (an incomplete frame)."""
        return len(self._frame)

    def _error(self, ev: Event, message: str) -> TraceError:
        at = f"{self.where}:{ev.line}" if ev.line else self.where
        return TraceError(f"{at}: {message}")

    def feed(self, events: Iterable[Event]) -> list[RawSample]:
        """Decode events; return the samples of every frame they complete, in time order."""
        out: list[RawSample] = []
        for ev in events:
            ev = Event(*ev)
            if ev.type == EV_SYN and ev.code == SYN_DROPPED:
                self.dropped += 1
                self._dropped_since = True
                self._frame.clear()
                self._skipping = True
            elif ev.type == EV_SYN and ev.code == SYN_REPORT:
                if not self._skipping:
                    self._end_frame(ev, out)
                self._frame.clear()
                self._skipping = False
            elif self._skipping and ev.type == EV_ABS and ev.code == ABS_MT_SLOT:
                self._frame.append(ev)  # the slot is known again (module docstring)
                self._skipping = False
            elif not self._skipping and ev.type in (EV_SYN, EV_KEY, EV_ABS):
                self._frame.append(ev)
        return out

    def _end_frame(self, syn: Event, out: list[RawSample]) -> None:
        if not math.isfinite(syn.t_s):
            raise self._error(syn, f"time {syn.t_s!r} s is not a finite number")
        if syn.t_s < self._t_last:
            raise self._error(syn, f"time goes back from {self._t_last!r} to {syn.t_s!r} s "
                                   "(events must be in the order the kernel sent them)")
        self._t_last = syn.t_s
        has_mt_report = any(e.type == EV_SYN and e.code == SYN_MT_REPORT for e in self._frame)
        has_slot = any(e.type == EV_ABS and e.code == ABS_MT_SLOT for e in self._frame)
        has_axes = any(e.type == EV_ABS and e.code in MT_AXES for e in self._frame)
        if has_mt_report and has_slot:
            raise self._error(syn, "frame mixes SYN_MT_REPORT (protocol A) and ABS_MT_SLOT "
                                   "(protocol B)")
        kind = "A" if has_mt_report else "B" if (has_slot or has_axes) else None
        if kind and self.protocol and kind != self.protocol:
            raise self._error(syn, f"frame uses multitouch protocol {kind} but the stream so far "
                                   f"used protocol {self.protocol}")
        self.protocol = self.protocol or kind
        self.frames += 1
        if self.protocol == "A":
            self._frame_a(syn, out)
        elif self.protocol == "B":
            self._frame_b(syn.t_s, out)

    # -- finger ids -------------------------------------------------------------------------
    def _finger(self, key: object) -> int:
        if key not in self._fingers:
            used = set(self._fingers.values())
            self._fingers[key] = next(i for i in range(len(used) + 1) if i not in used)
        return self._fingers[key]

    def _emit(self, out: list, t: float, key: object, c: _Contact, event: int) -> None:
        out.append(RawSample(t, self._finger(key), c.x, c.y, c.pressure, c.touch_major, event))
        if event == UP:
            del self._fingers[key]

    # -- protocol A ---------------------------------------------------------------------------
    def _reports_a(self) -> tuple[list[_Contact], bool]:
        """The contacts this protocol A frame reports, and whether it lifts every finger
        (an empty SYN_MT_REPORT or BTN_TOUCH 0)."""
        reports: list[_Contact] = []
        cur = _Contact()
        lift_all = False
        for ev in self._frame:
            if ev.type == EV_SYN and ev.code == SYN_MT_REPORT:
                lift_all |= not cur.changed
                if cur.changed:
                    reports.append(cur)
                cur = _Contact()
            elif ev.type == EV_ABS and ev.code == ABS_MT_TRACKING_ID:
                cur.tracking_id = ev.value
                cur.changed = True
            elif ev.type == EV_ABS and ev.code in MT_AXES:
                cur.set_axis(ev.code, ev.value)
            elif ev.type == EV_KEY and ev.code == BTN_TOUCH and ev.value == 0:
                lift_all = True
        if cur.changed:  # axes after the last SYN_MT_REPORT: a contact left unclosed
            reports.append(cur)
        return reports, lift_all

    def _frame_a(self, syn: Event, out: list[RawSample]) -> None:
        t = syn.t_s
        reports, lift_all = self._reports_a()
        placed = [c for c in reports if c.placed]
        self.unplaced += len(reports) - len(placed)
        if not placed and not lift_all:
            return  # a frame of other events (ABS_MISC, MSC_TIMESTAMP): contacts unchanged
        if len(placed) > MAX_CONTACTS:
            raise self._error(syn, f"frame at {t!r} s reports {len(placed)} contacts "
                                   f"(at most {MAX_CONTACTS} expected)")
        if self._dropped_since and t - self._last_t > LIFT_LOST_S:  # a lift lost (docstring)
            self.lifts_lost += len(self._last)
            for key, c in self._last.items():
                self._emit(out, self._last_t, key, c, UP)
            self._last = {}
        self._dropped_since = False
        current = self._match_a(syn, placed)
        for key, c in self._last.items():
            if key not in current:
                self._emit(out, t, key, c, UP)
        for key, c in current.items():
            self._emit(out, t, key, c, MOVE if key in self._last else DOWN)
        self._last = current
        self._last_t = t

    def _match_a(self, syn: Event, reports: list[_Contact]) -> dict[object, _Contact]:
        """Key every contact of this frame: by tracking id, or by least distance to the last frame."""
        current: dict[object, _Contact] = {}
        anonymous = []
        for c in reports:
            if c.tracking_id < 0:
                anonymous.append(c)
                continue
            key = ("id", c.tracking_id)
            if key in current:
                raise self._error(syn, f"frame at {syn.t_s!r} s reports tracking id "
                                       f"{c.tracking_id} twice (expected one report per contact)")
            current[key] = c
        previous = [k for k in self._last if k[0] == "anon"]
        if anonymous and previous:
            cost = np.array([[math.hypot(c.x - self._last[k].x, c.y - self._last[k].y)
                              for k in previous] for c in anonymous])
            rows, cols = linear_sum_assignment(cost)
            for r, col in zip(rows.tolist(), cols.tolist()):
                current[previous[col]] = anonymous[r]
            matched = set(rows.tolist())
            anonymous = [c for i, c in enumerate(anonymous) if i not in matched]
        for c in anonymous:
            current[("anon", self._next_key)] = c
            self._next_key += 1
        return current

    # -- protocol B ---------------------------------------------------------------------------
    def _frame_b(self, t: float, out: list[RawSample]) -> None:
        positioned = set()  # slots given a position in this frame
        for ev in self._frame:
            if ev.type != EV_ABS:
                continue
            if ev.code == ABS_MT_SLOT:
                if not 0 <= ev.value < MAX_CONTACTS:
                    raise self._error(ev, f"ABS_MT_SLOT {ev.value} is out of range "
                                          f"(expected 0..{MAX_CONTACTS - 1})")
                self._slot = ev.value
                continue
            if ev.code not in MT_AXES:
                continue
            slot = self._slots.setdefault(self._slot, _Contact())
            if ev.code == ABS_MT_TRACKING_ID:
                if slot.tracking_id >= 0 and ev.value != slot.tracking_id:
                    self._lift_slot(t, self._slot, slot, out)
                if ev.value >= 0 and ev.value != slot.tracking_id:
                    slot.tracking_id, slot.new, slot.changed = ev.value, True, True
            else:
                slot.set_axis(ev.code, ev.value)
                if ev.code in (ABS_MT_POSITION_X, ABS_MT_POSITION_Y):
                    positioned.add(self._slot)
        self.untracked += any(self._slots[n].tracking_id < 0 for n in positioned)
        for number, slot in sorted(self._slots.items()):
            if slot.tracking_id < 0 or not slot.changed:
                continue
            if not slot.placed:
                self.unplaced += 1
                continue
            self._emit(out, t, ("slot", number, slot.tracking_id), slot,
                       DOWN if slot.new else MOVE)
            slot.new = slot.changed = False

    def _lift_slot(self, t: float, number: int, slot: _Contact, out: list[RawSample]) -> None:
        key = ("slot", number, slot.tracking_id)
        if key in self._fingers:  # it was emitted; a contact never placed just vanishes
            self._emit(out, t, key, slot, UP)
        slot.tracking_id, slot.new, slot.changed = -1, False, False


def decode_all(events: Iterable[Event], where: str) -> tuple[list[RawSample], EvdevDecoder]:
    """Decode a whole recording; events after the last SYN_REPORT are left in ``pending``.
    A recording with no touch whose positions all came in slots with no tracking id raises
    TraceError saying so (a caller could only say it found no touches)."""
    decoder = EvdevDecoder(where)
    samples = decoder.feed(events)
    if not samples and decoder.untracked:
        raise TraceError(f"{where}: no touches found: positions in {decoder.untracked} "
                         f"frame{'s' if decoder.untracked != 1 else ''} came with no "
                         "ABS_MT_TRACKING_ID (protocol B contacts start with one)")
    return samples, decoder


@dataclass(frozen=True)
class AxisMap:
    """Device units ``lo..hi`` onto screen ``0..size_mm`` (reversed when ``flip``)."""

    lo: float
    hi: float
    size_mm: float
    flip: bool = False

    def __post_init__(self) -> None:
        if not (math.isfinite(self.lo) and math.isfinite(self.hi) and self.hi > self.lo):
            raise TraceError(f"axis range {self.lo!r}..{self.hi!r}: expected finite MIN < MAX")
        if not SCREEN_MM[0] <= self.size_mm <= SCREEN_MM[1]:  # NaN fails
            raise TraceError(f"screen size {self.size_mm:g} mm: expected {SCREEN_MM[0]:g} to "
                             f"{SCREEN_MM[1]:g} mm")

    def mm(self, value: np.ndarray) -> np.ndarray:
        """Position (mm) of device values; shape kept."""
        u = (np.asarray(value, dtype=np.float64) - self.lo) / (self.hi - self.lo)
        return (1.0 - u if self.flip else u) * self.size_mm


@dataclass(frozen=True)
class ScreenMap:
    """Device samples to screen samples.

    x, y : the screen axes; with ``swap_xy`` the screen x axis reads the device's y
        values (so ``x.lo..x.hi`` is then a range of device y).
    pressure_n : newtons per pressure unit; None: every sample gets ``force_n``.
    force_n : normal force (N) when pressure is not mapped.
    """

    x: AxisMap
    y: AxisMap
    swap_xy: bool = False
    pressure_n: float | None = None
    force_n: float = DEFAULT_FORCE_N

    def arrays(self, samples: list[RawSample], where: str = "samples") -> dict[str, np.ndarray]:
        """Columns of a trace: t_s, finger, x_mm, y_mm, force_n, event; each shape (n,)."""
        a = np.array([s[:5] for s in samples], dtype=np.float64).reshape(-1, 5)
        dev_x, dev_y = (a[:, 3], a[:, 2]) if self.swap_xy else (a[:, 2], a[:, 3])
        if self.pressure_n is None:
            force = np.full(len(samples), self.force_n)
        else:
            with np.errstate(over="ignore"):  # an inf force is refused by name below
                force = a[:, 4] * self.pressure_n
            if np.isnan(force).any():
                i = int(np.argmax(np.isnan(force)))
                raise TraceError(f"{where}: sample {i} at {a[i, 0]:g} s has no pressure, but a "
                                 "pressure scale was given (expected ABS_MT_PRESSURE on every contact)")
        return {"t_s": a[:, 0], "finger": a[:, 1].astype(np.int64), "x_mm": self.x.mm(dev_x),
                "y_mm": self.y.mm(dev_y), "force_n": force,
                "event": np.array([s.event for s in samples], dtype=np.int8)}

    def trace(self, samples: list[RawSample], where: str = "samples") -> Trace:
        """A validated :class:`Trace` of the samples (positions in mm, forces in N)."""
        return make_trace(where=where, **self.arrays(samples, where))

    def touches(self, samples: list[RawSample]) -> list[TouchSample]:
        """The samples on the screen, one :class:`TouchSample` each (for live sources)."""
        if not samples:
            return []
        cols = self.arrays(samples)
        return [TouchSample(*row) for row in zip(cols["t_s"].tolist(), cols["finger"].tolist(),
                                                 cols["x_mm"].tolist(), cols["y_mm"].tolist(),
                                                 cols["force_n"].tolist(), cols["event"].tolist())]


class RangeUnknown(TraceError):
    """A device axis range that is neither given, nor read from the device, nor observed."""


def _axis_map(axis: str, size_option: str, size_mm: float | None, flip: bool,
              given: tuple[float, float] | None, absinfo: AbsInfo | None,
              observed: tuple[float, float] | None, where: str,
              check_scale: bool = True) -> tuple[AxisMap, bool]:
    """The map of device axis ``axis`` (see :func:`screen_map`), and whether its range is
    the observed one; ``check_scale`` False: ``size_mm`` is no real size (a normalised
    map), so its units per mm are not checked."""
    guessed = False
    if given is not None:
        lo, hi = given
        if not hi > lo:
            raise TraceError(f"{where}: --{axis}-range {lo:g} {hi:g}: expected MIN < MAX "
                             "(device counts)")
    elif absinfo is not None and absinfo.maximum > absinfo.minimum:
        lo, hi = absinfo.minimum, absinfo.maximum
    elif observed is not None and observed[1] > observed[0]:
        (lo, hi), guessed = observed, True
    else:
        seen = f" (the recording only shows {axis} = {observed[0]:g})" if observed else ""
        raise RangeUnknown(f"{where}: device {axis} range unknown{seen}: give --{axis}-range MIN MAX")
    if size_mm is None:
        if absinfo is None or absinfo.resolution <= 0:
            raise TraceError(f"{where}: screen size along device {axis} unknown (the device "
                             f"gives no resolution): give {size_option}")
        size_mm = (hi - lo) / absinfo.resolution
        if not SCREEN_MM[0] <= size_mm <= SCREEN_MM[1]:
            raise TraceError(f"{where}: device {axis} counts {lo:g}..{hi:g} at its resolution of "
                             f"{absinfo.resolution} units/mm make a screen {size_mm:.3g} mm "
                             f"across; expected {SCREEN_MM[0]:g} to {SCREEN_MM[1]:g} mm (give "
                             f"{size_option})")
    try:
        axis_map = AxisMap(float(lo), float(hi), float(size_mm), flip)  # a size out of bounds
    except TraceError as exc:
        raise TraceError(f"{where}: {exc}") from None
    if check_scale:
        _check_scale(axis, lo, hi, size_mm, "the observed range" if guessed else
                     f"--{axis}-range" if given is not None else "the device's range", where)
    return axis_map, guessed


def _check_scale(axis: str, lo: float, hi: float, size_mm: float, source: str, where: str) -> None:
    """TraceError when device ``axis`` counts ``lo..hi`` (from ``source``) over ``size_mm``
    (mm) make more than MAX_RESOLUTION units/mm, a scale no digitizer has (a glitch count
    such as 0x7fffffff in the observed range, or a typo)."""
    per_mm = (hi - lo) / size_mm
    if per_mm > MAX_RESOLUTION:
        raise TraceError(f"{where}: device {axis} counts {lo:g}..{hi:g} ({source}) over "
                         f"{size_mm:g} mm are {per_mm:.3g} units/mm; no digitizer gives more "
                         f"than {MAX_RESOLUTION:,} (a glitch value or a typo?): give "
                         f"--{axis}-range MIN MAX")


@dataclass(frozen=True)
class ScreenSpec:
    """What the user says about a touch screen.

    width_mm, height_mm : screen size along its x (right) and y (down); None: from the
        device resolution. x_range, y_range : device X / Y counts spanning the screen (the
        device's own axes, before ``swap_xy``); None: from the device, else observed.
    swap_xy : device X runs along screen y. flip_x, flip_y : screen axes run against the device.
    pressure_n : N per pressure unit (None: constant ``force_n``, N).
    normalised : positions as fractions 0..1 of each axis range (``width_mm`` and
        ``height_mm`` are ignored, taken as 1), for a live source whose consumer maps
        them to its own screen; no units-per-mm plausibility check, which needs a real size.
    """

    width_mm: float | None = None
    height_mm: float | None = None
    x_range: tuple[float, float] | None = None
    y_range: tuple[float, float] | None = None
    swap_xy: bool = False
    flip_x: bool = False
    flip_y: bool = False
    pressure_n: float | None = None
    force_n: float = DEFAULT_FORCE_N
    normalised: bool = False


def screen_map(spec: ScreenSpec, absinfo: dict[int, AbsInfo],
               observed: dict[int, tuple[float, float]] | None = None,
               where: str = "touch screen") -> tuple[ScreenMap, list[str]]:
    """The device-to-screen map from what is known, best first, and the warnings to show.

    Each device axis range is the user's (``spec``), else the device's (``absinfo``, keyed
    by ABS_MT_POSITION_X / _Y), else the ``observed`` min..max of the recording with a
    warning; each size is the user's (1 for a ``normalised`` spec), else the range over the
    device resolution (units/mm), and must lie within SCREEN_MM. ``where`` (a file, a
    device) starts every error: :class:`RangeUnknown` for an axis with no range, else
    TraceError.

    An observed range is taken at one scale for both axes (device units per mm: the
    largest of the two axes'), from its smallest value: a stroke keeps its shape and its
    speed along both axes, where stretching each axis to the screen's edges would blow a
    drag's few units of sideways wobble up to the screen's height (3 units of a phone's
    y became 5.9 mm each). Touch screens' units are square to within a factor of about
    2; a range given or read from the device is kept as it is.
    """
    observed = observed or {}
    sw = spec.swap_xy
    width_mm, height_mm = (1.0, 1.0) if spec.normalised else (spec.width_mm, spec.height_mm)
    dev_x, guessed_x = _axis_map("x", "--height-mm" if sw else "--width-mm",
                          height_mm if sw else width_mm, spec.flip_y if sw else spec.flip_x,
                          spec.x_range, absinfo.get(ABS_MT_POSITION_X), observed.get(ABS_MT_POSITION_X),
                          where, not spec.normalised)
    dev_y, guessed_y = _axis_map("y", "--width-mm" if sw else "--height-mm",
                          width_mm if sw else height_mm, spec.flip_x if sw else spec.flip_y,
                          spec.y_range, absinfo.get(ABS_MT_POSITION_Y), observed.get(ABS_MT_POSITION_Y),
                          where, not spec.normalised)
    warnings = []
    if guessed_x or guessed_y:
        per_mm = max((m.hi - m.lo) / m.size_mm for m in (dev_x, dev_y))
        if guessed_x:
            dev_x, said = _observed_at_scale("x", dev_x, per_mm)
            warnings.append(said)
        if guessed_y:
            dev_y, said = _observed_at_scale("y", dev_y, per_mm)
            warnings.append(said)
    screen_x, screen_y = (dev_y, dev_x) if sw else (dev_x, dev_y)
    return ScreenMap(screen_x, screen_y, sw, spec.pressure_n, spec.force_n), warnings


def _observed_at_scale(axis: str, observed: AxisMap, per_mm: float) -> tuple[AxisMap, str]:
    """The map of an axis whose range was observed (``observed``: its min..max onto the
    screen) at ``per_mm`` device units per mm, and the warning that says so."""
    scaled = AxisMap(observed.lo, observed.lo + per_mm * observed.size_mm, observed.size_mm,
                     observed.flip)
    return scaled, (f"device {axis} range unknown: using the observed "
                    f"{observed.lo:g}..{observed.hi:g} at {per_mm:.4g} units/mm, one scale "
                    f"for both axes ({observed.lo:g}..{scaled.hi:.6g} across the screen): "
                    "positions and speeds are wrong unless the gesture covered the whole "
                    "screen, too large by the screen's size over the gesture's (5x for a "
                    "gesture over a fifth of it); record with 'getevent -lpt' (its -p section "
                    f"gives the ranges) or give --{axis}-range MIN MAX")


def observed_ranges(samples: list[RawSample]) -> dict[int, tuple[float, float]]:
    """Min..max of the samples' device X and Y, keyed by ABS_MT_POSITION_X / _Y."""
    xs = [s.x for s in samples]
    ys = [s.y for s in samples]
    return {ABS_MT_POSITION_X: (min(xs), max(xs)), ABS_MT_POSITION_Y: (min(ys), max(ys))} if samples else {}


#: Largest recording read (bytes), set by its cost: decoding takes about 0.26 s of CPU and
#: 21 MB of memory per MB of evemu log (the densest format, about 25 bytes an event;
#: getevent's 80-byte lines cost a third of that per MB), so the largest accepted file
#: stays under 5 s and 1 GiB: 12 MiB of evemu took 3.9 s and 340 MB, 8 MB 2.7 s and
#: 240 MB (``trace import``, /usr/bin/time). 10 MiB is about 7 minutes of evemu at two
#: fingers and 120 Hz, 25 minutes of getevent log; split longer recordings.
MAX_RECORDING_BYTES = 10 << 20


def read_text(path: str | Path, what: str) -> str:
    """The text of a recording (``textures.library.read_utf8``: a regular UTF-8 file of at
    most MAX_RECORDING_BYTES); anything else raises :class:`TraceError`."""
    try:
        return read_utf8(path, MAX_RECORDING_BYTES)
    except UnreadableText as exc:
        where = f"{path}:{exc.line}" if exc.line is not None else f"{path}"
        raise TraceError(f"{where}: {exc}; expected a text {what}") from None
