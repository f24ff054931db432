"""The demo's window loop (main thread): input -> haptic side, snapshots -> frames.

The haptic side is an ``app.live.haptic_thread.HapticThread`` or an
``app.live.haptic_process.HapticProcess`` (same interface).

Backend-neutral: it drives any ``rendering.visual.context.Window`` (input callbacks,
``wait_events(timeout_s)``, ``wake()``, ``make_current()``, ``release_context()``,
``swap()``, ``should_close``): the glfw window, or without a display the headless one
(``rendering.visual.headless``) with a synthesized hand injecting its input
(``app.live.synthetic``).

Input and drawing run on two threads, so that a slow frame delays drawing, never the
finger. The main thread (where the window's events arrive) only waits for events and
hands the mouse to the haptic side as soon as they are handled; the emergency stop,
quitting and the force act there too. A render thread holds the GL context and draws a
frame every ``FRAME_S`` at most (a late frame is followed by the next at once, not by a
burst); the keys that change what is drawn (scene, renderer, scope, outlines,
screenshot) are queued to it. On Mesa's llvmpipe under load a frame took 100-870 ms;
the input thread waits meanwhile in the window system, without the GIL, and runs as
soon as an event comes. Events handled together (the input thread was held up) keep
their order and path, stamped evenly over the time they arrived in (``flush_mouse``);
a pointer held still while touching is reported still every ``STILL_REPORT_S``. Only
the scene's drawn area touches: a press on the scope strip, a panel column or the
letterbox makes no finger, and a drag that leaves the area lifts where it last was on it.

On the glass (``viewport.on_glass``: fullscreen at the scene's display pixels, or
fullscreen under a touch screen) the scene fills the screen, mm -> px per axis, so that
what is drawn lies where it is felt; the scope starts hidden and S draws it over the
bottom of the scene without moving the scene (whose part under it still touches, as
a touch screen's fingers do there), and the status lines are hidden. A touch screen off
the glass is said once on stderr: its touches are mapped onto the whole panel, the
drawing is not.

Touch input (``--input``): ``mouse``, the mouse is finger 0 (left button held =
touching); ``follow``, the mouse is finger 0 and finger 1 follows it at a fixed offset
along x (seed 001's way of testing two-finger control with one hand); a touch screen
(TUIO, evdev) is read by the haptic side itself (``app.live.touch_pump``), not here:
the mouse then only hovers, and a touch screen that fails is shown and the mouse
takes over. The wheel or up/down set the normal force of every finger. Keys: N / B
next / previous scene (with a link or a recording open, those driving other channels
are skipped: said once on stderr and on screen, :meth:`DemoLoop.step_scene`), R cycles the renderer (as the file says, then each of
``loadable_render_modes()``), S
scope, O outlines, P screenshot (numbered after those already in the folder, never
overwriting one), SPACE emergency stop (latched; SPACE again resumes, ramped), Q /
Escape quit.

L opens (and closes) the layer panel at the left of the frame
(``rendering.visual.layer_panel``, its state ``app.live.layer_edit``): a click on a
layer selects it, a drag on a slider sets a number key, a click on a menu and one of
its options sets a word key, Ctrl+Z (or U) undoes, Ctrl+S (or the panel's button)
saves. The pointer there never touches the scene. A save writes only onto the file
as the panel read it: if it changed on disk since (an editor), the save is refused and
said, and Ctrl+S again overwrites it (``layer_edit.SaveConflict``). A reload of the file
or of one it names keeps the panel's unsaved edits on top of it where they still apply
(``LayerEdit.reread``), and says how many it kept and dropped; so does closing and
opening the panel. Moving to another scene with unsaved edits says they were dropped. The input thread only turns clicks
and drags into panel events queued to the render thread, which applies them once per
frame (a drag's latest position): the edited text is loaded into a scene
(``load_scene(path, text=...)``) and handed to the haptic side as a reload is
(``haptic.switch``, crossfaded in one block), and the next frame draws it. Saving
writes the file back with its untouched lines as they were; a bundled scene is saved
as a copy in the user's scene folder (``layer_edit.save_path``), which the demo
watches and edits from then on.

The scene's texture file and every file it names (raster images, height-map PNGs,
recorded-texture models, AHAP clips, measured mode tables: ``textures.references``)
are polled for changes (``app.live.watch``); a change to any of them reloads the scene
(haptics crossfade in one block), and a bad edit keeps the last good scene and shows
its error on screen and once on stderr (a reload too: "reloaded"); a texture file moved
away or deleted is said to be gone, the last good scene kept.
Events are appended to ``events.csv`` (t_s on the haptic clock, event, detail) when a
record folder is given: what the window did when it did it (keys: ``estop``,
``estop-release``, ``scope``, ``outlines``, ``force`` with the normal force set by the
wheel or up/down; scene loads, screenshots and screenshots that failed), and what the
output did when it did it, at the output time of the first block it shaped
(``output-stop``, ``output-resume``, ``output-switch``, ``finger-down``, ``finger-up``;
read from the haptic side's snapshots; a finger touching when the demo ends gets its
``finger-up`` at the last output drawn), and what the device link did, at the output time
of the snapshot whose status first shows it (``link-lost`` with the port's error,
``link-back``, ``link-stalled`` when queued blocks have not moved for over 0.5 s,
``link-moving``: ``app.live.link_watch``); while the link is lost or stalled the window
shows it in a red banner, and a stall and its end are said on stderr. The rows of
events.csv are put in time order when the demo closes (:func:`sort_events`). The touches
themselves go to ``touches.csv`` (``app.live.haptic_setup``).
"""

from __future__ import annotations

import queue
import re
import sys
import threading
import time
from pathlib import Path

import numpy as np
from PIL import Image

