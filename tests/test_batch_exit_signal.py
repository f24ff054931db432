"""A SIGTERM that comes once a batch (or a replay with its progress bar) is over ends the
process with its status
(``StartupSignals.end_with``), never by the signal. The process sends it to itself from
the interpreter's teardown (a ``__del__`` of ``__main__``'s), which a thread left running
makes it go through, and which puts SIGTERM back to its default first; nothing depends
on timing."""

import subprocess
import sys

import pytest

SCRIPT = '''\
import os, signal, sys


class TermAtTeardown:
    def __del__(self):
        os.kill(os.getpid(), signal.SIGTERM)


at_teardown = TermAtTeardown()
sys.argv = ["frictex", *sys.argv[1:]]
from frictex.app.commands.entry import entry
entry()
'''


@pytest.mark.parametrize("jobs", ["1", "2"])
def test_a_sigterm_after_a_batch_ends_it_with_the_batch_status(tmp_path, jobs):
    (tmp_path / "m.csv").write_text("scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\n"
                                    "grating-5mm,swipe-40mms-50hz,b\n")
    (tmp_path / "term_at_teardown.py").write_text(SCRIPT)
    done = subprocess.run([sys.executable, "term_at_teardown.py", "batch", "m.csv", "--out",
                           "out", "--jobs", jobs, "--quiet"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert (done.returncode, done.stderr) == (0, "")
    assert (tmp_path / "out" / "batch.csv").exists()


def test_a_sigterm_after_a_replay_with_its_progress_bar_ends_it_with_its_status(tmp_path):
    """A trace of 30 s or more gets the progress bar (``app.engine.progress``)."""
    (tmp_path / "term_at_teardown.py").write_text(SCRIPT)
    synth = subprocess.run([sys.executable, "-m", "frictex", "trace", "synth", "swipe", "-o",
                            "long.csv", "--duration", "30", "--speed", "2", "--x0", "20"],
                           cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert synth.returncode == 0, synth.stderr
    done = subprocess.run([sys.executable, "term_at_teardown.py", "replay", "grating-5mm",
                           "long.csv", "--out", "out", "--rate", "1000"],
                          cwd=tmp_path, capture_output=True, text=True, timeout=300)
    assert done.returncode == 0, done.stderr
    assert (tmp_path / "out" / "summary.json").exists()
