"""Naive Bayes: the closed form for a one-cell prior, PI early, shrinkage late."""

import numpy as np
import pytest

from hippo_probe.baselines import BaselineConfig, NaiveBayesConfig, naive_bayes, path_integration
from hippo_probe.baselines.naive_bayes import TargetPrior
from hippo_probe.tasks import make_trials, task_config
from hippo_probe.world import NoiseModel, WorldConfig

SMALL = BaselineConfig(naive_bayes=NaiveBayesConfig(prior_trials=200))


def point_prior(n_steps, where, cell=0.04, grid=9):
    """A prior with all its mass in the grid cell centred on ``where``."""
    centres = where[:, None] + cell * (np.arange(grid) - grid // 2)
    counts = np.zeros((n_steps, grid, grid))
    counts[:, grid // 2, grid // 2] = 1.0
    return TargetPrior(centres[0], centres[1], counts, cell, "generalized", "train", 0, 1, 0)


def test_one_cell_prior_is_the_gaussian_product():
    batch = make_trials("generalized", 3, "test", 0)
    where = np.array([0.05, -0.02])
    prior = point_prior(batch.n_steps, where)
    res = naive_bayes(batch, prior=prior)
    pi = path_integration(batch).estimate
    noise = (NoiseModel().speed_sd ** 2 + NoiseModel().rotation_sd ** 2) / 2
    disp = batch.inputs[..., :2].astype(float)
    # PI variance: the steps' own errors plus the drifting frame's, by brute force
    track = np.cumsum(disp, axis=0)
    before = np.concatenate([np.zeros_like(track[:1]), track[:-1]])
    remaining = np.array([np.sum((track[t][None] - before[:t + 1]) ** 2, axis=(0, 2))
                          for t in range(batch.n_steps)])              # (T, B)
    drift = 0.5 * batch.world.noise.heading_drift ** 2 * batch.dt * remaining
    v = (noise * np.cumsum(np.sum(disp ** 2, axis=-1), axis=0) + drift)[..., None]
    s2 = prior.kernel_variance
    expected = (v * where + s2 * pi) / (v + s2)       # N(pi, v) times N(where, s2)
    assert np.allclose(res.estimate, expected, atol=1e-9)


def test_exact_inputs_make_it_path_integration():
    config = task_config("generalized", world=WorldConfig(
        arena=task_config("generalized").world.arena, noise=NoiseModel.noiseless()))
    batch = make_trials("generalized", 3, "test", 0, config=config)
    prior = point_prior(batch.n_steps, np.array([0.05, -0.02]))
    nb = naive_bayes(batch, prior=prior, config=config)
    assert np.allclose(nb.estimate, path_integration(batch, config=config).estimate)


def test_shrinks_late():
    batch = make_trials("generalized", 40, "test", 0)
    nb = naive_bayes(batch, baseline=SMALL)
    pi = path_integration(batch)
    assert nb.error(batch)[:25].mean() < pi.error(batch)[:25].mean() + 0.002
    nb_err, pi_err = nb.error(batch)[-100:].mean(), pi.error(batch)[-100:].mean()
    assert nb_err < 0.8 * pi_err
    # shrinkage: NB estimates are closer to the prior's centre (the start) than PI's
    assert np.linalg.norm(nb.estimate[-1], axis=-1).mean() < \
        np.linalg.norm(pi.estimate[-1], axis=-1).mean()


def test_prior_must_cover_the_trial():
    batch = make_trials("generalized", 1, "test", 0)
    prior = point_prior(10, np.zeros(2))
    with pytest.raises(ValueError, match="`prior` must cover"):
        naive_bayes(batch, prior=prior)
