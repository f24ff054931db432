"""The live haptic pipeline in a child process, so that the window's GL calls cannot
starve it.

moderngl holds the GIL for the whole of each GL call; on a software renderer (Mesa
llvmpipe) a frame's calls take 10-25 ms, longer than a block's 5 ms deadline, so a
haptic *thread* in the window's process misses deadlines while the window draws. Here
the child runs the same :class:`app.live.haptic_thread.HapticThread` (plus a small bridge
thread for scene switches and shutdown); the window talks to it through bounded
``multiprocessing`` queues that never block it (touches: a full queue drops the sample,
counted; snapshots: the child drops the oldest, counted) and an ``mp.Event`` for the
emergency stop, which the child reads at every block.

The link (``--device``), the recording (``--record``) and a touch screen (``--input tuio``
or ``evdev``: read by a thread of the child, ``app.live.touch_pump``, so that its
samples reach the pipeline as they arrive however slow the window's frames are) are
opened in the child, which sends: the status with every snapshot, a touch screen's
failure, and the final stats and link status when it stops. The force the wheel sets
for a touch screen's fingers is a shared ``mp.Value``.
A scene switch sends the scene's file and the renderer (and the file's text as the
layer panel edited it, not saved yet); the child loads and builds it, and an error comes back as a message (the old scene stays). The child stops when asked,
when its haptic thread fails, or when the window's process is gone.

The child never outlives the window's process (:func:`die_with_parent`). Two watches
tell it the parent died, however: the kernel's parent-death signal (Linux
``prctl(PR_SET_PDEATHSIG, SIGTERM)``; sent when the thread that started the child
ends, so a :class:`HapticProcess` is made on a thread that lives as long as the window,
the demo's main thread; a SIGTERM while the parent lives stops the child cleanly, as a
stop request does, and the window is told its output stopped) and a thread waiting on the parent's end of the pipe ``multiprocessing`` leaves
the child (readable when the parent's process is gone, on any system). Either one
stops the queues the child writes from flushing at exit (the child holds both ends of
their pipes: with no reader left, a full pipe held its exit for good: 25 minutes and
more after the window died) and arms a hard exit ``PARENT_GONE_EXIT_S`` later; in
between, the bridge loop sees the parent gone and shuts down as when asked (the link
closed, the recording committed). The child ignores SIGINT and SIGHUP, which a
terminal sends the whole process group: the window's process ends the demo on them.
So does ``multiprocessing``'s resource tracker, another process of the group that
cleans up the queues' semaphores: it ignores SIGINT and SIGTERM itself, and is started
with SIGHUP ignored (:func:`start_resource_tracker`); a SIGHUP to the group killed it,
and the window's process printed a warning and 17 tracebacks of its replacement.

Both processes stamp with ``time.perf_counter`` (on Linux CLOCK_MONOTONIC, one clock for
the whole machine), so the window's ``now()`` is the child's output clock.
"""

from __future__ import annotations

import ctypes
import gc
import multiprocessing as mp
import multiprocessing.connection as mp_connection
import os
import pickle
import queue
import signal
import sys
import threading
import time
from dataclasses import dataclass
from pathlib import Path

from frictex.app.live.haptic_thread import (COMMAND_QUEUE, SNAPSHOT_QUEUE, TOUCH_QUEUE,
                                           ChannelMismatch, HapticStats, TouchInput,
                                           shorten_switch_interval)
from frictex.device.actuation.factory import make_actuation

WINDOW_NICE = 10  # how much lower than the haptic child the window's threads run
START_TIMEOUT_S = 60.0  # spawn, imports, scene load and build, link handshake
SWITCH_TIMEOUT_S = 30.0  # a modal scene's build
STOP_TIMEOUT_S = 30.0  # the recording's queued blocks are written before the child says done
PARENT_CHECK_S = 0.2  # how often the idle bridge looks whether the window's process lives
#: once the window's process is gone, the child exits at the latest this much later (s):
#: the haptic thread's join and the link's close (haptic_setup.JOIN_TIMEOUT_S) fit in it
PARENT_GONE_EXIT_S = 15.0
PR_SET_PDEATHSIG = 1  # linux/prctl.h


