"""The demo's layer panel, its state and logic (no GL): which layer, which key, the
value, the undo stack and the edit to the texture file's TOML document.

A :class:`LayerEdit` holds a texture file's text as a ``tomlkit`` document, which keeps
comments, key order and formatting: saving writes back every line the author did not
change byte for byte: a key the panel adds goes on a line of its own after the layer's
keys, in the file's line ending, with no blank line added before the layer's sub-tables
(``[layer.visual]``); a leading byte order mark (U+FEFF, which the loader accepts) is
kept too. A layer's controls come from the loader's key tables
(``textures.keys.LAYER_KEYS``, each key's ``textures.schema`` spec):

- a number key (``Num``, ``Int``) is a :class:`Slider` over the range the format
  allows, a side the format leaves open (or bounds only by its catch-all, such as
  ``MAX_MM``, 100 N for a force) narrowed to what can be dragged (see
  :func:`slider_span`), then cut to what the loader takes for the layer as it is (a
  rectangle's ``edge_mm`` at most its shorter side; the loader asked,
  :func:`loader_spans`); a value set is clamped into it and rounded to the slider's step
  (a short decimal in the file), except the slider's own value (the knob grabbed and not
  moved), which is kept as the file gives it. Where the loader refuses values between
  the slider's ends (a directional layer's ``angle_deg``: 0 or 180 only) the slider
  stops only at the values it takes (:func:`_stops`);
- a word key (``Choice``: ``blend``, ``render``, a grating's ``edge``, ...) is a
  :class:`Menu` of the options the loader takes for the layer as it is (no "sht" on a
  rectangle: it needs a periodic layer). The keys that decide which other keys a
  layer takes (``type``, a height's ``shape``, a clip's ``clip`` and ``trigger``, a
  waveform's ``shape``) are not offered.

A key is offered when the file gives it, or when its default is a value (a key whose
default is derived by the loader, "none" in the tables, is offered only once written)
and the loader takes it written beside the layer's other keys: the loader itself is
asked (:func:`refused_keys`: the layer with those keys written at their defaults,
which changes nothing but that they are given), so a waveform of shape "sine" offers no
``duty``, a height layer only its shape's keys, a clip only its clip's.

A refused edit is said at the line of the file as it is on disk (the file the user
sees; :meth:`LayerEdit.refusal`), not of the edited text, where a key the edit wrote
adds a line.

A grating's ``edge`` menu carries its ``edge_mm`` along: "smooth" needs edge_mm > 0
(at most the narrower band), so switching to it writes edge_mm at half the narrower
band (min(duty, 1 - duty) x period_mm / 2, the middle of what the format allows) unless
the file gives a usable one; "square" refuses an edge_mm, so switching back removes it.
A raster's ``mode`` set to "one-to-one" (the size comes from the image) removes the
sizes it refuses (``width_mm``, ``height_mm``, ``tile_width_mm``, ``tile_height_mm``);
a one-to-one raster is not offered "stretch" or "tile", which need a size the file
does not give.

Every change pushes the document's text before it on the undo stack; changes made with
the same ``group`` (one slider drag) share one entry; a change the loader refuses is
taken back whole (:meth:`LayerEdit.revert`), leaving no undo entry.

The file is the author's as much as the panel's: :meth:`LayerEdit.save` writes only
onto the text the panel read (its content, mtime and size, :attr:`LayerEdit.disk`). If
the file changed since (an editor saved it) or is gone (deleted or moved), the save
is refused with :class:`SaveConflict`; saving again with the file as it was then found
overwrites it (or writes it anew) deliberately. A save writes the file a symbolic link
leads to, beside it (the link stays a link), and keeps the file's permission bits (a new
copy gets the mode a file created under the umask gets). :meth:`LayerEdit.reread` takes the file again after it
changed and reloaded, keeping the panel's unsaved edits (each a layer's key set, the
undo stack's too) on top of it where the layer is still there, of the same type and
name, the file did not change that key too (then the file's value, the later, wins),
and the result loads.

:meth:`LayerEdit.save` writes the document to :func:`save_path` (a bundled scene: a copy
in the user's scene folder, with the files it names) and checks that the saved file
loads.
"""

from __future__ import annotations

import math
import os
import re
import secrets
import shutil
import stat as statmod
import tomllib
from dataclasses import dataclass, replace
from pathlib import Path

import tomlkit
from tomlkit.exceptions import TOMLKitError
from tomlkit.items import AoT, Table

from frictex.device.errors import InputError
from frictex.device.safe_files import UnsafeFile, read_bytes
from frictex.rendering.visual.layer_panel import ControlView, PanelView
from frictex.textures.errors import Locator, TextureError, field_name
from frictex.textures.clips import MAX_CLIP_S
from frictex.textures.keys import COMMON, LAYER_KEYS, MAX_ANGLE_DEG, MAX_FORCE_N, MAX_MM
from frictex.textures.library import LIBRARY_DIR, user_scenes_dir
from frictex.textures.loader import check_document, load_scene
from frictex.textures.references import referenced_files
from frictex.textures.schema import MAX_MAGNITUDE, Choice, Int, Num
from frictex.textures.toml_safe import MAX_FILE_BYTES
from frictex.textures.sections.layers import default_layer_name

#: word keys that change which keys a layer takes: not offered as menus
STRUCTURAL = ("type", "shape", "clip", "trigger")
#: slider steps per span at least (the step is a power of ten)
MIN_STEPS = 500
MAX_UNDO = 200
#: a value within this many steps of the slider's is its value (float rounding of the
#: knob's position, not a move)
UNMOVED = 1e-6


