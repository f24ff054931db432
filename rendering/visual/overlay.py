"""What moves on top of the scene: finger cursors, their trails, the scope strip, and
for the devices that push a finger (seeds 002, 004) the force on each finger as an arrow.

:class:`OverlayState` keeps the recent history the haptic side produced (fed with
:class:`BlockRecord` snapshots, decimated copies of ``rendering.pipeline.BlockOutput``)
and turns it into vertex arrays in frame pixels for ``compositor`` (each finger's trail
thinned once, as its samples arrive: ``trail``); it does no OpenGL, so its geometry is
tested without a context.

The scope shows, for the last ``scope_s`` seconds and per finger, the mu' target
(upper plot, 0 to 1) and the vibration amplitude under the finger (lower plot,
0 to the device's amplitude limit, um zero-to-peak); "now" is the right edge
(``scope_ring`` draws it from this history). Each
plot keeps ``SCOPE_PAD_PX`` free above its full scale and below its zero, so a trace
at mu' = 1 or at the limit is never drawn on the plot's edge.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from frictex.device.jit import njit
from frictex.rendering.layers.keyclick import IDLE
from frictex.rendering.visual.trail import TrailPath
from frictex.rendering.visual.viewport import Viewport

#: cursor/trace colour per finger (sRGB, 0-1): finger k uses FINGER_RGB[k % len]
FINGER_RGB = ((0.10, 0.60, 1.00), (1.00, 0.45, 0.10), (0.20, 0.80, 0.30),
              (0.85, 0.25, 0.85), (0.95, 0.85, 0.10))
CURSOR_RADIUS_MM = 4.0  # about a fingertip contact patch
TRAIL_WIDTH_PX = 2.0
#: a dark band this wide (px) each side of a trail, as the cursors' halo ring: a trail
#: stays visible on a scene of its own colour (finger 0's blue on a blue grating)
TRAIL_OUTLINE_PX, TRAIL_OUTLINE_ALPHA = 1.5, 0.7
SCOPE_LINE_PX = 1.5
SCOPE_PAD_PX = 4.0  # between a plot's edge and its full scale (or zero) line


@dataclass(frozen=True, eq=False)
class BlockRecord:
    """A decimated copy of one block's output, safe to hand to another thread.

    t_s : (m,) s. finger_ids : F ids. contact : bool (F, m). x_mm, y_mm : (F, m) mm.
    mu_target : (F, m) mu'. amplitude_um : (F, m) um zero-to-peak.
    commands_um : (m, q) channel commands sent (um zero-to-peak); phases_rad : (m, q) rad
    or None. force_n, wanted_force_n : (F, m, 2) achieved and wanted force on each finger
    (N, display x and y) or None. button : (F, m) key-click state of each finger's button
    (``rendering.layers.keyclick`` IDLE, ON, CLICKED) or None (no button in the scene).
    """

    t_s: np.ndarray
    finger_ids: tuple[int, ...]
    contact: np.ndarray
    x_mm: np.ndarray
    y_mm: np.ndarray
    mu_target: np.ndarray
    amplitude_um: np.ndarray
    commands_um: np.ndarray | None = None
    phases_rad: np.ndarray | None = None
    force_n: np.ndarray | None = None
    wanted_force_n: np.ndarray | None = None
    button: np.ndarray | None = None


def record_from_output(out, stride: int = 10, lo: int = 0, hi: int | None = None,
                       commands_um: np.ndarray | None = None) -> BlockRecord:
    """Every ``stride``-th sample of ``out`` (a pipeline BlockOutput) in [lo, hi), copied;
    ``commands_um``: what was sent if not ``out.commands_um`` (an emergency stop, a ramp).
    The rows carry their finger ids at ``lo`` (a caller cuts where a row changes finger)."""
    s = slice(lo, hi, stride)
    ids = out.finger_ids if out.sample_ids is None else out.sample_ids[:, lo].tolist()
    commands = out.commands_um if commands_um is None else commands_um

    def take(a, axis):
        return None if a is None else np.array(a[(slice(None),) * axis + (s,)])

    forces = out.forces
    return BlockRecord(out.t_s[s].copy(), tuple(ids), out.contact[:, s].copy(),
                       out.x_mm[:, s].copy(), out.y_mm[:, s].copy(),
                       out.mu_target[:, s].copy(), out.amplitude_um[:, s].copy(),
                       take(commands, 0), take(out.phases_rad, 0),
                       None if forces is None else take(forces.achieved_n, 1),
                       None if forces is None else take(forces.wanted_n, 1),
                       None if forces is None else take(forces.button, 1))


class _History:
    """One finger's samples within the kept window (arrays grow by concatenation), and
    its trail as drawn in the latest frame's viewport."""

    def __init__(self):
        self.t = np.empty(0)
        self.data = np.empty((5, 0))  # contact, x, y, mu, amplitude
        self.trail: TrailPath | None = None

    def trail_in(self, viewport: Viewport) -> TrailPath:
        """The trail in ``viewport``'s pixels with every sample taken in (started again
        from the kept samples in a viewport other than the last one's)."""
        if self.trail is None or self.trail.viewport != viewport:
            self.trail = TrailPath(viewport)
        self.trail.take(self.t, *self.data[:3])
        return self.trail

    def append(self, t, rows, keep_from_s: float):
        self.t = np.concatenate((self.t, t))
        self.data = np.concatenate((self.data, rows), axis=1)
        k = np.searchsorted(self.t, keep_from_s)
        self.t, self.data = self.t[k:], self.data[:, k:]


