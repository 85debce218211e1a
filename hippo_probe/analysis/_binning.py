"""Per-bin sums of activity in one pass over the samples, eager or lazy (dask).

Every tuning analysis (rate maps, head-direction curves, their shuffles) reduces to the
same thing: for each bin ``b``, the number of samples in ``b`` and the sum of each unit's
activity over them. :func:`bin_sums` computes it with a numba kernel that reads each
sample's row of activity once and adds it to its bin's row, so no samples x bins matrix
is ever formed and memory stays ``O(bins x units)``. On a dask-backed recording each time
chunk is reduced on its own and the partial sums are added in a tree, so a recording much
larger than memory streams through; the same graph runs under a ``dask.distributed``
client.

Bins are given as one integer per sample (-1 = not counted, e.g. position lost or speed
too low). Circular time-shift shuffles are bins shifted against the activity; they are
computed in the same pass (``shifts``).
"""

from __future__ import annotations

from dataclasses import dataclass

import numba
import numpy as np

from .config import COMPUTE



@numba.njit(cache=True, nogil=True)
def _accumulate(activity, bins, t0, shifts, lo, sums, counts, amin, sumsq, want_min,
                want_sq):
    """Add the samples of one time block to the accumulators (in place).

    activity : (m, U) block of samples ``t0 .. t0 + m`` of the recording
    bins : (n,) compact bin of every sample of the recording, -1 = skipped
    shifts : (K,) circular shifts; shift ``k`` pairs activity at ``t`` with ``bins[t - s]``
    lo : compact bins are stored at ``index - lo`` (a block touches a narrow range)
    sums : (K, n_local, U) float64; counts : (K, n_local) int64
    amin : (U,) running minimum over all samples (valid or not), if ``want_min``
    sumsq : (n_local, U) per-bin sum of squares (unshifted bins), if ``want_sq``
    """
    m, n_units = activity.shape
    n = bins.shape[0]
    n_shifts = shifts.shape[0]
    for i in range(m):
        row = activity[i]
        if want_min:
            for u in range(n_units):
                amin[u] = min(amin[u], row[u])
        t = t0 + i
        for k in range(n_shifts):
            src = t - shifts[k]
            if src < 0:
                src += n
            b = bins[src]
            if b < 0:
                continue
            b -= lo
            counts[k, b] += 1
            acc = sums[k, b]
            for u in range(n_units):
                acc[u] += row[u]
            if want_sq and k == 0:
                sq = sumsq[b]
                for u in range(n_units):
                    sq[u] += row[u] * row[u]


@dataclass
class BinSums:
    """Sums over the samples of each bin.

    Attributes
    ----------
    sums : ndarray (K, n_bins, U)
        Sum of each unit's activity over the samples of each bin, for each shift.
    counts : ndarray (K, n_bins)
        Number of samples in each bin (identical for every shift of a permutation).
    amin : ndarray (U,)
        Each unit's minimum activity over every sample of the recording (NaN if not
        asked for).
    sumsq : ndarray (n_bins, U) or None
        Sum of squared activity over the samples of each bin (unshifted), if asked.
    """

    sums: np.ndarray
    counts: np.ndarray
    amin: np.ndarray
    sumsq: np.ndarray


def _block_range(bins, shifts, t0, t1):
    """Smallest and largest compact bin a block can touch, or (0, -1) if none."""
    n = bins.shape[0]
    lo, hi = np.iinfo(np.int64).max, -1
    for s in shifts:
        a, b = (t0 - s) % n, (t1 - 1 - s) % n
        parts = [bins[a:b + 1]] if a <= b else [bins[a:], bins[:b + 1]]
        for p in parts:
            valid = p[p >= 0]
            if valid.size:
                lo, hi = min(lo, int(valid.min())), max(hi, int(valid.max()))
    return (0, -1) if hi < 0 else (lo, hi)


