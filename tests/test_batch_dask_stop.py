"""A batch on a Dask cluster stops as a local one does: a SIGTERM or SIGHUP cancels its
tasks and ends it as Ctrl-C does, and a cluster without any worker (none from the start,
or its only worker killed) makes it give up after ``fanout.NO_WORKER_S`` instead of
waiting for ever. The cluster's scheduler runs in this process on loopback; batches run
in subprocesses, every wait bounded."""

import csv
import os
import signal
import subprocess
import sys
import textwrap
import time
from pathlib import Path

import pytest

from conftest import signals_as_a_terminal_gives

distributed = pytest.importorskip("distributed", reason="dask.distributed is not installed "
                                  "(pip install 'frictex[cluster]')")

FRICTEX = str(Path(sys.executable).with_name("frictex"))
#: the longest any wait here may take (s): far beyond what a busy machine needs
BOUND_S = 120
MANIFEST = "scene,trace,name\ngrating-5mm,swipe-40mms-50hz,a\ngrating-5mm,swipe-40mms-50hz,b\n"

#: ``frictex batch`` with the no-worker bound shortened to 2 s (checks every 0.2 s)
BATCH_WITH_SHORT_BOUND = textwrap.dedent("""
    import sys
    from frictex.app.engine import fanout
    from frictex.app.commands.cli import main
    fanout.NO_WORKER_S, fanout.WORKER_CHECK_S = 2.0, 0.2
    sys.exit(main(sys.argv[1:]))
""")

#: fan_out of three items on the cluster at argv[1], each writing <argv[2]>/<k>.start
#: then sleeping BOUND_S; the no-worker bound shortened to 2 s; prints how it ended
SLEEPING_ITEMS = textwrap.dedent("""
    import sys, time
    from functools import partial
    from pathlib import Path
    from frictex.app.engine import fanout

    def item(folder, k):
        (Path(folder) / f"{k}.start").write_text("")
        time.sleep(%d)
        return k

    if __name__ == "__main__":
        fanout.NO_WORKER_S, fanout.WORKER_CHECK_S = 2.0, 0.2
        try:
            fanout.fan_out(partial(item, sys.argv[2]), [0, 1, 2], scheduler=sys.argv[1])
        except fanout.NoWorkers as exc:
            print("no workers", exc.results)
            sys.exit(1)
        except fanout.Interrupted as exc:
            print("stopped", exc.stopped)
            sys.exit(2)
""" % BOUND_S)


def wait_for(predicate, what: str) -> None:
    end = time.monotonic() + BOUND_S
    while not predicate():
        if time.monotonic() > end:
            raise AssertionError(f"waited {BOUND_S} s for {what}")
        time.sleep(0.05)


def finish(proc: subprocess.Popen) -> tuple[int, str, str]:
    """The process's status and output; it is killed, and the test fails, if it runs on
    past BOUND_S."""
    try:
        out, err = proc.communicate(timeout=BOUND_S)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        raise AssertionError(f"still running after {BOUND_S} s")
    return proc.returncode, out, err


@pytest.fixture
def cluster():
    """A scheduler on loopback, in this process, with no worker."""
    with distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp://", host="127.0.0.1",
                                  dashboard_address=None) as local:
        yield local


@pytest.fixture
def spawn():
    """``spawn(argv)``: a started process with pipes, killed if still running at the end."""
    started = []

    def start(argv):
        started.append(subprocess.Popen(argv, stdout=subprocess.PIPE, stderr=subprocess.PIPE,
                                        text=True, preexec_fn=signals_as_a_terminal_gives))
        return started[-1]

    yield start
    for proc in started:
        if proc.poll() is None:
            proc.kill()
            proc.communicate()


def statuses(out: Path) -> dict:
    with open(out / "batch.csv", newline="") as fh:
        return {row["name"]: (row["status"], row["error"]) for row in csv.DictReader(fh)}


