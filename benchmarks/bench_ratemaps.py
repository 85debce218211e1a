"""Rate maps + Skaggs information: hippo_probe beside pynapple, opexebo and a numpy floor.

One run, the same data for everyone: 256 units x 1,000,000 samples of spike counts
(Poisson, Gaussian place fields) on a random walk in a 1 m square, 2.5 cm bins (40 x 40),
no smoothing. Each contender computes every unit's occupancy-normalised map and its
Skaggs information:

* hippo_probe: ``hp.ratemaps(rec, sigma=0)`` then ``hp.spatial_information(maps)`` on an
  in-memory recording (one numba pass over the samples);
* floor: plain numpy/scipy, one sparse (bins x samples) @ (samples x units) product;
* pynapple 0.11: ``compute_tuning_curves`` (TsdFrame of the counts) +
  ``compute_mutual_information``;
* opexebo 0.7: ``spatial_occupancy`` + per unit ``rate_map`` + ``rate_map_stats`` (its
  input is each unit's spike positions, prepared outside the timing).

Then the lazy case: 10,000,000 samples (the same kind of data) saved with
``save_recording`` and opened with ``open_recording`` (dask, trial-aligned chunks);
ratemaps + information are timed in a fresh process whose peak resident memory is
reported (target < 2 GB).

    python benchmarks/bench_ratemaps.py [--samples 1000000] [--units 256] [--threads 2]
        [--lazy-samples 10000000] [--store /tmp/bench_10M.zarr] [--skip-peers] [--skip-lazy]

Timings are best of ``--repeat`` for hippo_probe and the floor (after a warm-up that
compiles the numba kernel), one run for the peers (they take seconds to minutes).
hippo_probe is timed on 1 thread (as the peers run) and on ``--threads``. Note the
machine load printed at the top and bottom: the machine is shared.
"""

from __future__ import annotations

import argparse
import os
import subprocess
import sys
import time


def _pin_threads(n):
    os.environ["NUMBA_NUM_THREADS"] = str(n)
    for var in ("OMP_NUM_THREADS", "OPENBLAS_NUM_THREADS", "MKL_NUM_THREADS"):
        os.environ[var] = "1"  # numpy/scipy single-threaded, like the peers


def walk(n, rng, dt=0.02, speed=0.2, half=0.5):
    """Smooth random walk reflected inside [-half, half]^2."""
    import numpy as np

    heading = np.cumsum(rng.normal(0, 0.6 * np.sqrt(dt), n))
    step = speed * dt * np.stack([np.cos(heading), np.sin(heading)], axis=1)
    raw = np.cumsum(step, axis=0)
    folded = np.mod(raw + half, 4 * half)
    return np.where(folded > 2 * half, 4 * half - folded, folded) - half


def spike_counts(pos, centres, dt, rng, peak=5.0, width=0.1):
    """Poisson counts (n, U) float32 of Gaussian place fields, in blocks (bounded memory)."""
    import numpy as np

    out = np.empty((len(pos), len(centres)), np.float32)
    for s in range(0, len(pos), 100_000):
        p = pos[s:s + 100_000]
        d2 = ((p[:, None, :] - centres[None]) ** 2).sum(-1)
        out[s:s + 100_000] = rng.poisson(peak * dt * np.exp(-d2 / (2 * width**2)))
    return out


def make_recording(n, n_units, seed=0, dt=0.02, trial_len=5000):
    import numpy as np

    import hippo_probe as hp

    rng = np.random.default_rng(seed)
    pos = walk(n, rng, dt)
    centres = rng.uniform(-0.5, 0.5, (n_units, 2))
    counts = spike_counts(pos, centres, dt, rng)
    trial = np.arange(n) // trial_len
    t = (np.arange(n) + trial) * dt  # one empty dt between trials
    return hp.from_arrays(time=t, position=pos, activity=counts, trial=trial,
                          activity_kind="spike_count", source="animal", dt=dt)


def floor(pos, act, edges, dt):
    """numpy/scipy: one sparse (bins x samples) product, then Skaggs information."""
    import numpy as np
    import scipy.sparse as sp

    xe, ye = edges
    nx, ny = len(xe) - 1, len(ye) - 1
    ix = np.clip(np.searchsorted(xe, pos[:, 0], side="right") - 1, 0, nx - 1)
    iy = np.clip(np.searchsorted(ye, pos[:, 1], side="right") - 1, 0, ny - 1)
    b = iy * nx + ix
    n = len(b)
    S = sp.csr_matrix((np.ones(n, np.float32), (b, np.arange(n))), shape=(nx * ny, n))
    sums = (S @ act).T  # (U, bins)
    occ = np.bincount(b, minlength=nx * ny).astype(float)
    with np.errstate(invalid="ignore", divide="ignore"):
        maps = sums / occ / dt
        p = occ / occ.sum()
        mean = np.nansum(p * maps, axis=1, keepdims=True)
        r = maps / mean
        info = np.nansum(np.where(r > 0, p * r * np.log2(r), 0.0), axis=1)
    return maps.reshape(-1, ny, nx), info


