"""OpenGL contexts to draw into, as interchangeable backends picked by name.

- ``egl``: offscreen, no display needed (moderngl standalone context on EGL, Mesa's
  llvmpipe in CI); draws into a framebuffer of any pixel size.
- ``glfw``: a window (windowed or fullscreen on a chosen monitor) whose input
  (cursor, buttons, wheel, keys) is forwarded to callbacks as backend-neutral values:
  cursor positions in framebuffer pixels as floats (never truncated), key names as
  lower-case strings ("space", "n", "up", ...; held Control prefixes "ctrl+": "ctrl+z").
- ``headless``: the glfw window's contract without a display: an EGL framebuffer whose
  input the caller injects (``rendering.visual.headless``).

Every backend is a :class:`Frame` (``ctx``, ``size``, ``use()``, ``read_rgb()``,
``close()``); ``glfw`` and ``headless`` are also a :class:`Window`, what the demo loop
drives (``app.live.demo_loop``). They are registered by name in
``rendering.visual.windows.WINDOWS``.
"""

from __future__ import annotations

import os
from collections.abc import Callable
from typing import Protocol, runtime_checkable

import moderngl
import numpy as np

from frictex.device.errors import FrictexError, InputError


def fit_size(size: tuple[int, int], room: tuple[int, int]) -> tuple[int, int]:
    """``size`` (w, h px) cut to ``room`` (w, h px) side by side, at least 1 px each."""
    return (max(1, min(int(size[0]), int(room[0]))), max(1, min(int(size[1]), int(room[1]))))


@runtime_checkable
class Frame(Protocol):
    """Something to draw into: a moderngl context ``ctx`` and ``size`` (width, height) px."""

    ctx: moderngl.Context
    size: tuple[int, int]

    def use(self) -> None:
        """Draw into this frame from now on (its framebuffer and viewport)."""

    def read_rgb(self) -> np.ndarray:
        """The frame as sRGB uint8 (height, width, 3), row 0 at the top."""

    def close(self) -> None:
        """Release the frame (and its context if it made it)."""


@runtime_checkable
class Window(Frame, Protocol):
    """A frame with input, as the demo loop drives it (``GlfwBackend`` documents each).

    Callbacks (attributes, None or callables): ``on_cursor(x_px, y_px)`` (framebuffer
    pixels, floats), ``on_button(pressed)`` (left button), ``on_scroll(dy)``,
    ``on_key(name, shift)``; called on the thread running :meth:`wait_events`.
    """

    on_cursor: Callable | None
    on_button: Callable | None
    on_scroll: Callable | None
    on_key: Callable | None
    should_close: bool

    def cursor_px(self) -> tuple[float, float]:
        """Where the pointer is now (framebuffer px)."""

    def wait_events(self, timeout_s: float) -> None:
        """Handle the pending events, waiting for one at most ``timeout_s`` s."""

    def swap(self) -> None:
        """Show the frame drawn."""

    def make_current(self) -> None:
        """Make the GL context current on the calling thread."""

    def release_context(self) -> None:
        """Detach the GL context from the calling thread."""

    def wake(self) -> None:
        """End a ``wait_events`` in progress (from any thread)."""

    def set_title(self, title: str) -> None:
        """Show ``title`` in the window's title bar (from any thread)."""


class VisualError(FrictexError, OSError):
    """The visual layer cannot run here (no display, no GL); the message says what is missing."""


class NoDisplayError(VisualError):
    """No display to open a window on."""


def _read(fbo, size) -> np.ndarray:
    """The (h, w, 3) uint8 pixels of ``fbo``'s lower-left ``size`` = (w, h), top row first.
    The area is given: a window's default framebuffer keeps the viewport it was made with
    (moderngl), so after a resize it read the old size's pixels."""
    w, h = size
    data = np.frombuffer(fbo.read(viewport=(0, 0, w, h), components=3, alignment=1),
                         dtype=np.uint8)
    return data.reshape(h, w, 3)[::-1].copy()


