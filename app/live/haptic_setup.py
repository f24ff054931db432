"""The live haptic thread with its link (``--device``) and recording (``--record``), set up
and torn down together; used by the demo in thread mode and by the haptic child process."""

from __future__ import annotations

import queue
import threading
from pathlib import Path

from app.engine.replay import FRICTION_COLUMNS, friction_rows
from app.engine.tables import TableWriter

RECORD_QUEUE = 4000  # blocks (20 s at 5 ms) the writer may fall behind before dropping


class Recorder:
    """Writes each block's commands and friction rows on its own thread; the haptic
    thread only enqueues (a full queue drops the block, counted in ``dropped``)."""

    def __init__(self, out_dir: Path, channels: tuple[str, ...], phases: bool = False):
        out_dir.mkdir(parents=True, exist_ok=True)
        self.channels = channels
        self.phases = phases
        cols = [("t_s", float, "%.7f")] + [(f"{ch}_um", float, "%.6f") for ch in channels]
        if phases:
            cols += [(f"{ch}_phase_rad", float, "%.6f") for ch in channels]
        self.commands = TableWriter(out_dir, "commands", cols, "csv")
        self.friction = TableWriter(out_dir, "friction", FRICTION_COLUMNS, "csv")
        self.queue: queue.Queue = queue.Queue(RECORD_QUEUE)
        self.dropped = 0
        self.thread = threading.Thread(target=self._run, name="frictex-recorder", daemon=True)
        self.thread.start()

    def __call__(self, out, commands_um) -> None:
        try:
            self.queue.put_nowait((out, commands_um))
        except queue.Full:
            self.dropped += 1

    def _run(self) -> None:
        while (item := self.queue.get()) is not None:
            out, commands = item
            cols = {"t_s": out.t_s}
            cols.update({f"{ch}_um": commands[:, k] for k, ch in enumerate(self.channels)})
            if self.phases:
                cols.update({f"{ch}_phase_rad": out.phases_rad[:, k]
                             for k, ch in enumerate(self.channels)})
            self.commands.write(cols)
            self.friction.write(friction_rows(out))

    def close(self) -> None:
        self.queue.put(None)
        self.thread.join()
        self.commands.commit()
        self.friction.commit()


def open_haptic(scene, rate_hz: float, block_size: int, render_override: str | None,
                device: str | None, record: Path | None, **queues):
    """A :class:`HapticThread` (not started) for ``scene`` with its link (``--device``) and
    recorder (``--record``), and ``finish() -> (link status, dropped record blocks)``,
    which stops the thread and closes them. ``queues``: HapticThread's ``estop``,
    ``touches``, ``snapshots``."""
    from app.live.haptic_thread import HapticThread
    haptic = HapticThread(scene, rate_hz, block_size, render_override, **queues)
    pipeline = haptic.pipeline
    if device is not None:
        from device.link.host import open_sink
        haptic.sink = open_sink(device, channels=len(pipeline.channels), rate_hz=rate_hz,
                                phases=pipeline.actuation.has_phases, paced=False)
    try:
        if record is not None:
            haptic.recorder = Recorder(record, pipeline.channels, pipeline.actuation.has_phases)
    except BaseException:
        if haptic.sink is not None:
            haptic.sink.close()
        raise

    def finish():
        haptic.stop()
        if haptic.is_alive():
            haptic.join(timeout=2.0)
        if haptic.recorder is not None:
            haptic.recorder.close()
        link = haptic.sink.status() if haptic.sink is not None else {"state": "none"}
        if haptic.sink is not None:
            haptic.sink.close()
        return link, haptic.recorder.dropped if haptic.recorder is not None else 0

    return haptic, finish
