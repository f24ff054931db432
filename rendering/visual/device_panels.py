"""What the visual layer shows of the device itself, drawn with a ``Compositor``'s primitives.

- A modal device (seed 000's beam, seed 001's plate; ``modal_view``): the vibration
  amplitude |W| along the beam, a curve in a strip under it, or over the plate, a heat
  map in a column of its own at the right of the frame (``column_px``: the compositor
  fits the scene beside it, so it never covers the scene or a finger); each finger
  marked in its colour, with |W| under it, in rows of their own above and below the map.
- A device that pushes a finger (seeds 002, 004): the force on each finger as an arrow
  (achieved solid, wanted thin) and the arrow's N scale; each key-click button framed and
  labelled in the colour of its state (seed 004 Fig. 5: idle, wave on, clicked).
"""

from __future__ import annotations

import moderngl
import numpy as np

from frictex.rendering.layers.keyclick import CLICKED, IDLE, ON
from frictex.rendering.visual.modal_view import Envelope, heat_rgb
from frictex.rendering.visual.overlay import FINGER_RGB, OverlayState, arrow_triangles, segment_triangles
from frictex.rendering.visual import viewport
from frictex.rendering.visual.scene_image import to_srgb8
from frictex.device.profile import FORCE_PROFILES, PlateStructure
from frictex.textures.model import Directional, Guidance, KeyClick, Scene

PANEL_BG = (0.0, 0.0, 0.0, 0.8)
PANEL_MARGIN_PX = 8.0
#: a plate's heat map panel: this share of the frame's height, within PLATE_PANEL_PX
PLATE_PANEL_SHARE, PLATE_PANEL_PX = 0.32, (120.0, 300.0)
FORCE_ARROW_MM = 20.0  # on screen, the arrow of the scene's largest force
BUTTON_LOOK = {IDLE: ("idle", (0.45, 0.45, 0.45, 0.95)), ON: ("wave on", (0.95, 0.6, 0.05, 0.95)),
               CLICKED: ("clicked", (0.1, 0.75, 0.25, 0.95))}


def force_scale_n(scene: Scene) -> float | None:
    """The force (N) drawn FORCE_ARROW_MM long: the largest of the friction on a finger at
    rest friction and nominal normal force (mu0 F_n: a sliding finger's arrow includes its
    friction) and of what the scene's force layers ask for; None for a device that cannot
    push a finger."""
    if scene.device.profile not in FORCE_PROFILES:
        return None
    sizes = [scene.device.driving.mu0 * scene.device.normal_force_n]
    for layer in scene.layers:
        if isinstance(layer, KeyClick):
            sizes.append(layer.force_n)
        elif isinstance(layer, Guidance):
            sizes.append(layer.max_force_n)
        elif isinstance(layer, Directional) and layer.target == "force":
            sizes += [abs(layer.forward), abs(layer.backward)]
    return max(sizes)


def default_frame_size(scene: Scene) -> tuple[int, int]:
    """The default frame for ``scene``: its display at its own pixel size above the scope
    strip and beside the column its panels need (``DevicePanels.column_px``)."""
    size = viewport.default_frame_size(scene.display)
    return viewport.default_frame_size(scene.display, DevicePanels.column_px(scene, size))


