"""``frictex preview SCENE -o out.png``: two PNGs, the scene at its display's pixels and
a figure of the scene beside its friction map (mu' as an image with a colour bar).

The scene image (``--scene-out``, by default ``<out>-scene.png`` beside ``out.png``) is
the visual layer's static image (``rendering.visual.scene_image``): the display's mm
area fitted in its ``width_px`` x ``height_px`` keeping the mm aspect, pixel for pixel
what the demo's window draws there (all of them where the pixels are square; 800 x 480 px
on 120 x 64.8 mm gives 800 x 432), at most MAX_PANEL_PX a side: a grating's period
measures period_mm x px/mm in it. ``--size WxH`` draws it at another size (the display
fitted in WxH, its aspect kept).

The figure's left panel is that image scaled to fit the figure (its pixels are not the
display's: its title says so); the right panel is mu' composed from the layers that
apply to a finger touching alone (``textures.overlap.applies_alone``: ``fingers`` any,
1 or a positional selector) by ``rendering.compose.ideal_mu``, what a perfect renderer
gives a lone finger there, averaged over each pixel. Layers felt only with two or more
fingers down (``fingers = "2"``, ...) are left out of it, and named in its title and
printed. The colour bar marks the lowest mu' the device reaches at the scene's nominal
normal force (``device.friction.mu_floor``); where the map asks for less, it is hatched
and outlined in red: targets there will be clamped (``frictex validate`` gives the
share of a typical stroke, ``rendering.reach``).

Layers whose mu' depends on motion or time are shown as follows (and said so in the
title): a height layer as a finger sliding towards +x feels it (climbing flanks above
its rest level, descending ones below); a recorded texture at its mean; a clip at rest
(mu' 1) in the map, with its trigger, length and deepest mu' in the title (the lowest
of its samples at the default 10 kHz output rate, which is 1 - depth only where its
events reach full level). Force layers (directional, guidance, keyclick) are mu' 1 in the
map: the title and a printed line give what each does (mu' or force per direction of
travel, the pull, the push and its thresholds) and where.

Under the panels, and printed, as ``frictex validate --perception`` reports them
(``rendering.perception``): the scene's features a finger will not feel (below a
published threshold of touch, with its source), and apart from them, notes on how a
layer renders (a period finer than the touch samples can place, and what the layer's
renderer makes of it).
"""

from __future__ import annotations

import argparse
import textwrap
from dataclasses import replace
from pathlib import Path

import numpy as np

from frictex.device.safe_text import printable
from frictex.app.engine.outfile import write_file
from frictex.device.errors import InputError
from frictex.device.friction import mu_floor
from frictex.device.safe_text import escape, escape_path
from frictex.rendering.compose import ideal_mu
from frictex.rendering.perception import RENDERING_KINDS, scene_findings
from frictex.rendering.reach import as_previewed
from frictex.rendering.visual.scene_image import scene_rgb, to_srgb8
from frictex.rendering.visual.viewport import fit_viewport
from frictex.textures.outside import add_allow_outside
from frictex.textures.overlap import applies_alone


#: Largest scene image (px per side): ``--size`` up to this; by default the display's own
#: pixel size, scaled down to fit it.
MAX_PANEL_PX = 4096
#: Largest panel (px per side) the figure's two panels are computed at (they are scaled
#: to the figure's few hundred pixels anyway).
DEFAULT_MAX_PANEL_PX = 2048
#: Displays flatter than this (height / width) get their panels one above the other,
#: stretched in y, with a horizontal colour bar (seed 000's beam is 350 x 6 mm).
FLAT_ASPECT = 0.35
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


def default_size(display, limit: int = DEFAULT_MAX_PANEL_PX) -> tuple[int, int]:
    """The display's pixel size, scaled down to at most ``limit`` px per side."""
    w, h = display.width_px, display.height_px
    scale = min(1.0, limit / max(w, h))
    return max(1, round(w * scale)), max(1, round(h * scale))


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("scene", help="texture file (.toml) or bundled scene name (see frictex library)")
    parser.add_argument("-o", "--out", required=True, metavar="PNG",
                        help="the figure: the scene (scaled to fit) beside its friction map (.png)")
    parser.add_argument("--scene-out", default=None, metavar="PNG",
                        help="the scene alone at its pixels, as the demo's window draws it "
                             "(default: OUT's name with -scene, beside it)")
    parser.add_argument("--size", type=frame_size, default=None, metavar="WxH",
                        help="pixel size of the scene image (--scene-out): the display fitted "
                             "in WxH, its aspect kept (default: the display's width_px x "
                             f"height_px, up to {MAX_PANEL_PX} px a side)")
    parser.add_argument("--outlines", action="store_true", help="outline every region and object")
    add_allow_outside(parser)


