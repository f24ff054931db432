"""A user's script type-checks against frictex's typed API with ``mypy --strict``, and a
misspelt name or a wrong argument type in it is an error (the API's names are explicit
exports; nothing public is ``Any`` but the pyarrow tables, ``Replay.friction`` and
``Replay.commands``: pyarrow ships no type information, so a checker takes them on trust).

mypy reads the source tree, not the editable install (whose import hook it cannot
follow): a temporary folder holds a package ``frictex`` laid out as the wheel installs it
(pyproject.toml's ``package-dir``), made of links into the checkout, on ``MYPYPATH``.
``--follow-imports=silent``: frictex's own modules are read for their types, not checked
to --strict themselves.
"""

import os
import subprocess
import sys
import textwrap
import tomllib
from pathlib import Path

import pytest

import frictex

pytest.importorskip("mypy", reason="mypy is not installed (pip install 'frictex[test]')")

ROOT = Path(__file__).resolve().parents[1]

USER_SCRIPT = '''\
from __future__ import annotations

from pathlib import Path

import numpy as np
import numpy.typing as npt

import frictex


def mean_mu(out: frictex.BlockOutput) -> float:
    mu: npt.NDArray[np.float64] = out.mu_target
    return float(mu[out.contact].mean())


def mu_per_finger(out: frictex.BlockOutput) -> dict[int, float]:
    return {finger: float(out.mu_target[row, lo:hi].mean())
            for row, finger, lo, hi in out.segments()}


def main(folder: Path) -> None:
    scene: frictex.Scene = frictex.load_scene("grating-5mm")
    trace: frictex.Trace = frictex.read_trace("swipe-40mms-50hz")
    synth: frictex.Trace = frictex.synth_trace("human", rate_hz=120.0, duration_s=1.0, seed=3)
    pipe: frictex.Pipeline = frictex.build_pipeline(scene, rate_hz=10_000.0)
    # numpy integers are taken where a whole number is (as numpy floats are where a float is)
    pipe = frictex.build_pipeline(scene, rate_hz=np.float64(1e4), block_size=np.int64(100))
    synth = frictex.synth_trace("swipe", seed=np.int64(3))
    frictex.replay(scene, synth, block_size=np.int32(50))
    out: frictex.BlockOutput = pipe.process(synth)
    channels: tuple[str, ...] = pipe.channels
    r: frictex.Replay = frictex.replay(scene, trace, out=folder, format="npz", renderer="sht")
    s: frictex.Summary = r.summary
    contact: int = s.counts.contact_samples
    files: tuple[str, ...] = s.output.files
    name: str = s.scene.name
    rows: int = r.friction.num_rows
    columns: list[str] = r.commands.column_names
    clamps: frictex.Clamps = s.clamps
    codes: tuple[int, int, int] = (frictex.DOWN, frictex.MOVE, frictex.UP)
    version: str = frictex.__version__
    try:
        frictex.load_scene("no-such-scene")
    except frictex.InputError as error:
        print(error)
    print(mean_mu(out), mu_per_finger(out), channels, contact, files, name, rows, columns, clamps.total, codes,
          version, s.to_dict())


def run_kept(error: frictex.DeviceError) -> frictex.Replay | None:
    return error.replay
'''

#: (line, what mypy must say there) of each mistake in MISTAKES
MISTAKES = '''\
import frictex

scene = frictex.load_scene("grating-5mm")
frictex.replya(scene, "swipe-40mms-50hz")
frictex.build_pipeline(scene, rate_hz="10 kHz")


def ahead(block: frictex.FingerBlock) -> float:
    return float(block.x_pread.max())
'''
EXPECTED = [
    (4, 'Module has no attribute "replya"; maybe "replay"?  [attr-defined]'),
    (5, 'Argument "rate_hz" to "build_pipeline" has incompatible type "str"; expected "float"'
        '  [arg-type]'),
    # a renderer's block: its fields are typed, not Any
    (9, '"FingerBlock" has no attribute "x_pread"; maybe "x_pred" or "y_pred"?  [attr-defined]'),
]