class HapticProcessError(OSError):
    """The haptic child process did not start, answer or stop as expected."""


@dataclass(frozen=True)
class HapticConfig:
    """What the child needs to build its pipeline, link, recorder and touch screen (units
    as in ``HapticThread``; ``device``: ``--device`` spec or None; ``record``: folder or
    None; ``touch_input``: a touch screen's (name, argument) as
    ``app.live.inputs.parse_input`` gives them, or None; ``faults``: a
    ``device.link.faults.FaultPlan`` for the link, or None; ``control``: the friction
    loop's mode instead of the scene file's; ``sim_args``: ``frictex sim-device`` flags)."""

    scene_path: Path
    rate_hz: float
    block_size: int
    render_override: str | None
    device: str | None
    record: Path | None
    touch_input: tuple | None = None
    faults: object = None
    control: str | None = None
    sim_args: tuple[str, ...] = ()


@dataclass(frozen=True)
class PipelineInfo:
    """What the window needs of the child's pipeline: its channels and an actuation for
    the modal envelope view (``device.actuation.factory.make_actuation`` of the scene's device)."""

    channels: tuple[str, ...]
    actuation: object


def start_resource_tracker() -> None:
    """Start ``multiprocessing``'s resource tracker (if it does not run yet) with SIGHUP
    ignored, which it keeps: a terminal's SIGHUP to the process group then leaves it to
    clean up the queues' semaphores (module docstring). In the main thread only (signal
    handlers can be set nowhere else); elsewhere it starts as it would."""
    from multiprocessing import resource_tracker
    if threading.current_thread() is not threading.main_thread():
        resource_tracker.ensure_running()
        return
    previous = signal.signal(signal.SIGHUP, signal.SIG_IGN)
    try:
        resource_tracker.ensure_running()
    finally:
        signal.signal(signal.SIGHUP, previous)


