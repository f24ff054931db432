"""Bench section "visual": the visual layer offscreen (EGL) at 800x480 and 1920x1080.

Figures: the static scene image (drawn once per scene switch or reload, what a visitor
waits for: image, sRGB encoding and texture upload, with no table cached from an
earlier draw; best of 3, or 1 with ``--quick``) for a 0.6 mm grating at 30 degrees
inside a disc composed with a 5 mm grating, and at 1920x1080 for every bundled scene,
each of these with the verdict on "under 0.5 s" from its draws (their geometric mean and
its 95 % interval, ``ratio_claim.time_claim``; one draw with ``--quick`` shows nothing);
the per-frame cost of the overlay on top of it (two
fingers with trails, the scope with 3 s of history, the status line; each frame after
1/60 s more of the stroke, as live), each frame
finished on the GPU (``ctx.finish``), without and with reading the pixels back (what
``--frames`` and screenshots pay), best wall time of 100 (20 with ``--quick``) and the
mean CPU time of all threads; beside them, alternated with the frames read back (one of
each per round, the order reversed every other round, so that a change in the machine's
load falls on both), the floor of this renderer (clear, the scene's textured quad and the
read-back, nothing else), the verdict on "a frame read back at most 2x the floor" from
each round's ratio of wall times (their geometric mean and its 95 % interval,
``app.measure.ratio_claim``), the ratio of mean CPU times, the frame's draw calls. The frame and the
floor are measured again beside one busy process per core. A static image's label names
the pixels drawn (the scene's aspect, fitted into the window) and the window. Each
label names the renderer EGL chose (llvmpipe is Mesa's software rasterizer; a GPU's
driver names the GPU). The CPU is shared: quote the machine's load with the figures; the
CPU ratio is the one that holds on a busy machine.
"""

from __future__ import annotations

import sys
import time

import moderngl
import numpy as np

from frictex.app.measure.figure import Figure
from frictex.app.measure.in_turn import timed_in_turn
from frictex.app.measure.processes import BusyProcesses, cores
from frictex.app.measure.ratio_claim import ratio_claim, time_claim
from frictex.rendering.visual.compositor import TEXTURED, Compositor, FrameView
from frictex.rendering.visual import scene_image
from frictex.rendering.visual.context import OffscreenBackend, VisualError
from frictex.rendering.visual.overlay import BlockRecord, OverlayState
from frictex.rendering.visual.viewport import fit_viewport
from frictex.device.profile import DeviceProfile
from frictex.textures.model import DiscRegion, Display, Grating, Scene, VisualHints

SIZES = ((800, 480), (1920, 1080))


def bench_scene() -> Scene:
    coarse = Grating(name="coarse", render="sho", region=None, blend="multiply",
                     visual=VisualHints((0.3, 0.3, 0.3), (1.0, 1.0, 1.0)), period_mm=5.0)
    fine = Grating(name="fine", render="sht", region=DiscRegion(54.0, 32.4, 20.0), blend="multiply",
                   visual=VisualHints(), period_mm=0.6, angle_deg=30.0)
    return Scene(1, "bench", "", Display(108.0, 64.8, 800, 480), DeviceProfile(), (coarse, fine))


#: the bench's two fingers: 2 kHz records, a frame every 1/60 s
RECORD_HZ, FRAME_S = 2000.0, 1.0 / 60.0


def stroke_record(t0: float, t1: float) -> BlockRecord:
    """Two fingers sliding over [t0, t1) s (sampled at RECORD_HZ), mu' a square wave
    and a slow sine, amplitude following."""
    t = np.arange(round(t0 * RECORD_HZ), round(t1 * RECORD_HZ)) / RECORD_HZ
    x = np.stack((54 + 30 * np.sin(0.7 * t), 54 - 25 * np.sin(0.5 * t)))
    y = np.stack((32 + 12 * np.sin(1.1 * t), 20 + 5 * np.cos(0.9 * t)))
    mu = np.stack((0.6 + 0.4 * (np.sin(200 * t) > 0), 0.8 + 0.1 * np.sin(20 * t)))
    return BlockRecord(t, (0, 1), np.ones((2, t.size), bool), x, y, mu, (1 - mu) * 4)


def busy_overlay() -> OverlayState:
    """An overlay with 3 s of both fingers' history (full trails and scope)."""
    overlay = OverlayState()
    overlay.add(stroke_record(0.0, 3.0))
    return overlay


