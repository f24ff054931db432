"""Registries by name: how frictex's extension points find their implementations.

Each extension point (renderer, touch source, output device, actuation, clock, sink,
window backend) is a ``typing.Protocol`` in the module that uses it, and a
:class:`Registry` beside it. frictex's own implementations register there by name; other
packages add theirs through an entry-point group:

.. code-block:: toml

    # a plugin's pyproject.toml
    [project.entry-points."frictex.renderers"]
    wobble = "frictex_wobble:WobbleRenderer"

The group's entry points are read (not imported) the first time the registry is asked
for a name or its names (the installed metadata once per process for every registry),
and read again by every lookup (:meth:`Registry.get`, :meth:`Registry.names`, ``in``)
once a folder of ``sys.path`` has changed (its modification time: a package installed
since, as ``%pip install`` in a running notebook does) or the path itself has, and
whenever a name is not found; an entry point's object is imported the first time its
name is looked up, so listing the names imports no plugin. A registry whose names belong to a lower
layer than its implementations (the renderers, which texture files name) gets frictex's
own entries from frictex's own entry points, as a plugin would: the lower layer then lists
them without importing the higher one.

Another package's entry point is refused on its own, never breaking the rest: one whose
name is malformed, reserved (:attr:`Registry.reserved`, such as the renderer ``sho``) or
already taken is left out with a one-line warning on stderr (``frictex: warning: ...``,
once per process); one that cannot be imported, or whose object is not what the registry
holds (its ``expect``: a device profile that is a dict), is a :class:`PluginError` when its
name is used, and is left out with such a warning where every entry is needed at once
(:meth:`Registry.loaded`; :meth:`Registry.loadable_names` for a command's choices). A
built-in registered after a plugin took its name replaces it (the plugin is refused, with
the warning). :meth:`Registry.register` called from code outside frictex's own modules (a
notebook's ``RENDERERS.register("wobble", Wobble)``) is another package's entry too: the
same checks when registered, the same wrapping when used; that module may register the
name again to replace its own entry.

Every list of names a user sees (command-line choices, the demo's key cycle, the report's
matrix, texture-file validation, the docs) is ``registry.names()``; an unknown name is an
:class:`UnknownName` (an :class:`~frictex.device.errors.InputError`) that lists the known
ones. This module is in the lowest layer so that every layer can register into it.
"""

from __future__ import annotations

import functools
import os
import sys
import threading
from collections.abc import Callable, Iterator
from dataclasses import dataclass
from typing import Any, Generic, TypeVar, overload

from frictex.device.errors import FrictexError, InputError

T = TypeVar("T")

#: the distribution whose entry points are frictex's own (listed first)
OWN_DISTRIBUTION = "frictex"


class UnknownName(InputError, KeyError):
    """A name no implementation is registered under."""

    def __str__(self) -> str:  # KeyError would quote the whole message
        return str(self.args[0])


class PluginError(FrictexError, RuntimeError):
    """An entry point of another package that cannot be loaded, or clashes with a name
    already registered."""


_WARNED: set[str] = set()  # the warnings printed by this process


def guarded(who: str, doing: str, call: Callable[..., T], *args) -> T:
    """``call(*args)``, where ``call`` is another package's code: what it raises becomes a
    :class:`PluginError` saying ``who`` failed ``doing`` what (one line, exit 1), so that
    a plugin's bug is not reported as frictex's; frictex's own errors it raises
    (:class:`~frictex.device.errors.FrictexError`: an ``InputError`` for a bad argument, a
    ``DeviceError``) pass as they are."""
    try:
        return call(*args)
    except FrictexError:
        raise
    except Exception as exc:  # noqa: BLE001 -- a plugin's bug, told as the plugin's
        raise PluginError(f"{who} failed {doing}: {type(exc).__name__}: {exc}") from exc


