"""The console script's exit (``app.commands.entry.entry``): the exit code of ``main``,
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
        from frictex.app.commands import entry
        atexit.register(lambda: print("handler ran"))
        sys.argv = ["frictex", "library"]
        print("before", end="")  # unflushed: no newline, stdout a pipe
        entry.entry()
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
        from frictex.app.commands import entry
        mark = Path(sys.argv[1])
        def late():
            time.sleep(0.3)
            mark.write_text("done")
        threading.Thread(target=late).start()
        sys.argv = ["frictex", "library"]
        entry.entry()
        """, str(mark))
    assert done.returncode == 0, done.stderr
    assert mark.read_text() == "done"


def _run_raising(exc_source: str) -> subprocess.CompletedProcess:
    """``frictex library`` whose run raises what ``exc_source`` builds."""
    return _python(f"""
        import sys
        from frictex.app.commands import entry, library
        from frictex.device import errors
        def run(args):
            raise {exc_source}
        library.run = run
        sys.argv = ["frictex", "library"]
        entry.entry()
        """)


def test_a_bug_is_an_internal_error_with_its_traceback_never_bad_input():
    # a numpy broadcast error inside frictex is not the user's mistake
    done = _run_raising("ValueError('operands could not be broadcast together')")
    assert done.returncode == 70
    assert "Traceback (most recent call last)" in done.stderr
    assert "ValueError: operands could not be broadcast together" in done.stderr
    assert done.stderr.rstrip().splitlines()[-1].startswith("frictex: internal error: please report")
    assert "frictex: error:" not in done.stderr


def test_each_kind_of_error_has_its_exit_code_and_one_line():
    for source, code in [("errors.InputError('bad value')", 2),
                         ("errors.DeviceError('the port went away')", 1),
                         ("errors.OutputSpaceError('need 3 GB, 1 GB free')", 1),
                         ("errors.RunFailed('2 of 5 jobs failed')", 1),
                         ("FileNotFoundError(2, 'No such file or directory', 'my.toml')", 2),
                         ("OSError(5, 'Input/output error')", 1),
                         ("ModuleNotFoundError('no moderngl', name='moderngl')", 1)]:
        done = _run_raising(source)
        assert done.returncode == code, (source, done.stderr)
        assert done.stderr.startswith("frictex: error: ") and done.stderr.count("\n") == 1, source
    assert "pip install 'frictex[gui]'" in _run_raising(
        "ModuleNotFoundError('no moderngl', name='moderngl')").stderr


def test_control_characters_in_a_message_never_reach_the_terminal():
    done = _run_raising(r"errors.InputError('key \x1b]0;owned\x07\x1b[2J\nforged line')")
    assert done.returncode == 2
    assert "\x1b" not in done.stderr and "\x07" not in done.stderr
    assert done.stderr == "frictex: error: key \\x1b]0;owned\\x07\\x1b[2J\\nforged line\n"


def test_an_option_that_sets_the_environment_sets_it_for_its_run_only(tmp_path, monkeypatch):
    from frictex.app.commands.cli import main
    from frictex.textures.outside import ALLOW_OUTSIDE_ENV
    monkeypatch.delenv(ALLOW_OUTSIDE_ENV, raising=False)
    import os
    assert main(["validate", "grating-5mm", "--allow-outside"]) == 0
    assert ALLOW_OUTSIDE_ENV not in os.environ  # an in-process caller's next run is confined


def test_version_prints_the_installed_version_on_stdout_and_exits_0():
    done = _python("""
        import sys
        from frictex.app.commands import entry
        sys.argv = ["frictex", "--version"]
        entry.entry()
        """)
    from importlib.metadata import version
    assert (done.returncode, done.stdout, done.stderr) == (0, f"frictex {version('frictex')}\n", "")


def test_an_argument_no_command_takes_is_said_by_the_command_it_was_given_to(capsys):
    """argparse's top parser said extra arguments without the command's name, as no other
    error of a command's line is said ('frictex: error: unrecognized arguments: extra')."""
    import pytest
    from frictex.app.commands.cli import main
    for argv, said in [(["library", "extra"], "library: unrecognized arguments: extra"),
                       (["validate", "grating-5mm", "--bogus", "x"],
                        "validate: unrecognized arguments: --bogus x"),
                       (["--bogus"], "unrecognized arguments: --bogus")]:
        with pytest.raises(SystemExit) as ended:
            main(argv)
        assert ended.value.code == 2
        assert capsys.readouterr().err == f"frictex: error: {said}\n"


def test_a_closed_stdout_or_stderr_leaves_the_command_s_status(tmp_path):
    """Started with stdout or stderr closed (``>&-`` in a script or a cron job), a run
    that succeeded exits 0 and one refused exits 2: the end's flush of a stream that is
    None took the exit to 1 with a traceback."""
    def run(args, closed):
        return subprocess.run(
            ["sh", "-c", f'"$0" -m frictex "$@" {closed}', sys.executable, *args],
            capture_output=True, text=True, timeout=120)
    out = tmp_path / "out"
    for closed in (">&-", "2>&-", ">&- 2>&-"):
        done = run(["replay", "grating-5mm", "swipe-40mms-50hz", "--out", str(out), "--quiet"],
                   closed)
        assert done.returncode == 0 and "Traceback" not in done.stderr, (closed, done.stderr)
        assert (out / "summary.json").is_file()
        done = run(["library"], closed)
        assert done.returncode == 0 and "Traceback" not in done.stderr, (closed, done.stderr)
        assert run(["replay", "grating-5mm", "no-such-trace", "--out", str(tmp_path / "no")],
                   closed).returncode == 2
