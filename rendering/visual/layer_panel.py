"""The demo's layer panel, drawn in a column at the left of the frame: the scene's
layers, the selected layer's number keys as sliders and its word keys as menus, and
undo / save buttons.

What the panel shows arrives as plain data (:class:`PanelView`, made by
``app.live.layer_edit``'s caller); :func:`panel_layout` places it in rows
(:class:`PanelRow`: what a row is and its box in frame pixels), which both the drawing
(:func:`draw_layer_panel`) and the pointer (:func:`hit`) use, so a click lands on what
is drawn under it. Rows that do not fit the column are left out (not drawn, not hit):
the last controls first, so that undo, save and the news stay in view. The news is
wrapped over as many rows as it needs (a refused save ends with what to do about it).
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

from frictex.rendering.visual.text import font

PANEL_SHARE, PANEL_PX = 0.3, (220, 360)  # the column's width: this share of the frame's, within
PANEL_BG = (0.08, 0.08, 0.1, 1.0)
SELECTED_BG = (0.2, 0.3, 0.45, 1.0)
TRACK_RGBA = (1.0, 1.0, 1.0, 0.35)
KNOB_RGBA = (0.95, 0.75, 0.2, 1.0)
BUTTON_BG = (0.22, 0.22, 0.25, 1.0)
PAD_PX = 6.0
#: a press this close to a slider track's end (px) sets the end's value
END_SNAP_PX = 2.0


def panel_width(frame_w: int) -> int:
    """Width (px) of the panel's column in a frame ``frame_w`` px wide."""
    return int(round(np.clip(PANEL_SHARE * frame_w, *PANEL_PX)))


@dataclass(frozen=True)
class ControlView:
    """One control: ``kind`` "slider" (``fraction`` 0 to 1 along its track) or "menu"
    (``options``); ``label``: the key and its value as shown."""

    kind: str
    key: str
    label: str
    fraction: float = 0.0
    options: tuple[str, ...] = ()


@dataclass(frozen=True)
class PanelView:
    """What the panel shows: the layers (``selected``: index or None), the selected
    layer's controls, the menu open (its key or None), a line of news (saved, an
    error), whether there is a change to undo and whether the scene differs from its
    file as read or last saved (``dirty``: "unsaved changes" on the save button)."""

    layers: tuple[str, ...]
    selected: int | None
    controls: tuple[ControlView, ...]
    open_menu: str | None = None
    note: str = ""
    can_undo: bool = False
    dirty: bool = False


@dataclass(frozen=True)
class PanelRow:
    """A row: ``kind`` ("title", "layer", "slider", "menu", "option", "undo", "save",
    "note"), what it acts on (``index`` of a layer, ``key``, ``option``), its ``text``
    and its box (x, y, w, h) px; a slider's track is ``track`` (x, y, w, h) px."""

    kind: str
    text: str
    box: tuple[float, float, float, float]
    index: int | None = None
    key: str | None = None
    option: str | None = None
    track: tuple[float, float, float, float] | None = None
    fraction: float = 0.0


