"""The inputs of a replay: scenes, recorded traces, synthetic traces."""

from __future__ import annotations

import dataclasses
import functools
import math
import typing
from collections.abc import Iterable, Sequence
from pathlib import Path

import numpy as np
import numpy.typing as npt

from frictex._args import flag, path_like, real, whole
from frictex.device.errors import InputError
from frictex.rendering.input.trace_file import DOWN, MOVE, UP, Trace, TraceError
from frictex.rendering.input.trace_file import make_trace as checked_trace
from frictex.rendering.input.trace_synth import MOTIONS
from frictex.textures.model import Scene

#: the kinds :func:`synth_trace` makes: finger paths, and ``press`` (a still finger pressing)
SYNTH_KINDS = (*MOTIONS, "press")
#: what names a trace's source in its errors
_WHERE = "trace"


def load_scene(name_or_path: str | Path) -> Scene:
    """Load and validate a scene.

    Parameters
    ----------
    name_or_path : str or Path
        A texture file (``.toml``), or the name of a bundled scene (``frictex library``
        lists them), e.g. ``"grating-5mm"``.

    Returns
    -------
    Scene
        The validated scene: display (mm, px), device profile, layers in drawing order.

    Raises
    ------
    InputError
        No such file or bundled scene, or a file that is not a valid texture file; the
        message names the file, the line and the field.
    PluginError
        A ``RuntimeError``, not an InputError: another package's device profile the file
        names that cannot be loaded or is not a profile; the message names its package.
    """
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene as load
    path_like("name_or_path", name_or_path, "a texture file or a bundled scene's name")
    return load(resolve_scene(name_or_path))


def scene_of(scene: Scene | str | Path) -> Scene:
    """``scene`` itself (checked: :func:`checked_scene`), or the scene a texture file or
    bundled scene's name gives."""
    if isinstance(scene, Scene):
        return checked_scene(scene)
    path_like("scene", scene, "a Scene (frictex.load_scene), a texture file or a bundled "
                              "scene's name")
    return load_scene(scene)


def checked_scene(scene: Scene) -> Scene:
    """``scene`` if its values keep the rules a texture file's keys keep, else a
    :class:`~frictex.textures.errors.TextureError` naming the layer and field of each one
    that does not (its first in one line).

    A scene :func:`load_scene` read was checked as its file was read; this is for one
    built or changed in code (``dataclasses.replace``). Each field named as a texture
    file's key (``layers[i].mu_low``, ``display.width_mm``, ``device.amplitude_limit_um``,
    a layer's ``region``, ``geometry`` and ``visual``) is checked by that key's own type
    (``textures.keys``, ``textures.schema``): a number, finite, within the key's bounds;
    a word, one of the key's choices (``edge``, ``blend``, ``mode``); a value equal to
    the key's default is taken as the loader takes it (``render = "auto"`` becomes the
    renderer the loader picks: the returned scene holds it; a renderer of periods on a
    layer without one is refused). A ``region``, ``geometry`` or ``visual`` is of a class
    its field's annotation names. Layer names are unique and not blank, and ``format`` is
    one this frictex reads, as in a file. Fields the file writes another way (colours, a raster's image, a clip's events,
    a height shape, a key click's ``first_push``) and the other rules between keys
    (mu_low under mu_high, objects on the display) are not checked again.
    """
    from frictex.device.profile import DeviceProfile, DrivingForceParams, FrictionParams
    from frictex.textures import keys
    from frictex.textures.loader import format_refusal
    from frictex.textures.sections.layers import report_bad_name
    from frictex.textures.model import Display, _LayerBase
    from frictex.textures.schema import Reader, Retired

    r = Reader(f"scene {_named(scene.name)}", None)
    top = {name: keys.TOP[name] for name in ("format", "name", "description", "control")}
    device = getattr(scene, "device", None)
    for obj, path, table, kind in (
            (scene, (), top, Scene), (scene.display, ("display",), keys.DISPLAY, Display),
            (device, ("device",), keys.DEVICE, DeviceProfile),
            (getattr(device, "friction", None), ("device", "friction"), keys.FRICTION,
             FrictionParams),
            (getattr(device, "driving", None), ("device", "driving"), keys.DRIVING,
             DrivingForceParams)):
        _fields(r, obj, path, {name: (spec, [spec.default]) for name, spec in table.items()
                               if not isinstance(spec, Retired)}, kind)
    if isinstance(scene.format, int) and (refusal := format_refusal(scene.format)):
        r.report(("format",), refusal)
    layers = scene.layers
    if not isinstance(layers, tuple | list) or not 1 <= len(layers) <= keys.MAX_LAYERS:
        count = (f"{len(layers)} layers" if isinstance(layers, tuple | list)
                 else f"a {type(layers).__name__}")
        r.report(("layers",), f"{count}; expected a tuple of 1 to {keys.MAX_LAYERS} layers")
        layers = ()
    rules = _layer_rules()
    names: dict = {}  # a layer's name -> the index of the first layer of that name
    for i, layer in enumerate(layers):
        r.label = f"scene {_named(scene.name)}, layer {_named(getattr(layer, 'name', '?'))}"
        path = (f"layers[{i}]",)
        if _fields(r, layer, path, rules, _LayerBase):
            if isinstance(layer.name, str):
                report_bad_name(r, path + ("name",), layer.name, i, names,
                                lambda first: f"layers[{first}]")
            for part, kinds in _parts(type(layer)):
                value = getattr(layer, part)
                if not isinstance(value, kinds):
                    r.report(path + (part,), f"expected {_either(kinds)}, got "
                                             f"{type(value).__name__}")
                elif value is not None:
                    _fields(r, value, path + (part,), rules)
            _check_render(r, layer, path + ("render",))
    if r.problems:
        from frictex.textures.errors import TextureError
        more = len(r.problems) - 1
        error = TextureError(f"{r.problems[0]}"
                             + (f" (and {more} more problem{'s' * (more > 1)})" if more else ""))
        error.problems = r.problems
        raise error
    return _auto_resolved(scene)


