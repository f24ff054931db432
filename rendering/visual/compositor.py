"""Draws a frame: the static scene texture, then trails, cursors, the device panels
(``device_panels``), the scope and text.

The scope, when shown, has a strip of its own at the bottom of the frame and the scene
is fitted above it (``viewport.frame_layout``): the scope never covers the scene, and
its labels sit in title rows of their own, never under a trace. A device panel that
needs a place of its own (a plate's |W| heat map) has a column at the right of the
frame (``DevicePanels.column_px``), and the scene is fitted beside it. On the glass
(``viewport.on_glass``: fullscreen at the display's own pixels, or under a touch screen)
the scene fills the frame at its own pixels instead, so that it lies where it is felt:
the strip and the columns are drawn over it, and the status lines are not drawn.

The scene is rendered once per scene (``scene_image``) into a texture drawn 1:1 on
the viewport's pixels; each frame only the overlay is rebuilt, the scope's frame only
when the strip moves, and of the scope's traces only the columns that time brought
(``scope_ring``: a ring of time bins in a texture, min and max per column). All
geometry arrives in frame pixels (float, y down) and one vertex shader maps it to clip
space; the drawing primitives (``draw_triangles``, ``draw_rect``, ``draw_texture``,
``draw_cursors``, ``text``) are public for the panels, and queue their vertices by kind
(``batch``; texts live in one atlas, ``text_atlas``): a frame of the demo is five draw
calls (scene, lines, scope traces, cursors, texts).
"""

from __future__ import annotations

from dataclasses import dataclass

import moderngl
import numpy as np

from frictex.rendering.visual.batch import Batcher
from frictex.rendering.visual.device_panels import DevicePanels
from frictex.rendering.visual.layer_panel import PanelRow, PanelView, draw_layer_panel, panel_width
from frictex.rendering.visual.modal_view import Envelope
from frictex.rendering.visual.overlay import FINGER_RGB, OverlayState, plot_y
from frictex.rendering.visual.scene_image import scene_rgb, to_srgb8
from frictex.rendering.visual.scope_ring import ScopeRing
from frictex.rendering.visual.text import text_rgba, wrap
from frictex.rendering.visual.text_atlas import AtlasEntry, TextAtlas
from frictex.rendering.visual.viewport import Viewport, frame_layout, on_glass
from frictex.textures.model import Scene

_VERT_PX = """
uniform vec2 u_frame;
vec4 to_clip(vec2 px) { return vec4(px.x / u_frame.x * 2.0 - 1.0, 1.0 - px.y / u_frame.y * 2.0, 0.0, 1.0); }
"""

TEXTURED = ("""#version 330
in vec2 in_px; in vec2 in_uv; out vec2 v_uv;""" + _VERT_PX + """
void main() { v_uv = in_uv; gl_Position = to_clip(in_px); }""", """#version 330
uniform sampler2D u_tex; in vec2 v_uv; out vec4 f_colour;
void main() { f_colour = texture(u_tex, v_uv); }""")

COLOURED = ("""#version 330
in vec2 in_px; in vec4 in_rgba; out vec4 v_rgba;""" + _VERT_PX + """
void main() { v_rgba = in_rgba; gl_Position = to_clip(in_px); }""", """#version 330
in vec4 v_rgba; out vec4 f_colour;
void main() { f_colour = v_rgba; }""")

# A cursor is a quad around its centre; the fragment shader draws, from its distance to
# the centre, a dark halo ring, a coloured ring and, if filled (a touching finger), a
# translucent disc inside the ring and a solid dot at the centre; hollow (a lifted finger,
# the hover pointer) it is the ring alone: readable on black, white and grey scenes, and
# anti-aliased over one pixel.
CURSOR = ("""#version 330
in vec2 in_px; in vec2 in_local; in float in_radius; in vec4 in_rgba; in float in_fill;
out vec2 v_local; out float v_radius; out vec4 v_rgba; out float v_fill;""" + _VERT_PX + """
void main() { v_local = in_local; v_radius = in_radius; v_rgba = in_rgba; v_fill = in_fill;
              gl_Position = to_clip(in_px); }""", """#version 330
in vec2 v_local; in float v_radius; in vec4 v_rgba; in float v_fill; out vec4 f_colour;
const float CURSOR_FILL_ALPHA = 0.35;
float band(float d, float centre, float half_width) {
    return clamp(half_width + 0.5 - abs(d - centre), 0.0, 1.0); }
void main() {
    float d = length(v_local);
    float halo = band(d, v_radius, 2.5);
    float ring = band(d, v_radius, 1.0);
    float dot_ = v_fill * clamp(v_radius * 0.3 + 0.5 - d, 0.0, 1.0);
    float disc = v_fill * CURSOR_FILL_ALPHA * clamp(v_radius + 0.5 - d, 0.0, 1.0);
    float c = max(max(ring, dot_), disc);
    float a = max(halo * 0.6, c) * v_rgba.a;
    vec3 rgb = mix(vec3(0.0), v_rgba.rgb, c / max(max(halo * 0.6, c), 1e-6));
    f_colour = vec4(rgb, a);
}""")

