"""A caller's waits on a link end when the caller is interrupted.

The engine holds Ctrl-C, SIGTERM and SIGHUP while a run is under way and turns them into
an exception between its steps (``app.engine.driver.deferred_interrupts``). A wait on a
device link (the handshake, a paced ``send``, a close's drain) can last seconds, and the
plate vibrates meanwhile, so every such wait asks between its turns (at least every
:data:`TURN_S`) whether a held signal ends it::

    with interruptible(check):       # check() raises to end the run
        sink = open_sink(...)        # the handshake's wait calls check_interrupt()

``interruptible`` installs ``check`` for the current thread only (a ``contextvars``
variable: a link's port thread, which only moves bytes, never sees it).
"""

from __future__ import annotations

from contextlib import contextmanager
from contextvars import ContextVar

#: the longest a caller's wait on a link goes without asking whether it is interrupted (s)
TURN_S = 0.02

_CHECK: ContextVar = ContextVar("frictex_link_interrupt_check", default=None)


@contextmanager
def interruptible(check):
    """Within: :func:`check_interrupt` calls ``check()`` (which raises to end a wait)."""
    token = _CHECK.set(check)
    try:
        yield
    finally:
        _CHECK.reset(token)


def check_interrupt() -> None:
    """Call the check installed by :func:`interruptible`, if any: it raises (a held
    Ctrl-C as ``KeyboardInterrupt``) when the caller's wait must end now."""
    check = _CHECK.get()
    if check is not None:
        check()