def _partial(block, bins, t0, shifts, want_min, want_sq):
    """Reduce one (time, unit) block to (lo, sums, counts, amin, sumsq)."""
    block = np.ascontiguousarray(block)
    n_units = block.shape[1]
    lo, hi = _block_range(bins, shifts, t0, t0 + block.shape[0])
    width = hi - lo + 1
    sums = np.zeros((len(shifts), width, n_units))
    counts = np.zeros((len(shifts), width), np.int64)
    amin = np.full(n_units, np.inf)
    sumsq = np.zeros((width if want_sq else 0, n_units))
    if block.dtype.kind not in "fiu" or block.dtype == np.float16:
        block = block.astype(np.float64)
    _accumulate(block, bins, t0, shifts, lo, sums, counts, amin, sumsq, want_min, want_sq)
    return lo, sums, counts, amin if want_min else np.full(n_units, np.nan), sumsq


def _combine(parts):
    """Add partials that may cover different compact-bin ranges."""
    amin = np.minimum.reduce([p[3] for p in parts])  # blocks with no valid sample count too
    # (NaN when the minimum was not tracked: np.minimum propagates it)
    want_sq = any(p[4].shape[0] for p in parts)
    parts = [p for p in parts if p[1].shape[1] > 0] or parts[:1]
    lo = min(p[0] for p in parts)
    hi = max(p[0] + p[1].shape[1] for p in parts)
    k, _, n_units = parts[0][1].shape
    sums = np.zeros((k, hi - lo, n_units))
    counts = np.zeros((k, hi - lo), np.int64)
    sumsq = np.zeros((hi - lo if want_sq else 0, n_units))
    for p_lo, p_sums, p_counts, _, p_sumsq in parts:
        sl = slice(p_lo - lo, p_lo - lo + p_sums.shape[1])
        sums[:, sl] += p_sums
        counts[:, sl] += p_counts
        if p_sumsq.shape[0]:
            sumsq[sl] += p_sumsq
    return lo, sums, counts, amin, sumsq


def _finish(part, n_bins):
    lo, sums, counts, amin, sumsq = part
    k, width, n_units = sums.shape
    full_sums = np.zeros((k, n_bins, n_units))
    full_counts = np.zeros((k, n_bins), np.int64)
    full_sums[:, lo:lo + width] = sums
    full_counts[:, lo:lo + width] = counts
    full_sq = None
    if sumsq.shape[0]:
        full_sq = np.zeros((n_bins, n_units))
        full_sq[lo:lo + width] = sumsq
    return BinSums(full_sums, full_counts, amin, full_sq)


