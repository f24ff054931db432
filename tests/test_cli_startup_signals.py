"""A signal at any moment of a command's start-up is one line and the signal's exit status,
as it is later: SIGINT ``frictex: interrupted`` (130), SIGTERM and SIGHUP ``frictex:
terminated by SIGTERM`` (128 + the signal), through ``python -m frictex``.

Deterministic: a child gets the signal from an import hook at a chosen import of the
start-up (the hook sends it to its own process and waits, bounded, for what the handler
raises), from the command line's first import to numpy's. Timed: a child gets it at
several delays after its handlers are in place (``SigCgt`` in ``/proc/PID/status``), each
of which must give the same result; what runs before that moment (the interpreter's own
start-up) keeps the interpreter's defaults."""

from __future__ import annotations

import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from conftest import signals_as_a_terminal_gives

SIGNALS = {signal.SIGINT: (130, "frictex: interrupted\n"),
           signal.SIGTERM: (143, "frictex: terminated by SIGTERM\n"),
           signal.SIGHUP: (129, "frictex: terminated by SIGHUP\n")}

CHILD = textwrap.dedent("""
    import os, runpy, sys, time, weakref
    signum, target, c_import = int(sys.argv[1]), sys.argv[2], sys.argv[3]
    del sys.argv[1:4]

    def signal_and_wait():
        os.kill(os.getpid(), signum)
        end = time.monotonic() + 10
        while time.monotonic() < end:
            time.sleep(0.01)
        raise RuntimeError("the signal raised nothing")

    class Held:
        pass

    class SignalDuringImport:
        fired = False

        def find_spec(self, name, path=None, target_=None):
            if name != target or SignalDuringImport.fired:
                return None
            SignalDuringImport.fired = True
            if c_import == "weakref_callback":  # as in importlib's module-lock callback:
                held = Held()  # what the handler raises there is printed and dropped
                ref = weakref.ref(held, lambda _: signal_and_wait())
                del held
                return None
            try:
                signal_and_wait()
            except KeyboardInterrupt:
                if c_import == "import_array":  # prints the exception, then replaces it
                    sys.excepthook(*sys.exc_info())
                    raise ImportError("numpy._core.multiarray failed to import")
                if c_import == "import_umath":  # replaces it, prints that, replaces again
                    try:
                        raise ImportError("_multiarray_umath failed to import")
                    except ImportError:
                        sys.excepthook(*sys.exc_info())
                    raise ImportError("numpy._core.umath failed to import")
                raise

    sys.meta_path.insert(0, SignalDuringImport())
    runpy.run_module("frictex", run_name="__main__", alter_sys=True)
""")

#: imports of a parquet replay's start-up, in their order (numba and pyarrow come later,
#: in the run, whose signals are held until a step ends: app.engine.driver)
START_UP_IMPORTS = ["frictex.app.commands.cli", "argparse", "ctypes",
                    "frictex.app.commands.replay", "numpy"]


def _replay_argv(out: Path) -> list[str]:
    return ["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out),
            "--format", "parquet"]


@pytest.mark.parametrize("signum", list(SIGNALS))
@pytest.mark.parametrize("target", START_UP_IMPORTS)
def test_a_signal_at_each_import_of_the_start_up_is_its_one_line(tmp_path, signum, target):
    done = subprocess.run([sys.executable, "-c", CHILD, str(signum), target, "python",
                           *_replay_argv(tmp_path / "run")],
                          capture_output=True, text=True, timeout=120,
                          preexec_fn=signals_as_a_terminal_gives)
    assert (done.returncode, done.stderr) == SIGNALS[signum], done.stderr
    assert not (tmp_path / "run").exists()


@pytest.mark.parametrize("c_import", ["import_array", "import_umath", "weakref_callback"])
@pytest.mark.parametrize("signum", list(SIGNALS))
@pytest.mark.parametrize("target", ["numpy", "numpy._core._multiarray_umath", "numpy.linalg"])
def test_a_signal_inside_numpys_c_import_is_its_one_line(tmp_path, signum, target, c_import):
    """What a C extension's import of numpy does with the exception: import_array
    (numpy's __multiarray_api.h) prints it (PyErr_Print) and raises ImportError:
    numpy._core.multiarray failed to import, the path that ended as an internal error
    (exit 70); import_umath (__ufunc_api.h) first replaces it with ImportError:
    _multiarray_umath failed to import and prints that, a line before the signal's. And
    where no exception can pass (a weakref callback, as importlib's module locks have):
    the signal was printed as "Exception ignored" and the replay ran on, exit 0."""
    done = subprocess.run([sys.executable, "-c", CHILD, str(signum), target, c_import,
                           *_replay_argv(tmp_path / "run")],
                          capture_output=True, text=True, timeout=120,
                          preexec_fn=signals_as_a_terminal_gives)
    assert (done.returncode, done.stderr) == SIGNALS[signum], done.stderr
    assert done.stdout == ""


def _catches_all(pid: int) -> bool:
    """Whether process ``pid`` has a handler for each of SIGINT, SIGTERM and SIGHUP."""
    try:
        status = Path(f"/proc/{pid}/status").read_text()
    except FileNotFoundError:  # it has ended (and the caller's poll() tells)
        return False
    caught = int(next(line for line in status.splitlines()
                      if line.startswith("SigCgt:")).split()[1], 16)
    return all(caught >> (sig - 1) & 1 for sig in SIGNALS)


@pytest.mark.skipif(not Path("/proc/self/status").exists(), reason="reads /proc (Linux)")
@pytest.mark.parametrize("signum", list(SIGNALS))
@pytest.mark.parametrize("delay_s", [0, 0.005, 0.02, 0.05, 0.1])
def test_a_signal_at_any_delay_after_start_is_its_one_line(tmp_path, signum, delay_s):
    child = subprocess.Popen([sys.executable, "-m", "frictex", *_replay_argv(tmp_path / "run")],
                             stdout=subprocess.PIPE, stderr=subprocess.PIPE, text=True,
                             preexec_fn=signals_as_a_terminal_gives)
    end = time.monotonic() + 60
    while child.poll() is None and not _catches_all(child.pid) and time.monotonic() < end:
        time.sleep(0.0005)
    time.sleep(delay_s)
    finished_first = child.poll() is not None  # a fast machine's whole replay: no signal
    if not finished_first:
        child.send_signal(signum)
    _, stderr = child.communicate(timeout=120)
    if finished_first:
        assert child.returncode == 0, stderr
    else:
        assert (child.returncode, stderr) == SIGNALS[signum], stderr
