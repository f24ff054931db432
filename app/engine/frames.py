"""PNG frames of the visual layer during a replay (``frictex replay ... --frames FPS``).

A :class:`FrameWriter` receives the replay's pipeline output chunk by chunk
(``add(out)``) and, at every frame time t0 + j / fps, draws the scene with the fingers,
their trails and the scope as they were at that instant into
``DIR/frames/frame_00000.png``, ``frame_00001.png``, ... Offscreen (EGL): no display
needed. ``ffmpeg -framerate FPS -i DIR/frames/frame_%05d.png out.mp4`` makes a video.
Modal devices show |W| from the commands of each frame's instant, devices that push a
finger its force and their buttons' state, as in the demo window.

A replay stages its outputs (``app.engine.staging``): it points the writer at its staging
folder (:meth:`FrameWriter.into`) before the first frame. Each frame is room-checked
(:data:`FRAME_BYTES_PER_PX` per pixel, or twice the last frame's size if larger) and
written under a temporary name, then renamed: a full disk never leaves a truncated PNG,
and the error names the frame.
"""

from __future__ import annotations

from pathlib import Path

import numpy as np
from PIL import Image

from frictex.device.actuation.factory import make_actuation
from frictex.device.errors import InputError
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.modal_view import modal_envelope
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.overlay import OverlayState, record_from_output
from frictex.rendering.visual.device_panels import default_frame_size
from frictex.textures.model import Scene
from frictex.app.engine.outfile import write_file

#: bytes per pixel a frame is counted at before it is written: five times the most the
#: bundled scenes' frames take (0.018-0.046 measured on grating-5mm, keyclick-ring and
#: two-finger-beam-seed000); a scene that compresses worse (a photograph as a raster
#: layer) is caught frame by frame, each counted at twice the last one's size
FRAME_BYTES_PER_PX = 0.25


class FrameWriter:
    """Writes frames at ``fps`` into ``out_dir/frames`` (see the module docstring).

    ``scene``: a Scene, or a texture file path / bundled scene name. ``size``: frame
    (width, height) px, default the scene's display size (at least ``MIN_FRAME``).
    """

    def __init__(self, out_dir, scene, fps: float, rate_hz: float = 10_000.0,
                 size: tuple[int, int] | None = None):
        if not fps > 0 or not np.isfinite(fps):
            raise InputError(f"frame rate {fps!r} fps: expected a positive number")
        if not isinstance(scene, Scene):
            from frictex.textures.library import resolve_scene
            from frictex.textures.loader import load_scene
            scene = load_scene(resolve_scene(scene))
        self.scene = scene
        self.fps = float(fps)
        self.folder = Path(out_dir) / "frames"
        self.last_bytes = 0
        self.size = size or default_frame_size(scene)
        self.backend = OffscreenBackend(self.size)
        self.compositor = Compositor(self.backend.ctx, scene, self.size)
        self.overlay = OverlayState()
        self.envelope = modal_envelope(scene, make_actuation(scene.device))
        self.envelope_scale_um = scene.device.amplitude_limit_um
        self.stride = max(1, int(rate_hz / 2000.0))  # 2 kHz is plenty for the scope
        self.t_first: float | None = None
        self.count = 0

    def into(self, out_dir) -> None:
        """Write the frames into ``out_dir/frames`` instead (before the first frame)."""
        self.folder = Path(out_dir) / "frames"

    def frame_bytes(self) -> float:
        """Bytes a frame is counted at in a room check (see the module docstring)."""
        return max(self.size[0] * self.size[1] * FRAME_BYTES_PER_PX, 2.0 * self.last_bytes)

    def frames_bytes(self, duration_s: float) -> float:
        """Bytes the frames of ``duration_s`` seconds of output are counted at."""
        return (int(duration_s * self.fps) + 1) * self.frame_bytes()

    def _frame_time(self, j: int) -> float:
        return self.t_first + j / self.fps

    def add(self, out) -> None:
        """Feed one chunk of pipeline output; writes every frame whose time it reaches."""
        t = out.t_s
        if self.t_first is None:
            self.t_first = float(t[0])
        lo = 0
        # a row that passes to another finger starts a new record there: trails per finger
        changes = sorted({lo for _, _, lo, _ in out.segments()} - {0})
        while self._frame_time(self.count) <= t[-1]:
            hi = int(np.searchsorted(t, self._frame_time(self.count), side="right"))
            if hi > lo:
                self._records(out, lo, hi, changes)
                lo = hi
            self._write(out, hi - 1)
        if lo < t.size:
            self._records(out, lo, t.size, changes)

    def _records(self, out, lo: int, hi: int, changes: list[int]) -> None:
        cuts = [lo, *(c for c in changes if lo < c < hi), hi]
        for a, b in zip(cuts[:-1], cuts[1:]):
            self.overlay.add(record_from_output(out, self.stride, a, b))

    def _write(self, out, i: int) -> None:
        touching = [f"finger {fid}: " + (
                        f"mu' {out.mu_target[row, i]:.3f}" if out.forces is None else
                        f"force {out.forces.achieved_n[row, i, 0]:+.3f} N (wanted "
                        f"{out.forces.wanted_n[row, i, 0]:+.3f})")
                    + f", {out.amplitude_um[row, i]:.2f} um"
                    for row, fid in enumerate(out.ids_per_sample()[:, i].tolist())
                    if out.contact[row, i]]
        status = (f"{self.scene.name} | replay t = {self._frame_time(self.count):.3f} s | "
                  + ("; ".join(touching) or "no finger touching"),)
        envelope = None
        if self.envelope is not None:
            envelope = self.envelope.at(self.overlay.commands, self.overlay.current())
            self.envelope_scale_um = max(self.envelope_scale_um, envelope.peak_um)
        self.backend.use()
        self.compositor.draw(FrameView(overlay=self.overlay, status=status,
                                       amplitude_max_um=self.scene.device.amplitude_limit_um,
                                       envelope=envelope, envelope_scale_um=self.envelope_scale_um))
        path = self.folder / f"frame_{self.count:05d}.png"
        self.folder.mkdir(parents=True, exist_ok=True)
        image = Image.fromarray(self.backend.read_rgb())
        write_file(path, lambda to: image.save(to, format="PNG"), self.frame_bytes())
        self.last_bytes = path.stat().st_size
        self.count += 1

    def close(self) -> None:
        self.compositor.release()
        self.backend.close()