class OffscreenBackend:
    """An EGL context and a framebuffer of ``size`` = (width, height) px."""

    name = "egl"

    def __init__(self, size: tuple[int, int], ctx: moderngl.Context | None = None):
        try:
            self.ctx = ctx or moderngl.create_standalone_context(backend="egl")
        except Exception as exc:  # moderngl raises bare Exception when EGL is absent
            raise VisualError(f"cannot create an offscreen OpenGL context with EGL ({exc}); "
                              "install Mesa's EGL (Debian: libegl1 libegl-mesa0)") from None
        self._owns_ctx = ctx is None
        # framebuffer 0, bound before releasing ours: moderngl rebinds the previous
        # framebuffer when it creates one, which fails if that one was released
        self._default = self.ctx.detect_framebuffer(0)
        self.size = (0, 0)
        self.fbo = None
        self.resize(size)

    def resize(self, size: tuple[int, int]) -> None:
        w, h = int(size[0]), int(size[1])
        if w < 1 or h < 1:
            raise InputError(f"frame size {w}x{h} px: expected at least 1x1")
        if self.fbo is not None:
            self._default.use()
            self.fbo.release()
        self.size = (w, h)
        self.fbo = self.ctx.simple_framebuffer((w, h), components=4)

    def use(self) -> None:
        self.fbo.use()

    def read_rgb(self) -> np.ndarray:
        """The framebuffer as sRGB uint8 (height, width, 3), row 0 at the top."""
        return _read(self.fbo, self.size)

    def close(self) -> None:
        self._default.use()
        self.fbo.release()
        if self._owns_ctx:
            self.ctx.release()


def _key_names(glfw) -> dict[int, str]:
    names = {getattr(glfw, f"KEY_{c}"): c.lower() for c in "ABCDEFGHIJKLMNOPQRSTUVWXYZ0123456789"}
    names.update({glfw.KEY_SPACE: "space", glfw.KEY_ESCAPE: "escape", glfw.KEY_UP: "up",
                  glfw.KEY_DOWN: "down", glfw.KEY_LEFT: "left", glfw.KEY_RIGHT: "right",
                  glfw.KEY_TAB: "tab", glfw.KEY_F12: "f12", glfw.KEY_PAGE_UP: "page_up",
                  glfw.KEY_PAGE_DOWN: "page_down", glfw.KEY_ENTER: "enter",
                  glfw.KEY_KP_ENTER: "enter", glfw.KEY_BACKSPACE: "backspace",
                  glfw.KEY_MINUS: "minus", glfw.KEY_KP_SUBTRACT: "minus"})
    names.update({getattr(glfw, f"KEY_KP_{d}"): str(d) for d in range(10)})
    return names


def display_names() -> str:
    """The displays the environment names, as an error says them: "display ':77'",
    "Wayland display 'wayland-0'", or both joined by "or"."""
    names = [f"{kind}display {os.environ[var]!r}"
             for var, kind in (("WAYLAND_DISPLAY", "Wayland "), ("DISPLAY", ""))
             if os.environ.get(var)]
    return " or ".join(names) or "no display"


