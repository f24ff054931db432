"""numba's on-disk cache (``cache=True``) is keyed on the source file of the cached
function only: a cached kernel that calls (and so compiles in) a jitted function of
another module keeps running the old code after that module is edited. Every cached
kernel here calls jitted functions of its own module only."""

import importlib
import inspect
from pathlib import Path

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
