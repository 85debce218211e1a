"""The analyses' entry check beside the rate maps it guards, on a lazily opened session.

Every public analysis first runs :func:`hippo_probe.recording.check_analysable`
(the cheap rules of ``validate``). Its cost is measured here against ``hp.ratemaps`` on
the same lazily opened recording: 1,000,000 samples x 256 units (float32 activity, 100
trials), saved with ``save_recording`` and opened with ``open_recording`` (dask). Target:
the check costs <= 5% of ``ratemaps``. Best of ``--repeat`` each, one thread.

    python benchmarks/bench_entry_check.py [--samples 1000000] [--units 256]
        [--store /tmp/bench_entry.zarr] [--repeat 3]
"""

from __future__ import annotations

import argparse
import os
import shutil
import time

os.environ.setdefault("NUMBA_NUM_THREADS", "1")
os.environ.setdefault("OMP_NUM_THREADS", "1")


def best_of(fn, repeat):
    times = []
    for _ in range(repeat):
        t0 = time.perf_counter()
        fn()
        times.append(time.perf_counter() - t0)
    return min(times)


def main():
    import numpy as np

    import hippo_probe as hp
    from hippo_probe.recording.validate import check_analysable

    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--samples", type=int, default=1_000_000)
    ap.add_argument("--units", type=int, default=256)
    ap.add_argument("--trials", type=int, default=100)
    ap.add_argument("--store", default="/tmp/bench_entry.zarr")
    ap.add_argument("--repeat", type=int, default=3)
    a = ap.parse_args()
    print(f"load average before: {os.getloadavg()[0]:.2f}")
    rng = np.random.default_rng(0)
    n, per = a.samples, a.samples // a.trials
    dt = 0.02
    t = np.concatenate([k * (per + 10) * dt + dt * np.arange(1, per + 1)
                        for k in range(a.trials)])
    heading = np.cumsum(rng.normal(0, 0.1, n))
    xy = np.cumsum(0.2 * dt * np.c_[np.cos(heading), np.sin(heading)], axis=0)
    xy = np.abs((xy + 0.5) % 2 - 1) - 0.5
    act = rng.random((n, a.units), dtype=np.float32)
    rec = hp.from_arrays(t, xy, activity=act, trial=np.repeat(np.arange(a.trials), per),
                         activity_kind="rate", dt=dt)
    shutil.rmtree(a.store, ignore_errors=True)
    hp.save_recording(rec, a.store)
    del rec, act
    lazy = hp.open_recording(a.store)
    hp.ratemaps(lazy, bin_size=0.025)                  # warm-up: compile the kernels
    t_check = best_of(lambda: check_analysable(lazy), a.repeat)
    t_maps = best_of(lambda: hp.ratemaps(lazy, bin_size=0.025), a.repeat)
    # the same call with the check switched off: what the check adds to the analysis
    # (it reads position once and hands it on, so the analysis does not read it again)
    from unittest import mock
    with mock.patch("hippo_probe.analysis._common.check_analysable", lambda r, **k: r):
        t_bare = best_of(lambda: hp.ratemaps(lazy, bin_size=0.025), a.repeat)
    print(f"{n:,} samples x {a.units} units, lazily opened ({a.trials} trials)")
    print(f"  entry check alone            {t_check * 1e3:8.1f} ms")
    print(f"  ratemaps with the check      {t_maps * 1e3:8.1f} ms")
    print(f"  ratemaps without the check   {t_bare * 1e3:8.1f} ms")
    print(f"  added by the check: {(t_maps - t_bare) / t_bare:+.3f} of ratemaps "
          f"(target <= 0.05)")
    print(f"load average after: {os.getloadavg()[0]:.2f}")
    shutil.rmtree(a.store, ignore_errors=True)


if __name__ == "__main__":
    main()
