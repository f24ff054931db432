"""numba's on-disk cache (``cache=True``) is keyed on the source file of the cached
function only: a cached kernel that calls (and so compiles in) a jitted function of
another module keeps running the old code after that module is edited. Every cached
kernel here calls jitted functions of its own module only. A kernel loaded from the
cache computes what it computed when compiled, loaded the way ``device.jit`` loads it."""

import importlib
import inspect
import json
import os
import subprocess
import sys
from pathlib import Path

import numpy as np
import pytest
from numba.core.registry import CPUDispatcher

from frictex.device.jit import dispatcher

ROOT = Path(__file__).resolve().parents[1]


def modules_with_kernels() -> list[str]:
    """Every project module whose source uses numba's njit."""
    found = []
    for top in ("app", "device", "rendering", "textures"):
        for path in sorted((ROOT / top).rglob("*.py")):
            if "njit" in path.read_text(encoding="utf-8"):
                found.append(".".join(path.relative_to(ROOT).with_suffix("").parts))
    return found


def foreign_calls(module):
    """(kernel, callee module.name) for every cached kernel of ``module`` naming a jitted
    function defined in another module."""
    found = []
    for name, obj in vars(module).items():
        obj = dispatcher(obj)
        if not (isinstance(obj, CPUDispatcher) and obj.__module__ == module.__name__
                and type(obj._cache).__name__ != "NullCache"):  # cache=True
            continue
        code_names = set()
        stack = [obj.py_func.__code__]
        while stack:
            code = stack.pop()
            code_names.update(code.co_names)
            stack.extend(c for c in code.co_consts if inspect.iscode(c))
        for ref in sorted(code_names):
            target = dispatcher(obj.py_func.__globals__.get(ref))
            if isinstance(target, CPUDispatcher) and target.__module__ != module.__name__:
                found.append((name, f"{target.__module__}.{ref}"))
    return found


@pytest.mark.parametrize("name", modules_with_kernels())
def test_cached_kernels_call_jitted_code_of_their_own_module_only(name):
    assert foreign_calls(importlib.import_module(name)) == []


def test_the_check_sees_a_foreign_call(tmp_path, monkeypatch):
    """A cached kernel calling another module's jitted function is found."""
    (tmp_path / "numba_cache_a.py").write_text(
        "from numba import njit\n@njit(cache=True)\ndef twice(x):\n    return 2 * x\n")
    (tmp_path / "numba_cache_b.py").write_text(
        "from numba import njit\nfrom numba_cache_a import twice\n"
        "@njit(cache=True)\ndef four(x):\n    return twice(twice(x))\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    module = importlib.import_module("numba_cache_b")
    assert foreign_calls(module) == [("four", "numba_cache_a.twice")]


KERNELS = """
import numpy as np
from frictex.device.jit import njit

@njit(cache=True)
def distinct_words(n):
    # a typed dict of strings: numba's runtime (NRT) and its hash secret's symbols
    seen = {}
    for i in range(n):
        seen[str(i % 7)] = i
    out = np.empty(len(seen), dtype=np.int64)
    for j, key in enumerate(sorted(seen.keys())):
        out[j] = seen[key]
    return out

@njit(cache=True)
def running_sum(x):
    return np.cumsum(x * 0.5)
"""

LOAD_PROBE = r"""
import json, sys
import numpy as np
from frictex.device import registry
if json.loads(sys.argv[1]):  # a distribution with a numba extension, as its metadata lists it
    import importlib.metadata as metadata
    point = metadata.EntryPoint("init", "json:dumps", "numba_extensions")
    registry.entry_points_named = lambda group, name: [point]
import cached_kernels as k
from frictex.device.jit import dispatcher
from numba.core.registry import cpu_target
refreshes = []
real = cpu_target.target_context.refresh
cpu_target.target_context.refresh = lambda: refreshes.append(1) or real()
words = k.distinct_words(20)
sums = k.running_sum(np.arange(5.0))
kernel = dispatcher(k.distinct_words)
print(json.dumps({"words": words.tolist(), "sums": sums.tolist(),
                  "hits": sum(kernel.stats.cache_hits.values()),
                  "cache": type(kernel._cache).__name__, "refreshes": len(refreshes)}))
"""


def load_in_fresh_process(folder: Path, extension: bool) -> dict:
    done = subprocess.run([sys.executable, "-c", LOAD_PROBE, json.dumps(extension)],
                          capture_output=True, text=True, timeout=600, cwd=folder,
                          env={**os.environ, "PYTHONPATH": str(folder)})
    assert done.returncode == 0, done.stderr
    return json.loads(done.stdout.strip().splitlines()[-1])


def expected_results() -> dict:
    words = {}
    for i in range(20):
        words[str(i % 7)] = i
    return {"words": [words[key] for key in sorted(words)],
            "sums": np.cumsum(np.arange(5.0) * 0.5).tolist()}


@pytest.fixture(scope="module")
def compiled_kernels(tmp_path_factory) -> Path:
    """A folder with the kernels' module, compiled once (and cached) in a fresh process."""
    folder = tmp_path_factory.mktemp("kernels")
    (folder / "cached_kernels.py").write_text(KERNELS)
    compiled = load_in_fresh_process(folder, False)
    assert compiled["hits"] == 0
    assert {key: compiled[key] for key in expected_results()} == expected_results()
    return folder


@pytest.mark.parametrize("extension", [False, True])
def test_a_cached_kernel_loads_without_the_context_refresh_and_computes_the_same(
        compiled_kernels, extension):
    """``device.jit`` loads a cached kernel without numba's context refresh unless a
    package extends numba. A kernel whose code needs numba's runtime and the hash secret
    (a dict of strings, arrays made) computes, loaded so, what Python computes; with an
    extension installed, numba's own load (and its refresh) is kept."""
    loaded = load_in_fresh_process(compiled_kernels, extension)
    assert {key: loaded[key] for key in expected_results()} == expected_results()
    assert loaded["hits"] == 1
    if extension:
        assert loaded["cache"] == "FunctionCache" and loaded["refreshes"] >= 1
    else:
        assert loaded["cache"] == "FunctionCacheLoadingWithoutRefresh"
        assert loaded["refreshes"] == 0
