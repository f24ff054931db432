"""``frictex warm``: compile the pipeline's kernels now, once per install.

The per-sample kernels (tracking, SHT phase, the hybrid, modal actuation, height layers
and effect clips, the CSV writer) are compiled by numba on first use and cached beside their sources; setup runs
this so that no replay, demo or test pays the compilation. It replays a short synthetic
stroke on one bundled scene of each kind of device into a temporary folder, in every
output format.
"""

from __future__ import annotations

import argparse
import tempfile
import time

#: one scene per kind of actuation and renderer the kernels serve
SCENES = ("composed-fine-grating-in-disc", "grating-5mm", "two-finger-beam-seed000",
          "two-finger-plate-seed001", "directional-beam", "keyclick-ring", "height-button",
          "slider-clips")


def add_arguments(parser: argparse.ArgumentParser) -> None:
    parser.add_argument("--quiet", action="store_true", help="print nothing")


def run(args: argparse.Namespace) -> int:
    from app.engine.replay import run_replay
    from app.engine.tables import FORMATS
    from rendering.input.trace_synth import make_motion, sample
    from rendering.pipeline import RENDERERS
    start = time.perf_counter()
    motion = make_motion("human", duration_s=1.0, seed=1)
    with tempfile.TemporaryDirectory(prefix="frictex-warm-") as tmp:
        for k, scene in enumerate(SCENES):
            for renderer in (None, *RENDERERS) if k == 0 else (None,):
                for fmt in FORMATS if k == 0 and renderer is None else ("csv",):
                    run_replay(scene, sample(motion, 60.0, noise_mm=0.05, seed=2), tmp,
                               fmt=fmt, render_override=renderer, progress=False)
    if not args.quiet:
        print(f"frictex: kernels compiled and cached ({time.perf_counter() - start:.1f} s)")
    return 0