def build_entry(registry: Registry, kind: str, name: str, arg: str, request, *,
                doing: str, members: tuple[str, ...], contract: str, wrap,
                release: str | None = None):
    """Entry ``name`` of ``registry`` (a factory) called with ``(arg, request)``: frictex's
    own as it returns it; another package's through :func:`guarded` (what it raises names
    it, ``"{kind} {name!r} of {distribution}"``), checked to have ``members`` (``"m()"``
    a method, ``"m"`` any attribute; else a :class:`PluginError` saying which are
    missing and that ``contract`` was expected, after calling its method ``release``
    where given, to free what it opened) and returned as ``wrap(built, who)``."""
    factory = registry.get(name)
    origin = registry.origin(name)
    if origin == OWN_DISTRIBUTION:
        return factory(arg, request)
    who = f"{kind} {name!r} of {origin}"
    built = guarded(who, doing, factory, arg, request)
    missing = [m for m in members if not (callable(getattr(built, m[:-2], None))
                                          if m.endswith("()") else hasattr(built, m))]
    if missing:
        if release is not None:
            try:
                getattr(built, release)()
            except Exception:  # noqa: BLE001 -- the missing members are the error to tell
                pass
        raise PluginError(f"{who} returned a {type(built).__name__} without "
                          f"{', '.join(missing)}; expected {contract}")
    return wrap(built, who)


def warn_once(message: str) -> None:
    """``message`` on stderr as one line, ``frictex: warning: ...`` (control characters
    escaped), the first time this process says it."""
    if message in _WARNED:
        return
    _WARNED.add(message)
    text = "".join(ch if ch.isprintable() else ch.encode("unicode_escape").decode("ascii")
                   for ch in message)
    print(f"frictex: warning: {text}", file=sys.stderr, flush=True)


#: held while the installed metadata is read and while a registry's entries are read or
#: changed: the threads of one process (a Dask worker runs a job on each of its threads)
#: saw another's scan half done, its names not yet added ("unknown renderer 'sht'")
_LOCK = threading.RLock()


def _locked(method):
    """``method`` run holding :data:`_LOCK`."""
    @functools.wraps(method)
    def run(*args, **kwargs):
        with _LOCK:
            return method(*args, **kwargs)
    return run


_INSTALLED = None  # importlib.metadata's entry points of every installed distribution
_GROUPS: dict[str, list] = {}  # those of each group asked for, from _INSTALLED
_STAMP: tuple = ()  # sys.path and its folders' modification times when _INSTALLED was read
_READINGS = 0  # how many times _INSTALLED was read (a registry scans again after another)


def _path_stamp() -> tuple:
    """``sys.path`` with each folder's modification time (ns; None where it cannot be
    read): installing a package into a folder adds its dist-info there, which changes the
    time. A few microseconds per folder."""
    stamp = []
    for folder in sys.path:
        try:
            stamp.append((folder, os.stat(folder or ".").st_mtime_ns))
        except (OSError, TypeError, ValueError):
            stamp.append((folder, None))
    return tuple(stamp)


@_locked
def _read_installed(fresh: bool = False) -> int:
    """Read every installed distribution's entry points (about 20 ms) the first time, when
    ``fresh`` (a name not found) and when :func:`_path_stamp` has changed since the last
    reading (a package installed since); returns the number of readings so far."""
    global _INSTALLED, _STAMP, _READINGS
    stamp = _path_stamp()
    if _INSTALLED is None or fresh or stamp != _STAMP:
        import importlib
        from importlib.metadata import entry_points
        if _INSTALLED is not None:
            importlib.invalidate_caches()
        _INSTALLED = entry_points()  # 3.11: SelectableGroups, 3.12: EntryPoints; both select
        _GROUPS.clear()
        _STAMP = stamp
        _READINGS += 1
    return _READINGS


@_locked
def _entry_points(group: str, fresh: bool) -> list:
    """The installed entry points of ``group``, from the one reading of the installed
    metadata every registry shares (:func:`_read_installed`)."""
    _read_installed(fresh)
    if group not in _GROUPS:
        _GROUPS[group] = list(_INSTALLED.select(group=group))
    return _GROUPS[group]


