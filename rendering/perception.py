"""What a finger can feel: a scene's features, and pairs of stimuli, against published
thresholds of touch.

Every check warns; none refuses a scene. The thresholds, with their sources, are in one
table, :data:`THRESHOLDS`, and each finding names the one it is below:

- ``weber``: a layer's friction contrast, (mu'_high - mu'_low) / mu'_high over what it
  asks for (``layer.mu_range``), under 0.11 is not detected as a change of friction
  (a Weber fraction: Gueorguiev et al. 2017, the change relative to the level before
  it, so a drop relative to the higher level). Layers with no contrast (force layers,
  mu' 1 everywhere) are not features of friction and are left out.
- ``touch`` (a limit of rendering, not of perception: :data:`RENDERING_KINDS`): a
  periodic layer (grating, waveform) of period p below the spatial Nyquist period of
  the touch samples, p < 2 v / f_touch: at a finger speed v the touch screen reports
  the finger every v / f_touch mm, and a period shorter than two of those steps cannot
  be placed by the samples. What that does depends on the layer's renderer, and the
  finding says which: SHO-held (the map at the last touch sample) aliases it; SHO-
  predicted plays it between samples and jumps its phase at each; the hybrid and SHT,
  which synthesise the period from the finger's velocity and exist for such periods,
  play it (felt), registered with the drawing only as closely as the samples allow.
  At the typical 100 mm/s and 60 Hz: 3.33 mm.
- ``temporal``: a periodic layer whose fundamental at the typical speed, f = v / p (Hz),
  is above 800 Hz (p < 0.125 mm at 100 mm/s): frictex's own limit, a margin above the
  500 Hz up to which Bolanowski et al. 1988 measured the skin's vibration channels.
- ``period``, ``weber`` and ``event`` for pairs (:func:`compare_values`,
  :func:`compare_scenes`): two stimuli whose every difference is below its
  discrimination threshold, periods within 14 % of the smaller, friction contrasts, or
  the friction levels two depths or clip levels play (mu' = 1 - depth on a grating),
  within 11 % of the larger, and clip events' lengths within 2.3 ms of each other (the
  difference in duration or transition time of short friction drops told apart:
  Gueorguiev et al. 2019; it bounds no single event, which the check leaves alone). A
  design of levels measures that threshold and needs levels below it: it is compared
  by its level farthest from the reference (``app.experiment.perception_check``).
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from frictex.device.errors import InputError

#: a finger speed typical of exploring a texture (mm/s)
SPEED_MM_S = 100.0
#: a common touch screen's report rate (Hz)
TOUCH_HZ = 60.0
#: findings about how a layer renders, not about what a finger can feel
RENDERING_KINDS = frozenset({"touch"})


@dataclass(frozen=True)
class Threshold:
    """A published threshold: ``value`` in ``unit``, what it bounds, and its source."""

    value: float
    unit: str
    what: str
    source: str


THRESHOLDS: dict[str, Threshold] = {
    "weber": Threshold(0.11, "", "Weber fraction of a friction change, dmu'/mu'",
                       "Gueorguiev et al. 2017, J R Soc Interface 14:20170641"),
    # the paper's abstract: "a relative difference of 14% in spatial period was required to
    # discriminate two periodic gratings"; neither the code nor the seed papers name its
    # authors, year or venue
    "period": Threshold(0.14, "", "discrimination of grating periods, dp/p",
                        'the paper "Tactile perception of virtual edges and gratings displayed '
                        'by friction modulation via ultrasonic actuation" (its abstract; '
                        'authors, year and venue not given here)'),
    # a difference threshold between two stimuli, not the shortest drop felt: the abstract
    # reports 2.3-2.4 ms for the transition time and for the duration of short square
    # reductions; applied to events of any length, taking longer ones to need no smaller
    # a difference
    "event": Threshold(0.0023, "s", "difference in length of two friction drops told apart",
                       "Gueorguiev et al. 2019, IEEE Trans Haptics 12(2):179-188 (transition "
                       "time and duration of short ultrasonic square reductions of friction)"),
    # Bolanowski et al. measured vibrotactile thresholds up to 500 Hz ("over 500 Hz" for
    # the P channel); 800 Hz is not in the paper: it is frictex's own margin above that
    # range, so that a warning means a frequency well past every measured channel
    "temporal": Threshold(800.0, "Hz", "texture frequency limit",
                          "frictex's own limit, above the 500 Hz that vibrotactile thresholds "
                          "were measured to in Bolanowski et al. 1988, J Acoust Soc Am "
                          "84:1680"),
    "touch": Threshold(2.0 * SPEED_MM_S / TOUCH_HZ, "mm",
                       f"spatial Nyquist period of the touch samples, 2 v / f_touch (v "
                       f"{SPEED_MM_S:g} mm/s, f_touch {TOUCH_HZ:g} Hz)",
                       "sampling theorem; typical touch rate and exploration speed"),
}


@dataclass(frozen=True)
class Finding:
    """One feature beyond a threshold (below it; for ``temporal``, above): ``kind`` (a key of :data:`THRESHOLDS`), where
    (``where``: a layer's or a pair's name), its ``value`` in the threshold's unit and
    the sentence to print."""

    kind: str
    where: str
    value: float
    message: str

    @property
    def threshold(self) -> Threshold:
        return THRESHOLDS[self.kind]


def _below(kind: str, where: str, value: float, text: str, side: str = "below") -> Finding:
    t = THRESHOLDS[kind]
    return Finding(kind, where, value, f"{where}: {text}, {side} the {t.what} {t.value:.4g}"
                                       f"{' ' + t.unit if t.unit else ''} ({t.source})")


def contrast(layer) -> float:
    """A layer's friction contrast, (mu'_high - mu'_low) / mu'_high (0 for none)."""
    low, high = layer.mu_range
    return 0.0 if high <= 0.0 else (high - low) / high


def _period(layer) -> float | None:
    return layer.period_mm if layer.is_periodic else None


def _under_touch(layer, where: str, period: float, renderer: str | None = None) -> Finding:
    """The ``touch`` finding of ``layer`` (``where``) of period ``period`` (mm): the limit
    and what its renderer makes of it (its class's ``fine_period``; ``sho``: the default
    SHO variant's). ``renderer``: the one that plays it (an experiment stimulus's), else
    the layer's own ``render``."""
    from frictex.rendering.renderers import DEFAULT_SHO, RENDERERS
    from frictex.textures.model import SHO
    t = THRESHOLDS["touch"]
    render = renderer or layer.render
    render = DEFAULT_SHO if render == SHO else render
    effect = getattr(RENDERERS.get(render), "fine_period", None) or (
        f"renderer {render} may alias it where it reads the map at the touch samples; "
        f"render = \"hybrid\" plays it from the finger's velocity")
    return Finding("touch", where, period,
                   f"{where}: period {period:g} mm, below the {t.what} {t.value:.4g} {t.unit} "
                   f"({t.source}): {effect}")