@pytest.mark.parametrize("sig", [signal.SIGTERM, signal.SIGHUP])
def test_a_signal_stops_a_dask_batch_as_ctrl_c_does(tmp_path, cluster, spawn, sig):
    (tmp_path / "m.csv").write_text(MANIFEST)
    out = tmp_path / "out"
    proc = spawn([FRICTEX, "batch", str(tmp_path / "m.csv"), "--out", str(out), "--quiet",
                  "--scheduler", cluster.scheduler_address])
    wait_for(lambda: len(cluster.scheduler.tasks) == 2, "the batch's two tasks")
    os.kill(proc.pid, sig)
    code, _, err = finish(proc)
    name = signal.Signals(sig).name
    assert code == 128 + sig, err
    assert err.strip().splitlines()[-1] == f"frictex: terminated by {name}"
    assert statuses(out) == dict.fromkeys(
        "ab", ("interrupted", f"not started: the batch was stopped by {name}"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["m.csv", "out"]  # no staging left
    wait_for(lambda: not cluster.scheduler.tasks, "the tasks to be cancelled")


def test_a_cluster_without_workers_fails_the_batch_after_the_bound(tmp_path, cluster, spawn):
    (tmp_path / "m.csv").write_text(MANIFEST)
    script = tmp_path / "batch.py"
    script.write_text(BATCH_WITH_SHORT_BOUND)
    out = tmp_path / "out"
    proc = spawn([sys.executable, str(script), "batch", str(tmp_path / "m.csv"), "--out",
                  str(out), "--quiet", "--scheduler", cluster.scheduler_address])
    code, _, err = finish(proc)
    address = cluster.scheduler_address
    assert code == 1, err
    assert err.strip().splitlines() == [
        f"frictex: warning: the Dask cluster at {address} has no worker; waiting up to 2 s "
        "for one",
        f"frictex: error: the Dask cluster at {address} had no worker for 2 s; gave up 2 of "
        "2 jobs unfinished"]
    assert statuses(out) == dict.fromkeys(
        "ab", ("interrupted", f"not finished: the Dask cluster at {address} had no worker "
                              "for 2 s"))
    assert sorted(p.name for p in tmp_path.iterdir()) == ["batch.py", "m.csv", "out"]
    wait_for(lambda: not cluster.scheduler.tasks, "the tasks to be cancelled")


def start_sleeping_items(tmp_path, cluster, spawn):
    """SLEEPING_ITEMS on ``cluster`` with one worker of one thread, once an item has
    started: (the items' process, the worker's, the marks' folder)."""
    script = tmp_path / "items.py"
    script.write_text(SLEEPING_ITEMS)
    marks = tmp_path / "marks"
    marks.mkdir()
    worker = spawn([str(Path(sys.executable).with_name("dask")), "worker",
                    cluster.scheduler_address, "--nthreads", "1", "--no-nanny",
                    "--host", "127.0.0.1", "--no-dashboard"])
    wait_for(lambda: cluster.scheduler.workers, "the worker to join")
    proc = spawn([sys.executable, str(script), cluster.scheduler_address, str(marks)])
    wait_for(lambda: list(marks.glob("*.start")), "an item to start")
    return proc, worker, marks


def test_a_signal_counts_the_items_running_on_workers_as_stopped(tmp_path, cluster, spawn):
    """All three read 'not started' before. The worker holds a second item queued behind
    its one thread (the scheduler lists it processing): it has not started."""
    proc, _, marks = start_sleeping_items(tmp_path, cluster, spawn)
    os.kill(proc.pid, signal.SIGTERM)
    code, out, err = finish(proc)
    assert code == 2, err
    (started,) = [int(mark.stem) for mark in marks.glob("*.start")]
    assert out.strip() == f"stopped [{started}]"


def test_a_batch_whose_only_worker_dies_gives_up_after_the_bound(tmp_path, cluster, spawn):
    proc, worker, _ = start_sleeping_items(tmp_path, cluster, spawn)
    worker.kill()
    code, out, err = finish(proc)
    assert code == 1, err
    assert out.strip() == "no workers [None, None, None]"
    assert "has no worker; waiting up to 2 s for one" in err


#: fan_out on the cluster at argv[1] of items where "die" kills its worker's process;
#: prints the results as JSON, a lost item's as what on_lost made of it
ITEMS_WITH_A_KILLER = textwrap.dedent("""
    import json, os, signal, sys
    from frictex.app.engine.fanout import fan_out

    def item(name):
        if name == "die":
            os.kill(os.getpid(), signal.SIGKILL)
        return name.upper()

    if __name__ == "__main__":
        print(json.dumps(fan_out(item, ["a", "die", "b"], scheduler=sys.argv[1],
                                 on_lost=lambda name, why: f"lost {name}: {why}")))
""")


def test_an_item_whose_dask_workers_die_is_lost_and_the_others_finish(tmp_path, spawn):
    """Dask's KilledWorker (the task's workers died as often as the cluster allows, here
    once) was a traceback that ended the batch without batch.csv. The item is lost (what
    on_lost makes of it), the others finish; one that Dask held on the dying worker may
    be lost with it, as Dask counts it too."""
    import json

    import dask
    script = tmp_path / "items.py"
    script.write_text(ITEMS_WITH_A_KILLER)
    with dask.config.set({"distributed.scheduler.allowed-failures": 0}), \
            distributed.LocalCluster(n_workers=0, processes=False, protocol="tcp://",
                                     host="127.0.0.1", dashboard_address=None) as cluster:
        spawn([str(Path(sys.executable).with_name("dask")), "worker",
               cluster.scheduler_address, "--nthreads", "1", "--host", "127.0.0.1",
               "--no-dashboard"])  # with a nanny, which starts a new worker when one dies
        wait_for(lambda: cluster.scheduler.workers, "the worker to join")
        code, out, err = finish(spawn([sys.executable, str(script), cluster.scheduler_address]))
    assert code == 0, err
    lost = "the Dask workers running it died as often as the cluster allows (Dask's KilledWorker"
    results = json.loads(out)
    assert results[1].startswith(f"lost die: {lost}")
    for name, result in zip("ab", (results[0], results[2])):
        assert result == name.upper() or result.startswith(f"lost {name}: {lost}")
    assert "Traceback" not in err


#: fan_out on the cluster at argv[1] of items 0 (at once) and 1, 2 (each writing
#: <argv[2]>/<k>.start, then sleeping BOUND_S); prints how it ended
ITEMS_OUTLIVING_THEIR_SCHEDULER = textwrap.dedent("""
    import sys, time
    from functools import partial
    from pathlib import Path
    from frictex.app.engine import fanout

    def item(folder, k):
        if k:
            (Path(folder) / f"{k}.start").write_text("")
            time.sleep(%d)
        return k

    if __name__ == "__main__":
        try:
            fanout.fan_out(partial(item, sys.argv[2]), [0, 1, 2], scheduler=sys.argv[1],
                           on_done=lambda k: (Path(sys.argv[2]) / f"{k}.done").write_text(""))
        except fanout.SchedulerLost as exc:
            print("scheduler lost", exc.results)
            print(exc, file=sys.stderr)
            sys.exit(1)
""" % BOUND_S)


def test_a_scheduler_lost_mid_run_ends_it_with_one_line_keeping_what_finished(tmp_path, spawn):
    """The scheduler's process killed while items ran: a traceback (FutureCancelledError,
    'scheduler-connection-lost') and an internal error, the finished items' results lost."""
    import socket
    with socket.socket() as probe:  # a free port for the scheduler
        probe.bind(("127.0.0.1", 0))
        port = probe.getsockname()[1]
    address = f"tcp://127.0.0.1:{port}"
    dask = str(Path(sys.executable).with_name("dask"))
    scheduler = spawn([dask, "scheduler", "--host", "127.0.0.1", "--port", str(port),
                       "--no-dashboard"])
    script = tmp_path / "items.py"
    script.write_text(ITEMS_OUTLIVING_THEIR_SCHEDULER)
    marks = tmp_path / "marks"
    marks.mkdir()
    worker = None
    end = time.monotonic() + BOUND_S
    while worker is None:  # the scheduler takes a moment to listen
        with socket.socket() as probe:
            if probe.connect_ex(("127.0.0.1", port)) == 0:
                worker = spawn([dask, "worker", address, "--nthreads", "1", "--no-nanny",
                                "--host", "127.0.0.1", "--no-dashboard"])
        if time.monotonic() > end:
            raise AssertionError(f"the scheduler did not listen within {BOUND_S} s")
        time.sleep(0.1)
    proc = spawn([sys.executable, str(script), address, str(marks)])
    wait_for(lambda: (marks / "0.done").exists() and list(marks.glob("*.start")),
             "item 0 to finish and another to start")
    scheduler.kill()
    code, out, err = finish(proc)
    assert code == 1, err
    assert out.strip() == "scheduler lost [0, None, None]"
    assert err.strip().splitlines()[-1].startswith(f"lost the Dask scheduler at {address} ("), err
    assert err.strip().endswith("; gave up 2 of 3 items unfinished"), err
    assert "Traceback" not in err


class _LateFuture:
    """A Dask future whose task has left its worker's thread but reaches the client as
    finished only at its ``late``-th look."""

    def __init__(self, late: int):
        self.looks, self.late = 0, late

    @property
    def status(self):
        self.looks += 1
        return "finished" if self.looks >= self.late else "pending"

    def result(self):
        return "done"


def test_an_item_that_finishes_within_the_grace_after_a_signal_is_kept(monkeypatch):
    """The grace loop ended once no worker's thread ran the item, before its future had
    finished on the client: an item done within the 3 s was listed 'stopped while it ran'
    (3 of 6 tries of four 3 s jobs on two workers, SIGINT at 1.8 s)."""
    from frictex.app.engine import fanout
    threads = iter([{0}])  # running at the signal; no thread runs it afterwards
    monkeypatch.setattr(fanout, "_running_on_dask",
                        lambda client, futures, indices: next(threads, set()))
    monkeypatch.setattr(fanout, "POLL_S", 0.001)
    client = type("Client", (), {"cancel": lambda self, futures: None})()
    results, done = [None], []
    stopped = fanout._stop_on_dask(client, [_LateFuture(late=5)], results, done.append,
                                   lambda k, why: why, "items")
    assert (stopped, results, done) == ([], ["done"], ["done"])
