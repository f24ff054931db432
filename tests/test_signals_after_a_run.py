"""Signals that come as a run ends: a Ctrl-C during a replay's commit reaches the loop
that runs replays one after another (``frictex batch --jobs 1``), which stops after
that replay, and a further signal during a command's cleanup does not cut it short or
change the signal reported. Signals are sent by the process to itself at a set point
(a patched commit), so nothing depends on timing."""

import os
import signal

import pytest
from test_experiment_resume_parts import PROTOCOL

SCENE = "grating-5mm"
TRACE = "swipe-40mms-50hz"


def ctrl_c_in_commit(monkeypatch, at: int) -> list:
    """Patch the staging commit so that commit number ``at`` (1-based) gets a Ctrl-C;
    the list counts the commits."""
    from frictex.app.engine import staging
    commit = staging.Staging.commit
    commits = []

    def commit_under_ctrl_c(self):
        commits.append(self)
        if len(commits) == at:
            os.kill(os.getpid(), signal.SIGINT)
        return commit(self)

    monkeypatch.setattr(staging.Staging, "commit", commit_under_ctrl_c)
    return commits


def test_a_ctrl_c_during_a_commit_stops_a_loop_of_replays_after_it(tmp_path, monkeypatch):
    from frictex.app.engine.fanout import Interrupted, fan_out
    from frictex.app.engine.replay import run_replay
    commits = ctrl_c_in_commit(monkeypatch, at=2)
    with pytest.raises(Interrupted) as stop:
        fan_out(lambda k: run_replay(SCENE, TRACE, tmp_path / f"o{k}", progress=False),
                list(range(4)), workers=1)
    assert stop.value.signum == signal.SIGINT
    assert len(commits) == 2  # jobs 3 and 4 never started
    assert (tmp_path / "o1" / "summary.json").exists()  # the second run is complete,
    assert stop.value.results[1] is not None and stop.value.stopped == []  # and kept


def test_a_run_alone_whose_commit_dropped_a_ctrl_c_completes_and_returns():
    """A handler that is no loop of runs (a script's, Python's default) is told nothing:
    the run's outputs are complete and it returns (``replay_with``'s docstring)."""
    from frictex.app.engine.driver import deferred_interrupts
    seen = []
    before = signal.signal(signal.SIGINT, lambda signum, frame: seen.append(signum))
    try:
        with deferred_interrupts() as check:
            with check.committing():
                os.kill(os.getpid(), signal.SIGINT)
        returned = True
    finally:
        signal.signal(signal.SIGINT, before)
    assert returned and seen == []


def test_a_ctrl_c_dropped_by_a_commit_leaves_a_later_one_stopping_the_command():
    """A command that runs more than one replay (an experiment's intervals, frictex
    warm): a Ctrl-C its first run's commit dropped neither silences the signals after it
    nor makes a later error a signal's."""
    from frictex.app.commands.startup_signals import StartupSignals
    from frictex.app.engine.driver import deferred_interrupts
    with StartupSignals() as startup:
        with deferred_interrupts() as check:
            with check.committing():
                os.kill(os.getpid(), signal.SIGINT)
        assert startup.signum is None and not startup.caused(TypeError("a bug"))
        with pytest.raises(KeyboardInterrupt):
            os.kill(os.getpid(), signal.SIGTERM)
            for _ in range(100):  # the handler runs at the next bytecodes
                pass
    assert startup.signum == signal.SIGTERM




def test_a_ctrl_c_during_an_intervals_commit_stops_the_experiment_after_its_trial(
        tmp_path, monkeypatch, capsys):
    """frictex experiment replays each interval as it records it (--record all); a Ctrl-C
    during the third interval's commit (trial 2's first) was dropped and all 8 trials
    ran: the session stops once trial 2 is recorded, exit 130, and --resume goes on."""
    from frictex.app.commands.cli import main
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")  # 8 trials of 2 intervals
    out = tmp_path / "s"
    argv = ["experiment", str(path), "--participant", "simulated:weber=0.11,seed=3",
            "--seed", "4", "--out", str(out), "--quiet"]
    commits = ctrl_c_in_commit(monkeypatch, at=3)
    assert main(argv) == 130
    assert len(commits) == 4  # trial 2's second interval ran, no trial after it
    assert len((out / "results.csv").read_text().splitlines()) == 1 + 2
    assert capsys.readouterr().err.strip().splitlines()[-1] == "frictex: interrupted"
    assert main([*argv[:4], "--out", str(out), "--resume", "--quiet"]) == 0
    assert len((out / "results.csv").read_text().splitlines()) == 1 + 8


