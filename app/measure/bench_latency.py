"""``frictex bench latency``: from a touch event to the first output sample that carries it.

A touch goes into the live haptic path the demo runs (``app.live.haptic_setup.
open_haptic``: the haptic thread, one block of 25 samples every 2.5 ms at 10 kHz on the
wall clock, and for TUIO its touch pump), on ``grating-5mm`` with the finger resting on a
low-friction line, so that the output is 0 um without a finger and rises with it. Two
inputs: *trace* (the sample queued through the thread's ``touch_at``, as the mouse and
a trace do) and *TUIO* (a TUIO 1.1 datagram sent over loopback UDP to the listener the
demo opens for ``--input tuio``). Events come at random instants, one finger down for
50 ms, then up, 60 to 110 ms apart.

The latency of an event is the wall time from the touch (the call, or the datagram's
send) to the moment the device played the first sample the touch changed. Each figure
includes the wait for the next block boundary (0 to 2.5 ms), the pipeline's compute, the
link (frames through the port thread) and the device's buffer lead (the link's prefill of
two blocks, less the block playing; after an underrun the link skips blocks until the
device is back to it, ``device.link.catch_up``); not the touch hardware's own delay. A
touch whose first sample was skipped is timed at the first sample played in its stead.
A touch whose change never played (a flushed or late block) is lost: p50 and p99 are
over the touches that played, and their labels say how many of how many, and how many
lost touches they leave out. Under 101 played (20 or 60 touches a run) a 99th
percentile lies between the two largest, so the label says max (``app.measure.tail``). The play time is the device's:

- *sim*: the simulated device in this process (``sim``), its played samples timed when
  its clock plays them (each at its own tick: the time its batch was played less the
  ticks after it);
- *qemu*: the firmware's QEMU port (``device/firmware/sf2``, a Cortex-M3 in
  ``qemu-system-arm`` on the host's clock) on a pty, its played samples timed as its log
  reaches this process (batches written at least every 2 ms; each sample timed back
  from its batch's arrival by the ticks after it, so QEMU's I/O delay is included);
- *audio*: ``device.audio.latency.audio_latency`` into a PortAudio device (a JACK
  server at 192 kHz with 256-frame periods where one runs): a live producer paced by
  the device, the first frame carrying an event timed at the DAC (PortAudio's reported
  output latency included); no haptic thread, so no touch input of its own.

Each is measured with no busy processes added (whatever else runs on the machine goes
on) and beside two busy processes this section starts and ends (the "two-process
load"); the machine's load (1-minute average) is printed before each. Targets (issue
text): p99 at most 10 ms through the link, 15 ms through audio at 192 kHz with 256
frames, under the load. A run in which no event played, and an audio output named by
``FRICTEX_BENCH_AUDIO`` that could not be opened, each give one failed figure (NaN,
saying which; ``frictex bench`` exits 1), not a figure of 0; with none named, a machine
without an audio output (as one without QEMU) is said on standard error and not measured.
"""

from __future__ import annotations

import io
import os
import socket
import struct
import sys
import threading
import time

import numpy as np

from frictex.app.live.haptic_thread import BLOCK_SIZE as BLOCK
from frictex.app.live.haptic_thread import LEAD_BLOCKS, link_options
from frictex.app.measure.figure import Figure
from frictex.app.measure.processes import BusyProcesses
from frictex.app.measure.processes import load as machine_load
from frictex.app.measure.tail import tail

RATE = 10_000.0
FINGER_MM = (1.0, 30.0)  # on grating-5mm's first low-friction line
HOLD_S = 0.05
GAP_S = (0.06, 0.11)
LOAD_PROCESSES = 2
SETTLE_S = 0.3  # the stream playing steadily before the first event