@functools.cache
def _parts(layer_type: type) -> tuple[tuple[str, tuple[type, ...]], ...]:
    """A layer class's fields that hold a region or visual hints (``region``,
    ``geometry``, ``visual``), each with the classes its annotation allows; none where
    its annotations do not resolve (another package's layer naming what its module does
    not import: its own renderer checks what it takes)."""
    try:
        hints = typing.get_type_hints(layer_type)
    except (NameError, TypeError, AttributeError):
        return ()
    return tuple((part, typing.get_args(hints[part]) or (hints[part],))
                 for part in ("region", "geometry", "visual") if part in hints)


def _either(kinds: tuple[type, ...]) -> str:
    """``kinds`` in a message: "a RectRegion, a DiscRegion or None"."""
    names = ["None" if kind is type(None) else f"a {kind.__name__}" for kind in kinds]
    return " or ".join(filter(None, (", ".join(names[:-1]), names[-1])))


def _check_render(r, layer, path: tuple) -> None:
    """Report a layer's ``render`` that is no renderer's name (``auto`` and ``sho``
    included), or that names a renderer of periods on a layer without one."""
    from frictex.textures import keys, model
    from frictex.textures.sections.layers import needs_a_period
    render = getattr(layer, "render", None)
    if keys.COMMON["render"].check(r, render, path) is not render or render in ("auto", model.SHO):
        return
    if getattr(layer, "period_mm", None) is None:
        r.report(path, needs_a_period(render, f"{type(layer).__name__} layer"))


def _auto_resolved(scene: Scene) -> Scene:
    """``scene`` with each layer's ``render = "auto"`` replaced by the renderer the loader
    picks for it (``textures.model.auto_render_mode``)."""
    from frictex.textures.model import auto_render_mode
    if all(layer.render != "auto" for layer in scene.layers):
        return scene
    return dataclasses.replace(scene, layers=tuple(
        dataclasses.replace(layer, render=auto_render_mode(getattr(layer, "period_mm", None)))
        if layer.render == "auto" else layer for layer in scene.layers))


