"""The oracular particle filter: bounded, calibrated, ambiguous only where the world is."""

import numpy as np
import pytest
from scipy import stats

from hippo_probe.baselines import particle_filter, path_integration
from hippo_probe.tasks import make_trials
from hippo_probe.world import random_arena


def mahalanobis_rank(res, truth):
    """Posterior mass of the particles closer to the weighted mean (in the particles' own
    Mahalanobis metric) than the truth: uniform on [0, 1] for a calibrated filter, whatever
    the posterior's shape."""
    p, w = res.particles, res.particle_weights                     # (K, B, N, 2), (K, B, N)
    mean = np.einsum("kbn,kbnd->kbd", w, p)
    d = p - mean[:, :, None]
    cov = np.einsum("kbn,kbnd,kbne->kbde", w, d, d)
    inv = np.linalg.inv(cov + 1e-12 * np.eye(2))
    own = np.einsum("kbnd,kbde,kbne->kbn", d, inv, d)
    e = truth - mean
    true = np.einsum("kbd,kbde,kbe->kb", e, inv, e)
    return np.sum(w * (own < true[..., None]), axis=-1).ravel()


def projection_rank(res, truth, rng):
    """Posterior mass below the truth along a random direction: uniform if calibrated."""
    angle = rng.uniform(0, 2 * np.pi, truth.shape[:2])
    u = np.stack([np.cos(angle), np.sin(angle)], axis=-1)
    own = np.einsum("kbnd,kbd->kbn", res.particles, u)
    true = np.einsum("kbd,kbd->kb", truth, u)
    return np.sum(res.particle_weights * (own < true[..., None]), axis=-1).ravel()


def test_error_stays_bounded_while_pi_drifts():
    batch = make_trials("generalized", 16, "test", 0)
    pf = particle_filter(batch, 300).error(batch).mean(axis=1)
    pi = path_integration(batch).error(batch).mean(axis=1)
    early, late = slice(25, 75), slice(450, 500)            # 10-30 s and 180-200 s
    assert pi[late].mean() > 2 * pi[early].mean()           # PI drifts ...
    assert pf[late].mean() < 1.3 * pf[early].mean()         # ... the PF does not
    assert pf.max() < 0.1                                   # within 10 cm all along


@pytest.mark.parametrize("task", ["generalized", "localization"])
def test_calibrated(task):
    # snapshots 20 s apart so that successive ranks of a trial are nearly independent
    keep = np.arange(25, 500, 50)
    batch = make_trials(task, 60, "validation", 0)
    res = particle_filter(batch, 400, keep=keep)
    truth = batch.position[keep]
    rng = np.random.default_rng(0)
    for ranks in (mahalanobis_rank(res, truth), projection_rank(res, truth, rng)):
        assert stats.kstest(ranks, "uniform").pvalue > 0.01
        # and the 90% highest-rank region holds the truth 90% of the time
        assert abs(np.mean(ranks < 0.9) - 0.9) < 0.05


def test_ambiguous_where_the_world_is(make_trials_in):
    """With the allocentric frame given, only a translation leaves every input unchanged:
    in a long corridor the posterior stays spread along its axis (until an end is
    touched) while contacts pin the cross-axis position; a compact asymmetric arena
    localizes."""
    corridor = np.array([[-5.0, -0.15], [5.0, -0.15], [5.0, 0.15], [-5.0, 0.15]])
    batch = make_trials_in(corridor, 8, seed=1, n_steps=75)             # 30 s
    res = particle_filter(batch, 500, start="unknown")
    sd_along, sd_across = np.sqrt(res.cov[-1, :, 0]), np.sqrt(res.cov[-1, :, 1])
    assert np.median(sd_along) > 1.0
    assert np.median(sd_across) < 0.03

    arena = random_arena(np.random.default_rng(3), 10, 0.6).vertices
    batch = make_trials_in(arena, 8, seed=1, n_steps=75)
    res = particle_filter(batch, 500, start="unknown")
    sd = np.sqrt(res.cov[-1, :, 0] + res.cov[-1, :, 1])
    assert np.median(sd) < 0.1
    assert np.median(res.error(batch)[-1]) < 0.1


def test_identical_seeds_identical_results():
    batch = make_trials("localization", 6, "test", 0)
    a = particle_filter(batch, 200, threads=2)
    b = particle_filter(batch, 200, threads=1)
    part = particle_filter(batch.select([4, 5]), 200)
    assert np.array_equal(a.estimate, b.estimate) and np.array_equal(a.cov, b.cov)
    assert np.array_equal(a.estimate[:, 4:], part.estimate)   # per-trial random streams
    other = make_trials("localization", 6, "test", 1)
    assert not np.array_equal(a.estimate, particle_filter(other, 200).estimate)


def test_results_and_particles_are_consistent():
    batch = make_trials("generalized", 3, "test", 0)
    keep = [0, 10, 499]
    res = particle_filter(batch, 150, keep=keep)
    assert res.particles.shape == (3, 3, 150, 2)
    assert np.allclose(res.particle_weights.sum(axis=-1), 1.0)
    mean = np.einsum("kbn,kbnd->kbd", res.particle_weights, res.particles)
    assert np.allclose(mean, res.mean[keep])
    # the generalized estimate is the start-relative mean (start known)
    assert np.allclose(res.estimate, res.mean - batch.start[None])
    assert (res.cov[..., 0] >= 0).all() and (res.cov[..., 1] >= 0).all()
    assert (res.cov[..., 2] ** 2 <= res.cov[..., 0] * res.cov[..., 1] + 1e-15).all()


def test_bad_input_is_named():
    batch = make_trials("generalized", 1, "test", 0)
    with pytest.raises(ValueError, match="`n_particles` must be > 0"):
        particle_filter(batch, -5)
    with pytest.raises(ValueError, match="`keep` must hold steps"):
        particle_filter(batch, 10, keep=[500])
    with pytest.raises(ValueError, match="`config` is for task"):
        from hippo_probe.tasks import task_config
        particle_filter(batch, 10, config=task_config("localization"))