class EditError(InputError):
    """A texture file the panel cannot edit or save (unreadable TOML, no layers, ...)."""


class SaveConflict(EditError):
    """The file to save changed on disk since the panel read it (or, for a copy of a
    bundled scene, is there already): not overwritten unless saved again. ``banner``:
    the window's short line for it."""

    def __init__(self, message: str, banner: str):
        super().__init__(message)
        self.banner = banner


@dataclass(frozen=True)
class OnDisk:
    """A texture file as the panel read or wrote it: its ``text`` and (mtime ns, size
    bytes), or None for both when there is no file."""

    text: str | None
    mtime_size: tuple[int, int] | None


def on_disk(path: Path) -> OnDisk:
    """``path``'s text and (mtime ns, size) now, or ``OnDisk(None, None)`` when it is not
    there. Read as every texture file is (``device.safe_files.read_bytes``): a regular
    file of at most ``toml_safe.MAX_FILE_BYTES``, else :class:`EditError`; a leading byte
    order mark is kept in the text. The (mtime, size) is taken before the text, so a
    change in between shows as a change at the next look, never hides one."""
    try:
        info = os.stat(path)
        data = read_bytes(path, MAX_FILE_BYTES)
    except FileNotFoundError:
        return OnDisk(None, None)
    except UnsafeFile as exc:
        raise EditError(f"cannot read {Path(path).name}: it {exc}") from None
    except OSError as exc:
        raise EditError(f"cannot read {Path(path).name}: {exc.strerror or exc}") from None
    try:
        text = data.decode("utf-8")
    except UnicodeDecodeError as exc:
        raise EditError(f"{Path(path).name} is not UTF-8 text: {exc}") from None
    return OnDisk(text, (info.st_mtime_ns, info.st_size))


@dataclass(frozen=True)
class Slider:
    """A number key: ``value`` (``unit``) dragged over [``lo``, ``hi``] in ``step``s,
    allowed in [``allowed_lo``, ``allowed_hi``] (the key's range; an open bound kept out
    by a step). ``written``: the file gives the key (else ``value`` is its default).
    ``stops``: where not empty, the only values the loader takes between the ends (a
    drag goes to the nearest, a value set to the next that way: :func:`clamp`)."""

    key: str
    unit: str
    lo: float
    hi: float
    step: float
    value: float
    written: bool
    allowed_lo: float
    allowed_hi: float
    integer: bool = False
    stops: tuple[float, ...] = ()

    @property
    def fraction(self) -> float:
        """Where ``value`` sits on the slider, 0 (``lo``) to 1 (``hi``)."""
        if not self.hi > self.lo:  # the loader takes the value alone (loader_spans)
            return 0.0
        return float(min(max((self.value - self.lo) / (self.hi - self.lo), 0.0), 1.0))

    def value_at(self, fraction: float) -> float:
        """The value at ``fraction`` (0 to 1, clipped) of the slider (its nearest stop,
        where it has ``stops``)."""
        f = min(max(float(fraction), 0.0), 1.0)
        return _nearest(self.stops, self.lo + f * (self.hi - self.lo))


def _nearest(stops: tuple[float, ...], value: float) -> float:
    """The one of ``stops`` nearest ``value``; ``value`` itself when there are none."""
    return min(stops, key=lambda s: abs(s - value)) if stops else value


@dataclass(frozen=True)
class Menu:
    """A word key: ``value``, one of ``options``."""

    key: str
    options: tuple[str, ...]
    value: str
    written: bool


def _step(span: float) -> float:
    """The power of ten giving at least MIN_STEPS steps over ``span``."""
    return 10.0 ** math.floor(math.log10(span / MIN_STEPS))


#: a slider narrowed around its value spans NARROW x |value| each way the key goes
NARROW = 4.0
#: the narrowed half-span (the unit's) for a value of 0
ZERO_SPAN = 1.0
#: the bounds the format gives every key of a unit as a catch-all (not a limit of the key),
#: by the unit's first word: lengths, angles, forces (a fingertip presses with 0.1 to 5 N),
#: times (a clip lasts well under a second)
CATCH_ALL = {"mm": MAX_MM, "deg": MAX_ANGLE_DEG, "N": MAX_FORCE_N, "s": MAX_CLIP_S}


def _narrowed(unit: str, value: float, signed: bool, extent_mm: float) -> tuple[float, float]:
    """The (lo, hi) a drag can use for a key of ``unit`` holding ``value`` whose format
    bounds are open or catch-alls: lengths and positions [0, ``extent_mm``] (mm), angles
    [-180, 180] deg, other units up to NARROW x |value| (``ZERO_SPAN`` for 0), and as far
    below 0 where the key takes negative values (``signed``), else from 0."""
    if unit == "mm":
        return 0.0, extent_mm
    if unit == "deg":
        return -180.0, 180.0
    reach = NARROW * abs(value) if value else ZERO_SPAN
    return (-reach if signed else 0.0), reach


