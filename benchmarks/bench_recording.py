"""Save and reopen a big recording with bounded memory, beside raw disk throughput.

A network-style recording of ``--samples`` samples × ``--units`` units (float32 activity,
trials of ``--trial-length`` samples) is generated lazily (dask; every chunk is a fixed
block of tanh-of-Gaussian values plus a per-chunk offset, so generating costs next to
nothing and compresses like real LSTM states, i.e. hardly), saved with
``save_recording``, flushed to disk (fsync of every file) and dropped from the page cache
(``posix_fadvise(DONTNEED)``, per file, so nothing else on the machine is affected), then
read in full (a float64 sum over time per unit) three ways, each from a cold cache:
``open_recording(direct_io=False)`` (through the page cache), ``direct_io=True`` (around
it), and the field's own way, ``xarray.open_zarr`` (zarr-python's reader). The store is
then written twice more, each time flushed and timed the same way:
``save_recording(direct_io=True)`` and the field's own way, ``Dataset.to_zarr`` with the
same chunks and codecs (zarr-python's writer). Peer:
raw sequential write (+ fsync) and cold read of a plain file as large as the activity
(``--raw-mb`` to choose another size), in 8 MiB blocks, measured in the same run on the
same disk before the store is written and after it is removed; the faster of the two is
the peer (this machine's virtual disk drifts, and writes slower after tens of GB). A smaller peer file reads faster than the disk
delivers a large one (the first 2 GB of a 10 GB file just written read at 2.4-2.5 GB/s,
the whole file at 1.8-1.9 GB/s in one run on the machine of the benchmarks guide), so the
peer reads as much as the store does.

Reported: peak resident memory (VmHWM, reset between phases) of each phase, write and
read throughput in MB/s of uncompressed activity (1 MB = 10^6 bytes), the store's size.

    python benchmarks/bench_recording.py [--samples 10000000] [--units 256]
        [--trial-length 500] [--threads 2] [--dir DIR] [--raw-mb MB] [--keep]

The default size is 10,000,000 × 256 float32 = 10.24 GB; the tests run 1/100 of it.
"""

from __future__ import annotations

import argparse
import os
import shutil
import sys
import tempfile
import time

import numpy as np

BLOCK = 8 * 2**20                      # raw-disk peer: 8 MiB sequential writes/reads
TARGET_PEAK_RSS_MB = 2000


def _reset_peak():
    """Reset VmHWM (Linux >= 4.0), so the next reading is the peak of one phase."""
    try:
        with open("/proc/self/clear_refs", "w") as f:
            f.write("5")
    except OSError:
        pass


def _peak_rss_mb():
    with open("/proc/self/status") as f:
        for line in f:
            if line.startswith("VmHWM:"):
                return int(line.split()[1]) / 1024
    return float("nan")


def _files(root):
    for folder, _, names in os.walk(root):
        for name in names:
            yield os.path.join(folder, name)


def _flush_and_evict(paths):
    """fsync each file, then drop its pages from the page cache."""
    for path in paths:
        fd = os.open(path, os.O_RDONLY)
        try:
            os.fsync(fd)
            os.posix_fadvise(fd, 0, 0, os.POSIX_FADV_DONTNEED)
        finally:
            os.close(fd)


