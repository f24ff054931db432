"""numba's ``njit``, compiled (or loaded from the cache) at a kernel's first use.

Importing numba costs 0.3-0.4 s of CPU and pulls in scipy; loading a cached kernel costs
a few milliseconds more. Kernels are defined beside the data they serve (a texture's
layer, a device's actuation), so a command that only reads texture files (``validate``,
``library``) would pay for every kernel of every module it imports. ``njit`` here
returns a stand-in that imports numba and builds the real dispatcher on its first call
or attribute access, then puts the dispatcher in its module's namespace in its place, so
that later calls from that module, and kernels compiled after it, see the dispatcher
itself. A cached kernel loaded from disk brings its callees' code with it: a callee that
nothing calls from Python is never built at all.

numba imports scipy at start-up only to check its version, and scipy.linalg (0.2 s) to
see whether BLAS is there; ``_import_numba`` skips both (scipy is a dependency, so BLAS
is there) and numba imports scipy.linalg itself when it compiles a call that needs it.
It also leaves out numba's typing of cffi functions (cffi and its C parser: 40 ms of
CPU a process), which no kernel here calls, unless cffi is loaded already.

Loading a kernel from numba's cache first refreshes numba's typing and lowering contexts
(every registry of every numba module: about 85 ms of a process's first load), which
only compiling uses, and numba's compiler refreshes them itself before it compiles. Where
no package extends numba, a kernel here loads from the cache after starting only what
the loaded machine code calls: numba's runtime (NRT).
"""

from __future__ import annotations

import functools
import importlib.abc
import importlib.util
import sys
import threading
from typing import Any, Callable

_lock = threading.RLock()
_typeof_registered = False
#: once numba is imported: whether no installed package extends it (an extension's
#: ``init`` may register what a cached kernel's code needs, so its refresh is kept)
_no_extensions: bool | None = None
#: numba's FunctionCache, loading without the refresh (see the module); built once
_cache_class = None


class LazyKernel:
    """A function to be compiled by ``numba.njit(**options)`` at its first use.

    Parameters
    ----------
    func : callable
        The Python function (numba's ``py_func``).
    options : dict
        ``numba.njit``'s keyword arguments (``cache``, ``nogil``, ``error_model``, ...).
    """

    def __init__(self, func: Callable, options: dict[str, Any]) -> None:
        self._func = func
        self._options = options
        self._kernel = None
        functools.update_wrapper(self, func)

    def kernel(self):
        """The numba dispatcher, built at the first call (thread-safe)."""
        if self._kernel is None:
            with _lock:
                if self._kernel is None:
                    numba = _import_numba()
                    _register_typeof()
                    self._kernel = numba.njit(**self._options)(self._func)
                    _load_without_refresh(self._kernel)
                    names = self._func.__globals__
                    if names.get(self._func.__name__) is self:
                        names[self._func.__name__] = self._kernel
        return self._kernel

    def __call__(self, *args, **kwargs):
        return self.kernel()(*args, **kwargs)

    def __getattr__(self, name: str):
        if name.startswith("__"):
            raise AttributeError(name)
        return getattr(self.kernel(), name)


#: packages numba imports at start-up that no kernel here needs
_LEFT_OUT = ("scipy", "cffi")


class _Refuse(importlib.abc.MetaPathFinder):
    """Refuses to import :data:`_LEFT_OUT` in the thread that made it, and in no other."""

    def __init__(self) -> None:
        self.thread = threading.get_ident()

    def find_spec(self, fullname, path=None, target=None):
        if fullname in _LEFT_OUT and threading.get_ident() == self.thread:
            raise ModuleNotFoundError(f"{fullname} is left out of numba's start-up",
                                      name=fullname)
        return None


def _import_numba():
    """numba, imported without scipy and cffi when scipy is not loaded yet (see the
    module)."""
    if "numba" not in sys.modules and "scipy" not in sys.modules:
        _import_numba_alone()
    import numba
    if _no_extensions is None:
        _numba_extensions_known()
    return numba


def _import_numba_alone() -> None:
    has_scipy = importlib.util.find_spec("scipy") is not None
    refuse = _Refuse()
    sys.meta_path.insert(0, refuse)
    try:
        import numba  # noqa: F401
        import numba.core.typing.cffi_utils  # noqa: F401 (its cffi support off, see the module)
        import numba.np.linalg as linalg
        ensure_blas = getattr(linalg, "ensure_blas", None)  # None: a numba that changed
        if ensure_blas is None:
            import numba.np.arraymath  # noqa: F401 (it probes BLAS its own way)
        else:
            linalg.ensure_blas = lambda: None if has_scipy else ensure_blas()
            try:
                import numba.np.arraymath
            finally:
                linalg.ensure_blas = ensure_blas
            numba.np.arraymath.ensure_blas = ensure_blas
    finally:
        sys.meta_path.remove(refuse)


def _numba_extensions_known() -> None:
    """numba reads every installed distribution's metadata again at its first compile, to
    run the ``init`` of each ``numba_extensions`` entry point (about 15 ms); frictex's
    registries have read it once already. Where no distribution has one, numba is told
    its extensions are loaded."""
    global _no_extensions
    from frictex.device.registry import entry_points_named
    _no_extensions = False
    if not entry_points_named("numba_extensions", "init"):
        entrypoints = importlib.import_module("numba.core.entrypoints")
        if hasattr(entrypoints, "_already_initialized"):  # else a numba that changed: it reads
            entrypoints._already_initialized = True
            _no_extensions = True


def _load_without_refresh(kernel) -> None:
    """Give ``kernel``'s cache a load that skips numba's context refresh (see the module),
    where numba's cache is the one this was written against and nothing extends numba."""
    global _cache_class
    from numba.core import caching
    cache = getattr(kernel, "_cache", None)
    if not _no_extensions or type(cache) is not caching.FunctionCache or not all(
            hasattr(cache, name) for name in ("_load_overload",
                                              "_guard_against_spurious_io_errors")):
        return  # an extended numba, no cache, or a numba that changed: numba's own load
    if _cache_class is None:
        _cache_class = type("FunctionCacheLoadingWithoutRefresh", (caching.FunctionCache,),
                            {"load_overload": _load_overload})
    cache.__class__ = _cache_class


def _load_overload(cache, sig, target_context):
    """numba's ``Cache.load_overload`` less its ``target_context.refresh()``: numba's
    runtime (NRT), which loaded code allocating arrays calls, is started instead. The
    other symbols such code links against (numba's C helpers, the hash secret) are added
    when numba is imported."""
    from numba.core.runtime import rtsys
    rtsys.initialize(target_context)
    with cache._guard_against_spurious_io_errors():
        return cache._load_overload(sig, target_context)
    return None  # the guard swallowed an I/O error: numba compiles instead, as its own load


def _register_typeof() -> None:
    """Teach numba that a stand-in met as a global in nopython code is its dispatcher."""
    global _typeof_registered
    if not _typeof_registered:
        from numba.extending import typeof_impl

        @typeof_impl.register(LazyKernel)
        def _typeof_lazy(value, context):
            return typeof_impl(value.kernel(), context)
        _typeof_registered = True


def njit(**options: Any) -> Callable[[Callable], LazyKernel]:
    """``numba.njit(**options)``, deferred to the kernel's first use (see the module)."""
    return functools.partial(LazyKernel, options=options)


def dispatcher(obj):
    """The numba dispatcher behind ``obj`` (built now), or ``obj`` itself if it is not a
    stand-in."""
    return obj.kernel() if isinstance(obj, LazyKernel) else obj
