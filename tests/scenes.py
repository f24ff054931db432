"""Scenes built in code for the core tests (independent of the texture-file loader), a
texture file's text, and how a grating's period is measured in a picture."""

import numpy as np

from frictex.device.profile import DeviceProfile

from frictex.textures.model import Display, DiscRegion, Grating, Scene, Shape, VisualHints

DISPLAY = Display(108.0, 64.8, 800, 480)


def grating_box_mean(layer: Grating, a, b) -> np.ndarray:
    """mu' a square ``layer`` plays over phase [a, b] (cycles): its mean there, the part of
    the interval inside low bands found exactly; where b == a (at rest) its value at b
    (``rendering.layers.band_limit``)."""
    a, b = np.asarray(a, dtype=np.float64), np.asarray(b, dtype=np.float64)
    low = lambda p: np.floor(p) * layer.duty + np.minimum(p - np.floor(p), layer.duty)
    with np.errstate(invalid="ignore", divide="ignore"):
        share = (low(b) - low(a)) / (b - a)
    mean = layer.mu_high + (layer.mu_low - layer.mu_high) * share
    return np.where(b == a, layer.profile(b), mean)


def _on_level(mu: np.ndarray, low: float, high: float) -> np.ndarray:
    return np.isclose(mu, low, rtol=0, atol=1e-9) | np.isclose(mu, high, rtol=0, atol=1e-9)


def grating_edges(mu: np.ndarray, low: float = 0.6, high: float = 1.0) -> int:
    """The changes from one level of a grating to the other in ``mu``, the samples between
    the two levels left out."""
    return int(np.count_nonzero(np.diff(np.round(mu[_on_level(mu, low, high)], 6))))


def straddling_samples(mu: np.ndarray, low: float = 0.6, high: float = 1.0) -> int:
    """The samples of ``mu`` off a grating's two levels, after checking that each lies
    between a sample of one level and one of the other: at an edge crossed within it,
    played as the mean of both sides (``rendering.layers.band_limit``)."""
    off = np.flatnonzero(~_on_level(mu, low, high))
    off = off[(off > 0) & (off < mu.size - 1)]
    assert np.all((mu[off] > low) & (mu[off] < high))
    assert np.allclose(np.abs(mu[off - 1] - mu[off + 1]), high - low, rtol=0, atol=1e-9)
    return off.size


def grating_scene(period_mm: float, render: str = "sho", mu_low: float = 0.6,
                  device: DeviceProfile | None = None) -> Scene:
    layer = Grating(name="lines", render=render, region=None, blend="multiply",
                    visual=VisualHints(), period_mm=period_mm, duty=0.5, mu_low=mu_low,
                    mu_high=1.0)
    return Scene(1, f"grating-{period_mm}mm", "", DISPLAY, device or DeviceProfile(), (layer,))


def disc_scene() -> Scene:
    disc = Shape(name="disc", render="sho", region=None, blend="multiply", visual=VisualHints(),
                 geometry=DiscRegion(54.0, 32.4, 15.0), mu=0.7)
    return Scene(1, "disc", "", DISPLAY, DeviceProfile(), (disc,))


#: a texture file: a 4 mm grating on a 120 x 80 mm display of 1200 x 800 px (10 px/mm)
GRATING_4MM = """format = 1
name = "grating-4mm-v"
[display]
width_mm = 120.0
height_mm = 80.0
width_px = 1200
height_px = 800

[[layer]]
type = "grating"
period_mm = 4.0
angle_deg = 0.0
offset_mm = 1.0
duty = 0.25
mu_low = 0.7
"""


def rising_edge_period(row: np.ndarray) -> float:
    """Mean spacing (px) of the dark-to-light crossings of the row's mid level."""
    light = row > (row.min() + row.max()) / 2
    rises = np.flatnonzero(light[1:] & ~light[:-1])
    assert rises.size >= 5
    return (rises[-1] - rises[0]) / (rises.size - 1)