class DevicePanels:
    """The device panels of ``comp``'s scene (``comp``: a ``compositor.Compositor``)."""

    def __init__(self, comp):
        self.comp = comp
        self.force_scale_n: float | None = None
        self._heat: tuple[Envelope | None, float, moderngl.Texture | None] = (None, 0.0, None)

    def set_scene(self, scene: Scene) -> None:
        self.force_scale_n = force_scale_n(scene)

    @staticmethod
    def column_px(scene: Scene, size: tuple[int, int]) -> int:
        """Width (px) of the column the panels need at the right of a frame of ``size``:
        a plate's heat map and its margins; 0 for other devices (a beam's |W| has a
        strip under or over it)."""
        if not isinstance(scene.device.structure, PlateStructure):
            return 0
        side = np.clip(PLATE_PANEL_SHARE * size[1], *PLATE_PANEL_PX)
        return int(round(side + 2 * PANEL_MARGIN_PX))

    @property
    def row_px(self) -> float:
        """Height (px) of a row of labels (the compositor's)."""
        return self.comp.label_row_px

    def draw(self, overlay: OverlayState, envelope: Envelope | None, envelope_scale_um: float) -> None:
        """Buttons, force arrows and |W|, as the scene's device has them."""
        self._draw_buttons(overlay.button)
        if self.force_scale_n is not None:
            self._draw_forces(overlay)
        if envelope is not None:
            self._draw_envelope(envelope, envelope_scale_um)

    # -- forces and buttons -------------------------------------------------------------

    def _draw_forces(self, overlay: OverlayState) -> None:
        """Force arrows on the fingers and their scale (bottom left of the scene's area,
        above the scope: right of the layer panel's column while it is open)."""
        comp, vp = self.comp, self.comp.viewport
        length = FORCE_ARROW_MM * min(vp.px_per_mm)
        comp.draw_triangles(overlay.force_arrows(vp, length / self.force_scale_n))
        x = comp.layer_panel_rect()[2] + 12.0  # the column is 0 px wide while closed
        y = comp.scope_rect()[1] - comp.font_px * 2.2
        comp.draw_triangles(arrow_triangles((x, y), (length, 0.0), (1.0, 1.0, 1.0, 0.9), 3.0))
        comp.draw_texture(comp.text((f"{self.force_scale_n:g} N (arrow: force on the finger, "
                                     "thin: wanted)",), comp.label_px, background=(0, 0, 0, 150)),
                          x + 4.0 + length, y - comp.font_px * 0.75)

    def _draw_buttons(self, state: int | None) -> None:
        """Each key-click button framed and labelled in the colour of its state."""
        comp = self.comp
        buttons = [layer for layer in comp.scene.layers if isinstance(layer, KeyClick)]
        if not buttons:
            return
        text, rgba = BUTTON_LOOK[IDLE if state is None else state]
        vp = comp.viewport
        for layer in buttons:
            g = layer.geometry
            a = np.radians(g.angle_deg)
            half = (np.array([[-1, -1], [1, -1], [1, 1], [-1, 1], [-1, -1]])
                    * [g.width_mm / 2, g.height_mm / 2])
            cx, cy = g.center
            corners = np.column_stack((cx + half[:, 0] * np.cos(a) - half[:, 1] * np.sin(a),
                                       cy + half[:, 0] * np.sin(a) + half[:, 1] * np.cos(a)))
            px = np.column_stack(vp.to_px(corners[:, 0], corners[:, 1]))
            comp.draw_triangles(segment_triangles(px, np.tile(rgba, (5, 1)), 4.0))
            tex = comp.text((f"{layer.name}: {text}",), comp.font_px,
                            background=(*(int(255 * c) for c in rgba[:3]), 230))
            comp.draw_texture(tex, px[:4, 0].min(), px[:4, 1].min() - tex.size[1] - 2)

    # -- |W| of a modal device ----------------------------------------------------------

    def envelope_rect(self, kind: str) -> tuple[float, float, float, float]:
        """Where |W| is drawn (x, y, w, h) px: for a beam a strip as wide as the display,
        under it if there is room above the scope, else over it; for a plate a square
        panel in the column at the right of the frame (``column_px``), under the status
        lines, as high as the column leaves room for."""
        comp = self.comp
        vp, (w, _) = comp.viewport, comp.size
        if kind == "plate":
            left = comp.column_rect()[0]
            top = comp.status_bottom + 4.0
            room = comp.scope_rect()[1] - PANEL_MARGIN_PX - top
            side = max(min(w - left - 2 * PANEL_MARGIN_PX, room), 1.0)
            return left + PANEL_MARGIN_PX, top, side, side
        scope_top = comp.scope_rect()[1]
        below = vp.y0 + vp.height_px + 4.0
        height = min(160.0, scope_top - below - 4.0)
        if height >= 40.0:
            return float(vp.x0), below, float(vp.width_px), height
        height = float(np.clip(vp.y0 - 56.0, 40.0, 160.0))
        return float(vp.x0), max(0.0, vp.y0 - height - 4.0), float(vp.width_px), height

    def heat_map_rect(self, rect) -> tuple[float, float, float, float]:
        """The heat map (x, y, w, h) px inside the panel ``rect``: the display's aspect,
        between the title row and the bottom row."""
        x, y, w, h = rect
        d = self.comp.scene.display
        avail_w, avail_h = w - 8.0, h - 2 * self.row_px
        scale = min(avail_w / d.width_mm, avail_h / d.height_mm)
        mw, mh = d.width_mm * scale, d.height_mm * scale
        return x + (w - mw) / 2, y + self.row_px + (avail_h - mh) / 2, mw, mh

    def _draw_envelope(self, env: Envelope, scale_um: float) -> None:
        comp = self.comp
        x, y, w, h = rect = self.envelope_rect(env.kind)
        comp.draw_rect(x, y, w, h, PANEL_BG)
        if env.kind == "beam":
            self._draw_beam(env, scale_um, rect)
        else:
            self._draw_plate(env, scale_um, rect)
        what = "along the beam" if env.kind == "beam" else "over the plate"
        title = comp.text((f"|W| {what}, 0 to {scale_um:.2g} um",), comp.label_px,
                          background=(0, 0, 0, 150))
        if title.size[0] > w - 8:  # a narrow column: the short form
            title = comp.text((f"|W|, 0 to {scale_um:.2g} um",), comp.label_px,
                              background=(0, 0, 0, 150))
        comp.draw_texture(title, x + 4, y + 2)
        # |W| under each finger, in its colour: after the title if there is room, else
        # along the panel's bottom (kept clear of the heat map)
        texs = [comp.text((f"{amp:.2f} um",), comp.label_px, background=(0, 0, 0, 150),
                          rgb=tuple(int(round(255 * c)) for c in FINGER_RGB[fid % len(FINGER_RGB)]))
                for fid, _, _, amp in env.fingers]
        right, row = x + 4 + title.size[0] + 6, y + 2
        if right + sum(t.size[0] + 6 for t in texs) > x + w:
            right, row = x + 4, y + h - self.row_px
        for tex in texs:
            if right + tex.size[0] > x + w:  # no room left in the row: the rest unlabelled
                break
            comp.draw_texture(tex, right, row)
            right += tex.size[0] + 6

    def _draw_beam(self, env: Envelope, scale_um: float, rect) -> None:
        comp = self.comp
        x, y, w, h = rect
        vp = comp.viewport
        px = vp.to_px(env.x_mm, 0.0)[0]
        top, base = y + self.row_px, y + h - 2.0
        u = np.clip(env.amplitude_um / scale_um, 0.0, 1.0)
        ok = np.isfinite(u)
        py = base - (base - top) * np.where(ok, u, 0.0)
        # filled area: one quad per interval between samples on the structure
        keep = ok[:-1] & ok[1:]
        x0, x1, y0, y1 = px[:-1][keep], px[1:][keep], py[:-1][keep], py[1:][keep]
        b0, b1 = np.full_like(x0, base), np.full_like(x1, base)
        fill = np.stack([np.column_stack(p) for p in ((x0, y0), (x1, y1), (x0, b0),
                                                       (x0, b0), (x1, y1), (x1, b1))],
                        axis=1).reshape(-1, 2)
        rgba = np.tile((0.95, 0.45, 0.1, 0.55), (len(fill), 1))
        comp.draw_triangles(np.column_stack((fill, rgba)))
        curve = np.column_stack((px, py))
        comp.draw_triangles(segment_triangles(
            curve, np.tile((1.0, 0.8, 0.3, 1.0), (len(px), 1)), 1.5, keep))
        marks = []
        for fid, fx, _, amp in env.fingers:
            fx_px = float(vp.to_px(fx, 0.0)[0])
            comp.draw_rect(fx_px - 1.0, top, 2.0, base - top, (*FINGER_RGB[fid % len(FINGER_RGB)], 1.0))
            marks.append((fx_px, base - (base - top) * min(amp / scale_um, 1.0), fid))
        self._draw_marks(marks)

    def _draw_plate(self, env: Envelope, scale_um: float, rect) -> None:
        comp = self.comp
        cached, cached_scale, tex = self._heat
        if cached is not env or cached_scale != scale_um:
            rgb = to_srgb8(heat_rgb(env.amplitude_um / scale_um))
            if tex is None or tex.size != (rgb.shape[1], rgb.shape[0]):
                if tex is not None:
                    tex.release()
                tex = comp.ctx.texture((rgb.shape[1], rgb.shape[0]), 3, alignment=1)
                tex.filter = (moderngl.LINEAR, moderngl.LINEAR)
            tex.write(np.ascontiguousarray(rgb).tobytes())
            self._heat = (env, scale_um, tex)
        ax, ay, aw, ah = self.heat_map_rect(rect)
        comp.draw_texture(tex, ax, ay, (aw, ah), opaque=True)
        d = comp.scene.display
        self._draw_marks([(ax + aw * fx / d.width_mm, ay + ah * fy / d.height_mm, fid)
                          for fid, fx, fy, _ in env.fingers])

    def _draw_marks(self, marks: list[tuple[float, float, int]]) -> None:
        """Small filled finger markers (x px, y px, finger id)."""
        rows = [(mx, my, 5.0, *FINGER_RGB[fid % len(FINGER_RGB)], 1.0, 1.0) for mx, my, fid in marks]
        self.comp.draw_cursors(np.array(rows, dtype=np.float64).reshape(-1, 8))

    def release(self) -> None:
        if self._heat[2] is not None:
            self._heat[2].release()
        self._heat = (None, 0.0, None)
