"""A replay's summary as typed, frozen objects: what ``summary.json`` holds, field by field.

``app/engine/SUMMARY.md`` documents every key; each class here is one object of that
page, its fields the object's keys in the order ``summary.json`` writes them, so that
``Summary.from_dict(doc).to_dict() == doc`` and ``json.dumps`` of either gives the same
text. Sections whose keys are data or documented elsewhere (``forces``, ``device``,
``control``, the per-stage and per-layer seconds) stay mappings: dicts that cannot be
changed (:class:`ReadOnlyDict`, nested ones too, their lists :class:`ReadOnlyList`), so that a summary is
not changed after it is made; they are still dicts (``json.dumps`` takes them), and
:meth:`Summary.to_dict` gives plain copies. An optional section
(``trace.time_order``, ``forces``, ``control``, ``device``) is None when the run has none,
and is left out of :meth:`Summary.to_dict`, as out of ``summary.json``.

Standard library only: importing these types loads no numeric library.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

#: marks a field left out of ``to_dict`` when it is None (an optional section)
_OPTIONAL = {"optional": True}


@dataclass(frozen=True)
class LayerInfo:
    """One layer of the scene replayed.

    Attributes
    ----------
    name : str
        The layer's name in the texture file.
    type : str
        Its type (``grating``, ``disc``, ...).
    renderer : str
        The renderer it ran with (``sho-predicted``, ``sht``, ``hybrid``, ...).
    """

    name: str
    type: str
    renderer: str


@dataclass(frozen=True)
class SceneInfo:
    """The scene replayed (``summary.json``'s ``scene``).

    Attributes
    ----------
    name : str
        The scene's name.
    path : str or None
        Its texture file (None for a scene built in memory).
    device : str
        The device profile (``[device] profile``).
    layers : tuple of LayerInfo
        Its layers, in drawing order.
    """

    name: str
    path: str | None
    device: str
    layers: tuple[LayerInfo, ...]


@dataclass(frozen=True)
class TimeOrderInfo:
    """Where the trace's time went back (a trace read from a file only).

    Attributes
    ----------
    tolerance_s : float
        Samples up to this much earlier (s) were sorted into order.
    reordered : int
        Samples sorted into order.
    dropped : int
        Samples dropped (further back than ``tolerance_s``).
    """

    tolerance_s: float
    reordered: int
    dropped: int


@dataclass(frozen=True)
class GapInfo:
    """Gaps between touch samples longer than ``limit_s``, taken as lifts and skipped.

    Attributes
    ----------
    limit_s : float or None
        The longest gap output as it is (s).
    count : int
        Gaps longer than that.
    skipped_s : float
        Output skipped there (s): ``t_s`` jumps.
    """

    limit_s: float | None
    count: int
    skipped_s: float


@dataclass(frozen=True, kw_only=True)
class TraceInfo:
    """The touch trace replayed (``summary.json``'s ``trace``).

    Attributes
    ----------
    path : str or None
        Its file, absolute with links resolved; None for a trace given as a Trace
        object (``frictex.read_trace``'s too: a Trace keeps no file name).
    samples : int
        Touch samples read.
    fingers : tuple of int
        Finger ids seen: the 100 lowest.
    finger_count : int or None
        How many distinct finger ids the trace holds (None in summaries before it).
    duration_s : float
        Last sample time minus first (s).
    touch_rate_hz : float or None
        Median touch sample rate (Hz).
    touches_within_a_block : int or None
        Touches that began and lifted within one output block, so in contact for no
        output sample (None in summaries before it).
    touch_samples_off_display : int or None
        Touch samples outside the display's area, held at its edge (None in summaries
        before it).
    time_order : TimeOrderInfo or None
        Where time went back; None for a trace given as a Trace object
        (``frictex.read_trace`` sorted it as it read it, and keeps no count).
    gaps : GapInfo
        Long gaps taken as lifts.
    """

    path: str | None
    samples: int
    fingers: tuple[int, ...]
    finger_count: int | None = field(default=None, metadata=_OPTIONAL)
    duration_s: float
    touch_rate_hz: float | None
    touches_within_a_block: int | None = field(default=None, metadata=_OPTIONAL)
    touch_samples_off_display: int | None = field(default=None, metadata=_OPTIONAL)
    time_order: TimeOrderInfo | None = field(default=None, metadata=_OPTIONAL)
    gaps: GapInfo


@dataclass(frozen=True)
class OutputInfo:
    """The output stream (``summary.json``'s ``output``).

    Attributes
    ----------
    rate_hz : float
        Output sample rate (Hz).
    block_size : int
        Samples per block.
    samples : int
        Output samples per channel (skipped gaps not counted).
    duration_s : float
        ``samples / rate_hz`` (s).
    channels : tuple of str
        Actuator channel names (the ``commands`` table's amplitude columns, in um).
    format : str
        ``csv``, ``npz`` or ``parquet``; ``memory`` for tables kept in memory.
    files : tuple of str
        The table files written (none in memory).
    """

    rate_hz: float
    block_size: int
    samples: int
    duration_s: float
    channels: tuple[str, ...]
    format: str
    files: tuple[str, ...]


@dataclass(frozen=True, kw_only=True)
class Counts:
    """What happened, counted (``summary.json``'s ``counts``).

    Attributes
    ----------
    blocks : int
        Blocks run.
    contact_samples : int
        Output samples with at least one finger touching.
    jumps : int
        Finger jumps treated as lift and touch.
    out_of_order : int
        Touch samples the tracker dropped as out of order.
    max_amplitude_um : float or None
        Largest channel command (um, zero-to-peak).
    actuator_limited : int
        Samples where an actuator limit changed the actuation's solution.
    modal_capped : int or None
        Samples whose modal solve served two or more fingers and was regularised: the
        fingers could not be given independent amplitudes (seed 001, eq 8). None in
        summaries before it (version 6): not counted, which is not none capped.
    off_structure : int
        Finger samples off the vibrating structure (held at its edge).
    modal_unserved : int or None
        Finger samples touching but not served: beyond the p longest-touching fingers
        that a scene's p modes serve, they feel the served ones' vibration. None in
        summaries before it (version 7): not counted, which is not none unserved.
    """

    blocks: int
    contact_samples: int
    jumps: int
    out_of_order: int
    max_amplitude_um: float | None
    actuator_limited: int
    modal_capped: int | None = field(default=None, metadata=_OPTIONAL)
    off_structure: int
    modal_unserved: int | None = field(default=None, metadata=_OPTIONAL)


@dataclass(frozen=True)
class Clamps:
    """Samples each guard of the friction inversion changed (``device/friction.py``).

    Attributes
    ----------
    above_one : int
        Targets above 1 (w = 0).
    unreachable : int
        Targets below the lowest reachable mu' (w = limit), or forces out of a wave's reach.
    force_beyond_model : int
        Normal forces beyond the friction model's validity.
    bad_force : int
        Normal forces NaN, infinite or negative (nominal force used).
    nonfinite_target : int
        Targets NaN or infinite (w = 0).
    """

    above_one: int
    unreachable: int
    force_beyond_model: int
    bad_force: int
    nonfinite_target: int

    @property
    def total(self) -> int:
        """All clamped samples, every guard together."""
        return sum(dataclasses.astuple(self))


@dataclass(frozen=True)
class FingerErrors:
    """How far one finger's achieved amplitude was from the wanted one while touching.

    Attributes
    ----------
    contact_samples : int
        Output samples the finger touched.
    amplitude_error_rms_um : float or None
        RMS of achieved minus wanted amplitude (um).
    amplitude_error_max_um : float or None
        Largest absolute difference (um).
    """

    contact_samples: int
    amplitude_error_rms_um: float | None
    amplitude_error_max_um: float | None


@dataclass(frozen=True)
class Timings:
    """How long the run took; differs between two otherwise identical runs.

    Attributes
    ----------
    wall_s : float
        Wall time from loading the inputs to the last table committed (s).
    setup_s : float
        The part of ``wall_s`` spent loading the scene and building the pipeline (s).
    compute_s : float
        The pipeline's compute time (s).
    x_realtime_end_to_end : float or None
        Output seconds over ``wall_s - setup_s``.
    x_realtime_with_setup : float or None
        Output seconds over ``wall_s``.
    x_realtime_compute : float or None
        Output seconds over ``compute_s``.
    loop_s : Mapping of str to float
        The run loop's wall time by part (s): ``read``, ``compute``, ``write``, ``commit``.
    stages_s : Mapping of str to float
        Compute time per pipeline stage (s).
    layers_s : Mapping of str to float
        Compute time per layer, by layer name (s).
    """

    wall_s: float
    setup_s: float
    compute_s: float
    x_realtime_end_to_end: float | None
    x_realtime_with_setup: float | None
    x_realtime_compute: float | None
    loop_s: Mapping[str, float]
    stages_s: Mapping[str, float]
    layers_s: Mapping[str, float]

    def __post_init__(self) -> None:
        _freeze_mappings(self)


@dataclass(frozen=True, kw_only=True)
class Summary:
    """A replay's summary: ``summary.json`` as typed fields (``app/engine/SUMMARY.md``).

    Attributes
    ----------
    summary_version : int
        The schema's version.
    scene : SceneInfo
    trace : TraceInfo
    output : OutputInfo
    counts : Counts
    clamps : Clamps
    layer_clipped : Mapping of str to int
        Per layer name, for the layers that limit their own mu' (``recorded``: mu_min and
        mu_max; ``clip``: its events' level sum at 1; a grating or waveform rendered by SHT
        or the hybrid: its texture past the output's Nyquist frequency, played as its
        mean): the touching finger samples (friction-table rows) whose mu' those limits
        clipped.
    warnings : tuple of str
        One sentence per thing changed, dropped or not played.
    fingers : Mapping of int to FingerErrors
        Per finger id: the ``MAX_LISTED`` (100) with the most contact samples.
    fingers_others : Mapping or None
        The fingers not listed, aggregated (``fingers``: how many ids); None when every
        finger is listed.
    forces : Mapping or None
        Travelling-wave profiles only: per finger id (a string) the force errors (N).
    control : Mapping or None
        With the friction loop on only: the loop's report.
    device : Mapping or None
        Streaming to a device only: the link's counters (``device/PROTOCOL.md`` section 6).
    timings : Timings
    """

    summary_version: int
    scene: SceneInfo
    trace: TraceInfo
    output: OutputInfo
    counts: Counts
    clamps: Clamps
    layer_clipped: Mapping[str, int]
    warnings: tuple[str, ...]
    fingers: Mapping[int, FingerErrors]
    fingers_others: Mapping[str, Any] | None = field(default=None, metadata=_OPTIONAL)
    forces: Mapping[str, Any] | None = field(default=None, metadata=_OPTIONAL)
    control: Mapping[str, Any] | None = field(default=None, metadata=_OPTIONAL)
    device: Mapping[str, Any] | None = field(default=None, metadata=_OPTIONAL)
    timings: Timings

    def __post_init__(self) -> None:
        _freeze_mappings(self)

    @classmethod
    def from_dict(cls, doc: Mapping[str, Any]) -> Summary:
        """The summary of a ``summary.json`` document (as ``json.load`` gives it).

        Raises
        ------
        KeyError
            A required key is missing.
        """
        return _build(cls, doc)

    def to_dict(self) -> dict[str, Any]:
        """The ``summary.json`` document: plain dicts, lists, str, int, float and None."""
        return _plain(self)


def _refuse(self, *args, **kwargs):
    raise TypeError("a summary's data is read-only: change a copy, summary.to_dict() (dict(...) "
                    "and list(...) copy one level only)")


class ReadOnlyDict(dict):
    """A dict whose items cannot be set, deleted or updated (a ``TypeError``); a
    summary's mappings. Still a dict: ``json.dumps`` and ``isinstance(d, dict)`` take it;
    ``dict(d)`` is a copy of its top level to change."""

    __setitem__ = __delitem__ = __ior__ = _refuse
    clear = pop = popitem = setdefault = update = _refuse

    def __reduce__(self):  # pickle and copy rebuild it whole, not item by item
        return ReadOnlyDict, (dict(self),)


class ReadOnlyList(list):
    """A list that cannot be changed (a ``TypeError``); the lists in a summary's mappings
    (a loop's ``messages``). Still a list: it equals the list ``summary.json`` holds."""

    __setitem__ = __delitem__ = __iadd__ = __imul__ = _refuse
    append = extend = insert = pop = remove = reverse = sort = clear = _refuse

    def __reduce__(self):
        return ReadOnlyList, (list(self),)


def _freeze_mappings(obj) -> None:
    """Replace each mapping field of the frozen dataclass ``obj`` by a read-only copy
    (:func:`_frozen`), so that neither the object nor its :meth:`Summary.to_dict` can be
    changed through it."""
    for f in dataclasses.fields(obj):
        value = getattr(obj, f.name)
        if isinstance(value, Mapping):
            object.__setattr__(obj, f.name, _frozen(value))


def _frozen(value):
    """``value`` with every mapping inside it a :class:`ReadOnlyDict` copy and every list
    a :class:`ReadOnlyList` one."""
    if isinstance(value, Mapping):
        return ReadOnlyDict({k: _frozen(v) for k, v in value.items()})
    if isinstance(value, list):
        return ReadOnlyList(_frozen(v) for v in value)
    if isinstance(value, tuple):
        return tuple(_frozen(v) for v in value)
    return value


def _plain(value):
    if dataclasses.is_dataclass(value):
        return {f.name: _plain(getattr(value, f.name)) for f in dataclasses.fields(value)
                if not (f.metadata.get("optional") and getattr(value, f.name) is None)}
    if isinstance(value, Mapping):
        return {str(k): _plain(v) for k, v in value.items()}
    if isinstance(value, (list, tuple)):
        return [_plain(v) for v in value]
    return value


def _build(cls, doc: Mapping[str, Any]):
    hints = typing.get_type_hints(cls)
    return cls(**{f.name: _convert(hints[f.name], doc[f.name]) for f in dataclasses.fields(cls)
                  if f.name in doc or not f.metadata.get("optional")})


def _convert(hint, value):
    """``value`` (from JSON) as the type ``hint`` names."""
    if value is None:
        return None
    origin = typing.get_origin(hint)
    args = typing.get_args(hint)
    if origin in (typing.Union, types.UnionType):
        return _convert(next(a for a in args if a is not type(None)), value)
    if dataclasses.is_dataclass(hint):
        return _build(hint, value)
    if origin is tuple:
        return tuple(_convert(args[0], v) for v in value)
    if origin is Mapping and args[0] is int:
        return {int(k): _convert(args[1], v) for k, v in value.items()}
    return value
