"""The fast static image against brute force: exact pixel means of periodic layers,
boundary supersampling, sRGB encoding by table. References are computed here by dense
point sampling of the model's own ``profile`` / ``covers`` / ``mu_at``."""

from dataclasses import replace

import numpy as np
import pytest
from numpy.testing import assert_allclose

from frictex.rendering.visual.scene_image import (_srgb_formula, composed_rgb, periodic_mean, scene_rgb,
                                          to_srgb8)
from frictex.rendering.visual.viewport import fit_viewport
from scenes import DISPLAY
from frictex.textures.library import resolve_scene
from frictex.textures.loader import load_scene
from frictex.device.profile import DeviceProfile
from frictex.textures.heights import GaussianBump, HeightLayer, Step
from frictex.textures.model import (DiscRegion, Display, Grating, RectRegion, Scene, VisualHints,
                                    Waveform)


def dense_mean(layer, x, y, cell, n=300):
    """Mean of ``layer.mu_at`` over an n x n grid of points inside each cell."""
    off = (np.arange(n) + 0.5) / n - 0.5
    px = x[:, None, None] + off[None, None, :] * cell[0]
    py = y[:, None, None] + off[None, :, None] * cell[1]
    return layer.mu_at(px, py).mean(axis=(1, 2))


@pytest.mark.parametrize("layer", [
    Grating(name="g", render="sho", region=None, blend="multiply", visual=VisualHints(),
            period_mm=0.6, angle_deg=30.0, offset_mm=0.1, duty=0.3),
    Waveform(name="w", render="sht", region=None, blend="multiply", visual=VisualHints(),
             period_mm=0.8, angle_deg=-70.0, shape="sawtooth"),
    Waveform(name="s", render="sht", region=None, blend="multiply", visual=VisualHints(),
             period_mm=2.0, angle_deg=90.0, shape="samples", samples=(1.0, 0.6, 0.9, 0.7)),
])
def test_periodic_pixel_mean_is_the_exact_area_average(layer):
    rng = np.random.default_rng(7)
    x, y = rng.uniform(0, 50, 60), rng.uniform(0, 50, 60)
    cell = (0.135, 0.135)  # one pixel at 7.4 px/mm
    # dense sampling is exact to about 1/300 of the cell at each of the few edges inside
    assert_allclose(periodic_mean(layer, x, y, cell), dense_mean(layer, x, y, cell), atol=4e-3)


def brute_force(scene, vp, n=16):
    """Scene image by n x n point samples per pixel (no analytic filtering at all)."""
    sx, sy = vp.px_per_mm
    off = (np.arange(n) + 0.5) / n
    acc = np.zeros((vp.height_px, vp.width_px, 3))
    for oy in off:
        y = ((np.arange(vp.height_px) + oy) / sy)[:, None]
        for ox in off:
            x = ((np.arange(vp.width_px) + ox) / sx)[None, :]
            acc += composed_rgb(scene, *np.broadcast_arrays(x, y))
    return acc / n ** 2


def two_gratings() -> Scene:
    coarse = Grating(name="coarse", render="sho", region=None, blend="multiply",
                     visual=VisualHints((0.3, 0.3, 0.3), (1.0, 1.0, 1.0)), period_mm=5.0)
    fine = Grating(name="fine", render="sht", region=DiscRegion(30.0, 20.0, 12.0),
                   blend="replace", visual=VisualHints((0.0, 0.2, 0.6), (1.0, 1.0, 1.0)),
                   period_mm=0.6, angle_deg=30.0)
    return Scene(1, "two", "", Display(60.0, 40.0, 240, 160), DeviceProfile(), (coarse, fine))