def run_pynapple(t, pos, act, edges):
    import warnings

    import pynapple as nap

    with warnings.catch_warnings():
        warnings.simplefilter("ignore")
        frame = nap.TsdFrame(t=t, d=act)
        feats = nap.TsdFrame(t=t, d=pos, columns=["x", "y"])
        tc = nap.compute_tuning_curves(frame, feats, bins=list(edges))
        mi = nap.compute_mutual_information(tc)
    return tc.transpose("unit", "y", "x").values, mi


def run_opexebo(t, pos, spikes_tracking, edges):
    import opexebo

    occ, _, _ = opexebo.analysis.spatial_occupancy(t, pos.T, 1.0, bin_edges=edges)
    out = []
    for st in spikes_tracking:
        rmap = opexebo.analysis.rate_map(occ, st, 1.0, bin_edges=edges)
        out.append(opexebo.analysis.rate_map_stats(rmap, occ)["spatial_information_content"])
    return out


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        result = fn()
        times.append(time.perf_counter() - t0)
    return min(times), result


def in_memory(args):
    import numpy as np

    import hippo_probe as hp
    from hippo_probe.analysis.ratemaps import spatial_grid

    print(f"data: {args.units} units x {args.samples:,} samples, bins {args.bin_size} m")
    rec = make_recording(args.samples, args.units)
    dt = rec.attrs["dt"]
    grid = spatial_grid(rec, args.bin_size, extent=(-0.5, 0.5, -0.5, 0.5))
    edges = (grid.x_edges, grid.y_edges)
    pos = rec.position.values
    act = rec.activity.values
    t = rec.time.values

    def ours():
        maps = hp.ratemaps(rec, bin_size=args.bin_size, sigma=0, extent=(-0.5, 0.5, -0.5, 0.5))
        return maps, hp.spatial_information(maps)

    import numba

    hp.ratemaps(rec.isel(time=slice(0, 20000)), bin_size=args.bin_size, sigma=0)  # compile
    rows = []
    numba.set_num_threads(1)
    t_ours, (maps, info) = best_of(ours, args.repeat)
    rows.append(("hippo_probe (1 thread)", t_ours))
    if args.threads > 1:
        numba.set_num_threads(args.threads)
        t_par, _ = best_of(ours, args.repeat)
        rows.append((f"hippo_probe ({args.threads} threads)", t_par))
        numba.set_num_threads(1)
    t_floor, (f_maps, f_info) = best_of(lambda: floor(pos, act, edges, dt), args.repeat)
    rows.append(("numpy/scipy floor (sparse product)", t_floor))
    assert np.allclose(maps.values, f_maps, rtol=1e-5, equal_nan=True), "floor maps differ"
    assert np.allclose(info.information.values, f_info, rtol=1e-6), "floor information differs"
    if not args.skip_peers:
        # prepare opexebo's input (each unit's spike positions) outside the timing
        tracking = []
        for u in range(act.shape[1]):
            k = act[:, u].astype(np.int64)
            tracking.append(np.stack([np.repeat(t, k), np.repeat(pos[:, 0], k),
                                      np.repeat(pos[:, 1], k)]))
        t0 = time.perf_counter()
        o_info = run_opexebo(t, pos, tracking, edges)
        rows.append(("opexebo 0.7 (per-unit rate_map + rate_map_stats)",
                     time.perf_counter() - t0))
        t0 = time.perf_counter()
        p_maps, p_mi = run_pynapple(t, pos, act, edges)
        rows.append(("pynapple 0.11 (compute_tuning_curves + mutual information)",
                     time.perf_counter() - t0))
        ok = np.isfinite(maps.values)
        corr = min(np.corrcoef(maps.values[u][ok[u]], p_maps[u][ok[u]])[0, 1]
                   for u in range(act.shape[1]))
        rel = np.abs(info.information.values / p_mi["bits/spike"].values - 1).max()
        clip = np.nanmedian(np.asarray(o_info) / info.information.values - 1)
        print(f"agreement: min map correlation with pynapple {corr:.6f}, max relative "
              f"information difference {rel:.2e}; "
              f"opexebo's information is {100 * clip:+.1f}% (median) — it clips bins "
              "below the mean rate")
    print(f"\n{'contender':<62}{'seconds':>10}{'/ hippo_probe 1 thread':>24}")
    for name, sec in rows:
        print(f"{name:<62}{sec:>10.3f}{sec / t_ours:>24.2f}")
    return t_ours