def load(scene_name: str):
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    return load_scene(resolve_scene(scene_name))


#: what the title calls a height layer's shape (the file's ``shape`` word)
HEIGHT_SHAPE_WORDS = {"GaussianBump": "bump", "Ridge": "ridge", "Step": "step",
                      "ButtonRim": "button", "HeightMap": "map"}


def layer_kind(layer) -> str:
    """The layer's ``type`` as its file writes it (``shape`` too for heights and waveforms)."""
    from frictex.textures import model
    kind = getattr(layer, "renderer_kind", None)
    if kind == "height":
        return "height " + HEIGHT_SHAPE_WORDS.get(type(layer.shape).__name__, "map")
    if isinstance(layer, model.Shape):
        return "disc" if isinstance(layer.geometry, model.DiscRegion) else "rectangle"
    if isinstance(layer, model.RasterMap):
        return "raster"
    if isinstance(layer, model.Waveform):
        return f"{layer.shape} waveform"
    return type(layer).__name__.lower()


def _layer_note(layer, display) -> str:
    """How the title describes a layer of a scene on ``display``."""
    from frictex.textures.model import FORCE_LAYERS
    if isinstance(layer, FORCE_LAYERS):
        return f"{layer.name} ({layer_kind(layer)}: {force_effect(layer, display)}; not in the map)"
    kind = getattr(layer, "renderer_kind", None)
    if kind == "height":
        return f"{layer.name} ({layer_kind(layer)}, felt moving +x)"
    if kind == "ar":
        return f"{layer.name} (recorded texture, shown at its mean {layer.mu_mean:g})"
    if kind == "clip":
        return (f"{layer.name} (clip on {layer.trigger}: {layer.clip.duration_s * 1e3:.0f} ms, "
                f"deepest mu' {layer.clip.deepest_mu:.3f}; not in the map)")
    return (f"{layer.name} ({layer_kind(layer)}, {layer.render}"
            + (f", {layer.period_mm:g} mm" if layer.is_periodic else "") + ")")


def force_effect(layer, display) -> str:
    """What a force layer (``textures.model.FORCE_LAYERS``: mu' 1 in the friction map) does
    to a finger, in words, and where on ``display`` (mm)."""
    from frictex.textures.model import Directional, Guidance
    if isinstance(layer, Directional):
        ahead, back = ("+x", "-x") if layer.axis_sign > 0 else ("-x", "+x")
        if layer.target == "mu":
            what = f"mu' {layer.forward:g} moving {ahead}, {layer.backward:g} moving {back}"
        else:
            what = (f"a net tangential force of {layer.forward:g} N moving {ahead}, "
                    f"{layer.backward:g} N moving {back} (positive resists the finger)")
    elif isinstance(layer, Guidance):
        what = (f"a pull towards {_guidance_target(layer)}, {layer.gain_n_per_mm:g} N/mm "
                f"up to {layer.max_force_n:g} N")
    else:  # KeyClick
        what = (f"a push of {layer.force_n:g} N towards {'+x' if layer.first_push > 0 else '-x'} "
                f"from a press of {layer.press_n:g} N, reversed at {layer.click_n:g} N, "
                f"released below {layer.release_n:g} N")
    return f"{what}, {_within(_force_box(layer, display), display)}"


def _guidance_target(layer) -> str:
    """A guidance layer's target point or line, in words (mm)."""
    if not layer.line:
        return f"({layer.x_mm:g}, {layer.y_mm:g}) mm"
    angle = layer.line_angle_deg % 180.0
    if angle == 90.0:
        return f"the line x = {layer.x_mm:g} mm"
    if angle == 0.0:
        return f"the line y = {layer.y_mm:g} mm"
    return f"the line through ({layer.x_mm:g}, {layer.y_mm:g}) mm at {layer.line_angle_deg:g} deg"


def _force_box(layer, display):
    """The box (mm) holding where a force layer acts on ``display``: its region and, for a
    button, its rectangle; None where they share no area."""
    from frictex.textures.extent import display_box, intersect, region_box
    box = display_box(display)
    for region in (layer.region, getattr(layer, "geometry", None)):
        if region is not None:
            box = intersect(box, region_box(region))
    return box