class GlfwBackend:
    """A glfw window with an OpenGL 3.3 core context.

    ``vsync``: swap buffers on the display's refresh (then ``swap`` may wait up to a
    refresh period); the demo paces its own frames and leaves it off, so that the
    thread handling input never waits on the display.

    Callbacks (set as attributes, all optional): ``on_cursor(x_px, y_px)``,
    ``on_button(pressed: bool)`` (left button), ``on_scroll(dy)``, ``on_key(name, shift)``.
    Events are handled, and callbacks called, on the thread that created the window
    (``wait_events``); the GL context may be handed to another thread
    (``release_context`` here, ``make_current`` there), which may ``swap``, ``wake``
    the event thread and read ``size`` (kept from the window's resize events).
    """

    name = "glfw"

    def __init__(self, size: tuple[int, int], title: str = "frictex", fullscreen: bool = False,
                 monitor: int = 0, vsync: bool = True):
        import glfw
        self._glfw = glfw
        if not (os.environ.get("DISPLAY") or os.environ.get("WAYLAND_DISPLAY")):
            raise NoDisplayError("no display (DISPLAY and WAYLAND_DISPLAY are unset)")
        glfw.ERROR_REPORTING = "ignore"  # a failure is said once, as the error raised here
        if not glfw.init():
            raise NoDisplayError(f"glfw cannot initialise on {display_names()}")
        monitors = glfw.get_monitors() or []
        target = None
        if fullscreen:
            if not 0 <= monitor < len(monitors):
                glfw.terminate()
                raise VisualError(f"monitor {monitor}: this display has {len(monitors)} "
                                  f"(expected 0..{len(monitors) - 1})")
            target = monitors[monitor]
            mode = glfw.get_video_mode(target)
            size = (mode.size.width, mode.size.height)
        #: the window covers a whole monitor at its video mode's size
        self.fullscreen = target is not None
        #: the size asked for (px); a window is opened within the screen's work area
        self.requested = (int(size[0]), int(size[1]))
        self.work_area: tuple[int, int] | None = None
        if target is None and monitors:
            self.work_area = tuple(int(v) for v in
                                   glfw.get_monitor_workarea(glfw.get_primary_monitor())[2:])
            size = fit_size(self.requested, self.work_area)
        glfw.window_hint(glfw.CONTEXT_VERSION_MAJOR, 3)
        glfw.window_hint(glfw.CONTEXT_VERSION_MINOR, 3)
        glfw.window_hint(glfw.OPENGL_PROFILE, glfw.OPENGL_CORE_PROFILE)
        glfw.window_hint(glfw.OPENGL_FORWARD_COMPAT, True)
        self.window = glfw.create_window(int(size[0]), int(size[1]), title, target, None)
        self._title: str | None = None  # a title set_title asked for, not yet shown
        if not self.window:
            glfw.terminate()
            raise VisualError("glfw could not create an OpenGL 3.3 core window on this display")
        if self.work_area is not None:  # its title bar and borders within the work area too
            left, top, right, bottom = glfw.get_window_frame_size(self.window)
            inner = fit_size(size, (self.work_area[0] - left - right,
                                    self.work_area[1] - top - bottom))
            if inner != tuple(size):
                glfw.set_window_size(self.window, *inner)
        glfw.make_context_current(self.window)
        glfw.swap_interval(1 if vsync else 0)
        self.ctx = moderngl.create_context()
        self.on_cursor = self.on_button = self.on_scroll = self.on_key = None
        self.size = tuple(glfw.get_framebuffer_size(self.window))
        self._keys = _key_names(glfw)
        glfw.set_cursor_pos_callback(self.window, self._cursor)
        glfw.set_mouse_button_callback(self.window, self._button)
        glfw.set_scroll_callback(self.window, self._scroll)
        glfw.set_key_callback(self.window, self._key)
        glfw.set_framebuffer_size_callback(self.window, self._resized)

    def _resized(self, _win, width, height):
        self.size = (int(width), int(height))

    def _scale(self) -> tuple[float, float]:
        fw, fh = self.size
        ww, wh = self._glfw.get_window_size(self.window)
        return (fw / ww if ww else 1.0), (fh / wh if wh else 1.0)

    def _cursor(self, _win, x, y):
        if self.on_cursor:
            sx, sy = self._scale()
            self.on_cursor(float(x) * sx, float(y) * sy)

    def _button(self, _win, button, action, _mods):
        if self.on_button and button == self._glfw.MOUSE_BUTTON_LEFT:
            self.on_button(action == self._glfw.PRESS)

    def _scroll(self, _win, _dx, dy):
        if self.on_scroll:
            self.on_scroll(float(dy))

    def _key(self, _win, key, _scancode, action, mods):
        if self.on_key and action == self._glfw.PRESS and key in self._keys:
            name = self._keys[key]
            if mods & self._glfw.MOD_CONTROL:
                name = "ctrl+" + name
            self.on_key(name, bool(mods & self._glfw.MOD_SHIFT))

    def cursor_px(self) -> tuple[float, float]:
        x, y = self._glfw.get_cursor_pos(self.window)
        sx, sy = self._scale()
        return float(x) * sx, float(y) * sy

    def use(self) -> None:
        self.ctx.screen.use()
        self.ctx.viewport = (0, 0, *self.size)

    def wait_events(self, timeout_s: float) -> None:
        """Handle the window's events, waiting for one at most ``timeout_s`` s (0: only
        those already there). The Python GIL is free while it waits."""
        if timeout_s > 0.0:
            self._glfw.wait_events_timeout(timeout_s)
        else:
            self._glfw.poll_events()
        title, self._title = self._title, None
        if title is not None:
            self._glfw.set_window_title(self.window, title)

    def swap(self) -> None:
        self._glfw.swap_buffers(self.window)

    def make_current(self) -> None:
        """Make the GL context current on the calling thread."""
        self._glfw.make_context_current(self.window)

    def release_context(self) -> None:
        """Detach the GL context from the calling thread (another may take it)."""
        self._glfw.make_context_current(None)

    def wake(self) -> None:
        """End a ``wait_events`` in progress (from any thread)."""
        self._glfw.post_empty_event()

    def set_title(self, title: str) -> None:
        """Show ``title`` in the window's title bar (from any thread: glfw takes it on the
        event thread, at its next ``wait_events``)."""
        self._title = title
        self.wake()

    @property
    def should_close(self) -> bool:
        return bool(self._glfw.window_should_close(self.window))

    def read_rgb(self) -> np.ndarray:
        return _read(self.ctx.screen, self.size)

    def close(self) -> None:
        self.ctx.release()
        self._glfw.destroy_window(self.window)
        self._glfw.terminate()
