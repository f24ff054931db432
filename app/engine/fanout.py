"""Run one function over many items: in this process, over this machine's cores, or on a
Dask cluster. ``frictex batch`` fans replays out this way, ``frictex report`` its matrix.

The function and the items must be picklable (a module-level function, frozen
dataclasses); results come back in the items' order whatever order they finish in.

Stopping. A SIGINT (Ctrl-C), SIGTERM or SIGHUP that comes while :func:`fan_out` runs
(in the main thread) stops it: no item starts after it, the items running are stopped,
and once none runs :func:`fan_out` raises :class:`Interrupted` with the results of the
items that finished. Over this machine's cores the workers run in a process group of
their own, so that a terminal's Ctrl-C (or ``timeout``'s signal to the group) reaches
only this process, which sets a flag the workers share (a worker reads it before each
item, and starts none once it is set) and passes one SIGINT on to each worker: a
worker gets it once whether the signal came to this process alone or to its group. A
worker between items lets it pass; one running an item gets ``KeyboardInterrupt`` there,
or, in a replay, where a replay ends a run on Ctrl-C (between blocks, its output folder
left as it was: ``app.engine.driver.deferred_interrupts``). A further signal is passed
on again, and a replay then stops at once. In this process (one worker) the signal
stops the item running the same way. A terminal's Ctrl-Z (SIGTSTP) stops the workers
with this process, and ``fg`` or ``bg`` continues them. Should this process die (SIGKILL), each worker
gets a SIGINT from the system (Linux) and stops its item likewise. On a Dask cluster
the same stopper takes the signal (Ctrl-C, SIGTERM, SIGHUP) and the items not yet
started are cancelled; those running are given :data:`DASK_STOP_S` to finish (their
results taken, as are those of the items that finished since the last look for
results). One still running then is cancelled and counted stopped while it ran, and a
warning says so: it goes on to its end on its worker (Dask cannot stop a running task),
its result dropped.

A worker that dies. A worker process that ends abruptly while an item runs (SIGKILL from
the system's out-of-memory killer, a crash) breaks the pool, and the pool ends every
worker with it. The items running then are each run again alone, in a worker of their
own; one that ends its worker again is lost: ``on_lost(item, why)`` is its result, and
without ``on_lost`` :func:`fan_out` raises :class:`WorkerLost` once the other items are
done. Items not started go on in a new pool. On a Dask cluster an item whose workers
died as often as the cluster allows (its ``allowed-failures``, 3 by default: Dask's
``KilledWorker``) is lost the same way.

A Dask cluster without workers. Its workers are counted when the items are sent and then
every :data:`WORKER_CHECK_S` while they run: with none, a warning says so once, and after
:data:`NO_WORKER_S` in a row with none the items left are cancelled and :func:`fan_out`
raises :class:`NoWorkers` with the results of the items that finished.
"""

from __future__ import annotations

import os
import pickle
import signal
import sys
import threading
import time
import traceback
from contextlib import contextmanager

from frictex.app.engine.driver import HELD_SIGNALS
from frictex.device.errors import FrictexError, InputError, MissingExtra

#: prctl(2)'s option: the signal a process gets when its parent dies (Linux)
_PR_SET_PDEATHSIG = 1
#: how often (s) the parent looks at the signal flag while it waits for results
POLL_S = 0.1
#: a worker's outcomes for one item: fn(item) returned; not started (the flag was set);
#: stopped by a signal while it ran
DONE, NOT_STARTED, STOPPED = "done", "not started", "stopped"
#: how long (s) a Dask cluster may have no worker at all before the items left are given up
NO_WORKER_S = 60.0
#: how often (s) a Dask cluster's workers are counted while its items run
WORKER_CHECK_S = 1.0
#: how long (s) connecting to a Dask scheduler may take, its handshake included
CONNECT_S = 10.0
#: how long (s) the items running on a Dask cluster may take to finish after a signal
DASK_STOP_S = 3.0
#: an item's state in the workers' shared array: taken by a worker and running, or ended
#: (0: not started)
_RUNNING, _ENDED = 1, 2
#: why an item is lost (module docstring), over this machine's cores and on Dask
LOST_HERE = ("its worker process ended abruptly while it ran, and again when it ran alone "
             "(killed, as the system's out-of-memory killer does, or crashed)")
