"""Memory the process has freed, handed back to the operating system.

glibc's ``malloc`` serves a block under its mmap threshold from the heap, and the threshold rises to the size of
each mapped block freed, up to 32 MiB: once a few large arrays have come and gone, every array under 32 MiB lives on
the heap, and a freed one's pages stay resident unless they lie at the heap's top. The model check on a long log
makes columns of 3 x N doubles by the hundred (12 MB at N = 500,000) and drops each once it is written into the
design (:func:`ocp.identify.footprint.weighted`); kept by the heap, the dropped columns were resident beside the array
they were written into: a 500,000-row log peaked at 2.7 GB where about 1.7 GB was live. :func:`give_back` returns
the heap's free pages (``malloc_trim``); the design's writer calls it after every :data:`GIVE_BACK_BYTES` dropped.
Fixing the threshold low instead (``mallopt``) was tried: arrays above it are mapped and page-faulted afresh each
time, and blind log 34 (183k rows) took 25 % longer.
"""

from __future__ import annotations

import ctypes
from collections.abc import Callable

#: bytes a loop may drop before it hands the heap's free pages back (:func:`give_back`): a few calls on the
#: longest logs, none on a log whose columns all fit in it
GIVE_BACK_BYTES = 64 << 20

_TRIM: list[Callable[[int], int] | None] = []  # glibc's malloc_trim once looked up (None: not available)


def give_back() -> bool:
    """Return the heap's free pages to the operating system (glibc's ``malloc_trim(0)``: a few milliseconds on a
    heap of a gigabyte). True if they were looked at; False where the C library has no ``malloc_trim``."""
    if not _TRIM:
        try:
            trim = ctypes.CDLL(None).malloc_trim
            trim.argtypes, trim.restype = [ctypes.c_size_t], ctypes.c_int
            _TRIM.append(trim)
        except (OSError, AttributeError):
            _TRIM.append(None)
    if _TRIM[0] is None:
        return False
    _TRIM[0](0)
    return True
