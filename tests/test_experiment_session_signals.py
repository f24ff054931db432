"""How session.json says a run ended by a signal: SIGTERM and SIGHUP by their names, as
the command's last line does ("frictex: terminated by SIGTERM"); Ctrl-C as
KeyboardInterrupt. A SIGTERM was recorded "stopped (KeyboardInterrupt)": the command's
handler raises a KeyboardInterrupt for every signal (``StartupSignals``)."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from frictex.app.commands.startup_signals import StartupSignals
from frictex.app.engine.driver import Terminated, between_runs
from frictex.app.experiment.protocol import load_protocol
from frictex.app.experiment.runner import make_presenter, run_session, stopped_by
from frictex.app.experiment.window_presenter import SessionPaused
from test_experiment_session import PARTICIPANT, PROTOCOL


@pytest.mark.parametrize("exc, signum, why", [
    (KeyboardInterrupt(), signal.SIGTERM, "SIGTERM"),
    (KeyboardInterrupt(), signal.SIGHUP, "SIGHUP"),
    (KeyboardInterrupt(), signal.SIGINT, "KeyboardInterrupt"),
    (KeyboardInterrupt(), None, "KeyboardInterrupt"),
    (Terminated(signal.SIGTERM), None, "SIGTERM"),  # a replay's held signal
    (Terminated(signal.SIGHUP), signal.SIGHUP, "SIGHUP"),
    (SessionPaused(4, "Escape"), None, "Escape"),
    (OSError("disk full"), signal.SIGTERM, "OSError"),  # an error, whatever came before
])
def test_why_a_run_stopped(exc, signum, why):
    assert stopped_by(exc, signum) == why


@pytest.fixture
def protocol_file(tmp_path):
    path = tmp_path / "p.toml"
    path.write_text(PROTOCOL, encoding="utf-8")
    return path


@pytest.mark.parametrize("signum, why", [(signal.SIGTERM, "SIGTERM"),
                                         (signal.SIGHUP, "SIGHUP"),
                                         (signal.SIGINT, "KeyboardInterrupt")])
def test_a_signal_at_a_trial_is_recorded_by_its_name(tmp_path, protocol_file, signum, why):
    """The signal sent to this process at trial 4, under the command's handlers (its
    ``StartupSignals``, then ``between_runs``), as ``frictex experiment`` has them."""
    presenter = make_presenter(PARTICIPANT)
    answer = presenter.present

    def signal_at_four(trial, shown):
        if trial.number == 4:
            os.kill(os.getpid(), signum)
        return answer(trial, shown)

    presenter.present = signal_at_four
    out = tmp_path / "s"
    with StartupSignals() as startup, between_runs() as runs:
        with pytest.raises(KeyboardInterrupt):
            run_session(load_protocol(protocol_file), presenter, out, seed=5,
                        participant=PARTICIPANT, record="all", between_trials=runs.check)
    assert startup.signum == signum
    [part] = json.loads((out / "session.json").read_text())["parts"]
    assert (part["trials"], part["ended"]) == (3, f"stopped ({why})")


def test_the_command_terminated_records_sigterm(tmp_path, protocol_file):
    """``frictex experiment`` sent SIGTERM once its third trial is recorded: exit 143,
    its last line and session.json name SIGTERM, and so does the analysis."""
    long = tmp_path / "long.toml"
    long.write_text(PROTOCOL.replace("repetitions = 2", "repetitions = 1000"),
                    encoding="utf-8")
    out = tmp_path / "s"
    command = [sys.executable, "-m", "frictex", "experiment", str(long), "--participant",
               PARTICIPANT, "--seed", "7", "--out", str(out), "--record", "results",
               "--quiet"]
    proc = subprocess.Popen(command, stdout=subprocess.DEVNULL, stderr=subprocess.PIPE,
                            text=True)
    try:
        deadline = time.monotonic() + 300.0
        results = out / "results.csv"
        while time.monotonic() < deadline and proc.poll() is None:
            if results.exists() and results.read_bytes().count(b"\n") > 3:
                break
            time.sleep(0.01)
        assert proc.poll() is None, f"the session ended before its third trial: " \
                                    f"{proc.stderr.read()}"
        proc.send_signal(signal.SIGTERM)
        _, stderr = proc.communicate(timeout=120)
    finally:
        proc.kill()
        proc.wait(timeout=30)
        proc.stderr.close()
    assert proc.returncode == 128 + signal.SIGTERM
    assert stderr.strip().splitlines()[-1] == "frictex: terminated by SIGTERM"
    info = json.loads((out / "session.json").read_text())
    assert info["parts"][0]["ended"] == "stopped (SIGTERM)"
    analysed = subprocess.run([sys.executable, "-m", "frictex", "experiment", "analyse",
                               str(out), "--no-plot"], capture_output=True, text=True,
                              timeout=300)
    assert analysed.returncode == 0, analysed.stderr
    [study] = json.loads((out / "analysis" / "analysis.json").read_text())["studies"]
    assert study["session_ends"][0]["ended"] == "stopped (SIGTERM)"
    assert "did not run to its end (stopped (SIGTERM)" in analysed.stdout
