"""The ``audio`` output device's ARG, and the drive figures it resolves to.

Grammar of ARG (the text after ``audio:`` in ``--device audio:ARG``)::

    ARG     := [TARGET] ("," OPTION)*
    TARGET  := ""                 the default PortAudio output device
             | NAME               a PortAudio output device, by (part of) its name or index
             | "wav:" PATH        write the stream to a WAV file instead of playing it
    OPTION  := "envelope"         play the amplitude envelope itself (a generator's AM input)
             | "rate=" HZ         audio sample rate (Hz; default 192000; 8000 to 768000)
             | "carrier=" HZ      the plate's resonance (Hz; default: the profile's)
             | "profile=" NAME    the device profile whose drive figures apply
             | "full_scale=" V    drive volts (zero-to-peak) at digital full scale
                                  (default: the profile's voltage limit)
             | "blocksize=" N     PortAudio frames per callback (default 256; 1 to 8192)
             | "buffer_ms=" MS    frames queued ahead of the callback (default 100 ms;
                                  1 to 1000 ms)
             | "ramp_ms=" MS      start, stop, starvation and emergency-stop ramps (default
                                  2 ms; more than 0, at most 50 ms less one block)

A PATH or NAME cannot contain a comma, and a NAME that starts with an option's name and
"=" (``rate=1``) is that option. The rate is a whole number of Hz from 8 kHz to
768 kHz, the rates sound cards offer (a WAV file would take more, but nothing would play
it; RIFF's 32-bit byte rate ends at 4.29 GHz / 4 bytes / channels). The rate must keep the
carrier below 0.4 of it (192 kHz: up to 76.8 kHz; 96 kHz: up to 38.4 kHz; 768 kHz: up to
307.2 kHz, the highest carrier); envelope mode has no carrier. The default profile's plate
(seed 003) resonates at 60.75 kHz, so it needs a rate above 151.875 kHz: 48 and 96 kHz are
refused in one line naming the carrier, its profile and the least rate that carries it.

The plate must be still within :data:`MAX_STOP_MS` (50 ms) of a stop, as a serial
device's ``watchdog_ms + ramp_ms`` (PROTOCOL.md 5.3): an emergency stop or a starving
stream begins its ramp at the next callback, so one block (``blocksize`` frames at the
rate) plus ``ramp_ms`` must not exceed it. ``buffer_ms`` is at most 1 s: a stop with drain
plays the queue out first, and the ring holds that many frames (at least 4 ``blocksize``;
live, two of the pipeline's blocks too: a block the ring cannot take is dropped).
An option out of its range is refused in one line naming the option, what was typed and
the range.

The drive figures (``carrier_hz``, ``um_per_volt``, ``voltage_limit_v``) come from the
device profile (``device.profile.PROFILES``): ``profile=`` where given (the plate wired to
the output, when it is not the one the scene was written for), else the one the
pipeline's scene names (``DeviceRequest.profile``), else
``device.profile.DEFAULT_PROFILE``. The drive never passes the scene's profile's voltage
limit either: with ``profile=`` naming another profile, the limit is the lower of the two
(and full scale stays the typed profile's, so the samples peak below 1.0), and
:func:`profile_warning` says so in one line.
"""

from __future__ import annotations

import difflib

import math
from dataclasses import dataclass

from frictex.device.errors import InputError
from frictex.device.link.protocol import MAX_STOP_MS  # one callback block plus the ramp
from frictex.device.profile import DEFAULT_PROFILE, PROFILES

DEFAULT_RATE_HZ = 192_000
#: the audio rates sound cards offer, lowest and highest (Hz)
MIN_RATE_HZ = 8_000
MAX_RATE_HZ = 768_000
#: the carrier must stay below this share of the audio rate
MAX_CARRIER_SHARE = 0.4
DEFAULT_BLOCKSIZE = 256
#: most PortAudio frames per callback (43 ms at 192 kHz)
MAX_BLOCKSIZE = 8192
DEFAULT_BUFFER_MS = 100.0
#: most frames queued ahead of the callback (ms): a stop with drain plays them out first
MAX_BUFFER_MS = 1000.0
#: start, stop, starvation and emergency-stop ramps (ms): 384 frames at 192 kHz; a ramp
#: lengthens a friction step's transition by less than the 2.3-2.4 ms difference in
#: transition time participants told apart (Gueorguiev 2019)
DEFAULT_RAMP_MS = 2.0