def slider_span(spec: Num | Int, value: float, extent_mm: float) -> tuple[float, float, float]:
    """(lo, hi, step) of a slider for ``spec`` holding ``value``.

    The range the format allows (``spec``'s bounds), where a side is open or at the
    format's catch-all bound for the unit (``CATCH_ALL``: lengths and positions at
    +-``MAX_MM``, angles at +-``MAX_ANGLE_DEG``, forces at ``MAX_FORCE_N``, times at
    ``MAX_CLIP_S``) narrowed to what a drag can use (:func:`_narrowed`); a side the
    format bounds more tightly (a height's ``rise_mm``, -100 to 100 mm; a mu' at 1) is
    the slider's end. Always wide enough to hold ``value``. The step gives at least
    MIN_STEPS over the span and over the span narrowed around ``value`` (so at most
    |value| / 125: a small value keeps its digits). An open bound (``gt``/``lt``) is kept
    out by one step.
    """
    lower = spec.ge if isinstance(spec, Int) else (spec.gt if spec.gt is not None else spec.ge)
    upper = spec.le if isinstance(spec, Int) else (spec.lt if spec.lt is not None else spec.le)
    unit = spec.unit.split(",")[0]  # "N, positive resisting the finger": N
    catch_all = CATCH_ALL.get(unit, MAX_MAGNITUDE)
    lo, hi = _narrowed(unit, value, lower is None or lower < 0, extent_mm)
    if lower is not None:
        lo = max(lo, lower) if lower <= -catch_all else lower
    if upper is not None:
        hi = min(hi, upper) if upper >= catch_all else upper
    lo, hi = min(lo, value), max(hi, value)
    if not hi > lo:
        hi = lo + 1.0
    step = 1.0 if isinstance(spec, Int) else _value_step(hi - lo, value)
    if isinstance(spec, Num):
        if spec.gt is not None and lo <= spec.gt:
            lo = spec.gt + step
        if spec.lt is not None and hi >= spec.lt:
            hi = spec.lt - step
    return float(lo), float(hi), float(step)


#: a periodic layer's shift along its normal (mm): one period holds every shift it makes
SHIFT_KEY = "offset_mm"


def _shift_span(table, specs: dict, value: float) -> tuple[float, float, float] | None:
    """(lo, hi, step) of a periodic layer's ``offset_mm`` slider: one period, [0,
    ``period_mm``] (wide enough to hold ``value``), so that a drag sets the phase finely
    (over the display's 108 mm one pixel moved a 0.6 mm grating by 1.75 periods); None
    where the layer has no usable period (the slider then spans as any length's)."""
    period = table.get("period_mm", getattr(specs.get("period_mm"), "default", None))
    if isinstance(period, bool) or not isinstance(period, (int, float)) or not period > 0:
        return None
    lo, hi = min(0.0, value), max(float(period), value)
    return lo, hi, _value_step(hi - lo, value)


def _value_step(span: float, value: float) -> float:
    """The step of a slider over ``span`` holding ``value``: the finer of the span's and
    that of the span narrowed around ``value`` (NARROW x |value|)."""
    return min(_step(span), _step(NARROW * abs(value))) if value else _step(span)


def allowed_range(spec: Num | Int, step: float) -> tuple[float, float]:
    """The values ``spec`` accepts, as a closed interval: an open bound moved in by
    ``step``, a missing one at the schema's largest magnitude (``MAX_MAGNITUDE``)."""
    if isinstance(spec, Int):
        lo, hi = spec.ge, spec.le
    else:
        lo = spec.gt + step if spec.gt is not None else spec.ge
        hi = spec.lt - step if spec.lt is not None else spec.le
    return (float(lo) if lo is not None else -MAX_MAGNITUDE,
            float(hi) if hi is not None else MAX_MAGNITUDE)


def clamp(slider: Slider, value: float) -> float:
    """``value`` for ``slider``'s key: not finite refused, clamped to the key's allowed
    range, rounded to the slider's step (a whole number for an integer key; a short
    decimal for a real one), or for a slider with ``stops`` the stop nearest it of
    those past the slider's value the way it moved (the value kept where none is: a
    move goes to the next value the key takes, never back). The slider's own value
    (give or take float rounding: the knob grabbed and not moved) is kept as it is, on a
    step or not."""
    v = float(value)
    if not math.isfinite(v):
        raise EditError(f"{slider.key} = {value!r}: expected a finite number ({slider.unit})")
    if abs(v - slider.value) <= UNMOVED * slider.step:
        return slider.value
    if slider.stops:
        past = tuple(s for s in slider.stops if (s - slider.value) * (v - slider.value) > 0)
        return _nearest(past, v) if past else slider.value
    v = min(max(v, slider.allowed_lo), slider.allowed_hi)
    if slider.integer:
        return float(round(v))
    return min(max(_on_step(v, slider.step), slider.allowed_lo), slider.allowed_hi)


def _on_step(value: float, step: float) -> float:
    """``value`` rounded to a multiple of ``step`` (a power of ten), as a short decimal."""
    digits = max(0, -int(math.floor(math.log10(step))))
    return round(round(value / step) * step, digits)


def refused_keys(path: Path, doc, index: int) -> frozenset[str]:
    """The keys of ``doc``'s layer ``index`` (0-based) the file does not give and the
    loader refuses given: they are written at their defaults (the only change: the keys
    are given) and the document checked once (``check_document``, for the file at ``path``); a
    problem at a key ("not used with shape = ...") refuses it. Keys whose default is
    derived ("none") are not tried: the panel does not offer them unwritten."""
    table = doc["layer"][index]
    specs = {**{k: COMMON[k] for k in ("blend", "render")},
             **LAYER_KEYS.get(str(table.get("type", "")), {})}
    tried = {key: spec.default for key, spec in specs.items()
             if key not in table and key not in STRUCTURAL and not isinstance(spec.default, bool)
             and isinstance(spec.default, (int, float, str))}
    probe = _plain(doc)
    probe["layer"][index].update(tried)
    fields = _problem_fields(path, probe)
    return frozenset(key for key in tried if field_name(("layer", index, key)) in fields)


def _plain(doc) -> dict:
    """``doc`` (tomlkit's) as ``tomllib`` reads its text: plain values to try keys on."""
    return tomllib.loads(tomlkit.dumps(doc))


