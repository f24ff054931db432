"""The inputs of a replay: scenes, recorded traces, synthetic traces."""

from __future__ import annotations

from collections.abc import Sequence
from pathlib import Path

from frictex.device.errors import InputError
from frictex.rendering.input.trace_file import Trace
from frictex.rendering.input.trace_synth import MOTIONS
from frictex.textures.model import Scene

#: the kinds :func:`synth_trace` makes: finger paths, and ``press`` (a still finger pressing)
SYNTH_KINDS = (*MOTIONS, "press")


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
    """
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene as load
    return load(resolve_scene(name_or_path))


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
        No such file or bundled trace, or a file that is not a valid trace (the message
        names the file and the line).
    """
    from frictex.rendering.input.trace_file import read_trace as read
    from frictex.textures.library import resolve_trace
    return read(resolve_trace(path), strict=strict)


def synth_trace(kind: str, *, rate_hz: float = 50.0, duration_s: float = 2.0,
                speed_mm_s: float = 40.0, x0_mm: float = 14.0, y0_mm: float = 32.4,
                angle_deg: float = 0.0, length_mm: float = 80.0, radius_mm: float = 20.0,
                noise_mm: float = 0.0, jitter_s: float = 0.0, force_n: float = 0.5,
                peaks_n: Sequence[float] = (1.0, 0.95, 1.1), force_noise_n: float = 0.03,
                seed: int = 0) -> Trace:
    """A synthetic touch trace, sampled as a touch screen reports it (``frictex trace synth``).

    Parameters
    ----------
    kind : str
        ``swipe`` (a straight line at constant speed),
        ``back-and-forth``, ``circle``, ``human`` (strokes and pauses, seeded),
        ``human-varied``, or ``press`` (a still finger whose normal force rises to each of
        ``peaks_n`` and back, for key-click scenes).
    rate_hz : float, optional
        Touch sampling rate (Hz).
    duration_s : float, optional
        Length of a finger path (s); a press lasts as long as its peaks take.
    speed_mm_s : float, optional
        Finger speed (mm/s); for ``human``, the typical peak speed.
    x0_mm, y0_mm : float, optional
        Start position (mm); for ``press``, where the finger presses.
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
        Normal force (N); for ``press``, the force at touch-down.
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
        An unknown kind or a value out of range.
    """
    if kind not in SYNTH_KINDS:
        raise InputError(f"unknown trace kind {kind!r}; expected one of {', '.join(SYNTH_KINDS)}")
    if kind == "press":
        from frictex.rendering.input.press_synth import press_trace
        return press_trace(peaks_n=tuple(peaks_n), x_mm=x0_mm, y_mm=y0_mm, rate_hz=rate_hz,
                           touch_n=force_n, noise_n=force_noise_n, seed=seed)
    from frictex.rendering.input.trace_synth import make_motion, sample
    motion = make_motion(kind, speed_mm_s=speed_mm_s, duration_s=duration_s, x0_mm=x0_mm,
                         y0_mm=y0_mm, angle_deg=angle_deg, length_mm=length_mm,
                         radius_mm=radius_mm, seed=seed)
    return sample(motion, rate_hz, noise_mm=noise_mm, jitter_s=jitter_s, force_n=force_n,
                  seed=seed)