class HapticProcess(TouchInput):
    """The demo's haptic side in a child process, with :class:`HapticThread`'s interface
    as the window uses it: ``now``, ``touch``, ``touch_at``, ``switch``, ``estop``,
    ``snapshots``, ``error``, ``input_error``, ``touch_force``, ``stop``, ``stats``,
    ``render_override``, ``pipeline``.

    Starts the child and waits until it runs; a failure to load the scene, open the
    link or the touch screen comes back as the child's exception (an InputError, an
    OSError, ...), raised here.
    """

    def __init__(self, scene, config: HapticConfig, clock=time.perf_counter):
        start_resource_tracker()
        ctx = mp.get_context("spawn")  # not fork: the window's process has GL and threads
        self.clock = clock
        self.block_s = config.block_size / config.rate_hz
        self.render_override = config.render_override
        self.scene = scene
        self.estop = ctx.Event()
        self.touch_force = ctx.Value("d", scene.device.normal_force_n, lock=False)
        self.touches = ctx.Queue(TOUCH_QUEUE)
        self.snapshots = ctx.Queue(SNAPSHOT_QUEUE)
        self._requests = ctx.Queue(COMMAND_QUEUE)
        self._replies = ctx.Queue()
        self.stats = HapticStats()
        self.link: dict = {"state": "none"}
        self.dropped_records = 0
        self._last_stamp = 0.0
        self._error: BaseException | None = None
        self._input_error: str | None = None
        self._done = False
        self._proc = ctx.Process(target=serve, name="frictex-haptic", daemon=True,
                                 args=(config, self.estop, self.touches, self.snapshots,
                                       self._requests, self._replies, self.touch_force))
        self._proc.start()
        reply = self._wait("ready", START_TIMEOUT_S)
        if reply[0] == "failed":
            self._proc.join(timeout=STOP_TIMEOUT_S)
            raise reply[1]  # the child's own exception: its kind decides the exit status
        self.t0 = reply[1]
        self.pipeline = PipelineInfo(reply[2], make_actuation(scene.device))

    @property
    def error(self) -> BaseException | None:
        """Why the child stopped on its own, the exception its haptic thread ended with
        (None while it runs, and after a clean stop)."""
        if self._done:
            return self._error
        self._poll(0.0)
        if self._error is None and not self._done and not self._proc.is_alive():
            self._error = HapticProcessError(f"haptic process exited with code "
                                             f"{self._proc.exitcode}")
        return self._error

    def input_error(self) -> str | None:
        """Why the child's touch screen stopped (once; None while it works or without one)."""
        self._poll(0.0)
        error, self._input_error = self._input_error, None
        return error

    def switch(self, scene=None, render_override: str | None | bool = False,
               text: str | None = None) -> PipelineInfo:
        """Change scene and/or renderer (False: keep the current renderer), as
        ``HapticThread.switch``: the child loads ``scene.source`` (read as ``text`` if
        given: the layer panel's edit, not saved) and builds it (the window waits for its
        answer, the haptic output does not); errors raise ValueError with the child's
        message (a scene for other channels: ``ChannelMismatch``), and nothing changes."""
        override = self.render_override if render_override is False else render_override
        new = scene is not None and scene is not self.scene
        if new and scene.source is None:
            raise ValueError(f"scene {scene.name} has no file: the haptic process loads "
                             "scenes from their files")
        self._requests.put(("switch", str(scene.source) if new else None, override,
                            text if new else None), timeout=SWITCH_TIMEOUT_S)
        reply = self._wait("switched", SWITCH_TIMEOUT_S)
        if isinstance(reply[1], ChannelMismatch):
            raise reply[1]
        if reply[1] is not None:
            raise ValueError(str(reply[1]))
        if new:
            self.scene = scene
            self.pipeline = PipelineInfo(reply[2], make_actuation(scene.device))
        self.render_override = override
        return self.pipeline

    def stop(self) -> None:
        """Stop the child and collect its final ``stats``, ``link`` status and
        ``dropped_records`` (the child's dropped touches add to the window's); raises
        HapticProcessError (an OSError) if it ended without reporting them. Whatever
        interrupts the wait (a second signal raised in it) still ends the child, at once:
        left running, it blocked on a queue nobody read, and the interpreter's exit waited
        on it for ever."""
        waited = False
        try:
            if self._proc.is_alive() and not self._done:
                try:
                    self._requests.put(("stop",), timeout=1.0)
                    self._wait("done", STOP_TIMEOUT_S, past_errors=True)
                except (HapticProcessError, queue.Full):
                    pass  # it hung or died: terminated below, and said so
            waited = True
        finally:
            self._end_child(grace_s=2.0 if waited else 0.0)
        if not self._done:
            raise HapticProcessError(f"haptic process ended (exit code {self._proc.exitcode}) "
                                     "without reporting its stats and link status")

    def _end_child(self, grace_s: float) -> None:
        """The child ended: waited for ``grace_s`` (s), then terminated, then killed, each
        wait bounded; the queues closed without waiting on what they hold. A signal raised
        in a wait (the run's second: later ones are held) skips only that wait."""
        try:
            self._proc.join(timeout=grace_s)
        finally:
            try:
                if self._proc.is_alive():
                    self._proc.terminate()
                    self._proc.join(timeout=2.0)
            finally:
                if self._proc.is_alive():  # its SIGTERM is a stop request it did not take
                    self._proc.kill()
                    self._proc.join()
                for q in (self.touches, self.snapshots, self._requests, self._replies):
                    q.cancel_join_thread()  # a full queue must not hold the window at exit
                    q.close()

    def _wait(self, kind: str, timeout_s: float, past_errors: bool = False) -> tuple:
        """The child's next reply of ``kind`` (or its failure; ``past_errors``: wait on
        past a failure it reported, as it still reports its stats when it stops); other
        replies are noted."""
        deadline = time.monotonic() + timeout_s
        while True:
            reply = self._poll(min(0.1, max(deadline - time.monotonic(), 0.0)), want=kind)
            if reply is not None:
                return reply
            if self._error is not None and not past_errors:
                raise HapticProcessError(f"haptic process failed: {self._error}")
            if not self._proc.is_alive() and self._replies.empty():
                raise HapticProcessError(f"haptic process exited with code {self._proc.exitcode} "
                                         f"while the window waited for {kind!r}")
            if time.monotonic() > deadline:
                raise HapticProcessError(f"haptic process did not answer {kind!r} "
                                         f"within {timeout_s:g} s")

    def _poll(self, timeout_s: float, want: str | None = None) -> tuple | None:
        """Handle the replies waiting (the first up to ``timeout_s``); return the first
        of kind ``want`` (a start failure counts as an answer to "ready")."""
        block = timeout_s > 0
        while True:
            try:
                reply = self._replies.get(block, timeout_s) if block else self._replies.get_nowait()
            except queue.Empty:
                return None
            block = False
            if reply[0] == "error":
                self._error = reply[1]
            elif reply[0] == "input-failed":
                self._input_error = reply[1]
            elif reply[0] == "done":
                self._done = True
                dropped_here = self.stats.dropped_touches
                self.stats, self.link, self.dropped_records = reply[1:]
                self.stats.dropped_touches += dropped_here
            if reply[0] == want or (want == "ready" and reply[0] == "failed"):
                return reply