def _within(box, display) -> str:
    """Where ``box`` (mm) lies on ``display``, in words: only the axes it does not span."""
    if box is None:
        return "nowhere on the display"
    x0, y0, x1, y1 = box
    parts = ([] if x0 <= 0.0 and x1 >= display.width_mm else [f"x {x0:g}-{x1:g}"]) \
        + ([] if y0 <= 0.0 and y1 >= display.height_mm else [f"y {y0:g}-{y1:g}"])
    return f"within {', '.join(parts)} mm" if parts else "over the whole display"


def force_notes(scene) -> list[str]:
    """Each force layer of ``scene`` (not in the friction map) and what it does, in words."""
    from frictex.textures.model import FORCE_LAYERS
    return [f"{layer.name} ({layer_kind(layer)}, not in the friction map): "
            f"{force_effect(layer, scene.display)}"
            for layer in scene.layers if isinstance(layer, FORCE_LAYERS)]


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


def scene_image(scene, size: tuple[int, int], outlines: bool = False) -> np.ndarray:
    """The scene as the demo's window draws it, the display fitted in ``size`` (w, h px)
    keeping its aspect (fullscreen on the glass the demo stretches each axis instead,
    ``rendering.visual.viewport.on_glass``): sRGB uint8 (height_px, width_px, 3)."""
    return to_srgb8(scene_rgb(scene, fit_viewport(scene.display, *size), outlines=outlines))


def preview_figure(scene, size: tuple[int, int] | None = None, outlines: bool = False,
                   image: np.ndarray | None = None):
    """The preview of ``scene`` as a matplotlib Figure, and what it shows (mu' range, floor,
    share of the display below the floor, panel size, the layers left out of the map and
    ``map``: the friction map, mu' (height_px, width_px)).

    The panels are computed at ``size`` (w, h px; default the display's pixels up to
    DEFAULT_MAX_PANEL_PX a side) and scaled to fit the figure; ``image``: the scene image
    at that size if already drawn (:func:`scene_image`). Where the composed mu' lies below
    the device's floor at the scene's nominal normal force, the friction map is hatched
    (those targets will be clamped); the floor is a red line and a labelled tick on the
    colour bar."""
    d = scene.display
    viewport = fit_viewport(d, *(size or default_size(d)))
    if image is None or image.shape[:2] != (viewport.height_px, viewport.width_px):
        image = to_srgb8(scene_rgb(scene, viewport, outlines=outlines))
    alone, left_out = split_by_fingers(as_previewed(scene).layers)
    mu = mu_map(replace(scene, layers=alone), viewport)
    force = scene.device.normal_force_n
    floor = mu_floor(scene.device, force)
    below = mu < floor - 1e-12
    extent = (0.0, d.width_mm, d.height_mm, 0.0)
    flat = d.height_mm / d.width_mm < FLAT_ASPECT
    fig, left, right, stretch = _panels(d, flat)
    left.imshow(image, extent=extent, interpolation="antialiased", aspect=stretch)
    left.set_title(f"{scene.name}: as drawn, scaled to fit" + (", y stretched" if flat else "")
                   + ("; " if flat else "\n") + "at the display's pixels: the scene image",
                   fontsize=10)
    vmin = min(float(mu.min()), floor) - 0.02
    shown = right.imshow(mu, extent=extent, cmap="viridis", vmin=vmin, vmax=1.0,
                         interpolation="antialiased", aspect=stretch)
    _hatch_below(right, below, d, viewport, left_out)
    for ax in (left, right):
        ax.set_xlabel("x (mm)")
        ax.set_ylabel("y (mm)")
    _floor_bar(fig, shown, right, flat, floor, force, vmin)
    felt, rendering = _captions(fig, scene)
    info = {"mu_min": float(mu.min()), "mu_max": float(mu.max()), "floor": floor,
            "below": float(below.mean()), "size": (viewport.width_px, viewport.height_px),
            "left_out": left_out_note(left_out), "forces": force_notes(scene),
            "perception": felt, "rendering": rendering, "map": mu}
    return fig, info


def split_by_fingers(layers) -> tuple[tuple, tuple]:
    """``layers`` split into those a finger touching alone feels (the map's) and those
    felt only with two or more fingers down (``fingers = "2"``, ``"3"``, ...)."""
    return (tuple(layer for layer in layers if applies_alone(layer)),
            tuple(layer for layer in layers if not applies_alone(layer)))


def left_out_note(left_out) -> str:
    """What the map leaves out, in words: '' where it leaves out no layer."""
    if not left_out:
        return ""
    names = ", ".join(f'{layer.name} (fingers = "{layer.fingers}": only with {layer.fingers} or '
                      "more fingers down)" for layer in left_out)
    return f"left out of the map: {names}"


