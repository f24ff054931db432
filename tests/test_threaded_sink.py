"""The ``threaded`` sink: in a replay it waits for room in its queue, so that the sink it
runs gets every pipeline call (it dropped 312 of 401 calls of a slow sink, silently); one
built not to wait (the live loop's) drops, and a replay says how many in its summary; the
sink it runs gets one abort when its write failed (it got two)."""

import threading
import time

import numpy as np
import pytest

import frictex
from frictex.app.engine.sinks import SINKS, ThreadedSink
from frictex.device.registry import PluginError


class NoWait:
    """A clock that never waits: the run goes as fast as it computes, one block a call."""

    def wait(self, k):
        pass

    def finished(self, k, n):
        pass


class Slow:
    """A sink whose first write takes 0.3 s, so that the run gets far ahead of it; counts
    its calls, its samples and its commits and aborts."""

    def __init__(self):
        self.calls = self.samples = 0
        self.ends: list[str] = []

    def write(self, out, commands_um):
        if self.calls == 0:
            time.sleep(0.3)
        self.calls += 1
        self.samples += commands_um.shape[0]

    def commit(self):
        self.ends.append("commit")

    def abort(self):
        self.ends.append("abort")


class Failing(Slow):
    """A sink whose every write raises."""

    def write(self, out, commands_um):
        raise RuntimeError("disk full")


@pytest.fixture
def in_process_sinks(monkeypatch):
    """SINKS as it is, restored after the test (what it registers leaves with it)."""
    for field in ("_entries", "_origin", "_registered_by"):
        monkeypatch.setattr(SINKS, field, dict(getattr(SINKS, field)))


def replay_into(*sinks):
    trace = frictex.synth_trace("swipe", duration_s=0.5)
    return frictex.replay("grating-5mm", trace, sinks=list(sinks), block_size=50,
                          clock=NoWait())


def test_a_replays_threaded_sink_gets_every_call(in_process_sinks):
    slow = Slow()
    SINKS.register("slow-sink", lambda arg, request: slow)
    result = replay_into("threaded:slow-sink")
    calls = int(np.ceil(result.summary.output.samples / 50))
    assert calls > 64  # more than the queue holds
    assert (slow.calls, slow.samples) == (calls, result.summary.output.samples)
    assert slow.ends == ["commit"]
    assert result.summary.warnings == ()


def test_a_threaded_sink_that_drops_is_a_warning_in_the_summary():
    slow = Slow()
    threaded = ThreadedSink(slow, 4)  # the live loop's kind: never waits
    result = replay_into(threaded)
    assert threaded.dropped > 0 and slow.calls == threaded.calls - threaded.dropped
    assert list(result.summary.warnings) == [
        f"sink threaded:Slow dropped {threaded.dropped} of {threaded.calls} pipeline calls "
        "(its queue of 4 calls was full): its output misses them"]


def test_a_sink_whose_write_failed_is_aborted_once(in_process_sinks):
    failing = Failing()
    SINKS.register("failing-sink", lambda arg, request: failing)
    with pytest.raises(PluginError, match="disk full"):
        replay_into("threaded:failing-sink")
    assert failing.ends == ["abort"]
    assert not any(t.name == "frictex-sink" for t in threading.enumerate())