def yield_to_haptic(increment: int = WINDOW_NICE, keep: tuple[int, ...] = ()) -> int | None:
    """Lower the priority of the threads of this (the window's) process, but those whose
    native ids are in ``keep``, by ``increment`` nice steps (threads they start later
    inherit it); returns how many were lowered, or None where the system has no
    per-thread priorities.

    On two cores the window's software renderer (llvmpipe runs a thread per core) and
    the haptic child compete; at equal priority the child waited up to 20 ms for a core
    while a frame was drawn. Any user may lower their own priority, and the renderer
    only needs what the child leaves (a few percent of a core). The demo keeps its input
    thread (``keep``): it mostly sleeps, and a finger must not wait for a core."""
    try:
        lowered = 0
        for tid in map(int, os.listdir("/proc/self/task")):
            if tid not in keep:
                os.setpriority(os.PRIO_PROCESS, tid,
                               min(os.getpriority(os.PRIO_PROCESS, tid) + increment, 19))
                lowered += 1
        return lowered
    except (OSError, AttributeError):
        return None


class _ParentWatch:
    """What the child does when its parent is gone (:func:`die_with_parent`): once,
    stop ``outgoing`` queues from flushing at exit and arm the hard exit."""

    def __init__(self, outgoing, exit_after_s: float):
        self.outgoing = outgoing
        self.exit_after_s = exit_after_s
        self.gone = threading.Event()
        self.terminated = threading.Event()  # a SIGTERM while the parent lives
        self._lock = threading.Lock()

    def parent_gone(self, *_signal) -> None:
        with self._lock:
            if self.gone.is_set():
                return
            self.gone.set()
        for q in self.outgoing:
            q.cancel_join_thread()  # no reader will ever take what is still buffered
        threading.Thread(target=self._hard_exit, name="frictex-orphan-exit", daemon=True).start()

    def _hard_exit(self) -> None:
        time.sleep(self.exit_after_s)
        os._exit(1)  # the clean shutdown hung: the parent is gone, nobody waits for it


def _set_parent_death_signal(signum: int) -> bool:
    """Ask the kernel to send ``signum`` to this process when its parent (the thread
    that started it) ends; False where the system has no such request (not Linux)."""
    if not sys.platform.startswith("linux"):
        return False
    try:
        libc = ctypes.CDLL(None, use_errno=True)
        return libc.prctl(PR_SET_PDEATHSIG, signum, 0, 0, 0) == 0
    except (OSError, AttributeError):
        return False


