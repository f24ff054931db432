"""``device.audio.bounded``: a call that may block forever, waited for with a bound."""

from __future__ import annotations

import subprocess
import sys
import threading

import pytest

from frictex.device.audio.bounded import abandon_portaudio, call_bounded


def test_a_call_that_returns_in_time_is_waited_for():
    ran = []
    assert call_bounded(lambda: ran.append(threading.current_thread().daemon), 30.0)
    assert ran == [True]  # in a daemon thread: one left blocked does not hold the exit


def test_a_call_that_does_not_return_is_abandoned_after_the_bound():
    release = threading.Event()
    try:
        assert call_bounded(release.wait, 0.2) is False
    finally:
        release.set()  # let the abandoned thread end


def test_what_the_call_raises_is_raised_to_the_caller():
    def fails():
        raise OSError("device gone")

    with pytest.raises(OSError, match="device gone"):
        call_bounded(fails, 30.0)


def test_abandoning_unregisters_the_exit_handler_that_would_block_again():
    """In a process of its own: the handler registered as sounddevice registers its own
    would print at exit."""
    code = """
import atexit, types
from frictex.device.audio.bounded import abandon_portaudio
sd = types.SimpleNamespace(_exit_handler=lambda: print("exit handler ran"))
atexit.register(sd._exit_handler)
atexit.register(lambda: print("the others run"))
abandon_portaudio(sd)
abandon_portaudio(types.SimpleNamespace())  # a sounddevice without one: nothing to do
"""
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True,
                          timeout=60)
    assert done.returncode == 0, done.stderr
    assert done.stdout == "the others run\n"
