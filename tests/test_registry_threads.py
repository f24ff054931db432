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


def test_a_thread_importing_a_module_that_registers_while_another_loads_it(tmp_path,
                                                                          monkeypatch):
    """Thread B imports a module that registers into a registry as it is imported (as
    frictex's modules do); thread A loads an entry point to that module through the same
    registry. Holding the lock across the import, A waited for B's import and B for the
    lock: both hung."""
    import importlib.metadata
    (tmp_path / "gadget_registry.py").write_text(
        "from frictex.device.registry import Registry\n"
        "GADGETS = Registry('gadget', 'frictex.test-gadgets-none')\n")
    (tmp_path / "slow_gadget.py").write_text(
        "import time\n"
        "time.sleep(0.3)  # an import that takes a while (numba, a compiled library)\n"
        "from gadget_registry import GADGETS\n"
        "GADGETS.register('registered-on-import', len)\n"
        "X = abs\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    from gadget_registry import GADGETS
    point = importlib.metadata.EntryPoint(name="slow", value="slow_gadget:X",
                                          group="frictex.test-gadgets-none")
    with registry_module._LOCK:
        GADGETS._entries["slow"] = registry_module._Unloaded(point)
        GADGETS._origin["slow"] = "a test's entry point"
    got = []
    importer = threading.Thread(target=lambda: __import__("slow_gadget"), daemon=True)
    loader = threading.Thread(target=lambda: got.append(GADGETS.get("slow")), daemon=True)
    importer.start()
    loader.start()
    importer.join(30)
    loader.join(30)
    assert not importer.is_alive() and not loader.is_alive()
    assert got == [abs] and GADGETS.get("registered-on-import") is len