SCOPE_BG = (0.05, 0.05, 0.05, 1.0)
SCOPE_GRID = (1.0, 1.0, 1.0, 0.18)  # at 0, half and full scale of each plot
SCOPE_RULE = (1.0, 1.0, 1.0, 0.45)  # the edges of the strip and between the two plots
#: the banner's band is opaque: a text under it is not drawn (``draw_texture``)
#: the status box covers at most this share of the scene's drawn height; the lines beyond
#: it (the keys' help first: it comes last) are left out, so a small window still shows
#: its scene
STATUS_SHARE = 1.0 / 3.0
BANNER_RGBA = {"stop": (0.75, 0.0, 0.0, 1.0), "error": (0.55, 0.05, 0.05, 1.0),
               "info": (0.1, 0.1, 0.1, 1.0)}


@dataclass
class FrameView:
    """What a frame shows besides the scene (all optional)."""

    overlay: OverlayState | None = None
    hover_mm: tuple[float, float] | None = None
    show_scope: bool = True
    amplitude_max_um: float = 2.5
    status: tuple[str, ...] = ()
    banner: str | None = None
    banner_kind: str = "error"
    #: |W| of a modal device (``modal_view.ModalEnvelope.at``) and its full scale (um)
    envelope: Envelope | None = None
    envelope_scale_um: float = 1.0
    #: the demo's layer panel (``layer_panel``), in a column at the left; None: none
    layer_panel: PanelView | None = None
    #: a uniform field of this colour (RGBA, 0-1) drawn instead of the scene's picture
    #: (an experiment that must not show its stimulus); None: the scene
    field_rgba: tuple[float, float, float, float] | None = None


