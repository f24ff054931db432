"""A signal stops fan_out and frictex batch: no item starts after it, the running ones
stop, batch.csv lists what finished. Signals are sent from the test to a subprocess,
to the parent alone (kill PID) or to its process group (a terminal's Ctrl-C); waits are
bounded, and nothing is asserted about how long anything took."""

import csv
import json
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

FRICTEX = str(Path(sys.executable).with_name("frictex"))
#: the longest any wait here may take (s): far beyond what a busy machine needs
BOUND_S = 120

#: fan_out over five items, each writing <dir>/<k>.start, then sleeping up to BOUND_S
#: and writing <dir>/<k>.end; prints the outcome, exits 130 when interrupted
FAKE_JOBS = textwrap.dedent("""
    import json, sys, time
    from functools import partial
    from pathlib import Path
    from frictex.app.engine.fanout import Interrupted, fan_out

    def job(folder, k):
        (Path(folder) / f"{k}.start").write_text(repr(time.time()))
        end = time.monotonic() + %d
        while time.monotonic() < end:
            time.sleep(0.02)
        (Path(folder) / f"{k}.end").write_text("")
        return k

    if __name__ == "__main__":
        try:
            fan_out(partial(job, sys.argv[1]), list(range(5)), workers=int(sys.argv[2]))
        except Interrupted as stop:
            print(json.dumps({"signum": stop.signum, "results": stop.results,
                              "stopped": stop.stopped}))
            sys.exit(130)
""" % BOUND_S)


def wait_for(predicate, what: str, detail=None) -> None:
    """Poll ``predicate`` until true, at most BOUND_S; ``detail()``: what the failure
    message adds (the state that kept it false)."""
    end = time.monotonic() + BOUND_S
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"waited {BOUND_S} s for {what}"
                                 + (f": {detail()}" if detail else ""))
        time.sleep(0.05)


@pytest.fixture
def spawn():
    """``spawn(argv, **popen)``: a started process, with pipes; one still running at the
    end of the test is killed (its workers continued first, so that they can end)."""
    started = []

    def start(argv, **popen):
        started.append(subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True, **popen))
        return started[-1]

    yield start
    for proc in started:
        if proc.poll() is None:
            for pid in children(proc.pid):
                os.kill(pid, signal.SIGCONT)
            proc.kill()
            proc.communicate()


def send(proc: subprocess.Popen, sig: int, target: str) -> None:
    """``sig`` to the process alone, or to its whole group (it leads a session)."""
    if target == "group":
        os.killpg(proc.pid, sig)
    else:
        os.kill(proc.pid, sig)


def finish(proc: subprocess.Popen) -> tuple[int, str, str]:
    try:
        out, err = proc.communicate(timeout=BOUND_S)
    except subprocess.TimeoutExpired:
        os.killpg(proc.pid, signal.SIGKILL)
        proc.communicate()
        raise AssertionError(f"still running {BOUND_S} s after the signal")
    return proc.returncode, out, err


@pytest.mark.parametrize("workers, target", [(2, "parent"), (2, "group"), (1, "parent"),
                                             (1, "group")])
def test_a_signal_starts_no_item_and_stops_the_running_ones(tmp_path, spawn, workers, target):
    script = tmp_path / "fake_jobs.py"
    script.write_text(FAKE_JOBS)
    marks = tmp_path / "marks"
    marks.mkdir()
    proc = spawn([sys.executable, str(script), str(marks), str(workers)],
                 start_new_session=True)
    wait_for(lambda: len(list(marks.glob("*.start"))) == workers, f"{workers} items to start")
    send(proc, signal.SIGINT, target)
    code, out, err = finish(proc)
    assert code == 130, err
    outcome = json.loads(out)
    started = sorted(int(p.stem) for p in marks.glob("*.start"))
    assert started == list(range(workers))  # none started after the signal
    assert outcome == {"signum": signal.SIGINT, "results": [None] * 5, "stopped": started}
    assert not list(marks.glob("*.end"))  # the running ones were stopped
    assert "Traceback" not in err


