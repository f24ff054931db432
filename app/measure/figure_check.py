"""Legibility of a matplotlib figure: texts that overlap one another or leave the canvas.

``text_flaws(fig)`` draws the figure and compares the window extents (display pixels) of
the Text artists the draw drew: titles, labels, tick labels, legend entries and
annotations. Tests call it on every plot a command writes; a plotting function can call
it too before saving.
"""

from __future__ import annotations

from dataclasses import dataclass

#: pixels two extents may share before they count as overlapping (antialiased edges)
TOLERANCE_PX = 1.0


@dataclass(frozen=True)
class TextFlaw:
    """One flaw: ``kind`` is "overlap" (``text`` and ``other`` overlap) or "clipped"
    (``text`` leaves the canvas; ``other`` empty)."""

    kind: str
    text: str
    other: str = ""

    def __str__(self) -> str:
        if self.kind == "overlap":
            return f"{self.text!r} overlaps {self.other!r}"
        return f"{self.text!r} leaves the canvas"


def drawn_texts(fig) -> list:
    """The Text artists a draw of ``fig`` actually draws (visible, with something to show:
    an axis's unused ticks, kept for reuse, are not drawn), each once, in drawing order.
    Draws the figure, so that layout engines have placed everything."""
    from unittest import mock

    from matplotlib.text import Text
    drawn: dict[int, Text] = {}
    draw = Text.draw

    def spy(text, renderer):
        if text.get_visible() and text.get_text().strip():
            drawn.setdefault(id(text), text)
        return draw(text, renderer)

    with mock.patch.object(Text, "draw", spy):
        fig.draw_without_rendering()
    return list(drawn.values())


def text_flaws(fig, tolerance_px: float = TOLERANCE_PX) -> list[TextFlaw]:
    """Every pair of drawn texts whose extents overlap by more than ``tolerance_px`` on
    both axes, and every text whose extent leaves the canvas; empty for a legible figure.
    Draws the figure (so that layout engines have placed everything)."""
    texts = drawn_texts(fig)
    renderer = fig.canvas.get_renderer()
    width, height = fig.canvas.get_width_height()
    boxes = [(t, t.get_window_extent(renderer)) for t in texts]
    flaws = []
    for k, (text, box) in enumerate(boxes):
        if (box.x0 < -tolerance_px or box.y0 < -tolerance_px
                or box.x1 > width + tolerance_px or box.y1 > height + tolerance_px):
            flaws.append(TextFlaw("clipped", text.get_text()))
        for other, obox in boxes[k + 1:]:
            if (min(box.x1, obox.x1) - max(box.x0, obox.x0) > tolerance_px
                    and min(box.y1, obox.y1) - max(box.y0, obox.y0) > tolerance_px):
                flaws.append(TextFlaw("overlap", text.get_text(), other.get_text()))
    return flaws