def _problem_fields(path: Path, doc: dict) -> frozenset[str]:
    """The fields (``layer[2].duty``) of the problems the loader finds in ``doc`` (the
    file at ``path`` as edited, parsed: :func:`_plain`)."""
    _, problems, _ = check_document(path, doc)
    return frozenset(p.field for p in problems)


def loader_spans(path: Path, doc, index: int, controls) -> tuple[Slider | Menu, ...]:
    """``controls`` of ``doc``'s layer ``index`` (:func:`layer_controls`) cut to what the
    loader takes for that layer as it is: each slider's ends (:func:`_loader_slider`)
    and stops (:func:`_stops`), each menu's options. A key's limit set by its layer's
    other keys (a rectangle's ``edge_mm``, at most the shorter side; "sht" only on a
    periodic layer) is found by asking the loader, not by a copy of its rules. A value
    is taken when setting it (with what it carries along, :func:`_set`) adds no problem
    to those of the document as it is."""
    probe = _plain(doc)
    known = _problem_fields(path, probe)
    layers = probe["layer"]
    table = layers[index]

    def accepts(key: str, value) -> bool:
        layers[index] = dict(table)  # _set changes only the layer's own keys
        _set(layers[index], key, value)
        try:
            return _problem_fields(path, probe) <= known
        finally:
            layers[index] = table

    out = []
    for c in controls:
        if isinstance(c, Slider):
            def takes(value: float, c=c) -> bool:
                return accepts(c.key, int(value) if c.integer else value)
            c = _stops(_loader_slider(c, takes), takes)
        else:
            c = replace(c, options=tuple(o for o in c.options
                                         if o == c.value or accepts(c.key, o)))
        out.append(c)
    return tuple(out)


def _held_spans(controls, before) -> tuple[Slider | Menu, ...]:
    """``controls`` (:func:`layer_controls`, the values of now) with each slider's ends,
    step, allowed range and stops as in ``before`` (the same layer's,
    :func:`loader_spans`), widened to hold its value, and each menu's options as there:
    a drag's controls as the drag began."""
    held = {c.key: c for c in before}
    out = []
    for c in controls:
        old = held.get(c.key)
        if isinstance(c, Slider) and isinstance(old, Slider):
            c = replace(c, lo=min(old.lo, c.value), hi=max(old.hi, c.value), step=old.step,
                        allowed_lo=old.allowed_lo, allowed_hi=old.allowed_hi, stops=old.stops)
        elif isinstance(c, Menu) and isinstance(old, Menu) and c.value in old.options:
            c = replace(c, options=old.options)
        out.append(c)
    return tuple(out)


def _loader_slider(slider: Slider, accepts) -> Slider:
    """``slider`` with each end the loader refuses (``accepts(value)`` False) moved in to
    the farthest value from the slider's that it takes (:func:`_reach`), the key's
    allowed range cut there too; the step made finer where the span left needs it
    (``MIN_STEPS``, :func:`_value_step`). The values taken are assumed to be one interval
    around the slider's value, as every limit of the format makes them."""
    refused = [end for end in (slider.lo, slider.hi) if not accepts(end)]
    if not refused:
        return slider
    ends = {end: _reach(accepts, slider.value, end, slider.step) for end in refused}
    lo, hi = ends.get(slider.lo, slider.lo), ends.get(slider.hi, slider.hi)
    step = slider.step
    if hi > lo and not slider.integer:
        step = min(step, _value_step(hi - lo, slider.value))
        if step < slider.step:  # look again between the end found and the step past it
            ends = {end: _reach(accepts, found, found + math.copysign(slider.step, end - found), step)
                    for end, found in ends.items()}
            lo, hi = ends.get(slider.lo, slider.lo), ends.get(slider.hi, slider.hi)
    return replace(slider, lo=lo, hi=hi, step=step,
                   allowed_lo=lo if slider.lo in ends else slider.allowed_lo,
                   allowed_hi=hi if slider.hi in ends else slider.allowed_hi)


#: a slider is probed at PROBES - 1 points evenly between its ends (:func:`_stops`)
PROBES = 4


def _stops(slider: Slider, accepts) -> Slider:
    """``slider`` as it is where the loader takes (``accepts``) each of PROBES - 1 points
    evenly between its ends (on its step), as it does every value of a key whose limits
    are bounds. Where it refuses one, the key takes only some values (a directional
    layer's ``angle_deg``: the waves push along x, so 0 or 180): the slider gets as
    ``stops`` its ends, its value and the points the loader takes (-180, 0, 180 deg)."""
    if not slider.hi > slider.lo:
        return slider
    points = [slider.lo + k * (slider.hi - slider.lo) / PROBES for k in range(1, PROBES)]
    points = [float(round(p)) if slider.integer else _on_step(p, slider.step) for p in points]
    taken = [p for p in points if accepts(p)]
    if len(taken) == len(points):
        return slider
    return replace(slider, stops=tuple(sorted({slider.lo, slider.hi, slider.value, *taken})))


def _reach(accepts, good: float, bad: float, step: float) -> float:
    """The multiple of ``step`` farthest from ``good`` (taken) towards ``bad`` (refused)
    that ``accepts`` takes, found by bisection (about log2(|bad - good| / step) tries),
    or ``good`` when none between them is taken. A short decimal: rounded to the step's
    digits."""
    sign = 1 if bad > good else -1
    digits = max(0, -int(math.floor(math.log10(step))))
    first = math.floor(good / step) if sign > 0 else math.ceil(good / step)

    def point(t: int) -> float:
        return round((first + sign * t) * step, digits)

    taken, past = 0, max(1, math.ceil(abs(bad - first * step) / step))
    while past - taken > 1:
        mid = (taken + past) // 2
        if accepts(point(mid)):
            taken = mid
        else:
            past = mid
    return point(taken) if taken and sign * (point(taken) - good) > 0 else good


