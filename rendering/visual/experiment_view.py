"""What a participant sees of an experiment session, drawn over the demo's frame:
instructions, breaks and the question as screens of text with buttons, and during an
interval the scene with the part to explore marked and a button to move on.

What is shown arrives as plain data (:class:`ExperimentView`, made by
``app.experiment.window_presenter``); :func:`layout` places its texts and buttons in
frame pixels (:class:`Button`: a response and its box), which both the drawing
(:func:`draw_experiment`) and the pointer (:func:`hit`) use, so a click lands on what
is drawn under it. Texts never overlap: the lines are stacked from the top, the
buttons in rows below them (``tests/test_experiment_window.py`` checks the boxes the
compositor records).
"""

from __future__ import annotations

from dataclasses import dataclass

from frictex.rendering.visual.text import font, wrap

COVER_RGBA = (0.1, 0.1, 0.12, 1.0)
DIM_RGBA = (0.0, 0.0, 0.0, 0.7)  # over the part of the scene not explored in this interval
BUTTON_RGBA = (0.22, 0.3, 0.45, 1.0)
BUTTON_EDGE_RGBA = (0.75, 0.8, 0.9, 1.0)
TITLE_RGB = (255, 220, 120)
PAD_PX = 12.0
GAP_PX = 10.0


@dataclass(frozen=True)
class ExperimentView:
    """One screen of a session.

    phase : "message" (text and buttons over the scene: instructions, a break, a
        question), or "interval" (the scene shown; ``active_mm`` the part explored).
    title, lines : a heading and paragraphs of text (wrapped to the frame).
    buttons : (value, label) of each button, in order.
    progress : the progress line (the frame's status line).
    active_mm : (x, y, width, height) mm of the scene to explore (interval), or None.
    """

    phase: str
    title: str = ""
    lines: tuple[str, ...] = ()
    buttons: tuple[tuple[str, str], ...] = ()
    progress: str = ""
    active_mm: tuple[float, float, float, float] | None = None


@dataclass(frozen=True)
class Button:
    """A button as drawn: the ``value`` a click gives and its box (x, y, w, h) px."""

    value: str
    label: str
    box: tuple[float, float, float, float]


def font_px(height_px: int) -> int:
    """Text size (px) of a screen's paragraphs in a frame ``height_px`` high."""
    return int(min(max(height_px / 30, 13), 26))


def _button_boxes(labels, size_px: int, top: float, width: float) -> list[tuple]:
    """Boxes (x, y, w, h) px of buttons labelled ``labels``, in centred rows from ``top``
    within ``width`` px."""
    f = font(size_px)
    widths = [max(f.getlength(label) + 2 * PAD_PX, 2.5 * size_px) for label in labels]
    height = round(size_px * 1.25) + 2 * PAD_PX
    rows, row, used = [], [], 0.0
    for k, w in enumerate(widths):
        if row and used + GAP_PX + w > width - 2 * PAD_PX:
            rows.append(row)
            row, used = [], 0.0
        used += (GAP_PX if row else 0.0) + w
        row.append(k)
    if row:
        rows.append(row)
    boxes: list[tuple] = [None] * len(labels)
    for r, members in enumerate(rows):
        total = sum(widths[k] for k in members) + GAP_PX * (len(members) - 1)
        x = (width - total) / 2
        for k in members:
            boxes[k] = (x, top + r * (height + GAP_PX), widths[k], height)
            x += widths[k] + GAP_PX
    return boxes


def layout(view: ExperimentView, size: tuple[int, int], top_px: float
           ) -> tuple[list[tuple[tuple[str, ...], int, float, float]], tuple[Button, ...]]:
    """Where ``view``'s texts and buttons go in a frame of ``size`` (w, h) px, below
    ``top_px`` (the status lines): (texts as (lines, size px, x, y), buttons). Message
    screens stack title, paragraphs and button rows from the top; an interval puts
    its buttons in a row centred at the bottom."""
    w, h = size
    px = font_px(h)
    texts: list[tuple[tuple[str, ...], int, float, float]] = []
    if view.phase == "interval":
        boxes = _button_boxes([label for _, label in view.buttons], px, 0.0, w)
        height = boxes[-1][1] + boxes[-1][3] if boxes else 0.0
        lift = h - PAD_PX - height
        buttons = tuple(Button(v, label, (b[0], b[1] + lift, b[2], b[3]))
                        for (v, label), b in zip(view.buttons, boxes))
        return texts, buttons
    y = top_px + 2 * PAD_PX
    line_h = round(px * 1.25)
    if view.title:
        title = wrap(view.title, px + 4, w - 4 * PAD_PX)
        texts.append((title, px + 4, 2 * PAD_PX, y))
        y += len(title) * round((px + 4) * 1.25) + 8 + GAP_PX
    for para in view.lines:
        lines = wrap(para, px, w - 4 * PAD_PX)
        texts.append((lines, px, 2 * PAD_PX, y))
        y += len(lines) * line_h + 8 + GAP_PX
    boxes = _button_boxes([label for _, label in view.buttons], px, y + GAP_PX, w)
    buttons = tuple(Button(v, label, b) for (v, label), b in zip(view.buttons, boxes))
    return texts, buttons


def hit(buttons: tuple[Button, ...], x_px: float, y_px: float) -> Button | None:
    """The button under (x_px, y_px), or None."""
    for b in buttons:
        bx, by, bw, bh = b.box
        if bx <= x_px < bx + bw and by <= y_px < by + bh:
            return b
    return None


def draw_experiment(compositor, view: ExperimentView) -> tuple[Button, ...]:
    """Draw ``view`` over the frame ``compositor`` has just drawn (its scene and status
    lines), and return the buttons as drawn (for :func:`hit`)."""
    import moderngl
    w, h = compositor.size
    top = compositor.status_bottom + 4.0
    texts, buttons = layout(view, (w, h), top)
    compositor.ctx.enable(moderngl.BLEND)
    if view.phase == "interval":
        if view.active_mm is not None:
            vp = compositor.viewport
            ax, _, aw, _ = view.active_mm  # an area spans the display's height
            x0 = float(vp.to_px(ax, 0.0)[0])
            x1 = float(vp.to_px(ax + aw, 0.0)[0])
            right = vp.x0 + vp.width_px
            for rx, rw in ((vp.x0, x0 - vp.x0), (x1, right - x1)):
                if rw > 0.5:  # the part of the scene not explored now, dimmed
                    compositor.draw_rect(rx, vp.y0, rw, vp.height_px, DIM_RGBA)
    else:
        compositor.draw_rect(0.0, top, w, h - top, COVER_RGBA)
    for lines, size_px, x, y in texts:
        rgb = TITLE_RGB if size_px > font_px(h) else (255, 255, 255)
        compositor.draw_texture(compositor.text(lines, size_px, rgb, (0, 0, 0, 0)), x, y)
    for b in buttons:
        x, y, bw, bh = b.box
        compositor.draw_rect(x - 1, y - 1, bw + 2, bh + 2, BUTTON_EDGE_RGBA)
        compositor.draw_rect(x, y, bw, bh, BUTTON_RGBA)
        tex = compositor.text((b.label,), font_px(h), (255, 255, 255), (0, 0, 0, 0))
        compositor.draw_texture(tex, x + (bw - tex.size[0]) / 2, y + (bh - tex.size[1]) / 2)
    compositor.batch.flush()
    compositor.ctx.disable(moderngl.BLEND)
    return buttons