#: why items are lost whose pools' workers ended before taking any, MAX_IDLE_POOLS times
NEVER_RAN = ("the worker processes ended before taking it, in pool after pool (they "
             "cannot start here: killed, or crashed as they started)")
#: pools in a row whose workers ended before any item finished or ran, after which the
#: items left are lost (without a limit a machine whose workers cannot start would try
#: pool after pool for ever)
MAX_IDLE_POOLS = 3
LOST_ON_DASK = ("the Dask workers running it died as often as the cluster allows "
                "(Dask's KilledWorker: out of memory, or crashed)")


class Interrupted(KeyboardInterrupt):
    """:func:`fan_out` stopped by signal ``signum``: ``results`` in the items' order, None
    for an item that did not finish; ``stopped`` the indices of the items stopped while
    they ran (the other unfinished ones never started)."""

    def __init__(self, signum: int, results: list, stopped: list[int]):
        super().__init__(signal.Signals(signum).name)
        self.signum = signum
        self.results = results
        self.stopped = stopped


class WorkerLost(FrictexError):
    """An item lost with its worker (module docstring) where :func:`fan_out` was given no
    ``on_lost``: ``results`` in the items' order, None for a lost item."""

    def __init__(self, lost: list[int], why: str, results: list):
        super().__init__(f"{len(lost)} of {len(results)} items lost: {why} "
                         f"(item {', '.join(str(k + 1) for k in lost)})")
        self.lost = lost
        self.results = results


class ClusterGone(FrictexError):
    """A Dask cluster that stopped serving the items: ``results`` in the items' order, None
    for an item that did not finish; ``why`` what happened, a phrase ("the Dask cluster
    had no worker for 60 s"); ``noun`` what the items are (plural)."""

    def __init__(self, why: str, results: list, noun: str):
        unfinished = sum(result is None for result in results)
        super().__init__(f"{why}; gave up {unfinished} of {len(results)} {noun} unfinished")
        self.why = why
        self.results = results


class NoWorkers(ClusterGone):
    """A Dask cluster at ``address`` that had no worker for ``waited_s`` (s)."""

    def __init__(self, address: str, waited_s: float, results: list, noun: str = "items"):
        super().__init__(f"the Dask cluster at {address} had no worker for {waited_s:.0f} s",
                         results, noun)
        self.address = address
        self.waited_s = waited_s


class SchedulerLost(ClusterGone):
    """The Dask scheduler at ``address`` gone mid-run (its process ended, or the
    connection to it closed): ``detail`` what the client said."""

    def __init__(self, address: str, detail: str, results: list, noun: str = "items"):
        super().__init__(f"lost the Dask scheduler at {address} ({detail})", results, noun)
        self.address = address


def default_workers() -> int:
    """The cores this process may use."""
    try:
        return len(os.sched_getaffinity(0))
    except AttributeError:
        return os.cpu_count() or 1


def fan_out(fn, items: list, *, workers: int = 1, scheduler: str | None = None,
            on_done=None, on_lost=None, noun: str = "items") -> list:
    """``[fn(item) for item in items]``, computed by ``workers`` processes (1: here, in
    order) or, with ``scheduler`` (a Dask scheduler's address), by that cluster's workers,
    which need frictex installed and the items' files at the same paths.
    ``on_done(result)`` is called in this process as each finishes. A signal stops it
    (module docstring): :class:`Interrupted`. ``on_lost(item, why)`` gives the result of
    an item lost with its worker (module docstring); without it: :class:`WorkerLost`.
    ``noun`` names the items (plural) in :class:`NoWorkers`' message: "jobs" for a batch's.
    """
    done = on_done or (lambda result: None)
    lost: dict[int, str] = {}  # item -> why it was lost

    def lose(k: int, why: str):  # item k lost with its worker: its result, if any
        lost[k] = why
        if on_lost is None:
            return None
        result = on_lost(items[k], why)
        done(result)
        return result

    if scheduler is not None:
        results = _dask(fn, items, scheduler, done, lose, noun)
    elif workers == 1 or len(items) <= 1:
        return _here(fn, items, done)
    else:
        results = _pool(fn, items, min(workers, len(items)), done, lose)
    if lost and on_lost is None:
        raise WorkerLost(sorted(lost), "; ".join(sorted(set(lost.values()))), results)
    return results


