"""frictex's one exception root and its kinds.

Every error frictex raises on purpose is a :class:`FrictexError`; its kind says who can
fix it, and the ``frictex`` command's exit code follows from the kind alone:

============================  ===================================================  ====
kind                          what went wrong                                      exit
============================  ===================================================  ====
:class:`InputError`           a file, an option, a name the user gave              2
:class:`DeviceError`          the plate, its port or its link                      1
:class:`OutputSpaceError`     the outputs do not fit where they are to be written  1
:class:`RunFailed`            a run that could not do what was asked               1
:class:`MissingExtra`         an optional part of frictex that is not installed    1
============================  ===================================================  ====

Anything else that escapes a command (a ``ValueError`` from numpy, an ``IndexError``) is
a bug in frictex: the command prints its traceback and ``internal error: please
report`` and exits 70 (BSD's EX_SOFTWARE), never dressed as the user's mistake.

The kinds also subclass the builtin a caller would catch without knowing frictex
(``InputError`` is a ``ValueError``, ``DeviceError`` an ``OSError``), as pyserial's
``SerialException`` is an ``IOError``. This module sits in the lowest layer so that every
layer can raise them.
"""

from __future__ import annotations

import errno

from typing import TYPE_CHECKING

if TYPE_CHECKING:  # the API's layer sits above this one: its type, never an import
    from frictex._replay import Replay


class FrictexError(Exception):
    """Root of every error frictex raises on purpose."""

    #: the ``frictex`` command's exit status for this kind
    exit_code = 1


class InputError(FrictexError, ValueError):
    """Bad input: a file (texture, trace, manifest, model), an option or a name."""

    exit_code = 2


class DeviceError(FrictexError, OSError):
    """The output device: its port, its handshake, its link, what it played."""

    #: the complete run, where ``frictex.replay`` ran to the end and the device left more
    #: than ``max_unplayed`` of its samples unplayed; else None
    replay: Replay | None = None


class OutputSpaceError(FrictexError, OSError):
    """The outputs do not fit (disk room, a folder that cannot be written)."""


def disk_full(exc: OSError, said: str) -> OutputSpaceError | None:
    """``exc`` as a one-line :class:`OutputSpaceError` saying ``said`` (with ``exc``'s
    errno) where it is a full disk or quota (ENOSPC, EDQUOT) not said so already; None
    for any other error."""
    if isinstance(exc, OutputSpaceError) or exc.errno not in (errno.ENOSPC, errno.EDQUOT):
        return None
    full = OutputSpaceError(said)
    full.errno = exc.errno
    return full


class RunFailed(FrictexError, RuntimeError):
    """A run that finished but could not do what was asked (failed jobs of a batch,
    a claim that does not hold under ``--strict``)."""


class MissingExtra(FrictexError, ImportError):
    """A command or option needs an optional part of frictex that is not installed;
    the message names the pip command that installs it."""

    def __init__(self, extra: str, what: str, module: str):
        super().__init__(f"{what} needs frictex's {extra!r} extra ({module} is not "
                         f"installed): pip install 'frictex[{extra}]'")
        self.extra = extra
        self.name = module


def require_extra(extra: str, module: str, what: str):
    """Import and return ``module`` of the optional ``extra``; a :class:`MissingExtra`
    naming the pip command when it is not installed."""
    import importlib
    try:
        return importlib.import_module(module)
    except ImportError as exc:
        if exc.name is not None and exc.name.split(".")[0] != module.split(".")[0]:
            raise  # the extra is there but something it needs is broken: not this error
        raise MissingExtra(extra, what, module) from exc
