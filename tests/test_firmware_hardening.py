"""The firmware under AddressSanitizer and UndefinedBehaviorSanitizer, and fuzzed: no
input crashes it, reads out of bounds, or gets a frame that failed its CRC played."""

import re
import subprocess

import pytest

from frictex.device.firmware.build import BUILD, FIRMWARE, FirmwareBuildError, make
from test_firmware_link import stream_and_check

SANITIZER_REPORT = re.compile(r"runtime error|ERROR: (Address|Leak|Undefined)Sanitizer")


def _make(*targets, **variables):
    try:
        return make(*targets, **variables)
    except FirmwareBuildError as exc:
        pytest.fail(str(exc), pytrace=False)


@pytest.fixture(scope="module")
def asan_build():
    _make("asan")
    return BUILD / "asan"


def test_the_vectors_pass_under_the_sanitizers(asan_build):
    out = subprocess.run([str(asan_build / "check_vectors"), str(FIRMWARE / "vectors" /
                                                                 "frames.json")],
                         capture_output=True, text=True, timeout=300)
    assert out.returncode == 0 and not SANITIZER_REPORT.search(out.stderr), out.stderr[-3000:]
    assert " 0 failed" in out.stdout


def test_a_link_session_with_the_sanitized_host_port_reports_nothing(asan_build, tmp_path):
    stderr, played, _ = stream_and_check(asan_build / "frictex-fw-host", tmp_path)
    assert not SANITIZER_REPORT.search(stderr), stderr[-3000:]
    assert f"played {played} samples" in stderr


def test_libfuzzer_finds_nothing_in_15_seconds():
    out = _make("fuzz", FUZZ_SECONDS="15")
    runs = re.search(r"Done (\d+) runs in (\d+) second", out)
    # thousands of runs even on a loaded machine (about 45000 on an idle one)
    assert runs and int(runs.group(1)) > 1_000, out[-3000:]
    assert not SANITIZER_REPORT.search(out) and "deadly signal" not in out, out[-3000:]
    assert not list((BUILD / "fuzz").glob("crash-*"))


def test_the_random_mutation_loop_finds_nothing_in_3_seconds():
    """The fuzz driver for machines without libFuzzer (gcc only)."""
    out = _make("fuzz-loop", FUZZ_SECONDS="3")
    runs = re.search(r"fuzz_loop: (\d+) inputs in 3 s, no failure", out)
    assert runs and int(runs.group(1)) > 1_000, out[-2000:]
