"""``frictex warm``: compile the pipeline's kernels now, once per install.

The per-sample kernels (tracking, SHT phase, the hybrid, modal actuation, height layers,
recorded textures and effect clips, the friction loop, the CSV writer) are compiled by
numba on first use and cached beside their sources; setup runs this so that no replay,
demo or test pays the compilation. It replays a short synthetic stroke on one bundled
scene of each kind of device into a temporary folder, in every output format, on a
scene with a height layer of every shape, on a scene with a recorded texture and with
the friction loop on. The visual overlay's kernels (trails, scope columns) are compiled
on a short two-finger stroke, without OpenGL.
"""

from __future__ import annotations

import argparse
import tempfile
import time

#: one scene per kind of actuation and renderer the kernels serve
SCENES = ("composed-fine-grating-in-disc", "grating-5mm", "two-finger-beam-seed000",
          "two-finger-plate-seed001", "directional-beam", "keyclick-ring", "height-button",
          "slider-clips")


def recorded_texture_scene():
    """grating-5mm with a recorded texture on top. frictex ships no recorded data (the
    Penn toolkit's licence), so four AR(2) vertices over (20-200 mm/s, 0.2-2 N) stand in:
    the kernels are the same for any model file."""
    from dataclasses import replace

    import numpy as np

    from frictex.textures.hatt import ArTextureLayer, model_from_coefficients
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    from frictex.textures.model import VisualHints

    def resonance(f_hz: float, r: float) -> list[float]:   # a stable AR(2) at 10 kHz
        return [1.0, -2.0 * r * np.cos(2.0 * np.pi * f_hz / 1e4), r * r]
    model = model_from_coefficients([20.0, 200.0, 20.0, 200.0], [0.2, 0.2, 2.0, 2.0],
                                    [[0, 1, 2], [1, 3, 2]],
                                    [resonance(f, 0.95) for f in (80.0, 150.0, 60.0, 300.0)],
                                    [1e-6, 2e-6, 0.5e-6, 1.5e-6])
    scene = load_scene(resolve_scene("grating-5mm"))
    layer = ArTextureLayer(name="recorded", render="sho", region=None, blend="multiply",
                           visual=VisualHints(), model=model)
    return replace(scene, layers=(*scene.layers, layer))


def height_shapes_scene():
    """grating-5mm with a height layer of every shape on top (the bundled height scenes
    have a bump, a ridge and a button; each shape has its own kernels)."""
    from dataclasses import replace

    import numpy as np

    from frictex.textures.heights import ButtonRim, GaussianBump, HeightLayer, HeightMap, Ridge, Step
    from frictex.textures.library import resolve_scene
    from frictex.textures.loader import load_scene
    from frictex.textures.model import VisualHints

    rows, cols = np.mgrid[0:16, 0:32]
    shapes = (GaussianBump(30.0, 32.4, 8.0, 1.0), Ridge(54.0, 32.4, 90.0, 6.0, 0.8),
              Step(70.0, 32.4, 0.0, 0.3, 2.0), ButtonRim(80.0, 32.4, 12.0, 4.0, 0.5),
              HeightMap(0.1 * np.sin(cols / 3.0) * np.cos(rows / 4.0), 0.0, 0.0, 108.0, 64.8))
    scene = load_scene(resolve_scene("grating-5mm"))
    layers = tuple(HeightLayer(name=f"height-{k}", render="sho", region=None, blend="multiply",
                               visual=VisualHints(), shape=shape) for k, shape in enumerate(shapes))
    return replace(scene, layers=(*scene.layers, *layers))


def overlay_geometry() -> None:
    """The demo's overlay kernels: two fingers' trails and their scope columns, drawn
    from a short stroke (no OpenGL: the geometry and the columns are numpy)."""
    import numpy as np

    from frictex.rendering.visual.overlay import BlockRecord, OverlayState
    from frictex.rendering.visual.scope_ring import scope_columns
    from frictex.rendering.visual.viewport import fit_viewport
    from frictex.textures.model import Display

    t = np.arange(200) / 2000.0
    x = np.stack((50.0 + 100.0 * t, 20.0 + 50.0 * t))
    overlay = OverlayState()
    overlay.add(BlockRecord(t, (0, 1), np.ones((2, t.size), bool), x, x / 2, np.ones((2, t.size)),
                            np.ones((2, t.size))))
    viewport = fit_viewport(Display(108.0, 64.8, 800, 480), 800, 480)
    overlay.trail_triangles(viewport)
    overlay.add(BlockRecord(t[-1:] + 0.1, (2,), np.ones((1, 1), bool), x[:1, :1], x[:1, :1],
                            np.ones((1, 1)), np.ones((1, 1))))  # a finger's first record of one sample
    overlay.trail_triangles(viewport)
    plots = ((0.0, 400.0, 800.0, 30.0), (0.0, 440.0, 800.0, 30.0))
    scope_columns(overlay, plots, 2.0, 0.01, 0, 10, 400.0, 70)


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--quiet", action="store_true", help="print nothing")


def run(args: argparse.Namespace) -> int:
    from frictex.app.engine.replay import run_replay
    from frictex.app.engine.tables import FORMATS
    from frictex.rendering.input.trace_synth import make_motion, sample
    from frictex.rendering.renderers import RENDERERS
    start = time.perf_counter()
    motion = make_motion("human", duration_s=1.0, seed=1)
    with tempfile.TemporaryDirectory(prefix="frictex-warm-") as tmp:
        for k, scene in enumerate(SCENES):
            for renderer in (None, *RENDERERS.names()) if k == 0 else (None,):
                for fmt in FORMATS if k == 0 and renderer is None else ("csv",):
                    run_replay(scene, sample(motion, 60.0, noise_mm=0.05, seed=2), tmp,
                               fmt=fmt, render_override=renderer, progress=False)
        for scene in (height_shapes_scene(), recorded_texture_scene()):
            run_replay(scene, sample(motion, 60.0, noise_mm=0.05, seed=2), tmp, progress=False)
        height_shapes_scene().layers[-1].mu_of_slope(0.0)  # the saturation alone (preview, tests)
        # the friction loop's kernels, on the force reports of a simulated finger
        run_replay("grating-15mm", sample(motion, 60.0, noise_mm=0.05, seed=2), tmp,
                   control="adaptive", device="sim", sim_args=("--finger", "3"),
                   progress=False)
    overlay_geometry()
    if not args.quiet:
        print(f"frictex: kernels compiled and cached ({time.perf_counter() - start:.1f} s)")
    return 0