def source_tree(folder: Path) -> Path:
    """``folder/frictex``, the package as pyproject.toml's ``package-dir`` installs it,
    made of links to the checkout's files and folders; returns ``folder``."""
    setup = tomllib.loads((ROOT / "pyproject.toml").read_text(encoding="utf-8"))
    dirs = setup["tool"]["setuptools"]["package-dir"]
    top = folder / "frictex"
    top.mkdir(parents=True)
    for entry in (ROOT / dirs["frictex"]).iterdir():
        (top / entry.name).symlink_to(entry)
    for package, where in dirs.items():
        if package != "frictex":
            (top / package.removeprefix("frictex.")).symlink_to(ROOT / where)
    return folder


@pytest.fixture(scope="module")
def checker(tmp_path_factory):
    """mypy --strict on a script (a path relative to its folder), the source tree and the
    cache shared by this module's tests."""
    shared = tmp_path_factory.mktemp("mypy")
    env = {**os.environ, "MYPYPATH": str(source_tree(shared / "src"))}
    env.pop("PYTHONPATH", None)

    def check(script: Path) -> subprocess.CompletedProcess:
        return subprocess.run([sys.executable, "-m", "mypy", "--strict",
                               "--follow-imports=silent", "--no-error-summary",
                               "--cache-dir", str(shared / "cache"), script.name],
                              capture_output=True, text=True, env=env, cwd=script.parent,
                              timeout=300)
    return check


def test_a_user_s_script_passes_mypy_strict(tmp_path, checker):
    script = tmp_path / "use.py"
    script.write_text(USER_SCRIPT, encoding="utf-8")
    done = checker(script)
    assert (done.returncode, done.stdout, done.stderr) == (0, "", "")


def test_a_misspelt_name_and_a_wrong_argument_type_are_errors(tmp_path, checker):
    script = tmp_path / "mistakes.py"
    script.write_text(MISTAKES, encoding="utf-8")
    done = checker(script)
    assert done.returncode == 1, done.stderr
    assert done.stdout.splitlines() == [f"mistakes.py:{line}: error: {message}"
                                        for line, message in EXPECTED]


def test_the_user_script_runs(tmp_path):
    """The script the first test checks is one that works."""
    code = USER_SCRIPT + textwrap.dedent(f'''
        main(Path({str(tmp_path / "out")!r}))
    ''')
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          cwd=tmp_path, timeout=300)
    assert done.returncode == 0, done.stderr
    error, printed = done.stdout.splitlines()
    assert error.startswith("no-such-scene: no such file")
    assert "('commands.npz', 'friction.npz') grating-5mm" in printed


LAYERS_SCRIPT = '''\
from __future__ import annotations

import dataclasses

import frictex
from frictex.textures.heights import HeightLayer


def periods_mm(scene: frictex.Scene) -> list[float]:
    return [layer.period_mm for layer in scene.layers if layer.is_periodic]


def with_height(scene: frictex.Scene, height: HeightLayer) -> frictex.Scene:
    return dataclasses.replace(scene, layers=scene.layers + (height,))


def finer(scene: frictex.Scene) -> frictex.Scene:
    layers = tuple(dataclasses.replace(layer, period_mm=layer.period_mm / 2)
                   if layer.is_periodic else dataclasses.replace(layer, blend="replace")
                   for layer in scene.layers)
    return dataclasses.replace(scene, layers=layers)
'''


def test_a_scenes_layers_are_told_apart_by_is_periodic(tmp_path, checker):
    """README's ``if layer.is_periodic: layer.period_mm`` failed (no period_mm on 8 of the
    union's classes), and a height, clip or AR texture layer was no ``Scene.layers`` item;
    ``dataclasses.replace`` of a layer was refused ("Value of type variable
    "_DataclassT" of "replace" cannot be "PeriodicLayer"")."""
    script = tmp_path / "layers.py"
    script.write_text(LAYERS_SCRIPT, encoding="utf-8")
    done = checker(script)
    assert (done.returncode, done.stdout, done.stderr) == (0, "", "")
    namespace: dict = {}
    exec(LAYERS_SCRIPT, namespace)
    assert namespace["periods_mm"](frictex.load_scene("grating-5mm")) == [5.0]
    assert namespace["periods_mm"](namespace["finer"](frictex.load_scene("grating-5mm"))) == [2.5]
