"""Keep the C heap's freed memory mapped for reuse (glibc's ``mallopt``; elsewhere nothing).

The pipeline's stages hand each other blocks of output samples as numpy arrays (0.4 MB
for 1000 blocks of 50 samples in a replay), freed once the next stage has read them.
glibc serves such sizes from the heap once it has seen one freed, but gives the heap's
free top back to the system whenever it exceeds twice the largest such size, so the
next call faults the same pages in again: 26,000 page faults in a 600 s replay of a
scene with every issue-18 layer, 109,000 for the composed scene, about 50 and 10 with
the thresholds below. Allocations under ``MMAP_THRESHOLD`` then always come from the
heap, and its free top is kept until it exceeds ``TRIM_THRESHOLD``: a process holds at
most that much more than it uses.
"""

from __future__ import annotations

import ctypes

#: mallopt's parameters (glibc's malloc.h) and the values set (bytes)
M_TRIM_THRESHOLD, M_MMAP_THRESHOLD = -1, -3
MMAP_THRESHOLD = 32 << 20  # glibc's largest on 64-bit systems
TRIM_THRESHOLD = 64 << 20


def keep_freed_memory() -> bool:
    """Set the process's heap thresholds (module docstring); False where the C library
    has no ``mallopt`` (not glibc) or refused a value."""
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = (ctypes.c_int, ctypes.c_int), ctypes.c_int
    return bool(mallopt(M_MMAP_THRESHOLD, MMAP_THRESHOLD)) and bool(
        mallopt(M_TRIM_THRESHOLD, TRIM_THRESHOLD))