def build_store(args):
    """Write the lazy benchmark's recording chunk by chunk (never whole in memory)."""
    import dask.array as da
    import numpy as np

    import hippo_probe as hp
    from hippo_probe.recording.layout import trial_layout
    from hippo_probe.recording.schema import annotate

    n, dt, trial_len = args.lazy_samples, 0.02, 5000
    rng = np.random.default_rng(1)
    pos = walk(n, rng, dt)
    centres = rng.uniform(-0.5, 0.5, (args.units, 2))
    rec = trial_layout(trial_len, n // trial_len, dt, source="animal",
                       activity_kind="spike_count")
    chunk = 8000

    def block(p, block_info=None):
        seed = block_info[0]["chunk-location"][0] if block_info else 0
        return spike_counts(p, centres, dt, np.random.default_rng([2, seed]))

    pos_d = da.from_array(pos, chunks=(chunk, 2))
    act = pos_d.map_blocks(block, dtype=np.float32, chunks=(pos_d.chunks[0], (args.units,)))
    rec["position"] = (("time", "space"), pos)
    rec["activity"] = (("time", "unit"), act)
    rec = annotate(rec.assign_coords(unit=np.arange(args.units)))
    t0 = time.perf_counter()
    hp.save_recording(rec, args.store)
    print(f"wrote {args.store} in {time.perf_counter() - t0:.0f} s")


def _peak_rss_gib():
    """Peak resident memory of this process (VmHWM). Not getrusage's ru_maxrss: on Linux a
    child started by fork+exec inherits its parent's maximum there."""
    with open("/proc/self/status") as f:
        kib = next(int(line.split()[1]) for line in f if line.startswith("VmHWM:"))
    return kib / 2**20


def lazy_child(args):
    import dask

    import hippo_probe as hp

    dask.config.set(scheduler="threads", num_workers=args.threads)
    t0 = time.perf_counter()
    rec = hp.open_recording(args.store)
    maps = hp.ratemaps(rec, bin_size=args.bin_size, sigma=0, extent=(-0.5, 0.5, -0.5, 0.5))
    info = hp.spatial_information(maps)
    sec = time.perf_counter() - t0
    peak = _peak_rss_gib()
    print(f"lazy: {rec.sizes['time']:,} samples x {rec.sizes['unit']} units in "
          f"{rec.activity.data.npartitions} dask chunks: {sec:.1f} s, peak RSS {peak:.2f} GiB "
          f"(information of unit 0: {float(info.information[0]):.3f} bits/spike)")


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, default=1_000_000)
    p.add_argument("--units", type=int, default=256)
    p.add_argument("--bin-size", type=float, default=0.025)
    p.add_argument("--threads", type=int, default=2,
                   help="threads for hippo_probe's second timing and the lazy run "
                        "(peers and the floor run single-threaded)")
    p.add_argument("--repeat", type=int, default=3)
    p.add_argument("--lazy-samples", type=int, default=10_000_000)
    p.add_argument("--store", default="/tmp/hippo_probe_bench_10M.zarr")
    p.add_argument("--skip-peers", action="store_true")
    p.add_argument("--skip-lazy", action="store_true")
    p.add_argument("--lazy-child", action="store_true", help=argparse.SUPPRESS)
    p.add_argument("--build-store", action="store_true", help=argparse.SUPPRESS)
    args = p.parse_args(argv)
    _pin_threads(args.threads)
    if args.lazy_child:
        return lazy_child(args)
    if args.build_store:
        return build_store(args)
    print("load:", os.popen("uptime").read().strip())
    print(f"numba threads: 1 and {args.threads}; BLAS threads: 1")
    in_memory(args)
    if not args.skip_lazy:
        base = [sys.executable, __file__, "--units", str(args.units), "--bin-size",
                str(args.bin_size), "--threads", str(args.threads), "--lazy-samples",
                str(args.lazy_samples), "--store", args.store]
        if not os.path.exists(args.store):
            subprocess.run(base + ["--build-store"], check=True)
        subprocess.run(base + ["--lazy-child"], check=True)
    print("load:", os.popen("uptime").read().strip())


if __name__ == "__main__":
    main()
