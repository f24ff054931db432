"""A registry shared by the threads of one process (a Dask worker runs a job on each of
its threads): lookups made at once, each the process's first, all find the name, never
a scan another thread has half done (a two-thread worker failed one job in six with
"unknown renderer 'sht'"; here, without the lock, 3 of 300 rounds failed)."""

import sys
import threading

import pytest

from frictex.device import registry as registry_module
from frictex.device.registry import Registry


@pytest.fixture
def often_switching_threads():
    """Threads switched every microsecond (the default is 5 ms), so that the rounds
    below meet the interleavings a busy worker meets."""
    before = sys.getswitchinterval()
    sys.setswitchinterval(1e-6)
    yield
    sys.setswitchinterval(before)


def test_first_lookups_at_once_from_four_threads_all_find_the_name(often_switching_threads,
                                                                   monkeypatch):
    failed = []
    for _ in range(300):
        monkeypatch.setattr(registry_module, "_INSTALLED", None)  # a process's first use
        registry_module._GROUPS.clear()
        renderers = Registry("renderer", "frictex.renderers")
        start = threading.Barrier(4)

        def look_up():
            start.wait()
            try:
                renderers.get("sht")
            except Exception as exc:
                failed.append(repr(exc))

        threads = [threading.Thread(target=look_up) for _ in range(4)]
        for thread in threads:
            thread.start()
        for thread in threads:
            thread.join(30)
    assert failed == []


def test_the_lock_is_reentrant_for_a_scan_within_a_lookup():
    """get() scans again for a name it does not know; names() asks whether to scan."""
    renderers = Registry("renderer", "frictex.renderers")
    with registry_module._LOCK:
        assert "sht" in renderers.names() and "nosuch" not in renderers
