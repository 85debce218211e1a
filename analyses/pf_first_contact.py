"""Is the particle filter calibrated at a trial's first contact? Two outlier models.

In the localization task the start is unknown, so before the first boundary contact the
posterior covers much of the 1 m arena. The first contact then leaves strips along the
walls that match the sensed angle and distance, plus whatever the contact likelihood's
outlier floor keeps (a contact the one-reflection model does not explain). With the floor
given to every particle (``ContactModelConfig.outlier_near_walls=False``, the earlier
contact model), particles deep in the arena's interior keep it, where a contact is
impossible; with ``outlier_near_walls=True`` (the default now) only particles whose step
could have reached a wall do.

For the validation trials whose first sensed contact falls in the first 8 s (a choice by
the data alone, so a valid subset for a calibration test), this prints, at the contact's
step and 1 and 5 steps later, the fraction of truths in the top and bottom deciles (0.10
each if calibrated) and the KS p-value of three ranks of the truth among the particles:
its Mahalanobis distance from the posterior mean, its distance from the arena's centre,
and its distance to the nearest wall (the rank of any function of the state is uniform
for a calibrated posterior).

    python analyses/pf_first_contact.py [--trials 1000] [--particles 10000] [--chunk 50]

The trials are cut to their first 26 steps (10.4 s): the filter is causal, so the ranks
are those of whole trials.
"""

import argparse
import dataclasses

import numpy as np
from scipy import stats
from tqdm.auto import tqdm

from hippo_probe.baselines import particle_filter
from hippo_probe.baselines.config import BaselineConfig, ContactModelConfig
from hippo_probe.tasks import make_trials
from hippo_probe.world.arena import wall_distance

STEPS = 26
FIRST_BEFORE = 20           # steps: first contacts in the first 8 s
LAGS = (0, 1, 5)
TIME_MAJOR = ("inputs", "target", "position", "head_direction", "heading_drift", "contact")


def first_steps(batch, n_steps):
    """The batch cut to its first ``n_steps`` steps."""
    return dataclasses.replace(batch, **{f: getattr(batch, f)[:n_steps] for f in TIME_MAJOR})


def ranks_at(particles, weights, truth, vertices):
    """Ranks of the truth (2,) among weighted particles (N, 2): Mahalanobis, radius, wall."""
    mean = weights @ particles
    d = particles - mean
    inv = np.linalg.inv((weights[:, None] * d).T @ d)
    e = truth - mean
    own = np.einsum("nd,de,ne->n", d, inv, d)
    wall = wall_distance(vertices, particles)[0]
    true_wall = wall_distance(vertices, truth[None])[0][0]
    return (np.sum(weights * (own < e @ inv @ e)),
            np.sum(weights * (np.hypot(*particles.T) < np.hypot(*truth))),
            np.sum(weights * (wall < true_wall)))


def first_contact_ranks(batch, first, n_particles, chunk, baseline):
    """(trials, lags, 3) ranks for the trials of ``batch`` whose first contact is ``first``."""
    out = []
    for lo in tqdm(range(0, len(batch), chunk), desc="filter chunks", leave=False):
        part = batch.select(slice(lo, lo + chunk))
        res = particle_filter(part, n_particles, keep=np.arange(part.n_steps),
                              baseline=baseline)
        for j in range(len(part)):
            rows = []
            for lag in LAGS:
                k = first[lo + j] + lag
                rows.append(ranks_at(res.particles[k, j], res.particle_weights[k, j],
                                     part.position[k, j], part.arena_vertices[j]))
            out.append(rows)
    return np.asarray(out)


def main():
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--trials", type=int, default=1000)
    ap.add_argument("--particles", type=int, default=10_000)
    ap.add_argument("--chunk", type=int, default=50, help="trials per filter run")
    a = ap.parse_args()
    batch = first_steps(make_trials("localization", a.trials, "validation", 0), STEPS)
    first = np.where(batch.contact.any(0), batch.contact.argmax(0), STEPS)
    chosen = np.flatnonzero(first < FIRST_BEFORE)
    batch, first = batch.select(chosen), first[chosen]
    print(f"{len(chosen)} of {a.trials} validation trials (localization, darkness) have "
          f"their first contact in the first {FIRST_BEFORE * batch.dt:.0f} s; "
          f"{a.particles} particles\n")
    print(f"{'outlier floor':<16}{'steps after':>12}  {'rank':<15}{'top':>6}{'bottom':>8}"
          f"{'KS p':>8}")
    for near in (False, True):
        baseline = BaselineConfig(contact=ContactModelConfig(outlier_near_walls=near))
        found = first_contact_ranks(batch, first, a.particles, a.chunk, baseline)
        for i, lag in enumerate(LAGS):
            for r, name in enumerate(("mahalanobis", "radius", "wall distance")):
                x = found[:, i, r]
                print(f"{'near walls' if near else 'everywhere':<16}{lag:>12}  {name:<15}"
                      f"{np.mean(x > 0.9):>6.3f}{np.mean(x < 0.1):>8.3f}"
                      f"{stats.kstest(x, 'uniform').pvalue:>8.4f}", flush=True)


if __name__ == "__main__":
    main()