def _layout(table) -> tuple:
    """What of a layer decides which keys the loader takes: the keys it gives and its
    words (``shape``, ``edge``, ``mode``, ...), not its numbers (a drag keeps it)."""
    return tuple(sorted((str(k), v if isinstance(v, (str, bool)) else None)
                        for k, v in table.items()))


def layer_controls(table, extent_mm: float, refused=frozenset()) -> tuple[Slider | Menu, ...]:
    """The panel's controls for one ``[[layer]]`` table (``extent_mm``: the display's
    larger side, mm), leaving out the keys the file does not give and the loader
    ``refused`` (:func:`refused_keys`)."""
    layer_type = str(table.get("type", ""))
    specs = {k: COMMON[k] for k in ("blend", "render")}
    specs.update(LAYER_KEYS.get(layer_type, {}))
    out: list[Slider | Menu] = []
    for key, spec in specs.items():
        written = key in table
        if key in refused and not written:
            continue
        if isinstance(spec, Choice):
            if key in STRUCTURAL:
                continue
            value = table[key] if written else spec.default
            if isinstance(value, str) and value in spec.options:
                out.append(Menu(key, spec.options, str(value), written))
        elif isinstance(spec, (Num, Int)):
            value = table[key] if written else spec.default
            if isinstance(value, bool) or not isinstance(value, (int, float)):
                continue  # derived default ("none"), or a bad value the loader reports
            lo, hi, step = (_shift_span(table, specs, float(value)) if key == SHIFT_KEY
                            else None) or slider_span(spec, float(value), extent_mm)
            out.append(Slider(key, spec.unit, lo, hi, step, float(value), written,
                              *allowed_range(spec, step), isinstance(spec, Int)))
    return tuple(out)


def _key_path(field: str) -> tuple | None:
    """A problem's field (``layer[2].duty``) as a key path (``("layer", 1, "duty")``),
    or None if it is not one (an escaped key)."""
    path: list = []
    for part in field.split("."):
        m = re.fullmatch(r"([A-Za-z0-9_-]+)((?:\[\d+\])*)", part)
        if m is None:
            return None
        path.append(m.group(1))
        path += [int(n) - 1 for n in re.findall(r"\[(\d+)\]", m.group(2))]
    return tuple(path) if field else None


def is_bundled(path: Path) -> bool:
    """``path`` is one of the scenes installed with frictex (never written to)."""
    resolved = Path(path).resolve()
    return resolved.is_relative_to(LIBRARY_DIR) or "site-packages" in resolved.parts


def save_path(path: Path) -> Path:
    """Where the panel saves the scene read from ``path``: ``path`` itself, or for a
    bundled scene ``<user scene folder>/<file name>``."""
    return user_scenes_dir() / Path(path).name if is_bundled(path) else Path(path)


BOM = "\ufeff"


def _split_bom(text: str) -> tuple[str, str]:
    """``text`` as (its leading byte order mark, or "", and the TOML after it)."""
    return (BOM, text[1:]) if text.startswith(BOM) else ("", text)


def _parse(path: Path, text: str):
    """``text`` (the file at ``path``, a leading byte order mark allowed) as a tomlkit
    document with at least one layer."""
    try:
        doc = tomlkit.parse(_split_bom(text)[1])
    except TOMLKitError as exc:
        raise EditError(f"{path.name} is not TOML the panel can edit: {exc}") from None
    if not doc.get("layer"):
        raise EditError(f"{path.name} has no [[layer]] to edit")
    return doc


def _same_layer(a, b) -> bool:
    """Layer tables ``a`` and ``b`` are the same layer: same type, same name (or none)."""
    return a.get("type") == b.get("type") and a.get("name") == b.get("name")


def edits(doc, base) -> list[tuple[int, str, object]]:
    """What ``doc`` sets that ``base`` does not: (layer index, key, value) for each key
    of a layer that ``base`` lacks or gives another value (the panel only sets keys;
    one it removed, a smooth edge's edge_mm, is put back by the menu it goes with)."""
    out = []
    for k, (table, was) in enumerate(zip(doc["layer"], base["layer"])):
        for key, value in table.items():
            if key not in was or was[key] != value:
                out.append((k, str(key), value))
    return out


def _applies(layers, old_layers, k: int, key: str) -> bool:
    """An edit of ``key`` in layer ``k`` made on ``old_layers`` applies to ``layers``:
    the layer is the same one (:func:`_same_layer`) and the file left the key as the
    edit found it (a key changed in the file too: the file's value is the later)."""
    if k >= len(layers) or not _same_layer(layers[k], old_layers[k]):
        return False
    return layers[k].get(key) == old_layers[k].get(key)


def _edited(text: str, old_base, new_base) -> str:
    """``text`` (a document made from ``old_base`` by the panel) made again on
    ``new_base``: its edits (:func:`edits`) set where they apply (:func:`_applies`)."""
    doc = tomlkit.parse(tomlkit.dumps(new_base))
    layers = doc["layer"]
    for k, key, value in edits(tomlkit.parse(text), old_base):
        if _applies(new_base["layer"], old_base["layer"], k, key):
            _set(layers[k], key, value)
    return tomlkit.dumps(doc)


