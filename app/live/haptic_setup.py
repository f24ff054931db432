"""The live haptic thread with its link (``--device``, with ``--faults`` injected), its
recording (``--record``) and its touch screen (``--input tuio|evdev``), set up and torn
down together; used by the demo in thread mode and by the haptic child process."""

from __future__ import annotations

import sys
from pathlib import Path

from frictex.app.engine.sinks import TableSink, ThreadedSink
from frictex.app.live.touch_log import TOUCHES, TouchTable

RECORD_QUEUE = 8000  # blocks (20 s at 2.5 ms) the writer may fall behind before dropping
#: the most (s) ``finish`` waits for the thread to commit its sinks: the link's close
#: (under 2 s) and the recording's backlog (up to RECORD_QUEUE blocks) on a busy machine;
#: below the 30 s a demo waits for its haptic child (``haptic_process.STOP_TIMEOUT_S``)
JOIN_TIMEOUT_S = 25.0


def touches_comment(scene_name: str, block_size: int) -> str:
    """The comment heading a demo's ``touches.csv``: what it holds and how to replay it."""
    return (f"frictex demo, scene {scene_name}: the touches the haptic side took, on its output "
            f"clock (s); replay them with: frictex replay SCENE touches.csv --block "
            f"{block_size} (scene switches and emergency stops are in events.csv)")


def open_haptic(scene, rate_hz: float, block_size: int, render_override: str | None,
                device: str | None, record: Path | None, *, faults=None, source=None,
                control: str | None = None, sim_args: tuple[str, ...] = (), **queues):
    """A :class:`HapticThread` (not started) for ``scene`` with its link (``--device``;
    ``faults``: a ``device.link.faults.FaultPlan`` injected on it), recorder
    (``--record``: the replay's tables, written on a thread of their own) and touch
    screen (``source``: ``app.live.inputs.open_source``, pumped from the thread's
    start; closed here if setting up fails), and ``finish() -> (link status, dropped record blocks)``, which stops the
    touch screen and the thread; the thread closes the link and commits the recording
    as it ends. ``control``: the friction loop's mode instead of the scene file's;
    ``sim_args``: more ``frictex sim-device`` flags for ``device`` "sim". ``queues``:
    HapticThread's ``estop``, ``touches``, ``snapshots``, ``touch_force``."""
    from frictex.app.live.haptic_thread import HapticThread, link_options
    from frictex.app.live.touch_pump import TouchPump
    haptic = None
    try:
        haptic = HapticThread(scene, rate_hz, block_size, render_override, control=control,
                              **queues)
        pipeline = haptic.pipeline
        if source is not None:
            haptic.pump = TouchPump(source, haptic, lambda: haptic.pipeline.scene.display,
                                    lambda: haptic.touch_force.value)
        if device is not None:
            from frictex.device.link.host import open_sink
            haptic.sink = open_sink(device, channels=len(pipeline.channels), rate_hz=rate_hz,
                                    phases=pipeline.actuation.has_phases, paced=False,
                                    faults=faults, sim_args=tuple(sim_args),
                                    profile=pipeline.scene.device.profile,
                                    **link_options(haptic.block_s))
        if record is not None:
            record.mkdir(parents=True, exist_ok=True)
            tables = TableSink(record, pipeline.channels, pipeline.actuation.has_phases, "csv",
                               pipeline.forces is not None)
            haptic.recorder = ThreadedSink(tables, RECORD_QUEUE, name="frictex-recorder")
            haptic.touch_log = ThreadedSink(
                TouchTable(record / TOUCHES, touches_comment(pipeline.scene.name, block_size)),
                RECORD_QUEUE, name="frictex-touch-log")
    except BaseException:
        if haptic is not None and haptic.sink is not None:
            haptic.sink.close()
        if haptic is not None and haptic.recorder is not None:
            haptic.recorder.abort()
        if source is not None:
            source.close()  # the pump never started: it is the source's only owner
        raise

    def finish():
        if haptic.pump is not None:
            haptic.pump.stop()
            haptic.stats.input = haptic.pump.counters()
        haptic.stop()
        if haptic.is_alive():
            haptic.join(timeout=JOIN_TIMEOUT_S)
            if haptic.is_alive():
                print(f"frictex: warning: the haptic thread did not end within "
                      f"{JOIN_TIMEOUT_S:g} s; its recording may be incomplete", file=sys.stderr)
        elif not haptic.ident:  # never started: nothing committed the sinks
            for sink in (haptic.recorder, haptic.touch_log, haptic.sink):
                if sink is not None:
                    (sink.close if sink is haptic.sink else sink.abort)()
        link = haptic.sink.status() if haptic.sink is not None else {"state": "none"}
        return link, sum(log.dropped for log in (haptic.recorder, haptic.touch_log)
                         if log is not None)

    return haptic, finish