def next_frame(overlay: OverlayState) -> None:
    """Feed ``overlay`` the next FRAME_S of the stroke (what a live frame receives)."""
    overlay.add(stroke_record(overlay.now_s + 1.0 / RECORD_HZ, overlay.now_s + FRAME_S))


def scene_runs_ms(comp: Compositor, scene: Scene, repeats: int) -> list[float]:
    """Milliseconds ``comp`` takes to draw ``scene`` into its static texture, cold (no
    cached table), each of ``repeats`` draws. The scene is first drawn once at 64 x 48
    px, untimed: that loads its compiled kernels, once per process (start-up's cost, not
    the image's)."""
    scene_image.scene_rgb(scene, fit_viewport(scene.display, 64, 48))
    runs_ms = []
    for _ in range(repeats):
        scene_image.clear_tables()
        t0 = time.perf_counter()
        comp.set_scene(scene)
        runs_ms.append((time.perf_counter() - t0) * 1e3)
    return runs_ms


def static_label(comp: Compositor, name: str, label: str) -> str:
    """A static image's label: ``name``, the pixels drawn (``comp``'s viewport: the
    scene's aspect fitted into the window) and ``label`` (the window and renderer)."""
    drawn = f"{comp.viewport.width_px}x{comp.viewport.height_px} px"
    return f"static {name}, {drawn} drawn in the window {label}"


def static_figure(comp: Compositor, name: str, label: str, runs_ms: list[float]) -> Figure:
    """The best of a static image's draws (``scene_runs_ms``; the CPU is shared: the best
    run is the cost), labelled by ``static_label``."""
    return Figure("visual", static_label(comp, name, label), min(runs_ms),
                  static_unit(len(runs_ms)))


#: a bundled scene's static image at 1920x1080 is to take at most this long (s), issue 31
STATIC_TARGET_S = 0.5


def static_target_figure(comp: Compositor, name: str, label: str,
                         runs_ms: list[float]) -> Figure:
    """The verdict on :data:`STATIC_TARGET_S` from every draw's time (``time_claim``:
    their geometric mean and its 95 % interval; one draw, with ``--quick``, shows
    nothing)."""
    return time_claim([ms / 1e3 for ms in runs_ms], STATIC_TARGET_S).figure(
        "visual", f"{static_label(comp, name, label)}, time per draw", STATIC_TARGET_S,
        at_most=True, unit=" s", of="draws")


def bundled_scene_figures(comp: Compositor, label: str, repeats: int) -> list[Figure]:
    """Per bundled scene its static image's best draw and the verdict on its target."""
    from frictex.textures.library import list_scenes
    from frictex.textures.loader import load_scene
    figures = []
    for entry in list_scenes():
        name = f"image {entry.path.stem}"
        runs_ms = scene_runs_ms(comp, load_scene(entry.path), repeats)
        figures += [static_figure(comp, name, label, runs_ms),
                    static_target_figure(comp, name, label, runs_ms)]
    return figures


def static_unit(repeats: int) -> str:
    """The unit of a static image's figure: what ``scene_runs_ms`` measured."""
    return (f"ms (drawn once per scene; best of {repeats} after an untimed 64x48 px draw "
            "that loads its kernels)")


def floor_step(backend: OffscreenBackend, texture_size: tuple[int, int]):
    """The least a frame can cost on this renderer: clear, one textured quad of
    ``texture_size`` px (the scene) and the pixels read back. Returns (step, release):
    ``step()`` draws one such frame, ``release()`` frees its GL objects."""
    ctx = backend.ctx
    program = ctx.program(vertex_shader=TEXTURED[0], fragment_shader=TEXTURED[1])
    texture = ctx.texture(texture_size, 3, bytes(3 * texture_size[0] * texture_size[1]),
                          alignment=1)
    w, h = backend.size
    quad = np.array([[0, 0, 0, 0], [texture_size[0], 0, 1, 0], [0, texture_size[1], 0, 1],
                     [texture_size[0], texture_size[1], 1, 1]], dtype="f4")
    buffer = ctx.buffer(quad.tobytes())
    vao = ctx.vertex_array(program, [(buffer, "2f 2f", "in_px", "in_uv")])
    program["u_frame"] = (float(w), float(h))
    program["u_tex"] = 0
    backend.use()

    def step():
        ctx.clear(0.12, 0.12, 0.12, 1.0)
        texture.use(0)
        vao.render(moderngl.TRIANGLE_STRIP, vertices=4)
        backend.read_rgb()
        ctx.finish()

    def release():
        for obj in (vao, buffer, texture, program):
            obj.release()

    return step, release


