"""Lazy analyses hold chunks, not the recording: the peak memory of rate maps, spatial
information and Poisson spikes drawn from a store opened with open_recording grows far
less than the activity read."""

import json
import subprocess
import sys

import numpy as np
import pytest

CHILD = """
import json, sys, tracemalloc
import dask
import hippo_probe as hp
dask.config.set(scheduler=sys.argv[2], num_workers=2)
rec = hp.open_recording(sys.argv[1])
tracemalloc.start()
hp.ratemaps(rec, bin_size=0.05, sigma=0)
hp.spatial_information(rec, bin_size=0.05)
hp.poisson_spikes(rec, mean_rate=5.0).activity.sum().compute()
print(json.dumps({"peak_kib": tracemalloc.get_traced_memory()[1] // 1024}))
"""

def _store(path, n, units):
    import dask.array as da

    from hippo_probe.recording import annotate, from_arrays, save_recording

    trial = np.arange(n) // 2500                   # 50 s trials, as many as fit
    time = np.arange(n) * 0.02 + trial * 0.04
    xy = np.random.default_rng(0).uniform(-0.5, 0.5, (n, 2))
    # signed, as a network's units: the analyses and poisson_spikes also reduce each
    # unit's minimum
    rec = from_arrays(time, xy, activity=np.zeros((n, 1), np.float32), trial=trial,
                      activity_kind="lstm_hidden")
    rec = rec.drop_vars("activity").drop_dims("unit").assign_coords(unit=np.arange(units))
    rec["activity"] = ("time", "unit"), da.random.default_rng(0).random(
        (n, units), chunks=(2500, units)).astype(np.float32)
    save_recording(annotate(rec), path)
    return path


def _peak_kib(path, scheduler):
    done = subprocess.run([sys.executable, "-c", CHILD, str(path), scheduler],
                          capture_output=True,
                          text=True, check=True, env={"OMP_NUM_THREADS": "1",
                                                      "PATH": "/usr/bin:/bin"})
    out = json.loads(done.stdout.strip().splitlines()[-1])
    return out["peak_kib"]


@pytest.mark.parametrize("scheduler", ["synchronous", "threads"])
def test_peak_memory_does_not_follow_the_recording_length(tmp_path, scheduler):
    """4x the samples (same chunks, 4x as many): the peak may grow by the per-sample
    vectors the analyses keep in memory (time, trial coords, positions, bins: ~100 B a
    sample), not by the activity (1 KiB a sample at 256 float32 units).

    The peak is tracemalloc's (every numpy buffer, zarr's and dask's included), in a fresh
    interpreter with two dask workers: the process's high-water mark (VmHWM) swings by
    ~35 MB between identical runs (malloc arenas of the worker threads), and with one
    worker per core a many-core runner holds all 20 chunks of the short store at once."""
    short, long = 50_000, 200_000
    peak_short = _peak_kib(_store(tmp_path / "short.zarr", short, 256), scheduler)
    peak_long = _peak_kib(_store(tmp_path / "long.zarr", long, 256), scheduler)
    extra_activity_kib = (long - short) * 256 * 4 / 1024          # 146 MiB more to read
    assert peak_long - peak_short < 0.25 * extra_activity_kib, (peak_short, peak_long)
