"""After a command, the signal handling of its start-up is gone: ``cli.main`` leaves
SIGINT's handler and ``sys.excepthook`` as they were (a signal during start-up itself:
tests/test_cli_startup_signals.py)."""

import signal
import sys

from frictex.app.commands.cli import main


def test_after_main_sigint_and_excepthook_are_as_they_were():
    handler, hook = signal.getsignal(signal.SIGINT), sys.excepthook
    assert main(["library"]) == 0
    assert signal.getsignal(signal.SIGINT) is handler and sys.excepthook is hook
