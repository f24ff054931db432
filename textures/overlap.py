"""The lowest mu' a scene's layers ask for together, where they overlap.

Layers multiply (``rendering.compose``), so where several cover the same place their
product can fall below what any of them asks for alone, and below the device's floor.
:func:`lowest_overlap` bounds it from the layers' boxes (``textures.extent.lowering``):
the display is cut along every box's edges into cells, and in each cell every layer
whose box holds it contributes its lowest mu' there (at most 1). The lowest cell's
product is never above the lowest composed mu' the layers can ask for (a ``replace``
layer, which drops what lies below it, is counted as a multiplying one), and layers
whose boxes share no area never multiply in it. Cells are open: boxes that only touch
along an edge do not overlap.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from frictex.textures.clips import ClipLayer
from frictex.textures.dynamic import DynamicLayer
from frictex.textures.extent import lowering


@dataclass(frozen=True)
class Overlap:
    """The lowest product of the layers' lowest mu' where they overlap.

    lowest : that product (1.0 if no layer lowers mu').
    names : the layers that lower mu' there, in file order.
    at_mm : a position (x, y) (mm) inside the cell where it is reached.
    """

    lowest: float
    names: tuple[str, ...]
    at_mm: tuple[float, float]


def lowest_overlap(display, layers, under: int | None = None) -> Overlap:
    """:class:`Overlap` of ``layers`` (a sequence of scene layers) on ``display``
    (see the module docstring); with ``under``, only where ``layers[under]`` lowers mu'
    (1.0 and no names where it lowers it nowhere). O(n^3) for n boxes, a few ms for 32
    layers."""
    pieces = [lowering(layer, display) for layer in layers]
    boxes = [box for layer_pieces in pieces for box, _ in layer_pieces]
    if not boxes:
        return Overlap(1.0, (), (display.width_mm / 2, display.height_mm / 2))
    xs = np.unique([v for box in boxes for v in (box[0], box[2])])
    ys = np.unique([v for box in boxes for v in (box[1], box[3])])
    mx, my = (xs[:-1] + xs[1:]) / 2, (ys[:-1] + ys[1:]) / 2
    factors = np.ones((len(layers), my.size, mx.size))
    for factor, layer_pieces in zip(factors, pieces):
        for (x0, y0, x1, y1), mu in layer_pieces:
            inside = ((my > y0) & (my < y1))[:, None] & ((mx > x0) & (mx < x1))[None, :]
            np.minimum(factor, np.where(inside, mu, 1.0), out=factor)
    product = factors.prod(axis=0)
    if under is not None:
        if not (factors[under] < 1.0).any():
            return Overlap(1.0, (), (display.width_mm / 2, display.height_mm / 2))
        product = np.where(factors[under] < 1.0, product, np.inf)
    row, col = np.unravel_index(int(np.argmin(product)), product.shape)
    names = tuple(layer.name for layer, factor in zip(layers, factors) if factor[row, col] < 1.0)
    return Overlap(float(product[row, col]), names, (float(mx[col]), float(my[row])))


def applies_alone(layer) -> bool:
    """True if the layer applies to a finger touching alone: selectors ``any``, ``1`` and
    the positional ones, not ``2``, ``3``, ..."""
    return not layer.fingers.isdigit() or layer.fingers == "1"


def under_clips(display, layers) -> list[tuple[int, Overlap]]:
    """For each clip layer a lone finger feels (its index in ``layers``), the
    :class:`Overlap` of it and the layers fixed in place that a lone finger feels, where
    the clip plays: the lowest its deepest mu' times theirs. Height layers and recorded
    textures (whose mu' moves with the finger: their lowest is seldom met) and other clips
    (which play at their own times) are left out."""
    fixed = [layer for layer in layers
             if applies_alone(layer) and not isinstance(layer, DynamicLayer)]
    return [(index, lowest_overlap(display, [layer, *fixed], under=0))
            for index, layer in enumerate(layers)
            if isinstance(layer, ClipLayer) and applies_alone(layer)]
