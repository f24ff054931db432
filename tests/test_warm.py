"""After setup (``frictex warm``) no run compiles a kernel: every numba kernel a replay
calls, and those of a demo frame's overlay (trails, scope columns, force arrows), is
loaded from the cache (numba's own hit and miss counters, in a fresh process)."""

import json
import subprocess
import sys

PROBE = r"""
import gc, json, sys
from numba.core.registry import CPUDispatcher
from frictex.app.commands.cli import main
for scene, trace in [("composed-fine-grating-in-disc", "circle-30mms-60hz"),
                     ("two-finger-beam-seed000", "two-fingers-crossing-50hz"),
                     ("keyclick-ring", "keyclick-press-100hz")]:
    for fmt in ("csv", "parquet"):
        assert main(["replay", scene, trace, "--out", sys.argv[1], "--format", fmt,
                     "--quiet"]) == 0
from frictex.app.commands.warm import height_shapes_scene, recorded_texture_scene
from frictex.app.engine.replay import run_replay
for scene in (height_shapes_scene(), recorded_texture_scene()):
    run_replay(scene, "circle-30mms-60hz", sys.argv[1], progress=False)
run_replay("grating-15mm", "circle-30mms-60hz", sys.argv[1], control="adaptive", device="sim",
           sim_args=("--finger", "3"), progress=False)
from frictex.app.measure.bench_visual import bench_scene, busy_overlay
import numpy as np
from frictex.rendering.visual.overlay import BlockRecord, arrow_triangles
from frictex.rendering.visual.scope_ring import scope_columns
from frictex.rendering.visual.viewport import fit_viewport
overlay = busy_overlay()
overlay.trail_triangles(fit_viewport(bench_scene().display, 1920, 1080))
one = np.ones((1, 1))
overlay.add(BlockRecord(np.array([overlay.now_s + 0.01]), (7,), one > 0, 50 * one, 30 * one, one, one))
overlay.trail_triangles(fit_viewport(bench_scene().display, 1920, 1080))  # a one-sample finger
scope_columns(overlay, ((0.0, 830.5, 1920.0, 90.0), (0.0, 950.5, 1920.0, 90.0)), 3.0,
              3.0 / 1920, 1500, 40, 830.5, 210)
arrow_triangles((10.0, 10.0), (5.0, 3.0), (1.0, 1.0, 1.0, 1.0), 2.0)
ours = [d for d in gc.get_objects() if isinstance(d, CPUDispatcher)
        and d.py_func.__module__.startswith("frictex.")]
print(json.dumps({"hits": sum(sum(d.stats.cache_hits.values()) for d in ours),
                  "misses": [f"{d.py_func.__module__}.{d.py_func.__name__}" for d in ours
                             if d.stats.cache_misses]}))
"""


def test_a_replay_after_setup_compiles_nothing(tmp_path):
    done = subprocess.run([sys.executable, "-c", PROBE, str(tmp_path)], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    counts = json.loads(done.stdout.strip().splitlines()[-1])
    assert counts["misses"] == [], ("kernels compiled during a run (setup runs `frictex warm`; "
                                    f"run it after changing a kernel): {counts['misses']}")
    assert counts["hits"] >= 4  # the tracker, a renderer, the CSV writer at least