def entry_points_named(group: str, name: str) -> list:
    """The installed entry points of ``group`` called ``name``, from the one reading of
    the installed metadata every registry shares (:func:`_entry_points`)."""
    return [point for point in _entry_points(group, False) if point.name == name]


def _distribution(point) -> str:
    return point.dist.name if point.dist is not None else "?"


def _a(value: object) -> str:
    """What ``value`` is, for a message: "a dict", "the int 42"."""
    if isinstance(value, type):
        return f"the class {value.__module__}.{value.__qualname__}"
    if isinstance(value, int | float | str | bool) or value is None:
        return f"the {type(value).__name__} {value!r}"[:80]
    return f"a {type(value).__name__}"


def _from_a_signal(exc: BaseException) -> bool:
    """Whether ``exc``, raised in a plugin's import, came from a signal (Ctrl-C's
    ``KeyboardInterrupt``; a subclass of ``SystemExit``, as ``app.engine.driver.Terminated``
    for SIGTERM and SIGHUP) rather than from the plugin: a plain ``SystemExit`` is a
    script's ``sys.exit()`` or ``argparse`` at module level, a broken plugin."""
    return isinstance(exc, KeyboardInterrupt) or (isinstance(exc, SystemExit)
                                                  and type(exc) is not SystemExit)


@dataclass(frozen=True)
class _Unloaded:
    """An entry point not imported yet (``importlib.metadata``'s, or the backport's where
    a package installs ``importlib_metadata``'s finder: the same interface)."""

    point: Any


@dataclass(frozen=True)
class Expect:
    """What a registry's entries must be: ``test(entry)`` true; ``what`` says it in
    messages ("a frictex.device.profile.ProfileSpec"). Another package's entry that is not
    is refused when loaded (:class:`PluginError`), before frictex uses it."""

    test: Callable[[Any], bool]
    what: str

    @classmethod
    def instance_of(cls, kind: type) -> Expect:
        """Entries that are instances of ``kind``."""
        return cls(lambda entry: isinstance(entry, kind),
                   f"a {kind.__module__}.{kind.__qualname__}")

    @classmethod
    def factory(cls, what: str) -> Expect:
        """Entries that are called (a class or a function); ``what`` says its call."""
        return cls(callable, what)


