"""Ctrl-C at any moment of start-up is one line, ``frictex: interrupted``, exit 130.

A child process gets SIGINT from an import hook while its command imports numpy: the
hook sends the signal to its own process and waits (bounded) for the KeyboardInterrupt.
With ``as_c_import`` it then does what a C extension's ``import_array`` does with it
(numpy's ``__multiarray_api.h``: ``PyErr_Print()``, then ``ImportError: numpy._core.
multiarray failed to import``), the path that ended as an internal error (exit 70)."""

import subprocess
import sys
import textwrap

import pytest

from frictex.textures.library import resolve_scene

CHILD = textwrap.dedent("""
    import os, signal, sys, time
    target, as_c_import = sys.argv.pop(1), sys.argv.pop(1) == "1"

    class SigintDuringImport:
        fired = False

        def find_spec(self, name, path=None, target_=None):
            if name != target or SigintDuringImport.fired:
                return None
            SigintDuringImport.fired = True
            try:
                os.kill(os.getpid(), signal.SIGINT)
                end = time.monotonic() + 30
                while time.monotonic() < end:
                    time.sleep(0.01)
                raise SystemExit("the SIGINT never came")
            except KeyboardInterrupt:
                if not as_c_import:
                    raise
                sys.excepthook(*sys.exc_info())
                raise ImportError("numpy._core.multiarray failed to import")

    sys.meta_path.insert(0, SigintDuringImport())
    from frictex.app.commands.entry import entry
    entry()
""")


@pytest.mark.parametrize("as_c_import", [True, False])
@pytest.mark.parametrize("target", ["numpy", "numpy._core._multiarray_umath", "numpy.linalg"])
def test_a_sigint_while_numpy_is_imported_is_the_one_line(tmp_path, target, as_c_import):
    done = subprocess.run([sys.executable, "-c", CHILD, target, "1" if as_c_import else "0",
                           "validate", str(resolve_scene("grating-5mm"))],
                          capture_output=True, text=True, timeout=120)
    assert (done.returncode, done.stderr) == (130, "frictex: interrupted\n"), done.stderr
    assert done.stdout == ""


def test_after_main_sigint_and_excepthook_are_as_they_were(tmp_path):
    import signal
    from frictex.app.commands.cli import main
    handler, hook = signal.getsignal(signal.SIGINT), sys.excepthook
    assert main(["library"]) == 0
    assert signal.getsignal(signal.SIGINT) is handler and sys.excepthook is hook