class _Stopper:
    """This process's handler of :data:`HELD_SIGNALS` while :func:`fan_out` runs: keeps
    the first signal (``signum``); with workers (``flag``, their shared flag) sets the
    flag and passes SIGINT on to each, else raises ``KeyboardInterrupt`` in the item
    running here (``running``). With workers it also handles a terminal's Ctrl-Z
    (:meth:`pause`).

    A worker is forked with these handlers and replaces them as it starts
    (:func:`_start_worker`); a signal that reaches it before (the pool ends every worker
    when one dies, a Ctrl-C passed on) is the worker's own (:func:`_before_start`): a
    stopper run there would set the shared flag as if this process had been stopped."""

    def __init__(self, flag=None):
        self.signum: int | None = None
        self.flag = flag
        self.running = False
        self.pid = os.getpid()

    def __call__(self, signum, frame) -> None:
        if os.getpid() != self.pid:
            return _before_start(signum)
        if self.signum is None:
            self.signum = signum
        if self.flag is None:
            if self.running:
                raise KeyboardInterrupt
            return
        self.flag.value = 1
        _to_workers(signal.SIGINT)

    def run_saw(self, signum: int, ended: bool) -> None:
        """A run of the item running here (``driver.deferred_interrupts``) saw
        ``signum``: it ended the item (which raises), or came during its commit (the item
        is complete and keeps its result): no item starts after it."""
        if self.signum is None:
            self.signum = signum

    def pause(self, signum, frame) -> None:
        """SIGTSTP (Ctrl-Z): stop the workers, which the terminal's signal to this
        process's group does not reach, then this process as the signal would; once
        continued (``fg``, ``bg``), continue them."""
        if os.getpid() != self.pid:
            return _before_start(signum)
        _to_workers(signal.SIGSTOP)
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)  # stops here until SIGCONT
        signal.signal(signum, self.pause)
        _to_workers(signal.SIGCONT)


def _before_start(signum: int) -> None:
    """Signal ``signum`` in a worker forked with its parent's handlers, before it replaced
    them: SIGINT passes (the parent, which passed it on, holds the signal and has set the
    flag), any other does what it does by default (SIGTERM, SIGHUP end the worker;
    SIGTSTP stops it)."""
    if signum != signal.SIGINT:
        signal.signal(signum, signal.SIG_DFL)
        os.kill(os.getpid(), signum)


def _to_workers(sig: int) -> None:
    """Send ``sig`` to each worker process of this one."""
    import multiprocessing
    for child in multiprocessing.active_children():
        try:
            os.kill(child.pid, sig)
        except ProcessLookupError:  # it ended meanwhile
            pass


@contextmanager
def _handling(stopper: _Stopper):
    """Within: ``stopper`` handles the signals this process does not ignore, and with
    workers Ctrl-Z (main thread only: elsewhere Python runs no handler)."""
    if threading.current_thread() is not threading.main_thread():
        yield
        return
    handlers = dict.fromkeys(HELD_SIGNALS, stopper)
    if stopper.flag is not None and hasattr(signal, "SIGTSTP"):
        handlers[signal.SIGTSTP] = stopper.pause
    previous = {sig: signal.getsignal(sig) for sig in handlers}
    for sig, handler in handlers.items():
        if previous[sig] is not signal.SIG_IGN:
            signal.signal(sig, handler)
    try:
        yield
    finally:
        for sig, handler in previous.items():
            if handler is not signal.SIG_IGN:
                signal.signal(sig, handler)


def _signal_of(exc: BaseException) -> int | None:
    """The signal that ``exc`` (raised by an item) stands for: SIGINT for a
    ``KeyboardInterrupt``, ``SystemExit(128 + signal)`` as a replay raises it for the
    others; None for any other exit."""
    if isinstance(exc, KeyboardInterrupt):
        return signal.SIGINT
    code = exc.code if isinstance(exc, SystemExit) else None
    return next((sig for sig in HELD_SIGNALS if code == 128 + sig), None)


def _here(fn, items: list, done) -> list:
    """The items one after another in this process, stopped by a signal."""
    stopper = _Stopper()
    results: list = [None] * len(items)
    stopped: list[int] = []
    with _handling(stopper):
        for k, item in enumerate(items):
            if stopper.signum is not None:
                break
            stopper.running = True
            try:
                results[k] = fn(item)
            except (KeyboardInterrupt, SystemExit) as exc:
                signum = _signal_of(exc)
                if signum is None:
                    raise
                stopper.signum = stopper.signum or signum
                stopped.append(k)
                break
            finally:
                stopper.running = False
            done(results[k])
    if stopper.signum is not None:
        raise Interrupted(stopper.signum, results, stopped)
    return results


