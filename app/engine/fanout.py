"""Run one function over many items: in this process, over this machine's cores, or on a
Dask cluster. ``frictex batch`` fans replays out this way, ``frictex report`` its matrix.

The function and the items must be picklable (a module-level function, frozen
dataclasses); results come back in the items' order whatever order they finish in.
"""

from __future__ import annotations

import os
import sys

from frictex.device.errors import MissingExtra


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def fan_out(fn, items: list, *, workers: int = 1, scheduler: str | None = None,
            on_done=None) -> list:
    """``[fn(item) for item in items]``, computed by ``workers`` processes (1: here, in
    order) or, with ``scheduler`` (a Dask scheduler's address), by that cluster's workers,
    which need frictex installed and the items' files at the same paths.
    ``on_done(result)`` is called in this process as each finishes.
    """
    done = on_done or (lambda result: None)
    if scheduler is not None:
        return _dask(fn, items, scheduler, done)
    if workers == 1 or len(items) <= 1:
        results = []
        for item in items:
            results.append(fn(item))
            done(results[-1])
        return results
    from concurrent.futures import ProcessPoolExecutor, as_completed
    results: list = [None] * len(items)
    with ProcessPoolExecutor(min(workers, len(items)), mp_context=_pool_context()) as pool:
        futures = {pool.submit(fn, item): k for k, item in enumerate(items)}
        for future in as_completed(futures):
            results[futures[future]] = future.result()
            done(results[futures[future]])
    return results


def _pool_context():
    """How this machine's workers start: forked on Linux, spawned elsewhere.

    A forked worker begins with this process's modules imported; a spawned one starts an
    interpreter and imports numpy, numba and frictex again (~0.5 s of CPU, on every core
    at once, before any job runs). 64 one-minute jobs on the 2-core machine, idle, 6
    interleaved rounds: ``--jobs 2`` spawned 11.0 s wall, 20.5 s CPU; forked 10.4 s,
    19.4 s; ``--jobs 1`` 15.4 s, 19.5 s. Each worker still loads the numba kernels it
    uses on its first item, as ``--jobs 1`` does once. Only the forking thread lives on in
    a worker (the pool forks all of them before starting its own thread; a progress
    bar's monitor thread stays behind). macOS cannot safely fork a process that has
    loaded its system frameworks, Windows cannot fork at all: they spawn.
    """
    import multiprocessing as mp
    return mp.get_context("fork" if sys.platform == "linux" else "spawn")


def _dask(fn, items: list, address: str, done) -> list:
    try:
        from distributed import Client, as_completed
    except ImportError:
        raise MissingExtra("cluster", "--scheduler", "dask.distributed") from None
    try:
        client = Client(address, timeout=10)
    except (OSError, TimeoutError) as exc:
        raise OSError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        futures = client.map(fn, items, pure=False)
        index = {f.key: k for k, f in enumerate(futures)}
        results: list = [None] * len(items)
        for future in as_completed(futures):
            results[index[future.key]] = future.result()
            done(results[index[future.key]])
    finally:
        client.close()
    return results