def _fields(r, obj: object, path: tuple, rules: dict, kind: type | None = None) -> bool:
    """Report to the reader ``r`` each field of the dataclass ``obj`` that the rule of its
    name refuses (``rules``: name -> (a key's type, the defaults it is not checked at));
    False (reported) where ``obj`` is not a ``kind``."""
    if kind is not None and not isinstance(obj, kind):
        r.report(path, f"expected a {kind.__name__}, got {type(obj).__name__}")
        return False
    for field in dataclasses.fields(obj):
        if field.name in rules and _held_as_written(rules[field.name][0], field):
            spec, defaults = rules[field.name]
            value = _plain(getattr(obj, field.name))
            if not any(value is default or value == _plain(default) for default in defaults):
                spec.check(r, value, path + (field.name,))
    return True


def _held_as_written(spec, field: dataclasses.Field) -> bool:
    """Whether ``field`` holds what its key's ``spec`` checks: any key but a choice, and a
    choice where the field holds the word (annotated ``str``); the model keeps some
    choices otherwise (a key click's ``first_push`` as +1 or -1), not checked again."""
    from frictex.textures.schema import Choice
    return not isinstance(spec, Choice) or field.type in ("str", str)


def _named(name: object) -> str:
    """A scene's or layer's name in a message, quoted, its first 40 characters (the
    message escapes what is not printable)."""
    text = name if isinstance(name, str) else repr(name)
    return f"'{text[:40]}...'" if len(text) > 40 else f"'{text}'"


def _plain(value: object) -> object:
    """A field's value as TOML would give it: numpy scalars as Python's, tuples as lists."""
    if isinstance(value, np.generic):
        return value.item()
    if isinstance(value, tuple):
        return [_plain(item) for item in value]
    return value


@functools.cache
def _layer_rules() -> dict:
    """The rules for a layer's fields, name -> (a key's type, its defaults): the keys
    every layer has (name, blend, fingers), and by name every number, flag and choice key
    of the layer types, regions and visual hints (``textures.keys``). A name two types bound
    differently is left out; one they bound alike in different units keeps both units
    for its messages, and the defaults of both."""
    from frictex.textures import keys
    from frictex.textures.schema import REQUIRED, Choice, Flag, Int, Num, NumList

    def rule(spec):  # what a spec checks, not what it documents or defaults to
        neutral = {"default": None, "doc": "", "rule": ""}
        if isinstance(spec, NumList):
            return dataclasses.replace(spec, item=rule(spec.item), **neutral)
        return dataclasses.replace(spec, **neutral, **({"unit": ""} if isinstance(spec, Num)
                                                        else {}))

    rules: dict = {name: (keys.COMMON[name], [keys.COMMON[name].default])
                   for name in ("name", "blend", "fingers")}
    clashing = set()
    for table in (keys.RECT_REGION, keys.DISC_REGION, keys.VISUAL, *keys.LAYER_KEYS.values()):
        for name, spec in table.items():
            if not isinstance(spec, Num | Int | NumList | Flag | Choice):
                continue
            known, defaults = rules.setdefault(name, (spec, []))
            if rule(known) != rule(spec):
                clashing.add(name)
                continue
            if isinstance(spec, Num) and spec.unit not in known.unit.split(" or "):
                known = dataclasses.replace(known, unit=f"{known.unit} or {spec.unit}")
            if spec.default is not REQUIRED and spec.default not in defaults:
                defaults.append(spec.default)
            rules[name] = (known, defaults)
    return {name: rule for name, rule in rules.items() if name not in clashing}


def read_trace(path: str | Path, *, strict: bool = False) -> Trace:
    """Read and validate a whole touch trace.

    Parameters
    ----------
    path : str or Path
        A trace CSV (columns ``t_s,finger,x_mm,y_mm`` and optionally ``force_n``,
        ``event``), or the name of a bundled trace, e.g. ``"swipe-40mms-50hz"``.
    strict : bool, optional
        Refuse a trace whose time goes back; by default samples up to 5 ms back are
        sorted into order and samples further back dropped.

    Returns
    -------
    Trace
        n touch samples: ``t_s`` (n,) s, ``finger`` (n,) ids, ``x_mm``, ``y_mm`` (n,) mm
        (origin top-left, y down), ``force_n`` (n,) N, ``event`` (n,) down/move/up codes.

    Raises
    ------
    InputError
        A :class:`TraceError`: no such file or bundled trace, or a file that is not a
        valid trace (the message names the file and the line).
    """
    from frictex.rendering.input.trace_file import read_trace as read
    from frictex.textures.library import resolve_trace
    path_like("path", path, "a trace CSV or a bundled trace's name")
    try:
        found = resolve_trace(path)
    except InputError as exc:  # the library's lookup says TextureError, for scenes too
        raise TraceError(str(exc)) from None
    return read(found, strict=flag("strict", strict))


