"""Is the oracular particle filter calibrated? Ranks of the truth among its particles.

For each task and world, the filter (default size, or ``--particles``) runs on validation
trials with its particles kept every 20 s; the rank of the true position (Mahalanobis and
a random projection) and of the true heading drift among the particles should be
uniform. Prints the fraction of truths in the 90% region (rank < 0.9), the ten decile
fractions (0.1 each if calibrated) and two Kolmogorov-Smirnov p-values:

- per time: one rank per trial at each kept time (independent across trials, as the KS
  test assumes), the smallest of the 10 p-values times 10 (Bonferroni): the test of
  uniformity within sampling error;
- pooled: all ranks of all times at once, as earlier versions printed. The ranks of one
  trial 20 s apart are correlated (the posterior carries over), so this p-value is too
  small: the effective sample is smaller than the count. Shown for comparison.

    python analyses/pf_calibration.py [--trials 200] [--worlds darkness compass]
        [--tasks localization ...] [--particles N] [--chunk 100] [--per-time]
        [--outlier-everywhere] [--contact-proposals M]

The filter runs on ``--chunk`` trials at a time (``filter_ranks``), so the particles it
keeps for ranking fit in memory at tens of thousands of particles.
"""

import argparse

import numpy as np
from scipy import stats

from hippo_probe.baselines.calibration import filter_ranks
from _filter_options import add_filter_options, baseline_config
from hippo_probe.tasks import TASKS, make_trials


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=200)
    ap.add_argument("--worlds", nargs="+", default=["darkness", "compass"])
    ap.add_argument("--tasks", nargs="+", default=list(TASKS))
    add_filter_options(ap)
    ap.add_argument("--per-time", action="store_true",
                    help="also print each time's KS p-value and top-decile fraction")
    a = ap.parse_args()
    baseline = baseline_config(a)
    keep = np.arange(25, 500, 50)                      # every 20 s from 10 s
    print(f"{a.trials} validation trials per task, ranks at {len(keep)} steps 20 s apart, "
          f"{a.particles or 'default'} particles\n")
    print(f"{'world':<10}{'task':<14}{'rank':<13}{'KS p, per time':>15}{'pooled':>8}"
          f"{'in 90%':>8}   deciles")
    for world in a.worlds:
        for task in a.tasks:
            batch = make_trials(task, a.trials, "validation", 0, world=world)
            found = filter_ranks(batch, a.particles, keep=keep, chunk=a.chunk,
                                 baseline=baseline)
            for name in ("mahalanobis", "projection", "drift"):
                if name == "drift" and world == "compass":
                    continue
                by_time = found[name]                                # (K, B)
                rank = by_time.ravel()
                deciles = np.histogram(rank, bins=10, range=(0, 1))[0] / rank.size
                per_time = [stats.kstest(r, "uniform").pvalue for r in by_time]
                print(f"{world:<10}{task:<14}{name:<13}"
                      f"{min(1.0, len(keep) * min(per_time)):>15.3f}"
                      f"{stats.kstest(rank, 'uniform').pvalue:>8.3f}"
                      f"{np.mean(rank < 0.9):>8.3f}   "
                      + " ".join(f"{d:.3f}" for d in deciles), flush=True)
                if a.per_time:
                    top = [np.mean(r > 0.9) for r in by_time]
                    print(f"{'':<37}p at {', '.join(f'{t:.0f}' for t in (keep + 1) * batch.dt)}"
                          f" s: " + " ".join(f"{p:.3f}" for p in per_time)
                          + "; top decile: " + " ".join(f"{f:.3f}" for f in top), flush=True)


if __name__ == "__main__":
    main()
