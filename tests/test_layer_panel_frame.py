"""The layer panel drawn by the compositor: its column keeps the scene beside it, a
slider's knob sits where its value is, and no text of the panel overlaps another text of
the frame or leaves it, whatever the frame's size, with a menu open, a banner (right of
the column, hiding none of its rows) and the scope (``Compositor.text_boxes``, as test_visual_text_layout checks frames without it)."""

import itertools

import numpy as np
import pytest

from frictex.app.live.layer_edit import LayerEdit, panel_view
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.layer_panel import KNOB_RGBA, panel_width
from frictex.rendering.visual.overlay import OverlayState
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from test_visual_text_layout import BANNER, STATUS, overlapping


@pytest.mark.parametrize("size", [(640, 400), (800, 615), (1920, 1080)])
@pytest.mark.parametrize("name, layer, menu", [("height-bump", 0, "rendering"),
                                               ("objects-bump-edge-disc", 1, "blend")])
@pytest.mark.parametrize("banner", [None, BANNER])
def test_the_panel_keeps_its_texts_apart_and_in_the_frame(gl, size, name, layer, menu, banner):
    path = resolve_scene(name)
    scene = load_scene(path)
    editor = LayerEdit(path)
    editor.select(layer)
    editor.set("mu_max" if name == "height-bump" else "mu", 0.95)
    view = panel_view(editor, menu, note=f"saved {path.name} in /home/someone/.local/share/frictex/scenes")
    backend = OffscreenBackend(size, ctx=gl)
    comp = Compositor(gl, scene, size)
    backend.use()
    comp.draw(FrameView(overlay=OverlayState(), status=STATUS, banner=banner, layer_panel=view))
    boxes, rows, vp = list(comp.text_boxes), comp.panel_rows, comp.viewport
    frame = backend.read_rgb()
    comp.release()
    backend.close()
    w, h = size
    column = min(panel_width(w), w // 2)
    assert vp.x0 >= column  # the scene right of the column
    assert [r.kind for r in rows][:1 + len(view.layers)] == ["title"] + ["layer"] * len(view.layers)
    assert len(rows) >= 6 and all(r.box[0] + r.box[2] <= column for r in rows)
    for box in boxes:
        x, y, bw, bh = box
        assert x >= -0.5 and y >= -0.5 and x + bw <= w + 0.5 and y + bh <= h + 0.5, (box, size)
    for a, b in itertools.combinations(boxes, 2):
        assert not overlapping(a, b), (a, b, size)
    # every row's text drawn: a banner's band lies right of the column, hiding none
    top, bottom = rows[0].box[1] - 1.0, rows[-1].box[1] + rows[-1].box[3] + 1.0
    assert sum(x + bw <= column + 0.5 and top <= y and y + bh <= bottom
               for x, y, bw, bh in boxes) == len(rows)
    # each slider's knob at its value along the track
    knob = np.round(np.array(KNOB_RGBA[:3]) * 255)
    for row in rows:
        if row.track is None:
            continue
        tx, ty, tw, th = row.track
        x0 = int(tx)
        line = frame[int(ty + th / 2), x0:int(tx + tw) + 1].astype(int)
        cols = np.flatnonzero(np.all(np.abs(line - knob) <= 2, axis=-1))
        assert cols.size > 0, row.key
        assert abs(x0 + cols.mean() + 0.5 - (tx + row.fraction * tw)) <= 1.0, row.key
