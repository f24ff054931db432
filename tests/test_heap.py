"""The heap thresholds frictex sets (``app.engine.heap``): blocks freed and allocated again
do not fault their pages in again."""

import platform
import subprocess
import sys
from pathlib import Path

import pytest

#: a stage's pattern: a few temporaries of a block's size, freed before the next call
CHURN = """
import resource, sys
import numpy as np
from frictex.app.engine.heap import keep_freed_memory
if sys.argv[1] == "keep":
    assert keep_freed_memory()
block = np.ones(50_000)
for _ in range(3):  # warm: the heap has grown to what a call needs
    a = block * 2.0; b = np.ones((2, 50_000)); c = a + b[0]; del a, b, c
before = resource.getrusage(resource.RUSAGE_SELF).ru_minflt
for _ in range(100):
    a = block * 2.0; b = np.ones((2, 50_000)); c = a + b[0]; d = np.zeros(400_000, bool)
    del a, b, c, d
print(resource.getrusage(resource.RUSAGE_SELF).ru_minflt - before)
"""


def _faults(mode: str) -> int:
    run = subprocess.run([sys.executable, "-c", CHURN, mode], capture_output=True, text=True,
                         check=True, cwd=Path(__file__).resolve().parents[1])
    return int(run.stdout)


@pytest.mark.skipif(platform.libc_ver()[0] != "glibc", reason="mallopt is glibc's")
def test_freed_blocks_are_reused_without_faulting_their_pages_in_again():
    default, kept = _faults("default"), _faults("keep")
    assert 50 * kept < default  # 100 calls of 2 MB: about 40,000 faults by default, 100 kept