def die_with_parent(outgoing, exit_after_s: float = PARENT_GONE_EXIT_S) -> _ParentWatch:
    """Make this (child) process end when its parent does: see the module docstring.
    ``outgoing``: the ``multiprocessing`` queues this process writes to. Call it from
    the main thread, first thing (the signal handlers are installed there).

    Ctrl-C and a closed terminal reach the whole process group: the child ignores
    SIGINT and SIGHUP, and the window's process, which ends the demo on them, stops it
    as on Q. A SIGTERM while the parent lives (``timeout`` signals the group) is a stop
    request (``watch.terminated``): the child closes the link and commits the recording
    and says so to the window."""
    watch = _ParentWatch(tuple(outgoing), exit_after_s)
    parent = mp.parent_process()

    def on_sigterm(signum, _frame):
        if parent is not None and not parent.is_alive():
            watch.parent_gone()
        else:
            watch.terminated.set()
    for held in (signal.SIGINT, signal.SIGHUP):
        signal.signal(held, signal.SIG_IGN)
    signal.signal(signal.SIGTERM, on_sigterm)
    _set_parent_death_signal(signal.SIGTERM)
    if parent is not None:
        def wait_for_parent():
            mp_connection.wait([parent.sentinel])
            watch.parent_gone()
        threading.Thread(target=wait_for_parent, name="frictex-parent-watch", daemon=True).start()
    if parent is not None and not parent.is_alive():  # it died before the watches were set
        watch.parent_gone()
    return watch


def serve(config: HapticConfig, estop, touches, snapshots, requests, replies,
          touch_force) -> None:
    """The child process: build, run, answer switches, stop (see the module docstring)."""
    watch = die_with_parent((snapshots, replies))
    from frictex.app.live.haptic_setup import open_haptic  # the thread mode's own setup, in this process
    from frictex.app.live.inputs import open_source
    from frictex.textures.loader import load_scene
    shorten_switch_interval(config.block_size / config.rate_hz)
    try:
        scene = load_scene(config.scene_path)
        source = None if config.touch_input is None else open_source(*config.touch_input)
        haptic, finish = open_haptic(scene, config.rate_hz, config.block_size,
                                     config.render_override, config.device, config.record,
                                     faults=config.faults, source=source, estop=estop,
                                     control=config.control, sim_args=config.sim_args,
                                     touches=touches, snapshots=snapshots,
                                     touch_force=touch_force)
    except (ValueError, OSError, ModuleNotFoundError) as exc:  # open_haptic closed the source
        replies.put(("failed", _sendable(exc)))
        return
    # the built pipeline lives until the next switch: keep it out of the cyclic
    # collector's scans (a full collection of it took 15-30 ms, three blocks, here)
    gc.freeze()
    haptic.start()
    replies.put(("ready", haptic.t0, haptic.pipeline.channels))
    try:
        while (haptic.error is None and not watch.gone.is_set()
               and not watch.terminated.is_set()):
            if (failure := haptic.input_error()) is not None:
                replies.put(("input-failed", failure))
            try:
                request = requests.get(timeout=PARENT_CHECK_S)
            except queue.Empty:
                continue
            if request[0] == "stop":
                break
            replies.put(("switched", *_switch(haptic, load_scene, *request[1:])))
        if haptic.error is not None:
            replies.put(("error", _sendable(haptic.error)))
        elif watch.terminated.is_set():
            replies.put(("error", HapticProcessError("the haptic process was terminated "
                                                     "(SIGTERM); its output stopped")))
    finally:
        link, dropped_records = finish()
        if not watch.gone.is_set():
            replies.put(("done", haptic.stats, link, dropped_records))


def _sendable(exc: BaseException) -> BaseException:
    """``exc`` if it survives pickling (a LinkStalled does: the window exits as a replay
    would), else a RuntimeError saying what it was."""
    try:
        pickle.loads(pickle.dumps(exc))
        return exc
    except Exception:  # any exception a foreign __reduce__ may raise
        return RuntimeError(repr(exc))


def _switch(haptic, load_scene, path: str | None, override, text: str | None) -> tuple:
    """(error message, a ``ChannelMismatch``, or None; the pipeline's channels) of switching ``haptic`` to the
    scene in the file at ``path`` (read as ``text`` if given) with ``override``."""
    try:
        scene = None if path is None else load_scene(path, text=text)
        pipeline = haptic.switch(scene, override)
    except ChannelMismatch as exc:  # the window skips such a scene
        return exc, None
    except (ValueError, OSError, ModuleNotFoundError) as exc:
        return str(exc), None
    gc.freeze()  # as at the start
    return None, pipeline.channels