class _Worker:
    """A worker process's part: the parent's flag and pid, and whether an item runs now
    (a SIGINT then stops it, once: further ones while it stops pass, so that its cleanup
    runs to the end; between items it passes, unless the parent has died: then the worker
    ends, as it does after an item once the parent is gone).

    A dying parent can send more than one: the system sends the parent-death signal each
    time the worker is handed to another of the parent's threads as they end, one by one
    (seen here: 2 SIGINTs in 1 of 10 deaths of a parent with 3 threads)."""

    flag = None
    states = None
    parent = 0
    running = False
    stopping = False

    @classmethod
    def interrupt(cls, signum, frame) -> None:
        if cls.running:
            if not cls.stopping:
                cls.stopping = True
                raise KeyboardInterrupt
            return
        cls.end_if_orphaned()

    @classmethod
    def run_saw(cls, signum: int, ended: bool) -> None:
        """The item's run (``driver.deferred_interrupts``) saw the parent's SIGINT: it
        ended the run, or came during its commit (the item keeps its result; the
        parent's flag starts no other): further SIGINTs during this item pass."""
        cls.stopping = True

    @classmethod
    def end_if_orphaned(cls) -> None:
        """End this worker if its parent is gone: nothing would take its results, and
        every worker holds the item queue open, so that it would wait for ever."""
        if os.getppid() != cls.parent:
            os._exit(128 + signal.SIGINT)


def _start_worker(flag, states, parent: int) -> None:
    """A worker's start: the parent's ``flag`` and the items' ``states`` (where it marks
    the item it runs), a process group of its own (signals to
    the parent's group reach only the parent, which passes them on), its SIGINT handler;
    writing to the terminal from that background group never stops it (SIGTTOU). On
    Linux a SIGINT also comes when the parent (pid ``parent``) dies, even by SIGKILL, so
    that the item running stops as it would on the parent's Ctrl-C."""
    _Worker.flag, _Worker.states, _Worker.parent = flag, states, parent
    signal.signal(signal.SIGINT, _Worker.interrupt)
    for sig in (*HELD_SIGNALS[1:], getattr(signal, "SIGTSTP", None)):
        if sig is not None and signal.getsignal(sig) is not signal.SIG_IGN:  # nohup's stays
            signal.signal(sig, signal.SIG_DFL)
    if hasattr(signal, "SIGTTOU"):
        signal.signal(signal.SIGTTOU, signal.SIG_IGN)
    if hasattr(os, "setpgid"):
        os.setpgid(0, 0)
    if sys.platform == "linux":
        import ctypes
        ctypes.CDLL(None).prctl(_PR_SET_PDEATHSIG, signal.SIGINT)
        _Worker.end_if_orphaned()  # it died before that


def _run_item(fn, item, k: int) -> tuple[str, object]:
    """In a worker: ``(DONE, fn(item))``, or ``(NOT_STARTED, None)`` once the parent's
    flag is set, or ``(STOPPED, None)`` when the parent's SIGINT stopped ``fn``; item
    ``k``'s state marked running while ``fn`` runs, then ended. What else ``fn`` raises
    is raised; one that could not reach the parent as it is, as a ``RuntimeError`` of its
    traceback's text, raised outside the handler: with Dask imported (tblib's pickling)
    an exception is pickled with the one it was raised while handling, and the worker
    died on its result (the pool made again for ever)."""
    _Worker.running, _Worker.stopping = True, False  # before the flag is read: a signal
    try:  # after it stops the item
        if _Worker.flag.value:
            return NOT_STARTED, None
        _Worker.states[k] = _RUNNING
        return DONE, fn(item)
    except (KeyboardInterrupt, SystemExit) as exc:
        if _signal_of(exc) is None:
            raise
        return STOPPED, None
    except Exception as exc:  # noqa: BLE001 - raised again, as the parent can take it
        if _sendable(exc):
            raise
        unsent = RuntimeError("".join(traceback.format_exception(exc)).rstrip()
                              + "\n(raised in a worker process, which could not send it "
                              "back as it was)")
    finally:
        if _Worker.states[k] == _RUNNING:
            _Worker.states[k] = _ENDED
        _Worker.running = False
        _Worker.end_if_orphaned()
    raise unsent