def panel_layout(view: PanelView, rect: tuple[float, float, float, float],
                 row_px: float, label_px: int | None = None) -> tuple[PanelRow, ...]:
    """The rows of ``view`` in the column ``rect`` (x, y, w, h px), ``row_px`` high each,
    top down: the title and the layers, the controls, then undo, save and the news,
    wrapped to the rows' width in text ``label_px`` px high (None: on one row). Where
    they do not all fit, the last controls are left out first, then the rows below the
    column's bottom."""
    x, y, w, h = rect
    head: list[dict] = [dict(kind="title", text="layers  (L: close)")]
    head += [dict(kind="layer", text=name, index=k) for k, name in enumerate(view.layers)]
    controls: list[dict] = []
    for c in view.controls:
        if c.kind == "slider":
            controls.append(dict(kind="slider", text=c.label, key=c.key, fraction=c.fraction))
        else:
            controls.append(dict(kind="menu", key=c.key, text=c.label + (
                "  ^" if view.open_menu == c.key else "  v")))
            if view.open_menu == c.key:
                controls += [dict(kind="option", text=o, key=c.key, option=o) for o in c.options]
    specs = [dict(kind="undo", text="undo  (Ctrl+Z)" if view.can_undo else "nothing to undo")]
    specs.append(dict(kind="save", text="unsaved changes: Ctrl+S saves" if view.dirty
                      else "save  (Ctrl+S): no changes"))
    if view.note:
        lines = [view.note] if label_px is None else _wrap(view.note, label_px, w - 2 * PAD_PX)
        specs += [dict(kind="note", text=line) for line in lines]
    room = int(max(h - PAD_PX, 0.0) // row_px)
    specs = head + controls[:max(room - len(head) - len(specs), 0)] + specs
    rows, top = [], y + PAD_PX
    for spec in specs:
        if top + row_px > y + h:
            break
        box = (x + PAD_PX, top, w - 2 * PAD_PX, row_px - 2.0)
        track = None
        if spec["kind"] == "slider":
            tx = x + PAD_PX + 0.55 * (w - 2 * PAD_PX)
            track = (tx, top, x + w - PAD_PX - tx, row_px - 2.0)
        rows.append(PanelRow(box=box, track=track, **spec))
        top += row_px
    return tuple(rows)


def hit(rows: tuple[PanelRow, ...], x_px: float, y_px: float) -> tuple[PanelRow, float] | None:
    """The row under (x_px, y_px) and, for a slider's track, the fraction (0 to 1) of
    the track left of the point (0.0 elsewhere); None off every row."""
    for row in rows:
        bx, by, bw, bh = row.box
        if bx <= x_px < bx + bw and by <= y_px < by + bh:
            return row, track_fraction(row, x_px)
    return None


def track_fraction(row: PanelRow, x_px: float) -> float:
    """Where ``x_px`` falls along ``row``'s slider track, clipped to 0 to 1; within
    :data:`END_SNAP_PX` of an end, that end (the track's last pixel is the row's last, so
    a click could otherwise never reach 1)."""
    if row.track is None:
        return 0.0
    tx, _, tw, _ = row.track
    if x_px >= tx + tw - END_SNAP_PX:
        return 1.0
    return float(np.clip((x_px - tx) / tw, 0.0, 1.0)) if x_px > tx + END_SNAP_PX else 0.0


def draw_layer_panel(compositor, view: PanelView, rect: tuple[float, float, float, float]
                     ) -> tuple[PanelRow, ...]:
    """Draw ``view`` in the column ``rect`` with ``compositor``'s primitives; returns the
    rows drawn (for :func:`hit`)."""
    x, y, w, h = rect
    compositor.draw_rect(x, y, w, h, PANEL_BG)
    label_px = compositor.label_px
    rows = panel_layout(view, rect, compositor.label_row_px, label_px)
    for row in rows:
        bx, by, bw, bh = row.box
        if row.kind == "layer" and row.index == view.selected:
            compositor.draw_rect(bx, by, bw, bh, SELECTED_BG)
        elif row.kind in ("undo", "save", "menu"):
            compositor.draw_rect(bx, by, bw, bh, BUTTON_BG)
        text_w = bw if row.track is None else row.track[0] - bx - PAD_PX
        indent = 2 * PAD_PX if row.kind == "option" else 0.0
        tex = compositor.text((_fit(row.text, label_px, text_w - indent),), label_px,
                              background=(0, 0, 0, 0))
        compositor.draw_texture(tex, bx + 2.0 + indent, by + (bh - tex.size[1]) / 2)
        if row.track is not None:
            tx, ty, tw, th = row.track
            compositor.draw_rect(tx, ty + th / 2 - 1.0, tw, 2.0, TRACK_RGBA)
            knob = tx + row.fraction * tw
            compositor.draw_rect(knob - 3.0, ty + 2.0, 6.0, th - 4.0, KNOB_RGBA)
    return rows


def _fit(text: str, size_px: int, width_px: float) -> str:
    """``text`` cut with an ellipsis to fit ``width_px`` (the text's pads included)."""
    f = font(size_px)
    room = width_px - 8.0  # text_rgba's pads
    if f.getlength(text) <= room:
        return text
    while len(text) > 1 and f.getlength(text + "…") > room:
        text = text[:-1]
    return text + "…"


def _wrap(text: str, size_px: int, width_px: float) -> list[str]:
    """``text`` in lines that fit ``width_px`` (the text's pads included), broken at
    spaces; a word longer than a line (a path) is broken where the line is full."""
    f = font(size_px)
    room = width_px - 8.0  # text_rgba's pads
    lines: list[str] = []
    line = ""
    for word in text.split():
        joined = f"{line} {word}" if line else word
        if f.getlength(joined) <= room:
            line = joined
            continue
        if line:
            lines.append(line)
        line = word
        while f.getlength(line) > room and len(line) > 1:
            cut = _longest_fitting(line, f, room)
            lines.append(line[:cut])
            line = line[cut:]
    return lines + [line] if line else lines


def _longest_fitting(text: str, f, room: float) -> int:
    """How many leading characters of ``text`` fit ``room`` px in font ``f`` (at least 1)."""
    cut = len(text)
    while cut > 1 and f.getlength(text[:cut]) > room:
        cut -= 1
    return cut