def frame_step(backend: OffscreenBackend, comp: Compositor, view: FrameView,
               read_back: bool):
    """(step, before): ``step()`` draws a frame of ``view`` finished on the GPU
    (``read_back``: with the pixels read back), ``before()`` feeds its overlay the next
    FRAME_S of the stroke (untimed). One frame is drawn here first, untimed (shaders,
    text atlas)."""
    backend.use()
    comp.draw(view)
    backend.ctx.finish()

    def step():
        comp.draw(view)
        if read_back:
            backend.read_rgb()
        backend.ctx.finish()

    return step, lambda: next_frame(view.overlay)


def run(quick: bool) -> list[Figure]:
    frames = 20 if quick else 100
    repeats = 1 if quick else 3
    figures = []
    scene = bench_scene()
    view = FrameView(overlay=busy_overlay(), hover_mm=(50.0, 30.0),
                     status=("bench | renderer: file | force 0.50 N | link: none",))
    for size in SIZES:
        try:
            backend = OffscreenBackend(size)
        except VisualError as exc:
            print(f"frictex: bench visual: not available ({exc})", file=sys.stderr)
            return figures
        # the renderer EGL chose: llvmpipe (software) or a GPU's driver
        label = f"{size[0]}x{size[1]} on {backend.ctx.info['GL_RENDERER'].split(' (')[0]}"
        comp = Compositor(backend.ctx, scene, size)
        figures.append(static_figure(comp, "scene image", label,
                                     scene_runs_ms(comp, scene, repeats)))
        if size == SIZES[-1]:
            figures.extend(bundled_scene_figures(comp, label, repeats))
            comp.set_scene(scene)
        [(frame, _)] = timed_in_turn([frame_step(backend, comp, view, read_back=False)],
                                     frames)
        figures.append(Figure("visual", f"frame {label}", frame.min() * 1e3,
                              best_unit(frames)))
        figures += against_floor(backend, comp, view, frames, label)
        busy = cores()
        with BusyProcesses(busy, 120.0):
            figures += against_floor(backend, comp, view, frames,
                                     f"{label}, beside {busy} busy processes")
        figures.append(Figure("visual", f"draw calls per frame {label}", comp.batch.calls, ""))
        comp.release()
        backend.close()
    return figures


def best_unit(frames: int) -> str:
    """The unit of a frame's or floor's best time of ``frames``."""
    return f"ms of wall time (best of {frames})"


#: a frame with its pixels read back: at most this many times the floor's wall time
FLOOR_TARGET = 2.0


def against_floor(backend: OffscreenBackend, comp: Compositor, view: FrameView, frames: int,
                  label: str) -> list[Figure]:
    """The frame with its pixels read back against the floor, ``frames`` of each in
    alternated rounds (a frame and a floor each round, the order reversed every other
    round; ``in_turn``): ``floor_figures``."""
    read_back = frame_step(backend, comp, view, read_back=True)
    floor_draw, release = floor_step(backend, (comp.viewport.width_px,
                                               comp.viewport.height_px))
    try:
        read, floor = timed_in_turn([read_back, (floor_draw, None)], frames)
    finally:
        release()
    return floor_figures(read, floor, label)


def floor_figures(read: tuple, floor: tuple, label: str) -> list[Figure]:
    """From per-round (wall s, CPU s) of the frame read back (``read``) and of the floor
    (same round at the same index): the best wall time of each, the verdict on
    :data:`FLOOR_TARGET` from each round's ratio of wall times (``ratio_claim``), the
    mean CPU time of each and their ratio."""
    (read_wall, read_cpu), (floor_wall, floor_cpu) = read, floor
    frames = len(read_wall)
    best, mean = best_unit(frames), f"ms of CPU time (mean of {frames}, all threads)"
    claim = ratio_claim(list(read_wall / floor_wall), FLOOR_TARGET, at_most=True)
    return [Figure("visual", f"frame + read back {label}", read_wall.min() * 1e3, best),
            Figure("visual", f"floor {label} (clear, scene quad, read back; alternated with "
                             "the frames)", floor_wall.min() * 1e3, best),
            claim.figure("visual", f"frame + read back / floor {label}, wall time per round",
                         FLOOR_TARGET, at_most=True),
            Figure("visual", f"frame + read back CPU {label}", read_cpu.mean() * 1e3, mean),
            Figure("visual", f"floor CPU {label}", floor_cpu.mean() * 1e3, mean),
            Figure("visual", f"frame + read back / floor CPU {label}",
                   read_cpu.mean() / floor_cpu.mean(), "x (mean against mean)")]
