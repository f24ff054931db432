"""A window without a display: the glfw window's contract on an offscreen EGL framebuffer,
with its input injected by the caller.

:class:`HeadlessWindow` is what ``app.live.demo_loop.DemoLoop`` drives in place of the
glfw window (``rendering.visual.context.Window``), so that the demo loop itself runs
where no display exists (tests without Xvfb, ``frictex demo --headless``). Events are
the caller's: :meth:`move`, :meth:`press`, :meth:`release`, :meth:`scroll`,
:meth:`key` and :meth:`close_window` queue them from any thread, and
:meth:`wait_events`, on the loop's input thread, hands them to the callbacks in order,
as glfw's event handling does. Cursor positions are framebuffer pixels as floats, key
names as the glfw backend gives them ("space", "q", ...).

The EGL context moves between threads as the glfw one does (``make_current`` on the
render thread, ``release_context`` where it was): EGL's ``eglMakeCurrent`` through
ctypes, on the display and context moderngl created. ``swap`` hands each finished
frame to ``on_frame`` (the frame as ``read_rgb`` gives it), e.g. to save it as a PNG.
"""

from __future__ import annotations

import ctypes
import queue
from collections.abc import Callable

import moderngl
import numpy as np

from frictex.rendering.visual.context import OffscreenBackend, VisualError

_EGL_DRAW, _EGL_READ = 0x3059, 0x305A  # eglGetCurrentSurface's readdraw


def _egl():
    """libEGL with the few functions used here typed (handles are pointers)."""
    try:
        lib = ctypes.CDLL("libEGL.so.1")
    except OSError as exc:
        raise VisualError(f"cannot load libEGL.so.1 ({exc}); install Mesa's EGL "
                          "(Debian: libegl1 libegl-mesa0)") from None
    for name in ("eglGetCurrentDisplay", "eglGetCurrentContext", "eglGetCurrentSurface"):
        getattr(lib, name).restype = ctypes.c_void_p
    lib.eglGetCurrentSurface.argtypes = [ctypes.c_int]
    lib.eglMakeCurrent.argtypes = [ctypes.c_void_p] * 4
    lib.eglMakeCurrent.restype = ctypes.c_uint
    lib.eglGetError.restype = ctypes.c_int
    return lib


class HeadlessWindow(OffscreenBackend):
    """The glfw window's interface (see the module docstring) on an EGL framebuffer of
    ``size`` = (width, height) px.

    Parameters
    ----------
    size : (width, height) px.
    on_frame : called with each frame ``swap`` shows ((height, width, 3) uint8, row 0
        at the top), on the thread that swaps; None: frames are not kept.
    ctx : an EGL context to draw with (current on this thread), or None to make one.
    title, monitor, vsync : the glfw backend's options, taken and ignored (there is no
        screen), so that callers open either the same way.
    fullscreen : kept as ``fullscreen``: the frame stands for a whole screen of ``size``
        (the demo then lays it out as on the glass, ``viewport.on_glass``).
    """

    name = "headless"

    def __init__(self, size: tuple[int, int], on_frame: Callable[[np.ndarray], None] | None = None,
                 ctx: moderngl.Context | None = None, title: str = "frictex",
                 fullscreen: bool = False, monitor: int = 0, vsync: bool = False):
        super().__init__(size, ctx=ctx)
        self.title = title
        self.fullscreen = fullscreen
        self.on_frame = on_frame
        self.on_cursor = self.on_button = self.on_scroll = self.on_key = None
        self.should_close = False
        self.frames = 0
        self._cursor = (0.0, 0.0)
        self._inbox: queue.SimpleQueue = queue.SimpleQueue()
        self._lib = _egl()
        self._display = self._lib.eglGetCurrentDisplay()
        self._context = self._lib.eglGetCurrentContext()
        self._surfaces = (self._lib.eglGetCurrentSurface(_EGL_DRAW),
                          self._lib.eglGetCurrentSurface(_EGL_READ))
        if not self._display or not self._context:
            raise VisualError("the offscreen OpenGL context is not an EGL context current here")

    # -- input, injected (any thread) ------------------------------------------------------

    def move(self, x_px: float, y_px: float) -> None:
        """The pointer moves to (x_px, y_px), framebuffer pixels."""
        self._inbox.put(("cursor", float(x_px), float(y_px)))

    def press(self) -> None:
        """The left button goes down."""
        self._inbox.put(("button", True))

    def release(self) -> None:
        """The left button comes up."""
        self._inbox.put(("button", False))

    def scroll(self, dy: float) -> None:
        """The wheel turns by ``dy`` steps."""
        self._inbox.put(("scroll", float(dy)))

    def key(self, name: str, shift: bool = False) -> None:
        """Key ``name`` (as the glfw backend names keys) is pressed."""
        self._inbox.put(("key", name, bool(shift)))

    def close_window(self) -> None:
        """As closing a window: ``should_close`` becomes True once handled."""
        self._inbox.put(("close",))

    def wake(self) -> None:
        """End a ``wait_events`` in progress (from any thread)."""
        self._inbox.put(("wake",))

    def set_title(self, title: str) -> None:
        """The title a window would show (kept in ``title``; from any thread)."""
        self.title = title

    # -- the window's side -----------------------------------------------------------------

    def wait_events(self, timeout_s: float) -> None:
        """Handle the injected events, waiting for one at most ``timeout_s`` s (0: only
        those already there): each goes to its callback, in order, on this thread."""
        try:
            event = self._inbox.get(timeout=timeout_s) if timeout_s > 0.0 else self._inbox.get_nowait()
        except queue.Empty:
            return
        while True:
            self._handle(*event)
            try:
                event = self._inbox.get_nowait()
            except queue.Empty:
                return

    def _handle(self, kind: str, *args) -> None:
        if kind == "cursor":
            self._cursor = args
            if self.on_cursor:
                self.on_cursor(*args)
        elif kind == "button" and self.on_button:
            self.on_button(*args)
        elif kind == "scroll" and self.on_scroll:
            self.on_scroll(*args)
        elif kind == "key" and self.on_key:
            self.on_key(*args)
        elif kind == "close":
            self.should_close = True

    def cursor_px(self) -> tuple[float, float]:
        return self._cursor

    def swap(self) -> None:
        """The frame drawn is shown: handed to ``on_frame``."""
        self.frames += 1
        if self.on_frame is not None:
            self.on_frame(self.read_rgb())

    def make_current(self) -> None:
        """Make the EGL context current on the calling thread."""
        self._make_current(self._surfaces[0], self._surfaces[1], self._context)

    def release_context(self) -> None:
        """Detach the EGL context from the calling thread (another may take it)."""
        self._make_current(None, None, None)

    def _make_current(self, draw, read, context) -> None:
        if not self._lib.eglMakeCurrent(self._display, draw, read, context):
            raise VisualError(f"eglMakeCurrent failed (EGL error 0x{self._lib.eglGetError():04x})")
