"""The process's allocator: large arrays go back to the operating system when they are freed.

glibc's ``malloc`` serves a block above its mmap threshold from a mapping of its own, unmapped on ``free``; a
smaller one comes from the heap, whose freed memory stays with the process unless it lies at the heap's top. The
threshold starts at 128 KiB and rises to the size of each mapped block freed, up to 32 MiB, so once a few large
arrays have come and gone every array under 32 MiB lives on the heap. The model check on a long log makes columns of
3 x N doubles by the hundred (12 MB at N = 500,000) and drops them as it goes; on the heap the dropped ones stayed
resident, and a 500,000-row log peaked at 2.7 GB of which about 1.7 GB was live. Called once by a process's entry
point (the CLI, a service worker), :func:`large_arrays_to_the_os` fixes the threshold at :data:`THRESHOLD`: arrays
above it are mapped and unmapped, the smaller ones (most of them: a log under ~175,000 rows makes none above it) are
served as before. Fixing it is a process-wide choice, so library calls leave it to the caller.
"""

from __future__ import annotations

import ctypes

#: blocks above this many bytes get a mapping of their own, returned to the system when freed
THRESHOLD = 4 << 20
#: glibc's ``mallopt`` parameter of the mmap threshold (malloc.h); setting it also stops it from rising
_M_MMAP_THRESHOLD = -3


def large_arrays_to_the_os(threshold: int = THRESHOLD) -> bool:
    """Fix the C library's mmap threshold at ``threshold`` [bytes] for this process (module doc). True if the C
    library took it (glibc); False where there is no ``mallopt`` or it refuses (another C library: nothing
    changes)."""
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):
        return False
    mallopt.argtypes, mallopt.restype = [ctypes.c_int, ctypes.c_int], ctypes.c_int
    return bool(mallopt(_M_MMAP_THRESHOLD, threshold) == 1)