class PlayedTimes:
    """When a device played each sample: batches of consecutive sample numbers, each
    with the wall time (``time.perf_counter``) its last sample played."""

    def __init__(self, rate_hz: float):
        self.rate_hz = rate_hz
        self._lock = threading.Lock()
        self._first: list[int] = []
        self._last: list[int] = []
        self._t: list[float] = []

    def note(self, index: np.ndarray, t_s: float) -> None:
        """Samples ``index`` (ascending) played, the last of them at ``t_s``."""
        if not len(index):
            return
        with self._lock:
            for run in np.split(index, np.flatnonzero(np.diff(index) != 1) + 1):
                # an earlier run of the batch ended (last - this run's last) ticks before
                self._first.append(int(run[0]))
                self._last.append(int(run[-1]))
                self._t.append(t_s - (int(index[-1]) - int(run[-1])) / self.rate_hz)

    def time_of(self, i: int) -> float | None:
        """When sample ``i`` played (s, perf_counter), or None if it did not."""
        with self._lock:
            for first, last, t in zip(self._first, self._last, self._t):
                if first <= i <= last:
                    return t - (last - i) / self.rate_hz
        return None


class _Commands:
    """The haptic thread's recorder: keeps channel 0's commands (um) in order."""

    dropped = 0  # blocks lost (none: it keeps them on the haptic thread)

    def __init__(self):
        self.blocks: list[np.ndarray] = []

    def write(self, out, commands_um) -> None:
        self.blocks.append(np.array(commands_um[:, 0], dtype=np.float64))

    def commit(self) -> None:
        pass

    abort = commit


def _osc(address: str, *args) -> bytes:
    def pad(b: bytes) -> bytes:
        return b + b"\0" * (-len(b) % 4)
    tags, data = ",", b""
    for a in args:
        if isinstance(a, str):
            tags, data = tags + "s", data + pad(a.encode() + b"\0")
        elif isinstance(a, int):
            tags, data = tags + "i", data + struct.pack(">i", a)
        else:
            tags, data = tags + "f", data + struct.pack(">f", a)
    return pad(address.encode() + b"\0") + pad(tags.encode() + b"\0") + data


def tuio_frame(fseq: int, cursor: tuple[float, float] | None) -> bytes:
    """A TUIO 1.1 2Dcur bundle: one cursor (session 1) at normalised (x, y), or none."""
    msgs = [_osc("/tuio/2Dcur", "alive", *([1] if cursor else []))]
    if cursor:
        msgs.append(_osc("/tuio/2Dcur", "set", 1, float(cursor[0]), float(cursor[1]),
                         0.0, 0.0, 0.0))
    msgs.append(_osc("/tuio/2Dcur", "fseq", fseq))
    return b"#bundle\0" + struct.pack(">Q", 1) + b"".join(
        struct.pack(">i", len(m)) + m for m in msgs)


class _Touch:
    """Touch events into the haptic thread: ``down()`` and ``up()`` return the wall time
    of the event (perf_counter)."""

    def __init__(self, kind: str, haptic, display):
        self.kind, self.haptic, self.display = kind, haptic, display
        self.fseq = 0
        self.sock = socket.socket(socket.AF_INET, socket.SOCK_DGRAM) if kind == "tuio" else None

    def _send(self, down: bool) -> float:
        from frictex.rendering.input.trace_file import DOWN, UP
        t = time.perf_counter()
        if self.sock is None:
            self.haptic.touch_at(self.haptic.now(), 0, *FINGER_MM, 0.5, DOWN if down else UP)
        else:
            self.fseq += 1
            cursor = (FINGER_MM[0] / self.display.width_mm, FINGER_MM[1] / self.display.height_mm)
            self.sock.sendto(tuio_frame(self.fseq, cursor if down else None),
                             ("127.0.0.1", self.haptic.pump.source.port))
        return t

    def down(self) -> float:
        return self._send(True)

    def up(self) -> float:
        return self._send(False)

    def close(self) -> None:
        if self.sock is not None:
            self.sock.close()


def _sim_output():
    """(opener, process, PlayedTimes, close) of the in-process simulated device."""
    from frictex.device.link.simport import SimDevice, sim_config
    device = SimDevice(sim_config([], 1, RATE, False))
    played = PlayedTimes(RATE)
    device.core.log = lambda index, values, phases: played.note(np.asarray(index),
                                                                time.perf_counter())
    return device.open, None, played, device.close


