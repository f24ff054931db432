"""The console script's exit (``app.commands.cli.entry``): the exit code of ``main``,
atexit handlers run, output flushed, and a thread still running waited for; only the
interpreter's teardown is skipped."""

from __future__ import annotations

import subprocess
import sys
import textwrap


def _python(code: str, *args: str) -> subprocess.CompletedProcess:
    return subprocess.run([sys.executable, "-c", textwrap.dedent(code), *args],
                          capture_output=True, text=True, timeout=120)


def test_entry_runs_atexit_handlers_and_flushes_what_was_printed():
    done = _python("""
        import atexit, sys
        from frictex.app.commands import cli
        atexit.register(lambda: print("handler ran"))
        sys.argv = ["frictex", "library"]
        print("before", end="")  # unflushed: no newline, stdout a pipe
        cli.entry()
        """)
    assert done.returncode == 0, done.stderr
    assert done.stdout.startswith("before") and "grating-5mm" in done.stdout
    assert done.stdout.rstrip().endswith("handler ran")


def test_entry_exits_with_the_commands_code(tmp_path):
    bad = tmp_path / "bad.csv"
    bad.write_text("t_s,finger,x_mm,y_mm\n0,0,1e308,1\n")
    done = subprocess.run([sys.executable, "-m", "frictex", "replay", "grating-5mm",
                           str(bad), "--out", str(tmp_path / "out")],
                          capture_output=True, text=True, timeout=120)
    assert done.returncode == 2
    assert done.stderr.startswith("frictex: error: ") and done.stderr.count("\n") == 1


def test_entry_waits_for_a_thread_still_running(tmp_path):
    mark = tmp_path / "written-by-the-thread"
    done = _python("""
        import sys, threading, time
        from pathlib import Path
        from frictex.app.commands import cli
        mark = Path(sys.argv[1])
        def late():
            time.sleep(0.3)
            mark.write_text("done")
        threading.Thread(target=late).start()
        sys.argv = ["frictex", "library"]
        cli.entry()
        """, str(mark))
    assert done.returncode == 0, done.stderr
    assert mark.read_text() == "done"