def _sendable(exc: Exception) -> bool:
    """Whether ``exc`` survives the way back from a worker process (pickled there, read
    back here): one holding a lock, or whose class is local to a function, does not, and
    the parent would see the pickling's error (or a broken pool) instead of it."""
    try:
        pickle.loads(pickle.dumps(exc))
    except Exception:  # noqa: BLE001 - whatever pickling raises
        return False
    return True


class _PoolRun:
    """The items over this machine's worker processes, in pools (module docstring):
    ``results`` (None until an item finishes), ``stopped`` (items a signal stopped while
    they ran), each item's state in ``states`` (shared with the workers)."""

    def __init__(self, fn, items: list, done, lose):
        self.fn, self.items, self.done, self.lose = fn, items, done, lose
        self.context = _pool_context()
        self.stopper = _Stopper(self.context.RawValue("b", 0))
        self.states = self.context.RawArray("b", len(items))
        self.results: list = [None] * len(items)
        self.stopped: list[int] = []

    def run(self, workers: int) -> list:
        queue = list(range(len(self.items)))
        idle = 0  # pools in a row that broke with no item finished or running
        with _handling(self.stopper):
            while queue and self.stopper.signum is None:
                broken = self._round(queue, workers)
                if broken is None:
                    break
                suspects, left = broken
                idle = 0 if suspects or len(left) < len(queue) else idle + 1
                queue = left
                if idle == MAX_IDLE_POOLS:  # workers that end before taking an item
                    for k in queue:
                        self.results[k] = self.lose(k, NEVER_RAN)
                    break
                if not suspects:
                    continue
                print(f"frictex: warning: a worker process ended abruptly (killed, as the "
                      f"system's out-of-memory killer does, or crashed) while {len(suspects)} "
                      f"{'item' if len(suspects) == 1 else 'items'} ran: each runs again alone",
                      file=sys.stderr)
                for k in suspects:  # each alone: the one that ends its worker again is lost
                    if self.stopper.signum is None and self._round([k], 1) is not None:
                        self.results[k] = self.lose(k, LOST_HERE)
        if self.stopper.signum is not None:
            raise Interrupted(self.stopper.signum, self.results, sorted(self.stopped))
        return self.results

    def _round(self, indices: list[int], workers: int):
        """Items ``indices`` over a new pool of ``workers``; None, or where a worker ended
        abruptly, the unfinished items running then and those not started."""
        from concurrent.futures import FIRST_COMPLETED, ProcessPoolExecutor, wait
        from concurrent.futures.process import BrokenProcessPool
        for k in indices:
            self.states[k] = 0
        pool = ProcessPoolExecutor(workers, mp_context=self.context,
                                   initializer=_start_worker,
                                   initargs=(self.stopper.flag, self.states, os.getpid()))
        broken, futures = False, {}
        try:
            try:
                for k in indices:
                    futures[pool.submit(_run_item, self.fn, self.items[k], k)] = k
            except BrokenProcessPool:  # a worker died already: the rest are not started
                broken = True
            pending = set(futures)
            while pending and self.stopper.signum is None and not broken:
                finished, pending = wait(pending, timeout=POLL_S, return_when=FIRST_COMPLETED)
                for future in finished:
                    broken |= not self._take(future, futures[future])
        finally:
            pool.shutdown(wait=True, cancel_futures=True)
        for future in pending:
            if not future.cancelled():
                broken |= not self._take(future, futures[future])
        if not broken:
            return None
        left = [k for k in indices if self.results[k] is None and k not in self.stopped]
        return ([k for k in left if self.states[k] == _RUNNING],
                [k for k in left if self.states[k] != _RUNNING])

    def _take(self, future, k: int) -> bool:
        """Item ``k``'s outcome from its ``future``; False where its pool broke."""
        from concurrent.futures.process import BrokenProcessPool
        try:
            outcome, result = future.result()
        except BrokenProcessPool:
            return False
        if outcome == DONE:
            self.results[k] = result
            self.done(result)
        elif outcome == STOPPED:
            self.stopped.append(k)
            if self.stopper.signum is None:  # a worker signalled on its own: stop all
                self.stopper(signal.SIGINT, None)
        return True


