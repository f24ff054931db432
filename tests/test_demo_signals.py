"""The demo under Xvfb ended by a signal as Q ends it (SIGTERM, SIGHUP, Ctrl-C's SIGINT:
the plate stopped, the recording committed with its summary, the usual lines, then one
line naming the signal and its exit status), and ``--record`` replaced as a whole: a
killed demo leaves the previous recording, the next one clears its leftovers and says
it replaced the recording.

Nothing here depends on how fast the machine is: each step waits for the demo to confirm
it in its events (``test_demo.wait_event``), within generous bounds."""

import json
import os
import signal
import subprocess
import sys
import time

import pytest

from conftest import signals_as_a_terminal_gives
from test_demo import wait_event

pytest.importorskip("glfw", reason="glfw (Python package) not installed")


def start(display, rec, *args, group=False):
    """``frictex demo grating-5mm --record rec`` on ``display``, with SIGINT and SIGHUP as
    a terminal gives them (a test's child may inherit them ignored); stderr to a file.
    ``group``: in a process group of its own (signalled as a terminal or ``timeout``
    signals it, its haptic process and simulated device too)."""
    err = rec.parent / f"{rec.name}-stderr.txt"
    with open(err, "w") as fh:
        proc = subprocess.Popen(
            [sys.executable, "-u", "-m", "frictex", "demo", "grating-5mm", "--record", str(rec),
             "--duration", "300", *args],
            env={**os.environ, "DISPLAY": display}, stdout=subprocess.PIPE, stderr=fh, text=True,
            start_new_session=group, preexec_fn=signals_as_a_terminal_gives)
    proc.stderr_path = err
    return proc


def ended(proc) -> tuple[int, str, str]:
    """(exit status, stdout, stderr) of ``proc``, which must end within 120 s."""
    try:
        out, _ = proc.communicate(timeout=120)
    except subprocess.TimeoutExpired:
        proc.kill()
        proc.communicate()
        pytest.fail(f"the demo did not end within 120 s: {proc.stderr_path.read_text()[-4000:]}")
    return proc.returncode, out, proc.stderr_path.read_text()


def staged(rec):
    return sorted(rec.parent.glob(f".{rec.name}.frictex-*"))


def wait_staged_frame(proc, rec, leftovers=()):
    """Wait until the demo's own staging folder beside ``rec`` (not one of ``leftovers``)
    says its first frame was drawn (``rec`` itself holds the previous recording)."""
    deadline = time.monotonic() + 120
    while True:
        assert proc.poll() is None, proc.stderr_path.read_text()
        assert time.monotonic() < deadline, "no first frame"
        for folder in set(staged(rec)) - set(leftovers):
            events = folder / "events.csv"
            if events.exists() and ",first-frame," in events.read_text():
                return folder
        time.sleep(0.02)


@pytest.mark.parametrize("signum, said, device, group", [
    (signal.SIGTERM, "frictex: terminated by SIGTERM", ("--device", "sim"), False),
    (signal.SIGINT, "frictex: interrupted", (), False),
    (signal.SIGHUP, "frictex: terminated by SIGHUP", (), False),
    (signal.SIGTERM, "frictex: terminated by SIGTERM", ("--device", "sim"), True),
    (signal.SIGINT, "frictex: interrupted", ("--device", "sim"), True),
])
def test_a_signal_ends_the_demo_as_q_does(xvfb_display, tmp_path, signum, said, device, group):
    rec = tmp_path / "rec"
    proc = start(xvfb_display, rec, *device, group=group)
    wait_event(proc, rec, "first-frame")
    if group:
        os.killpg(proc.pid, signum)
    else:
        proc.send_signal(signum)
    code, out, err = ended(proc)
    assert code == 128 + signum, err
    assert err.splitlines().count(said) == 1 and err.rstrip().endswith(said), err
    assert "leaked" not in err and "Traceback" not in err and "Exception ignored" not in err
    assert out.startswith("demo: ") and " blocks (" in out
    summary = json.loads((rec / "summary.json").read_text())
    assert summary["ended_by"] == signal.Signals(signum).name and summary["blocks"] > 0
    assert summary["link"]["state"] == ("closed" if device else "none")
    assert sorted(p.name for p in rec.iterdir()) == ["commands.csv", "events.csv",
                                                    "friction.csv", "summary.json",
                                                    "touches.csv"]
    assert staged(rec) == []


def test_a_killed_demo_leaves_the_previous_recording_and_the_next_replaces_it(xvfb_display,
                                                                             tmp_path):
    rec = tmp_path / "rec"
    first = start(xvfb_display, rec)
    wait_event(first, rec, "first-frame")
    first.send_signal(signal.SIGTERM)
    code, out, err = ended(first)
    assert code == 143 and "replaced" not in out, err
    kept = {p.name: p.read_bytes() for p in rec.iterdir()}

    killed = start(xvfb_display, rec)
    wait_staged_frame(killed, rec)  # it writes beside the recording, not into it
    killed.kill()
    ended(killed)
    assert {p.name: p.read_bytes() for p in rec.iterdir()} == kept
    leftovers = staged(rec)
    assert len(leftovers) == 1

    third = start(xvfb_display, rec)
    wait_staged_frame(third, rec, leftovers)
    third.send_signal(signal.SIGTERM)
    code, out, err = ended(third)
    assert code == 143, err
    assert f"demo: replaced the previous recording in {rec}\n" in out
    summary = json.loads((rec / "summary.json").read_text())
    assert summary["warnings"][0].startswith("removed the leftovers of killed runs beside rec")
    for name in ("summary.json", "events.csv"):  # its own, not the previous run's carried over
        assert (rec / name).read_bytes() != kept[name]
    assert staged(rec) == []
