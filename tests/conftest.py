"""Shared fixtures: one offscreen EGL context for all GL tests, and an Xvfb display.

A GL test takes ``gl`` (the shared context); ``ctx.error`` is checked to be
GL_NO_ERROR before and after each test so a test that leaves an error behind fails
itself rather than the next one. Tests skip only when the library or binary they need
is truly absent, and the skip names it.

No device link outlives its test (``_no_link_outlives_its_test``).

Ctrl-C is not ignored in the test process or the commands it starts: a shell starts a
background job (``pytest ... &`` in a script) with SIGINT ignored, which a run keeps
ignored, as it must (``app.engine.driver.deferred_interrupts``); the tests of Ctrl-C
mean the one a terminal sends.
"""

from __future__ import annotations

import os
import shutil
import signal
import subprocess

import pytest

# OpenBLAS on one thread: the suite's numpy work is on vectors of thousands of values,
# where a second BLAS thread gains nothing and, on a busy machine, spins against the
# tests' own processes (a simulated staircase session: 3.8-7.2 s of wall time with it,
# 1.6-3.3 s without, at load 7). Set before numpy loads; the commands tests start
# inherit it.
os.environ.setdefault("OPENBLAS_NUM_THREADS", "1")

from hypothesis import settings  # noqa: E402 (after the BLAS setting, in case it loads numpy)

# property tests: no deadline per example (a loaded 2-core machine pauses any example now
# and then: hypothesis would fail it as too slow or flaky) and the same examples every run
# (a failure reproduces); a test's own @settings change only what they name
settings.register_profile("frictex", deadline=None, derandomize=True)
settings.load_profile("frictex")

if signal.getsignal(signal.SIGINT) is signal.SIG_IGN:
    signal.signal(signal.SIGINT, signal.default_int_handler)


def signals_as_a_terminal_gives() -> None:
    """In a child process (``preexec_fn``): SIGINT and SIGHUP at their defaults, as a
    terminal gives them. A shell's background job inherits SIGINT ignored, ``nohup``
    SIGHUP, and frictex keeps an ignored signal ignored by design, so a test that sends
    one of them to a child it starts must not let the suite's own start decide."""
    for sig in (signal.SIGINT, signal.SIGHUP):
        signal.signal(sig, signal.SIG_DFL)


@pytest.fixture(scope="session")
def _egl_context():
    moderngl = pytest.importorskip("moderngl", reason="moderngl (Python package) not installed")
    try:
        ctx = moderngl.create_standalone_context(backend="egl")
    except Exception as exc:  # moderngl raises bare Exception when libEGL is missing
        pytest.skip(f"EGL (libEGL.so.1 with Mesa, Debian: libegl1 libegl-mesa0) unavailable: {exc}")
    yield ctx
    ctx.release()


@pytest.fixture
def gl(_egl_context):
    """The shared EGL context; fails the test if GL errors are pending before or after."""
    assert _egl_context.error == "GL_NO_ERROR", "a GL error was pending before this test"
    yield _egl_context
    assert _egl_context.error == "GL_NO_ERROR"


@pytest.fixture(scope="session")
def firmware_sim_library():
    """The C core built for the host (``device.firmware.build.sim_library``); a build
    that fails fails the tests that use it, with the compiler's message."""
    from frictex.device.firmware.build import FirmwareBuildError, sim_library
    try:
        return sim_library()
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


@pytest.fixture(scope="session")
def firmware_host_port():
    """The C firmware's host port built (``device.firmware.build.host_port``: the path of
    its binary); a build that fails fails the tests that use it, with the compiler's
    message."""
    from frictex.device.firmware.build import FirmwareBuildError, host_port
    try:
        return host_port()
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


@pytest.fixture(scope="session")
def xvfb_display():
    """A fresh Xvfb server on a free display number (Xvfb picks it: -displayfd)."""
    binary = shutil.which("Xvfb")
    if binary is None:
        pytest.skip("Xvfb binary not installed (Debian: xvfb)")
    read_fd, write_fd = os.pipe()
    proc = subprocess.Popen([binary, "-displayfd", str(write_fd), "-screen", "0", "1024x768x24",
                             "-nolisten", "tcp"], pass_fds=(write_fd,),
                            stdout=subprocess.DEVNULL, stderr=subprocess.DEVNULL)
    os.close(write_fd)
    with os.fdopen(read_fd) as pipe:
        number = pipe.readline().strip()
    if not number:
        proc.kill()
        proc.wait()
        raise RuntimeError("Xvfb started but did not report a display number")
    yield f":{number}"
    proc.terminate()
    proc.wait(timeout=10)


@pytest.fixture(autouse=True)
def _no_link_outlives_its_test(monkeypatch):
    """Close every CommandSink the test opened and fail if its link thread lives on.

    A link thread left running (its test failed before ``close``, or a close gave up on
    the join) keeps reconnecting to its port's path, and a later test's pseudo-terminal
    may get the same /dev/pts number: its device would then play another test's blocks.
    """
    from frictex.device.link.host import CommandSink

    opened = []
    init = CommandSink.__init__

    def registering_init(self, *args, **kwargs):
        opened.append(self)
        init(self, *args, **kwargs)
    monkeypatch.setattr(CommandSink, "__init__", registering_init)
    yield
    for sink in opened:
        thread = getattr(sink, "_thread", None)   # absent: the first connection failed
        if thread is None:
            continue
        sink.close()
        thread.join(timeout=30.0)
        assert not thread.is_alive(), f"{sink.label}: link thread still running after close"


@pytest.fixture
def in_process_renderers(monkeypatch):
    """RENDERERS and LAYER_RENDERERS as they are, restored after the test (what it
    registers in this process, and the lookups it makes, leave with it)."""
    from frictex.rendering.renderers import LAYER_RENDERERS, RENDERERS
    for registry in (RENDERERS, LAYER_RENDERERS):
        for field in ("_entries", "_origin", "_registered_by"):
            monkeypatch.setattr(registry, field, dict(getattr(registry, field)))
        monkeypatch.setattr(registry, "_readings", registry._readings)
