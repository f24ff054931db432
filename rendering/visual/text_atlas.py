"""Text images packed into one texture, so that every label of a frame is drawn by one call.

Texts are placed on shelves (rows as high as their tallest text) left to right, top to
bottom, and kept while the frame's texts recur (a status line, the scope's labels).
When a new text does not fit, the atlas is emptied and packing starts again: the caller
first draws what it has queued (``on_full``), since those quads point into the old
content. A text larger than the atlas is cropped to it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Callable

import moderngl
import numpy as np

ATLAS_PX = 2048  # side of the atlas (px); wider where the frame is wider
GAP_PX = 1  # empty pixels between texts (NEAREST sampling never reaches a neighbour)


@dataclass(frozen=True)
class AtlasEntry:
    """Where a text lies in its atlas: the top-left corner (x, y) and ``size`` = (w, h) px."""

    x: int
    y: int
    size: tuple[int, int]


class TextAtlas:
    """An RGBA texture of ``width`` x ``ATLAS_PX`` px holding text images by key.

    ``on_full()`` is called before the atlas is emptied to make room.
    """

    def __init__(self, ctx: moderngl.Context, width: int, on_full: Callable[[], None]):
        self.width, self.height = max(ATLAS_PX, int(width)), ATLAS_PX
        self.texture = ctx.texture((self.width, self.height), 4, alignment=1)
        self.texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.on_full = on_full
        self.entries: dict[tuple, AtlasEntry] = {}
        self._x = self._y = self._shelf = 0

    def get(self, key: tuple, image: Callable[[], np.ndarray]) -> AtlasEntry:
        """The entry of ``key``, packing ``image()`` (uint8 (h, w, 4), row 0 on top) the
        first time."""
        entry = self.entries.get(key)
        if entry is not None:
            return entry
        img = np.ascontiguousarray(image()[:self.height, :self.width])
        h, w = img.shape[:2]
        if self._x + w > self.width:  # next shelf
            self._x, self._y, self._shelf = 0, self._y + self._shelf + GAP_PX, 0
        if self._y + h > self.height:
            self.on_full()
            self.entries.clear()
            self._x = self._y = self._shelf = 0
        entry = AtlasEntry(self._x, self._y, (w, h))
        if w and h:
            self.texture.write(img.tobytes(), viewport=(self._x, self._y, w, h), alignment=1)
        self._x += w + GAP_PX
        self._shelf = max(self._shelf, h)
        self.entries[key] = entry
        return entry

    def uv(self, entry: AtlasEntry) -> tuple[float, float, float, float]:
        """Texture coordinates (u0, v0, u1, v1) of ``entry``'s corners (v0 at its top row)."""
        w, h = entry.size
        return (entry.x / self.width, entry.y / self.height,
                (entry.x + w) / self.width, (entry.y + h) / self.height)

    def release(self) -> None:
        self.texture.release()
