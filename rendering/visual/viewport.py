"""Where the scene's active area sits in a frame of pixels, and mm <-> pixel transforms.

In a window (a mouse on a desktop monitor) the active area (``Display.width_mm`` x
``height_mm``) is fitted inside the frame keeping its aspect ratio, centred, on whole
pixels (:func:`fit_viewport`). On the glass (:func:`on_glass`: a fullscreen frame at the
display's own pixels, or one a touch screen drives) it fills the whole frame, mm -> px
per axis (``width_px / width_mm``, ``height_px / height_mm``: a panel's pixels need not
be square), so that every drawn mm is the mm felt there (:func:`glass_viewport`). The
mouse maps back through the same :class:`Viewport`. Pixel coordinates are continuous:
pixel column i spans [i, i + 1), so its centre is at i + 0.5. Nothing here truncates
positions to integers.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from frictex.textures.model import Display


@dataclass(frozen=True)
class Viewport:
    """A frame of ``frame_w`` x ``frame_h`` px holding the active area at
    (``x0``, ``y0``) px (top-left), ``width_px`` x ``height_px`` px in size, which
    shows ``width_mm`` x ``height_mm`` of the screen."""

    frame_w: int
    frame_h: int
    x0: int
    y0: int
    width_px: int
    height_px: int
    width_mm: float
    height_mm: float

    @property
    def px_per_mm(self) -> tuple[float, float]:
        """Pixel density (px/mm) of the drawn area along x and y."""
        return self.width_px / self.width_mm, self.height_px / self.height_mm

    def to_px(self, x_mm, y_mm) -> tuple[np.ndarray, np.ndarray]:
        """Frame pixel coordinates (float, y down) of positions (mm)."""
        sx, sy = self.px_per_mm
        return (self.x0 + np.asarray(x_mm, dtype=np.float64) * sx,
                self.y0 + np.asarray(y_mm, dtype=np.float64) * sy)

    def to_mm(self, x_px, y_px) -> tuple[np.ndarray, np.ndarray]:
        """Positions (mm) of frame pixel coordinates (float, y down)."""
        sx, sy = self.px_per_mm
        return ((np.asarray(x_px, dtype=np.float64) - self.x0) / sx,
                (np.asarray(y_px, dtype=np.float64) - self.y0) / sy)


    def contains_px(self, x_px: float, y_px: float) -> bool:
        """Whether frame pixel coordinates (float, y down) fall on the drawn active area,
        edges included: where a press may touch the scene (not the scope strip, a panel
        column, the letterbox, or beyond the window while a drag goes on)."""
        return (self.x0 <= x_px <= self.x0 + self.width_px
                and self.y0 <= y_px <= self.y0 + self.height_px)


def fit_viewport(display: Display, frame_w: int, frame_h: int) -> Viewport:
    """The largest aspect-preserving placement of ``display``'s active area in a frame."""
    if frame_w < 1 or frame_h < 1:
        raise ValueError(f"frame size {frame_w}x{frame_h} px: expected at least 1x1")
    scale = min(frame_w / display.width_mm, frame_h / display.height_mm)
    w = max(1, min(frame_w, round(display.width_mm * scale)))
    h = max(1, min(frame_h, round(display.height_mm * scale)))
    return Viewport(frame_w, frame_h, (frame_w - w) // 2, (frame_h - h) // 2, w, h,
                    display.width_mm, display.height_mm)


def glass_viewport(display: Display, frame_w: int, frame_h: int) -> Viewport:
    """The active area over the whole frame, scaled per axis (px/mm: ``frame_w /
    width_mm`` along x, ``frame_h / height_mm`` along y): the frame is the glass."""
    if frame_w < 1 or frame_h < 1:
        raise ValueError(f"frame size {frame_w}x{frame_h} px: expected at least 1x1")
    return Viewport(frame_w, frame_h, 0, 0, frame_w, frame_h, display.width_mm, display.height_mm)


def on_glass(display: Display, frame_size: tuple[int, int], fullscreen: bool,
             touch_screen: bool) -> bool:
    """Whether the frame must coincide with the glass: it is fullscreen and either at the
    display's own ``width_px`` x ``height_px`` or driven by a touch screen (whose touches
    are mapped to the whole panel, ``rendering.input``)."""
    own = tuple(int(v) for v in frame_size) == (display.width_px, display.height_px)
    return bool(fullscreen) and (own or bool(touch_screen))


#: smallest default frame (px): room for the status lines, the scope and a device panel
MIN_FRAME = (640, 480)
#: the scope strip's height: this share of the frame's height, within SCOPE_PX
SCOPE_SHARE, SCOPE_PX = 0.22, (100, 220)


def scope_height(frame_h: int) -> int:
    """Height (px) of the scope strip at the bottom of a frame ``frame_h`` px high."""
    return int(round(np.clip(SCOPE_SHARE * frame_h, *SCOPE_PX)))


def frame_layout(display: Display, frame_w: int, frame_h: int, scope: bool, side_px: int = 0,
                 left_px: int = 0, glass: bool = False
                 ) -> tuple[Viewport, tuple[float, float, float, float] | None,
                            tuple[float, float, float, float]]:
    """Where the active area, the scope strip and the panel column go in a frame.

    ``glass``: the active area fills the frame (:func:`glass_viewport`) and the strip and
    the columns, placed as below, lie over it: they never move the scene.

    With ``scope`` the strip (x, y, w, h px) takes the bottom ``scope_height`` px and the
    active area is fitted above it, never under it (in a frame too low for both, each
    gets half); without, the strip is None. ``side_px``: a column that wide at the right
    of the frame, above the strip, is kept for a device panel (at most half the frame)
    and the active area is fitted beside it, never under it. ``left_px``: likewise a
    column at the left (the demo's layer panel; at most half of what the right one
    leaves).

    Returns
    -------
    (viewport, strip, column)
        ``column`` is the kept column (x, y, w, h px), 0 px wide when none is asked for.
    """
    strip = min(scope_height(frame_h), frame_h // 2) if scope else 0
    side = min(max(int(side_px), 0), frame_w // 2)
    left = min(max(int(left_px), 0), (frame_w - side) // 2)
    rect = (0.0, float(frame_h - strip), float(frame_w), float(strip)) if scope else None
    column = (float(frame_w - side), 0.0, float(side), float(frame_h - strip))
    if glass:
        return glass_viewport(display, frame_w, frame_h), rect, column
    area = fit_viewport(display, max(frame_w - side - left, 1), max(frame_h - strip, 1))
    return replace(area, x0=area.x0 + left, frame_w=frame_w, frame_h=frame_h), rect, column


def default_frame_size(display: Display, side_px: int = 0) -> tuple[int, int]:
    """A frame showing the display at its own pixel size above the scope strip (and
    beside a panel column ``side_px`` wide), at least MIN_FRAME (a thin beam is
    letterboxed)."""
    h = max(display.height_px, 1)
    while h - scope_height(h) < display.height_px:
        h += 1
    return max(display.width_px + max(int(side_px), 0), MIN_FRAME[0]), max(h, MIN_FRAME[1])
