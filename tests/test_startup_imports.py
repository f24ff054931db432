"""A command imports only what it uses: each command runs in a fresh process, which then
names the heavy packages it has loaded (``sys.modules``). No timing is asserted."""

import json
import subprocess
import sys

import pytest

HEAVY = ("numba", "llvmlite", "scipy", "matplotlib", "moderngl", "glfw", "pyarrow", "dask", "cffi",
         "pycparser")

PROBE = r"""
import json, sys
from frictex.app.commands.cli import main
try:
    code = main(json.loads(sys.argv[1]))
except SystemExit as exc:   # --version exits through argparse
    code = exc.code
print(json.dumps({"code": code, "loaded": sorted({m.split(".")[0] for m in sys.modules})}))
"""


def loaded_after(argv: list[str]) -> set[str]:
    """The heavy top-level packages in ``sys.modules`` after ``frictex ARGV`` ran."""
    done = subprocess.run([sys.executable, "-c", PROBE, json.dumps(argv)], capture_output=True,
                          text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    result = json.loads(done.stdout.strip().splitlines()[-1])
    assert result["code"] == 0, done.stderr
    return set(result["loaded"]) & set(HEAVY)


@pytest.mark.parametrize("argv", [["--version"], ["library"]])
def test_commands_that_compute_nothing_import_no_compiler(argv):
    assert loaded_after(argv) == set()


def test_a_parquet_replay_imports_pyarrow_and_numba_only(tmp_path):
    argv = ["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(tmp_path / "run"),
            "--format", "parquet", "--quiet"]
    assert loaded_after(argv) == {"numba", "llvmlite", "pyarrow"}


@pytest.mark.parametrize("fmt", ["csv", "npz"])
def test_a_text_or_npz_replay_imports_no_pyarrow(tmp_path, fmt):
    argv = ["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(tmp_path / "run"),
            "--format", fmt, "--quiet"]
    assert loaded_after(argv) == {"numba", "llvmlite"}


def test_a_kernel_compiled_after_the_lazy_import_can_use_blas():
    """numba is imported without scipy.linalg (``device.jit``); a kernel calling BLAS still
    compiles, numba importing scipy.linalg then."""
    probe = ("import numpy as np\n"
             "from frictex.device.jit import njit\n"
             "@njit()\n"
             "def dot(a, b):\n"
             "    return np.dot(a, b)\n"
             "print(dot(np.arange(3.0), np.arange(3.0)))\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "5.0"


def test_reading_a_scene_loads_no_kernel():
    """Texture modules define kernels beside their layers (``device.jit``): loading every
    kind of scene builds none of them and imports no numba."""
    probe = ("import sys\n"
             "from frictex.textures.library import resolve_scene\n"
             "from frictex.textures.loader import load_scene\n"
             "for name in ('grating-5mm', 'height-button', 'slider-clips', 'keyclick-ring'):\n"
             "    load_scene(resolve_scene(name))\n"
             "print(sorted(m for m in ('numba', 'scipy') if m in sys.modules))\n")
    done = subprocess.run([sys.executable, "-c", probe], capture_output=True, text=True,
                          timeout=600)
    assert done.returncode == 0, done.stderr
    assert done.stdout.strip() == "[]"


NUMBA_EXTENSIONS_PROBE = r"""
import importlib.metadata as metadata, json, sys
import numpy as np
from frictex.device import registry
from frictex.device.jit import njit
registry.entry_points_named("frictex.renderers", "sho")  # the registries' one reading
if json.loads(sys.argv[1]):  # a distribution with a numba extension, as its metadata lists it
    point = metadata.EntryPoint("init", "json:dumps", "numba_extensions")
    registry.entry_points_named = lambda group, name: [point]
reads = []
real = metadata.entry_points
metadata.entry_points = lambda *a, **k: reads.append(1) or real(*a, **k)
@njit()
def twice(x):
    return 2.0 * x
twice(np.float64(1.5))
print(json.dumps(len(reads)))
"""


@pytest.mark.parametrize("extension", [False, True])
def test_numba_reads_the_installed_metadata_again_only_for_an_extension(extension):
    """frictex's registries read every distribution's entry points once (here, before
    the count starts); numba would read them all again at its first compile to run its
    extensions' ``init``. With none installed it is told they are loaded (no second
    reading); with one, it reads and runs them as it would without frictex."""
    done = subprocess.run([sys.executable, "-c", NUMBA_EXTENSIONS_PROBE, json.dumps(extension)],
                          capture_output=True, text=True, timeout=600)
    assert done.returncode == 0, done.stderr
    reads = json.loads(done.stdout.strip().splitlines()[-1])
    assert reads == (1 if extension else 0)