class OverlayState:
    """History of the fingers for the trails (``trail_s``) and the scope (``scope_s``)."""

    def __init__(self, trail_s: float = 1.0, scope_s: float = 3.0):
        self.trail_s = trail_s
        self.scope_s = scope_s
        self.now_s = 0.0
        self.fingers: dict[int, _History] = {}
        #: how many times the history was cleared (what it drew before is stale)
        self.generation = 0
        #: the finger ids of the latest record (a finger not among them has gone)
        self.present: set[int] = set()
        #: at the latest sample: channel commands (q,) complex (um, phase), or None
        self.commands: np.ndarray | None = None
        #: at the latest sample, per touching finger id: (achieved, wanted) force (N, (2,))
        self.forces: dict[int, tuple[np.ndarray, np.ndarray]] = {}
        #: the key-click state at the latest sample (None: no button in the scene, or no
        #: block seen yet)
        self.button: int | None = None

    def add(self, record: BlockRecord) -> None:
        if record.t_s.size == 0:
            return
        self.now_s = max(self.now_s, float(record.t_s[-1]))
        self.present = set(record.finger_ids)
        keep = self.now_s - max(self.trail_s, self.scope_s)
        for row, fid in enumerate(record.finger_ids):
            rows = np.stack((record.contact[row].astype(np.float64), record.x_mm[row],
                             record.y_mm[row], record.mu_target[row], record.amplitude_um[row]))
            self.fingers.setdefault(fid, _History()).append(record.t_s, rows, keep)
        for fid in [f for f in self.fingers if f not in record.finger_ids]:
            history = self.fingers[fid]  # gone from the tracks: its trail fades out
            history.append(record.t_s[:0], np.empty((5, 0)), keep)
            if history.t.size == 0:  # and then it is forgotten
                del self.fingers[fid]
        if record.commands_um is not None:
            phase = 0.0 if record.phases_rad is None else record.phases_rad[-1]
            self.commands = record.commands_um[-1] * np.exp(1j * phase)
        if record.button is not None:  # the furthest any finger got (0 with no finger)
            self.button = int(record.button[:, -1].max(initial=IDLE))
        self.forces = {}
        if record.force_n is not None:
            for row, fid in enumerate(record.finger_ids):
                if record.contact[row, -1]:
                    self.forces[fid] = (record.force_n[row, -1], record.wanted_force_n[row, -1])

    def clear(self) -> None:
        self.fingers.clear()
        self.generation += 1
        self.present = set()
        self.commands, self.forces, self.button = None, {}, None

    def _touching(self, fid: int, h: _History) -> bool:
        """Whether finger ``fid`` touches now: in the latest record, touching at its
        latest sample (a finger gone from the tracks has lifted, whatever its last
        sample said)."""
        return fid in self.present and h.t.size > 0 and h.data[0, -1] > 0

    def current(self) -> list[tuple[int, float, float, bool]]:
        """(finger id, x mm, y mm, True) of each finger touching now."""
        return [(fid, float(h.data[1, -1]), float(h.data[2, -1]), True)
                for fid, h in sorted(self.fingers.items()) if self._touching(fid, h)]

    def lifted(self) -> list[tuple[int, float, float, float]]:
        """(finger id, x mm, y mm, s since its last contact) of each finger that touched
        within the last ``trail_s`` and does not touch now, at its latest position."""
        out = []
        for fid, h in sorted(self.fingers.items()):
            touched = np.flatnonzero(h.data[0] > 0)
            if self._touching(fid, h) or touched.size == 0:
                continue
            age = self.now_s - float(h.t[touched[-1]])
            if age <= self.trail_s:
                out.append((fid, float(h.data[1, -1]), float(h.data[2, -1]), age))
        return out

    # -- geometry in frame pixels -------------------------------------------------------

    def trail_triangles(self, viewport: Viewport) -> np.ndarray:
        """Triangles (k, 6) of x_px, y_px, r, g, b, a for the touching part of each trail,
        fading out over ``trail_s``; broken where the finger lifted or jumped. The trails
        are dark outlines (``TRAIL_OUTLINE_PX`` each side), then their coloured lines on
        top, in drawing order."""
        outlines, lines = [], []
        for fid, h in self.fingers.items():
            points, t, joined = h.trail_in(viewport).since(self.now_s - self.trail_s)
            if t.size < 2:
                continue
            outline, line = _fading_trail(points, t, joined, self.now_s, self.trail_s,
                                          np.array(FINGER_RGB[fid % len(FINGER_RGB)]))
            outlines.append(outline)
            lines.append(line)
        return np.concatenate(outlines + lines) if outlines else np.empty((0, 6))

    def cursors(self, viewport: Viewport, hover_mm: tuple[float, float] | None = None) -> np.ndarray:
        """Cursor instances (k, 8): x_px, y_px, radius_px, r, g, b, a, filled. A touching
        finger is a filled ring (a dot inside) in its colour; a lifted one a hollow ring
        in its colour, fading out with its trail over ``trail_s``; the hover pointer a
        hollow grey ring."""
        radius = CURSOR_RADIUS_MM * min(viewport.px_per_mm)
        rows = []
        for fid, x, y, _ in self.current():
            px, py = viewport.to_px(x, y)
            rows.append((float(px), float(py), radius, *FINGER_RGB[fid % len(FINGER_RGB)], 1.0, 1.0))
        for fid, x, y, age in self.lifted():
            px, py = viewport.to_px(x, y)
            alpha = 0.9 * (1.0 - age / self.trail_s)
            rows.append((float(px), float(py), radius, *FINGER_RGB[fid % len(FINGER_RGB)], alpha, 0.0))
        if hover_mm is not None:
            px, py = viewport.to_px(*hover_mm)
            rows.append((float(px), float(py), radius, 0.6, 0.6, 0.6, 0.9, 0.0))
        return np.array(rows, dtype=np.float64).reshape(-1, 8)

    def force_arrows(self, viewport: Viewport, px_per_n: float) -> np.ndarray:
        """Triangles (k, 6) of the force on each touching finger, from its centre, ``px_per_n``
        px long per N: the achieved force solid in the finger's colour, the wanted one a
        thin white line (where they differ, the device could not give what the scene asked)."""
        parts = []
        for fid, x, y, _ in self.current():
            if fid not in self.forces:
                continue
            px, py = viewport.to_px(x, y)
            achieved, wanted = self.forces[fid]
            rgb = FINGER_RGB[fid % len(FINGER_RGB)]
            parts.append(arrow_triangles((px, py), wanted * px_per_n, (1.0, 1.0, 1.0, 0.8), 1.5))
            parts.append(arrow_triangles((px, py), achieved * px_per_n, (*rgb, 1.0), 4.0))
        return np.concatenate(parts) if parts else np.empty((0, 6))