from frictex.app.live.haptic_thread import EVENTS, ChannelMismatch
from frictex.app.live.layer_edit import EditError, LayerEdit, SaveConflict, panel_view
from frictex.app.live.link_watch import LinkWatch, device_clamps, limit_warning, run_underruns
from frictex.app.live.watch import FileWatch
from frictex.device.safe_text import escape
from frictex.rendering.renderers import loadable_render_modes
from frictex.rendering.visual.compositor import Compositor, FrameView
from frictex.rendering.visual.layer_panel import PanelView, hit, track_fraction
from frictex.rendering.visual.modal_view import modal_envelope
from frictex.rendering.visual.overlay import OverlayState
from frictex.rendering.visual.viewport import frame_layout
from frictex.textures.errors import TextureError
from frictex.textures.loader import load_scene
from frictex.textures.references import referenced_files

RENDERER_CYCLE = (None, *loadable_render_modes())
FORCE_STEP_N = 0.05
FORCE_RANGE_N = (0.05, 2.0)
#: an edit is applied once it has held still for a poll: 0.075-0.15 s after saving, so that
#: with the new scene's image (at most 0.12 s for a bundled scene at 1920x1080 on
#: llvmpipe: ``frictex bench visual``) the picture changes within 0.3 s of a save
RELOAD_POLL_S = 0.075
#: a texture file missing this long (s) is said to be gone: an editor deleting it before
#: writing it again takes milliseconds
GONE_S = 0.5
ENVELOPE_S = 0.2  # a modal device's |W| is redrawn from the latest commands 5 times a second
FRAME_S = 1.0 / 60.0
NOTICE_S = 8.0  # a note (scenes N skipped) stays in the info banner this long
INPUT_WAKE_S = 0.05  # longest the input thread waits for an event before looking at the time
#: while the button is held, the pointer is reported at least this often (s), moved or
#: not, as a touch screen re-reports a still finger: a mouse that stops sends no event,
#: and the tracker would otherwise rest the finger where its prediction had carried it
STILL_REPORT_S = 0.01
KEYS_HELP = ("wheel, up/down: force | N/B: scene | R: renderer | S: scope | "
             "O: outlines | P: screenshot | L: layers | SPACE: emergency stop | Q: quit")


def window_title(scene) -> str:
    """The window's title for ``scene``: "frictex demo" and the scene's name (escaped: a
    name comes from a file)."""
    return f"frictex demo: {escape(scene.name, limit=80)}"


def file_stem(name: str) -> str:
    """``name`` (a scene's: it comes from a file) as part of a file name: every run of
    characters other than ASCII letters, digits, '.', '-' and '_' becomes one '_' (a
    '/' can lead nowhere), at most 80 characters."""
    return re.sub(r"[^A-Za-z0-9._-]+", "_", name)[:80]


def next_screenshot(folder: Path, stem: str):
    """A new file ``<stem>-NNN.png`` in ``folder``, numbered one past the highest there,
    created exclusively (another demo writing there at once cannot take the same
    name): (path, binary file open for writing)."""
    folder.mkdir(parents=True, exist_ok=True)
    pattern = re.compile(re.escape(stem) + r"-(\d+)\.png")
    taken = [int(m.group(1)) for p in folder.iterdir() if (m := pattern.fullmatch(p.name))]
    n = max(taken, default=-1) + 1
    while True:
        path = folder / f"{stem}-{n:03d}.png"
        try:
            return path, open(path, "xb")
        except FileExistsError:
            n += 1


def skip_note(skipped: list) -> str:
    """One line on the scenes ``skipped`` by N / B (a ``ChannelMismatch`` each)."""
    groups: dict[str, list[str]] = {}
    for exc in skipped:
        groups.setdefault(exc.wants, []).append(exc.scene)
    which = "; ".join(f"{', '.join(names)} (channels {wants})" for wants, names in groups.items())
    return (f"skipped {len(skipped)} scene{'s' * (len(skipped) != 1)} {skipped[0].held}, "
            f"opened for {skipped[0].opened}, cannot play: {which}; start the demo on one to "
            "play it")


def starved(link: dict) -> str:
    """What a device link's status (``sink.status()``) says the device did not play so
    far, for the status line: ", 7.6 % unplayed, 3 underruns", each part only when
    non-zero; "" without a device."""
    commanded, unplayed = link.get("commanded_samples") or 0, link.get("unplayed_samples") or 0
    said = f", {100.0 * unplayed / commanded:.1f} % unplayed" if commanded and unplayed else ""
    if underruns := run_underruns(link):
        said += f", {underruns} underrun{'s' * (underruns != 1)}"
    return said


class HapticStopped(OSError):
    """The haptic side stopped for a reason that is neither a device's nor a file's."""


def output_stopped(error) -> BaseException:
    """What the demo raises when its haptic side stopped with ``error`` (an exception,
    or the child process's message): a device that stopped taking data stays itself
    (``LinkError``, an OSError: the command's one-line error and exit status), anything
    else says the output stopped."""
    if isinstance(error, (OSError, ValueError)):
        return error
    return HapticStopped(f"haptic output stopped: {error}")