def _qemu_output():
    """The same for the firmware in QEMU: its played-sample log timed as it arrives.
    QEMU runs on the host's clock (``device.firmware.qemuport``)."""
    from frictex.device.firmware import qemuport
    from frictex.device.link.host import open_port
    played = PlayedTimes(RATE)
    rest = b""

    def on_log(chunk: bytes, t: float) -> None:
        nonlocal rest
        data = rest + chunk
        index, _ = qemuport.records(data)
        rest = data[len(index) * (4 + 2 * qemuport.CHANNELS):]
        played.note(index, t)

    device = qemuport.QemuDevice(on_log=on_log)
    return (lambda: open_port(device.path)), device.proc, played, device.close


def _events(output: str, touch: str, events: int, seed: int) -> tuple[np.ndarray, dict]:
    """Latencies (s) of ``events`` touches of kind ``touch`` through ``output``, and the
    link's status when it closed."""
    from frictex.app.live.haptic_setup import open_haptic
    from frictex.device.link.host import CommandSink
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    scene = load_scene(resolve_scene("grating-5mm"))
    source = None
    if touch == "tuio":
        from frictex.rendering.input.tuio import TuioListener
        source = TuioListener(0, width_mm=1.0, height_mm=1.0)
    opener, proc, played, close = _sim_output() if output == "sim" else _qemu_output()
    try:
        haptic, finish = open_haptic(scene, RATE, BLOCK, None, None, None, source=source)
        haptic.sink = sink = CommandSink(opener, 1, RATE, paced=False, stderr=io.StringIO(),
                                         process=proc, **link_options(BLOCK / RATE))
        haptic.recorder = commands = _Commands()
        rng = np.random.default_rng(seed)
        touches = _Touch(touch, haptic, scene.display)
        downs = []
        haptic.start()
        try:
            time.sleep(SETTLE_S)
            for _ in range(events):
                time.sleep(float(rng.uniform(*GAP_S)))
                downs.append(touches.down())
                time.sleep(HOLD_S)
                touches.up()
            time.sleep(0.1)
        finally:
            touches.close()
            link, _ = finish()
    finally:
        close()
    return _latencies(downs, np.concatenate(commands.blocks), played, sink.device_index), link


def _latencies(downs: list[float], commands: np.ndarray, played: PlayedTimes,
               device_index) -> tuple[np.ndarray, int]:
    """Per touch-down (in order, each 50 ms down, then up), the play time of its own
    rising edge of the commands (the n-th edge is the n-th touch's; ``device_index``
    numbers it as the device did) less the touch time (s); a touch whose edge never
    played (a flushed or late block) is left out. Also how many edges are dated at or
    before their touch: a device that reports its samples in batches is dated back from
    each batch's arrival one sample period a sample (:class:`PlayedTimes`), which a batch
    played in a burst to catch up (QEMU's port after a late timer: up to 100 ms) puts too
    early; those are left out too, and counted apart from the lost."""
    on = commands > 0
    edges = np.flatnonzero(on & ~np.concatenate([[False], on[:-1]]))
    out, early = [], 0
    for t, edge in zip(downs, edges):
        played_at = played.time_of(device_index(int(edge)))
        if played_at is not None and played_at > t:
            out.append(played_at - t)
        elif played_at is not None:
            early += 1
    return np.array(out, dtype=np.float64), early


def _figures(label: str, latency_s: np.ndarray, events: int,
             kind: str = "touches", early: int = 0) -> list[Figure]:
    """p50 and p99 (ms; the max under 101 played, ``app.measure.tail``) of the
    ``latency_s`` of the events that played, of ``events``
    ``kind``; each label counts them, and where some never played says that those lost
    are not in it (a lost one has no latency to rank: counting it as slower than every
    played one would make p99 a rank of the losses, not a time). Where none played, one
    failed figure (NaN, every event failed) says so."""
    played = latency_s.size
    if not played:  # no time to give: a failed figure, not a latency of 0
        return [Figure("latency", f"{label}: none played of {events} {kind}", float("nan"),
                       "ms", events)]
    lost = events - played - early
    left_out = ([f"{lost} lost"] if lost else []) + (
        [f"{early} dated at or before their touch (a batch played in a catch-up burst)"]
        if early else [])
    counted = f"of {played} played of {events} {kind}" + (
        f" ({', '.join(left_out)}, not in it)" if left_out else "")
    high, value = tail(latency_s * 1e3)
    return [Figure("latency", f"{label}: p50 {counted}", float(np.median(latency_s)) * 1e3,
                   "ms"),
            Figure("latency", f"{label}: {high} {counted}", value, "ms"),
            Figure("latency", f"{label}: events played", played, f"of {events}")]


