"""Draws a frame: the static scene texture, then trails, cursors, the device panels
(``device_panels``), the scope and text.

The scope, when shown, has a strip of its own at the bottom of the frame and the scene
is fitted above it (``viewport.frame_layout``): the scope never covers the scene, and
its labels sit in title rows of their own, never under a trace. A device panel that
needs a place of its own (a plate's |W| heat map) has a column at the right of the
frame (``DevicePanels.column_px``), and the scene is fitted beside it.

The scene is rendered once per scene (``scene_image``) into a texture drawn 1:1 on
the viewport's pixels; each frame only the overlay is rebuilt. All geometry arrives in
frame pixels (float, y down) and one vertex shader maps it to clip space; the drawing
primitives (``draw_triangles``, ``draw_rect``, ``draw_texture``, ``draw_cursors``,
``text``) are public for the panels.
"""

from __future__ import annotations

from collections import OrderedDict
from dataclasses import dataclass

import moderngl
import numpy as np

from frictex.rendering.visual.device_panels import DevicePanels
from frictex.rendering.visual.modal_view import Envelope
from frictex.rendering.visual.overlay import FINGER_RGB, OverlayState, plot_y
from frictex.rendering.visual.scene_image import scene_rgb, to_srgb8
from frictex.rendering.visual.text import text_rgba, wrap
from frictex.rendering.visual.viewport import Viewport, frame_layout
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
# the centre, a dark halo ring, a coloured ring and (if filled) a coloured dot: readable
# on black, white and grey scenes, and anti-aliased over one pixel.
CURSOR = ("""#version 330
in vec2 in_px; in vec2 in_local; in float in_radius; in vec4 in_rgba; in float in_fill;
out vec2 v_local; out float v_radius; out vec4 v_rgba; out float v_fill;""" + _VERT_PX + """
void main() { v_local = in_local; v_radius = in_radius; v_rgba = in_rgba; v_fill = in_fill;
              gl_Position = to_clip(in_px); }""", """#version 330
in vec2 v_local; in float v_radius; in vec4 v_rgba; in float v_fill; out vec4 f_colour;
float band(float d, float centre, float half_width) {
    return clamp(half_width + 0.5 - abs(d - centre), 0.0, 1.0); }
void main() {
    float d = length(v_local);
    float halo = band(d, v_radius, 2.5);
    float ring = band(d, v_radius, 1.0);
    float dot_ = v_fill * clamp(v_radius * 0.3 + 0.5 - d, 0.0, 1.0);
    float c = max(ring, dot_);
    float a = max(halo * 0.6, c) * v_rgba.a;
    vec3 rgb = mix(vec3(0.0), v_rgba.rgb, c / max(max(halo * 0.6, c), 1e-6));
    f_colour = vec4(rgb, a);
}""")

SCOPE_BG = (0.05, 0.05, 0.05, 1.0)
SCOPE_GRID = (1.0, 1.0, 1.0, 0.18)  # at 0, half and full scale of each plot
SCOPE_RULE = (1.0, 1.0, 1.0, 0.45)  # the edges of the strip and between the two plots
TEXT_CACHE = 64  # text textures kept between frames (a frame draws about 20)
BANNER_RGBA = {"stop": (0.75, 0.0, 0.0, 0.92), "error": (0.55, 0.05, 0.05, 0.92),
               "info": (0.1, 0.1, 0.1, 0.85)}


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