#: as FAKE_JOBS, but a stopped item cleans up for a while, getting two more SIGINTs
#: meanwhile (a dying parent sends one for each of its threads as they end), and
#: writes <dir>/<k>.cleaned when its cleanup is done
CLEANING_JOBS = FAKE_JOBS.replace("""    while time.monotonic() < end:
        time.sleep(0.02)
""", """    try:
        while time.monotonic() < end:
            time.sleep(0.02)
    except KeyboardInterrupt:
        import os, signal
        for _ in range(2):
            os.kill(os.getpid(), signal.SIGINT)
            time.sleep(0.05)
        (Path(folder) / f"{k}.cleaned").write_text("")
        raise
""")


@pytest.mark.parametrize("sig", [signal.SIGINT, signal.SIGKILL])
def test_more_signals_while_an_item_stops_do_not_cut_its_cleanup_short(tmp_path, spawn, sig):
    """A worker's item gets one KeyboardInterrupt: further SIGINTs while it stops pass,
    whether the parent passed a Ctrl-C on or died (SIGKILL)."""
    assert CLEANING_JOBS != FAKE_JOBS
    script = tmp_path / "cleaning_jobs.py"
    script.write_text(CLEANING_JOBS)
    marks = tmp_path / "marks"
    marks.mkdir()
    proc = spawn([sys.executable, str(script), str(marks), "2"], start_new_session=True)
    wait_for(lambda: len(list(marks.glob("*.start"))) == 2, "2 items to start")
    os.kill(proc.pid, sig)
    wait_for(lambda: len(list(marks.glob("*.cleaned"))) == 2, "both items to clean up",
             lambda: f"marks {sorted(p.name for p in marks.iterdir())}")
    assert not list(marks.glob("*.end"))


@pytest.fixture(scope="module")
def long_trace(tmp_path_factory):
    """A 600 s trace: a job of it at 100 kHz runs for many seconds on any machine."""
    path = tmp_path_factory.mktemp("trace") / "long.csv"
    subprocess.run([FRICTEX, "trace", "synth", "human", "--rate", "120", "--duration", "600",
                    "-o", str(path)], check=True, capture_output=True)
    return path


def staged(out: Path) -> Path:
    """Where a running batch writes its job folders: its staging folder beside ``out``
    (``app.engine.batch_folder``), or ``out`` itself while there is none."""
    found = sorted(out.parent.glob(f".{out.name}.frictex-staging.*"))
    return found[0] if found else out


def results(path: Path) -> dict:
    with open(path, newline="") as fh:
        return {row["name"]: row for row in csv.DictReader(fh)}


@pytest.mark.parametrize("sig, target, code", [(signal.SIGINT, "parent", 130),
                                               (signal.SIGINT, "group", 130),
                                               (signal.SIGTERM, "parent", 143)])
def test_a_stopped_batch_lists_what_finished(tmp_path, spawn, long_trace, sig, target, code):
    """A short job finishes, two long ones run, a fourth waits: the signal stops the two
    (their folders never appear), the fourth never starts, batch.csv says so."""
    manifest = tmp_path / "m.csv"
    manifest.write_text("scene,trace,rate_hz,name\ngrating-5mm,swipe-40mms-50hz,10000,S1\n"
                        + "".join(f"grating-5mm,{long_trace},100000,L{k}\n" for k in (2, 3, 4)))
    out = tmp_path / "out"
    proc = spawn([FRICTEX, "batch", str(manifest), "--out", str(out), "--jobs", "2",
                  "--quiet", "--allow-outside"],  # long_trace lies beside the manifest's folder
                 start_new_session=True)

    def running(name):
        return any(staged(out).glob(f".{name}.frictex-staging.*"))

    wait_for(lambda: ((staged(out) / "S1" / "summary.json").exists() and running("L2")
                      and running("L3")), "S1 to finish and L2, L3 to run")
    send(proc, sig, target)
    returncode, _, err = finish(proc)
    assert returncode == code, err
    table = results(out / "batch.csv")
    assert {name: row["status"] for name, row in table.items()} == {
        "S1": "ok", "L2": "interrupted", "L3": "interrupted", "L4": "interrupted"}
    name = signal.Signals(sig).name
    assert table["L4"]["error"] == f"not started: the batch was stopped by {name}"
    assert table["L2"]["error"] == f"stopped while it ran: the batch was stopped by {name}"
    assert table["L2"]["output_s"] == table["L2"]["wall_s"] == ""
    assert sorted(p.name for p in out.iterdir()) == ["S1", "batch.csv"]  # no leftovers
    assert not list(tmp_path.glob(".out.frictex-*"))
    assert "Traceback" not in err