def height_steps() -> Scene:
    """Heights whose relief jumps inside a pixel (at 4 px/mm): a step's chamfer edges (its
    slope jumps there), a chamfer and a bump narrower than two pixels, a region's rim;
    the steps face away from the light (the relief's darkest), so a jump left to a
    pixel's centre is off by up to 0.3."""
    def height(name, shape, region):
        return HeightLayer(name=name, render="sho", region=region, blend="replace",
                           visual=VisualHints((0.0, 0.0, 0.0), (1.0, 1.0, 1.0)), shape=shape)
    return Scene(1, "steps", "", Display(60.0, 40.0, 240, 160), DeviceProfile(), (
        height("wide", Step(15.0, 20.0, 225.0, 0.5, 3.0), RectRegion(0.0, 0.0, 30.0, 40.0)),
        height("narrow", Step(45.0, 20.0, 225.0, 0.3, 0.1), DiscRegion(45.0, 20.0, 12.0)),
        height("dot", GaussianBump(12.0, 30.0, 0.2, 0.3), DiscRegion(12.0, 30.0, 3.0))))


@pytest.mark.parametrize("scene", [two_gratings(), height_steps(), "objects-bump-edge-disc",
                                   "composed-fine-grating-in-disc", "raster-map",
                                   "keyclick-ring", "height-bump", "height-button",
                                   "height-ridge", "slider-clips"],
                         ids=lambda s: s if isinstance(s, str) else s.name)
def test_fast_image_matches_brute_force_supersampling(scene):
    """Linear RGB within 0.004 on average of 256 point samples per pixel; at most 0.13 on
    a pixel crossed by a boundary (4 x 4 sub-pixels there: up to 1/16 of the colour step,
    and as much for the reference), where a boundary pixel left unsupersampled, or a
    periodic layer's mean off by a fraction of its period, would be off by up to 0.5.
    (Outlines are drawn over the image afterwards: left out here.)"""
    if isinstance(scene, str):
        scene = load_scene(resolve_scene(scene))
    scene = replace(scene, layers=tuple(replace(layer, visual=replace(layer.visual, outline=False))
                                        for layer in scene.layers))
    vp = fit_viewport(scene.display, 240, 160)
    fast = scene_rgb(scene, vp)
    slow = brute_force(scene, vp)
    err = np.abs(fast - slow)
    assert err.max() < 0.13, np.unravel_index(err.argmax(), err.shape)
    assert err.mean() < 0.004


def test_two_periodic_layers_share_pixels_without_error():
    """Where the coarse grating's edge crosses the fine one, the product of their means is
    not the mean of their product: those pixels must be supersampled, not tabulated (away
    from the disc's boundary the only error left is the reference's, 1/16 of a step)."""
    scene = two_gratings()
    vp = fit_viewport(scene.display, 240, 160)
    fine = scene.layers[1]
    one = Scene(1, "one", "", scene.display, scene.device, (fine,))
    inside = np.zeros((vp.height_px, vp.width_px), bool)  # pixels well inside the disc
    yy, xx = np.mgrid[0:vp.height_px, 0:vp.width_px] + 0.5
    inside[np.hypot(xx / 4 - 30, yy / 4 - 20) < 11] = True
    for s in (scene, one):
        err = np.abs(scene_rgb(s, vp) - brute_force(s, vp))[inside]
        assert err.max() < 0.065, s.name


def test_srgb_table_encoding_equals_the_transfer_formula():
    rng = np.random.default_rng(3)
    values = np.concatenate((rng.random(200_000), np.linspace(0, 1, 70_001), [0.0, 1.0, -0.2, 1.3]))
    assert (to_srgb8(values) == _srgb_formula(np.clip(values, 0, 1))).all()


