"""Window backends by name: :data:`WINDOWS`, a registry of ``entry(size, **options)``
opening a ``rendering.visual.context.Frame`` (the demo's are a ``Window`` too).

Built in: ``egl`` (an offscreen framebuffer), ``glfw`` (a window on a display) and
``headless`` (the glfw window's contract without a display, input injected:
``rendering.visual.headless``). Other packages add theirs through the entry-point
group ``frictex.windows``.
"""

from __future__ import annotations

from collections.abc import Callable

from frictex.device.registry import Registry
from frictex.rendering.visual.context import Frame, GlfwBackend, OffscreenBackend
from frictex.rendering.visual.headless import HeadlessWindow

WINDOWS: Registry[Callable[..., Frame]] = Registry("window backend", "frictex.windows")
WINDOWS.register("egl", OffscreenBackend)
WINDOWS.register("glfw", GlfwBackend)
WINDOWS.register("headless", HeadlessWindow)


def open_backend(name: str, size: tuple[int, int], **options) -> Frame:
    """The backend called ``name`` (an unknown name is an error listing the known
    ones), opened at ``size`` (width, height) px."""
    return WINDOWS.get(name)(size, **options)