class LayerEdit:
    """The texture file at ``path`` open for editing; see the module docstring.

    Attributes
    ----------
    layer : the index of the layer selected (``[[layer]]`` order), or None.
    original : the text the document was read from or last saved as (after its byte
        order mark, if it has one).
    bom : the file's leading byte order mark, or "": written back before the text.
    disk : the file as last read or written (:class:`OnDisk`): a save writes only onto it.
    """

    def __init__(self, path: Path):
        self.path = Path(path)
        self.disk = on_disk(self.path)
        if self.disk.text is None:
            raise EditError(f"cannot read {self.path.name} for editing: no such file")
        self.bom, self.original = _split_bom(self.disk.text)
        self.doc = _parse(self.path, self.original)
        display = self.doc.get("display", {})
        self.extent_mm = float(max(display.get("width_mm", 100.0), display.get("height_mm", 100.0)))
        self.layer: int | None = None
        self._undo: list[tuple[str, object]] = []  # (text before, group)
        self._group: object = None
        self._last: tuple | None = None  # the last set(): (text before, group before, pushed)
        self._overwrite: OnDisk | None = None  # the changed file a save was refused on
        self._refused: tuple = (None, None, frozenset())  # (layer, _layout, refused_keys)
        self._spans: tuple = (None, None, ())  # (layer, text, its controls: loader_spans)

    # -- reading -----------------------------------------------------------------------

    def text(self) -> str:
        """The document as it would be saved."""
        return tomlkit.dumps(self.doc)

    @property
    def dirty(self) -> bool:
        """The document differs from the text it was opened with."""
        return self.text() != self.original

    @property
    def unsaved(self) -> int:
        """How many keys the document sets that the text it was read from does not."""
        return len(edits(self.doc, tomlkit.parse(self.original)))

    def layer_names(self) -> tuple[str, ...]:
        """Each layer as the panel lists it: "<name> (<type>)", an unnamed one by the
        name the loader gives it, "<type>-<k>" (k from 1, as ``preview`` and the format
        page name it)."""
        names = []
        for k, table in enumerate(self.doc["layer"]):
            kind = str(table.get("type", "?"))
            name = table["name"] if "name" in table else default_layer_name(kind, k)
            names.append(f"{name} ({kind})")
        return tuple(names)

    def controls(self) -> tuple[Slider | Menu, ...]:
        """The selected layer's controls (none when no layer is selected); the keys the
        loader refuses given (:func:`refused_keys`) are worked out again only when the
        layer's keys or words change (:func:`_layout`), the sliders' ends
        (:func:`loader_spans`: some hundred loader checks) when a value changes, but not
        during a drag (a ``group`` of changes), whose sliders keep the ends they had as
        it began (:func:`_held_spans`) until :meth:`end_group`."""
        if self.layer is None:
            return ()
        table = self.doc["layer"][self.layer]
        if self._refused[:2] != (self.layer, _layout(table)):
            self._refused = (self.layer, _layout(table),
                             refused_keys(self.path, self.doc, self.layer))
        text = self.text()
        if self._spans[:2] != (self.layer, text):
            controls = layer_controls(table, self.extent_mm, self._refused[2])
            if self._group is not None and self._spans[0] == self.layer:
                controls = _held_spans(controls, self._spans[2])
            else:
                controls = loader_spans(self.path, self.doc, self.layer, controls)
            self._spans = (self.layer, text, controls)
        return self._spans[2]

    def control(self, key: str) -> Slider | Menu:
        for c in self.controls():
            if c.key == key:
                return c
        raise EditError(f"the layer has no key {key!r} the panel edits")

    def refusal(self, exc: ValueError) -> str:
        """``exc`` (the loader refusing the edited text) in one line, its first problem at
        the line of the file as on disk (the text opened or last saved): a key the edit
        added, not in the file yet, is said at its layer's line."""
        if not isinstance(exc, TextureError) or not exc.problems:
            return str(exc)
        first, more = exc.problems[0], len(exc.problems) - 1
        path = _key_path(first.field)
        if path is not None:
            locator = Locator(self.original)
            line = locator.line(path)
            absent = len(path) > 1 and line == locator.line(path[:-1])
            first = replace(first, line=line, message=first.message
                            + (" (a key the edit adds; not in the file yet)" if absent else ""))
        return str(first) + (f" (and {more} more)" if more else "")

    @property
    def can_undo(self) -> bool:
        return bool(self._undo)

    # -- changing ----------------------------------------------------------------------

    def select(self, index: int) -> None:
        """Select layer ``index`` (0-based, file order)."""
        count = len(self.doc["layer"])
        if not 0 <= index < count:
            raise EditError(f"layer {index} does not exist; expected 0 to {count - 1}")
        self.layer = index

    def set(self, key: str, value, group: object = None) -> str | float:
        """Set ``key`` of the selected layer: a number (clamped to its slider, rounded to
        its step) or one of a menu's options. Returns the value written. ``group``: a
        change with the group of the change before it (a drag) shares its undo entry."""
        control = self.control(key)
        if isinstance(control, Menu):
            if value not in control.options:
                raise EditError(f"{key} = {value!r} is not one of {', '.join(control.options)}")
            new = value
        else:
            new = clamp(control, value)
            new = int(new) if control.integer else new
        table = self.doc["layer"][self.layer]
        if control.written and control.value == new:
            return new
        before = self.text()
        pushed = group is None or group != self._group or not self._undo
        self._last = (before, self._group, pushed)
        if pushed:
            self._undo.append((before, group))
            del self._undo[:-MAX_UNDO]
        self._group = group
        _set(table, key, new)
        return new

    def undo(self) -> bool:
        """Take back the last change (a whole drag); False if there is none."""
        if not self._undo:
            return False
        text, _ = self._undo.pop()
        self.doc = tomlkit.parse(text)
        self._group = None
        return True

    def revert(self) -> None:
        """Take back the last :meth:`set` (a change the loader refused) whole: the
        document as before it, and the undo entry it made, if it made one (a refused
        drag position leaves the drag's entry to the positions before it)."""
        if self._last is None:
            return
        before, group, pushed = self._last
        self.doc = tomlkit.parse(before)
        if pushed:
            self._undo.pop()
            self._group = group
        self._last = None

    def reread(self) -> tuple[int, int]:
        """Take the file again (it changed on disk and loads), keeping the unsaved edits
        on top of it: each key the panel set (:func:`edits`, in the document and in each
        undo entry) set again in the same layer (same place, type and name) where the
        file left that key as it was (:func:`_applies`: a key changed in the file too
        keeps the file's value), as long as the result loads; an edit that no longer
        applies is dropped. Returns (edits kept, edits dropped) of the document."""
        disk = on_disk(self.path)
        if disk.text is None:
            raise EditError(f"cannot read {self.path.name} for editing: no such file")
        doc = _parse(self.path, disk.text)
        old, wanted = tomlkit.parse(self.original), edits(self.doc, tomlkit.parse(self.original))
        text = _edited(self.text(), old, doc)
        try:
            load_scene(self.path, text=text)
        except (ValueError, OSError):
            text = _split_bom(disk.text)[1]  # the edits, together, are refused: each alone
            for k, key, value in wanted:
                trial = tomlkit.parse(text)
                if _applies(doc["layer"], old["layer"], k, key):
                    _set(trial["layer"][k], key, value)
                    try:
                        load_scene(self.path, text=tomlkit.dumps(trial))
                    except (ValueError, OSError):
                        continue
                    text = tomlkit.dumps(trial)
        self._undo = [(_edited(t, old, doc), g) for t, g in self._undo]
        self.bom, original = _split_bom(disk.text)
        self.disk, self.original, self.doc = disk, original, tomlkit.parse(text)
        self._group, self._last, self._overwrite = None, None, None
        if self.layer is not None and self.layer >= len(self.doc["layer"]):
            self.layer = len(self.doc["layer"]) - 1
        kept = len(edits(self.doc, doc))
        return kept, len(wanted) - kept

    def end_group(self) -> None:
        """The drag ended: the next change starts a new undo entry, and the sliders' ends
        are worked out again for the values it left."""
        self._group = None
        self._spans = (None, None, ())

    # -- saving ------------------------------------------------------------------------

    def save(self) -> Path:
        """Write the document to :func:`save_path` (atomically: a new file renamed over
        the old, with the old file's permission bits), with the files it names for a
        copy of a bundled scene; the saved file must load (``textures.loader.load_scene``).
        Returns the path written.

        Raises :class:`EditError` when the file there has no owner-write bit, and
        :class:`SaveConflict` when the file there is not the one the panel read
        (:attr:`disk`; for a first copy of a bundled scene: no file): changed on disk
        since, by content or by mtime and size. Saving again while the file is as that
        refusal found it overwrites it."""
        target = save_path(self.path)
        text = self.text()
        load_scene(self.path, text=text)  # refused before anything is written
        _refuse_read_only(target)
        now = on_disk(target)
        expected = self.disk if target == self.path else OnDisk(None, None)
        if now != expected and now != self._overwrite:
            self._overwrite = now
            raise _conflict(target, copy=target != self.path, gone=now.text is None)
        try:
            target.parent.mkdir(parents=True, exist_ok=True)
            if target != self.path:
                self._copy_references(target.parent)
            _write_keeping_mode(target, self.bom + text)
        except OSError as exc:
            raise EditError(f"cannot save {target}: {exc.strerror or exc}") from None
        load_scene(target)
        self.path, self.original, self._overwrite = target, text, None
        self.disk = OnDisk(self.bom + text, on_disk(target).mtime_size)
        return target

    def _copy_references(self, folder: Path) -> None:
        """Copy the files the scene names (rasters, clips, ...) below ``folder`` as they
        lie below the scene's own folder, unless a file is there already."""
        home = self.path.parent.resolve()
        for ref in referenced_files(self.path):
            ref = Path(ref).resolve()
            if ref.is_relative_to(home) and not (folder / ref.relative_to(home)).exists():
                (folder / ref.relative_to(home)).parent.mkdir(parents=True, exist_ok=True)
                shutil.copy2(ref, folder / ref.relative_to(home))