def scene_findings(scene, renderer: str | None = None) -> list[Finding]:
    """The features of ``scene`` below a threshold of :data:`THRESHOLDS` (module
    docstring), in layer order; ``renderer``: the one its periodic layers are played by
    (an experiment stimulus's), else each layer's own ``render``."""
    out = []
    for layer in scene.layers:
        where = f'layer "{layer.name}"'
        c = contrast(layer)
        if 0.0 < c < THRESHOLDS["weber"].value:
            out.append(_below("weber", where, c, f"friction contrast (mu'_high - "
                                                 f"mu'_low)/mu'_high {c:.3g}"))
        period = _period(layer)
        if period is not None:
            if period < THRESHOLDS["touch"].value:
                out.append(_under_touch(layer, where, period, renderer))
            hz = SPEED_MM_S / period
            if hz > THRESHOLDS["temporal"].value:
                out.append(_below("temporal", where, hz,
                                  f"period {period:g} mm plays at {hz:.4g} Hz at "
                                  f"{SPEED_MM_S:g} mm/s (f = v / p)", side="above"))
    return out


#: what the threshold of each relative difference divides by: the Weber fraction is a
#: change of friction relative to the level before it (a drop: the higher level, as
#: :func:`contrast`); a period's dp/p is relative to the reference, the smaller period
#: of a design whose levels lie above it (the period source's abstract gives "a relative
#: difference of 14 %" without naming the denominator; dp/p of the reference is the
#: usual form of a discrimination threshold)
_RELATIVE_TO = {"weber": max, "period": min}


def relative_difference(kind: str, a: float, b: float) -> float:
    """|a - b| over the value the threshold ``kind`` (``weber`` or ``period``) is
    relative to: the larger of ``a`` and ``b`` for ``weber``, the smaller for ``period``
    (0 for equal values)."""
    if a == b:
        return 0.0
    return abs(a - b) / _RELATIVE_TO[kind](abs(a), abs(b))


def _relative(kind: str, d: float, of: str) -> str:
    """A relative difference ``d`` of two values of ``of`` as a percentage and as a
    fraction named for what it is: ``2 % (dp/p 0.02)`` for periods (the fraction the
    period threshold is given in), ``6.67 % (d(contrast)/contrast 0.0667)`` for friction
    contrasts set against the Weber fraction dmu'/mu'."""
    symbol = "dp/p" if kind == "period" else f"d({of})/{of}"
    return f"{d * 100:.3g} % ({symbol} {d:.3g})"


#: what a stimulus parameter (``vary``) is compared by: its threshold's key
VARY_THRESHOLD = {"period_mm": "period", "depth": "weber", "level": "weber"}