class Compositor:
    """Draws ``scene`` and a :class:`FrameView` into the current framebuffer of ``ctx``.

    ``scope``: lay the frame out for the scope strip at first (a frame drawn with or
    without it lays the frame out again, re-rendering the scene if it moved).
    """

    def __init__(self, ctx: moderngl.Context, scene: Scene, size: tuple[int, int],
                 outlines: bool = False, supersample: int = 4, scope: bool = True):
        self.ctx = ctx
        self.outlines = outlines
        self.scope = scope
        self.supersample = supersample
        self.textured = ctx.program(vertex_shader=TEXTURED[0], fragment_shader=TEXTURED[1])
        self.coloured = ctx.program(vertex_shader=COLOURED[0], fragment_shader=COLOURED[1])
        self.cursor = ctx.program(vertex_shader=CURSOR[0], fragment_shader=CURSOR[1])
        self._buffers: dict[str, moderngl.Buffer] = {}
        self._text_cache: OrderedDict[tuple, moderngl.Texture] = OrderedDict()
        self.panels = DevicePanels(self)
        self.status_bottom = 4.0  # px: below the status lines of the last frame drawn
        self.scene = scene
        self.size = (0, 0)
        self.viewport: Viewport | None = None
        self._scope_rect: tuple[float, float, float, float] | None = None
        self._column_rect: tuple[float, float, float, float] = (0.0, 0.0, 0.0, 0.0)
        self.scene_texture: moderngl.Texture | None = None
        self.resize(size)

    # -- static layer -------------------------------------------------------------------

    def resize(self, size: tuple[int, int]) -> None:
        """Fit the scene to a frame of ``size`` px (re-renders the scene texture if needed)."""
        size = (int(size[0]), int(size[1]))
        if size == self.size:
            return
        self.size = size
        self.set_scene(self.scene)

    def set_scene(self, scene: Scene, outlines: bool | None = None) -> None:
        """Draw ``scene`` (once) into the static texture."""
        self.scene = scene
        if outlines is not None:
            self.outlines = outlines
        self.viewport, self._scope_rect, self._column_rect = frame_layout(
            scene.display, *self.size, self.scope, self.panels.column_px(scene, self.size))
        rgb = to_srgb8(scene_rgb(scene, self.viewport, self.supersample, self.outlines))
        if self.scene_texture is not None:
            self.scene_texture.release()
        self.scene_texture = self.ctx.texture((self.viewport.width_px, self.viewport.height_px),
                                              3, np.ascontiguousarray(rgb).tobytes(), alignment=1)
        self.scene_texture.filter = (moderngl.NEAREST, moderngl.NEAREST)
        self.panels.set_scene(scene)

    # -- drawing helpers ----------------------------------------------------------------

    def _buffer(self, key: str, data: np.ndarray) -> moderngl.Buffer:
        raw = np.ascontiguousarray(data, dtype="f4").tobytes()
        buf = self._buffers.get(key)
        if buf is None or buf.size < len(raw):
            if buf is not None:
                buf.release()
            buf = self.ctx.buffer(reserve=max(len(raw), 4096) * 2, dynamic=True)
            self._buffers[key] = buf
        buf.write(raw)
        return buf

    def draw_texture(self, texture: moderngl.Texture, x: float, y: float,
                      size: tuple[float, float] | None = None) -> None:
        w, h = size or texture.size
        quad = np.array([[x, y, 0, 0], [x + w, y, 1, 0], [x, y + h, 0, 1],
                         [x + w, y + h, 1, 1]], dtype=np.float64)
        buf = self._buffer("quad", quad)
        vao = self.ctx.vertex_array(self.textured, [(buf, "2f 2f", "in_px", "in_uv")])
        texture.use(0)
        self.textured["u_tex"] = 0
        vao.render(moderngl.TRIANGLE_STRIP, vertices=4)
        vao.release()

    def draw_triangles(self, key: str, tris: np.ndarray) -> None:
        if len(tris) == 0:
            return
        buf = self._buffer(key, tris)
        vao = self.ctx.vertex_array(self.coloured, [(buf, "2f 4f", "in_px", "in_rgba")])
        vao.render(moderngl.TRIANGLES, vertices=len(tris))
        vao.release()

    def draw_rect(self, x, y, w, h, rgba) -> None:
        corners = np.array([[x, y], [x + w, y], [x, y + h], [x, y + h], [x + w, y], [x + w, y + h]])
        self.draw_triangles("rect", np.column_stack((corners, np.tile(rgba, (6, 1)))))

    def draw_cursors(self, cursors: np.ndarray) -> None:
        if len(cursors) == 0:
            return
        r = cursors[:, 2:3] + 4.0
        local = np.array([[-1, -1], [1, -1], [-1, 1], [-1, 1], [1, -1], [1, 1]], dtype=np.float64)
        verts = []
        for c, reach in zip(cursors, r[:, 0]):
            offs = local * reach
            verts.append(np.column_stack((c[0] + offs[:, 0], c[1] + offs[:, 1], offs,
                                          np.full(6, c[2]), np.tile(c[3:7], (6, 1)),
                                          np.full(6, c[7]))))
        buf = self._buffer("cursor", np.concatenate(verts))
        vao = self.ctx.vertex_array(self.cursor, [(buf, "2f 2f 1f 4f 1f", "in_px", "in_local",
                                                   "in_radius", "in_rgba", "in_fill")])
        vao.render(moderngl.TRIANGLES, vertices=6 * len(cursors))
        vao.release()

    def text(self, lines: tuple[str, ...], size_px: int, rgb=(255, 255, 255),
              background=(0, 0, 0, 170)) -> moderngl.Texture:
        """The texture of ``lines`` of text (cached; valid until the next frame starts)."""
        key = (lines, size_px, rgb, background)
        tex = self._text_cache.get(key)
        if tex is not None:
            self._text_cache.move_to_end(key)
        else:
            img = text_rgba(lines, size_px, rgb, background)
            tex = self.ctx.texture((img.shape[1], img.shape[0]), 4, img.tobytes(), alignment=1)
            tex.filter = (moderngl.NEAREST, moderngl.NEAREST)
            self._text_cache[key] = tex
        return tex

    def _trim_text_cache(self) -> None:
        """Release the least recently used texts beyond TEXT_CACHE. Only between frames:
        a text made earlier in a frame may still be waiting to be drawn."""
        while len(self._text_cache) > TEXT_CACHE:
            self._text_cache.popitem(last=False)[1].release()

    # -- the frame ----------------------------------------------------------------------

    def _set_scope(self, scope: bool) -> None:
        """Lay the frame out with or without the scope strip; the scene is drawn again
        only if it moved."""
        if scope == self.scope:
            return
        self.scope = scope
        viewport = self.viewport
        self.viewport, self._scope_rect, self._column_rect = frame_layout(
            self.scene.display, *self.size, scope, self.panels.column_px(self.scene, self.size))
        if self.viewport != viewport:
            self.set_scene(self.scene)

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
        """Draw the scene and ``view`` into the framebuffer in use."""
        view = view or FrameView()
        self._set_scope(view.show_scope and view.overlay is not None)
        self._trim_text_cache()
        ctx = self.ctx
        w, h = self.size
        ctx.viewport = (0, 0, w, h)
        ctx.disable(moderngl.DEPTH_TEST)
        ctx.clear(0.12, 0.12, 0.12, 1.0)
        for prog in (self.textured, self.coloured, self.cursor):
            prog["u_frame"] = (float(w), float(h))
        vp = self.viewport
        ctx.disable(moderngl.BLEND)
        self.draw_texture(self.scene_texture, vp.x0, vp.y0)
        ctx.enable(moderngl.BLEND)
        ctx.blend_func = moderngl.SRC_ALPHA, moderngl.ONE_MINUS_SRC_ALPHA
        font_px = self.font_px
        status = None
        if view.status:
            status = self.text(sum((wrap(line, font_px, w - 16) for line in view.status), ()), font_px)
        self.status_bottom = 4.0 + (status.size[1] if status is not None else 0.0)
        overlay = view.overlay or OverlayState()
        if view.overlay is not None:
            self.draw_triangles("trail", view.overlay.trail_triangles(vp))
        self.draw_cursors(overlay.cursors(vp, view.hover_mm))
        self.panels.draw(overlay, view.envelope, view.envelope_scale_um)
        if view.show_scope and view.overlay is not None:
            self._draw_scope(view, font_px)
        if status is not None:
            self.draw_texture(status, 4, 4)
        if view.banner:
            lines = wrap(view.banner, font_px + 2, w - 40)
            tex = self.text(lines, font_px + 2, background=(0, 0, 0, 0))
            bh = tex.size[1] + 12
            y = (h - bh) / 2 if view.banner_kind == "stop" else h * 0.12
            self.draw_rect(0, y, w, bh, BANNER_RGBA.get(view.banner_kind, BANNER_RGBA["info"]))
            self.draw_texture(tex, max(4.0, (w - tex.size[0]) / 2), y + 6)
        ctx.disable(moderngl.BLEND)

    def _draw_scope(self, view: FrameView, font_px: int) -> None:
        x, y, w, h = self.scope_rect()
        self.draw_rect(x, y, w, h, SCOPE_BG)
        plots = self.scope_plots()
        for px, py, pw, ph in plots:
            self.draw_rect(px, py - 1.0, pw, 1.0, SCOPE_RULE)  # under the title row
            for level in plot_y((0.0, 0.5, 1.0), (px, py, pw, ph)):
                self.draw_rect(px, level - 0.5, pw, 1.0, SCOPE_GRID)
        self.draw_rect(x, y, w, 1.0, SCOPE_RULE)
        self.draw_triangles("scope", view.overlay.scope_triangles(plots, view.amplitude_max_um))
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
        return int(np.clip(self.size[1] / 45, 11, 22))

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
        for obj in (*self._buffers.values(), *self._text_cache.values(), self.scene_texture,
                    self.textured, self.coloured, self.cursor):
            if obj is not None:
                obj.release()
