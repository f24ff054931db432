"""A finger's trail as the vertices worth drawing, kept as its samples arrive.

A trail sampled every 0.5 ms moves a fraction of a pixel between samples: ``thin_polyline``
keeps a vertex per ``TRAIL_STEP_PX`` of path (and both ends of every break). A
:class:`TrailPath` thins each new stretch of samples once, when it arrives, and keeps
the vertices in frame pixels, so that a frame draws the few hundred vertices of the last
second instead of thinning its thousands of samples again (the overlay's per-frame cost).
"""

from __future__ import annotations

import math

import numpy as np

from frictex.device.jit import njit
from frictex.rendering.tracking.tracks import TrackerConfig
from frictex.rendering.visual.viewport import Viewport

TRAIL_STEP_PX = 1.0  # a trail keeps a vertex per this much of its path (and its breaks)
#: a trail step longer than this (mm) and faster than this (mm/s) is a lift and a touch
#: elsewhere within one block, not a stroke: not joined (the tracker's jump rule,
#: rendering.tracking.tracks; shorter steps are the prediction catching up with a new sample)
TRAIL_BREAK_MM, TRAIL_BREAK_MM_S = TrackerConfig.jump_min_mm, TrackerConfig.jump_speed_mm_s


@njit(cache=True, nogil=True)
def thin_polyline(points: np.ndarray, joined: np.ndarray,
                  step_px: float) -> tuple[np.ndarray, np.ndarray]:
    """The vertices of a polyline worth drawing: its first and last, each end of a break,
    and one wherever the path has gone another ``step_px``.

    Parameters
    ----------
    points : (n,) x 2 px, n >= 1. joined : (n - 1,) bool, the segments drawn.
    step_px : path length (px) between kept vertices.

    Returns
    -------
    kept : (k,) indices of the kept vertices, increasing. joined : (k - 1,) bool, whether
    every segment between two kept vertices was drawn.
    """
    n = points.shape[0]
    keep = np.zeros(n, dtype=np.bool_)
    keep[0] = keep[n - 1] = True
    length, mark = 0.0, 0.0  # the path's length (px) to vertex i, and floor(length / step)
    for i in range(1, n):
        length += math.hypot(points[i, 0] - points[i - 1, 0], points[i, 1] - points[i - 1, 1])
        step_mark = np.floor(length / step_px)  # NaN after a NaN point: every vertex kept
        if step_mark != mark or not joined[i - 1]:
            keep[i] = True
        if not joined[i - 1]:
            keep[i - 1] = True
        mark = step_mark
    kept = np.flatnonzero(keep)
    kept_joined = np.ones(max(kept.size - 1, 0), dtype=np.bool_)
    for k in range(kept.size - 1):
        for i in range(kept[k], kept[k + 1]):
            if not joined[i]:
                kept_joined[k] = False
    return kept, kept_joined


@njit(cache=True, nogil=True)
def joined_steps(t_s: np.ndarray, contact: np.ndarray, x_mm: np.ndarray, y_mm: np.ndarray,
                 break_mm: float, break_mm_s: float) -> np.ndarray:
    """(n - 1,) bool: whether each step between consecutive samples (t s, contact, x and
    y mm) is drawn: both ends touching, and not a jump (longer than ``break_mm`` and
    faster than ``break_mm_s`` mm/s)."""
    joined = np.empty(max(t_s.size - 1, 0), dtype=np.bool_)
    for i in range(joined.size):
        step = math.hypot(x_mm[i + 1] - x_mm[i], y_mm[i + 1] - y_mm[i])
        joined[i] = (contact[i] > 0 and contact[i + 1] > 0
                     and (step <= break_mm or step <= break_mm_s * (t_s[i + 1] - t_s[i])))
    return joined


class TrailPath:
    """One finger's thinned trail in the frame pixels of ``viewport``, taken in as its
    samples arrive.

    Holds the touching vertices ``thin_polyline`` keeps (each stretch of new samples
    thinned with the last sample before it, so each stretch's last sample is a vertex
    too), their times (s) and whether the segment into each from the vertex before is
    drawn.
    """

    def __init__(self, viewport: Viewport):
        self.viewport = viewport
        self.taken_s = -np.inf  # the time (s) of the latest sample taken in
        self.last: np.ndarray | None = None  # that sample: t s, contact, x mm, y mm, x px, y px
        self.points_px = np.empty((0, 2))
        self.t_s = np.empty(0)
        self.joined = np.empty(0, dtype=bool)

    def take(self, t_s: np.ndarray, contact: np.ndarray, x_mm: np.ndarray,
             y_mm: np.ndarray) -> None:
        """Take in those of the samples (t s increasing, contact, x and y mm) later than
        the ones taken before."""
        first = int(np.searchsorted(t_s, self.taken_s, side="right"))
        if first == t_s.size:
            return
        px, py = self.viewport.to_px(x_mm[first:], y_mm[first:])
        new = np.stack((t_s[first:], contact[first:], x_mm[first:], y_mm[first:], px, py))
        rows = new if self.last is None else np.column_stack((self.last, new))
        joined = joined_steps(*rows[:4], TRAIL_BREAK_MM, TRAIL_BREAK_MM_S)
        # C order whatever the count (a single sample's (1, 2) is both orders to numba)
        kept, kept_joined = thin_polyline(np.ascontiguousarray(rows[4:].T), joined, TRAIL_STEP_PX)
        if self.last is None:  # the first vertex has none before it
            joined_into = np.concatenate(([False], kept_joined))
        else:  # the sample before: a vertex already where it touches
            kept, joined_into = kept[1:], kept_joined
        touching = rows[1, kept] > 0  # only touching vertices end a drawn segment
        kept, joined_into = kept[touching], joined_into[touching]
        self.points_px = np.concatenate((self.points_px, rows[4:, kept].T))
        self.t_s = np.concatenate((self.t_s, rows[0, kept]))
        self.joined = np.concatenate((self.joined, joined_into))
        self.last, self.taken_s = rows[:, -1], float(rows[0, -1])

    def since(self, start_s: float) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
        """The vertices from the latest one before ``start_s`` (s) on, forgetting older
        ones: points (k, 2) px, times (k,) s, joined (k - 1,) bool (each segment drawn)."""
        first = max(int(np.searchsorted(self.t_s, start_s)) - 1, 0)
        self.points_px, self.t_s, self.joined = (self.points_px[first:], self.t_s[first:],
                                                 self.joined[first:])
        return self.points_px, self.t_s, self.joined[1:]
