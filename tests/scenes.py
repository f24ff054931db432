"""Scenes built in code for the core tests (independent of the texture-file loader)."""

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