def raw_disk(directory, n_bytes, block):
    """Sequential write (+ fsync) and cold read of one plain file: (write, read) MB/s."""
    path = os.path.join(directory, "raw.bin")
    data = np.ascontiguousarray(block).view(np.uint8).ravel()[:BLOCK]
    n_blocks = max(1, n_bytes // data.size)
    start = time.perf_counter()
    with open(path, "wb") as f:
        for _ in range(n_blocks):
            f.write(data)
    _flush_and_evict([path])
    write = n_blocks * data.size / (time.perf_counter() - start) / 1e6
    start = time.perf_counter()
    with open(path, "rb", buffering=0) as f:
        while f.readinto(bytearray(BLOCK)) == BLOCK:
            pass
    read = n_blocks * data.size / (time.perf_counter() - start) / 1e6
    os.remove(path)
    return write, read


def build(samples, units, trial_length, seed=0):
    """A lazy network-style recording and the function that makes its activity chunks."""
    import dask.array as da

    from hippo_probe.recording import annotate, trial_layout
    from hippo_probe.recording.config import DEFAULTS

    n_trials = samples // trial_length
    per_chunk = DEFAULTS.chunk_bytes // (units * 4)
    chunk = trial_length * max(1, per_chunk // trial_length)   # = save_recording's choice
    base = np.tanh(np.random.default_rng(seed).standard_normal((chunk, units))).astype(
        np.float32)

    def make_block(index, n):
        return base[:n] + np.float32(index * 1e-3)

    def block(block_info=None):
        info = block_info[None]
        index = info["chunk-location"][0]
        return make_block(index, info["chunk-shape"][0])

    n = n_trials * trial_length
    chunks = (tuple(min(chunk, n - i) for i in range(0, n, chunk)), (units,))
    activity = da.map_blocks(block, chunks=chunks, dtype=np.float32, meta=np.empty((0, 0),
                                                                             np.float32))
    rec = trial_layout(trial_length, n_trials, 0.4, task="benchmark", seed=seed)
    rec = rec.assign_coords(unit=np.arange(units))
    rec["activity"] = ("time", "unit"), activity
    rec["position"] = ("time", "space"), da.zeros((n, 2), chunks=(chunks[0], 2))
    return annotate(rec), make_block, chunk, base


def _zarr_write(rec, store, chunk):
    """The field's own writer: ``Dataset.to_zarr`` with save_recording's chunks and codecs
    (Blosc lz4 level 5, byte shuffle, CRC32C) for the activity."""
    from zarr.codecs import BloscCodec, Crc32cCodec

    compressors = [BloscCodec(cname="lz4", clevel=5, shuffle="shuffle"), Crc32cCodec()]
    rec.to_zarr(store, mode="w-", zarr_format=3, consolidated=False,
                encoding={"activity": {"chunks": (chunk, rec.sizes["unit"]),
                                       "compressors": compressors}})


def run(samples=10_000_000, units=256, trial_length=500, threads=2, directory=None,
        raw_mb=None, keep=False):
    """Run the benchmark; return a dict of the measurements."""
    import dask
    import numcodecs
    import xarray as xr
    import zarr

    from hippo_probe.recording import open_recording, save_recording

    numcodecs.blosc.set_nthreads(1)        # parallelism comes from the dask threads only
    zarr.config.set({"threading.max_workers": threads})
    workdir = tempfile.mkdtemp(prefix="bench_recording-", dir=directory)
    store = os.path.join(workdir, "bench.zarr")
    out = {"samples": samples, "units": units, "threads": threads}
    try:
        with dask.config.set(scheduler="threads", num_workers=threads):
            _reset_peak()
            rec, make_block, chunk, base = build(samples, units, trial_length)
            nbytes = rec.activity.nbytes
            out["activity_MB"] = nbytes / 1e6
            out["build_peak_rss_MB"] = _peak_rss_mb()
            raw_bytes = int(max(nbytes if raw_mb is None else raw_mb * 1e6, BLOCK))
            out["raw_MB"] = raw_bytes / 1e6
            raw = [raw_disk(workdir, raw_bytes, base)]

            _reset_peak()
            start = time.perf_counter()
            save_recording(rec, store)
            _flush_and_evict(_files(store))
            out["write_s"] = time.perf_counter() - start
            out["write_MBps"] = nbytes / out["write_s"] / 1e6
            out["write_peak_rss_MB"] = _peak_rss_mb()
            out["stored_MB"] = sum(os.path.getsize(p) for p in _files(store)) / 1e6
            del rec                # its coords (32 B a sample) would add to the reads' peak

            readers = {"read": lambda: open_recording(store, direct_io=False),
                       "direct_read": lambda: open_recording(store, direct_io=True),
                       "zarr_read": lambda: xr.open_zarr(store, consolidated=False)}
            for phase, reader in readers.items():
                _flush_and_evict(_files(store))
                _reset_peak()
                start = time.perf_counter()
                back = reader()
                # a plain dask reduction: measures reading + decoding, not NaN handling
                total = back.activity.data.sum(axis=0, dtype=np.float64).compute()
                out[f"{phase}_s"] = time.perf_counter() - start
                out[f"{phase}_MBps"] = nbytes / out[f"{phase}_s"] / 1e6
                out[f"{phase}_peak_rss_MB"] = _peak_rss_mb()
                if phase == "read":
                    first_total = total
                # equal trials: every reader has the same dask chunks, so the same sums
                elif not np.array_equal(total, first_total):
                    raise AssertionError(f"{phase} sums differ from open_recording's")

            back = open_recording(store)
            out["chunks_per_trial_aligned"] = back.activity.chunks[0][0] % trial_length == 0
            # exactness: spot-check three chunks against their generator
            n_chunks = len(back.activity.chunks[0])
            for index in sorted({0, n_chunks // 2, n_chunks - 1}):
                lo = index * chunk
                got = back.activity[lo:lo + chunk].values
                if not np.array_equal(got, make_block(index, got.shape[0])):
                    raise AssertionError(f"chunk {index} differs after the round trip")
            out["total_activity"] = float(first_total.sum())
            del back

            # the peer first: a kept store (--keep) is save_recording's
            writers = {"zarr_write": lambda rec: _zarr_write(rec, store, chunk),
                       "direct_write": lambda rec: save_recording(rec, store,
                                                                  direct_io=True)}
            for phase, write in writers.items():
                shutil.rmtree(store)
                rec = build(samples, units, trial_length)[0]
                _reset_peak()
                start = time.perf_counter()
                write(rec)
                del rec
                _flush_and_evict(_files(store))
                out[f"{phase}_s"] = time.perf_counter() - start
                out[f"{phase}_MBps"] = nbytes / out[f"{phase}_s"] / 1e6
                out[f"{phase}_peak_rss_MB"] = _peak_rss_mb()
        if not keep:                  # room on the disk for the peer file
            shutil.rmtree(store)
        raw.append(raw_disk(workdir, raw_bytes, base))
        # the disk's speed drifts, and slows after tens of GB written: measured before
        # and after, the faster of the two is the peer
        (out["raw_write_first_MBps"], out["raw_read_first_MBps"]), \
            (out["raw_write_last_MBps"], out["raw_read_last_MBps"]) = raw
        out["raw_write_MBps"] = max(write for write, _ in raw)
        out["raw_read_MBps"] = max(read for _, read in raw)
    finally:
        if not keep:
            shutil.rmtree(workdir, ignore_errors=True)
    out["peak_rss_MB"] = max(out[k] for k in out if k.endswith("peak_rss_MB"))
    return out


def main(argv=None):
    parser = argparse.ArgumentParser(description=__doc__.split("\n\n")[0])
    parser.add_argument("--samples", type=int, default=10_000_000)
    parser.add_argument("--units", type=int, default=256)
    parser.add_argument("--trial-length", type=int, default=500)
    parser.add_argument("--threads", type=int, default=2)
    parser.add_argument("--dir", default=None, help="where to write (default: system temp)")
    parser.add_argument("--raw-mb", type=float, default=None,
                        help="size of the raw-disk peer file (default: the activity's)")
    parser.add_argument("--keep", action="store_true", help="keep the store")
    args = parser.parse_args(argv)
    for var in ("OMP_NUM_THREADS", "NUMBA_NUM_THREADS", "OPENBLAS_NUM_THREADS"):
        os.environ.setdefault(var, str(args.threads))
    print(f"load average before: {os.getloadavg()}", flush=True)
    out = run(args.samples, args.units, args.trial_length, args.threads, args.dir,
              args.raw_mb, args.keep)
    print(f"load average after:  {os.getloadavg()}")
    print(f"{out['samples']:,} samples x {out['units']} units float32 = "
          f"{out['activity_MB']:,.0f} MB activity; stored {out['stored_MB']:,.0f} MB; "
          f"{args.threads} threads")
    raw_read = out["raw_read_MBps"]
    print(f"{'':36}{'MB/s':>8}{'× raw disk':>12}{'peak RSS MB':>14}")
    raw_write = out["raw_write_MBps"]
    rows = [("save_recording + fsync", "write", raw_write),
            ("save_recording(direct_io) + fsync", "direct_write", raw_write),
            ("xarray.to_zarr + fsync (peer)", "zarr_write", raw_write),
            ("open_recording + read", "read", raw_read),
            ("open_recording(direct_io) + read", "direct_read", raw_read),
            ("xarray.open_zarr + read (peer)", "zarr_read", raw_read)]
    for label, phase, raw in rows:
        print(f"{label:36}{out[phase + '_MBps']:>8.0f}{out[phase + '_MBps'] / raw:>12.2f}"
              f"{out[phase + '_peak_rss_MB']:>14.0f}")
    print(f"{'raw disk write + fsync':36}{out['raw_write_MBps']:>8.0f}   "
          f"({out['raw_MB']:,.0f} MB file; first {out['raw_write_first_MBps']:.0f}, "
          f"last {out['raw_write_last_MBps']:.0f})")
    print(f"{'raw disk read (cold)':36}{raw_read:>8.0f}   "
          f"(first {out['raw_read_first_MBps']:.0f}, last {out['raw_read_last_MBps']:.0f})")
    ok = out["peak_rss_MB"] < TARGET_PEAK_RSS_MB
    print(f"peak RSS {out['peak_rss_MB']:.0f} MB (target < {TARGET_PEAK_RSS_MB}): "
          f"{'OK' if ok else 'OVER'}")
    return 0 if ok else 1


if __name__ == "__main__":
    sys.exit(main())