def _panels(d, flat: bool):
    """A figure with its two panels (drawing, friction map) and their aspect for a display
    ``d``: one above the other, stretched, for a ``flat`` strip, else side by side."""
    from matplotlib.backends.backend_agg import FigureCanvasAgg
    from matplotlib.figure import Figure

    if flat:  # a strip: the panels one above the other, stretched to a legible height
        fig = Figure(figsize=(13.0, 6.4), dpi=110, layout="constrained")
        left, right = fig.subplots(2, 1)
        stretch = "auto"
    else:  # a display far taller than wide would ask for a figure metres high
        aspect = min(d.height_mm / d.width_mm, 4.0)
        fig = Figure(figsize=(13.0, 13.0 * aspect / 2 + 1.6), dpi=110, layout="constrained")
        left, right = fig.subplots(1, 2)
        stretch = None
    FigureCanvasAgg(fig)
    return fig, left, right, stretch


def _hatch_below(ax, below: np.ndarray, d, viewport, left_out) -> None:
    """Hatch and outline in red the pixels ``below`` the floor on the friction map ``ax``,
    and title it with their share and the layers ``left_out`` of it."""
    if below.any():
        xs = (np.arange(viewport.width_px) + 0.5) * d.width_mm / viewport.width_px
        ys = (np.arange(viewport.height_px) + 0.5) * d.height_mm / viewport.height_px
        ax.contourf(xs, ys, below.astype(np.float64), levels=[0.5, 1.5], colors="none",
                    hatches=["////"])
        ax.contour(xs, ys, below.astype(np.float64), levels=[0.5], colors="red",
                   linewidths=0.8)
    # one short line each: a long one ran under the colour bar beside the panel
    lines = ["target mu' of a finger touching alone (1 = plate at rest)"]
    if below.any():
        lines.append(f"hatched: below the floor ({below.mean():.1%} of the display)")
    lines += textwrap.wrap(escape(left_out_note(left_out), limit=None), len(lines[0]))
    ax.set_title("\n".join(lines), fontsize=10)


def _floor_bar(fig, shown, ax, flat: bool, floor: float, force: float, vmin: float) -> None:
    """The colour bar of the friction map ``ax``, with the device's ``floor`` (mu') at
    ``force`` (N) as a red line and a red tick of its own."""
    # a flat strip's bar lies under it: one standing beside it would be shorter than its label
    bar = fig.colorbar(shown, ax=ax, shrink=0.9,
                       location="bottom" if flat else "right")
    bar.set_label(f"mu' = mu(w) / mu(0); red: the device's floor at {force:g} N")
    (bar.ax.axvline if flat else bar.ax.axhline)(floor, color="red", linewidth=2)
    # the floor is a tick of its own; a tick next to it would print over its label
    room = (0.2 if flat else 0.08) * (1.0 - vmin)
    ticks = sorted([t for t in bar.get_ticks() if vmin <= t <= 1.0 and abs(t - floor) > room]
                   + [floor])
    bar.set_ticks(ticks, labels=[f"floor {t:.2f}" if t == floor else f"{t:g}" for t in ticks])
    for label in (bar.ax.get_xticklabels() if flat else bar.ax.get_yticklabels()):
        if label.get_text().startswith("floor"):
            label.set_color("red")


def _captions(fig, scene) -> tuple[list[str], list[str]]:
    """Title ``fig`` with the scene's layers and caption it with what a finger will not
    feel and how layers render (``rendering.perception``); return those two lists of
    messages."""
    layers = "; ".join(_layer_note(layer, scene.display) for layer in scene.layers)
    fig.suptitle("\n".join(textwrap.wrap(f"layers: {layers}", 150)), fontsize=9)
    findings = scene_findings(scene)
    felt = [f.message for f in findings if f.kind not in RENDERING_KINDS]
    rendering = [f.message for f in findings if f.kind in RENDERING_KINDS]
    lines = []  # under the panels (frictex validate --perception)
    if felt:
        lines += textwrap.wrap("a finger will not feel: " + "; ".join(felt), 170)
    if rendering:
        lines += textwrap.wrap("rendering: " + "; ".join(rendering), 170)
    if lines:
        fig.supxlabel("\n".join(lines), fontsize=8, color="darkorange" if felt else "dimgrey")
    return felt, rendering