def _pool(fn, items: list, workers: int, done, lose) -> list:
    """The items over ``workers`` processes of this machine (:class:`_PoolRun`), stopped
    by a signal."""
    return _PoolRun(fn, items, done, lose).run(workers)


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


def _dask(fn, items: list, address: str, done, lose, noun: str) -> list:
    """The items on the Dask cluster at ``address``, stopped by a signal (the stopper
    :func:`_here` uses) or by the cluster having no worker (module docstring)."""
    client = _dask_client(address)
    stopper = _Stopper()
    lost = False
    try:
        with _handling(stopper):
            futures = client.map(fn, items, pure=False)
            try:
                return _dask_results(client, futures, stopper, _WorkerWatch(client, address, noun),
                                     done, lose, noun)
            except SchedulerLost:
                lost = True  # nothing to cancel on a scheduler that has gone
                raise
            except BaseException:
                client.cancel(futures)
                raise
    finally:
        if lost:  # closing cancels the client's attempts to reconnect, each logged with
            with _silent("distributed.client"):  # a traceback: the loss is said once
                client.close()
        else:
            client.close()


@contextmanager
def _silent(logger: str):
    """The log records of ``logger`` dropped meanwhile."""
    import logging
    log = logging.getLogger(logger)
    was, log.disabled = log.disabled, True
    try:
        yield
    finally:
        log.disabled = was


def _dask_client(address: str):
    """A client of the Dask scheduler at ``address``; a one-line error where there is none."""
    try:
        from distributed import Client
    except ImportError:
        raise MissingExtra("cluster", "--scheduler", "dask.distributed") from None
    from distributed.comm import resolve_address
    try:
        resolve_address(address)
    except (ValueError, TypeError) as exc:  # not an address ("missing port number")
        raise InputError(f"--scheduler {address}: not a scheduler's address ({exc}); "
                         "expected tcp://HOST:PORT") from None
    except OSError as exc:  # a host name that does not resolve
        raise OSError(f"cannot reach the Dask scheduler at {address}: {exc}") from None
    try:
        _shake_hands(address)
        return Client(address, timeout=CONNECT_S)
    except TimeoutError:
        raise OSError(f"cannot reach the Dask scheduler at {address}: no answer within "
                      f"{CONNECT_S:.0f} s") from None
    except OSError as exc:
        raise OSError(f"cannot reach the Dask scheduler at {address}: {exc}") from None


def _shake_hands(address: str) -> None:
    """Connect to ``address`` as a Dask client does, exchange the handshake and part,
    all within :data:`CONNECT_S` (else ``TimeoutError``); ``OSError`` where what answers
    is not a Dask scheduler.

    distributed's own connect waits on the handshake without limit: a server that accepts
    and stays silent held ``frictex batch`` for ever, and one that answers in another
    protocol (HTTP's 'HTTP/1.1 400') had its first bytes read as a frame's length, an
    allocation of exabytes (``MemoryError``). Once a Dask scheduler has answered here,
    the client's connect is bounded by its own timeouts.
    """
    import asyncio
    from distributed import Security
    from distributed.comm import connect

    async def handshake():
        comm = await connect(address, timeout=CONNECT_S,
                             **Security().get_connection_args("client"))
        await comm.close()

    try:
        asyncio.run(asyncio.wait_for(handshake(), CONNECT_S))
    except OSError:
        raise
    except Exception as exc:  # whatever the reader made of a stranger's bytes
        raise OSError(f"what answers there is not a Dask scheduler ({type(exc).__name__} "
                      "in the handshake)") from None


def _dask_results(client, futures: list, stopper: _Stopper, watch: "_WorkerWatch",
                  done, lose, noun: str) -> list:
    """The results of ``futures`` in their order, taken as they finish (every
    :data:`POLL_S`, so that a signal the stopper kept is seen); :class:`Interrupted` once
    it keeps one (:func:`_stop_on_dask`), :class:`NoWorkers` when ``watch`` gives up;
    ``lose(k, why)`` the result of item ``k`` whose workers died (``KilledWorker``);
    :class:`SchedulerLost` when the scheduler goes (a future cancelled for want of its
    connection, or the connection closed), with the results taken so far."""
    from concurrent.futures import CancelledError

    from distributed import as_completed
    results: list = [None] * len(futures)
    index = {future.key: k for k, future in enumerate(futures)}
    finished = as_completed(futures)
    while not finished.is_empty() and stopper.signum is None:
        try:
            for future in finished.next_batch(block=False):
                _take_from_dask(future, index[future.key], results, done, lose)
            watch.check(results)
        except (CancelledError, OSError) as exc:  # only the scheduler's loss cancels here
            detail = getattr(exc, "reason", None) or f"{type(exc).__name__}: {exc}"
            raise SchedulerLost(watch.address, detail, results, noun) from None
        time.sleep(POLL_S)
    if stopper.signum is not None:
        raise Interrupted(stopper.signum, results,
                          _stop_on_dask(client, futures, results, done, lose, noun))
    return results