@dataclass(frozen=True)
class AudioPlan:
    """What the synthesis and the outputs run with (validated, trusted inside).

    rate_hz : command sample rate (Hz) of the pipeline. audio_rate : audio frames per
    second (an integer, Hz). channels : actuator channels, one audio channel each.
    carrier_hz : carrier frequency (Hz). envelope : play the envelope, no carrier.
    um_per_volt : um zero-to-peak per volt zero-to-peak. limit_v : the largest drive
    played (V zero-to-peak): the lowest of the profile's voltage limit, the scene's
    profile's and full scale. full_scale_v : volts at digital full scale (1.0). ramp_frames : ramp length
    (audio frames). profile : the profile whose figures these are.
    """

    rate_hz: float
    audio_rate: int
    channels: int
    carrier_hz: float
    envelope: bool
    um_per_volt: float
    limit_v: float
    full_scale_v: float
    ramp_frames: int
    profile: str


@dataclass(frozen=True)
class AudioArgs:
    """ARG parsed: ``target`` ("" default device, a device NAME), ``wav_path`` (or None),
    and the options (None where not given)."""

    target: str = ""
    wav_path: str | None = None
    envelope: bool = False
    rate: float | None = None
    carrier: float | None = None
    profile: str | None = None
    full_scale: float | None = None
    blocksize: int = DEFAULT_BLOCKSIZE
    buffer_ms: float = DEFAULT_BUFFER_MS
    ramp_ms: float = DEFAULT_RAMP_MS


_NUMBERS = {"rate": float, "carrier": float, "full_scale": float, "blocksize": int,
            "buffer_ms": float, "ramp_ms": float}
#: the names an OPTION takes before its '='
_OPTION_NAMES = {"profile", *_NUMBERS}
#: (lowest, highest, what the range is) of the options that size a buffer or a time;
#: a lowest of 0 is excluded (``_number`` takes only numbers > 0)
_RANGES = {
    "rate": (MIN_RATE_HZ, MAX_RATE_HZ, "Hz, the rates sound cards offer"),
    "blocksize": (1, MAX_BLOCKSIZE, "frames per callback"),
    "buffer_ms": (1, MAX_BUFFER_MS, "ms: a stop with drain plays the queue out first"),
    "ramp_ms": (0, MAX_STOP_MS, f"ms: the plate must be still within {MAX_STOP_MS:g} ms of "
                                "a stop (PROTOCOL.md 5.3)"),
}


def parse_arg(arg: str) -> AudioArgs:
    """Read ARG (module docstring). Raises InputError naming the bad part."""
    parts = [p.strip() for p in arg.split(",")] if arg.strip() else [""]
    target, options = parts[0], parts[1:]
    name, eq, _ = target.partition("=")  # an option by its name: wav:/tmp/a=b.wav is a PATH
    if target == "envelope" or eq and name.strip() in _OPTION_NAMES:
        target, options = "", parts
    elif eq and not target.startswith("wav:") and (
            close := difflib.get_close_matches(name.strip(), sorted(_OPTION_NAMES), n=1)):
        raise InputError(f"audio device option {target!r}: no option {name.strip()!r} (did you "
                         f"mean {close[0]}=?)")
    values: dict = {}
    if target.startswith("wav:"):
        path = target[4:]
        if not path:
            raise InputError("audio device 'wav:': expected wav:PATH")
        values["wav_path"], target = path, ""
    values["target"] = target
    for option in options:
        name, eq, text = option.partition("=")
        name = name.strip()
        if option == "envelope":
            values["envelope"] = True
        elif eq and name == "profile":
            values["profile"] = text.strip()
        elif eq and name in _NUMBERS:
            values[name] = _number(name, text, _NUMBERS[name])
        else:
            raise InputError(f"audio device option {option!r}: expected envelope, profile=NAME "
                             "or one of " + ", ".join(f"{n}=NUMBER" for n in _NUMBERS))
    return AudioArgs(**values)


def _number(name: str, text: str, kind: type) -> float | int:
    try:
        value = kind(text)
    except ValueError:
        raise InputError(f"audio device option {name}={text!r}: expected a "
                         f"{'whole ' if kind is int else ''}number") from None
    if not math.isfinite(value) or value <= 0:
        raise InputError(f"audio device option {name}={text!r}: expected a finite number > 0")
    if name in _RANGES:
        low, high, unit = _RANGES[name]
        if not low <= value <= high:
            lowest = f"more than {low:g}" if low == 0 else f"{low:g}"
            raise InputError(f"audio device {name}={text.strip()}: expected {lowest} to "
                             f"{high:g} {unit}")
    if name == "rate" and value != int(value):
        raise InputError(f"audio device rate={text.strip()}: expected a whole number of Hz")
    return value


def profile_name(requested) -> str | None:
    """The profile name in a request's ``profile`` (a name, an object with ``.profile``
    such as ``device.profile.DeviceProfile``, or None)."""
    if requested is None or isinstance(requested, str):
        return requested
    return getattr(requested, "profile", None)