def plot_y(values, rect) -> np.ndarray:
    """Heights (px) of ``values`` (clipped to [0, 1]: 1 is full scale) in a scope plot
    ``rect`` = (x, y, w, h) px: full scale ``SCOPE_PAD_PX`` below its top edge, zero as
    far above its bottom edge."""
    _, y, _, h = rect
    v = np.clip(np.asarray(values, dtype=np.float64), 0.0, 1.0)
    return y + SCOPE_PAD_PX + (h - 2.0 * SCOPE_PAD_PX) * (1.0 - v)


def arrow_triangles(origin, vector_px, rgba, width_px: float) -> np.ndarray:
    """An arrow from ``origin`` (px) along ``vector_px`` (2,): a shaft ``width_px`` wide and
    a head 3 widths wide (triangles (k, 6) of x, y, r, g, b, a; none for a null vector)."""
    vector = np.asarray(vector_px, dtype=np.float64)
    length = float(np.hypot(*vector))
    if length < 0.5:
        return np.empty((0, 6))
    unit = vector / length
    normal = np.array([-unit[1], unit[0]])
    head = min(length, 4.0 * width_px)
    tip = np.asarray(origin, dtype=np.float64) + vector
    base = tip - unit * head
    colour = np.tile(rgba, (2, 1))
    shaft = segment_triangles(np.array([origin, base]), colour, width_px)
    wings = np.array([tip, base + normal * 1.5 * width_px, base - normal * 1.5 * width_px])
    return np.concatenate((shaft, np.column_stack((wings, np.tile(rgba, (3, 1))))))


