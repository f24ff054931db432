"""``frictex preview SCENE -o out.png``: the scene as the demo draws it, beside its
friction map (mu' as an image with a colour bar), in one PNG.

The left panel is the visual layer's static image (``rendering.visual.scene_image``,
the same pixels the demo window shows); the right panel is mu' composed from the
layers (``rendering.compose.ideal_mu``: what a perfect renderer gives a finger there),
averaged over each pixel. The colour bar marks the lowest mu' the device reaches at
the scene's nominal normal force: targets below it will be clamped.

Layers whose mu' depends on motion or time are shown as follows (and said so in the
title): a height layer as a finger sliding towards +x feels it (climbing flanks above
its rest level, descending ones below); a recorded texture at its mean; a clip at rest
(mu' 1) in the map, with its trigger, length and deepest mu' in the title.
"""

from __future__ import annotations

import argparse
from pathlib import Path

import numpy as np

from frictex.app.engine.outfile import write_file
from frictex.device.errors import InputError
from frictex.rendering.compose import ideal_mu
from frictex.device.friction import mu_floor
from frictex.rendering.visual.scene_image import scene_rgb, to_srgb8
from frictex.rendering.visual.viewport import fit_viewport
from frictex.textures.outside import add_allow_outside


#: Largest scene panel (px per side): ``--size`` up to this; by default the display's own
#: pixel size, scaled down to fit it.
MAX_PANEL_PX = 4096
DEFAULT_MAX_PANEL_PX = 2048
#: Rows of the friction map computed at once (bounds memory for any panel size).
ROWS_PER_PASS = 256


def frame_size(text: str) -> tuple[int, int]:
    """argparse type for ``WIDTHxHEIGHT`` in pixels."""
    try:
        w, h = (int(v) for v in text.lower().split("x"))
    except ValueError:
        raise argparse.ArgumentTypeError(f"{text!r} is not WIDTHxHEIGHT (e.g. 800x480)") from None
    if not (1 <= w <= MAX_PANEL_PX and 1 <= h <= MAX_PANEL_PX):
        raise argparse.ArgumentTypeError(f"{text!r}: width and height must be 1 to "
                                         f"{MAX_PANEL_PX} px")
    return w, h


def default_size(display) -> tuple[int, int]:
    """The display's pixel size, scaled down to at most DEFAULT_MAX_PANEL_PX per side."""
    w, h = display.width_px, display.height_px
    scale = min(1.0, DEFAULT_MAX_PANEL_PX / max(w, h))
    return max(1, round(w * scale)), max(1, round(h * scale))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="texture file (.toml) or bundled scene name (see frictex library)")
    parser.add_argument("-o", "--out", required=True, metavar="PNG", help="output image (.png)")
    parser.add_argument("--size", type=frame_size, default=None, metavar="WxH",
                        help="pixel size of the scene panel (default: the scene's display size)")
    parser.add_argument("--outlines", action="store_true", help="outline every region and object")
    add_allow_outside(parser)


def load(scene_name: str):
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    return load_scene(resolve_scene(scene_name))


class _MovingRight:
    """A height layer as ``ideal_mu`` sees it in the preview: felt sliding towards +x
    (above ``v_fade_mm_s``), instead of at rest."""

    def __init__(self, layer):
        self.layer = layer
        self.blend = layer.blend

    def covers(self, x, y):
        return self.layer.covers(x, y)

    def mu_at(self, x, y):
        layer = self.layer
        gx, gy = layer.shape.gradient(x, y)
        speed = 2.0 * layer.v_fade_mm_s
        return layer.mu_of_motion(gx, gy, speed, 0.0)


def as_previewed(scene):
    """The scene with its height layers felt sliding towards +x (see the module docstring)."""
    from dataclasses import replace
    return replace(scene, layers=tuple(_MovingRight(layer) if getattr(layer, "renderer_kind", None)
                                       == "height" else layer for layer in scene.layers))


def _layer_note(layer) -> str:
    """How the title describes a layer."""
    kind = getattr(layer, "renderer_kind", None)
    if kind == "height":
        return f"{layer.name} (height {type(layer.shape).__name__.lower()}, felt moving +x)"
    if kind == "ar":
        return f"{layer.name} (recorded texture, shown at its mean {layer.mu_mean:g})"
    if kind == "clip":
        lo = 1.0 - layer.clip.depth
        return (f"{layer.name} (clip on {layer.trigger}: {layer.clip.duration_s * 1e3:.0f} ms, "
                f"mu' down to {lo:.2f}; not in the map)")
    return (f"{layer.name} ({type(layer).__name__.lower()}, {layer.render}"
            + (f", {layer.period_mm:g} mm" if layer.is_periodic else "") + ")")


