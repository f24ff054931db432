"""Build the reference firmware's targets for tests and tools (``make`` in this folder).

Outputs go to ``device/firmware/build/`` (ignored by git). A missing compiler is an error
that names the Debian package to install (``.ci/setup-firmware`` installs them all), never
a silent skip.
"""

from __future__ import annotations

import fcntl
import shutil
import subprocess
from pathlib import Path

from frictex.device.errors import FrictexError

FIRMWARE = Path(__file__).resolve().parent
BUILD = FIRMWARE / "build"
#: program -> Debian package that provides it
PACKAGES = {"make": "make", "cc": "gcc", "clang": "clang", "python3": "python3",
            "arm-none-eabi-gcc": "gcc-arm-none-eabi", "arm-none-eabi-size": "binutils-arm-none-eabi",
            "valgrind": "valgrind", "callgrind_annotate": "valgrind",
            "qemu-system-arm": "qemu-system-arm"}
#: what each make target needs
NEEDS = {"host": ("make", "cc"), "simlib": ("make", "cc"), "check": ("make", "cc"),
         "asan": ("make", "cc"), "fuzz": ("make", "clang", "python3"),
         "fuzz-loop": ("make", "cc", "python3"),
         "stm32g0": ("make", "arm-none-eabi-gcc", "arm-none-eabi-size"),
         "isr-cost": ("make", "cc", "valgrind", "callgrind_annotate"),
         "sf2": ("make", "arm-none-eabi-gcc")}


class FirmwareBuildError(FrictexError, RuntimeError):
    """A tool is missing or a build failed; the message says which and how to fix it."""


def require(*programs: str) -> None:
    missing = [t for t in programs if shutil.which(t) is None]
    if missing:
        pkgs = sorted({PACKAGES.get(t, t) for t in missing})
        raise FirmwareBuildError(
            f"{', '.join(missing)} not found: install the Debian package(s) {' '.join(pkgs)} "
            "(as root: bash .ci/setup-firmware)")


def make(*targets: str, timeout: float = 600.0, **variables: str) -> str:
    """Run ``make`` for ``targets`` in the firmware folder; returns its output.

    Builds are serialised with a lock file, so concurrent test runs share one build dir.
    """
    for target in targets:
        require(*NEEDS.get(target, ("make",)))
    BUILD.mkdir(exist_ok=True)
    args = ["make", "--no-print-directory", "-C", str(FIRMWARE), f"BUILD={BUILD}", *targets,
            *(f"{k}={v}" for k, v in variables.items())]
    with open(BUILD / ".lock", "w") as lock:
        fcntl.flock(lock, fcntl.LOCK_EX)
        proc = subprocess.run(args, capture_output=True, text=True, timeout=timeout)
    output = proc.stdout + proc.stderr
    if proc.returncode != 0:
        raise FirmwareBuildError(f"make {' '.join(targets)} failed ({proc.returncode}):\n"
                                 f"{output[-4000:]}")
    return output


def host_port() -> Path:
    """The host port binary (``frictex-fw-host``), built if needed."""
    make("host")
    return BUILD / "host" / "frictex-fw-host"


def sim_library() -> Path:
    """The virtual-clock shared library (``libfwsim.so``), built if needed."""
    make("simlib")
    return BUILD / "host" / "libfwsim.so"