class DemoLoop:
    """See the module docstring. ``load(path) -> Scene`` raises ValueError on a bad file."""

    def __init__(self, backend, haptic, playlist: list[Path], index: int, scene, load,
                 screenshot_dir: Path, events_path: Path | None = None, link_name: str = "none",
                 follow_mm: float | None = None, touch_screen: bool = False,
                 input_name: str = "mouse"):
        self.backend = backend
        self.haptic = haptic
        self.playlist = playlist
        self.index = index
        self.scene = scene
        self.load = load
        self.screenshot_dir = screenshot_dir
        self.link_name = link_name
        self.follow_mm = follow_mm
        self._follower_at: tuple[float, float] | None = None  # follow mode's finger 1 (mm)
        self.touch_screen = touch_screen
        self.input_name = input_name
        self.compositor = Compositor(backend.ctx, scene, backend.size,
                                     fullscreen=getattr(backend, "fullscreen", False),
                                     touch_screen=touch_screen)
        self.show_scope = self._scope_first(scene)
        self._say_touch_off_glass()
        backend.set_title(window_title(scene))
        self.overlay = OverlayState()
        self.force_n = scene.device.normal_force_n
        self.renderer = haptic.render_override
        self.touching = False
        #: the mouse button is held off the scene's drawn area (pressed there, or dragged
        #: off it; a press the layer panel took is none): back on the scene, it touches
        self._held_off_scene = False
        self.hover_px: tuple[float, float] | None = None
        #: window events since the last flush: (None: a move, True: press, False: release,
        #: pointer px then)
        self._pending: list[tuple[bool | None, tuple[float, float]]] = []
        self._flushed_at: float | None = None  # haptic clock (s)
        self._sent: tuple | None = None  # (pointer px, force N) of the last mouse sample
        self.outlines = False
        self.error: str | None = None
        #: a note shown in the info banner until ``_notice_until`` (s on the loop's clock;
        #: None: from its first frame on, :meth:`show_notice`)
        self.notice: str | None = None
        self._notice_until: float | None = None
        self.status: dict = {}
        self.quit = False
        self.screenshot_pending = False
        self.screenshots: list[Path] = []
        self.frames = 0
        self.frame_seconds = 0.0
        self.files = FileWatch()
        self._watch(self.playlist[self.index])
        self._set_envelope(scene, haptic.pipeline.actuation)
        self._next_poll = 0.0
        self._missing_since: float | None = None  # when the texture file went missing (s)
        self._keys: queue.SimpleQueue = queue.SimpleQueue()  # for the render thread
        #: the playlist's scenes the open link or recording cannot play (path: why)
        self.unplayable: dict[Path, ChannelMismatch] = {}
        #: the layer panel: its editor, the menu open, its note (render thread); the
        #: slider being dragged and the drags so far (input thread); panel events
        #: (input -> render thread): ("click", row) | ("slide", row, fraction, drag) | ("end",)
        self.editor: LayerEdit | None = None
        self.panel_open = False
        self.open_menu: str | None = None
        self.panel_note = ""
        self._save_refused: str | None = None  # the banner of the last refused save
        self._drag = None
        self._drags = 0
        self._panel: queue.SimpleQueue = queue.SimpleQueue()
        self._drag_slider: tuple = (None, None)  # (drag, the slider as it began)
        self._log_lock = threading.Lock()  # both threads log
        self._stop = threading.Event()
        self.render_error: BaseException | None = None
        self._applied_seen = 0  # output changes (stats.applied) already logged
        self._contact: dict[int, bool] = {}  # finger ids touching at the last snapshot: True
        self._contact_t_s = 0.0  # output time (s) of the last snapshot's last sample
        self.link_watch = LinkWatch()
        self._stalled_at: float | None = None  # output time the link stalled (s)
        self._limit_checked = None  # the scene the device's limit was checked against
        self._events = open(events_path, "a", encoding="utf-8") if events_path else None
        if self._events is not None and self._events.tell() == 0:
            self._events.write("t_s,event,detail\n")
        backend.on_cursor = self.on_cursor
        backend.on_button = self.on_button
        backend.on_scroll = self.on_scroll
        backend.on_key = self.on_key

    def _scope_first(self, scene) -> bool:
        """Whether the scope strip is shown at first: not on the glass (the scene fills
        the screen where it is felt: said once on stderr; S draws the strip over the
        scene, never moving it), nor where the window was cut to the screen's work area
        (``backend.requested``: the size asked for) and holds the scene at its display's
        pixels only without the strip (a grating's lines then keep their size); a cut
        window says on stderr what it shows."""
        d, size = scene.display, tuple(self.backend.size)
        if self.compositor.glass:
            sx, sy = self.compositor.viewport.px_per_mm
            self.say(f"the scene fills the {size[0]} x {size[1]} px screen ({sx:.3g} x {sy:.3g} "
                     "px/mm) as it lies on the glass; the status lines are hidden, S draws "
                     "the scope over the bottom of the scene")
            return False
        asked = tuple(getattr(self.backend, "requested", size))
        if asked[0] <= size[0] and asked[1] <= size[1]:
            return True
        side = self.compositor.panels.column_px(scene, size)
        drawn = {scope: frame_layout(d, *size, scope, side)[0] for scope in (True, False)}
        own = {scope: (v.width_px, v.height_px) == (d.width_px, d.height_px)
               for scope, v in drawn.items()}
        window = f"the window is cut to {size[0]} x {size[1]} px ({asked[0]} x {asked[1]} asked)"
        if (area := getattr(self.backend, "work_area", None)) is not None:
            window += (f" to fit, with its title bar and borders, the screen's work area "
                       f"({area[0]} x {area[1]} px)")
        if own[False] and not own[True]:
            self.say(f"{window}: the scene at its {d.width_px} x {d.height_px} px leaves no room "
                     "for the scope strip under it; S shows the scope (the scene then scaled "
                     "to fit above it)")
            return False
        if not own[True]:
            v = drawn[True]
            self.say(f"{window}: the scene is drawn at {v.width_px} x {v.height_px} px "
                     f"({v.px_per_mm[0]:.3g} px/mm), not its display's {d.width_px} x "
                     f"{d.height_px} px ({d.width_px / d.width_mm:.3g} px/mm)")
        return True

    def _say_touch_off_glass(self) -> None:
        """A touch screen maps its touches onto the whole panel (``rendering.input``):
        off the glass (a window, or a fullscreen frame the scene is fitted into) say once
        on stderr that the drawing and the touches do not coincide."""
        if not self.touch_screen or self.compositor.glass:
            return
        v, size = self.compositor.viewport, tuple(self.backend.size)
        self.say(f"--input {self.input_name} maps touches onto the whole panel, but the scene "
                 f"is drawn in {v.width_px} x {v.height_px} px at ({v.x0}, {v.y0}) of a "
                 f"{size[0]} x {size[1]} px window: the drawing and the touches do not "
                 "coincide (run the demo --fullscreen on the touch screen's monitor)")

    # -- input --------------------------------------------------------------------------

    def log(self, event: str, detail: str = "", t_s: float | None = None) -> None:
        """Append an event at ``t_s`` (s, haptic clock; default now) to events.csv."""
        if self._events is not None:
            quoted = '"' + detail.replace('"', "'").replace("\n", " ") + '"'
            with self._log_lock:
                t = self.haptic.now() if t_s is None else t_s
                self._events.write(f"{t:.6f},{event},{quoted}\n")
                self._events.flush()

    def _mm(self, px: tuple[float, float]) -> tuple[float, float]:
        x, y = self.compositor.viewport.to_mm(*px)
        return float(x), float(y)

    def _mouse_touch(self, event: str, px: tuple[float, float], t_s: float) -> None:
        """The mouse's finger 0 at ``px`` at ``t_s`` (haptic clock; in follow mode with
        finger 1, ``follow_mm`` to its right, at the same instant: :meth:`_follower`)."""
        x, y = self._mm(px)
        fingers = [(0, x, y, self.force_n, EVENTS[event])]
        if self.follow_mm is not None and (follower := self._follower(event, x, y)):
            fingers.append(follower)
        self.haptic.touches_at(t_s, fingers)
        self._sent = (px, self.force_n)

    def _follower(self, event: str, x: float, y: float) -> tuple | None:
        """Follow mode's finger 1 for finger 0's ``event`` at (x, y) mm: ``follow_mm`` to
        its right while that point is on the display (a second finger of the same hand,
        seed 001), lifted at its last place there when it leaves it or finger 0 lifts,
        and down again where it comes back onto it; None where it has nothing to say.
        Held at the display's edge, it would feel the edge's texture at a spacing the
        scene does not have."""
        fx = x + self.follow_mm
        if event != "up" and 0.0 <= fx <= self.scene.display.width_mm:
            code = EVENTS["down" if self._follower_at is None else "move"]
            self._follower_at = (fx, y)
            return (1, fx, y, self.force_n, code)
        if self._follower_at is None:
            return None
        (last_x, last_y), self._follower_at = self._follower_at, None
        return (1, last_x, last_y, self.force_n, EVENTS["up"])

    # The callbacks only note what happened, in order; flush_mouse(), after each batch of
    # window events, turns it into samples (see the module docstring).

    def on_cursor(self, x_px: float, y_px: float) -> None:
        self.hover_px = (x_px, y_px)
        if self._drag is not None:
            self._panel.put(("slide", self._drag, track_fraction(self._drag, x_px), self._drags))
            return
        self._pending.append((None, self.hover_px))

    def on_button(self, pressed: bool) -> None:
        if self.hover_px is None:
            self.hover_px = self.backend.cursor_px()
        if self._drag is not None and not pressed:
            self._drag = None
            self._panel.put(("end",))
            return
        if pressed and not self.touching and self._on_panel(self.hover_px):
            return
        self._pending.append((pressed, self.hover_px))

    def _on_panel(self, px: tuple[float, float]) -> bool:
        """A press at ``px``: if it is on the layer panel's column, the panel's (a click
        on a row, or the start of a slider's drag) and True."""
        left = self.compositor.left_px  # 0 while the panel is closed
        rows = self.compositor.panel_rows
        if not left or px[0] >= left or not rows:
            return False
        found = hit(rows, *px)
        if found is not None:
            row, fraction = found
            if row.track is not None and px[0] >= row.track[0]:
                self._drags += 1
                self._drag = row
                self._panel.put(("slide", row, fraction, self._drags))
            else:
                self._panel.put(("click", row))
        return True

    def on_scroll(self, dy: float) -> None:
        self.set_force(self.force_n + FORCE_STEP_N * dy)

    def set_force(self, force_n: float) -> None:
        """The normal force (N) of the mouse's fingers and of a touch screen's."""
        before, self.force_n = self.force_n, float(np.clip(force_n, *FORCE_RANGE_N))
        self.haptic.touch_force.value = self.force_n
        if self.force_n != before:
            self.log("force", f"{self.force_n:.2f} N")

    def flush_mouse(self) -> None:
        """The mouse's touches since the last call, in order: the button held on the
        scene's drawn area touches (a down where it is pressed there or comes back onto
        it held), a move at each pointer position while touching, an up where it is let
        go or leaves the scene (at the last place on it), a move when the force changed.
        They are stamped evenly over the time since the last call (when they arrived, as
        far as this thread can tell), so a batch the window handles late keeps its path
        and its pace."""
        pending, self._pending = self._pending, []
        now = self.haptic.now()
        since = now if self._flushed_at is None else self._flushed_at
        self._flushed_at = now
        if self.touch_screen:
            return  # a touch screen drives the fingers; its emulated mouse must not add one
        samples, touching = [], self.touching
        inside = self.compositor.viewport.contains_px
        last_in = self._sent[0] if self._sent is not None else None  # last place touched
        for pressed, px in pending:
            on_scene = inside(*px)
            if pressed is False:
                self._held_off_scene = False
                if touching:
                    touching = False
                    samples.append(("up", px if on_scene else last_in))
            elif on_scene and (pressed or touching or self._held_off_scene):
                samples.append(("move" if touching else "down", px))
                touching, last_in, self._held_off_scene = True, px, False
            elif pressed or touching:  # pressed off the scene (the scope, a panel, the
                self._held_off_scene = True  # window's edge), or dragged off it
                if touching:
                    touching = False
                    samples.append(("up", last_in))
        if touching:
            samples.append(("move", self.hover_px))  # the last position, at the force set now
        self.touching = touching
        kept, last = [], self._sent
        for event, px in samples:
            if event != "move" or (px, self.force_n) != last:  # a move nowhere new: none
                kept.append((event, px))
                last = (px, self.force_n)
        if touching and not kept:  # held still: reported still (STILL_REPORT_S)
            kept.append(("move", self.hover_px))
        for i, (event, px) in enumerate(kept):
            self._mouse_touch(event, px, since + (now - since) * (i + 1) / len(kept))

    def check_input(self) -> None:
        """A touch screen that failed: say so, and let the mouse touch from now on."""
        failure = self.haptic.input_error()
        if failure is not None:
            self.error = f"touch input {self.input_name} stopped, the mouse touches now: {failure}"
            self.log("input-failed", failure)
            self.touch_screen = False

    def on_key(self, name: str, shift: bool) -> None:
        """The emergency stop, quitting and the force act at once; the other keys change
        what is drawn and go to the render thread (:meth:`handle_key`)."""
        if name == "space":  # logged after: the output changes no later than a block on
            if self.haptic.estop.is_set():
                self.haptic.estop.clear()
                self.log("estop-release")
            else:
                self.haptic.estop.set()
                self.log("estop")
        elif name in ("q", "escape"):
            self.quit = True
        elif name == "up":
            self.set_force(self.force_n + FORCE_STEP_N)
        elif name == "down":
            self.set_force(self.force_n - FORCE_STEP_N)
        else:
            self._keys.put((name, shift))

    def handle_key(self, name: str, shift: bool) -> None:
        """A key that changes what is drawn (on the thread holding the GL context)."""
        if name in ("n", "b", "tab", "page_down", "page_up"):
            step = -1 if name in ("b", "page_up") or (name == "tab" and shift) else 1
            self.step_scene(step)
        elif name == "r":
            nxt = RENDERER_CYCLE[(RENDERER_CYCLE.index(self.renderer) + 1) % len(RENDERER_CYCLE)]
            self._apply(self.scene, nxt, "renderer", nxt or "file")
        elif name == "s":
            self.show_scope = not self.show_scope
            self.log("scope", "shown" if self.show_scope else "hidden")
        elif name == "o":
            self.outlines = not self.outlines
            self.compositor.set_scene(self.scene, outlines=self.outlines)
            self.log("outlines", "on" if self.outlines else "off")
        elif name in ("p", "f12"):
            self.screenshot_pending = True
        elif name == "l":
            self.toggle_panel()
        elif name in ("ctrl+z", "u"):
            self.undo_edit()
        elif name == "ctrl+s":
            self.save_edit()

    # -- the layer panel (render thread) ------------------------------------------------

    def toggle_panel(self) -> None:
        """L: open the layer panel on the scene's file, or close it (edits stay applied)."""
        self.panel_open = not self.panel_open
        self.log("panel", "open" if self.panel_open else "closed")
        if self.panel_open:
            self._open_editor()

    def _open_editor(self) -> None:
        """Read the scene's file into a new editor while the panel is open (a file the
        panel cannot edit is said in the panel); an editor already open on that file
        (the panel closed and opened again) is kept, its unsaved edits with it."""
        if not self.panel_open:
            return
        path = Path(self.playlist[self.index])
        if self.editor is not None and self.editor.path == path:
            return
        try:
            self.editor = LayerEdit(path)
        except EditError as exc:
            self.editor, self.panel_note = None, str(exc)
            return
        self.editor.select(0)
        self.open_menu, self.panel_note = None, ""

    def handle_panel(self, items: list[tuple]) -> None:
        """The panel events queued since the last frame, in order; of a drag's run of
        positions only the last is applied (one scene built a frame). An event for a
        row the editor no longer has (the file was reloaded meanwhile) is said in the
        panel and dropped."""
        for k, item in enumerate(items):
            if self.editor is None:
                return
            try:
                if item[0] == "slide":
                    nxt = items[k + 1] if k + 1 < len(items) else None
                    if nxt is not None and nxt[0] == "slide" and nxt[3] == item[3]:
                        continue  # a later position of the same drag follows
                    _, row, fraction, drag = item
                    if self._drag_slider[0] != drag:  # its span as the drag began, all along
                        self._drag_slider = (drag, self.editor.control(row.key))
                    self._set_key(row.key, self._drag_slider[1].value_at(fraction), drag)
                elif item[0] == "end":
                    self.editor.end_group()
                elif item[0] == "click":
                    self._click(item[1])
            except EditError as exc:
                self.panel_note = str(exc)

    def _click(self, row) -> None:
        if row.kind == "layer":
            self.editor.select(row.index)
            self.open_menu = None
        elif row.kind == "menu":
            self.open_menu = None if self.open_menu == row.key else row.key
        elif row.kind == "option":
            self.open_menu = None
            self._set_key(row.key, row.option)
        elif row.kind == "undo":
            self.undo_edit()
        elif row.kind == "save":
            self.save_edit()

    def _set_key(self, key: str, value, drag: object = None) -> None:
        """Set ``key`` of the selected layer and apply the edited scene; a value the
        loader refuses is taken back and said."""
        editor = self.editor
        before = editor.text()
        written = editor.set(key, value, group=drag)
        if editor.text() != before:
            name = editor.layer_names()[editor.layer]
            if self._apply_text(f"{name} {key} = {written}"):
                self.panel_note = ""
            else:
                editor.revert()

    def _apply_text(self, what: str) -> bool:
        """The editor's text as the scene, to the haptic side and the picture."""
        text = self.editor.text()
        try:
            scene = load_scene(self.editor.path, text=text)
        except (ValueError, OSError) as exc:
            why = self.editor.refusal(exc) if isinstance(exc, ValueError) else str(exc)
            self.error = f"edit refused ({what}), keeping {self.scene.name}: {why}"
            self.log("edit-failed", why)
            return False
        return self._apply(scene, self.renderer, "edit", what, text)

    def undo_edit(self) -> None:
        """Ctrl+Z: take back the panel's last change (a whole drag)."""
        if self.editor is not None and self.editor.undo():
            self._apply_text("undo")
            self.panel_note = ""

    def save_edit(self) -> None:
        """Ctrl+S: write the edited file (a bundled scene: its copy in the user's
        folder, watched and edited from then on)."""
        if self.editor is None:
            return
        try:
            path = self.editor.save()
        except SaveConflict as exc:
            self._refuse_save(exc.banner, str(exc))
            return
        except (EditError, ValueError, OSError) as exc:
            self._refuse_save(f"not saved: {exc}", f"not saved: {exc}")
            return
        if self.error == self._save_refused:  # that banner is out of date now
            self.error = None
        self.playlist[self.index] = path
        self.files = FileWatch()  # the file as saved is no change to reload
        self._watch(path)
        self.panel_note = f"saved {path.absolute()}"
        self.log("save", str(path))
        print(f"saved: {path.absolute()}")

    def _refuse_save(self, note: str, why: str) -> None:
        """A refused Ctrl+S: ``note`` in the panel, ``why`` in the error banner, the
        events log and as one line on stderr (a save prints its path on stdout)."""
        self.panel_note = note
        self.error = self._save_refused = why
        self.log("save-failed", why)
        self.say(why)

    def panel_view(self) -> PanelView:
        """What the panel shows now."""
        return panel_view(self.editor, self.open_menu, self.panel_note)

    # -- scenes -------------------------------------------------------------------------

    def _apply(self, scene, renderer, event: str, detail: str, text: str | None = None,
               passes: tuple = ()) -> bool:
        """Hand ``scene`` with ``renderer`` to the haptic thread and redraw; on error keep
        the current one and show why. ``text``: the text ``scene`` was read from, when it
        is not its file's (the layer panel's edit); ``passes``: exceptions raised to the
        caller instead."""
        try:
            if text is None:
                pipeline = self.haptic.switch(scene, renderer)
            else:
                pipeline = self.haptic.switch(scene, renderer, text=text)
        except passes:
            raise
        except (ValueError, OSError, ModuleNotFoundError) as exc:
            self.error = f"{event} failed (keeping {self.scene.name}, {self.renderer or 'file'}): {exc}"
            self.log(f"{event}-failed", str(exc))
            return False
        self.log(event, detail)  # before redrawing the scene image
        if scene is not self.scene:
            self.compositor.set_scene(scene)
            self.backend.set_title(window_title(scene))
            if event != "edit":  # an edit keeps the trails: the finger is where it was
                self.overlay.clear()
            self._set_envelope(scene, pipeline.actuation)
        self.scene, self.renderer, self.error = scene, renderer, None
        return True

    def step_scene(self, step: int) -> None:
        """N (``step`` 1) or B (-1): the next scene of the playlist that the open link and
        recording can play. Those that drive other channels (``ChannelMismatch``) are
        skipped, said once on stderr and in the info banner (for NOTICE_S: a note, not an
        error), and skipped silently from then on; if no other scene fits, that is said
        instead, in the error banner."""
        n, skipped = len(self.playlist), []
        for k in range(1, n):
            index = (self.index + step * k) % n
            if self.playlist[index] in self.unplayable:
                continue
            try:
                self.select(index, passes=(ChannelMismatch,))
            except ChannelMismatch as exc:
                self.unplayable[self.playlist[index]] = exc
                skipped.append(exc)
                self.log("scene-skipped", str(exc))
                continue
            break
        else:
            if self.unplayable:
                refused = next(iter(self.unplayable.values()))
                self.error = (f"no other scene of the playlist plays on {refused.held} opened "
                              f"for {refused.opened}: start the demo on another scene to play it")
        if skipped:
            note = skip_note(skipped)
            self.say(note)
            self.show_notice(note)

    def show_notice(self, text: str) -> None:
        """Show ``text``, a note and no error, in the grey info banner for NOTICE_S from
        the first frame that draws it (a red error banner, while one is up, hides it)."""
        self.notice, self._notice_until = text, None

    def _age_notice(self, now: float) -> None:
        """Start the notice's NOTICE_S at its first frame (``now``: s on the loop's
        clock), and take it down once they are over."""
        if self.notice is None:
            return
        if self._notice_until is None:
            self._notice_until = now + NOTICE_S
        elif now >= self._notice_until:
            self.notice = None

    def select(self, index: int, passes: tuple = ()) -> None:
        """Switch to the playlist's scene ``index`` (``passes``: as :meth:`_apply`)."""
        path = self.playlist[index]
        try:
            scene = self.load(path)
        except (ValueError, OSError) as exc:
            self.error = f"cannot load {path.name} (keeping {self.scene.name}): {exc}"
            self.log("load-failed", str(exc))
            return
        if self._apply(scene, self.renderer, "scene", scene.name, passes=passes):
            self.index = index
            self.files, self._missing_since = FileWatch(), None
            self._watch(path)
            self._drop_editor("another scene was chosen")
            self._open_editor()

    def _watch(self, path: Path) -> None:
        """Watch the texture file at ``path`` and the files it names now (an edit may
        name others); if it cannot be read as TOML, what was watched stays watched."""
        try:
            named = referenced_files(path)
        except TextureError:
            named = self.files.paths
        self.files.watch((Path(path), *named))

    def check_reload(self, now: float) -> None:
        """Every RELOAD_POLL_S (s on the loop's clock): if the scene's texture file or
        a file it names changed and has since held still for a poll (a save caught between
        truncating and writing is not loaded, unless the writing waits a whole poll), load
        the scene again; a good load is applied, a bad one keeps the last good scene and
        shows why. A texture file that is not there (an editor between deleting and
        writing it) is waited for; missing GONE_S on, it is said to be gone (moved or
        deleted; a symbolic link: leading to no file), the last good scene kept, and
        reloaded once it is back. Each failure,
        and each reload, is also one line on stderr (:meth:`say`)."""
        if now < self._next_poll:
            return
        self._next_poll = now + RELOAD_POLL_S
        changed = self.files.changed()
        path = Path(self.playlist[self.index])
        if self.files.stamps.get(path) is None:
            if path in changed:
                self._missing_since = now
            if self._missing_since is not None and now - self._missing_since >= GONE_S:
                self._missing_since = None
                gone = ("is a symbolic link that leads to no file (a loop, or its target "
                        "gone)" if path.is_symlink() else "is gone (moved or deleted)")
                self.error = (f"{path.name} {gone}, keeping the last good scene; it reloads "
                              f"when {path.name} is back")
                self.log("reload-failed", f"{path} is gone")
                self.say(self.error)
            return
        self._missing_since = None
        if not changed:
            return
        self._watch(path)
        what = ", ".join(p.name for p in changed)
        try:
            scene = self.load(path)
        except (ValueError, OSError) as exc:
            self.error = f"reload failed ({what} changed), keeping the last good scene: {exc}"
            self.log("reload-failed", str(exc))
            self.say(self.error)
            return
        text, kept = self._reread_editor(path)
        if self._apply(scene if text is None else load_scene(path, text=text), self.renderer,
                       "reload", f"{scene.name} ({what} changed)", text):
            self.say(f"reloaded {scene.name} ({what} changed){kept}")
            self._open_editor()  # the file as saved, from now on
        else:
            self.say(self.error)

    def _reread_editor(self, path: Path) -> tuple[str | None, str]:
        """The panel's editor on ``path`` (reloaded: it changed and loads) takes the file
        again, its unsaved edits on top where they still apply (``LayerEdit.reread``).
        Returns the text to show (None: the file's own) and what became of the edits
        (", kept N unsaved panel values", ", dropped M unsaved panel values that no
        longer apply", both, or "")."""
        editor = self.editor
        if editor is None or editor.path != path:
            return None, ""
        dirty = editor.dirty
        try:
            kept, dropped = editor.reread()
        except EditError as exc:
            self.editor, self.panel_note = None, str(exc)
            self._open_editor()
            return None, ""
        if not dirty:
            return None, ""
        said = f", kept {kept} unsaved panel value{'s' * (kept != 1)}" if kept else ""
        if dropped:
            said += (f", dropped {dropped} unsaved panel value{'s' * (dropped != 1)} "
                     f"that no longer appl{'y' if dropped != 1 else 'ies'}")
        self.panel_note = said[2:]
        return (editor.text() if kept else None), said

    def _drop_editor(self, why: str) -> None:
        """The editor goes (``why``: another scene, the demo's end); its unsaved edits,
        if any, are said lost."""
        editor, self.editor = self.editor, None
        if editor is not None and editor.dirty:
            n = editor.unsaved
            self.say(f"{editor.path.name}: {n} unsaved panel value{'s' * (n != 1)} dropped "
                     f"({why})")

    @staticmethod
    def say(message: str) -> None:
        """``message`` as one line on stderr, as the demo's other messages."""
        print(f"frictex demo: {' '.join(message.split())}", file=sys.stderr, flush=True)

    def _set_envelope(self, scene, actuation) -> None:
        self.envelope = modal_envelope(scene, actuation)
        self.envelope_now = None
        self.envelope_scale_um = scene.device.amplitude_limit_um
        self._next_envelope = 0.0

    def update_envelope(self, now: float) -> None:
        """A modal device's |W| from the latest commands, every ENVELOPE_S; its scale
        grows (never shrinks, within a scene) to the largest |W| seen."""
        if self.envelope is None or now < self._next_envelope:
            return
        self._next_envelope = now + ENVELOPE_S
        self.envelope_now = self.envelope.at(self.overlay.commands, self.overlay.current())
        self.envelope_scale_um = max(self.envelope_scale_um, self.envelope_now.peak_um)

    # -- frames -------------------------------------------------------------------------

    def drain(self) -> None:
        """Take the haptic side's snapshots: the overlay's history, the status, and the
        output's changes and touches logged at their output times."""
        while True:
            try:
                snap = self.haptic.snapshots.get_nowait()
            except queue.Empty:
                return
            self.overlay.add(snap.record)
            self.status = snap.status
            self._log_applied(*snap.status.get("applied", (0, ())))
            self._log_contacts(snap.record)
            t = float(snap.record.t_s[-1]) if snap.record.t_s.size else self.haptic.now()
            self._watch_link(snap.status.get("link", {}), t)

    def _watch_link(self, link: dict, t_s: float) -> None:
        """The link's losses, returns and stalls since the last status, logged at
        ``t_s`` (s, output clock); a stall and its end also said on stderr (a loss and a
        return the link says itself). Once per scene: a device limit below the scene's
        said on stderr and on screen."""
        for event, detail in self.link_watch.update(link):
            self.log(event, detail, t_s)
            if event == "link-stalled":
                self._stalled_at = t_s
                self.say(f"link stalled at {t_s:.1f} s of output: {detail}; the plate gets "
                         "nothing (said again when it moves)")
            elif event == "link-moving" and self._stalled_at is not None:
                self.say(f"link moving again at {t_s:.1f} s of output, after "
                         f"{t_s - self._stalled_at:.1f} s stalled")
        if self._limit_checked is not self.scene and link.get("device"):
            self._limit_checked = self.scene
            if (warning := limit_warning(link, self.scene)) is not None:
                self.say(f"warning: {warning}")
                self.error = self.error or warning

    def _log_applied(self, count: int, latest: tuple) -> None:
        """Stops, resumes, switches and the friction loop's messages not logged yet
        (``latest``: the last of ``count``)."""
        for i, (t, event, detail) in enumerate(latest, start=count - len(latest)):
            if i >= self._applied_seen:
                self.log(event, detail, t)
                if event == "loop":  # the friction loop fell back or recovered: say so
                    print(f"frictex: {detail}", file=sys.stderr)
        self._applied_seen = max(self._applied_seen, count)

    def _log_contacts(self, record) -> None:
        """finger-down and finger-up where a finger's contact changes in ``record``."""
        if record.t_s.size == 0:
            return
        for row, fid in enumerate(record.finger_ids):
            states = np.concatenate(([self._contact.get(fid, False)], record.contact[row]))
            for i in np.flatnonzero(states[1:] != states[:-1]):
                self.log("finger-down" if states[i + 1] else "finger-up",
                         f"finger {fid} at {record.x_mm[row, i]:.2f}, {record.y_mm[row, i]:.2f} mm",
                         float(record.t_s[i]))
            if states[-1]:
                self._contact[fid] = True
            else:  # forgotten: the dict follows the fingers touching, not every id seen
                self._contact.pop(fid, None)
        for fid in [f for f in self._contact if f not in record.finger_ids]:
            self.log("finger-up", f"finger {fid}", float(record.t_s[0]))
            del self._contact[fid]
        self._contact_t_s = float(record.t_s[-1])

    @property
    def fingers_down(self) -> tuple[int, ...]:
        """The finger ids touching at the last snapshot drained (the output's view)."""
        return tuple(self._contact)

    def status_lines(self) -> tuple[str, ...]:
        st = self.status
        link = st.get("link", {})
        state = link.get("state", self.link_name)
        frames = f", {link['frames_sent']} frames sent" if "frames_sent" in link else ""
        first = (f"{self.scene.name} ({self.index + 1}/{len(self.playlist)}) | renderer: "
                 f"{self.renderer or 'file'} | force {self.force_n:.2f} N | link: {state}{frames}"
                 f"{starved(link)} | "
                 f"clamps {st.get('clamps', 0)}{device_clamps(link)} | "
                 f"deadline misses {st.get('deadline_misses', 0)}")
        fingers = len(self.overlay.current())
        touch = ("drag: touch" if self.follow_mm is None
                 else f"drag: two fingers, the second {self.follow_mm:g} mm to the right")
        if self.touch_screen:
            touch = "touch the screen"
        return (first, f"input: {self.input_name} ({touch}; {fingers} touching)", KEYS_HELP)

    def draw(self) -> None:
        self.compositor.resize(self.backend.size)
        self.backend.use()
        if self.haptic.estop.is_set():
            banner, kind = "EMERGENCY STOP: output is 0 um. SPACE resumes.", "stop"
        elif alarm := self.link_watch.alarm or self.error:
            banner, kind = alarm, "error"
        else:
            banner, kind = self.notice, "info"
        hover = self._mm(self.hover_px) if self.hover_px is not None and not self.touching else None
        self.compositor.draw(FrameView(
            overlay=self.overlay, hover_mm=hover, show_scope=self.show_scope,
            amplitude_max_um=self.scene.device.amplitude_limit_um, status=self.status_lines(),
            banner=banner, banner_kind=kind, envelope=self.envelope_now,
            envelope_scale_um=self.envelope_scale_um,
            layer_panel=self.panel_view() if self.panel_open else None))

    def screenshot_stem(self) -> str:
        """The start of a screenshot's file name: the scene's."""
        return f"frictex-{file_stem(self.scene.name)}"

    def screenshot(self) -> Path | None:
        """The frame drawn last, as a new PNG in the screenshot folder (never overwriting),
        said on stdout. A folder that cannot take it (a file of that name, no room, no
        permission) is said on stderr and on screen and logged; the demo carries on."""
        try:
            path, f = next_screenshot(self.screenshot_dir, self.screenshot_stem())
            with f:
                Image.fromarray(self.backend.read_rgb()).save(f, format="PNG")
        except OSError as exc:
            self.error = f"screenshot failed: {exc}"
            self.log("screenshot-failed", str(exc))
            self.say(self.error)
            return None
        self.screenshots.append(path)
        self.log("screenshot", str(path))
        print(f"screenshot: {path}")
        return path

    def frame(self, now: float) -> None:
        """Draw and show one frame (``now``: s on the loop's clock)."""
        self.check_reload(now)
        self._age_notice(now)
        self.drain()
        self.update_envelope(now)
        self.draw()
        if self.screenshot_pending:
            self.screenshot_pending = False
            self.screenshot()
        self.backend.swap()
        if self.frames == 0:
            self.log("first-frame", self.scene.name)
        self.frames += 1

    def run(self, duration_s: float | None = None, clock=time.perf_counter, stop=None) -> None:
        """Pump input on this thread and draw on a render thread until the window
        closes, Q, ``duration_s`` (s on ``clock``), ``stop()`` is true (looked at after
        each wait for events: a signal held as a flag, never raised in a window
        callback) or a failure (raised here)."""
        start = clock()
        self.backend.release_context()
        renderer = threading.Thread(target=self._render, args=(clock,), name="frictex-render",
                                    daemon=True)
        renderer.start()
        try:
            while not (self.quit or self.backend.should_close or self.render_error is not None):
                if duration_s is not None and clock() - start >= duration_s:
                    break
                if stop is not None and stop():
                    break
                self.backend.wait_events(STILL_REPORT_S if self.touching else INPUT_WAKE_S)
                self.flush_mouse()
        finally:
            self._stop.set()
            renderer.join()
            self.backend.make_current()
        if self.render_error is not None:
            raise self.render_error

    def check_output(self) -> None:
        """The haptic side stopped (a device lost, a failure): raise why, which ends the
        demo (render thread, every frame; an experiment session pauses instead)."""
        if (error := self.haptic.error) is not None:
            raise output_stopped(error)

    def _render(self, clock) -> None:
        """The render thread: keys, then a frame whenever one is due."""
        self.backend.make_current()
        try:
            next_frame = clock()
            while not self._stop.is_set():
                self.check_output()
                while not self._keys.empty():
                    self.handle_key(*self._keys.get())
                items = []
                while not self._panel.empty():
                    items.append(self._panel.get())
                if items:
                    self.handle_panel(items)
                now = clock()
                if now < next_frame:
                    self._stop.wait(next_frame - now)
                    continue
                self.check_input()
                self.frame(now)
                done = clock()
                self.frame_seconds += done - now
                next_frame = max(next_frame + FRAME_S, done)
        except BaseException as exc:  # raised again by run() on the input thread
            self.render_error = exc
            self.backend.wake()
        finally:
            self.backend.release_context()

    def close(self) -> None:
        """Say the panel's unsaved edits lost, release the GL objects, close the events
        file with its rows in time order, every finger-down in it followed by a finger-up
        (a finger still touching when the demo ends is lifted at the last output drawn)."""
        self._drop_editor("the demo ended")
        self.compositor.release()
        for fid in self._contact:
            self.log("finger-up", f"finger {fid}: touching when the demo ended", self._contact_t_s)
        self._contact.clear()
        if self._events is not None:
            self._events.close()
            sort_events(Path(self._events.name))


def sort_events(path: Path) -> None:
    """Put ``path``'s (events.csv) rows in order of t_s, those of one time in the order
    they were logged: a key is logged when pressed, an output change at the output time
    of its block (computed ahead of it) and a touch when its snapshot is drawn (after
    it), so they are written out of order."""
    header, *rows = path.read_text(encoding="utf-8").splitlines(keepends=True)
    rows.sort(key=lambda row: float(row.split(",", 1)[0]))
    path.write_text(header + "".join(rows), encoding="utf-8")