def segment_triangles(points: np.ndarray, rgba: np.ndarray, width_px: float,
                      keep: np.ndarray | None = None) -> np.ndarray:
    """A polyline as independent quads, two triangles per segment.

    Parameters
    ----------
    points : (N, 2) vertices (px). rgba : (N, 4) colour per vertex.
    width_px : line width (px). keep : optional (N - 1,) bool, segments to draw.

    Returns
    -------
    (6 * kept segments, 6) array of x, y, r, g, b, a (segments of zero length left out).
    """
    segments = max(len(points) - 1, 0)
    if keep is None:
        keep = np.ones(segments, dtype=bool)
    elif np.shape(keep) != (segments,):
        raise ValueError(f"keep: {np.shape(keep)} for {segments} segments")
    return _segment_triangles(np.asarray(points, dtype=np.float64),
                              np.asarray(rgba, dtype=np.float64), float(width_px), keep)


@njit(cache=True, nogil=True)
def _segment_triangles(points, rgba, width_px, keep):
    drawn = np.zeros(keep.size, dtype=np.bool_)
    for i in range(keep.size):
        drawn[i] = keep[i] and math.hypot(points[i + 1, 0] - points[i, 0],
                                          points[i + 1, 1] - points[i, 1]) > 1e-9
    tris = np.empty((6 * np.count_nonzero(drawn), 2 + rgba.shape[1]))
    row = 0
    for i in np.flatnonzero(drawn):
        dx, dy = points[i + 1, 0] - points[i, 0], points[i + 1, 1] - points[i, 1]
        length = math.hypot(dx, dy)
        nx, ny = -dy / length * (width_px / 2), dx / length * (width_px / 2)
        # corners p0+n, p0-n, p1+n, p1+n, p0-n, p1-n, each in its end's colour
        for end, side in ((0, 1.0), (0, -1.0), (1, 1.0), (1, 1.0), (0, -1.0), (1, -1.0)):
            tris[row, 0] = points[i + end, 0] + side * nx
            tris[row, 1] = points[i + end, 1] + side * ny
            for c in range(rgba.shape[1]):
                tris[row, 2 + c] = rgba[i + end, c]
            row += 1
    return tris


@njit(cache=True, nogil=True)
def _fading_trail(points, t_s, keep, now_s, trail_s, rgb):
    """One finger's trail (``OverlayState.trail_triangles``): its outline's triangles and
    its line's, each vertex's opacity falling from 0.9 to 0 over ``trail_s`` (s) of age."""
    rgba = np.empty((t_s.size, 4))
    dark = np.zeros((t_s.size, 4))
    for i in range(t_s.size):
        alpha = 0.9 * (1.0 - min(max((now_s - t_s[i]) / trail_s, 0.0), 1.0))
        rgba[i, :3] = rgb
        rgba[i, 3] = alpha
        dark[i, 3] = alpha * (TRAIL_OUTLINE_ALPHA / 0.9)
    return (_segment_triangles(points, dark, TRAIL_WIDTH_PX + 2 * TRAIL_OUTLINE_PX, keep),
            _segment_triangles(points, rgba, TRAIL_WIDTH_PX, keep))