def test_letterboxed_fullscreen_grating_keeps_its_period():
    """At 1920x1080 (letterboxed 1800x1080) a 0.6 mm grating still has its period: the
    table resolution follows the pixel size."""
    layer = Grating(name="g", render="sht", region=None, blend="multiply", visual=VisualHints(),
                    period_mm=0.6)
    scene = Scene(1, "g", "", DISPLAY, DeviceProfile(), (layer,))
    vp = fit_viewport(DISPLAY, 1920, 1080)
    row = scene_rgb(scene, vp)[500, :, 0].astype(np.float64)
    expect = dense_mean(layer, (np.arange(vp.width_px) + 0.5) / vp.px_per_mm[0],
                        np.full(vp.width_px, 10.0), (1 / vp.px_per_mm[0], 1 / vp.px_per_mm[1]), 64)
    assert_allclose(row, 0.0 + (expect - 0.6) / 0.4, atol=2e-3)


# -- force layers' marks (rendering.visual.force_marks) ----------------------------------

def _marks(scene, size=(1400, 300)):
    """(mask of pixels mostly in the mark colour, viewport) of ``scene`` drawn at ``size``."""
    from frictex.rendering.visual.force_marks import MARK_RGB
    vp = fit_viewport(scene.display, *size)
    rgb = scene_rgb(scene, vp)
    return np.linalg.norm(rgb - MARK_RGB, axis=-1) < 0.1, vp


def test_guidance_line_is_drawn_where_the_pull_points():
    scene = load_scene(resolve_scene("guidance-ring"))
    mask, vp = _marks(scene)
    cols = np.nonzero(mask)[1]
    target_px = vp.to_px(70.0, 0.0)[0] - vp.x0
    assert cols.size > 100 and abs(cols.mean() + 0.5 - target_px) < 1.0
    # and the pull of the layer itself is zero on that line, away from it on either side
    layer = next(layer for layer in scene.layers if layer.name == "centre-line")
    fx, _ = layer.pull(np.array([60.0, 70.0, 80.0]), np.array([15.0, 15.0, 15.0]))
    assert fx[0] > 0 and fx[1] == 0 and fx[2] < 0
    # a target point: a ring of RING_MM around it
    from frictex.rendering.visual.force_marks import RING_MM
    point = replace(layer, line=False, x_mm=40.0, y_mm=12.0)
    mask, vp = _marks(replace(scene, layers=(scene.layers[0], point)))
    rows, cols = np.nonzero(mask)
    x_mm, y_mm = vp.to_mm(cols + 0.5 + vp.x0, rows + 0.5 + vp.y0)
    r = np.hypot(x_mm - 40.0, y_mm - 12.0)
    ring = r > 1.0
    assert abs(np.median(r[ring]) - RING_MM) < 0.5 / min(vp.px_per_mm)
    assert abs(x_mm.mean() - 40.0) < 0.1 and abs(y_mm.mean() - 12.0) < 0.1


@pytest.mark.parametrize("forward, backward, glide", [(0.03, 0.2, 1), (0.2, 0.03, -1)])
def test_directional_chevrons_point_the_way_the_finger_glides(forward, backward, glide):
    from frictex.rendering.visual.force_marks import CHEVRON_MM
    scene = load_scene(resolve_scene("directional-ring"))
    layer = replace(scene.layers[0], forward=forward, backward=backward)
    mask, vp = _marks(replace(scene, layers=(layer,)))
    rows, cols = np.nonzero(mask)
    x_mm, y_mm = vp.to_mm(cols + 0.5 + vp.x0, rows + 0.5 + vp.y0)
    middle = 15.0
    tips = x_mm[np.abs(y_mm - middle) < 0.3]
    arms = x_mm[np.abs(np.abs(y_mm - middle) - 0.75 * CHEVRON_MM) < 0.3]
    # the tip of the chevron near x = 60 mm, and its arms behind it (against the glide)
    tip = tips[np.abs(tips - 60.0) < 3.0].mean()
    arm = arms[np.abs(arms - 60.0) < 5.0].mean()
    assert abs(tip - 60.0) < 0.5
    assert np.sign(tip - arm) == glide and abs(abs(tip - arm) - 0.75 * CHEVRON_MM) < 0.5
    same = replace(layer, forward=0.1, backward=0.1)
    assert not _marks(replace(scene, layers=(same,)))[0].any()