def friction_level(vary: str, value: float, mu_high: float = 1.0,
                   clip_depth: float = 1.0, clip_level: float = 1.0) -> float:
    """The mu' a finger feels at a stimulus's ``depth`` or clip ``level`` ``value``: a
    grating's or shape's low level mu_high - depth (``app.experiment.stimuli``'s
    PARAMETERS; ``mu_high`` 1 where the layer has none), a clip's drop
    1 - clip_depth * level (``textures.clips``); a clip's ``depth`` drops mu' by
    depth * ``clip_level``, its weakest event's level (1 for a layer not a clip)."""
    if vary == "level":
        return 1.0 - clip_depth * value
    return mu_high - clip_level * value


def compare_values(vary: str, a: float, b: float, where: str, mu_high: float = 1.0,
                   clip_depth: float = 1.0, clip_level: float = 1.0) -> Finding | None:
    """Two stimuli that differ only in ``vary`` (``period_mm``, ``depth`` or a clip's
    ``level``), by less than its threshold; None if they differ by more, or not at all,
    or ``vary`` has no published threshold (a renderer). Periods are compared as they
    are (dp/p); depths and levels by the friction levels they play (:func:`friction_level`),
    as the Weber fraction dmu'/mu' is about friction, not about depths: a level of mu' 0 or
    below is a step no fraction of friction bounds (None). A value not finite, or below 0
    (a period: not above 0), is an :class:`InputError`."""
    period = vary == "period_mm"
    for value in (a, b):
        if not (math.isfinite(value) and (value > 0.0 if period else value >= 0.0)):
            raise InputError(f"{where}: {vary} {value!r}: expected a finite "
                             f"{'period above 0' if period else 'value of at least 0'}")
    kind = VARY_THRESHOLD.get(vary)
    if kind is None or a == b:
        return None
    if kind == "period":
        d = relative_difference(kind, a, b)
        text = f"{vary} {a:g} and {b:g} differ by {_relative(kind, d, vary)}"
    else:
        mu_a, mu_b = (friction_level(vary, v, mu_high, clip_depth, clip_level)
                      for v in (a, b))
        if min(mu_a, mu_b) <= 0.0:
            return None
        d = relative_difference(kind, mu_a, mu_b)
        text = (f"{vary} {a:g} and {b:g} play friction levels mu' {mu_a:.4g} and {mu_b:.4g}, "
                f"which differ by {d * 100:.3g} % (dmu'/mu' {d:.3g})")
    if d >= THRESHOLDS[kind].value:
        return None
    return _below(kind, where, d, text)


def _differences(x, y) -> list[tuple[str, float, str]] | None:
    """The differences a threshold bounds between layers ``x`` and ``y`` of one type, as
    (its key, the difference in its unit, the sentence): periods and friction contrasts
    relative (:func:`relative_difference`), clip events' lengths in s, event by event.
    None where they differ in a way no threshold bounds: a contrast or period of 0
    against one above it, clips whose events differ in number or kind."""
    px, py = _period(x), _period(y)
    pairs = ([("period", "period", px, py)] if px is not None and py is not None else []) + [
        ("weber", "contrast", contrast(x), contrast(y))]
    out = []
    for kind, of, u, v in pairs:
        if not (u > 0.0 and v > 0.0 or u == v):
            return None
        d = relative_difference(kind, u, v)
        out.append((kind, d, f'layer "{x.name}" {of} {u:.4g} and {v:.4g} differ by '
                             f'{_relative(kind, d, of)}'))
    cx, cy = getattr(x, "clip", None), getattr(y, "clip", None)
    if cx is None or cy is None:
        return out
    if [e.kind for e in cx.events] != [e.kind for e in cy.events]:
        return None
    for i, (ex, ey) in enumerate(zip(cx.events, cy.events)):
        lx, ly = cx.event_length_s(ex), cy.event_length_s(ey)
        out.append(("event", abs(lx - ly), f'layer "{x.name}" event {i + 1} lengths '
                                           f'{lx * 1e3:.4g} and {ly * 1e3:.4g} ms differ by '
                                           f'{abs(lx - ly) * 1e3:.3g} ms'))
    return out


def compare_scenes(a, b, where: str) -> Finding | None:
    """Two scenes whose layers match one to one (same count and types) and whose every
    difference of period, friction contrast and clip event length is below its
    threshold, some above 0: the finding for the largest of them (relative to its
    threshold). None if the scenes differ otherwise (layer types, count, clip events'
    number or kinds) or by more."""
    if len(a.layers) != len(b.layers) or any(type(x) is not type(y)
                                             for x, y in zip(a.layers, b.layers)):
        return None
    steps = []
    for x, y in zip(a.layers, b.layers):
        found = _differences(x, y)
        if found is None:
            return None
        steps += found
    ratios = [d / THRESHOLDS[kind].value for kind, d, _ in steps]
    if not ratios or not 0.0 < max(ratios) < 1.0:
        return None
    kind, d, text = steps[ratios.index(max(ratios))]
    return _below(kind, where, d, f"{text} (the largest difference between them)")