def test_a_ctrl_c_during_the_last_intervals_commit_leaves_the_session_complete(
        tmp_path, monkeypatch, capsys):
    """The Ctrl-C comes as the last trial's last interval commits: the session is
    complete, so it ends as one (exit 0, every trial's line printed), where it said
    'interrupted', exit 130, and left trial 8's line out."""
    from frictex.app.commands.cli import main
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")  # 8 trials of 2 intervals
    out = tmp_path / "s"
    commits = ctrl_c_in_commit(monkeypatch, at=16)
    assert main(["experiment", str(path), "--participant", "simulated:weber=0.11,seed=3",
                 "--seed", "4", "--out", str(out)]) == 0
    assert len(commits) == 16
    printed = capsys.readouterr()
    assert [line.split(":")[0] for line in printed.out.splitlines()] == [
        f"trial {k}" for k in range(1, 9)]
    assert "interrupted" not in printed.err
    assert len((out / "results.csv").read_text().splitlines()) == 1 + 8


def run_ended_by(first: int, then: list[int], cleaned: list):
    """A command whose run is ended by signal ``first``; the signals ``then`` come
    during its cleanup, which notes in ``cleaned`` that it ran to its end."""
    from frictex.app.engine.driver import deferred_interrupts

    def command():
        try:
            with deferred_interrupts() as check:
                os.kill(os.getpid(), first)
                check()
        finally:
            for sig in then:
                os.kill(os.getpid(), sig)
            cleaned.append("all")
    return command


@pytest.mark.parametrize("first, then, line, code", [
    (signal.SIGTERM, [signal.SIGHUP], "frictex: terminated by SIGTERM", 143),
    (signal.SIGINT, [signal.SIGINT, signal.SIGINT], "frictex: interrupted", 130)])
def test_signals_during_the_cleanup_after_a_run_neither_cut_it_short_nor_are_reported(
        capsys, first, then, line, code):
    from frictex.app.commands.cli import _run
    from frictex.app.commands.startup_signals import StartupSignals
    cleaned = []
    with StartupSignals() as startup:
        try:
            ended = _run(run_ended_by(first, then, cleaned), startup)
        except SystemExit as exc:
            ended = exc.code
    assert (ended, cleaned) == (code, ["all"])
    assert capsys.readouterr().err.strip().splitlines() == [line]


def test_a_ctrl_c_while_the_exit_line_is_written_does_not_write_it_twice(monkeypatch):
    import io
    import sys
    from frictex.app.commands.startup_signals import StartupSignals, report_signal

    class CtrlCOnWrite(io.StringIO):
        def write(self, text):
            os.kill(os.getpid(), signal.SIGINT)
            return super().write(text)

    monkeypatch.setattr(sys, "stderr", CtrlCOnWrite())
    with StartupSignals():
        assert report_signal(None) == 130
    assert sys.stderr.getvalue() == "frictex: interrupted\n"


#: ``entry`` over a command that returns 0 with a thread still running for 600 s (the
#: exit then waits for it); that thread sends a Ctrl-C once the command has returned
#: (its exit's handler is in place), then goes on
AFTER_THE_COMMAND = """
import signal, os, threading, time
from frictex.app.commands import cli, entry

def command(startup=None):
    threading.Thread(target=ctrl_c_once_returned).start()
    return 0

def ctrl_c_once_returned():
    deadline = time.monotonic() + 60
    while "end_with" not in getattr(signal.getsignal(signal.SIGINT), "__qualname__", ""):
        if time.monotonic() > deadline:
            os._exit(3)
        time.sleep(0.01)
    os.kill(os.getpid(), signal.SIGINT)
    time.sleep(600)

cli.main = command
entry.entry()
"""


def test_a_ctrl_c_after_the_command_returned_ends_the_wait_with_its_status():
    """Once the command has returned, a signal neither prints a line nor changes the exit
    status, and a wait for a thread left running stays stoppable (ignored signals kept
    the process waiting for the thread, stoppable only by SIGKILL)."""
    import subprocess
    import sys
    from conftest import signals_as_a_terminal_gives
    done = subprocess.run([sys.executable, "-c", AFTER_THE_COMMAND], capture_output=True,
                          text=True, timeout=120, preexec_fn=signals_as_a_terminal_gives)
    assert (done.returncode, done.stderr) == (0, "")


def test_a_worker_keeps_the_result_of_a_run_complete_when_its_ctrl_c_came(monkeypatch):
    """In a batch worker the parent's flag stops the items after it: the item whose
    commit held the Ctrl-C keeps its result, and a later Ctrl-C in its cleanup passes."""
    from frictex.app.engine.driver import deferred_interrupts
    from frictex.app.engine.fanout import _Worker
    monkeypatch.setattr(_Worker, "running", True)
    monkeypatch.setattr(_Worker, "stopping", False)
    before = signal.signal(signal.SIGINT, _Worker.interrupt)
    try:
        with deferred_interrupts() as check:
            with check.committing():
                os.kill(os.getpid(), signal.SIGINT)
        with pytest.raises(KeyboardInterrupt):  # a run ended by one: the next passes
            with deferred_interrupts() as check:
                os.kill(os.getpid(), signal.SIGINT)
                check()
        os.kill(os.getpid(), signal.SIGINT)
    finally:
        signal.signal(signal.SIGINT, before)
    assert _Worker.stopping