def _link_figures(label: str, link: dict) -> list[Figure]:
    """What the lead cost on a link: the device's underruns, the blocks skipped to bring
    it back (``device.link.catch_up``) and those dropped (its queue full, or the link
    down), of all blocks made."""
    blocks = link["blocks_sent"] + link["skipped_blocks"] + link["dropped_blocks"]
    return [Figure("latency", f"{label}: device underruns", link["underruns"] or 0, "times"),
            Figure("latency", f"{label}: blocks skipped to catch up", link["skipped_blocks"],
                   f"of {blocks}"),
            Figure("latency", f"{label}: blocks dropped (queue full, link down)",
                   link["dropped_blocks"], f"of {blocks}; {link['disconnects']} disconnects")]


def _audio(events: int) -> np.ndarray | str:
    """The latencies (s) of ``events`` through the audio output, or why it could not be
    opened (one line)."""
    try:
        from frictex.device.audio.latency import audio_latency
        return audio_latency(os.environ.get("FRICTEX_BENCH_AUDIO", ""), events=events,
                             block_size=BLOCK, lead_blocks=LEAD_BLOCKS,
                             timeout_s=60.0)["latency_s"]
    except Exception as exc:  # no PortAudio, no JACK server, no audio device: say so
        return f"{type(exc).__name__}: {str(exc)[:160]}"


def _audio_figures(label: str, audio: np.ndarray | str, events: int) -> list[Figure]:
    """``_figures`` of the audio output's latencies, or, where it could not be opened
    (``audio`` says why): one failed figure (NaN) saying so for an output
    ``FRICTEX_BENCH_AUDIO`` names, none for the default one (a machine without audio
    output; ``run`` says so on standard error)."""
    if isinstance(audio, str):
        if not os.environ.get("FRICTEX_BENCH_AUDIO"):
            return []
        return [Figure("latency", f"{label}: not measured, the audio output could not be "
                       f"opened ({audio})", float("nan"), "ms", 1)]
    return _figures(label, audio, events, "events")


def run(quick: bool) -> list[Figure]:
    events = 20 if quick else 60
    outputs = ["sim"]
    try:
        from frictex.device.firmware import qemuport
        qemuport.firmware()
        from frictex.device.firmware.build import require
        require(qemuport.QEMU)
        outputs.append("qemu")
    except Exception as exc:  # no cross compiler or QEMU: say so, measure the rest
        print(f"frictex: bench latency: firmware in QEMU not measured ({exc})", file=sys.stderr)
    figures: list[Figure] = []
    per_run_s = events * (HOLD_S + GAP_S[1]) + SETTLE_S + 30.0
    audio: np.ndarray | str = np.empty(0)  # why it failed, once it has: not tried again
    for loaded in (False, True):
        where = "two-process load" if loaded else "no busy processes added"
        figures.append(Figure("latency", f"machine load before the runs with {where} "
                              "(1-minute average)", machine_load(), ""))
        load = (BusyProcesses(LOAD_PROCESSES, per_run_s * (2 * len(outputs) + 1)) if loaded
                else None)
        try:
            for seed, (output, touch) in enumerate(
                    (o, t) for o in outputs for t in ("trace", "tuio")):
                (latency, early), link = _events(output, touch, events, seed)
                label = f"{touch} touch -> {output} device played, {where}"
                figures += (_figures(label, latency, events, early=early)
                            + _link_figures(label, link))
            if not isinstance(audio, str):
                audio = _audio(events)
                if isinstance(audio, str) and not os.environ.get("FRICTEX_BENCH_AUDIO"):
                    print(f"frictex: bench latency: audio not measured ({audio})",
                          file=sys.stderr)
            figures += _audio_figures(f"audio producer -> DAC (PortAudio), {where}", audio,
                                      events)
        finally:
            if load is not None:
                load.__exit__(None, None, None)
    return figures
