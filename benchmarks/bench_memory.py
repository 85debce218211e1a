"""Peak memory of the lazy analyses: bounded by the chunks, not by the recording?

Stores of 256 float32 units x N samples (N = 1e6 and 4e6; 1 GB and 4 GB of activity),
in 1 trial and in 200 trials, are written once with ``save_recording`` and opened with
``open_recording`` (dask, trial-aligned chunks). Each analysis runs in a fresh process
that reports its peak resident memory (``VmHWM``) and its peak right after
opening (imports + the per-sample coords that ``open_recording`` loads). Targets:
peak under 2 GB at 4e6 samples, and growing less than 10% from 1e6 to 4e6.

    python benchmarks/bench_memory.py [--samples 1000000 4000000] [--trials 1 200]
        [--dir /tmp/hippo_probe_bench_memory] [--analyses ratemaps spatial_information ...]

Memory, not time, is measured, so a busy machine changes little; the load average is
printed anyway.
"""

from __future__ import annotations

import argparse
import json
import os
import subprocess
import sys
from pathlib import Path

UNITS = 256
ANALYSES = {
    "ratemaps": "hp.ratemaps(rec, bin_size=0.025, sigma=0)",
    "spatial_information": "hp.spatial_information(rec, bin_size=0.025)",
    "spatial_selectivity": "hp.spatial_selectivity(rec, bin_size=0.025)",
    "head_direction_tuning": "hp.head_direction_tuning(rec)",
}

# VmHWM, the peak resident memory of this process image: unlike ru_maxrss it does not
# carry over the parent's peak through fork and exec
CHILD = """
import json, sys
def hwm():
    line = next(l for l in open("/proc/self/status") if l.startswith("VmHWM"))
    return int(line.split()[1])
import hippo_probe as hp
rec = hp.open_recording(sys.argv[1])
opened = hwm()
result = {call}
print(json.dumps({{"opened_kib": opened, "peak_kib": hwm()}}))
"""


def make_store(path: Path, n: int, trials: int) -> None:
    """A schema-v1 store of random activity on a random walk, written chunk by chunk."""
    import dask.array as da
    import numpy as np

    import hippo_probe as hp
    from hippo_probe.recording import annotate, from_arrays

    rng = np.random.default_rng(0)
    trial = np.repeat(np.arange(trials), -(-n // trials))[:n]
    time = np.arange(n) * 0.02 + trial * 0.04          # a gap of one dt between trials
    xy = np.clip(np.cumsum(rng.normal(0, 0.01, (n, 2)), axis=0) % 2 - 1, -1, 1) * 0.5
    hd = rng.uniform(-np.pi, np.pi, n)
    rec = from_arrays(time, xy, activity=np.zeros((n, 1), np.float32), trial=trial,
                      head_direction=hd)
    rec = rec.drop_vars("activity").drop_dims("unit").assign_coords(unit=np.arange(UNITS))
    chunk = min(n, 8 * 2**20 // (4 * UNITS))
    rec["activity"] = ("time", "unit"), da.random.default_rng(0).random(
        (n, UNITS), chunks=(chunk, UNITS)).astype(np.float32)
    hp.save_recording(annotate(rec), path, overwrite=True)


def measure(store: Path, analysis: str) -> dict:
    code = CHILD.format(call=ANALYSES[analysis])
    done = subprocess.run([sys.executable, "-c", code, str(store)], capture_output=True,
                          text=True, check=True)
    return json.loads(done.stdout.strip().splitlines()[-1])


def main(argv=None):
    p = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    p.add_argument("--samples", type=int, nargs="+", default=[1_000_000, 4_000_000])
    p.add_argument("--trials", type=int, nargs="+", default=[1, 200])
    p.add_argument("--dir", default="/tmp/hippo_probe_bench_memory")
    p.add_argument("--analyses", nargs="+", default=list(ANALYSES), choices=list(ANALYSES))
    a = p.parse_args(argv)
    print(f"load average {os.getloadavg()[0]:.2f}; {UNITS} float32 units")
    root = Path(a.dir)
    rows = {}
    for trials in a.trials:
        for n in a.samples:
            store = root / f"{n}x{UNITS}-{trials}trials.zarr"
            if not store.exists():
                print(f"writing {store} ...", flush=True)
                make_store(store, n, trials)
            for name in a.analyses:
                rows[name, trials, n] = measure(store, name)
                r = rows[name, trials, n]
                print(f"{name:22s} {trials:4d} trials {n:>9,d} samples: peak "
                      f"{r['peak_kib'] / 2**20:5.2f} GiB (after opening "
                      f"{r['opened_kib'] / 2**20:4.2f} GiB)", flush=True)
    lo, hi = min(a.samples), max(a.samples)
    print(f"\npeak at {hi:,d} samples (target < 2 GiB) and growth from {lo:,d} "
          f"(target < 10%):")
    for name in a.analyses:
        for trials in a.trials:
            small, big = rows[name, trials, lo]["peak_kib"], rows[name, trials, hi]["peak_kib"]
            print(f"  {name:22s} {trials:4d} trials: {big / 2**20:5.2f} GiB "
                  f"[{'ok' if big < 2 * 2**20 else 'over'}], growth "
                  f"{100 * (big / small - 1):5.1f}% [{'ok' if big < 1.1 * small else 'over'}]")


if __name__ == "__main__":
    main()
