"""The contact model against the world it inverts."""

import math

import numpy as np
import pytest

from hippo_probe.baselines import ContactModelConfig
from hippo_probe.baselines.contact import (ContactModel, Observations,
                                           post_contact_turn_variance, wall_angle_error,
                                           wall_table)
from hippo_probe.tasks import make_trials, task_config
from hippo_probe.world import (WORLDS, MotionConfig, NoiseModel, WorldConfig,
                               inward_normals, random_arena)


def test_turn_variance_matches_a_simulation():
    motion = MotionConfig()
    rng = np.random.default_rng(0)
    dt, tau, n = motion.fine_dt, motion.turn_tau, 200_000
    gain = motion.turn_sd * np.sqrt(2 * dt / tau)
    k = rng.integers(0, motion.substeps, n)              # fine steps left after a contact
    w, turn = np.zeros(n), np.zeros(n)
    for step in range(motion.substeps):
        live = step < k
        w = np.where(live, w - w * dt / tau + gain * rng.standard_normal(n), w)
        turn = np.where(live, turn + w * dt, turn)
    assert np.isclose(turn.var(), post_contact_turn_variance(motion), rtol=0.03)


def test_wall_table_geometry():
    v = random_arena(np.random.default_rng(1), 10, 0.33).vertices
    table = wall_table(v)
    assert np.allclose(table[:, 5:7], inward_normals(v))
    assert np.allclose(np.arctan2(table[:, 6], table[:, 5]), table[:, 7])
    assert np.allclose(table[:, 0:2] + table[:, 2:4], np.roll(v, -1, axis=0))


@pytest.mark.parametrize("world", WORLDS)
def test_angle_of_the_true_wall_is_calibrated(world):
    """The sensed contact angle differs from the touched wall's predicted one by
    N(0, angle_sd^2), the prediction made from the sensed heading minus the true drift
    (what the particle filters' particle at the true drift computes). The touched wall is
    named by a noise-free twin of the trials (same seeds, noiseless sensors: the same
    paths)."""
    config = task_config("generalized", world)
    exact = task_config("generalized", world=WorldConfig(arena=config.world.arena,
                                                          noise=NoiseModel.noiseless()))
    batch = make_trials("generalized", 60, "train", 0, world=world)
    twin = make_trials("generalized", 60, "train", 0, config=exact)
    assert np.array_equal(batch.contact, twin.contact)
    obs, true = Observations.from_batch(batch), Observations.from_batch(twin)
    model = ContactModel.from_config(config.world, ContactModelConfig())
    walls = wall_table(batch.arena_vertices)                     # (B, V, 8)
    b, t = np.nonzero(obs.contact)
    touched = np.argmin(np.abs(wall_angle_error(walls[b, :, 7], true.heading[b, t, None],
                                                true.angle[b, t, None])), axis=1)
    believed = obs.heading[b, t] - batch.heading_drift[t, b]
    error = wall_angle_error(walls[b, touched, 7], believed, obs.angle[b, t])
    z = error / model.angle_sd
    assert len(z) > 3000
    assert abs(np.std(z) - 1) < 0.05 and abs(np.mean(z)) < 0.05
    assert abs(np.mean(np.abs(z) < 1.96) - 0.95) < 0.015
    if world == "darkness":     # the sensed heading alone is off by the drift
        drifting = wall_angle_error(walls[b, touched, 7], obs.heading[b, t], obs.angle[b, t])
        assert np.std(drifting / model.angle_sd) > 1.5


def _contact_likelihood_of_every_wall(walls, heading, angle, path_length, contact_args,
                                      distance, eta, xs, ys, xe, ye):
    """The contact likelihood with every wall's terms computed, for each particle: the
    reference for the kernel's shortcuts."""
    from hippo_probe.baselines.contact import wall_terms
    from hippo_probe.baselines.particle_filter import _BAND, _SQRT2PI, _wall_distance

    lik = np.zeros(len(xe))
    for i in range(len(xe)):
        for wall in walls:
            weight, reach, sd = wall_terms.py_func(wall[7], heading - eta[i], angle,
                                                   path_length, *contact_args)
            if weight == 0.0:
                continue
            end = _wall_distance.py_func(wall, xe[i], ye[i])
            if end - 0.5 * reach > distance + 0.5 * reach + _BAND * sd:
                continue
            start = _wall_distance.py_func(wall, xs[i], ys[i])
            z = (distance - min(0.5 * (start + end - reach), start, end)) / sd
            if abs(z) < _BAND:
                lik[i] += weight / (_SQRT2PI * sd) * math.exp(-0.5 * z * z)
    return lik


def test_contact_likelihood_skips_only_walls_out_of_reach():
    """The kernel skips far walls by a bound before their terms and reuses the terms of a
    heading seen by the particle before: the likelihoods must be those of every wall, bit
    for bit, for particles anywhere in the arena and near its walls, with runs of equal
    drift hypotheses (as in the compass world) and distinct ones, and for a step of no
    length, where the bound is tightest."""
    from hippo_probe.baselines.particle_filter import _contact_likelihood

    config = task_config("generalized", "darkness")
    model = ContactModel.from_config(config.world, ContactModelConfig())
    rng = np.random.default_rng(3)
    walls = wall_table(random_arena(rng, 10, 0.33).vertices)
    n = 600
    corner = walls[rng.integers(0, len(walls), n), :2]            # near a vertex
    xe = np.where(np.arange(n) < n // 2, corner[:, 0] + rng.normal(0, 0.04, n),
                  rng.uniform(-0.6, 0.6, n))
    ye = np.where(np.arange(n) < n // 2, corner[:, 1] + rng.normal(0, 0.04, n),
                  rng.uniform(-0.6, 0.6, n))
    xs, ys = xe - rng.normal(0, 0.02, n), ye - rng.normal(0, 0.02, n)
    eta = np.repeat(rng.normal(0, 0.3, n // 20), 20)             # runs of equal drifts
    eta[::7] = rng.normal(0, 0.3, eta[::7].size)
    args = model.kernel_args()
    for step in range(8):
        angle, distance = rng.uniform(-np.pi, np.pi), rng.uniform(0, model.touch_range)
        heading = rng.uniform(-np.pi, np.pi)
        path_length = 0.0 if step == 0 else rng.uniform(0.0, 0.04)
        lik = np.empty(n)
        _contact_likelihood(walls, heading, angle, path_length, args, distance, eta, xs, ys,
                            xe, ye, lik)
        expected = _contact_likelihood_of_every_wall(walls, heading, angle, path_length,
                                                     args, distance, eta, xs, ys, xe, ye)
        assert (expected > 0).sum() > 20                           # walls within reach
        assert np.array_equal(lik, expected), step
