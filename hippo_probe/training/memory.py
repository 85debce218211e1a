"""Process-level memory setting of a training run: keep freed activations for reuse."""

from __future__ import annotations

import ctypes
import sys

#: glibc ``mallopt`` parameters (malloc.h)
_M_TRIM_THRESHOLD, _M_MMAP_THRESHOLD = -1, -3

#: Blocks up to this size are kept by malloc for reuse: above a training step's largest
#: activation buffer (the LSTM's gates, 4 T B H float32 = 524 MB at T = 500, B = 256, H =
#: 256) and below ``int``'s limit, which ``mallopt`` takes.
REUSE_LIMIT_BYTES = 1 << 30


def reuse_freed_memory(limit_bytes: int = REUSE_LIMIT_BYTES) -> bool:
    """Let glibc's malloc keep freed blocks up to ``limit_bytes`` for reuse.

    By default glibc serves every block above 32 MiB with a fresh ``mmap`` and unmaps it on
    ``free``. A training step allocates and frees ~0.3 GB (batch 64) to ~1.2 GB (batch 256)
    of activations, so every step page-faulted all of it in again: measured here at batch
    64, 60,000-85,000 page faults and 0.15-0.2 s of kernel time per step, a quarter of the
    bf16 step. With both thresholds raised, freed blocks stay in the heap and the next step
    reuses them (from the third step on, 0 faults in most steps and a few thousand now
    and then, as the heap settles). The cost: the process keeps up to ``limit_bytes`` of freed
    memory instead of returning it. Process-wide and not undone (malloc has no getter to
    restore from). Returns whether it took effect (False off glibc).
    """
    if not sys.platform.startswith("linux"):
        return False
    try:
        mallopt = ctypes.CDLL(None).mallopt
    except (OSError, AttributeError):      # not glibc (musl has no mallopt)
        return False
    mallopt.argtypes = [ctypes.c_int, ctypes.c_int]
    mallopt.restype = ctypes.c_int
    limit = int(limit_bytes)
    return bool(mallopt(_M_MMAP_THRESHOLD, limit)) and bool(mallopt(_M_TRIM_THRESHOLD, limit))
