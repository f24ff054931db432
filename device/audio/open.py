"""The ``audio`` output device's factory, registered under entry-point group
``frictex.devices`` (pyproject.toml): ``--device audio[:ARG]`` (grammar:
``device.audio.options``)."""

from __future__ import annotations

from frictex.device.audio.options import make_plan, parse_arg, profile_warning
from frictex.device.errors import InputError


def open_audio(arg: str, request):
    """Open the audio output ``arg`` describes for a ``device.link.devices.DeviceRequest``:
    a :class:`~device.audio.wav.WavOutput` for ``wav:PATH``, else a
    :class:`~device.audio.stream.StreamOutput`. The drive figures come from the
    request's ``profile`` (the scene's device profile) unless ARG's ``profile=`` names
    another, and the drive stays within both profiles' voltage limits (a warning where
    they differ). Refuses the
    request's ``faults``: they are injected into a serial link, which audio has not."""
    if getattr(request, "faults", None) is not None:
        raise InputError(f"audio:{arg}: faults are injected into a serial link (sim or a "
                         "port); audio has none")
    args = parse_arg(arg)
    requested_profile = getattr(request, "profile", None)
    plan = make_plan(args, request.channels, request.rate_hz, requested_profile)
    warning = profile_warning(args, requested_profile)
    if warning is not None:
        print(f"frictex: warning: {warning}", file=request.stderr)
    if args.wav_path is not None:
        from frictex.device.audio.wav import WavOutput
        return WavOutput(plan, args.wav_path, phases=request.phases, stderr=request.stderr)
    from frictex.device.audio.stream import StreamOutput
    return StreamOutput(plan, args.target, blocksize=args.blocksize,
                        buffer_frames=round(args.buffer_ms * 1e-3 * plan.audio_rate),
                        phases=request.phases, paced=request.paced,
                        wait_s=request.stall_s * request.max_stalls, stderr=request.stderr)
