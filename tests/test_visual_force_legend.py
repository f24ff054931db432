"""The force arrows' legend ("0.25 N (arrow: force on the finger, thin: wanted)") sits
at the bottom left of the scene's area: with the layer panel open (L) it moves right of
the panel's column, as the scene does; it used to stay right of a scale arrow drawn from
x = 12 px, under the panel, which left "r, thin: wanted)" showing (directional-ring at
1280 x 800)."""

from frictex.app.live.layer_edit import LayerEdit, panel_view
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.context import OffscreenBackend
from frictex.rendering.visual.overlay import OverlayState
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene

SIZE = (1280, 800)


def legend_box(gl, panel_open: bool):
    """(x, y, w, h) px of the force legend in a frame of directional-ring, and the layer
    panel's column (x, y, w, h)."""
    path = resolve_scene("directional-ring")
    scene = load_scene(path)
    backend = OffscreenBackend(SIZE, ctx=gl)
    comp = Compositor(gl, scene, SIZE)
    lines_of, boxes = {}, {}
    text, draw_texture = comp.text, comp.draw_texture

    def named_text(lines, *args, **kwargs):
        entry = text(lines, *args, **kwargs)
        lines_of[id(entry)] = lines
        return entry

    def placed(texture, x, y, *args, **kwargs):
        if id(texture) in lines_of:
            boxes[lines_of[id(texture)][0]] = (x, y, *texture.size)
        return draw_texture(texture, x, y, *args, **kwargs)

    comp.text, comp.draw_texture = named_text, placed
    view = FrameView(overlay=OverlayState(),
                     layer_panel=panel_view(LayerEdit(path)) if panel_open else None)
    try:
        backend.use()
        comp.draw(view)
        legend = next(box for line, box in boxes.items() if "arrow: force on the finger" in line)
        return legend, comp.layer_panel_rect()
    finally:
        comp.release()
        backend.close()


def test_the_legend_is_right_of_the_open_layer_panel(gl):
    (x, _, w, _), (_, _, panel_w, _) = legend_box(gl, panel_open=True)
    assert panel_w > 300.0  # the panel's column is there
    assert panel_w < x and x + w < SIZE[0]


def test_the_legend_is_at_the_left_edge_without_the_panel(gl):
    (x, *_), (_, _, panel_w, _) = legend_box(gl, panel_open=False)
    assert panel_w == 0.0 and x < 250.0  # after the 12 px margin and the scale arrow