class Registry(Generic[T]):
    """Implementations of one extension point, by name.

    Parameters
    ----------
    kind : str
        What the entries are, for messages ("renderer", "output device").
    group : str
        The entry-point group other packages register under ("frictex.renderers").
    reserved : iterable of str, optional
        Names no other package may register (a name that means something else where the
        registry's names are offered, such as ``sho`` beside the renderers).
    expect : Expect or None, optional
        What another package's entry must be, checked when it is loaded; None: anything.
    """

    def __init__(self, kind: str, group: str, reserved=(), expect: Expect | None = None):
        self.kind = kind
        self.group = group
        self.reserved = frozenset(reserved)
        self.expect = expect
        self._entries: dict[str, T | _Unloaded] = {}
        self._origin: dict[str, str] = {}
        self._registered_by: dict[str, str] = {}  # name -> module outside frictex (register)
        self._readings = 0  # the reading of the installed metadata last scanned (none: 0)

    @overload
    def register(self, name: str) -> Callable[[T], T]: ...

    @overload
    def register(self, name: str, entry: T) -> T: ...

    def register(self, name, entry=None):
        """Register ``entry`` under ``name`` (or use as a decorator). A name frictex
        registers twice is an error; one a plugin took is frictex's (the plugin refused
        with a warning): a plugin cannot replace a built-in. Code outside frictex's own
        modules (a notebook, another package) registers as a plugin would: a reserved
        name or an entry that is not the registry's ``expect`` is a :class:`PluginError`,
        and its entry is used as a plugin's (:func:`build_entry`), origin
        ``"{module} ({entry's name})"``. Such a module may register a name again to replace
        its own entry (a notebook's renderer, edited and registered anew); a name that
        frictex or another package or module registered stays a :class:`PluginError`."""
        # who registers is the calling module; taken here, as the decorator is called later
        caller = sys._getframe(1).f_globals.get("__name__", "?")
        if entry is None:
            return lambda obj: self._register(name, obj, caller)
        return self._register(name, entry, caller)

    @_locked
    def _register(self, name: str, entry: T, caller: str) -> T:
        """:meth:`register` ``entry``, called from module ``caller``."""
        if caller == OWN_DISTRIBUTION or caller.startswith(OWN_DISTRIBUTION + "."):
            self._add(name, entry, OWN_DISTRIBUTION)
            return entry
        origin = f"{caller} ({getattr(entry, '__name__', type(entry).__name__)})"
        if self.expect is not None and not self.expect.test(entry):
            raise PluginError(f"{self.kind} {name!r} from {origin} is {_a(entry)}; "
                              f"expected {self.expect.what}")
        if self._registered_by.get(name) == caller:  # its own entry, edited: replaced
            self._entries[name], self._origin[name] = entry, origin
            return entry
        self._add(name, entry, origin)
        self._registered_by[name] = caller
        return entry

    def _add(self, name: str, entry, origin: str) -> None:
        if (not isinstance(name, str) or not name or ":" in name
                or any(ch.isspace() or not ch.isprintable() for ch in name)):
            raise PluginError(f"{self.kind} name {name!r} from {origin}: expected a "
                              "non-empty name without spaces or ':'")
        if name in self.reserved and origin != OWN_DISTRIBUTION:
            raise PluginError(f"{self.kind} {name!r} from {origin}: the name is reserved")
        known = self._entries.get(name)
        if known is not None and known is not entry and known != entry:
            if origin == OWN_DISTRIBUTION and self._origin[name] != OWN_DISTRIBUTION:
                warn_once(f"{self.kind} {name!r} from {self._origin[name]} is refused: the "
                          "name is frictex's own")
                self._entries[name], self._origin[name] = entry, origin
                self._registered_by.pop(name, None)
                return
            raise PluginError(f"{self.kind} {name!r} from {origin} is already registered "
                              f"by {self._origin[name]}")
        self._entries.setdefault(name, entry)
        self._origin.setdefault(name, origin)

    @_locked
    def scan(self, fresh: bool = False) -> None:
        """Read the group's entry points (without importing them): frictex's own first,
        then the other distributions' by name; ``fresh``: read the installed metadata
        again. A name already known from the same entry point is kept; another package's
        entry point under a known, reserved or malformed name is refused with a warning
        (module docstring)."""
        readings = _read_installed(fresh)
        points = sorted(_entry_points(self.group, False),
                        key=lambda p: (_distribution(p) != OWN_DISTRIBUTION, _distribution(p)))
        for point in points:
            dist = _distribution(point)
            origin = dist if dist == OWN_DISTRIBUTION else f"{dist} ({point.value})"
            if self._origin.get(point.name) == origin:
                continue  # this entry point, seen before (perhaps loaded since)
            try:
                self._add(point.name, _Unloaded(point), origin)
            except PluginError as exc:
                if dist == OWN_DISTRIBUTION:
                    raise  # frictex's own metadata: a bug, not a plugin's
                warn_once(f"{exc}; left out")
        self._readings = readings  # only now: every entry read is in place

    def _load(self, name: str) -> T:
        """The object of entry ``name``, imported the first time. The import runs without
        :data:`_LOCK`: a module registers into a registry as it is imported, so a thread
        importing it while another held the lock across its import waited for each other
        for ever; the first object stored is the one every thread gets."""
        with _LOCK:
            entry, origin = self._entries[name], self._origin[name]
        if not isinstance(entry, _Unloaded):
            return entry
        try:
            loaded = entry.point.load()
        except BaseException as exc:  # a broken plugin names itself, not frictex
            if _from_a_signal(exc):
                raise
            raise PluginError(f"{self.kind} {name!r} of {origin} cannot be "
                              f"loaded: {type(exc).__name__}: {exc}") from exc
        if self.expect is not None and not self.expect.test(loaded):
            raise PluginError(f"{self.kind} {name!r} of {origin} is "
                              f"{_a(loaded)}; expected {self.expect.what}")
        with _LOCK:
            if self._entries.get(name) is entry:
                self._entries[name] = loaded
            return self._entries[name]

    @_locked
    def _current(self) -> None:
        """Scan again if the installed metadata was read again since the last scan, or
        needs to be (a package installed since: :func:`_read_installed`)."""
        if _read_installed() != self._readings:
            self.scan()

    def get(self, name: str) -> T:
        """The entry registered under ``name``; :class:`UnknownName` lists the known."""
        self._find(name)
        return self._load(name)

    @_locked
    def _find(self, name: str) -> None:
        """Scan as needed until ``name`` is registered; :class:`UnknownName` if it is not."""
        self._current()
        if not isinstance(name, str) or name not in self._entries:
            self.scan(fresh=True)
        if not (isinstance(name, str) and name in self._entries):
            raise UnknownName(f"unknown {self.kind} {name!r}; expected one of "
                              f"{', '.join(self.names())}")

    def named(self, spec: str, expected: str = "NAME[:ARG]") -> tuple[str, str]:
        """NAME and ARG of a ``NAME[:ARG]`` spec whose NAME is registered here (else
        :class:`UnknownName` listing the known); a spec that is no str is an InputError
        saying ``expected``."""
        if not isinstance(spec, str):
            raise InputError(f"{self.kind} {spec!r}: expected {expected}")
        name, _, arg = spec.partition(":")
        self.get(name)
        return name, arg

    def refuse_arg(self, name: str, arg: str) -> None:
        """An InputError where entry ``name``, which takes no ARG, was given ``arg``."""
        if arg:
            raise InputError(f"{self.kind} {name!r} takes no ARG, got {arg!r}")

    def loaded(self) -> dict[str, T]:
        """Every entry that loads, by name (importing every plugin's): one that cannot
        be loaded is left out with a warning (its :class:`PluginError` when its name is
        used)."""
        return {name: self._entries[name] for name in self.names() if self._loads(name)}

    def loadable_names(self) -> tuple[str, ...]:
        """:meth:`names` less another package's entries that cannot be loaded, each left
        out with a warning (importing every plugin's, as :meth:`loaded`); frictex's own
        are listed without being imported."""
        return tuple(name for name in self.names() if self.loads(name))

    def loads(self, name: str) -> bool:
        """Whether ``name`` is registered (a package installed since included) and can be
        loaded: frictex's own without being imported, another package's by importing that
        one entry now (a warning where it cannot be)."""
        if name not in self:
            return False
        return self._origin[name] == OWN_DISTRIBUTION or self._loads(name)

    def _loads(self, name: str) -> bool:
        """Load entry ``name``: False, with a warning, where it cannot be loaded."""
        try:
            self._load(name)
        except PluginError as exc:
            warn_once(f"{exc}; left out")
            return False
        return True

    @_locked
    def names(self) -> tuple[str, ...]:
        """Every registered name: frictex's own first in registration order, then the
        other packages' by distribution."""
        self._current()
        return tuple(self._entries)

    def origin(self, name: str) -> str:
        """Who registered ``name``: ``frictex`` or the plugin's distribution and object."""
        self.get(name)
        with _LOCK:
            return self._origin[name]

    @_locked
    def __contains__(self, name: object) -> bool:
        if not isinstance(name, str):
            return False
        self._current()
        if name not in self._entries:
            self.scan(fresh=True)
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {self.group!r}, {list(self.names())})"
