"""What an output device did with what was commanded, as the summary's warnings say it,
and whether a run that streamed to it failed (:func:`unplayed_problem`).

The commands table holds what the pipeline commanded; the device section of
``summary.json`` counts what the device then did with it: samples it never played, by
cause (``unplayed_samples``), and beside them values clamped to its amplitude
limit (the limit a link's device declared, ``device.link.host``; an audio output's voltage
limit, ``device.audio.synth``) and, on an audio output, the callbacks PortAudio flagged
with an output underflow (``xruns``). Neither is unplayed (``unplayed_samples``), so
neither shows there: a run whose every sample played can still have driven the plate
with something else than its commands.
"""

from __future__ import annotations


def device_clamped(device: dict) -> tuple[int, str]:
    """How many values the device clamped to its amplitude limit (``device``: as in
    :func:`device_warnings`) and what they count: samples on one channel, values
    (samples x channels) on more."""
    channels = len((device.get("device") or {}).get("limits_um") or [])
    return device.get("clamped_samples") or 0, "samples" if channels <= 1 else "values"


def device_warnings(device: dict, max_amplitude_um: float) -> list[str]:
    """One sentence per thing the output device did not play as commanded: samples never
    played (by cause), values clamped to its amplitude limit (a link's declared limit, an
    audio output's voltage limit), audio output underflows, Statuses out of order, and
    ``--faults`` events that never came (the link ended first). ``device``: the summary's ``device`` section
    (``device.link.host.CommandSink.status``, ``device.audio.output.AudioOutput.status``);
    ``max_amplitude_um``: the largest command (um, ``counts.max_amplitude_um``)."""
    warnings = _unplayed(device) + _uncounted(device)
    audio = device.get("audio") or {}
    clamped, counted = device_clamped(device)
    if clamped:
        limits = (device.get("device") or {}).get("limits_um") or []
        channels = max(1, len(limits))
        values = device.get("commanded_samples", 0) * channels
        share = [f"{clamped / values:.1%}"] if values else []
        said = ", ".join(([] if channels == 1 else [f"samples x {channels} channels"]) + share)
        if "limit_v" in audio:  # one voltage limit for every channel
            what = (f"the audio output's {audio['limit_v']:g} V limit "
                    f"({audio['limit_v'] * audio['um_per_volt']:.4g} um at "
                    f"{audio['um_per_volt']:g} um/V)")
        elif len(set(limits)) == 1:
            what = f"the device's {limits[0]:.4g} um limit"
        else:
            what = "the device's limits" + (
                " (" + ", ".join(f"{um:.4g}" for um in limits) + " um by channel)" if limits else "")
        warnings.append(f"{clamped} of {values} commanded {counted}"
                        f"{f' ({said})' if said else ''} were clamped to "
                        f"{what}: the plate got at most that where the commands table says "
                        f"up to {max_amplitude_um:.4g} um")
    xruns = audio.get("xruns") or 0
    if xruns:
        warnings.append(f"{xruns} audio callbacks were flagged with an output underflow "
                        "(xrun: the sound card or audio server ran late and may have put a "
                        f"gap of up to one {audio['blocksize']}-frame period, "
                        f"{audio['blocksize'] / audio['rate_hz'] * 1e3:.3g} ms, into the "
                        "plate's drive); unplayed_samples and underruns count only frictex's "
                        "own buffer running dry, not these")
    stale = device.get("stale_statuses") or 0
    if stale:
        warnings.append(f"the device sent {stale} Statuses out of order (answering a heartbeat "
                        "older than one already answered), which were ignored: a faulty "
                        "device or firmware (PROTOCOL.md 6.1)")
    return warnings + faults_not_reached(device)


def faults_not_reached(link: dict) -> list[str]:
    """One sentence where ``--faults`` events never came (a link's ``status``: the link
    ended before their time), else none."""
    not_reached = link.get("fault_events_not_reached") or []
    if not not_reached:
        return []
    return [f"--faults {', '.join(not_reached)}: never came, the link ended before (event "
            "times count from when the link opened)"]


def _unplayed(status: dict) -> list[str]:
    """What the device never played, by cause (``device.link.host.CommandSink.status``)."""
    commanded, unplayed = status.get("commanded_samples", 0), status.get("unplayed_samples", 0)
    if not unplayed:
        return []
    causes = ", ".join(f"{n} {cause.replace('_', ' ')}"
                       for cause, n in status.get("unplayed_by_cause", {}).items() if n)
    return [f"{unplayed} of {commanded} commanded samples ({unplayed / commanded:.2%}) were "
            f"never played by the device ({causes})"]


def _uncounted(status: dict) -> list[str]:
    """What a link's counts leave out (``device.link.host.CommandSink.status``), one
    sentence each: watchdog trips of a device that does not count what they dropped
    (protocol version 1), and underruns of a paced stream (the plate fell silent, though
    every sample played in the end), both counted from the host's first Status."""
    said = []
    trips = status.get("watchdog_trips_in_run") or 0
    if trips and status.get("unplayed_known") is False:
        said.append(f"the device tripped its watchdog {trips} time(s) (the plate stopped) "
                    f"and, speaking protocol version {status.get('protocol_version')}, does "
                    "not count the samples it dropped: unplayed_samples counts only the "
                    "known causes and --max-unplayed cannot be checked")
    underruns = status.get("underruns_in_run") or 0
    if status.get("paced") and underruns:
        buffered = (status.get("device") or {}).get("buffer_samples")
        said.append(f"the device's buffer{f' ({buffered} samples)' if buffered else ''} ran "
                    f"empty {underruns} time(s) during the paced replay (underruns): the "
                    "plate fell silent until the next block came")
    return said


def unplayed_problem(status: dict | None, max_unplayed: float, option: str,
                     excused: tuple[str, ...] = ()) -> str | None:
    """Why a run streaming to a device failed, if the device (``status``, the summary's
    ``device``) never played more than ``max_unplayed`` of the commanded samples, those of
    the ``excused`` causes (``unplayed_by_cause``) not counted; None if it played enough or
    there was no device. ``option`` names the limit in the message."""
    if status is None or not status.get("commanded_samples"):
        return None
    causes = status.get("unplayed_by_cause", {})
    unplayed = status["unplayed_samples"] - sum(causes.get(cause, 0) for cause in excused)
    lost = unplayed / status["commanded_samples"]
    if lost <= max_unplayed:
        return None
    left_out = f"; {', '.join(excused)} not counted" if excused else ""
    return (f"{lost:.2%} of the commanded samples never played on the device (limit "
            f"{max_unplayed:.2%}, {option}{left_out})")