def make_plan(args: AudioArgs, channels: int, rate_hz: float, requested_profile=None) -> AudioPlan:
    """The :class:`AudioPlan` of parsed ARG for a pipeline of ``channels`` at ``rate_hz``
    (Hz). The profile: ``profile=`` if given, else ``requested_profile``, else the default;
    ``limit_v`` is at most the voltage limit of each of ``profile=``, ``requested_profile``
    and full scale. Raises InputError for a carrier the rate does not fit, or a block and ramp that
    together exceed :data:`MAX_STOP_MS` at the rate (``parse_arg`` checks each option's
    own range)."""
    scene = profile_name(requested_profile)
    name = args.profile or scene or DEFAULT_PROFILE
    spec = PROFILES.get(name)
    audio_rate = int(args.rate if args.rate is not None else DEFAULT_RATE_HZ)
    block_ms = args.blocksize * 1e3 / audio_rate
    if block_ms + args.ramp_ms > MAX_STOP_MS:
        top_block = math.floor((MAX_STOP_MS - args.ramp_ms) * 1e-3 * audio_rate)
        room = (f"ramp_ms up to {MAX_STOP_MS - block_ms:.4g} ms" if block_ms < MAX_STOP_MS
                else f"blocksize up to {top_block}" if top_block >= 1
                else "a shorter ramp and block")
        ramp = repr(args.ramp_ms).removesuffix(".0")
        raise InputError(f"audio device blocksize={args.blocksize} and ramp_ms={ramp}"
                         f" at rate={audio_rate} Hz: one block ({block_ms:.4g} ms) plus the "
                         f"ramp must not exceed {MAX_STOP_MS:g} ms ({room}): the plate must be "
                         f"still within {MAX_STOP_MS:g} ms of a stop (PROTOCOL.md 5.3)")
    carrier = float(args.carrier if args.carrier is not None else spec.carrier_hz)
    top_carrier = MAX_CARRIER_SHARE * MAX_RATE_HZ
    if not args.envelope and carrier >= top_carrier:
        raise InputError(f"audio device: carrier {carrier:g} Hz: expected below "
                         f"{top_carrier:g} Hz, {MAX_CARRIER_SHARE:g} of the highest rate "
                         f"sound cards offer ({MAX_RATE_HZ} Hz)")
    if not args.envelope and carrier >= MAX_CARRIER_SHARE * audio_rate:
        named = "" if args.carrier is not None else f" (profile {name})"
        raise InputError(f"audio device: carrier {carrier:g} Hz{named} at rate={audio_rate} Hz:"
                         f" the carrier must stay below {MAX_CARRIER_SHARE:g} of the rate (use "
                         f"rate={math.floor(carrier / MAX_CARRIER_SHARE) + 1} or more)")
    if audio_rate < rate_hz:
        raise InputError(f"audio device rate={audio_rate} Hz: below the pipeline's "
                         f"{rate_hz:g} Hz commands")
    full_scale = float(args.full_scale if args.full_scale is not None else spec.voltage_limit_v)
    ramp = max(1, round(args.ramp_ms * 1e-3 * audio_rate))
    return AudioPlan(rate_hz=float(rate_hz), audio_rate=audio_rate, channels=int(channels),
                     carrier_hz=carrier, envelope=args.envelope, um_per_volt=spec.um_per_volt,
                     limit_v=min(_voltage_limit_v(name, scene), full_scale), full_scale_v=full_scale,
                     ramp_frames=ramp, profile=name)


def _voltage_limit_v(name: str, scene: str | None) -> float:
    """The lower voltage limit (V zero-to-peak) of profile ``name`` and of the scene's
    profile ``scene`` (None: the scene names none)."""
    return min(PROFILES.get(p).voltage_limit_v for p in {name, scene or name})


def profile_warning(args: AudioArgs, requested_profile=None) -> str | None:
    """One line where ``profile=`` names another profile than the scene's
    (``requested_profile``), naming both and their voltage limits (V zero-to-peak) and the
    limit the output keeps to; None where they agree or either is not given."""
    scene = profile_name(requested_profile)
    if args.profile is None or scene is None or args.profile == scene:
        return None
    typed, written = PROFILES.get(args.profile), PROFILES.get(scene)
    return (f"audio device profile={args.profile} ({typed.voltage_limit_v:g} V limit, "
            f"{typed.um_per_volt:g} um/V) is not the scene's profile {scene} "
            f"({written.voltage_limit_v:g} V limit): the drive figures are {args.profile}'s "
            f"and the drive stops at {_voltage_limit_v(args.profile, scene):g} V")