def make_trace(t_s: npt.ArrayLike, finger: npt.ArrayLike, x_mm: npt.ArrayLike,
               y_mm: npt.ArrayLike, force_n: npt.ArrayLike | None = None,
               event: npt.ArrayLike | None = None) -> Trace:
    """A touch trace from arrays (or lists), checked as a trace file's rows are.

    Parameters
    ----------
    t_s : array_like of float, shape (n,)
        Sample times (s), not decreasing, within +-1e10 s.
    finger : array_like of int, shape (n,)
        Finger ids, integers from 0 to 2**31 - 1 (as Linux tracking ids).
    x_mm, y_mm : array_like of float, shape (n,)
        Positions (mm, screen origin top-left, y down), within +-1e5 mm.
    force_n : array_like of float, shape (n,), optional
        Normal force (N), 0 to 1000; 0.5 N where not given.
    event : array_like of int, shape (n,), optional
        :data:`DOWN` (0), :data:`MOVE` (1) or :data:`UP` (2) per sample; all ``MOVE`` where
        not given. As in a trace file, a finger's first sample (or its first after an
        ``UP``) becomes a ``DOWN``, and at most 20 fingers touch at once.

    Returns
    -------
    Trace
        The samples as float64 arrays (``finger`` int64, ``event`` int8).

    Raises
    ------
    InputError
        A :class:`TraceError`: no samples, arrays of different lengths or not
        one-dimensional, values that are not numbers, or the first sample breaking a rule
        (a NaN or infinite value, a value out of range, time going back, an unknown event
        code); the message names the field and the sample.
    """
    columns = {"t_s": t_s, "finger": finger, "x_mm": x_mm, "y_mm": y_mm, "force_n": force_n,
               "event": event}
    for name in ("t_s", "finger", "x_mm", "y_mm"):
        if columns[name] is None:
            raise TraceError(f"{_WHERE}: {name} is None: expected one number per sample, "
                             "shape (n,)")
    arrays = {name: None if values is None else _column(name, values)
              for name, values in columns.items()}
    code = arrays["event"]
    if code is not None:
        if code.dtype != np.int8:  # a code the cast to int8 would not keep is refused here
            with np.errstate(invalid="ignore"):  # NaN and inf: not kept
                bad = code != code.astype(np.int8)
            if bad.any():
                i = int(np.argmax(bad))
                raise TraceError(f"{_WHERE}: sample {i}: event is {code[i].item()!r}, expected "
                                 f"{DOWN} (down), {MOVE} (move) or {UP} (up)")
            arrays["event"] = code.astype(np.int8)
    return checked_trace(**arrays, where=_WHERE)


def checked(trace: Trace) -> Trace:
    """``trace`` as :func:`make_trace` checks it (a :class:`Trace` built by hand is not):
    what :func:`~frictex.replay` and :meth:`~frictex.Pipeline.process` run."""
    if not isinstance(trace, Trace):
        raise InputError(f"trace: expected a Trace (frictex.make_trace, frictex.read_trace), "
                         f"got {type(trace).__name__}")
    return make_trace(trace.t_s, trace.finger, trace.x_mm, trace.y_mm, trace.force_n, trace.event)


def _column(name: str, values: npt.ArrayLike) -> np.ndarray:
    """One field of a trace as a 1-D array of numbers (not yet checked against the rules)."""
    try:
        array = np.asarray(values)
    except (TypeError, ValueError):  # a ragged nesting
        raise TraceError(f"{_WHERE}: {name} is not an array of numbers: expected one "
                         "number per sample, shape (n,)") from None
    if array.ndim == 0:  # numpy makes a generator, a set or a number a 0-d array
        raise TraceError(f"{_WHERE}: {name}: expected an array or list of one number per "
                         f"sample, got {type(values).__name__}")
    if array.ndim != 1:
        raise TraceError(f"{_WHERE}: {name} has shape {array.shape}: expected one number per "
                         "sample, shape (n,)")
    if array.dtype.kind not in "iuf" and array.size:
        raise TraceError(f"{_WHERE}: {name} holds {array.dtype} values: expected numbers")
    _refuse_masked(name, values)
    return array