def _take_from_dask(future, k: int, results: list, done, lose) -> None:
    """Item ``k``'s result from its finished ``future`` into ``results``: its value
    (``done`` called), or ``lose``'s where its workers died."""
    from distributed import KilledWorker
    try:
        results[k] = future.result()
    except KilledWorker:
        results[k] = lose(k, LOST_ON_DASK)
        return
    done(results[k])


def _stop_on_dask(client, futures: list, results: list, done, lose, noun: str) -> list[int]:
    """After a signal: cancel the items not started, give those running on a worker up
    to :data:`DASK_STOP_S` to finish (their results, and those of the items that
    finished since the last look, taken into ``results``), then cancel them too and
    warn if any still runs (the items named ``noun``). Returns the indices of the items that started and did not
    finish: one still running goes on to its end on its worker (Dask cannot stop a
    running task), its result dropped."""
    unfinished = [k for k in range(len(futures)) if results[k] is None]
    started = _running_on_dask(client, futures, unfinished)
    client.cancel([futures[k] for k in unfinished if k not in started])
    deadline_s = time.monotonic() + DASK_STOP_S
    while True:
        for k in unfinished:
            if results[k] is None and futures[k].status in ("finished", "error"):
                _take_from_dask(futures[k], k, results, done, lose)
        # the futures, not the workers' threads, say when an item is done: one that has
        # left its thread may not have reached the client as finished yet
        if all(results[k] is not None for k in started) or time.monotonic() >= deadline_s:
            break
        time.sleep(POLL_S)
    running = _running_on_dask(client, futures, [k for k in started if results[k] is None])
    stopped = [k for k in unfinished if results[k] is None and futures[k].status != "cancelled"]
    client.cancel([futures[k] for k in stopped])
    if running:
        print(f"frictex: warning: {len(running)} of the {noun} stopped still running on their "
              f"Dask workers after {DASK_STOP_S:.0f} s (Dask cannot stop a running task): "
              f"results dropped", file=sys.stderr)
    return stopped


def _running_on_dask(client, futures: list, indices: list[int]) -> set[int]:
    """Those of ``indices`` whose future a worker's thread is running now.

    The scheduler's ``processing`` would also list the tasks a worker holds queued
    behind its threads (a 1-thread worker holds 2), which have not started: the
    workers' call stacks list only the tasks running in a thread.
    """
    keys = {futures[k].key: k for k in indices}
    if not keys:
        return set()
    return {keys[key] for stacks in client.call_stack(keys=list(keys)).values()
            for key in stacks if key in keys}


class _WorkerWatch:
    """Counts a Dask cluster's workers at most every :data:`WORKER_CHECK_S`: warns once
    when it has none, raises :class:`NoWorkers` once it has had none for
    :data:`NO_WORKER_S` (of the items, ``noun``)."""

    def __init__(self, client, address: str, noun: str):
        self.client = client
        self.address = address
        self.noun = noun
        self.next_check_s = 0.0  # time.monotonic() of the next count
        self.none_since_s: float | None = None  # since when it has had none

    def check(self, results: list) -> None:
        now_s = time.monotonic()
        if now_s < self.next_check_s:
            return
        self.next_check_s = now_s + WORKER_CHECK_S
        if self.client.nthreads():
            self.none_since_s = None
        elif self.none_since_s is None:
            self.none_since_s = now_s
            print(f"frictex: warning: the Dask cluster at {self.address} has no worker; "
                  f"waiting up to {NO_WORKER_S:.0f} s for one", file=sys.stderr)
        elif now_s - self.none_since_s >= NO_WORKER_S:
            raise NoWorkers(self.address, now_s - self.none_since_s, results, self.noun)