def status_rows(status: tuple[str, ...], font_px: int, width_px: int,
                scene_px: int) -> tuple[str, ...]:
    """The status lines wrapped to a frame ``width_px`` wide, as many of them as fit in
    :data:`STATUS_SHARE` of the scene's drawn height ``scene_px`` (at least one); rows of
    ``text_rgba``."""
    rows = sum((wrap(line, font_px, width_px - 16, " | ") for line in status), ())
    room = int((STATUS_SHARE * scene_px - 8) // round(font_px * 1.25))  # 4 px pads
    return rows[:max(1, room)]


class Compositor:
    """Draws ``scene`` and a :class:`FrameView` into the current framebuffer of ``ctx``.

    ``scope``: lay the frame out for the scope strip at first (a frame drawn with or
    without it lays the frame out again, re-rendering the scene if it moved).
    ``fullscreen``, ``touch_screen``: the frame is a whole screen, a touch screen drives
    the fingers; with the scene's display they say whether the frame is the glass
    (``glass``, ``viewport.on_glass``).
    """

    def __init__(self, ctx: moderngl.Context, scene: Scene, size: tuple[int, int],
                 outlines: bool = False, supersample: int = 4, scope: bool = True,
                 fullscreen: bool = False, touch_screen: bool = False):
        self.ctx = ctx
        self.fullscreen, self.touch_screen = fullscreen, touch_screen
        self.glass = False  # the scene fills the frame as it lies on the glass
        self.outlines = outlines
        self.scope = scope
        self.supersample = supersample
        self.textured = ctx.program(vertex_shader=TEXTURED[0], fragment_shader=TEXTURED[1])
        self.coloured = ctx.program(vertex_shader=COLOURED[0], fragment_shader=COLOURED[1])
        self.cursor = ctx.program(vertex_shader=CURSOR[0], fragment_shader=CURSOR[1])
        self.batch = Batcher(ctx, {
            "coloured": (self.coloured, "2f 4f", ("in_px", "in_rgba")),
            "cursor": (self.cursor, "2f 2f 1f 4f 1f", ("in_px", "in_local", "in_radius",
                                                       "in_rgba", "in_fill")),
            "textured": (self.textured, "2f 2f", ("in_px", "in_uv")),
            "text": (self.textured, "2f 2f", ("in_px", "in_uv"))})
        self.atlas = TextAtlas(ctx, size[0], self.batch.flush)
        self.batch.textures["text"] = self.atlas.texture
        self._scope_frame: tuple[tuple, np.ndarray] | None = None
        self.scope_ring = ScopeRing(ctx)
        #: the box (x, y, w, h) px of every text drawn in the last frame, in drawing
        #: order (its background included): what a layout check reads
        self.text_boxes: list[tuple[float, float, float, float]] = []
        self._banner_band: tuple[float, float, float] | None = None  # (top, bottom, left) px
        self.panels = DevicePanels(self)
        self.status_bottom = 4.0  # px: below the status lines of the last frame drawn
        self.scene = scene
        self.size = (0, 0)
        self.viewport: Viewport | None = None
        self._scope_rect: tuple[float, float, float, float] | None = None
        self._column_rect: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
        self.left_px = 0  # the layer panel's column (px), kept at the left of the frame
        self.panel_rows: tuple[PanelRow, ...] = ()  # the layer panel's rows last drawn
        self.scene_texture: moderngl.Texture | None = None
        self.resize(size)

    # -- static layer -------------------------------------------------------------------

    def resize(self, size: tuple[int, int]) -> None:
        """Fit the scene to a frame of ``size`` px (re-renders the scene texture if needed)."""
        size = (int(size[0]), int(size[1]))
        if size == self.size:
            return
        self.size = size
        if size[0] > self.atlas.width:  # a status line as wide as the frame must fit
            self.batch.flush()
            self.atlas.release()
            self.atlas = TextAtlas(self.ctx, size[0], self.batch.flush)
            self.batch.textures["text"] = self.atlas.texture
        self.set_scene(self.scene)

    def set_scene(self, scene: Scene, outlines: bool | None = None) -> None:
        """Draw ``scene`` (once) into the static texture."""
        self.scene = scene
        if outlines is not None:
            self.outlines = outlines
        self.glass = on_glass(scene.display, self.size, self.fullscreen, self.touch_screen)
        self.viewport, self._scope_rect, self._column_rect = frame_layout(
            scene.display, *self.size, self.scope, self.panels.column_px(scene, self.size),
            left_px=self.left_px, glass=self.glass)
        rgb = to_srgb8(scene_rgb(scene, self.viewport, self.supersample, self.outlines))
        if self.scene_texture is not None:
            self.scene_texture.release()
        self.scene_texture = self.ctx.texture((self.viewport.width_px, self.viewport.height_px),
                                              3, np.ascontiguousarray(rgb).tobytes(), alignment=1)
        self.scene_texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.panels.set_scene(scene)

    # -- drawing primitives (queued by kind: ``batch``) ------------------------------------

    @staticmethod
    def _quad(x, y, w, h, u0=0.0, v0=0.0, u1=1.0, v1=1.0) -> np.ndarray:
        """Two triangles (6, 4) of x, y, u, v covering (x, y, w, h) px."""
        return np.array([[x, y, u0, v0], [x + w, y, u1, v0], [x, y + h, u0, v1],
                         [x, y + h, u0, v1], [x + w, y, u1, v0], [x + w, y + h, u1, v1]])

    def draw_texture(self, texture, x: float, y: float, size: tuple[float, float] | None = None,
                     opaque: bool = False) -> None:
        """Draw a text (an entry of :meth:`text`, queued with the frame's other texts) or
        a texture (drawn now; ``opaque``: replacing what is below, not blended) at
        (x, y) px, stretched to ``size`` px if given."""
        w, h = size or texture.size
        if isinstance(texture, AtlasEntry):
            band = self._banner_band
            if band is not None and y < band[1] and y + h > band[0] and x + w > band[2]:
                return  # under the banner's opaque band: hidden whole, not cut
            self.batch.queue("text", self._quad(x, y, w, h, *self.atlas.uv(texture)))
            self.text_boxes.append((float(x), float(y), float(w), float(h)))
            return
        self.batch.flush()
        if opaque:
            self.ctx.disable(moderngl.BLEND)
        self.batch.draw_now("textured", self._quad(x, y, w, h), texture)
        if opaque:
            self.ctx.enable(moderngl.BLEND)

    def draw_triangles(self, tris: np.ndarray) -> None:
        """Triangles (k, 6) of x, y (px), r, g, b, a, queued with the frame's others."""
        self.batch.queue("coloured", tris)

    def draw_rect(self, x, y, w, h, rgba) -> None:
        tris = np.empty((6, 6))
        tris[:, :2], tris[:, 2:] = self._quad(x, y, w, h)[:, :2], rgba
        self.draw_triangles(tris)

    def draw_cursors(self, cursors: np.ndarray) -> None:
        """Cursor instances (k, 8) (``OverlayState.cursors``), queued with the frame's others."""
        if len(cursors) == 0:
            return
        local = np.array([[-1, -1], [1, -1], [-1, 1], [-1, 1], [1, -1], [1, 1]], dtype=np.float64)
        offs = local[None, :, :] * (cursors[:, 2] + 4.0)[:, None, None]  # (k, 6, 2)
        verts = np.empty((len(cursors), 6, 10))
        verts[:, :, 0:2] = cursors[:, None, 0:2] + offs
        verts[:, :, 2:4] = offs
        verts[:, :, 4:] = cursors[:, None, 2:8]
        self.batch.queue("cursor", verts.reshape(-1, 10))

    def text(self, lines: tuple[str, ...], size_px: int, rgb=(255, 255, 255),
             background=(0, 0, 0, 170)) -> AtlasEntry:
        """``lines`` of text in the frame's text atlas (its ``size`` (w, h) px; drawn by
        :meth:`draw_texture`)."""
        return self.atlas.get((lines, size_px, rgb, background),
                              lambda: text_rgba(lines, size_px, rgb, background))

    # -- the frame ----------------------------------------------------------------------

    def _set_scope(self, scope: bool) -> None:
        """Lay the frame out with or without the scope strip; the scene is drawn again
        only if it moved."""
        if scope == self.scope:
            return
        self.scope = scope
        viewport = self.viewport
        self.viewport, self._scope_rect, self._column_rect = frame_layout(
            self.scene.display, *self.size, scope, self.panels.column_px(self.scene, self.size),
            left_px=self.left_px, glass=self.glass)
        if self.viewport != viewport:
            self.set_scene(self.scene)

    def _set_left(self, px: int) -> None:
        """Keep a column ``px`` wide at the left for the layer panel (0: none); the scene
        is fitted beside it, drawn again if it moved."""
        if px != self.left_px:
            self.left_px = px
            self.set_scene(self.scene)

    def layer_panel_rect(self) -> tuple[float, float, float, float]:
        """The layer panel's column (x, y, w, h) px: at the left, from below the status
        lines to the scope strip (on the glass, over the scene)."""
        top = self.status_bottom + 4.0
        width = self.left_px if self.glass else min(self.left_px, self.viewport.x0)
        return 0.0, top, float(width), max(self.scope_rect()[1] - top, 0.0)

    def column_rect(self) -> tuple[float, float, float, float]:
        """The device panel column (x, y, w, h) px at the right of the frame, above the
        scope strip (``viewport.frame_layout``; 0 px wide when the scene needs none)."""
        return self._column_rect

    def scope_rect(self) -> tuple[float, float, float, float]:
        """The scope strip (x, y, w, h) px at the bottom of the frame (height 0 when the
        frame is laid out without it)."""
        if self._scope_rect is None:
            w, h = self.size
            return 0.0, float(h), float(w), 0.0
        return self._scope_rect

    def scope_plots(self) -> tuple[tuple[float, float, float, float], ...]:
        """The scope's two plots (x, y, w, h) px, mu' above amplitude, each under a
        title row of its own (``label_row_px`` high) that holds its labels."""
        x, y, w, h = self.scope_rect()
        row = self.label_row_px
        plot_h = max((h - 2.0 * row - 3.0) / 2.0, 1.0)
        return ((x, y + 1.0 + row, w, plot_h), (x, y + 2.0 + 2.0 * row + plot_h, w, plot_h))

    def draw(self, view: FrameView | None = None) -> None:
        """Draw the scene and ``view`` into the framebuffer in use: the scene, then the
        trails and the scope's lines in one call, the cursors in one, the device panels,
        and every text in one (``batch``)."""
        view = view or FrameView()
        scope = view.show_scope and view.overlay is not None
        self._set_scope(scope)
        self._set_left(0 if view.layer_panel is None else panel_width(self.size[0]))
        ctx = self.ctx
        w, h = self.size
        ctx.viewport = (0, 0, w, h)
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.clear(0.12, 0.12, 0.12, 1.0)
        for prog in (self.textured, self.coloured, self.cursor):
            prog["u_frame"] = (float(w), float(h))
        self.textured["u_tex"] = 0
        self.batch.begin_frame()
        self.text_boxes = []
        vp = self.viewport
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
        if view.field_rgba is None:
            self.draw_texture(self.scene_texture, vp.x0, vp.y0, opaque=True)
        else:
            self.draw_rect(vp.x0, vp.y0, vp.width_px, vp.height_px, view.field_rgba)
        font_px = self.font_px
        status = None
        if view.status and not self.glass:  # on the glass no room is off the scene
            status = self.text(status_rows(view.status, font_px, w, vp.height_px), font_px)
        self.status_bottom = 4.0 + (status.size[1] if status is not None else 0.0)
        banner = self._banner(view) if view.banner else None
        self._banner_band = None if banner is None else banner[1]
        overlay = view.overlay or OverlayState()
        if view.overlay is not None:
            self.draw_triangles(view.overlay.trail_triangles(vp))
        if scope:
            self.draw_triangles(self._scope_lines())
            self._draw_scope_traces(view)
        self.draw_cursors(overlay.cursors(vp, view.hover_mm))
        self.panels.draw(overlay, view.envelope, view.envelope_scale_um)
        self.panel_rows = (() if view.layer_panel is None else
                           draw_layer_panel(self, view.layer_panel, self.layer_panel_rect()))
        if scope:
            self._draw_scope_labels(view)
        if status is not None:
            self.draw_texture(status, 4, 4)
        if banner is not None:
            tex, band = banner
            self._banner_band = None  # the banner's own text is drawn
            left = band[2]
            self.draw_rect(left, band[0], w - left, band[1] - band[0],
                           BANNER_RGBA.get(view.banner_kind, BANNER_RGBA["info"]))
            self.draw_texture(tex, left + max(4.0, (w - left - tex.size[0]) / 2), band[0] + 6)
        self.batch.flush()
        ctx.disable(moderngl.BLEND)

    def _banner(self, view: FrameView) -> tuple[AtlasEntry, tuple[float, float, float]]:
        """The banner's text and its band (top, bottom, left) px across the frame right
        of the layer panel (its column; none when closed: the panel's rows stay readable):
        centred for an emergency stop, else at 12 % of the height; below the status lines
        either way."""
        w, h = self.size
        left = self.layer_panel_rect()[2] if view.layer_panel is not None else 0.0
        size_px = self.font_px + 2
        tex = self.text(wrap(view.banner, size_px, w - left - 40), size_px, background=(0, 0, 0, 0))
        bh = tex.size[1] + 12
        y = (h - bh) / 2 if view.banner_kind == "stop" else h * 0.12
        y = min(max(y, self.status_bottom + 4.0), max(h - bh, 0.0))
        return tex, (y, y + bh, left)

    def _scope_lines(self) -> np.ndarray:
        """The scope strip's background, rules and grid: triangles (k, 6), made again only
        when the strip moves."""
        rect, plots = self.scope_rect(), self.scope_plots()
        if self._scope_frame is None or self._scope_frame[0] != (rect, plots):
            x, y, w, h = rect
            rects = [(x, y, w, h, SCOPE_BG)]
            for px, py, pw, ph in plots:
                rects.append((px, py - 1.0, pw, 1.0, SCOPE_RULE))  # under the title row
                rects += [(px, level - 0.5, pw, 1.0, SCOPE_GRID)
                          for level in plot_y((0.0, 0.5, 1.0), (px, py, pw, ph))]
            rects.append((x, y, w, 1.0, SCOPE_RULE))
            tris = np.empty((6 * len(rects), 6))
            for k, (rx, ry, rw, rh, rgba) in enumerate(rects):
                tris[6 * k:6 * k + 6, :2] = self._quad(rx, ry, rw, rh)[:, :2]
                tris[6 * k:6 * k + 6, 2:] = rgba
            self._scope_frame = ((rect, plots), tris)
        return self._scope_frame[1]

    def _draw_scope_traces(self, view: FrameView) -> None:
        """The traces: the ring of time bins (``scope_ring``) brought up to date and drawn
        as one quad over the two plots, its texture coordinate running with time."""
        plots = self.scope_plots()
        texture, u0, u1 = self.scope_ring.update(view.overlay, plots, view.amplitude_max_um)
        x, y, w, _ = plots[0]
        h = texture.size[1]
        self.batch.flush()
        self.batch.draw_now("textured", self._quad(x, y, w, h, u0, 0.0, u1, 1.0), texture)

    def _draw_scope_labels(self, view: FrameView) -> None:
        x, _, w, _ = self.scope_rect()
        plots = self.scope_plots()
        label_px, row = self.label_px, self.label_row_px
        titles = ("mu' target (0 to 1)",
                  f"amplitude (0 to {view.amplitude_max_um:g} um, 0-peak)")
        right = x + w - 4
        title_end = []
        for (px, py, _, _), title in zip(plots, titles):
            tex = self.text((title,), label_px, background=(0, 0, 0, 0))
            self.draw_texture(tex, px + 4, py - row + (row - tex.size[1]) / 2)
            title_end.append(px + 4 + tex.size[0])
        tick = self.text((f"last {view.overlay.scope_s:g} s  |  now",), label_px,
                         background=(0, 0, 0, 0))
        top = plots[0][1] - row
        right -= tick.size[0]
        self.draw_texture(tick, right, top + (row - tick.size[1]) / 2)
        self._draw_legend(sorted(view.overlay.fingers, reverse=True), right, top,
                          left=title_end[0])

    def _draw_legend(self, fingers: list[int], right: float, top: float, left: float) -> None:
        """One label per finger in its colour, leftwards from ``right`` (px) in the title
        row at ``top``, the highest ids (the latest touches of a log) nearest; fingers
        that would reach the title ending at ``left`` are summed up as "+k more"."""
        label_px, row = self.label_px, self.label_row_px
        gap = 4.0
        reserve = self.text(("+999 more",), label_px, background=(0, 0, 0, 0)).size[0] + gap
        for k, fid in enumerate(fingers):
            rgb = tuple(int(round(255 * c)) for c in FINGER_RGB[fid % len(FINGER_RGB)])
            tex = self.text((f"finger {fid}",), label_px, rgb=rgb, background=(0, 0, 0, 0))
            last = k == len(fingers) - 1
            if right - tex.size[0] - gap - (0.0 if last else reserve) < left + 2 * gap:
                tex = self.text((f"+{len(fingers) - k} more",), label_px,
                                background=(0, 0, 0, 0))
                if right - tex.size[0] - gap >= left + 2 * gap:
                    self.draw_texture(tex, right - tex.size[0] - gap,
                                      top + (row - tex.size[1]) / 2)
                return
            right -= tex.size[0] + gap
            self.draw_texture(tex, right, top + (row - tex.size[1]) / 2)

    # -- text sizes ---------------------------------------------------------------------

    @property
    def font_px(self) -> int:
        """Text size (px) of the status lines and banners, from the frame's height."""
        return int(min(max(self.size[1] / 45, 11), 22))  # (read several times a frame)

    @property
    def label_px(self) -> int:
        """Text size (px) of the scope's and panels' labels."""
        return max(10, self.font_px - 2)

    @property
    def label_row_px(self) -> float:
        """Height (px) of a row of labels (``text.text_rgba``: 1.25 lines and 4 px pads)."""
        return round(self.label_px * 1.25) + 10.0

    def release(self) -> None:
        self.panels.release()
        self.batch.release()
        self.scope_ring.release()
        for obj in (self.atlas, self.scene_texture, self.textured, self.coloured, self.cursor):
            if obj is not None:
                obj.release()