def _refuse_masked(name: str, values: npt.ArrayLike) -> None:
    """Refuse a numpy masked array with a masked value: ``np.asarray`` takes the value
    under the mask, which is not a sample."""
    if not isinstance(values, np.ma.MaskedArray):
        return
    masked = np.ma.getmaskarray(values)
    if masked.any():
        i = int(np.argmax(masked))
        raise TraceError(f"{_WHERE}: {name}: sample {i} is masked: expected a number at "
                         f"every sample (fill it, or leave the sample out)")


def synth_trace(kind: str, *, rate_hz: float | None = None, duration_s: float = 2.0,
                speed_mm_s: float = 40.0, x0_mm: float | None = None,
                y0_mm: float | None = None, area_mm: tuple[float, float] | None = None,
                angle_deg: float = 0.0, length_mm: float = 80.0, radius_mm: float = 20.0,
                noise_mm: float = 0.0, jitter_s: float = 0.0, force_n: float | None = None,
                peaks_n: Sequence[float] = (1.0, 0.95, 1.1), force_noise_n: float = 0.03,
                seed: int | np.integer = 0) -> Trace:
    """A synthetic touch trace, sampled as a touch screen reports it (``frictex trace synth``).

    Parameters
    ----------
    kind : str
        ``swipe`` (a straight line at constant speed),
        ``back-and-forth``, ``circle``, ``human`` (strokes and pauses, seeded),
        ``human-varied``, or ``press`` (a still finger whose normal force rises to each of
        ``peaks_n`` and back, for key-click scenes).
    rate_hz : float, optional
        Touch sampling rate (Hz); default 50 (seed 003's screen), for ``press`` 100 (the
        force sensor's rate, as ``frictex trace synth press``).
    duration_s : float, optional
        Length of a finger path (s); a press lasts as long as its peaks take.
    speed_mm_s : float, optional
        Finger speed (mm/s); for ``human``, the typical peak speed.
    x0_mm, y0_mm : float, optional
        Start position (mm); for ``press``, where the finger presses. Default (14, 32.4);
        for ``press`` (70, 15), on keyclick-ring's button; for ``human`` and
        ``human-varied`` 30 % and 50 % across ``area_mm``, which the start must lie in.
    area_mm : (float, float), optional
        ``human`` and ``human-varied`` only: the area (width, height in mm, from 0, 0) the
        finger wanders in, more than 16 mm each way; default 108 x 64.8 (the demo's
        display).
    angle_deg : float, optional
        Direction of travel, from +x towards +y (degrees).
    length_mm : float, optional
        Stroke length of ``back-and-forth`` (mm).
    radius_mm : float, optional
        Radius of ``circle`` (mm).
    noise_mm : float, optional
        Position noise, standard deviation (mm).
    jitter_s : float, optional
        Timestamp jitter, standard deviation (s).
    force_n : float, optional
        Normal force (N), default 0.5; for ``press``, the force at touch-down, default 0.1.
    peaks_n : sequence of float, optional
        ``press`` only: the peak normal force of each press (N).
    force_noise_n : float, optional
        ``press`` only: force sensor noise, standard deviation (N).
    seed : int, optional
        Random seed (human motion, noise).

    Returns
    -------
    Trace
        One finger (id 0): a down, moves, an up; times in s from 0.

    Raises
    ------
    InputError
        An unknown kind, a negative seed, or a value that is not a number or is beyond
        what ``frictex trace synth`` accepts for its option (``LIMITS`` and
        ``MAX_SAMPLES`` in ``app/commands/trace.py``), or a path that would leave the
        +-1e5 mm a trace's positions stay within; the message names the arguments.
    """
    if kind not in SYNTH_KINDS:
        raise InputError(f"unknown trace kind {kind!r}; expected one of {', '.join(SYNTH_KINDS)}")
    # ``frictex trace synth``'s limits and defaults
    from frictex.app.commands.trace import LIMITS, MAX_SAMPLES, motion_defaults

    def option(name: str, value: float, key: str, positive: bool = False) -> float:
        low, high, unit = LIMITS[key]
        return real(name, value, unit, (low, high), positive=positive)

    default_rate_hz, default_force_n, start_mm = motion_defaults(kind)
    rate_hz = option("rate_hz", default_rate_hz if rate_hz is None else rate_hz, "rate",
                     positive=True)
    from frictex.rendering.input.trace_synth import HUMAN_AREA_MM, START_MM
    if area_mm is not None and kind not in ("human", "human-varied"):
        raise InputError(f"area_mm: only the human motions wander in an area; a {kind} starts "
                         "at x0_mm, y0_mm")
    if kind not in ("human", "human-varied"):
        start_mm = start_mm or START_MM
        x0_mm = start_mm[0] if x0_mm is None else x0_mm
        y0_mm = start_mm[1] if y0_mm is None else y0_mm
    x0_mm = None if x0_mm is None else option("x0_mm", x0_mm, "x0")
    y0_mm = None if y0_mm is None else option("y0_mm", y0_mm, "y0")
    if area_mm is None:
        area_mm = HUMAN_AREA_MM
    elif isinstance(area_mm, str | bytes) or not isinstance(area_mm, Iterable) or len(
            tuple(area_mm)) != 2:
        raise InputError(f"area_mm: expected (width, height) in mm, got {area_mm!r}")
    area_mm = tuple(option(f"area_mm[{i}]", size, "area", positive=True)
                    for i, size in enumerate(area_mm))
    force_n = option("force_n", default_force_n if force_n is None else force_n, "force")
    seed = whole("seed", seed, "", (0, math.inf))
    if kind == "press":
        force_noise_n = option("force_noise_n", force_noise_n, "force_noise")
        if isinstance(peaks_n, str | bytes) or not isinstance(peaks_n, Iterable):
            raise InputError(f"peaks_n: expected a sequence of peak forces (N), got "
                             f"{type(peaks_n).__name__}")
        peaks_n = tuple(peaks_n)
        if not peaks_n:
            raise InputError("peaks_n: no peaks; expected one or more peak forces (N)")
        if len(peaks_n) * rate_hz > MAX_SAMPLES:  # a press lasts over a second
            raise InputError(f"peaks_n: {len(peaks_n)} presses at rate_hz={rate_hz:g} would "
                             f"exceed {MAX_SAMPLES:,} samples")
        peaks_n = tuple(option(f"peaks_n[{i}]", peak, "peaks") for i, peak in enumerate(peaks_n))
        from frictex.rendering.input.press_synth import press_trace
        return press_trace(peaks_n=peaks_n, x_mm=x0_mm, y_mm=y0_mm, rate_hz=rate_hz,
                           touch_n=force_n, noise_n=force_noise_n, seed=seed)
    speed_mm_s = option("speed_mm_s", speed_mm_s, "speed", positive=True)
    duration_s = option("duration_s", duration_s, "duration", positive=True)
    angle_deg = option("angle_deg", angle_deg, "angle")
    length_mm = option("length_mm", length_mm, "length", positive=True)
    radius_mm = option("radius_mm", radius_mm, "radius", positive=True)
    noise_mm = option("noise_mm", noise_mm, "noise")
    jitter_s = option("jitter_s", jitter_s, "jitter")
    if rate_hz * duration_s > MAX_SAMPLES:
        raise InputError(f"rate_hz={rate_hz:g} Hz over duration_s={duration_s:g} s is "
                         f"{rate_hz * duration_s:,.0f} samples; at most {MAX_SAMPLES:,}")
    from frictex.rendering.input.trace_synth import make_motion, sample
    motion = make_motion(kind, speed_mm_s=speed_mm_s, duration_s=duration_s, x0_mm=x0_mm,
                         y0_mm=y0_mm, angle_deg=angle_deg, length_mm=length_mm,
                         radius_mm=radius_mm, area_mm=area_mm, seed=seed)
    return sample(motion, rate_hz, noise_mm=noise_mm, jitter_s=jitter_s, force_n=force_n,
                  seed=seed)