@pytest.mark.skipif(sys.platform != "linux", reason="the workers learn of it by prctl (Linux)")
def test_a_killed_batch_stops_its_running_jobs(tmp_path, spawn, long_trace):
    """SIGKILL to the batch alone: its workers, in a group of their own, stop their jobs
    as on Ctrl-C (staging removed, no job folder), instead of running them to the end;
    the batch's own --out is never made (its staging folder waits for the next batch)."""
    manifest = tmp_path / "m.csv"
    manifest.write_text("scene,trace,rate_hz,name\n"
                        + "".join(f"grating-5mm,{long_trace},100000,L{k}\n" for k in (1, 2)))
    out = tmp_path / "out"
    proc = spawn([FRICTEX, "batch", str(manifest), "--out", str(out), "--jobs", "2",
                  "--quiet", "--allow-outside"],  # long_trace lies beside the manifest's folder
                 start_new_session=True)
    wait_for(lambda: len(list(staged(out).glob(".L*.frictex-staging.*"))) == 2,
             "both jobs to run")
    folder = staged(out)
    os.kill(proc.pid, signal.SIGKILL)
    assert proc.wait(timeout=BOUND_S) == -signal.SIGKILL
    wait_for(lambda: not list(folder.glob(".L*.frictex-staging.*")), "the jobs to stop",
             lambda: f"left {sorted(p.name for p in folder.iterdir())}; workers "
                     f"{[(pid, state(pid)) for pid in workers_of(out)]}")
    assert list(folder.iterdir()) == [] and not out.exists()
    wait_for(lambda: not workers_of(out), "the workers to end")


def workers_of(out: Path) -> list[int]:
    """The processes still running with ``out`` on their command line."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            if proc.name.isdigit() and str(out).encode() in (proc / "cmdline").read_bytes():
                found.append(int(proc.name))
        except OSError:  # it ended meanwhile
            pass
    return found


def state(pid: int) -> str:
    """A process's state letter (``T``: stopped), or "" once it is gone."""
    try:
        return Path(f"/proc/{pid}/stat").read_text().rsplit(")", 1)[1].split()[0]
    except (OSError, IndexError):
        return ""


def children(pid: int) -> list[int]:
    """The processes whose parent is ``pid``."""
    found = []
    for proc in Path("/proc").iterdir():
        try:
            fields = (proc / "stat").read_text().rsplit(")", 1)[1].split()
            if proc.name.isdigit() and int(fields[1]) == pid:
                found.append(int(proc.name))
        except (OSError, IndexError, ValueError):
            pass
    return found


@pytest.mark.skipif(not Path("/proc/self/stat").exists(), reason="reads process states in /proc")
def test_ctrl_z_stops_the_workers_too_and_fg_continues_them(tmp_path, spawn):
    """The workers are in a group of their own: a terminal's Ctrl-Z (SIGTSTP to the
    batch's group) stops them with the batch; SIGCONT continues them; Ctrl-C still
    stops everything."""
    script = tmp_path / "fake_jobs.py"
    script.write_text(FAKE_JOBS)
    marks = tmp_path / "marks"
    marks.mkdir()
    # a group of its own in this session, as a shell's job: in a session of its own the
    # group would be orphaned, and the system discards a SIGTSTP to it
    proc = spawn([sys.executable, str(script), str(marks), "2"], process_group=0)
    wait_for(lambda: len(list(marks.glob("*.start"))) == 2, "2 items to start")
    workers = children(proc.pid)
    assert len(workers) == 2
    os.killpg(proc.pid, signal.SIGTSTP)
    wait_for(lambda: [state(p) for p in (proc.pid, *workers)] == ["T"] * 3, "all to stop")
    os.killpg(proc.pid, signal.SIGCONT)
    wait_for(lambda: "T" not in [state(p) for p in (proc.pid, *workers)], "all to continue")
    os.killpg(proc.pid, signal.SIGINT)
    code, out, err = finish(proc)
    assert code == 130, err
    assert json.loads(out)["stopped"] == [0, 1]
