"""Touch to output latency through an audio output (the audio part of ``frictex bench
latency``).

:func:`audio_latency` runs a live producer as the haptic thread does: one block of
commands at a time, the device pacing it (a block is made whenever fewer than
``lead_blocks`` blocks are queued ahead of the callback). Touch events arrive at random
instants (uniform over a block period, every 10-20 blocks); the first block made after an
event carries it (its amplitude steps up). The latency of an event is the time from its
arrival to the moment the first frame carrying it reaches the DAC (``time.monotonic``:
the callback's time plus PortAudio's ``outputBufferDacTime - currentTime`` plus the
frame's offset in the buffer): so it counts the wait for the next block, the frames
queued in the ring and PortAudio's reported output latency, not the touch source's own
delay (the bench adds that for mouse, TUIO or trace input) nor the pipeline's compute time
beyond one block.
"""

from __future__ import annotations

import time

import numpy as np

from frictex.device.audio.open import open_audio
from frictex.device.errors import InputError
from frictex.device.link.devices import DeviceRequest

#: how often the producer looks at the ring while waiting (s)
POLL_S = 0.0002


def audio_latency(arg: str = "", *, events: int = 50, rate_hz: float = 10_000.0,
                  block_size: int = 50, lead_blocks: int = 2, level_um: float = 1.0,
                  seed: int = 0, timeout_s: float = 120.0) -> dict:
    """Measure touch-to-DAC latency on the audio output ``audio:ARG`` (module docstring).

    Parameters
    ----------
    arg : the ``audio`` device's ARG (not ``wav:``): a PortAudio device and options.
    events : touch events to measure. rate_hz : command rate (Hz). block_size : commands
    per block. lead_blocks : blocks the producer keeps queued. level_um : amplitude an
    event sets (um). seed : the event instants' random seed. timeout_s : bound on the run (s).

    Returns a dict: ``latency_s`` ((m,) float64, s, the events whose first frame played),
    ``missed`` (events whose frame never played), ``output_latency_s`` (PortAudio's
    report), ``blocksize``, ``audio_rate``, and the output's ``status``.
    """
    if arg.startswith("wav:"):
        raise InputError("audio latency: a WAV file has no output time; name a PortAudio device")
    out = open_audio(arg, DeviceRequest(channels=1, rate_hz=rate_hz, paced=False))
    rng = np.random.default_rng(seed)
    period = block_size / rate_hz
    lead = lead_blocks * block_size * out.plan.audio_rate / rate_hz  # frames
    carried: list[tuple[int, float]] = []  # (command index, arrival time) per event
    arrival, hold, index, block = None, 0, 0, 0
    next_event = int(rng.integers(10, 21))
    deadline = time.monotonic() + timeout_s
    try:
        while len(carried) < events and time.monotonic() < deadline:
            while out.ring.tail - out.ring.head > lead and time.monotonic() < deadline:
                time.sleep(POLL_S)
            now = out.now()
            if block == next_event:
                arrival = now + float(rng.uniform(0.0, period))
            if arrival is not None and now >= arrival:
                carried.append((index, arrival))
                arrival, hold = None, 10
                next_event = block + 10 + int(rng.integers(10, 21))
            out.send(index, np.full((block_size, 1), level_um if hold else 0.0))
            hold = max(0, hold - 1)
            index += block_size
            block += 1
    finally:
        out.close()
    latency = [out.dac_time_of_command(k) for k, _ in carried]
    played = [(dac - t) for dac, (_, t) in zip(latency, carried) if dac is not None]
    return {"latency_s": np.array(played, dtype=np.float64),
            "missed": sum(dac is None for dac in latency),
            "output_latency_s": out.output_latency_s, "blocksize": out.stream.blocksize,
            "audio_rate": out.plan.audio_rate, "status": out.status()}
