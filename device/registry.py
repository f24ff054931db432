"""Registries by name: how frictex's extension points find their implementations.

Each extension point (renderer, touch source, output device, actuation, clock, sink,
window backend) is a ``typing.Protocol`` in the module that uses it, and a
:class:`Registry` beside it. frictex's own implementations register there by name; other
packages add theirs through an entry-point group, loaded the first time a name is
looked up that is not already known, or the names are listed:

.. code-block:: toml

    # a plugin's pyproject.toml
    [project.entry-points."frictex.renderers"]
    wobble = "frictex_wobble:WobbleRenderer"

Every list of names a user sees (command-line choices, the demo's key cycle, the report's
matrix, texture-file validation, the docs) is ``registry.names()``; an unknown name is an
:class:`~frictex.device.errors.InputError` that lists the known ones. This module is in
the lowest layer so that every layer can register into it.
"""

from __future__ import annotations

from collections.abc import Callable, Iterator
from typing import Generic, TypeVar, overload

from frictex.device.errors import FrictexError, InputError

T = TypeVar("T")


class UnknownName(InputError, KeyError):
    """A name no implementation is registered under."""

    def __str__(self) -> str:  # KeyError would quote the whole message
        return str(self.args[0])


class PluginError(FrictexError, RuntimeError):
    """An entry point of another package that cannot be loaded, or clashes with a name
    already registered."""


class Registry(Generic[T]):
    """Implementations of one extension point, by name.

    Parameters
    ----------
    kind : str
        What the entries are, for messages ("renderer", "output device").
    group : str
        The entry-point group other packages register under ("frictex.renderers").
    """

    def __init__(self, kind: str, group: str):
        self.kind = kind
        self.group = group
        self._entries: dict[str, T] = {}
        self._origin: dict[str, str] = {}
        self._plugins_loaded = False

    @overload
    def register(self, name: str) -> Callable[[T], T]: ...

    @overload
    def register(self, name: str, entry: T) -> T: ...

    def register(self, name, entry=None):
        """Register ``entry`` under ``name`` (or use as a decorator). A name registered
        twice is an error: a plugin cannot silently replace a built-in."""
        if entry is None:
            return lambda obj: self.register(name, obj)
        self._add(name, entry, "frictex")
        return entry

    def _add(self, name: str, entry: T, origin: str) -> None:
        if not isinstance(name, str) or not name or name != name.strip() or ":" in name:
            raise PluginError(f"{self.kind} name {name!r} from {origin}: expected a "
                              "non-empty name without spaces at its ends or ':'")
        if name in self._entries and self._entries[name] is not entry:
            raise PluginError(f"{self.kind} {name!r} from {origin} is already registered "
                              f"by {self._origin[name]}")
        self._entries[name] = entry
        self._origin[name] = origin

    def load_plugins(self) -> None:
        """Load the entry points of the group (once)."""
        if self._plugins_loaded:
            return
        self._plugins_loaded = True
        from importlib.metadata import entry_points
        for point in entry_points(group=self.group):
            origin = f"{point.dist.name if point.dist else '?'} ({point.value})"
            try:
                entry = point.load()
            except Exception as exc:  # a broken plugin names itself, not frictex
                raise PluginError(f"{self.kind} {point.name!r} of {origin} cannot be "
                                  f"loaded: {type(exc).__name__}: {exc}") from exc
            self._add(point.name, entry, origin)

    def get(self, name: str) -> T:
        """The entry registered under ``name``; :class:`UnknownName` lists the known."""
        if name not in self._entries:
            self.load_plugins()
        try:
            return self._entries[name]
        except (KeyError, TypeError):
            raise UnknownName(f"unknown {self.kind} {name!r}; expected one of "
                              f"{', '.join(self.names())}") from None

    def names(self) -> tuple[str, ...]:
        """Every registered name, frictex's own first in registration order, then the
        plugins' in the order they loaded."""
        self.load_plugins()
        return tuple(self._entries)

    def origin(self, name: str) -> str:
        """Who registered ``name``: ``frictex`` or the plugin's distribution."""
        self.get(name)
        return self._origin[name]

    def __contains__(self, name: object) -> bool:
        if name not in self._entries:
            self.load_plugins()
        return name in self._entries

    def __iter__(self) -> Iterator[str]:
        return iter(self.names())

    def __repr__(self) -> str:
        return f"Registry({self.kind!r}, {self.group!r}, {list(self._entries)})"