def _eager(activity, bins, shifts, want_min, want_sq, threads):
    """In-memory samples: contiguous blocks reduced in parallel threads (the kernel
    releases the GIL), then combined."""
    n = len(activity)
    threads = numba.get_num_threads() if threads is None else threads
    threads = max(1, min(threads, n // COMPUTE.min_samples_per_thread))
    if threads == 1:
        return _partial(activity, bins, 0, shifts, want_min, want_sq)
    from concurrent.futures import ThreadPoolExecutor

    edges = np.linspace(0, n, threads + 1).astype(int)
    with ThreadPoolExecutor(threads) as pool:
        parts = list(pool.map(
            lambda a, b: _partial(activity[a:b], bins, a, shifts, want_min, want_sq),
            edges[:-1], edges[1:]))
    return _combine(parts)


def bin_sums(activity, bins, n_bins, shifts=(0,), want_min=True, want_sq=False,
             threads=None):
    """Per-bin sample counts and activity sums, in one pass over the samples.

    .. math:: S_{k,b,u} = \\sum_{t:\\, bins[t - s_k] = b} a_{t,u}, \\qquad
              N_{k,b} = \\#\\{t: bins[t - s_k] = b\\}

    Parameters
    ----------
    activity : numpy or dask array (time, unit)
        Samples; a dask array is reduced chunk by chunk (lazily, bounded memory).
    bins : ndarray (time,) of int
        Bin of every sample in ``[0, n_bins)``; -1 = sample not counted.
    n_bins : int
        Number of bins.
    shifts : sequence of int
        Circular shifts (in samples) of ``bins`` against ``activity``; 0 = no shift.
    want_min : bool
        Also track each unit's minimum over all samples (for the non-negative shift of
        signed activity).
    want_sq : bool
        Also sum the squared activity per bin (unshifted).
    threads : int, optional
        Threads for an in-memory ``activity`` (default: ``numba.get_num_threads()``, which
        follows ``NUMBA_NUM_THREADS``). A dask array uses the dask scheduler's workers.

    Returns
    -------
    BinSums
    """
    bins = np.ascontiguousarray(bins, dtype=np.int64)
    shifts = np.asarray(shifts, dtype=np.int64) % max(len(bins), 1)
    if not hasattr(activity, "dask"):
        return _finish(_eager(np.asarray(activity), bins, shifts, want_min, want_sq, threads),
                       n_bins)

    import dask

    bins_d = dask.delayed(bins, pure=True)
    shifts_d = dask.delayed(shifts, pure=True)
    partial = dask.delayed(_partial, pure=True)
    combine = dask.delayed(_combine, pure=True)
    blocks = activity.to_delayed()
    starts = np.concatenate([[0], np.cumsum(activity.chunks[0])[:-1]])
    columns = []
    for j in range(blocks.shape[1]):
        parts = [partial(blocks[i, j], bins_d, int(starts[i]), shifts_d, want_min, want_sq)
                 for i in range(blocks.shape[0])]
        while len(parts) > 1:
            parts = [combine(parts[i:i + COMPUTE.split_every])
                     for i in range(0, len(parts), COMPUTE.split_every)]
        columns.append(parts[0])
    results = [_finish(r, n_bins) for r in dask.compute(*columns)]
    return BinSums(
        sums=np.concatenate([r.sums for r in results], axis=2),
        counts=results[0].counts,
        amin=np.concatenate([r.amin for r in results]),
        sumsq=None if not want_sq else np.concatenate([r.sumsq for r in results], axis=1),
    )


@numba.njit(cache=True)
def _compact(bins, groups, n_bins, n_total):
    seen = np.zeros(n_total, np.bool_)
    for t in range(bins.shape[0]):
        if bins[t] >= 0:
            seen[groups[t] * n_bins + bins[t]] = True
    index = np.full(n_total, -1, np.int64)
    occupied = np.empty(n_total, np.int64)
    k = 0
    for j in range(n_total):
        if seen[j]:
            index[j] = k
            occupied[k] = j
            k += 1
    out = np.full(bins.shape[0], -1, np.int64)
    for t in range(bins.shape[0]):
        if bins[t] >= 0:
            out[t] = index[groups[t] * n_bins + bins[t]]
    return out, occupied[:k]


def compact(bins, groups, n_bins, n_groups):
    """Number the visited (group, bin) pairs 0..m-1, in order of ``group * n_bins + bin``.

    Returns ``(compact_bins, occupied)``: the compact bin of every sample (-1 where
    ``bins`` is -1) and the flat index ``group * n_bins + bin`` of each compact bin. Keeps
    accumulators as small as the visited pairs even when the full grid (e.g. trials x
    bins) is large.
    """
    bins = np.ascontiguousarray(bins, dtype=np.int64)
    groups = np.ascontiguousarray(groups, dtype=np.int64)
    return _compact(bins, groups, n_bins, n_groups * n_bins)


@numba.njit(cache=True)
def grid_bins(x, y, x0, y0, size, nx, ny):
    """Flat bin ``iy * nx + ix`` of each point of a square grid; -1 outside or NaN.

    A point on the far edge of the grid belongs to the last bin. Returns
    ``(bins, n_nan, n_outside)``.
    """
    n = x.shape[0]
    bins = np.full(n, -1, np.int64)
    n_nan = 0
    n_out = 0
    x1, y1 = x0 + nx * size, y0 + ny * size
    for t in range(n):
        xt, yt = x[t], y[t]
        if not (np.isfinite(xt) and np.isfinite(yt)):
            n_nan += 1
            continue
        ix = int(np.floor((xt - x0) / size))
        iy = int(np.floor((yt - y0) / size))
        if ix == nx and xt <= x1:
            ix = nx - 1
        if iy == ny and yt <= y1:
            iy = ny - 1
        if ix < 0 or ix >= nx or iy < 0 or iy >= ny:
            n_out += 1
            continue
        bins[t] = iy * nx + ix
    return bins, n_nan, n_out
