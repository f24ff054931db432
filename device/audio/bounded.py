"""PortAudio calls that can block forever, run with a bound.

PortAudio's JACK host API stops a stream by asking its callback thread to stop and then
waiting for it (``WaitCondition`` in pa_jack.c: up to 10 minutes). Once the JACK server
has gone the callback never runs again, so ``Pa_StopStream``, ``Pa_AbortStream`` and
``Pa_CloseStream`` (which aborts an active stream first) block the calling thread for 10
minutes, and the main thread's signal handlers with it: Python runs them only between
bytecodes, so Ctrl-C and SIGTERM did nothing until ``kill -9`` (a replay whose JACK server
was killed 2 s in was still alive 62 s later).

:func:`call_bounded` runs such a call in a daemon thread and waits for it at most
``limit_s``; the wait is interruptible (a signal handler that raises ends it). A call that
has not returned by then is abandoned, on purpose: its thread stays blocked inside
PortAudio until the process ends (a daemon thread does not hold the exit), and
:func:`abandon_portaudio` unregisters sounddevice's exit handler, which would stop,
close and terminate PortAudio at exit and so block on the same stream again.
"""

from __future__ import annotations

import atexit
import threading


def call_bounded(call, limit_s: float) -> bool:
    """Run ``call()`` in a daemon thread; True once it has returned, False if it has not
    within ``limit_s`` (s): then it is abandoned (module docstring), still running.
    What ``call`` raises is raised here. A signal handler that raises during the wait
    (Ctrl-C) raises here too, the call left running."""
    done = threading.Event()
    raised: list[BaseException] = []

    def run() -> None:
        try:
            call()
        except BaseException as exc:  # noqa: BLE001 - handed to the waiting thread
            raised.append(exc)
        finally:
            done.set()

    threading.Thread(target=run, name="frictex-portaudio-call", daemon=True).start()
    if not done.wait(limit_s):
        return False
    if raised:
        raise raised[0]
    return True


def abandon_portaudio(sd) -> None:
    """After a PortAudio call was abandoned: unregister sounddevice's exit handler
    (``sd._exit_handler``, which stops and closes the last stream and terminates
    PortAudio), so that the process can end. The caller touches the stream no more."""
    handler = getattr(sd, "_exit_handler", None)
    if handler is not None:
        atexit.unregister(handler)