def mu_map(scene, viewport, supersample: int = 3) -> np.ndarray:
    """mu' (height_px, width_px) averaged over ``supersample**2`` points per pixel,
    ``ROWS_PER_PASS`` rows at a time."""
    sx, sy = viewport.px_per_mm
    cols = np.arange(viewport.width_px, dtype=np.float64)
    acc = np.zeros((viewport.height_px, viewport.width_px))
    offsets = (np.arange(supersample) + 0.5) / supersample
    for start in range(0, viewport.height_px, ROWS_PER_PASS):
        rows = np.arange(start, min(start + ROWS_PER_PASS, viewport.height_px), dtype=np.float64)
        band = acc[start:start + rows.size]
        for oy in offsets:
            for ox in offsets:
                xx, yy = np.broadcast_arrays(((cols + ox) / sx)[None, :],
                                             ((rows + oy) / sy)[:, None])
                band += ideal_mu(scene, xx, yy)
    return acc / supersample ** 2


def write_preview(scene, out: Path, size: tuple[int, int] | None = None,
                  outlines: bool = False) -> dict:
    """Render the preview PNG of ``scene`` into ``out``; return what it shows (mu' range, floor).

    Room-checked (4 bytes per pixel of the figure) and written under a temporary name
    (``app.engine.outfile``): a full disk leaves no truncated or empty PNG, and an earlier
    file of that name stays."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    d = scene.display
    viewport = fit_viewport(d, *(size or default_size(d)))
    image = to_srgb8(scene_rgb(scene, viewport, outlines=outlines))
    mu = mu_map(as_previewed(scene), viewport)
    floor = mu_floor(scene.device, scene.device.normal_force_n)
    extent = (0.0, d.width_mm, d.height_mm, 0.0)
    # a display far taller than wide would ask for a figure metres high
    aspect = min(d.height_mm / d.width_mm, 4.0)
    fig = Figure(figsize=(13.0, 13.0 * aspect / 2 + 1.4), dpi=110, layout="constrained")
    FigureCanvasAgg(fig)
    left, right = fig.subplots(1, 2)
    left.imshow(image, extent=extent, interpolation="antialiased")
    left.set_title(f"{scene.name}: as drawn ({viewport.width_px} x {viewport.height_px} px)")
    vmin = min(float(mu.min()), floor) - 0.02
    shown = right.imshow(mu, extent=extent, cmap="viridis", vmin=vmin, vmax=1.0,
                         interpolation="antialiased")
    right.set_title("friction map: target mu' (1 = plate at rest)")
    for ax in (left, right):
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    bar = fig.colorbar(shown, ax=right, shrink=0.9)
    bar.set_label("mu' = mu(w) / mu(0)")
    bar.ax.axhline(floor, color="red", linewidth=2)
    # a tick label next to the floor's would print over it
    bar.set_ticks([t for t in bar.get_ticks()
                   if vmin <= t <= 1.0 and abs(t - floor) > 0.08 * (1.0 - vmin)])
    bar.ax.text(1.05, floor, f" floor\n {floor:.2f}\n @{scene.device.normal_force_n:g} N",
                transform=bar.ax.get_yaxis_transform(), color="red", fontsize=8, va="center")
    layers = "; ".join(_layer_note(layer) for layer in scene.layers)
    fig.suptitle(f"layers: {layers}", fontsize=9)
    width, height = fig.get_size_inches() * fig.dpi
    write_file(out, lambda to: fig.savefig(to, format="png"), width * height * 4)
    return {"mu_min": float(mu.min()), "mu_max": float(mu.max()), "floor": floor,
            "size": (viewport.width_px, viewport.height_px)}


def run(args: argparse.Namespace) -> int:
    out = Path(args.out)
    if out.suffix.lower() != ".png":
        raise InputError(f"output {str(out)!r}: expected a .png file name")
    if not out.parent.is_dir():
        raise InputError(f"output folder {str(out.parent)!r} does not exist")
    scene = load(args.scene)
    info = write_preview(scene, out, args.size, args.outlines)
    print(f"wrote {out}: {scene.name}, scene panel {info['size'][0]} x {info['size'][1]} px, "
          f"mu' {info['mu_min']:.3f} to {info['mu_max']:.3f} (device floor {info['floor']:.3f} "
          f"at {scene.device.normal_force_n:g} N)")
    return 0
