"""Where is the oracular particle filter over-confident? Its Mahalanobis ranks, split.

The rank of the true position among the particles (``filter_ranks``) is uniform for a
calibrated filter, and stays uniform within any subset chosen by a function of the data
alone (the filter's own posterior, the contacts sensed so far); a subset chosen by the
truth (e.g. the true distance to a wall) is not a valid test. This splits the ranks of
the localization task (darkness world, default particles, times from 30 s, every 20 s)
by the time since the last sensed contact, the posterior's spread and the distance of
its mean to the walls, and prints the fraction of truths in the top and bottom deciles
(0.10 each if calibrated).

    python analyses/pf_calibration_after_contact.py [--trials 600] [--particles N]
        [--chunk 100] [--outlier-everywhere] [--contact-proposals M]

The filter runs on ``--chunk`` trials at a time (``filter_ranks``), so the particles it
keeps for ranking fit in memory at tens of thousands of particles.
"""

import argparse

import numpy as np

from hippo_probe.baselines.calibration import filter_ranks
from _filter_options import add_filter_options, baseline_config
from hippo_probe.tasks import make_trials
from hippo_probe.world.arena import wall_distance


def print_split(label, values, ranks, edges):
    """Deciles of the ranks within each bin [lo, hi) of ``values`` (the last bin closed)."""
    for lo, hi in zip(edges[:-1], edges[1:]):
        m = (values >= lo) & ((values < hi) | (hi == edges[-1]))
        if m.any():
            print(f"{label} {lo:.3g}-{hi:.3g}: n={m.sum()}, top decile "
                  f"{np.mean(ranks[m] > 0.9):.3f}, bottom decile {np.mean(ranks[m] < 0.1):.3f}")


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=600)
    add_filter_options(ap)
    a = ap.parse_args()
    baseline = baseline_config(a)
    keep = np.arange(75, 500, 50)                        # every 20 s from 30 s
    batch = make_trials("localization", a.trials, "validation", 0, world="darkness")
    found = filter_ranks(batch, a.particles, keep=keep, chunk=a.chunk, progress=True,
                         baseline=baseline)
    all_ranks = {k: found[k].ravel() for k in ("mahalanobis", "projection", "drift")}
    mean, cov = found["mean"], found["cov"]                              # (K, B, .)
    ranks = all_ranks["mahalanobis"]

    contact = batch.feature("contact") > 0.5                      # (T, B)
    since = np.full(contact.shape, np.inf)
    elapsed = np.full(contact.shape[1], np.inf)
    for t in range(contact.shape[0]):
        elapsed = np.where(contact[t], 0.0, elapsed + batch.dt)
        since[t] = elapsed
    print_split("s since the last contact", since[keep].ravel(), ranks,
                [0, 2, 8, 20, 60, np.inf])
    # the heading drift's rank, two-sided: an over-confident drift posterior puts the truth
    # in both extreme deciles
    for kind in ("drift", "projection"):
        print(f"-- {kind} rank")
        print_split("s since the last contact", since[keep].ravel(), all_ranks[kind],
                    [0, 2, 8, 20, 60, np.inf])
    spread = np.sqrt(cov[..., :2].sum(-1)).ravel()
    print_split("posterior s.d. (m)", spread, ranks, np.quantile(spread, np.linspace(0, 1, 6)))
    mean_to_wall = wall_distance(batch.arena_vertices,
                                 np.swapaxes(mean, 0, 1))[0].T.ravel()
    print_split("posterior mean to wall (m)", mean_to_wall, ranks,
                np.quantile(mean_to_wall, np.linspace(0, 1, 6)))


if __name__ == "__main__":
    main()
