"""The frames a window shows, as numbered PNG files: what ``frictex demo --headless``
keeps of its screen (``rendering.visual.headless.HeadlessWindow``'s ``on_frame``)."""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np
from PIL import Image

FPS = 30.0  # at most this many frames a second are kept


class FrameFiles:
    """Writes frames to ``folder/frame-NNNNN.png``, at most ``fps`` a second of ``clock``
    (s); the folder's earlier ``frame-*.png`` are removed first, so that it holds this
    run's frames only. ``count``: frames written; ``save_s``: wall time spent encoding
    and writing them (s, on ``clock``), which the frames' drawing time includes."""

    def __init__(self, folder: Path, fps: float = FPS, clock=time.perf_counter):
        self.folder = Path(folder)
        self.folder.mkdir(parents=True, exist_ok=True)
        for old in self.folder.glob("frame-*.png"):
            old.unlink()
        self.step_s = 1.0 / fps
        self.clock = clock
        self.count = 0
        self.save_s = 0.0
        self._next = -np.inf

    def write(self, rgb: np.ndarray) -> None:
        """Keep ``rgb`` ((height, width, 3) uint8) if a frame is due."""
        now = self.clock()
        if now < self._next:
            return
        self._next = max(self._next + self.step_s, now)
        Image.fromarray(rgb).save(self.folder / f"frame-{self.count:05d}.png")
        self.count += 1
        self.save_s += self.clock() - now
