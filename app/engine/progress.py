"""Progress bars on stderr (tqdm) that leave no thread running.

tqdm starts a monitor thread with its first bar, disabled or not, and the thread outlives
the bar. A thread left running sends a command's exit through the interpreter's teardown
(``app.commands.entry``), which puts SIGTERM back to its default first: a SIGTERM in
those last 50 ms killed a finished batch (status -15, no line) where it ends with the
command's own status (``app.commands.startup_signals``). These bars start no such thread
(tqdm's ``monitor_interval = 0``); the monitor only splits the refresh of a bar that
stalls, which these update at every step anyway.
"""

from __future__ import annotations

import functools


def progress_bar(**options):
    """A tqdm bar made with ``options`` (tqdm's keywords), without the monitor thread."""
    return _bar_class()(**options)


@functools.cache
def _bar_class():
    from tqdm import tqdm  # imported only where a bar is made

    class Bar(tqdm):
        monitor_interval = 0  # tqdm's switch for its monitor thread

    return Bar