def _conflict(target: Path, copy: bool, gone: bool) -> SaveConflict:
    """Why a save to ``target`` was refused, and what Ctrl+S again does, with the window's
    banner: the file the panel holds changed on disk (an edit of it reloads) or is
    ``gone`` (deleted or moved: Ctrl+S again writes it anew), or, saving a bundled
    scene's ``copy``, a copy saved before is there (the panel holds the bundled file:
    editing that copy reloads nothing)."""
    if gone:
        return SaveConflict(f"{target.name} was deleted (or moved) since the panel read it: not "
                            "saved. Ctrl+S again writes it anew with the panel's version",
                            "not saved: the file was deleted or moved; Ctrl+S again writes it anew")
    if copy:
        return SaveConflict(f"{target} is there already (a copy saved before): not saved. "
                            "Ctrl+S again replaces its earlier edits with these",
                            "not saved: a copy saved before is there; Ctrl+S again replaces it")
    return SaveConflict(f"{target.name} changed on disk since the panel read it: not saved. "
                        "Ctrl+S again overwrites it with the panel's version; or leave it, and "
                        "a good edit of the file reloads (keeping the panel's unsaved edits)",
                        "not saved: the file changed on disk; Ctrl+S again overwrites")


def _set(table, key: str, value) -> None:
    """Set ``key`` of a layer ``table`` (tomlkit's, or a plain dict) to ``value``, with
    what a grating's ``edge`` (:func:`_edge_width`) and a raster's ``mode``
    (:func:`_raster_size`) carry along."""
    _put(table, key, value)
    if key == "edge" and table.get("type") == "grating":
        _edge_width(table, value)
    elif key == "mode" and table.get("type") == "raster":
        _raster_size(table, value)


