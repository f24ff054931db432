"""Scenes built in code for the core tests (independent of the texture-file loader), a
texture file's text, and how a grating's period is measured in a picture."""

import numpy as np

from frictex.device.profile import DeviceProfile

from frictex.textures.model import Display, DiscRegion, Grating, Scene, Shape, VisualHints

DISPLAY = Display(108.0, 64.8, 800, 480)


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