def write_preview(scene, out: Path, size: tuple[int, int] | None = None,
                  outlines: bool = False, image: np.ndarray | None = None) -> dict:
    """Render the preview figure of ``scene`` into ``out`` (panels computed at ``size``,
    ``image``: as :func:`preview_figure`'s); return what it shows (mu' range, floor,
    share below the floor, panel size, ``figure``: the PNG's size in px).

    Room-checked (4 bytes per pixel of the figure) and written under a temporary name
    (``app.engine.outfile``): a full disk leaves no truncated or empty PNG, and an earlier
    file of that name stays."""
    fig, info = preview_figure(scene, size, outlines, image)
    width, height = fig.get_size_inches() * fig.dpi
    write_file(out, lambda to: fig.savefig(to, format="png"), width * height * 4)
    info["figure"] = fig.canvas.get_width_height()
    return info


def write_scene_image(image: np.ndarray, out: Path) -> None:
    """Write ``image`` (sRGB uint8, rows x columns x 3) as the PNG ``out``, pixel for pixel
    (room-checked and written whole, as :func:`write_preview`)."""
    from PIL import Image
    write_file(out, lambda to: Image.fromarray(image).save(to, format="PNG"), image.size * 4 / 3 * 4)


def why_this_size(d, drawn: tuple[int, int], asked: tuple[int, int] | None) -> str:
    """Why the scene image of display ``d`` is ``drawn`` (w, h px) big, ``asked``: --size
    (None: the display's pixels, scaled down to MAX_PANEL_PX a side)."""
    if drawn == (d.width_px, d.height_px):
        return "the display's pixels"
    fitted_in = asked or default_size(d, MAX_PANEL_PX)
    reasons = [f"the display has {d.width_px} x {d.height_px} px"]
    if asked:
        reasons.append(f"fitted in --size {asked[0]}x{asked[1]} keeping the mm aspect")
    elif fitted_in != (d.width_px, d.height_px):
        reasons.append(f"scaled down to at most {MAX_PANEL_PX} px a side")
    if not asked and drawn != fitted_in:
        reasons.append(f"fitted keeping the mm aspect ({d.width_mm:g} x {d.height_mm:g} mm): "
                       "its pixels are not square")
    return "; ".join(reasons)


def scene_out_path(out: Path) -> Path:
    """The scene image's default name: ``out``'s with ``-scene`` before the suffix."""
    return out.with_name(f"{out.stem}-scene{out.suffix}")


def _png_path(out: Path, option: str) -> Path:
    """``out`` checked: a .png name in a folder that exists."""
    if out.suffix.lower() != ".png":
        raise InputError(f"{option} {str(out)!r}: expected a .png file name")
    if not out.parent.is_dir():
        state = "exists but is not a folder" if out.parent.exists() else "does not exist"
        raise InputError(f"output folder {str(out.parent)!r} {state}")
    return out


def run(args: argparse.Namespace) -> int:
    out = _png_path(Path(args.out), "output")
    scene_out = _png_path(Path(args.scene_out) if args.scene_out else scene_out_path(out),
                          "--scene-out")
    if scene_out.resolve() == out.resolve():
        raise InputError(f"--scene-out {str(scene_out)!r} is the figure's file (-o); "
                         "expected another name")
    scene = load(args.scene)
    d = scene.display
    size = args.size or default_size(d, MAX_PANEL_PX)
    image = scene_image(scene, size, args.outlines)
    info = write_preview(scene, out, outlines=args.outlines, image=image)
    write_scene_image(image, scene_out)
    print(f"wrote {escape_path(out)}: {escape(scene.name, limit=None)} beside its friction map, "
          f"a {info['figure'][0]} x {info['figure'][1]} px figure (the scene scaled to fit), "
          f"mu' of a finger touching alone {info['mu_min']:.3f} to {info['mu_max']:.3f} "
          f"(device floor {info['floor']:.3f} "
          f"at {scene.device.normal_force_n:g} N"
          + (f"; {info['below']:.1%} of the display below it, hatched)" if info["below"] else ")")
          + (f"; {printable(info['left_out'])}" if info["left_out"] else ""))
    h, w = image.shape[:2]
    print(f"wrote {escape_path(scene_out)}: the scene as the demo's window draws it, {w} x {h} px, "
          f"{w / d.width_mm:.4g} px/mm along x, {h / d.height_mm:.4g} along y ("
          + why_this_size(d, (w, h), args.size) + ")")
    for message in info["forces"]:
        print(f"force layer {printable(message)}")
    for message in info["perception"]:
        print(f"perception: {printable(message)}")
    for message in info["rendering"]:
        print(f"rendering: {printable(message)}")
    return 0