#: a raster's sizes, which mode = "one-to-one" refuses (the size comes from the image)
RASTER_SIZES = ("width_mm", "height_mm", "tile_width_mm", "tile_height_mm")


def _raster_size(table, mode: str) -> None:
    """A raster's ``mode`` set to ``mode``: "one-to-one" refuses the sizes
    (``RASTER_SIZES``), so they are removed. The other modes need width_mm and
    height_mm: a one-to-one raster is not offered them (:func:`loader_spans`)."""
    if mode == "one-to-one":
        for key in RASTER_SIZES:
            table.pop(key, None)


def _edge_width(table, edge: str) -> None:
    """A grating's ``edge`` set to ``edge``: "smooth" needs edge_mm > 0 and at most the
    narrower band, so one not usable is set to half that band (rounded to 3 significant
    digits, the middle of what the format allows); "square" refuses an edge_mm, so it
    is removed."""
    if edge == "square":
        table.pop("edge_mm", None)
        return
    specs = LAYER_KEYS["grating"]
    duty = float(table.get("duty", specs["duty"].default))
    period = float(table.get("period_mm", 0.0))
    narrow = min(duty, 1.0 - duty) * period
    if narrow > 0.0 and not 0.0 < float(table.get("edge_mm", 0.0)) <= narrow:
        _put(table, "edge_mm", float(f"{narrow / 2:.3g}"))


def _put(table, key: str, value) -> None:
    """Set ``key`` of ``table`` to ``value``, every other line as it was: a new key of a
    ``[table]`` gets the line ending and indent of the table's keys, and the sub-tables
    after it keep their indent (tomlkit puts a blank line before the first); a plain
    dict's key is just set."""
    if key in table or not isinstance(table, Table):
        table[key] = value
        return
    body = table.value.body
    tables = [item for _, item in body if isinstance(item, (Table, AoT))]
    indents = [_header(item).trivia.indent for item in tables]
    keys = [item for k, item in body if k is not None and not isinstance(item, (Table, AoT))]
    table[key] = value
    for item, indent in zip(tables, indents):
        _header(item).trivia.indent = indent
    if keys:
        added = table.value.item(key).trivia
        added.indent = keys[-1].trivia.indent
        added.trail = "\r\n" if keys[-1].trivia.trail.endswith("\r\n") else added.trail


def _header(item):
    """The item whose trivia holds a sub-table's header line: the table, or an array of
    tables' first."""
    return item[0] if isinstance(item, AoT) else item


def _refuse_read_only(target: Path) -> None:
    """Raise :class:`EditError` when the file ``target`` leads to has no owner-write
    bit. The mode bits are checked, not ``os.access``: the save renames a new file over
    the old one, which needs only the folder's write permission, and root may write
    anything, so neither would stop a chmod 444 file from being replaced."""
    try:
        mode = os.stat(target).st_mode
    except FileNotFoundError:
        return
    if not mode & statmod.S_IWUSR:
        raise EditError(f"cannot save {target.name}: the file is read-only "
                        f"(chmod u+w {target.name} to let the panel save it)")


def _write_keeping_mode(target: Path, text: str) -> None:
    """Write ``text`` to the file ``target`` is, or leads to through symbolic links,
    through a new file in that file's folder renamed over it (a link stays a link); the
    new file has the file's permission bits, or when there is none the mode a file
    created under the umask gets (0o666 less the umask)."""
    target = Path(os.path.realpath(target))
    try:
        mode = statmod.S_IMODE(os.stat(target).st_mode)
    except FileNotFoundError:
        mode = None
    tmp = target.parent / f".{target.name}.{secrets.token_hex(4)}.tmp"
    fd = os.open(tmp, os.O_WRONLY | os.O_CREAT | os.O_EXCL, 0o666)
    try:
        with os.fdopen(fd, "w", encoding="utf-8", newline="") as f:
            if mode is not None:
                os.fchmod(f.fileno(), mode)
            f.write(text)
            f.flush()
            os.fsync(f.fileno())  # on disk before it replaces the file: a power cut keeps one
        os.replace(tmp, target)
    except BaseException:
        tmp.unlink(missing_ok=True)
        raise


def panel_view(editor: LayerEdit | None, open_menu: str | None = None, note: str = "") -> PanelView:
    """What the panel shows of ``editor`` (None: a file it could not open, ``note`` saying
    why): its layers, the selected one's controls labelled "key = value" ("(default)"
    where the file does not give the key), the menu ``open_menu`` open, whether the
    scene differs from the file as read or last saved."""
    if editor is None:
        return PanelView((), None, (), note=note)
    controls = []
    for c in editor.controls():
        shown = c.value if isinstance(c, Menu) else f"{c.value:.6g}"
        label = f"{c.key} = {shown}" + ("" if c.written else " (default)")
        if isinstance(c, Menu):
            controls.append(ControlView("menu", c.key, label, options=c.options))
        else:
            controls.append(ControlView("slider", c.key, label, fraction=c.fraction))
    return PanelView(editor.layer_names(), editor.layer, tuple(controls), open_menu, note,
                     editor.can_undo, editor.dirty)
